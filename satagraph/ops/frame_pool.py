"""Consecutive frames of batched clips pooled into groups, and back."""
from __future__ import annotations

from typing import Any

from torch import Tensor
from torch_geometric.utils import scatter


def frame_groups(batch: Any, size: int) -> Tensor:
    r"""The group of every frame graph of a
    :class:`~satagraph.data.FrameBatch`: each clip's frames in runs of
    :obj:`size` from its first frame (its last run shorter where
    :obj:`size` does not divide its length), numbered across the batch
    (from the batch's ``frame_clip``, ``frame_time`` and
    ``clip_num_frames``). Groups never span two clips.

    Args:
        batch: A frame batch.
        size (int): Frames per group (1: one group per frame).

    Shapes:
        - **output**: :math:`(G,)` long, in :math:`[0, G')`, non-decreasing
    """
    if size < 1:
        raise ValueError(f"frame_groups: size must be at least 1, got {size}")
    groups = (batch.clip_num_frames.long() + size - 1) // size
    return (groups.cumsum(0) - groups)[batch.frame_clip] + batch.frame_time // size


def pool_frames(x: Tensor, group: Tensor) -> Tensor:
    r"""The mean of :obj:`x` over the frames of each group
    (:func:`frame_groups`); ``out[group]`` spreads it back over the frames.

    Shapes:
        - **x**: :math:`(G, C)`, **group**: :math:`(G,)`
        - **output**: :math:`(G', C)`
    """
    return scatter(x, group, dim=0, reduce="mean")


__all__ = ["frame_groups", "pool_frames"]
