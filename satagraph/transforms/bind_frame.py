r"""A leading bind-pose frame: a pose the motion never holds, written before it.

Some exporters write the rig's bind pose as frame 0 and the motion from
frame 1 on: CMU's BVH conversions (``cmu/01_01.bvh``: the arms in a T
for one frame, then at the sides) and Reallusion's CC_Base exports
(``ccbase/007_*.bvh``: a T-pose at the origin, then the actor 1.3-1.7
heights away). Read as motion, that frame is a jump no body makes: every
joint turns at once and the root teleports. It sets where the clip's
facing frame and origin are, and its velocities are the largest a model
is trained on.

:func:`has_bind_frame` calls frame 0 such a frame when its change to frame
1 is at least :data:`BIND_RATIO` times the largest change between any later
consecutive frames, by either of two measures: the mean over joints of the
angle each local rotation turns (at least :data:`BIND_MIN_ANGLE`), or how
far the joints' centroid moves (at least :data:`BIND_MIN_SHIFT` character
heights). Of the 247 files of the shared data, the eleven such clips
read 4.9-11.3 and 55-83 times; no other file, nor any of 48 zoo clips of
every body plan, exceeds 1.0 on either. The zoo's walks, each given its
rest pose as frame 0 where frame 1 stands (CMU's case), read 2.7-3.2 for
spiders, crabs and insects, whose many legs turn fast every frame, and
7.8-23.5 for the other plans.
:func:`replace_bind_frame` gives frame 0 frame 1's pose, so the clip keeps
its length and frame times.
"""
from __future__ import annotations

from typing import Optional, Tuple

import numpy as np

from satagraph.motion import Motion, character_height

#: How many times the largest later change frame 0's change must be.
BIND_RATIO = 2.0
#: Least mean joint rotation change (radians) of a bind frame.
BIND_MIN_ANGLE = 0.05
#: Least centroid shift (character heights) of a bind frame.
BIND_MIN_SHIFT = 0.2
#: Fewest frames of a clip that is checked.
BIND_MIN_FRAMES = 8


def frame_changes(motion: Motion, positions: Optional[np.ndarray] = None
                  ) -> Tuple[np.ndarray, np.ndarray]:
    r"""Per pair of consecutive frames, the mean over joints of the angle
    each local rotation turns (radians) and the shift of the joints'
    centroid (the motion's units).

    Args:
        motion (Motion): A motion of at least two frames.
        positions (np.ndarray, optional): Its global joint positions
            :math:`(T, J, 3)`, where the caller has them.

    Shapes:
        - **output**: two arrays :math:`(T - 1,)`
    """
    rot = motion.rotations  # trace(A^T B) is the elementwise sum of A * B
    cos = np.clip(((rot[:-1] * rot[1:]).sum(axis=(2, 3)) - 1.0) / 2.0, -1.0, 1.0)
    if positions is None:
        positions = motion.global_positions()
    centroid = positions.mean(axis=1)
    return np.arccos(cos).mean(axis=1), np.linalg.norm(np.diff(centroid, axis=0), axis=1)


def has_bind_frame(motion: Motion) -> bool:
    """Whether frame 0 of :obj:`motion` is a pose it jumps out of (see the
    module's rule); clips under :data:`BIND_MIN_FRAMES` frames never are."""
    if motion.num_frames < BIND_MIN_FRAMES:
        return False
    positions = motion.global_positions()
    angle, shift = frame_changes(motion, positions)
    size = max(character_height(motion.skeleton, positions), 1e-9)
    turned = angle[0] >= BIND_MIN_ANGLE and angle[0] >= BIND_RATIO * angle[1:].max()
    moved = shift[0] >= BIND_MIN_SHIFT * size and shift[0] >= BIND_RATIO * shift[1:].max()
    return bool(turned or moved)


def replace_bind_frame(motion: Motion) -> Motion:
    """:obj:`motion` with frame 0 given frame 1's pose where frame 0 is a
    bind frame (:func:`has_bind_frame`); else :obj:`motion` itself."""
    if not has_bind_frame(motion):
        return motion
    rotations, translations = motion.rotations.copy(), motion.translations.copy()
    rotations[0], translations[0] = rotations[1], translations[1]
    return motion.with_(rotations=rotations, translations=translations)


__all__ = ["BIND_RATIO", "BIND_MIN_ANGLE", "BIND_MIN_SHIFT", "BIND_MIN_FRAMES",
           "frame_changes", "has_bind_frame", "replace_bind_frame"]
