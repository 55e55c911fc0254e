"""Global motion of a batch of frame graphs (mixed skeletons and lengths)."""
from __future__ import annotations

from typing import Optional, Tuple

import torch
from torch import Tensor

from satagraph.ops.fk import fk_levels, forward_kinematics
from satagraph.ops.rotation import rotation_6d_to_matrix, yaw_matrix


def segment_cumsum(value: Tensor, num_frames: Tensor) -> Tensor:
    r"""Cumulative sum restarted at the first frame of every clip.

    Shapes:
        - **value**: :math:`(G, *)` frames of all clips, clip after clip
        - **num_frames**: :math:`(B,)`
    """
    total = value.cumsum(0)
    ends = num_frames.cumsum(0)
    before = torch.cat([value.new_zeros((1,) + value.shape[1:]), total[ends[:-1] - 1]])
    return total - before.repeat_interleave(num_frames, dim=0)


def integrate_root_batch(r: Tensor, num_frames: Tensor, fps: float) -> Tuple[Tensor, Tensor]:
    r"""Facing yaw and ground origin of every frame from root features,
    each clip starting at the world origin facing +Z.

    Shapes:
        - **r**: :math:`(G, 4)`
        - **output**: yaw :math:`(G,)`, origin :math:`(G, 3)`
    """
    theta = segment_cumsum(r[:, 0] / fps, num_frames)
    prev = theta - r[:, 0] / fps
    step = torch.stack([r[:, 1], torch.zeros_like(r[:, 1]), r[:, 2]], -1) / fps
    disp = (yaw_matrix(prev) @ step[..., None])[..., 0]
    return theta, segment_cumsum(disp, num_frames)


def batch_global_motion(q: Tensor, r: Tensor, batch, fps: Optional[float] = None,
                        offsets: Tensor = None) -> Tuple[Tensor, Tensor, Tensor]:
    r"""Local and global rotations and global positions of every node.

    Args:
        q (Tensor): 6D local rotations (the root's relative to its facing
            frame), physical units.
        r (Tensor): Root features per frame (yaw velocity, xz velocity,
            height), physical units.
        batch (FrameBatch): The frame graphs.
        fps (float, optional): Frame rate of the features (default: the
            batch's, :attr:`FrameBatch.fps`).
        offsets (Tensor, optional): Local offsets per node; by default
            ``X_l`` of each node's joint (``joint_static[:, :3]``).

    Shapes:
        - **q**: :math:`(N, 6)`, **r**: :math:`(G, 4)`
        - **output**: local :math:`(N, 3, 3)`, global rotations
          :math:`(N, 3, 3)`, positions :math:`(N, 3)`
    """
    local = rotation_6d_to_matrix(q)
    fps = batch.fps if fps is None else fps
    theta, origin = integrate_root_batch(r, batch.clip_num_frames, fps)
    root = batch.root_node
    rot = local.index_copy(0, root, yaw_matrix(theta) @ local[root])
    if offsets is None:
        offsets = batch.joint_static[batch.node_stream, :3]
    height = torch.stack([torch.zeros_like(r[:, 3]), r[:, 3], torch.zeros_like(r[:, 3])], -1)
    offsets = offsets.index_copy(0, root, origin + height)
    levels = fk_levels(batch.node_parent, batch.node_depth)
    glob_rot, pos = forward_kinematics(rot, offsets, batch.node_parent, levels)
    return local, glob_rot, pos
