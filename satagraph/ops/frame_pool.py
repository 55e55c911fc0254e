"""Consecutive frames of batched clips pooled into groups, and back."""
from __future__ import annotations

import torch
from torch import Tensor


def frame_groups(num_frames: Tensor, size: int) -> Tensor:
    r"""The group of every frame of consecutive clips: each clip's frames in
    runs of :obj:`size` from its first frame (its last run shorter where
    :obj:`size` does not divide its length), numbered across the batch.
    Groups never span two clips.

    Args:
        num_frames (Tensor): Frames per clip, summing to :math:`G`.
        size (int): Frames per group (1: one group per frame).

    Shapes:
        - **num_frames**: :math:`(B,)`
        - **output**: :math:`(G,)` long, in :math:`[0, G')`, non-decreasing
    """
    if size < 1:
        raise ValueError(f"frame_groups: size must be at least 1, got {size}")
    num_frames = num_frames.long()
    groups = (num_frames + size - 1) // size
    clip = torch.repeat_interleave(torch.arange(num_frames.numel(), device=num_frames.device),
                                   num_frames)
    start = num_frames.cumsum(0) - num_frames
    time = torch.arange(clip.numel(), device=num_frames.device) - start[clip]
    return (groups.cumsum(0) - groups)[clip] + time // size


def pool_frames(x: Tensor, group: Tensor) -> Tensor:
    r"""The mean of :obj:`x` over the frames of each group
    (:func:`frame_groups`); ``out[group]`` spreads it back over the frames.

    Shapes:
        - **x**: :math:`(G, C)`, **group**: :math:`(G,)`
        - **output**: :math:`(G', C)`
    """
    count = int(group.max()) + 1 if group.numel() else 0
    total = x.new_zeros(count, x.size(-1)).index_add_(0, group, x)
    sizes = torch.bincount(group, minlength=count).clamp(min=1).to(x.dtype)
    return total / sizes.unsqueeze(-1)


__all__ = ["frame_groups", "pool_frames"]
