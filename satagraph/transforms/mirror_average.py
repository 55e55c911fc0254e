"""Averaging a model's readings of one motion: of the motion and its
mirror image (test-time mirroring; ``experiments/PRETRAIN.md`` section
37), of the rigs shown in two rest poses (section 39).

A model trained with mirroring and re-rested rigs as augmentations reads
a motion, its left-right mirror image and the motion on a re-rested rig
as the same motion; each reading carries its own error, and part of it
cancels in their mean. :func:`mirror_canonical` mirrors a canonical
motion across its side-to-side axis (X), :func:`mirror_back` brings the
output of the mirror image back onto the first reading's rig and frame,
:func:`place_reading` does so for a reading whose source was turned
otherwise, and :func:`average_readings` takes their mean: each joint's
rotation by its chordal mean, the root's position by its mean.

Example::

    twin = mirror_canonical(canon)          # None: no left/right pairs
    ...                                     # decode canon and twin
    back = mirror_back(twin_output, twin_source, source)
    out = average_readings(output, back)
"""
from __future__ import annotations

from typing import Optional

import numpy as np

from satagraph.motion import Motion
from satagraph.ops.rotation_numpy import mean_rotation_numpy, yaw_matrix_numpy, yaw_of
from satagraph.transforms.augment import mirror, mirror_pairs

#: The canonical frame's side-to-side axis (+Y up, facing +Z).
LATERAL_AXIS = 0


def mirror_canonical(motion: Motion) -> Optional[Motion]:
    """The mirror image of a canonical motion across its side-to-side axis,
    or ``None`` where it has none to speak of: no left/right joint pairs
    (:func:`~satagraph.transforms.augment.mirror_pairs`), a joint named for
    one side without a counterpart, or a hierarchy whose sides are not
    each other's image (what :func:`~satagraph.transforms.augment.mirror`
    refuses)."""
    pair = mirror_pairs(motion.skeleton)
    if np.array_equal(pair, np.arange(motion.num_joints)):
        return None
    try:
        return mirror(motion, LATERAL_AXIS)
    except ValueError:
        return None


def mirror_back(output: Motion, mirrored_source: Motion, source: Motion) -> Motion:
    r""":obj:`output`, decoded from :obj:`mirrored_source` (the mirror
    image of :obj:`source`, as the decoding pipeline turned and placed
    it), mirrored back and moved rigidly (a turn about +Y and a ground
    shift) so that the mirrored-back source's root lies on :obj:`source`'s
    at frame 0."""
    return place_reading(mirror(output, LATERAL_AXIS), mirror(mirrored_source, LATERAL_AXIS),
                         source)


def place_reading(output: Motion, shown_source: Motion, source: Motion) -> Motion:
    r""":obj:`output`, decoded from :obj:`shown_source` (:obj:`source`
    turned about +Y and moved otherwise, as a second reading's pipeline
    placed it), moved rigidly (a turn about +Y and a ground shift) so that
    :obj:`shown_source`'s root lies on :obj:`source`'s at frame 0."""
    forward = np.array([0.0, 0.0, 1.0])
    turn = yaw_matrix_numpy(yaw_of(source.rotations[0, 0] @ forward)
                            - yaw_of(shown_source.rotations[0, 0] @ forward))
    root = source.translations[0, 0] - turn @ shown_source.translations[0, 0]
    root[1] = 0.0
    rotations, translations = output.rotations.copy(), output.translations.copy()
    rotations[:, 0] = turn @ rotations[:, 0]
    translations[:, 0] = translations[:, 0] @ turn.T + root
    return output.with_(rotations=rotations, translations=translations)


def average_readings(first: Motion, *others: Motion) -> Motion:
    r"""The mean of readings of one motion on one rig: each joint's
    rotation their chordal mean
    (:func:`~satagraph.ops.rotation_numpy.mean_rotation_numpy`), the
    root's position their mean, everything else :obj:`first`'s.

    Shapes:
        - every motion: :math:`T` frames of the same :math:`J` joints
    """
    for other in others:
        if first.rotations.shape != other.rotations.shape:
            raise ValueError(f"average_readings: {first.rotations.shape[:2]} and "
                             f"{other.rotations.shape[:2]} (frames, joints) differ")
    if not others:
        return first
    readings = (first,) + others
    rotations = mean_rotation_numpy(np.stack([m.rotations for m in readings]))
    translations = first.translations.copy()
    translations[:, 0] = np.mean([m.translations[:, 0] for m in readings], axis=0)
    return first.with_(rotations=rotations, translations=translations)


__all__ = ["LATERAL_AXIS", "mirror_canonical", "mirror_back", "place_reading",
           "average_readings"]
