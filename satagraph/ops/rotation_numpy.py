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
