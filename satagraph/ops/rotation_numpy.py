"""Numpy twins of the rotations in :mod:`satagraph.ops.rotation`, for code
that must load without torch (reading and canonicalising rigs, the zoo).

Same conventions: matrices act on column vectors, and the yaw about +Y
turns +Z towards +X (``yaw_matrix_numpy(pi / 2) @ [0, 0, 1] == [1, 0, 0]``).
"""
from __future__ import annotations

from typing import Union

import numpy as np

_AXES = "XYZ"


def axis_angle_matrix_numpy(angle: Union[float, np.ndarray],
                            axis: Union[str, int]) -> np.ndarray:
    r"""Rotation matrices about a coordinate axis (``"X"``, ``"Y"``,
    ``"Z"`` or 0, 1, 2); :func:`~satagraph.ops.rotation.axis_angle_matrix`
    in numpy.

    Shapes:
        - **angle**: :math:`(*)` in radians
        - **output**: :math:`(*, 3, 3)`
    """
    i = _AXES.index(axis) if isinstance(axis, str) else int(axis)
    a, b = (i + 1) % 3, (i + 2) % 3
    angle = np.asarray(angle, dtype=np.float64)
    c, s = np.cos(angle), np.sin(angle)
    out = np.zeros(angle.shape + (3, 3))
    out[..., i, i] = 1.0
    out[..., a, a], out[..., a, b] = c, -s
    out[..., b, a], out[..., b, b] = s, c
    return out


def rotation_about_numpy(axis: np.ndarray, angle: Union[float, np.ndarray]) -> np.ndarray:
    r"""Rotations by :obj:`angle` radians about a unit :obj:`axis`
    (Rodrigues' formula).

    Shapes:
        - **axis**: :math:`(3,)`
        - **angle**: :math:`(*)`
        - **output**: :math:`(*, 3, 3)`
    """
    k = _cross_matrix(np.asarray(axis, dtype=np.float64))
    a = np.asarray(angle, dtype=np.float64)[..., None, None]
    return np.eye(3) + np.sin(a) * k + (1 - np.cos(a)) * (k @ k)


def rotation_between_numpy(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    r"""The smallest rotation taking unit vector :obj:`a` onto unit vector
    :obj:`b` (a half turn about a perpendicular axis when they are
    opposite), for one pair or a batch.

    Shapes:
        - **a**, **b**: :math:`(\ldots, 3)`
        - **output**: :math:`(\ldots, 3, 3)`
    """
    a, b = np.broadcast_arrays(np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64))
    v, c = np.cross(a, b), np.einsum("...i,...i->...", a, b)
    k = _cross_matrix(v)
    opposite = c < -1 + 1e-9
    scale = 1.0 / np.where(opposite, 1.0, 1.0 + c)
    out = np.eye(3) + k + (k @ k) * scale[..., None, None]
    if opposite.any():
        axis = np.cross(a[opposite], [1.0, 0.0, 0.0])
        small = np.linalg.norm(axis, axis=-1) < 1e-6
        axis[small] = np.cross(a[opposite][small], [0.0, 1.0, 0.0])
        axis /= np.linalg.norm(axis, axis=-1, keepdims=True)
        out[opposite] = 2 * axis[:, :, None] * axis[:, None, :] - np.eye(3)
    return out


def _cross_matrix(v: np.ndarray) -> np.ndarray:
    r"""The matrices of ``v x .``, :math:`(\ldots, 3, 3)`."""
    zero = np.zeros_like(v[..., 0])
    return np.stack([np.stack([zero, -v[..., 2], v[..., 1]], -1),
                     np.stack([v[..., 2], zero, -v[..., 0]], -1),
                     np.stack([-v[..., 1], v[..., 0], zero], -1)], -2)


def yaw_matrix_numpy(yaw: Union[float, np.ndarray]) -> np.ndarray:
    r"""Rotations about +Y by :obj:`yaw` radians;
    :func:`~satagraph.ops.rotation.yaw_matrix` in numpy.

    Shapes:
        - **yaw**: :math:`(*)`
        - **output**: :math:`(*, 3, 3)`
    """
    return axis_angle_matrix_numpy(yaw, "Y")


def yaw_of(direction: np.ndarray) -> np.ndarray:
    r"""The yaw of a direction: the angle about +Y that turns +Z towards
    its horizontal part, so ``yaw_matrix_numpy(yaw_of(d))`` faces +Z to
    :obj:`d` (inverse of the rule above).

    Shapes:
        - **direction**: :math:`(*, 3)`
        - **output**: :math:`(*)`
    """
    return np.arctan2(direction[..., 0], direction[..., 2])


def mean_rotation_numpy(rotations: np.ndarray) -> np.ndarray:
    r"""The chordal mean of rotations over the first axis: the rotation
    nearest (in the Frobenius norm) to their arithmetic mean, the
    special-orthogonal Procrustes solution of
    :func:`roma.special_procrustes` in numpy.

    Shapes:
        - **rotations**: :math:`(N, *, 3, 3)`
        - **output**: :math:`(*, 3, 3)`
    """
    u, _, vt = np.linalg.svd(np.asarray(rotations, dtype=np.float64).mean(axis=0))
    u[..., :, -1] *= np.sign(np.linalg.det(u @ vt))[..., None]
    return u @ vt


def matrix_to_quaternion_numpy(matrix: np.ndarray) -> np.ndarray:
    r"""Rotation matrices to unit quaternions ``(x, y, z, w)``: the values
    of :func:`~satagraph.ops.rotation.matrix_to_quaternion` (roma's
    :func:`roma.rotmat_to_unitquat`, Markley's method) to the bit, the same
    operations in the same order, without its interleaved stack of sixteen
    strided columns (most of its time on a long take).

    Shapes:
        - **matrix**: :math:`(*, 3, 3)`
        - **output**: :math:`(*, 4)`
    """
    (a11, a21, a31, a12, a22, a32, a13, a23, a33) = matrix.reshape(-1, 9).T  # A = R^T
    x = np.stack([1 + a11 - a22 - a33, a12 + a21, a13 + a31, a23 - a32,
                  a21 + a12, 1 + a22 - a33 - a11, a23 + a32, a31 - a13,
                  a31 + a13, a32 + a23, 1 + a33 - a11 - a22, a12 - a21,
                  a23 - a32, a31 - a13, a12 - a21, 1 + a11 + a22 + a33]).reshape(4, 4, -1)
    best = np.argmax(x[[0, 1, 2, 3], [0, 1, 2, 3]], axis=0)  # the largest 4 q_i^2
    x_i = np.take_along_axis(x, best[None, None], axis=0)[0]
    sq = x_i * x_i  # summed in order, as torch.norm sums four entries
    quat = x_i / np.sqrt(((sq[0] + sq[1]) + sq[2]) + sq[3])
    return quat.T.reshape(matrix.shape[:-2] + (4,))


def quaternion_to_matrix_numpy(quaternion: np.ndarray) -> np.ndarray:
    r"""Unit quaternions ``(x, y, z, w)`` to rotation matrices: the values
    of :func:`~satagraph.ops.rotation.quaternion_to_matrix` (roma's
    :func:`roma.unitquat_to_rotmat`) to the bit, the same operations in the
    same order.

    Shapes:
        - **quaternion**: :math:`(*, 4)`
        - **output**: :math:`(*, 3, 3)`
    """
    x, y, z, w = np.moveaxis(quaternion, -1, 0)
    x2, y2, z2, w2 = x * x, y * y, z * z, w * w
    xy, zw, xz, yw, yz, xw = x * y, z * w, x * z, y * w, y * z, x * w
    return np.stack((x2 - y2 - z2 + w2, 2 * (xy - zw), 2 * (xz + yw),
                     2 * (xy + zw), - x2 + y2 - z2 + w2, 2 * (yz - xw),
                     2 * (xz - yw), 2 * (yz + xw), - x2 - y2 + z2 + w2),
                    axis=-1).reshape(quaternion.shape[:-1] + (3, 3))
