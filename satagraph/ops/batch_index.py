"""Index helpers of a batch of frame graphs (:class:`~satagraph.data.collate.FrameBatch`):
the clip of every node, the clip heights and the same joint one frame
earlier. Shared by the losses, the metrics and the padded baseline."""
from __future__ import annotations

import torch
from torch import Tensor


def node_clip(batch) -> Tensor:
    """Clip id of every node."""
    return batch.stream_clip[batch.node_stream]


def clip_heights(batch) -> Tensor:
    """Character height per clip (from the clips' meta), :math:`(B,)`."""
    return torch.tensor([float(m.get("height", 1.0)) for m in batch.meta],
                        device=batch.x.device)


def previous_node(batch) -> Tensor:
    """Index of the same joint one frame earlier (itself at frame 0)."""
    joints = batch.clip_num_joints[node_clip(batch)]
    return torch.where(batch.node_time > 0, torch.arange(
        batch.num_nodes, device=joints.device) - joints, torch.arange(
        batch.num_nodes, device=joints.device))


__all__ = ["node_clip", "clip_heights", "previous_node"]
