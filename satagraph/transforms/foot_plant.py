r"""Planting the feet of a decoded motion where they touch the ground.

A decoder unsure of a limb's phase plays its swing short while the root
travels at the source's speed, so the feet glide over the floor
(``experiments/T2M.md`` section 17: reconstructed walks whose feet slide
at 0.8 heights a second, against 0.03 for the real ones). On any
skeleton, :func:`plant_feet` finds the frames where each limb end
(:func:`~satagraph.semantics.limb_ends`) stands: the lowest joint below
it near the floor, the end slow next to the body (:func:`stance_frames`).
It holds the end at one floor position through each
such stance (fading in and out over :data:`BLEND_FRAMES`), on the floor
(the lowest joint of its subtree at the floor's height), and bends the
limb's single-child chain above it to reach there (FABRIK,
:func:`reach`; twist and share bones riding along a segment do not
count as children, and a hip bone, fused to the pelvis, is never bent:
:func:`limb_chain`). Before that the root is lowered, frame by frame, onto the
lowest of its standing limbs (:func:`stance_drop`): a decoded body bobs
above its feet (``experiments/T2M.md`` section 47), and a leg that has
to reach a floor below its foot's decoded height can only stretch. The
horizontal root path, the limbs in the air and every other joint's
rotation are left as decoded; the limb's end keeps its pose relative to
its parent; no frame ends below the floor.
"""
from __future__ import annotations

from typing import Dict, List, Optional, Sequence

import numpy as np

from satagraph.motion import CONTACT_HEIGHT, CONTACT_SPEED, Motion
from satagraph.ops.rotation_numpy import rotation_between_numpy
from satagraph.semantics.limbs import helper_joints, hip_bones, limb_ends
from satagraph.transforms.ground import levels, lift_above_floor, raise_root

#: Most bones above a limb end that :func:`plant_feet` bends.
MAX_CHAIN_BONES = 3
#: Frames over which a planted position fades in before a stance and out after it.
BLEND_FRAMES = 4
#: Fewest frames of a stance that is planted.
MIN_STANCE = 3
#: A stance's limb end is below this many :data:`~satagraph.motion.CONTACT_HEIGHT`.
HEIGHT_FACTOR = 2.0
#: ... and slower than :data:`~satagraph.motion.CONTACT_SPEED` plus this
#: fraction of the root's horizontal speed (a gliding stance foot moves
#: with a fraction of the body's speed, a swinging one faster than it: a
#: decoded quadruped's stance feet glide at 0.35-0.6 of it,
#: ``experiments/T2M.md`` section 47).
ROOT_SPEED_FACTOR = 0.8
#: Frames over which :func:`stance_drop` is averaged (no jolt where the
#: lowest standing limb changes).
DROP_FRAMES = 5


def limb_chain(parents: Sequence[int], end: int, max_bones: int = MAX_CHAIN_BONES,
               helpers: Optional[Sequence[bool]] = None,
               rigid: Optional[Sequence[bool]] = None) -> List[int]:
    """The joints from a limb's top down to :obj:`end`: :obj:`end`'s
    ancestors while each has that one child, at most :obj:`max_bones`
    bones, top first (the top's position is its parent's business).
    Children marked in :obj:`helpers` (twist and share bones riding along
    a segment: :func:`~satagraph.semantics.helper_joints`) do not count:
    a CC_Base calf with its foot, a twist bone and a knee share bone
    bends like a calf with its foot alone. A joint marked in :obj:`rigid`
    (a hip bone, fused to the pelvis: :func:`~satagraph.semantics.hip_bones`)
    is never part of a chain, so that the hip socket stays where the
    pelvis holds it."""
    parents = np.asarray(parents)
    counted = np.ones(len(parents), dtype=bool) if helpers is None else ~np.asarray(helpers, bool)
    fixed = np.zeros(len(parents), dtype=bool) if rigid is None else np.asarray(rigid, bool)
    children = np.bincount(parents[1:][counted[1:]], minlength=len(parents))
    chain = [int(end)]
    while len(chain) <= max_bones:
        parent = int(parents[chain[-1]])
        if parent < 0 or children[parent] != 1 or fixed[parent]:
            break
        chain.append(parent)
    return chain[::-1]


def stance_frames(track: np.ndarray, lowest: np.ndarray, root: np.ndarray, fps: float,
                  height: float, floor: float = 0.0) -> np.ndarray:
    r"""Frames where a limb stands: the lowest joint of its end's subtree
    (:obj:`lowest`, its height) within :data:`HEIGHT_FACTOR` contact
    heights of the floor and rising or falling slower than the contact
    speed, and the end horizontally slower than the contact speed plus
    :data:`ROOT_SPEED_FACTOR` of the root's, in runs of at least
    :data:`MIN_STANCE` frames (+Y up). A foot leaving the floor in a jump
    is low but not level: counted as standing, the root would be lowered
    onto it and the jump flattened (``experiments/T2M.md`` section 76).

    Shapes:
        - **track**, **root**: :math:`(T, 3)` positions, **lowest**: :math:`(T,)`
        - **output**: :math:`(T,)` bool
    """
    def speed(x: np.ndarray) -> np.ndarray:
        return np.linalg.norm(np.gradient(x[:, [0, 2]], axis=0), axis=-1) * fps

    if len(track) < 2:
        return np.zeros(len(track), dtype=bool)
    low = lowest - floor < HEIGHT_FACTOR * CONTACT_HEIGHT * height
    slow = speed(track) < CONTACT_SPEED * height + ROOT_SPEED_FACTOR * speed(root)
    level = np.abs(np.gradient(lowest)) * fps < CONTACT_SPEED * height
    return _drop_short(low & slow & level, MIN_STANCE)


def _runs(mask: np.ndarray) -> List[tuple]:
    """``(start, stop)`` of every run of ``True``."""
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))


def _drop_short(mask: np.ndarray, shortest: int) -> np.ndarray:
    out = mask.copy()
    for start, stop in _runs(mask):
        if stop - start < shortest:
            out[start:stop] = False
    return out


def planted_track(track: np.ndarray, stance: np.ndarray, blend: int = BLEND_FRAMES,
                  drop: Optional[np.ndarray] = None) -> np.ndarray:
    r"""Where the limb end should be: through each stance, its mean
    horizontal position over the stance, the height as decoded less
    :obj:`drop` (per frame: how far its lowest joint is above the floor;
    ``None``: as decoded), faded in over :obj:`blend` frames before and
    out after it by a smoothstep (no jolt where a fade begins or ends).
    Between two stances closer than two fades, both pulls are averaged by
    their weights, so the target glides from one stance's position to the
    next (it jumped where one stance's fade gave way to the other's).

    Shapes:
        - **track**: :math:`(T, 3)`, **stance**, **drop**: :math:`(T,)`
        - **output**: :math:`(T, 3)`
    """
    frames = np.arange(len(track))
    pull, total = np.zeros_like(track), np.zeros(len(track))
    held = []
    for start, stop in _runs(stance):
        gap = np.maximum(np.maximum(start - frames, frames - (stop - 1)), 0)
        ramp = np.clip(1.0 - gap / (blend + 1.0), 0.0, 1.0)
        weight = ramp * ramp * (3.0 - 2.0 * ramp)
        lock = track.copy()
        lock[:, [0, 2]] = track[start:stop][:, [0, 2]].mean(axis=0)
        if drop is not None:
            lock[:, 1] = track[:, 1] - drop
        pull += weight[:, None] * (lock - track)
        total += weight
        held.append((start, stop, lock[start:stop].copy()))  # not a take-long array each
    out = track + pull / np.maximum(total, 1.0)[:, None]
    for start, stop, lock in held:  # a stance holds its own position alone
        out[start:stop] = lock
    return out


def stance_drop(gaps: np.ndarray, frames: int = DROP_FRAMES) -> np.ndarray:
    r"""How far to lower the root in each frame: :obj:`gaps` (the height
    above the floor of the lowest standing limb, NaN where no limb
    stands), carried across the frames between stances by linear
    interpolation (held before the first and after the last), then
    averaged over :obj:`frames` frames. Zero where nothing ever stands.

    Shapes:
        - **gaps**, **output**: :math:`(T,)`
    """
    have = np.isfinite(gaps)
    if not have.any():
        return np.zeros(len(gaps))
    t = np.arange(len(gaps))
    drop = np.interp(t, t[have], gaps[have])
    pad = np.pad(drop, (frames // 2, frames - 1 - frames // 2), mode="edge")
    return np.convolve(pad, np.ones(frames) / frames, mode="valid")


def reach(chain: np.ndarray, target: np.ndarray, iterations: int = 10) -> np.ndarray:
    r"""FABRIK: the chain's joints moved, bone lengths kept and its first
    joint fixed, so that its last joint reaches :obj:`target` (or points at
    it, stretched, when out of reach), every frame at once.

    Shapes:
        - **chain**: :math:`(T, n + 1, 3)`, **target**: :math:`(T, 3)`
        - **output**: :math:`(T, n + 1, 3)`
    """
    lengths = np.linalg.norm(np.diff(chain, axis=1), axis=-1)
    out, base = chain.copy(), chain[:, 0].copy()

    def place(anchor: np.ndarray, toward: np.ndarray, length: np.ndarray) -> np.ndarray:
        d = toward - anchor
        norm = np.maximum(np.linalg.norm(d, axis=-1, keepdims=True), 1e-12)
        return anchor + d / norm * length[:, None]

    for _ in range(iterations):
        out[:, -1] = target
        for i in range(chain.shape[1] - 2, -1, -1):
            out[:, i] = place(out[:, i + 1], out[:, i], lengths[:, i])
        out[:, 0] = base
        for i in range(chain.shape[1] - 1):
            out[:, i + 1] = place(out[:, i], out[:, i + 1], lengths[:, i])
    return out


def _bend(motion: Motion, chain: List[int], goal: np.ndarray, frames: np.ndarray) -> Motion:
    """Local rotations of the chain's joints (top first) turned so that
    each bone points at its joint's goal position, on :obj:`frames` only."""
    rotations, parents = motion.rotations.copy(), motion.skeleton.parents
    for i, joint in enumerate(chain[:-1]):
        glob, pos = motion.with_(rotations=rotations).global_transforms()
        here, there = pos[frames, joint], goal[frames, i + 1]
        u, v = pos[frames, chain[i + 1]] - here, there - here
        u /= np.maximum(np.linalg.norm(u, axis=-1, keepdims=True), 1e-12)
        v /= np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)
        turned = rotation_between_numpy(u, v) @ glob[frames, joint]
        parent = glob[frames, parents[joint]] if parents[joint] >= 0 else np.eye(3)
        rotations[frames, joint] = np.swapaxes(parent, -1, -2) @ turned
    return motion.with_(rotations=rotations)


def plant_feet(motion: Motion, ends: Optional[Sequence[int]] = None) -> Motion:
    r""":obj:`motion` with its root lowered onto its standing limbs and each
    limb end held still on the floor through its stances (see the module's
    text; +Y up, the floor at the median height of the lowest joint, as
    :func:`~satagraph.transforms.ground.ground_at` sets it); last, each
    frame whose lowest joint is then below the floor is raised onto it. A
    motion in which no limb stands is returned as it is.

    Args:
        motion (Motion): A decoded motion, canonical.
        ends (sequence of int, optional): The limb ends to plant (default:
            :func:`~satagraph.semantics.limb_ends` of its skeleton).
    """
    if motion.num_frames < 2:
        return motion
    if ends is None:
        ends = list(limb_ends(motion.skeleton).values())
    skeleton = motion.skeleton
    pos = motion.global_positions()
    floor, height = levels(skeleton, pos)
    members = {end: skeleton.subtree(end) for end in ends}
    lowest = {end: pos[:, members[end], 1].min(axis=1) for end in ends}
    stances = {end: stance_frames(pos[:, end], lowest[end], pos[:, 0], motion.fps, height, floor)
               for end in ends}
    if not any(stance.any() for stance in stances.values()):
        return motion
    gaps = np.full(motion.num_frames, np.nan)
    for end, stance in stances.items():  # the lowest standing limb's height above the floor
        gaps[stance] = np.fmin(gaps[stance], lowest[end][stance] - floor)
    motion = _hold_stances(raise_root(motion, -stance_drop(gaps)), stances, members, floor,
                           helper_joints(skeleton), hip_bones(skeleton))
    return lift_above_floor(motion, floor)


def _hold_stances(motion: Motion, stances: Dict[int, np.ndarray],
                  members: Dict[int, List[int]], floor: float, helpers: np.ndarray,
                  rigid: np.ndarray) -> Motion:
    """Each limb end of :obj:`stances` (end -> :math:`(T,)` bool) held on
    the floor through its stances (its subtree :obj:`members` at the floor),
    the chain above it (:func:`limb_chain` of the :obj:`helpers` and
    :obj:`rigid` masks) bent to reach there."""
    skeleton = motion.skeleton
    pos = motion.global_positions()
    for end, stance in stances.items():
        chain = limb_chain(skeleton.parents, end, helpers=helpers, rigid=rigid)
        if len(chain) < 3:  # one bone cannot bend
            continue
        track = pos[:, end]
        above = pos[:, members[end], 1].min(axis=1) - floor
        target = planted_track(track, stance, drop=above)
        frames = np.flatnonzero(np.linalg.norm(target - track, axis=-1) > 1e-9)
        if not len(frames):
            continue
        motion = _bend(motion, chain, reach(pos[:, chain], target), frames)
        pos = motion.global_positions()
    return motion


__all__ = ["BLEND_FRAMES", "DROP_FRAMES", "MAX_CHAIN_BONES", "MIN_STANCE", "ROOT_SPEED_FACTOR",
           "limb_chain", "plant_feet", "planted_track", "reach", "stance_drop", "stance_frames"]
