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
    opposite).

    Shapes:
        - **a**, **b**: :math:`(3,)`
        - **output**: :math:`(3, 3)`
    """
    v, c = np.cross(a, b), float(np.dot(a, b))
    if c < -1 + 1e-9:
        axis = np.cross(a, [1.0, 0.0, 0.0])
        if np.linalg.norm(axis) < 1e-6:
            axis = np.cross(a, [0.0, 1.0, 0.0])
        axis = axis / np.linalg.norm(axis)
        return 2 * np.outer(axis, axis) - np.eye(3)
    k = _cross_matrix(v)
    return np.eye(3) + k + k @ k / (1 + c)


def _cross_matrix(v: np.ndarray) -> np.ndarray:
    """The matrix of ``v x .``."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


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
