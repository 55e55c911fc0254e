r"""Motion metrics as SAME defines them (DESIGN.md section 5), per clip.

All functions work on a batch of frame graphs with mixed skeletons and
return one value per clip, so that results can be averaged per dataset.

- JR: mean geodesic angle (radians) between predicted and true local
  rotations, over joints with children.
- RT: mean root xz trajectory error.  JP: mean global joint position error.
  Both in the motion's units (metres after canonicalisation), and divided
  by the character height (``*_h``).
- FS: foot sliding: horizontal displacement per frame of every joint,
  weighted by ``clamp(2 - 2^(h / H0), 0, 1)`` (``H0`` = 3 cm for a 1.75 m
  character, scaled with the height).
- GP: ground penetration: mean of ``min(y, 0)`` (signed, as SAME).
- Retarget error: ``1000 * mean ||p - p_hat||^2 / H^2``.
"""
from __future__ import annotations

from typing import Dict

import torch
from torch import Tensor
from torch_geometric.utils import scatter

from satagraph.motion import SLIDE_HEIGHT
from satagraph.ops.rotation import geodesic_angle


def _per_clip(value: Tensor, clip: Tensor, num_clips: int) -> Tensor:
    return scatter(value, clip, dim=0, dim_size=num_clips, reduce="mean")


def joint_rotation_error(local_pred: Tensor, local_true: Tensor, batch) -> Tensor:
    """JR per clip (radians), over joints with children."""
    angle = geodesic_angle(local_pred, local_true)
    inner, clip = batch.node_inner, batch.node_clip
    num = len(batch.meta)
    total = scatter(angle * inner, clip, dim=0, dim_size=num, reduce="sum")
    count = scatter(inner.float(), clip, dim=0, dim_size=num, reduce="sum")
    return total / count.clamp(min=1)


def root_trajectory_error(pos_pred: Tensor, pos_true: Tensor, batch) -> Tensor:
    """RT per clip: mean root xz distance."""
    root = batch.root_node
    err = (pos_pred[root][:, [0, 2]] - pos_true[root][:, [0, 2]]).norm(dim=-1)
    return _per_clip(err, batch.frame_clip, len(batch.meta))


def joint_position_error(pos_pred: Tensor, pos_true: Tensor, batch) -> Tensor:
    """JP per clip: mean global joint position distance."""
    err = (pos_pred - pos_true).norm(dim=-1)
    return _per_clip(err, batch.node_clip, len(batch.meta))


def foot_sliding(pos: Tensor, batch) -> Tensor:
    """FS per clip: height-weighted horizontal displacement per frame."""
    clip = batch.node_clip
    h0 = SLIDE_HEIGHT * batch.clip_height[clip]
    weight = (2 - torch.pow(2.0, pos[:, 1] / h0)).clamp(0, 1)
    step = (pos - pos[batch.node_prev])[:, [0, 2]].norm(dim=-1)
    moving = batch.node_time > 0
    num = len(batch.meta)
    total = scatter(step * weight * moving, clip, dim=0, dim_size=num, reduce="sum")
    count = scatter(moving.float(), clip, dim=0, dim_size=num, reduce="sum")
    return total / count.clamp(min=1)


def ground_penetration(pos: Tensor, batch) -> Tensor:
    """GP per clip: mean of min(y, 0) (negative when below the ground)."""
    return _per_clip(pos[:, 1].clamp(max=0), batch.node_clip, len(batch.meta))


def retarget_error(pos_pred: Tensor, pos_true: Tensor, batch) -> Tensor:
    """SAN/SAME retarget error per clip: 1000 * mean squared distance / H^2."""
    err = ((pos_pred - pos_true) ** 2).sum(-1)
    heights = batch.clip_height
    return 1000 * _per_clip(err, batch.node_clip, len(batch.meta)) / heights ** 2


def motion_metrics(local_pred: Tensor, pos_pred: Tensor, local_true: Tensor,
                   pos_true: Tensor, batch) -> Dict[str, Tensor]:
    r"""All metrics per clip: ``JR, RT, RT_h, JP, JP_h, FS, GP, RE``."""
    heights = batch.clip_height
    rt = root_trajectory_error(pos_pred, pos_true, batch)
    jp = joint_position_error(pos_pred, pos_true, batch)
    return {
        "JR": joint_rotation_error(local_pred, local_true, batch),
        "RT": rt, "RT_h": rt / heights, "JP": jp, "JP_h": jp / heights,
        "FS": foot_sliding(pos_pred, batch), "GP": ground_penetration(pos_pred, batch),
        "RE": retarget_error(pos_pred, pos_true, batch),
    }
