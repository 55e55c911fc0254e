"""Joint positions from predicted rotations and root features, on frame-graph
batches: in each frame's facing frame, in the world, and in units of the
character's height (what the positional loss terms compare)."""
from __future__ import annotations

from typing import Optional, Tuple

import torch.nn.functional as F
from torch import Tensor

from satagraph.ops.fk import fk_levels, forward_kinematics
from satagraph.ops.motion_batch import integrate_root_batch
from satagraph.ops.rotation import rotation_6d_to_matrix, yaw_matrix

#: Units per character height of the position terms (SAME's cm, 1.75 m human).
POSITION_SCALE = 175.0


def facing_positions(q: Tensor, r: Tensor, batch) -> Tensor:
    r"""Joint positions in each frame's facing frame by forward kinematics
    (rest offsets ``X_l``, root at ``(0, h, 0)``), physical units.

    Shapes:
        - **q**: :math:`(N, 6)`, **r**: :math:`(G, 4)`
        - **output**: :math:`(N, 3)`
    """
    offsets = batch.joint_static[batch.node_stream, :3].to(q.dtype)
    height = F.pad(r[:, 3:4], (1, 1))  # (0, h, 0)
    offsets = offsets.index_copy(0, batch.root_node, height.to(q.dtype))
    levels = fk_levels(batch.node_parent, batch.node_depth)
    return forward_kinematics(rotation_6d_to_matrix(q), offsets, batch.node_parent,
                              levels)[1]


def to_global(pos: Tensor, r: Tensor, batch, fps: Optional[float] = None) -> Tensor:
    r"""Facing-frame positions to global ones: :math:`F_t` (yaw and ground
    origin integrated from ``r`` at :obj:`fps`, by default the batch's;
    every clip starting at the origin).

    Shapes:
        - **pos**: :math:`(N, 3)`, **r**: :math:`(G, 4)`
        - **output**: :math:`(N, 3)`
    """
    fps = batch.fps if fps is None else fps
    theta, origin = integrate_root_batch(r, batch.clip_num_frames, fps)
    frame = batch.batch
    return (yaw_matrix(theta)[frame] @ pos[..., None])[..., 0] + origin[frame]


def position_scale(batch, scale: float = POSITION_SCALE) -> Tensor:
    """Factor per node turning physical lengths into :obj:`scale` units per
    character height, :math:`(N, 1)`."""
    return (scale / batch.clip_height)[batch.node_clip][:, None]


def time_difference(pos: Tensor, batch, order: int = 2) -> Tuple[Tensor, Tensor]:
    r"""Finite difference of :obj:`order` over time within each clip, and
    the nodes where it is defined (``node_time >= order``).

    Shapes:
        - **pos**: :math:`(N, F)`
        - **output**: :math:`(N, F)` and :math:`(N,)` bool
    """
    prev = batch.node_prev
    diff = pos
    for _ in range(order):  # loop over the order (2 or 3), not over frames
        diff = diff - diff[prev]
    return diff, batch.node_time >= order


__all__ = ["POSITION_SCALE", "facing_positions", "to_global", "position_scale",
           "time_difference"]
