"""Skeleton augmentation that yields paired ground truth for retargeting."""
from __future__ import annotations

from typing import Tuple

import numpy as np

from satagraph.motion import Motion


def scale_bones(motion: Motion, low: float = 0.8, high: float = 1.2,
                seed: int = 0) -> Motion:
    r"""The same motion on a differently proportioned copy of its skeleton.

    Every bone offset is scaled per axis by a factor drawn uniformly from
    ``[low, high]`` (mirror pairs are not forced to match). Local rotations
    are kept, and the root trajectory is scaled by the ratio of the first
    frame's root heights above the lowest joint (leg length), so the result
    is the ground truth of retargeting :obj:`motion` onto the new skeleton.

    Args:
        motion (Motion): A motion (canonical or not, +Y up for the height).
        low (float): Smallest per-axis scale.
        high (float): Largest per-axis scale.
        seed (int): Random seed.
    """
    rng = np.random.default_rng(seed)
    skel = motion.skeleton
    scale = rng.uniform(low, high, size=skel.offsets.shape)
    scale[0] = 1.0
    offsets = skel.offsets * scale
    new = skel.replace(offsets=offsets)
    trans = motion.translations * scale[None]
    trans[:, 0] = motion.translations[:, 0]
    scaled = motion.with_(skeleton=new, translations=trans)
    ratio = _leg_ratio(_pose(motion), _pose(scaled))
    trans[:, 0] = motion.translations[:, 0] * ratio
    return motion.with_(skeleton=new, translations=trans)


def _pose(motion: Motion) -> np.ndarray:
    """First frame's global positions (the rest pose without frames)."""
    if motion.num_frames == 0:
        return motion.skeleton.rest_positions()
    return motion.slice(0, 1).global_positions()[0]


def _leg_ratio(old: np.ndarray, new: np.ndarray) -> float:
    """Ratio of root heights above the lowest joint."""
    def leg(pos: np.ndarray) -> float:
        return max(pos[0, 1] - pos[:, 1].min(), 1e-6)
    return leg(new) / leg(old)


def paired(motion: Motion, seed: int = 0, low: float = 0.8,
           high: float = 1.2) -> Tuple[Motion, Motion]:
    """(source, scaled ground truth) pair for retargeting evaluation."""
    return motion, scale_bones(motion, low, high, seed)
