r"""Putting a decoded motion on the ground its source stands on.

A decoder predicts the root's height; decoded onto another body plan it can
carry the source's hip height over (a quadruped's hips at 0.7 of its height
decoded onto a biped leave the biped's feet 16 % of its height above the
floor). :func:`ground_like` moves the whole motion up or down by one
constant, so its vertical dynamics (bobbing, jumps) stay the decoder's and
only the offset is set: the median height of its lowest joint, in its own
character heights, becomes that of a reference (:func:`ground_like`): for a
retarget, the target character's own clip (:func:`ground_retarget`), or the
floor (:func:`ground_at`, for generated motion, which has no source).
Either is then raised, frame by frame, where it would sink below the
floor (:func:`lift_above_floor`: :func:`ground_retarget` ends with it, and
generation applies it after :func:`ground_at`).
"""
from __future__ import annotations

from typing import Optional, Union

import numpy as np

from satagraph.motion import Motion, character_height
from satagraph.skeleton import Skeleton


def lowest_heights(motion: Motion) -> np.ndarray:
    r"""Height of the lowest joint per frame (+Y up).

    Shapes:
        - **output**: :math:`(T,)`
    """
    return motion.global_positions()[..., 1].min(axis=1)


def levels(skeleton: Skeleton, positions: np.ndarray,
           frames: Optional[np.ndarray] = None) -> tuple:
    r"""(median over frames, or over :obj:`frames` only, of the lowest
    joint's height, character height) of a motion's global positions (+Y
    up).

    Shapes:
        - **positions**: :math:`(T, J, 3)`
        - **frames**: :math:`(F,)` frame indices
    """
    shown = positions if frames is None else positions[frames]
    return (float(np.median(shown[..., 1].min(axis=1))),
            character_height(skeleton, positions))


def _levels(motion: Motion, frames: Optional[np.ndarray] = None) -> tuple:
    """:func:`levels` from one forward kinematics pass."""
    return levels(motion.skeleton, motion.global_positions(), frames)


def ground_level(motion: Motion) -> float:
    """Median over frames of the lowest joint's height above the floor
    (y = 0), as a fraction of the character's height; negative below."""
    lowest, height = _levels(motion)
    return lowest / max(height, 1e-9)


def ground_at(motion: Motion, lift: float = 0.0,
              frames: Optional[np.ndarray] = None) -> Motion:
    r""":obj:`motion` shifted along +Y by one constant so that the median
    height of its lowest joint over its frames (or over :obj:`frames`) is
    :obj:`lift` times its character height (0: standing on the floor; +Y
    up, floor at 0).

    Args:
        motion (Motion): A decoded motion (canonical).
        lift (float): Median lowest-joint height, in character heights.
        frames (np.ndarray, optional): The frames the median is read over
            (default: all).
    """
    if motion.num_frames == 0:
        return motion
    lowest, height = _levels(motion, frames)
    return raise_root(motion, lift * height - lowest)


def raise_root(motion: Motion, rise: Union[float, np.ndarray]) -> Motion:
    r""":obj:`motion` with its root raised along +Y by :obj:`rise` (one
    value, or one per frame :math:`(T,)`; negative lowers it)."""
    translations = motion.translations.copy()
    translations[:, 0, 1] += rise
    return motion.with_(translations=translations)


def ground_like(motion: Motion, reference: Motion) -> Motion:
    r""":func:`ground_at` the :func:`ground_level` of :obj:`reference` (the
    motion :obj:`motion` was decoded from).

    Args:
        motion (Motion): A decoded motion (a retarget or reconstruction).
        reference (Motion): The motion it was decoded from.
    """
    if reference.num_frames == 0:
        return motion
    return ground_at(motion, ground_level(reference))


def ground_retarget(motion: Motion, source: Motion, target: Motion,
                    level: Optional[float] = None) -> Motion:
    r"""A retarget stood on the floor as the target character stands in its
    own clip: :func:`ground_at` the :func:`ground_level` of :obj:`target`
    where it has frames, else of :obj:`source`, read over the frames in
    which the source stands where it also sits or lies
    (:func:`ground_frames`), then :func:`lift_above_floor`. How high a
    rig's lowest joint sits above the floor is the rig's own (the dog's
    paw end sites stay 3-6 cm, 6-11 % of its height, above the floor its
    tail touches): copied from the source, a dog's offset left a human
    retarget hovering 9 % of its height up. Read over every frame, a dog
    that lies most of a clip, its human retarget standing all along, left
    the human hovering 0.7 m up where the dog stands
    (``experiments/PRETRAIN.md`` section 50); the lift keeps a body that
    sits or crouches lower than where its source stands from passing
    through the floor (section 42).

    Args:
        motion (Motion): The decoded retarget (canonical).
        source (Motion): The canonical source it was decoded from.
        target (Motion): The canonical target clip (its skeleton and, where
            it has frames, how it stands).
        level (float, optional): :obj:`target`'s :func:`ground_level` where
            it was read before (one target, many sources); used only where
            :obj:`target` has frames.
    """
    reference = target if target.num_frames else source
    if not motion.num_frames or not reference.num_frames:
        return motion
    if level is None or reference is not target:
        level = ground_level(reference)
    frames = ground_frames(source) if source.num_frames == motion.num_frames else None
    return lift_above_floor(ground_at(motion, level, frames))


def ground_frames(source: Motion) -> Optional[np.ndarray]:
    r"""The frames :func:`ground_retarget` stands a retarget of
    :obj:`source` on the floor in: every frame (``None``) where the source
    is up on its legs (:data:`UP_SHARE`) in all but :data:`DOWN_FRAMES` of
    them (a walk, a run, a jump); where it sits or lies longer, the frames
    in which it stands (:func:`standing_frames`): a decoded body that does
    not follow it down stands on the floor there, and sinks (to be lifted)
    where the source is down, instead of hovering where it stands.

    Shapes:
        - **output**: :math:`(F,)` frame indices, or ``None``
    """
    pos = source.global_positions()
    up = stands(pos, source.skeleton, source.fps, UP_SHARE)
    if 1.0 - up.mean() < DOWN_FRAMES:
        return None
    return np.flatnonzero(stands(pos, source.skeleton, source.fps))


def lift_above_floor(motion: Motion, floor: float = 0.0) -> Motion:
    r""":obj:`motion` with its root raised, in each frame whose lowest joint
    is below the floor (y = :obj:`floor`, +Y up), by that depth: no frame
    sinks, and the frames above the floor, the horizontal path and every
    rotation stay as they are. The last step of :func:`ground_retarget`: after one
    shift that stands a retarget as its target stands, a body that sits or
    crouches lower (a human retargeted from a sitting dog) would otherwise
    pass through the floor there.

    Args:
        motion (Motion): A canonical motion.
        floor (float): The floor's height (0: where :func:`ground_at` puts
            it).
    """
    if motion.num_frames == 0:
        return motion
    depth = np.maximum(floor - lowest_heights(motion), 0.0)
    return raise_root(motion, depth) if depth.any() else motion


#: Share of its greatest stance height at which a body counts as standing
#: (:func:`standing_frame`).
STANDING_SHARE = 0.95
#: Share of its greatest stance height above which a body is up on its
#: legs, not sitting, lying or crouched (every frame of a walk or a run,
#: whose hips dip 5-10 %) ...
UP_SHARE = 0.8
#: ... and the share of its frames a source must spend below it for a
#: retarget of it to be stood on the floor where it stands
#: (:func:`ground_frames`).
DOWN_FRAMES = 0.1
#: Seconds a stance height must be held to count as the body's greatest
#: (:func:`stands`): a dog landing a jump on its front paws, hind legs up,
#: holds its hips highest for a tenth of a second.
STANDING_HOLD = 0.3
#: Greatest held stance height, as a share of the body's size, below which
#: a body has no stance (:func:`stands`): a snake's root lies among its
#: support joints, its stance 1e-17 m of rounding.
NO_STANCE = 1e-3


def standing_frame(motion: Motion) -> int:
    r"""The first frame of a canonical motion (+Y up) in which the body
    stands (:func:`stands`): the frame whose root orientation the
    rest of ``rest="auto"`` takes
    (:func:`~satagraph.transforms.rest.shown_rest`), so that a clip
    that starts lying or sitting (many of the dog's) does not show the
    model a curled-up skeleton."""
    return int(np.argmax(stands(motion.global_positions(), motion.skeleton, motion.fps)))


def standing_frames(motion: Motion, share: float = STANDING_SHARE) -> np.ndarray:
    """Every frame of a canonical motion in which the body stands (as
    :func:`standing_frame` counts it; within :obj:`share` of its held
    stance height): the frames whose mean pose ``rest="auto"`` shows the
    model, and where :func:`~satagraph.pipelines.quality.posture` reads how
    a character carries itself."""
    return np.flatnonzero(stands(motion.global_positions(), motion.skeleton, motion.fps,
                                 share))


def stands(positions: np.ndarray, skeleton: Skeleton, fps: float = 30.0,
           share: float = STANDING_SHARE) -> np.ndarray:
    r"""Per frame, whether the root stands above its :func:`support_joints`
    within :obj:`share` (:data:`STANDING_SHARE`) of the greatest height it
    holds there for :data:`STANDING_HOLD` seconds (the greatest of a
    running median), below as above. The frames of a dog's jump, landing on its front paws with
    its hips and hind legs up (``dog/D1_ex04_KAN02_003``: the only three
    frames that counted, a handstand shown as the dog's rest), are not
    standing: its hind paws, not its front ones, say how high it stands.
    A body that holds no stance height (:data:`NO_STANCE`: a snake, its
    root among its support joints) stands in every frame: read against
    rounding, a snake's stance had it lying in 0-97 % of a clip's frames
    at random, and its retargets were grounded on a few of them (a human
    hovered 8-9 % of its height up over most of the clip).

    Args:
        positions (np.ndarray): Global joint positions.
        skeleton (Skeleton): Their skeleton.
        fps (float): Their frame rate.
        share (float): How near the greatest held height a standing
            frame's is, below as above.

    Shapes:
        - **positions**: :math:`(T, J, 3)` global, +Y up
        - **output**: :math:`(T,)` bool
    """
    support = support_joints(skeleton, positions)
    stance = positions[:, 0, 1] - positions[:, support, 1].min(axis=1)
    width = max(1, int(round(STANDING_HOLD * fps)))
    padded = np.pad(stance, (width // 2, width - 1 - width // 2), mode="edge")
    held = np.median(np.lib.stride_tricks.sliding_window_view(padded, width), axis=1).max()
    size = float(np.median(np.ptp(positions, axis=1).max(axis=-1)))
    if held <= NO_STANCE * size:  # no legs to stand on: it neither sits nor lies
        return np.ones(len(stance), dtype=bool)
    return (stance >= share * held) & (stance * share <= held)


#: A chain end touches the floor (:func:`support_joints`) where it is within
#: this share of the body's size of the frame's lowest joint ...
SUPPORT_CONTACT = 0.05
#: ... in at least this share of the frames.
SUPPORT_FRAMES = 0.1


def support_joints(skeleton: Skeleton, positions: np.ndarray) -> np.ndarray:
    r"""The joints a body stands on below its root: the chains from the
    root to the ends that touch the floor (:data:`SUPPORT_CONTACT` in
    :data:`SUPPORT_FRAMES` of the frames) fewest bones from the root, up
    to two more (a dog's hind paws, four bones from its hips, not its front
    paws, eight along the spine; a human's feet, toes included, not the
    hands it leans on); every joint where no end touches the floor.

    Shapes:
        - **positions**: :math:`(T, J, 3)` global, +Y up
    """
    heights = positions[..., 1] - positions[..., 1].min(axis=1, keepdims=True)
    size = max(float(np.median(np.ptp(positions, axis=1).max(axis=-1))), 1e-12)
    ends = np.flatnonzero(skeleton.is_leaf)
    touching = ends[(heights[:, ends] < SUPPORT_CONTACT * size).mean(axis=0) >= SUPPORT_FRAMES]
    if not len(touching):
        return np.arange(skeleton.num_joints)
    depth = skeleton.depth
    near = touching[depth[touching] <= depth[touching].min() + 2]
    chains: set = set()
    for j in near:
        while j > 0 and j not in chains:
            chains.add(int(j))
            j = skeleton.parents[j]
    if not chains:  # the root itself is the lowest end
        return np.arange(skeleton.num_joints)
    return np.array(sorted(chains), dtype=np.int64)


__all__ = ["lowest_heights", "ground_level", "ground_at", "ground_like", "ground_retarget",
           "ground_frames", "lift_above_floor", "raise_root", "STANDING_SHARE", "UP_SHARE",
           "DOWN_FRAMES", "STANDING_HOLD", "NO_STANCE", "SUPPORT_CONTACT", "SUPPORT_FRAMES",
           "standing_frame", "standing_frames", "stands", "support_joints"]
