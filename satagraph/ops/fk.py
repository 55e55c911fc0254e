"""Forward kinematics over a parent array (torch, batched, differentiable;
and a numpy version for single clips without gradients)."""
from __future__ import annotations

from functools import lru_cache
from typing import TYPE_CHECKING, List, NamedTuple, Optional, Tuple

import numpy as np

if TYPE_CHECKING:  # torch loads on first use: the numpy FK does without it
    from torch import Tensor

#: Joint-frames per step of :func:`forward_kinematics_numpy` (bounds the size
#: of its temporary arrays on long clips).
FK_CHUNK_JOINT_FRAMES = 1 << 18


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
    import torch

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
    import torch

    if levels is None:
        levels = fk_levels(parent)
    if rotation.dtype in (torch.float16, torch.bfloat16):
        rotation = rotation.float()  # chains of products: never in half precision
    with torch.autocast(rotation.device.type, enabled=False):
        return _fk(rotation, offset, parent.to(rotation.device), levels)


def _fk(rotation: Tensor, offset: Tensor, parent: Tensor,
        levels: List[Tensor]) -> Tuple[Tensor, Tensor]:
    """:func:`forward_kinematics` (autocast off, full precision)."""
    import torch

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
    autograd or devices. Joints are processed one level of depth at a time,
    on component-major copies of the inputs (``[3, 3, J, T]``), so that each
    step is a few element-wise products over all frames of all the joints
    of a level; on the CPU it is several times faster than the torch version
    for one clip, and it stays single-threaded.

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
    plan = _fk_plan(np.asarray(parent, dtype=np.int64).tobytes(), rotations)
    rotation = np.asarray(rotation, dtype=np.float64)
    offset = np.asarray(offset, dtype=np.float64)
    num_frames = offset.shape[0]
    glob_rot = np.empty(rotation.shape) if rotations else None
    glob_pos = np.empty(offset.shape)
    step = max(1, FK_CHUNK_JOINT_FRAMES // max(1, plan.order.size))
    for start in range(0, num_frames, step):
        part = slice(start, start + step)
        rot, pos = _fk_component_major(rotation[part], offset[part], plan)
        glob_pos[part][:, plan.order] = pos.transpose(2, 1, 0)
        if rotations:
            glob_rot[part][:, plan.order] = rot.transpose(3, 2, 0, 1)
    return glob_rot, glob_pos


class _FKLevel(NamedTuple):
    start: int  # joints plan.order[start:stop], of which the first ...
    stop: int
    turning: slice  # ... (stop - start) need a global rotation: these slots
    parent_slot: np.ndarray  # of the parents in plan.order
    parent_rot: np.ndarray  # of the parents among the rotation slots


class _FKPlan(NamedTuple):
    order: np.ndarray  # joints by depth, roots first
    turning: np.ndarray  # joints whose global rotation is needed, same order
    roots: int
    root_turning: int
    levels: Tuple[_FKLevel, ...]
    widest: int


@lru_cache(maxsize=256)
def _fk_plan(parent_bytes: bytes, all_rotations: bool) -> _FKPlan:
    """Joints sorted by depth; within a level, those whose global rotation
    is needed (all of them, or those with children) come first."""
    parents = np.frombuffer(parent_bytes, dtype=np.int64).tolist()
    if any(p >= j for j, p in enumerate(parents)):
        raise ValueError("forward_kinematics_numpy: parents must come before "
                         "children")
    depth, has_child = [0] * len(parents), [False] * len(parents)
    for j, p in enumerate(parents):
        if p >= 0:
            depth[j], has_child[p] = depth[p] + 1, True
    need = [all_rotations or c for c in has_child]
    order = sorted(range(len(parents)), key=lambda j: (depth[j], not need[j]))
    turning = [j for j in order if need[j]]
    slot = {j: i for i, j in enumerate(order)}
    rot_slot = {j: i for i, j in enumerate(turning)}
    roots = depth.count(0)
    root_turning = sum(need[j] for j in order[:roots])
    levels, start, rot_start = [], roots, root_turning
    for d in range(1, max(depth, default=0) + 1):
        joints = [j for j in order if depth[j] == d]
        rot_stop = rot_start + sum(need[j] for j in joints)
        levels.append(_FKLevel(
            start, start + len(joints), slice(rot_start, rot_stop),
            np.array([slot[parents[j]] for j in joints], dtype=np.intp),
            np.array([rot_slot[parents[j]] for j in joints], dtype=np.intp)))
        start, rot_start = start + len(joints), rot_stop
    widest = max([lv.stop - lv.start for lv in levels], default=0)
    return _FKPlan(np.array(order, dtype=np.intp), np.array(turning, dtype=np.intp),
                   roots, root_turning, tuple(levels), widest)


def _component_major(x: np.ndarray, joints: np.ndarray) -> np.ndarray:
    """``x[:, joints]`` of a frame-major array ``[T, J, *]``, moved to
    ``[*, J', T]`` (gathering whole joints first is the fast way)."""
    picked = np.take(x, joints, axis=1, mode="clip")
    axes = tuple(range(2, x.ndim)) + (1, 0)
    return np.ascontiguousarray(picked.transpose(axes))


def _fk_component_major(rotation: np.ndarray, offset: np.ndarray,
                        plan: _FKPlan) -> Tuple[np.ndarray, np.ndarray]:
    """FK of frame-major inputs ``[T, J, 3, 3]``, ``[T, J, 3]`` into
    component-major global rotations ``[3, 3, J', T]`` (joints of
    :obj:`plan.turning`) and positions ``[3, J, T]`` (joints of
    :obj:`plan.order`). Offsets that do not change over frames (all but
    the root's, unless joints have position channels) are used as
    constants."""
    rot = _component_major(rotation, plan.turning)
    num_frames = rotation.shape[0]
    glob_rot = np.empty_like(rot)
    glob_pos = np.empty((3, plan.order.size, num_frames))
    glob_rot[:, :, :plan.root_turning] = rot[:, :, :plan.root_turning]
    glob_pos[:, :plan.roots] = _component_major(offset, plan.order[:plan.roots])
    moving = (offset[1:] != offset[:1]).any(axis=(0, 2))
    if moving[plan.order[plan.roots:]].any():
        off = _component_major(offset, plan.order)[None]  # [1, 3, J, T]
    else:
        off = offset[0, plan.order].T[None, :, :, None]  # [1, 3, J, 1]
    size = plan.widest * num_frames
    parent_buf, product_buf = np.empty(9 * size), np.empty(9 * size)
    for level in plan.levels:
        n, k = level.stop - level.start, level.turning.stop - level.turning.start
        parent_rot = parent_buf[:9 * n * num_frames].reshape(3, 3, n, num_frames)
        np.take(glob_rot, level.parent_rot, axis=2, out=parent_rot, mode="clip")
        product = product_buf[:9 * n * num_frames].reshape(3, 3, n, num_frames)
        # Position: parent rotation times offset, plus the parent's position.
        np.multiply(parent_rot, off[:, :, level.start:level.stop], out=product)
        pos = glob_pos[:, level.start:level.stop]
        np.add.reduce(product, axis=1, out=pos)
        pos += glob_pos[:, level.parent_slot]
        if k:
            _compose(parent_rot[:, :, :k], rot[:, :, level.turning],
                     out=glob_rot[:, :, level.turning], tmp=product[:, :, :k])
    return glob_rot, glob_pos


def _compose(a: np.ndarray, b: np.ndarray, out: np.ndarray, tmp: np.ndarray) -> None:
    """Matrix products ``a @ b`` of component-major stacks ``[3, 3, *]``."""
    np.multiply(a[:, 0, None], b[None, 0], out=out)
    for k in (1, 2):
        np.multiply(a[:, k, None], b[None, k], out=tmp)
        out += tmp
