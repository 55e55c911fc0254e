r"""Padding-free per-frame self-attention for :class:`GPSConv`.

PyG's :class:`~torch_geometric.nn.conv.GPSConv` pads every graph of a batch
to the largest one (:func:`~torch_geometric.utils.to_dense_batch`) before its
multi-head attention. In a batch that mixes a 21-joint dog with a 142-node
rig, the dog's frames are padded sevenfold and the attention cost grows with
the square of that. Frames of one clip share a skeleton, and clips are
contiguous in a :class:`~satagraph.data.FrameBatch`, so the frames can instead
be grouped by joint count and attended to as dense, unpadded blocks.
"""
from __future__ import annotations

from typing import List, Optional, Tuple

import torch
import torch.nn.functional as F
from torch import Tensor, nn
from torch_geometric.nn import GPSConv

from satagraph.nn.layers.dropout import fast_dropout


def joint_count_groups(frames) -> List[Tuple[int, Optional[Tensor]]]:
    r"""Nodes of a :class:`~satagraph.data.FrameBatch` grouped by the joint
    count of their clip.

    Returns:
        A list of ``(J, index)``: ``index`` holds, frame after frame, the nodes
        of every clip with :math:`J` joints (``None`` when the whole batch has
        one joint count: the identity).
    """
    joints = frames.clip_num_joints.cpu()
    sizes = frames.clip_num_frames.cpu() * joints
    counts = torch.unique(joints)
    if counts.numel() == 1:
        return [(int(counts), None)]
    starts = sizes.cumsum(0) - sizes
    device = frames.x.device if frames.x is not None else frames.batch.device
    groups = []
    for count in counts.tolist():
        chosen = joints == count
        length, start = sizes[chosen], starts[chosen]
        first = length.cumsum(0) - length
        local = torch.arange(int(length.sum())) - first.repeat_interleave(length)
        groups.append((count, (start.repeat_interleave(length) + local).to(device)))
    return groups


def dense_self_attention(attn: nn.MultiheadAttention, h: Tensor) -> Tensor:
    r"""Multi-head self-attention with :obj:`attn`'s weights over unpadded
    sets, through :func:`torch.nn.functional.scaled_dot_product_attention`.

    Shapes:
        - **h**: :math:`(B, J, C)`, **output**: :math:`(B, J, C)`
    """
    size, num, channels = h.shape
    heads = attn.num_heads
    qkv = F.linear(h, attn.in_proj_weight, attn.in_proj_bias)
    qkv = qkv.view(size, num, 3, heads, channels // heads).permute(2, 0, 3, 1, 4)
    dropout = attn.dropout if attn.training else 0.0
    out = F.scaled_dot_product_attention(qkv[0], qkv[1], qkv[2], dropout_p=dropout)
    out = out.transpose(1, 2).reshape(size, num, channels)
    return attn.out_proj(out)


def frame_self_attention(attn: nn.MultiheadAttention, x: Tensor, frames) -> Tensor:
    r"""Self-attention within each frame graph of :obj:`frames`, without
    padding (equal to :class:`GPSConv`'s padded attention).

    Shapes:
        - **x**: :math:`(N, C)` in the node order of :obj:`frames`
        - **output**: :math:`(N, C)`
    """
    channels = x.shape[-1]
    out = None
    for count, index in joint_count_groups(frames):
        if index is None:
            return dense_self_attention(attn, x.view(-1, count, channels)).view(-1, channels)
        h = dense_self_attention(attn, x[index].view(-1, count, channels))
        if out is None:  # the attention's dtype: autocast may lower it
            out = h.new_empty(x.shape)
        out = out.index_copy(0, index, h.view(-1, channels))
    return out


class FrameGPSConv(GPSConv):
    r""":class:`~torch_geometric.nn.conv.GPSConv` whose attention runs per
    skeleton group without padding when a
    :class:`~satagraph.data.FrameBatch` is passed as :obj:`frames` (same
    parameters, same state dict, same results as :class:`GPSConv`; without
    :obj:`frames` it is :class:`GPSConv`).

    Shapes:
        - **x**: :math:`(N, C)`, **output**: :math:`(N, C)`
    """

    def forward(self, x: Tensor, edge_index: Tensor, batch: Optional[Tensor] = None,
                frames=None, **kwargs) -> Tensor:
        if frames is None or not isinstance(self.attn, nn.MultiheadAttention):
            return super().forward(x, edge_index, batch, **kwargs)
        parts = []
        if self.conv is not None:
            h = fast_dropout(self.conv(x, edge_index, **kwargs), self.dropout, self.training)
            parts.append(self._norm(self.norm1, h + x, batch))
        h = fast_dropout(frame_self_attention(self.attn, x, frames), self.dropout,
                         self.training)
        parts.append(self._norm(self.norm2, h + x, batch))
        out = parts[0] if len(parts) == 1 else parts[0] + parts[1]
        return self._norm(self.norm3, out + self.mlp(out), batch)

    def _norm(self, norm: Optional[nn.Module], h: Tensor, batch: Optional[Tensor]) -> Tensor:
        if norm is None:
            return h
        return norm(h, batch=batch) if self.norm_with_batch else norm(h)
