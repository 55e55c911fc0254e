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
