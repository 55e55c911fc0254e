"""Forward kinematics over a parent array (torch, batched, differentiable;
and a numpy version for single clips without gradients)."""
from __future__ import annotations

from typing import List, Optional, Tuple

import numpy as np
import torch
from torch import Tensor

#: Frames per step of :func:`forward_kinematics_numpy`: small enough for the
#: working set of a many-joint skeleton to stay in the CPU cache.
FK_CHUNK_FRAMES = 512


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


def forward_kinematics_numpy(
    rotation: np.ndarray,
    offset: np.ndarray,
    parent: np.ndarray,
    rotations: bool = True,
) -> Tuple[Optional[np.ndarray], np.ndarray]:
    r"""Global rotations and positions of one skeleton, in numpy.

    Same result as :func:`forward_kinematics` (up to rounding), without
    autograd or devices. It runs joint by joint, writing joint-major arrays
    so that every step is a contiguous batched product over frames; on the
    CPU it is several times faster than the torch version for one clip, and
    it stays single-threaded.

    Args:
        rotation (np.ndarray): Local rotation matrices.
        offset (np.ndarray): Local translations (the root's is its global
            position).
        parent (np.ndarray): Parent index per joint, ``-1`` for roots;
            parents come before their children.
        rotations (bool): If :obj:`False`, global rotations of leaf joints
            are not computed and :obj:`None` is returned in their place.

    Shapes:
        - **rotation**: :math:`(T, J, 3, 3)`
        - **offset**: :math:`(T, J, 3)`
        - **parent**: :math:`(J,)`
        - **output**: global rotations :math:`(T, J, 3, 3)` (or
          :obj:`None`) and positions :math:`(T, J, 3)`
    """
    parents = [int(p) for p in parent]
    if any(p >= j for j, p in enumerate(parents)):
        raise ValueError("forward_kinematics_numpy: parents must come before "
                         "children")
    rotation = np.asarray(rotation, dtype=np.float64)
    offset = np.asarray(offset, dtype=np.float64)
    num_frames = offset.shape[0]
    constant = ((offset == offset[0]).all(axis=0).all(axis=-1).tolist()
                if num_frames else [False] * len(parents))
    glob_rot = np.empty(rotation.shape) if rotations else None
    glob_pos = np.empty(offset.shape)
    for start in range(0, max(num_frames, 1), FK_CHUNK_FRAMES):
        part = slice(start, start + FK_CHUNK_FRAMES)
        rot, pos = _fk_joint_major(rotation[part], offset[part], parents,
                                   constant, rotations)
        glob_pos[part] = pos.transpose(1, 0, 2)
        if rotations:
            glob_rot[part] = rot.transpose(1, 0, 2, 3)
    return glob_rot, glob_pos


def _fk_joint_major(rotation: np.ndarray, offset: np.ndarray,
                    parents: List[int], constant: List[bool],
                    all_rotations: bool) -> Tuple[np.ndarray, np.ndarray]:
    """FK from frame-major inputs into joint-major outputs ``[J, T, 3, 3]``
    and ``[J, T, 3]``, so that every step writes contiguous memory. A joint
    whose offset is :obj:`constant` over frames needs one matrix-vector
    product for all frames."""
    num_frames, num = offset.shape[0], len(parents)
    has_child = [False] * num
    for p in parents:
        if p >= 0:
            has_child[p] = True
    glob_rot = np.empty((num, num_frames, 3, 3))
    glob_pos = np.empty((num, num_frames, 3))
    for j, p in enumerate(parents):
        if p < 0:
            glob_rot[j], glob_pos[j] = rotation[:, j], offset[:, j]
            continue
        if constant[j]:
            np.matmul(glob_rot[p].reshape(-1, 3), offset[0, j],
                      out=glob_pos[j].reshape(-1))
        else:
            np.matmul(glob_rot[p], offset[:, j, :, None],
                      out=glob_pos[j][..., None])
        glob_pos[j] += glob_pos[p]
        if all_rotations or has_child[j]:
            np.matmul(glob_rot[p], rotation[:, j], out=glob_rot[j])
    return glob_rot, glob_pos
