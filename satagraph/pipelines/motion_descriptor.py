r"""A skeleton-agnostic kinematic descriptor of a motion (issue 19, item 8).

The evaluator of text-to-motion (``benchmarks/t2m.py``) must not see SATA's
encoder, and must read any rig. This descriptor is computed from the motion
alone, in the canonical frame (+Y up, facing +Z at frame 0), and divided by
the character's own lengths so that the rig's size and units drop out:

- **root** (per frame): forward and lateral velocity in the facing frame
  and root height, in leg lengths (per second); yaw rate in rad/s
  (positive: to the left);
- **limb ends** (per frame): the four limb ends of
  :data:`~satagraph.semantics.limbs.LIMBS` (hands/front paws, feet/hind
  paws), their position and velocity relative to the root in the facing
  frame, in character heights (per second); a limb the skeleton lacks is
  zero, and :func:`limb_mask` says which;
- **pooled** (:func:`describe_features`): mean, std, 10th and 90th
  percentile of every per-frame channel over the clip, the means of its
  three thirds (what happens first and last), and the limb mask.

The leg length is the bone-chain length from the root to the hind limb ends
(front ones for a body without hind limbs, the height for neither), so it
needs no rest pose to stand upright.
"""
from __future__ import annotations

from typing import List, Optional, Sequence, Tuple

import numpy as np

from satagraph.data.features import MotionFeatures, motion_to_features
from satagraph.motion import SLIDE_HEIGHT, Motion
from satagraph.semantics.limbs import LIMBS, limb_end_index
from satagraph.skeleton import Skeleton
from satagraph.transforms.canonical import FLOOR_PERCENTILE, canonicalize

#: Per-frame root channels.
ROOT_CHANNELS: List[str] = ["forward", "lateral", "yaw_rate", "root_height"]
#: Per-frame channels: root, then limb-end positions and velocities.
FRAME_CHANNELS: List[str] = ROOT_CHANNELS + [
    f"{limb} {kind} {axis}" for kind in ("pos", "vel") for limb in LIMBS for axis in "xyz"]
#: Statistics pooled over the clip, then thirds of the clip (means).
POOLS: List[str] = ["mean", "std", "q10", "q90", "first", "middle", "last"]
#: Width of :func:`describe_features`'s vector.
DESCRIPTOR_DIM = len(POOLS) * len(FRAME_CHANNELS) + len(LIMBS)
#: Standard gravity (m/s^2), for Froude-normalised speed.
GRAVITY = 9.81


def _chain_length(skeleton: Skeleton, joint: int) -> float:
    """Sum of bone lengths from the root to :obj:`joint`."""
    total, j = 0.0, joint
    while j > 0:
        total += float(np.linalg.norm(skeleton.offsets[j]))
        j = int(skeleton.parents[j])
    return total


def leg_length(skeleton: Skeleton, ends: Optional[Sequence[int]] = None,
               height: float = 1.0) -> float:
    """Mean root-to-foot chain length of the hind limbs (front limbs for a
    body without them; :obj:`height` for a body without limbs).

    Args:
        skeleton: The skeleton.
        ends: Limb ends in :data:`LIMBS` order (``-1``: missing); default
            :func:`~satagraph.semantics.limbs.limb_end_index`.
        height: Fallback length.
    """
    ends = limb_end_index(skeleton) if ends is None else list(ends)
    for pair in (ends[2:], ends[:2]):
        lengths = [_chain_length(skeleton, j) for j in pair if j >= 0]
        lengths = [v for v in lengths if v > 1e-6]
        if lengths:
            return float(np.mean(lengths))
    return float(height)


def limb_mask(ends: Sequence[int]) -> np.ndarray:
    """1 for each limb of :data:`LIMBS` the skeleton has, else 0.

    Shapes:
        - **output**: :math:`(4,)`
    """
    return np.array([float(j >= 0) for j in ends])


def _limb_channels(values: np.ndarray, ends: Sequence[int], scale: float) -> np.ndarray:
    """Per-limb 3-vectors relative to the root, divided by :obj:`scale`
    (zero for a missing limb), flattened.

    Shapes:
        - **values**: :math:`(T, J, 3)`
        - **output**: :math:`(T, 12)`
    """
    out = np.zeros((values.shape[0], len(ends), 3))
    for k, j in enumerate(ends):
        if j >= 0:
            out[:, k] = (values[:, j] - values[:, 0]) / scale
    return out.reshape(values.shape[0], -1)


def frame_descriptor(feats: MotionFeatures, ends: Optional[Sequence[int]] = None
                     ) -> np.ndarray:
    r"""Per-frame channels (:data:`FRAME_CHANNELS`) of a canonical motion's
    features; the first frame is dropped (its velocities are not the
    clip's).

    Args:
        feats: Features of a canonical motion
            (:func:`~satagraph.data.features.motion_to_features`).
        ends: Limb ends in :data:`LIMBS` order (default: found by
            :func:`~satagraph.semantics.limbs.limb_end_index`).

    Shapes:
        - **output**: :math:`(T - 1, 28)`
    """
    ends = limb_end_index(feats.skeleton) if ends is None else list(ends)
    height = max(float(feats.height), 1e-6)
    leg = max(leg_length(feats.skeleton, ends, height), 1e-6)
    r = feats.r[1:]
    root = np.stack([r[:, 2] / leg, r[:, 1] / leg, r[:, 0], r[:, 3] / leg], axis=1)
    pos = _limb_channels(feats.x[1:], ends, height)
    vel = _limb_channels(feats.v_x[1:], ends, height)
    return np.concatenate([root, pos, vel], axis=1)


def pool_frames(frames: np.ndarray) -> np.ndarray:
    r"""Statistics of per-frame channels over time (:data:`POOLS` order):
    mean, std, 10th and 90th percentile, means of the three thirds.

    Shapes:
        - **frames**: :math:`(T, C)`, :math:`T \ge 1`
        - **output**: :math:`(7 C,)`
    """
    if frames.shape[0] == 0:
        raise ValueError("a motion needs at least 2 frames to be described")
    q10, q90 = np.percentile(frames, [10, 90], axis=0)
    thirds = [part.mean(axis=0) if len(part) else frames.mean(axis=0)
              for part in np.array_split(frames, 3)]
    return np.concatenate([frames.mean(axis=0), frames.std(axis=0), q10, q90, *thirds])


def describe_features(feats: MotionFeatures, ends: Optional[Sequence[int]] = None
                      ) -> np.ndarray:
    r"""The pooled descriptor of a canonical motion's features.

    Args:
        feats: Features of a canonical motion.
        ends: Limb ends in :data:`LIMBS` order (default: found by name).

    Shapes:
        - **output**: :math:`(D,)`, :data:`DESCRIPTOR_DIM`
    """
    ends = limb_end_index(feats.skeleton) if ends is None else list(ends)
    return np.concatenate([pool_frames(frame_descriptor(feats, ends)), limb_mask(ends)])


def canonical_features(motion: Motion, fps: float = 30.0, up_axis: Optional[str] = None,
                       unit_scale: Optional[float] = None) -> MotionFeatures:
    """Features of a motion brought to the canonical frame (see
    :func:`~satagraph.transforms.canonicalize`; a canonical motion stays
    as it is)."""
    return motion_to_features(canonicalize(motion, fps=fps, up_axis=up_axis,
                                           unit_scale=unit_scale))


def describe_motion(motion: Motion, fps: float = 30.0, up_axis: Optional[str] = None,
                    unit_scale: Optional[float] = None) -> np.ndarray:
    r"""The descriptor of any motion (a BVH read on any rig): canonicalised
    at :obj:`fps`, then :func:`describe_features`.

    Shapes:
        - **output**: :math:`(D,)`, :data:`DESCRIPTOR_DIM`
    """
    return describe_features(canonical_features(motion, fps, up_axis, unit_scale))


def froude_speed(feats: MotionFeatures, ends: Optional[Sequence[int]] = None) -> float:
    r"""Mean ground speed of the root as a Froude-normalised speed
    :math:`v / \sqrt{g L}` (:math:`L`: :func:`leg_length` in metres), which
    orders walk < run < dash alike on any body size."""
    ends = limb_end_index(feats.skeleton) if ends is None else list(ends)
    leg = max(leg_length(feats.skeleton, ends, float(feats.height)), 1e-6)
    speed = np.linalg.norm(feats.r[1:, 1:3], axis=1).mean() if feats.num_frames > 1 else 0.0
    return float(speed / np.sqrt(GRAVITY * leg))


def contact_quality(feats: MotionFeatures) -> Tuple[float, float]:
    r"""Foot sliding and hovering of a motion, in character heights.

    Foot sliding is the horizontal speed (per second) of every joint near
    the ground, averaged with SAME's weights
    :math:`\mathrm{clamp}(2 - 2^{h / H_0}, 0, 1)` (:data:`SLIDE_HEIGHT`).
    Hovering is the mean over frames of the lowest joint's height above
    the motion's floor (its :data:`~satagraph.transforms.canonical.FLOOR_PERCENTILE`
    of the per-frame lowest joint, as :func:`canonicalize` puts it): below
    0.01 for captured walks, whose feet keep to the floor, more for a body
    that bobs off it. It does not depend on where the floor was put, as a
    depth below the floor would (zero by construction once
    :func:`canonicalize` has put the floor there); a mean, not a median,
    so that a body standing on the floor in half its frames and off it in
    the rest (what :func:`~satagraph.transforms.ground.lift_above_floor`
    leaves of a bobbing one) still reads its hovering half."""
    height = max(float(feats.height), 1e-6)
    slide = 0.0
    if feats.num_frames > 1:
        y = feats.x[1:, :, 1]
        weight = np.clip(2.0 - 2.0 ** (y / (SLIDE_HEIGHT * height)), 0.0, 1.0)
        speed = np.linalg.norm(feats.v_x[1:][..., [0, 2]], axis=-1)
        slide = float((weight * speed).sum() / max(weight.sum(), 1e-6) / height)
    if feats.num_frames == 0:
        return slide, 0.0
    lowest = feats.x[:, :, 1].min(axis=1)
    return slide, float(np.mean(lowest) - np.percentile(lowest, FLOOR_PERCENTILE)) / height


def channel_index(channel: str, pool: str = "mean") -> int:
    """Position of one channel's pooled statistic in the descriptor."""
    return POOLS.index(pool) * len(FRAME_CHANNELS) + FRAME_CHANNELS.index(channel)


__all__ = ["DESCRIPTOR_DIM", "FRAME_CHANNELS", "POOLS", "ROOT_CHANNELS", "canonical_features",
           "channel_index", "contact_quality", "describe_features", "describe_motion", "frame_descriptor",
           "froude_speed", "leg_length", "limb_mask", "pool_frames"]
