"""Batched, differentiable rotation conversions (torch).

Conventions:
    - Rotation matrices act on column vectors: ``v_parent = R @ v_child``.
    - Quaternions are ``(x, y, z, w)``, the convention of :mod:`roma`.
    - 6D rotations are the first two COLUMNS of the matrix (Zhou et al.),
      flattened as ``[R00, R10, R20, R01, R11, R21]``.
    - Euler angles follow BVH: ``order="ZXY"`` means
      ``R = Rz(a[..., 0]) @ Rx(a[..., 1]) @ Ry(a[..., 2])`` (intrinsic).
"""
from __future__ import annotations

import roma
import torch
from torch import Tensor

_AXES = "XYZ"


def _check_order(order: str) -> str:
    order = order.upper()
    if len(order) != 3 or any(a not in _AXES for a in order):
        raise ValueError(f"invalid Euler order {order!r}: expected three of X, Y, Z")
    return order


def axis_angle_matrix(angle: Tensor, axis: str) -> Tensor:
    r"""Rotation matrices about a coordinate axis.

    Shapes:
        - **angle**: :math:`(*)` in radians
        - **output**: :math:`(*, 3, 3)`
    """
    i = _AXES.index(axis)
    a, b = (i + 1) % 3, (i + 2) % 3
    c, s = torch.cos(angle), torch.sin(angle)
    out = angle.new_zeros(*angle.shape, 3, 3)
    out[..., i, i] = 1.0
    out[..., a, a] = c
    out[..., a, b] = -s
    out[..., b, a] = s
    out[..., b, b] = c
    return out


def euler_to_matrix(angle: Tensor, order: str) -> Tensor:
    r"""Intrinsic Euler angles (radians) in BVH channel order to matrices.

    Shapes:
        - **angle**: :math:`(*, 3)`
        - **output**: :math:`(*, 3, 3)`
    """
    order = _check_order(order)
    mats = [axis_angle_matrix(angle[..., i], a) for i, a in enumerate(order)]
    return mats[0] @ mats[1] @ mats[2]


def matrix_to_euler(matrix: Tensor, order: str) -> Tensor:
    r"""Rotation matrices to intrinsic Euler angles (radians) in BVH order.

    Shapes:
        - **matrix**: :math:`(*, 3, 3)`
        - **output**: :math:`(*, 3)`
    """
    order = _check_order(order)
    return roma.rotmat_to_euler(order, matrix)


def unit_quaternion_to_euler(quaternion: Tensor, order: str) -> Tensor:
    r"""Unit quaternions ``(x, y, z, w)`` to intrinsic Euler angles
    (radians) in BVH order, directly: :func:`matrix_to_euler` of a matrix
    is this of its :func:`matrix_to_quaternion` (the same values to the
    bit: roma converts so), where :func:`quaternion_to_euler` goes through
    a matrix again.

    Shapes:
        - **quaternion**: :math:`(*, 4)`
        - **output**: :math:`(*, 3)`
    """
    return roma.unitquat_to_euler(_check_order(order), quaternion)


def matrix_to_quaternion(matrix: Tensor) -> Tensor:
    r"""Rotation matrices to unit quaternions ``(x, y, z, w)``.

    Shapes:
        - **matrix**: :math:`(*, 3, 3)`
        - **output**: :math:`(*, 4)`
    """
    return roma.rotmat_to_unitquat(matrix)


def quaternion_to_matrix(quaternion: Tensor) -> Tensor:
    r"""Unit quaternions ``(x, y, z, w)`` to rotation matrices.

    Shapes:
        - **quaternion**: :math:`(*, 4)`
        - **output**: :math:`(*, 3, 3)`
    """
    return roma.unitquat_to_rotmat(quaternion)


def euler_to_quaternion(angle: Tensor, order: str) -> Tensor:
    r"""Intrinsic Euler angles (radians) to quaternions ``(x, y, z, w)``.

    Shapes:
        - **angle**: :math:`(*, 3)`
        - **output**: :math:`(*, 4)`
    """
    return matrix_to_quaternion(euler_to_matrix(angle, order))


def quaternion_to_euler(quaternion: Tensor, order: str) -> Tensor:
    r"""Quaternions ``(x, y, z, w)`` to intrinsic Euler angles (radians).

    Shapes:
        - **quaternion**: :math:`(*, 4)`
        - **output**: :math:`(*, 3)`
    """
    return matrix_to_euler(quaternion_to_matrix(quaternion), order)


def matrix_to_rotation_6d(matrix: Tensor) -> Tensor:
    r"""First two columns of each matrix, ``[R00, R10, R20, R01, R11, R21]``.

    Shapes:
        - **matrix**: :math:`(*, 3, 3)`
        - **output**: :math:`(*, 6)`
    """
    return matrix[..., :, :2].transpose(-1, -2).reshape(*matrix.shape[:-2], 6)


def rotation_6d_to_matrix(rot6d: Tensor) -> Tensor:
    r"""6D rotations to matrices by Gram-Schmidt orthonormalisation.

    Shapes:
        - **rot6d**: :math:`(*, 6)`
        - **output**: :math:`(*, 3, 3)`
    """
    cols = rot6d.reshape(*rot6d.shape[:-1], 2, 3).transpose(-1, -2)
    return roma.special_gramschmidt(cols)


def quaternion_slerp(q0: Tensor, q1: Tensor, weight: Tensor) -> Tensor:
    r"""Spherical linear interpolation, element-wise (shortest path).

    Shapes:
        - **q0**, **q1**: :math:`(*, 4)`
        - **weight**: :math:`(*)` in :math:`[0, 1]`
        - **output**: :math:`(*, 4)`
    """
    dot = (q0 * q1).sum(-1, keepdim=True)
    q1 = torch.where(dot < 0, -q1, q1)
    dot = dot.abs().clamp(max=1.0)
    theta = torch.acos(dot)
    sin = torch.sin(theta)
    w = weight.unsqueeze(-1).to(q0.dtype)
    small = sin < 1e-6
    safe = torch.where(small, torch.ones_like(sin), sin)
    a = torch.where(small, 1 - w, torch.sin((1 - w) * theta) / safe)
    b = torch.where(small, w, torch.sin(w * theta) / safe)
    out = a * q0 + b * q1
    return out / out.norm(dim=-1, keepdim=True)


def geodesic_angle(matrix_a: Tensor, matrix_b: Tensor) -> Tensor:
    r"""Angle (radians) of the relative rotation between two sets of matrices:
    :math:`\operatorname{atan2}(\lVert w \rVert, \mathrm{tr} R - 1)` with
    :math:`w` the axis vector of :math:`R - R^\top` (:math:`2 \sin\theta`
    and :math:`2 \cos\theta`), exact at 0 and accurate near it, where the
    arc cosine of the trace loses half the digits (its clamp made equal
    rotations 4.9e-4 rad apart in float32); the gradient stays finite.

    Shapes:
        - **matrix_a**, **matrix_b**: :math:`(*, 3, 3)`
        - **output**: :math:`(*)`
    """
    rel = matrix_a.transpose(-1, -2) @ matrix_b
    trace = rel.diagonal(dim1=-2, dim2=-1).sum(-1)
    skew = torch.stack([rel[..., 2, 1] - rel[..., 1, 2], rel[..., 0, 2] - rel[..., 2, 0],
                        rel[..., 1, 0] - rel[..., 0, 1]], dim=-1)
    return torch.atan2(skew.norm(dim=-1), trace - 1)


def yaw_matrix(yaw: Tensor) -> Tensor:
    r"""Rotations about +Y by :obj:`yaw` radians.

    Shapes:
        - **yaw**: :math:`(*)`
        - **output**: :math:`(*, 3, 3)`
    """
    return axis_angle_matrix(yaw, "Y")
