"""Node features of frame graphs <-> per-joint temporal streams."""
from __future__ import annotations

from typing import Any, Tuple

import torch
from torch import Tensor


def _node_slot(batch: Any) -> Tensor:
    """Row of every node in the flattened :math:`(S T_{max})` streams."""
    return batch.node_stream * batch.max_time + batch.node_time


def _slot_node(batch: Any) -> Tuple[Tensor, Tensor]:
    """Node at every stream slot (an arbitrary valid node at padding) and
    the mask of real frames, from per-clip sizes (no pass over nodes)."""
    joints, frames = batch.clip_num_joints, batch.clip_num_frames
    clip = batch.stream_clip
    clip_start = (frames * joints).cumsum(0) - frames * joints
    stream = torch.arange(batch.num_streams, device=clip.device)
    first = clip_start[clip] + stream - (joints.cumsum(0) - joints)[clip]
    time = torch.arange(batch.max_time, device=clip.device)
    mask = stream_mask(batch)
    node = first.unsqueeze(-1) + time * joints[clip].unsqueeze(-1)
    return torch.where(mask, node, 0), mask


def stream_mask(batch: Any) -> Tensor:
    r"""Real frames of every stream (``True``) of a
    :class:`~satagraph.data.FrameBatch`.

    Shapes:
        - **output**: :math:`(S, T_{max})`
    """
    time = torch.arange(batch.max_time, device=batch.stream_clip.device)
    return time < batch.clip_num_frames[batch.stream_clip].unsqueeze(-1)


def to_temporal_streams(x: Tensor, batch: Any) -> Tuple[Tensor, Tensor]:
    r"""Rearranges node features of a :class:`~satagraph.data.FrameBatch`
    into one sequence per joint of every clip (a *stream*), padded with
    zeros after the last frame of shorter clips.

    Node (clip :math:`s`, frame :math:`t`, joint :math:`j`) goes to stream
    ``stream_offset_s + j`` at time :math:`t`. Differentiable, no host sync.

    Args:
        x (Tensor): Node features.
        batch (FrameBatch): The frame graphs (uses :obj:`num_streams`,
            :obj:`max_time`, :obj:`stream_clip`, :obj:`clip_num_frames`,
            :obj:`clip_num_joints`).

    Returns:
        (Tensor, Tensor): The streams and their mask (``True`` = real frame).

    Shapes:
        - **x**: :math:`(N, F)`
        - **output**: :math:`(S, T_{max}, F)` and :math:`(S, T_{max})`
    """
    if x.dim() != 2 or x.size(0) != batch.num_nodes:
        raise ValueError(f"to_temporal_streams: x must be (N, F) with the batch's "
                         f"N = {batch.num_nodes} nodes, got {tuple(x.shape)}")
    node, mask = _slot_node(batch)
    out = x.index_select(0, node.view(-1))  # a gather: faster than a scatter
    if x.size(0) != mask.numel():  # some clips are shorter than max_time
        out.masked_fill_(~mask.view(-1, 1), 0)
    return out.view(batch.num_streams, batch.max_time, -1), mask


def from_temporal_streams(streams: Tensor, batch: Any) -> Tensor:
    r"""Inverse of :func:`to_temporal_streams`: node features from streams
    (padding positions are dropped). Differentiable, no host sync.

    Args:
        streams (Tensor): Per-joint streams.
        batch (FrameBatch): The frame graphs (uses :obj:`node_stream`,
            :obj:`node_time`, :obj:`max_time`).

    Shapes:
        - **streams**: :math:`(S, T_{max}, F)`
        - **output**: :math:`(N, F)`
    """
    if streams.dim() != 3 or tuple(streams.shape[:2]) != (batch.num_streams, batch.max_time):
        raise ValueError(f"from_temporal_streams: streams must be (S, T_max, F) with the "
                         f"batch's S = {batch.num_streams} streams and T_max = "
                         f"{batch.max_time} frames, got {tuple(streams.shape)}")
    flat = streams.reshape(-1, streams.size(-1))
    return flat.index_select(0, _node_slot(batch))
