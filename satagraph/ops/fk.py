"""Forward kinematics over a parent array (torch, batched, differentiable)."""
from __future__ import annotations

from typing import List, Optional, Tuple

import torch
from torch import Tensor


def fk_levels(parent: Tensor, depth: Optional[Tensor] = None) -> List[Tensor]:
    r"""Joint indices grouped by depth, root level first.

    Works on the concatenated joints of several skeletons (or of many frames):
    every entry of :obj:`parent` is a global index, ``-1`` marks a root.
    Parents must come before their children. Passing :obj:`depth` (known from
    the skeletons) avoids a pass over the joints.

    Shapes:
        - **parent**: :math:`(N,)`
        - **depth**: :math:`(N,)`, optional
    """
    if depth is None:
        parent = parent.cpu().long()
        if (parent >= torch.arange(parent.numel())).any():
            raise ValueError("fk_levels: parents must come before children")
        has_parent = parent >= 0
        depth = torch.zeros_like(parent)
        while True:  # one vectorised step per level of the deepest chain
            new = torch.where(has_parent, depth[parent.clamp(min=0)] + 1, 0)
            if torch.equal(new, depth):
                break
            depth = new
    depth = depth.cpu().long()
    order = torch.argsort(depth, stable=True)
    counts = torch.bincount(depth).tolist()
    return [idx for idx in torch.split(order, counts) if idx.numel()]


def forward_kinematics(
    rotation: Tensor,
    offset: Tensor,
    parent: Tensor,
    levels: Optional[List[Tensor]] = None,
) -> Tuple[Tensor, Tensor]:
    r"""Global rotations and positions from local rotations and offsets.

    The joints of several different skeletons may be concatenated along the
    joint dimension (their parents given as global indices): all of them are
    processed at once, one level of depth at a time.

    Args:
        rotation (Tensor): Local rotation matrices.
        offset (Tensor): Local translations (rest offsets, or per-frame
            translations; the root's is its global position).
        parent (Tensor): Parent index per joint, ``-1`` for roots.
        levels (list[Tensor], optional): Precomputed :func:`fk_levels`.

    Shapes:
        - **rotation**: :math:`(*, N, 3, 3)`
        - **offset**: :math:`(*, N, 3)` or :math:`(N, 3)`
        - **parent**: :math:`(N,)`
        - **output**: global rotations :math:`(*, N, 3, 3)` and positions
          :math:`(*, N, 3)`
    """
    if levels is None:
        levels = fk_levels(parent)
    parent = parent.to(rotation.device)
    offset = offset.to(rotation.dtype).expand(*rotation.shape[:-2], 3)
    needs_grad = torch.is_grad_enabled() and (rotation.requires_grad
                                              or offset.requires_grad)
    if needs_grad:
        return _fk_functional(rotation, offset, parent, levels)
    glob_rot, glob_pos = rotation.clone(), offset.clone()
    for idx in levels[1:]:
        idx = idx.to(rotation.device)
        par = parent[idx]
        prot = glob_rot[..., par, :, :]
        glob_rot[..., idx, :, :] = prot @ rotation[..., idx, :, :]
        glob_pos[..., idx, :] = glob_pos[..., par, :] + (
            prot @ offset[..., idx, :, None])[..., 0]
    return glob_rot, glob_pos


def _fk_functional(rotation: Tensor, offset: Tensor, parent: Tensor,
                   levels: List[Tensor]) -> Tuple[Tensor, Tensor]:
    """Out-of-place FK for autograd."""
    glob_rot, glob_pos = rotation, offset
    for idx in levels[1:]:
        idx = idx.to(rotation.device)
        par = parent[idx]
        prot = glob_rot[..., par, :, :]
        new_rot = prot @ rotation[..., idx, :, :]
        new_pos = glob_pos[..., par, :] + (prot @ offset[..., idx, :, None])[..., 0]
        glob_rot = glob_rot.index_copy(-3, idx, new_rot)
        glob_pos = glob_pos.index_copy(-2, idx, new_pos)
    return glob_rot, glob_pos
