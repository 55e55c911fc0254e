r"""Carrying a motion as its character carries itself.

A decoder that reads a human's walk onto a quadruped can keep the human's
carriage: the built-in model's retargets of Bandai's walk onto the dog, and
of a zoo biped onto a zoo quadruped, walk on their hind legs with the trunk
pitched up and the forepaws held like hands, a quarter of the height off the
floor, although their limbs swing in step with the source's; a zoo
quadruped's trot onto a zoo biped walks bent forward at the hips
(``experiments/PRETRAIN.md`` sections 54 and 55).

:func:`carry_like` keeps what the decoder made of the source's *motion* and
takes the *carriage* from the character's own clip: every joint's local
rotation is turned by one constant rotation, so that its mean over the
motion's standing frames becomes its mean over the frames in which the
character's own clip stands (:func:`mean_carriage`); the root's tilt (its
rotation less its turn about +Y, :func:`tilts`) is turned so, its heading
kept frame by frame. Swings, their phases and the root's heading are the
decoder's; where the limbs hang from is the character's. A retarget's
root path is scaled so that the body covers as many of its own leg lengths
as decoded; a generated motion's is kept. Which retargets are carried so is the pipeline's choice
(:func:`~satagraph.pipelines.inference.carried_as_character`).
"""
from __future__ import annotations

import numpy as np

from satagraph.motion import Motion, character_height, leg_length
from satagraph.ops.rotation_numpy import mean_rotation_numpy, yaw_matrix_numpy
from satagraph.transforms.ground import standing_frames

#: ``carriage`` settings of the retarget pipeline
#: (:func:`~satagraph.pipelines.inference.carried_as_character`): ``"auto"``
#: carries a retarget that never puts down a limb its character stands on,
#: ``"always"`` every retarget onto a target with frames, ``"never"`` none.
CARRIAGE_MODES = ("auto", "always", "never")
#: The fewest standing frames a clip needs to say how it is carried; with
#: fewer, all its frames are read.
MIN_STANDING = 8


def twist_yaw(rotations: np.ndarray) -> np.ndarray:
    r"""The turn about +Y of each rotation (its twist about the vertical,
    as a swing-twist split reads it), in radians: :math:`\pm\pi` for a
    body heading back along -Z, undefined only for one upside down.

    Shapes:
        - **rotations**: :math:`(*, 3, 3)`, **output**: :math:`(*)`
    """
    # 4wy and 2(w^2 - y^2) of the quaternion: the angle 2 atan2(y, w), read
    # without dividing by w (a half turn, w = 0, is no 0/0)
    return np.arctan2(rotations[..., 0, 2] - rotations[..., 2, 0],
                      rotations[..., 0, 0] + rotations[..., 2, 2])


def tilts(rotations: np.ndarray) -> np.ndarray:
    r"""Rotations with their turn about +Y taken off,
    :math:`Y(\psi)^\top R` (:func:`twist_yaw`): how a body leans, whichever
    way it heads.

    Shapes:
        - **rotations**: :math:`(*, 3, 3)`, **output**: :math:`(*, 3, 3)`
    """
    return np.swapaxes(yaw_matrix_numpy(twist_yaw(rotations)), -1, -2) @ rotations


def carried_frames(motion: Motion) -> np.ndarray:
    """The frames that say how a canonical motion carries itself: those in
    which it stands (:func:`~satagraph.transforms.ground.standing_frames`),
    or all of them where it stands in fewer than :data:`MIN_STANDING`."""
    frames = standing_frames(motion)
    return frames if len(frames) >= MIN_STANDING else np.arange(motion.num_frames)


def mean_carriage(motion: Motion) -> np.ndarray:
    r"""How a canonical motion carries its joints: each joint's local
    rotation averaged over its :func:`carried_frames`
    (:func:`~satagraph.ops.rotation_numpy.mean_rotation_numpy`), the root's
    over its :func:`tilts`.

    Shapes:
        - **output**: :math:`(J, 3, 3)`

    Raises:
        ValueError: If the motion has no frames.
    """
    if not motion.num_frames:
        raise ValueError("carriage: a motion without frames shows no carriage")
    rot = motion.rotations[carried_frames(motion)]
    mean = mean_rotation_numpy(rot)
    mean[0] = mean_rotation_numpy(tilts(rot[:, 0]))
    return mean


def carry_like(motion: Motion, reference: np.ndarray, paced: bool = True) -> Motion:
    r""":obj:`motion` (canonical) carried as the :func:`mean_carriage`
    :obj:`reference` of its character's own clip: each joint's local
    rotation turned by the one constant that takes the motion's own
    carriage to :obj:`reference` (the root's tilt so, its heading kept per
    frame: the turned tilt's own turn about +Y, a few hundredths of a degree
    from two leans, is taken off), and, with :obj:`paced` (a retarget,
    whose travel is matched in leg lengths), the root's horizontal path
    about its first frame scaled by the ratio of the leg lengths after and
    before (:func:`~satagraph.motion.leg_length`); without, the path is
    kept. Heights are not set again: ground the result
    (:func:`~satagraph.transforms.ground.ground_retarget`).

    Shapes:
        - **reference**: :math:`(J, 3, 3)`

    Raises:
        ValueError: If :obj:`reference` is not one rotation per joint, or
            the motion has no frames.
    """
    if reference.shape != (motion.num_joints, 3, 3):
        raise ValueError(f"carry_like: a carriage of {motion.num_joints} joints is "
                         f"[{motion.num_joints}, 3, 3], got {list(reference.shape)}")
    turn = reference @ np.swapaxes(mean_carriage(motion), -1, -2)
    rot = turn[None] @ motion.rotations
    root = motion.rotations[:, 0]
    rot[:, 0] = yaw_matrix_numpy(twist_yaw(root)) @ tilts(turn[0] @ tilts(root))
    carried = motion.with_(rotations=rot)
    return _paced(carried, _leg(carried) / _leg(motion)) if paced else carried


def _leg(motion: Motion) -> float:
    """:func:`~satagraph.motion.leg_length` of a canonical motion."""
    pos = motion.global_positions()
    return leg_length(pos, character_height(motion.skeleton, pos))


def _paced(motion: Motion, factor: float) -> Motion:
    """:obj:`motion` with its root's horizontal path about its first
    frame scaled by :obj:`factor`."""
    trans = motion.translations.copy()
    start = trans[:1, 0, [0, 2]]
    trans[:, 0, [0, 2]] = start + (trans[:, 0, [0, 2]] - start) * factor
    return motion.with_(translations=trans)


__all__ = ["CARRIAGE_MODES", "MIN_STANDING", "twist_yaw", "tilts", "carried_frames", "mean_carriage", "carry_like"]
