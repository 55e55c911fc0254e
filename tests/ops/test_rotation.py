"""Rotation conversions: Euler (6 orders), matrices, quaternions, 6D."""
from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from satagraph.ops.rotation import (axis_angle_matrix, euler_to_matrix,
                                    euler_to_quaternion, geodesic_angle,
                                    matrix_to_euler, matrix_to_quaternion,
                                    matrix_to_rotation_6d, quaternion_slerp,
                                    quaternion_to_euler, quaternion_to_matrix,
                                    rotation_6d_to_matrix, yaw_matrix)

ORDERS = ["XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX"]


def elementary(axis: str, angle: float) -> np.ndarray:
    """Right-handed rotation about a coordinate axis (column vectors)."""
    c, s = math.cos(angle), math.sin(angle)
    return {
        "X": np.array([[1, 0, 0], [0, c, -s], [0, s, c]]),
        "Y": np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]),
        "Z": np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]),
    }[axis]


def random_angles(num: int, seed: int = 0) -> torch.Tensor:
    """Euler angles away from gimbal lock: middle angle in (-1.4, 1.4)."""
    gen = torch.Generator().manual_seed(seed)
    angle = (torch.rand(num, 3, generator=gen, dtype=torch.float64) * 2 - 1) * math.pi
    angle[:, 1] *= 1.4 / math.pi
    return angle


def random_rotations(num: int, seed: int = 0) -> torch.Tensor:
    gen = torch.Generator().manual_seed(seed)
    quat = torch.randn(num, 4, generator=gen, dtype=torch.float64)
    return quaternion_to_matrix(quat / quat.norm(dim=-1, keepdim=True))


def assert_rotation(matrix: torch.Tensor, atol: float = 1e-9) -> None:
    eye = torch.eye(3, dtype=matrix.dtype).expand_as(matrix)
    torch.testing.assert_close(matrix @ matrix.transpose(-1, -2), eye,
                               atol=atol, rtol=0)
    torch.testing.assert_close(torch.linalg.det(matrix),
                               torch.ones(matrix.shape[:-2], dtype=matrix.dtype),
                               atol=atol, rtol=0)


def test_elementary_rotations_right_handed():
    quarter = torch.tensor(math.pi / 2, dtype=torch.float64)
    x, y, z = torch.eye(3, dtype=torch.float64)
    torch.testing.assert_close(axis_angle_matrix(quarter, "Z") @ x, y)
    torch.testing.assert_close(axis_angle_matrix(quarter, "X") @ y, z)
    torch.testing.assert_close(axis_angle_matrix(quarter, "Y") @ z, x)
    torch.testing.assert_close(yaw_matrix(quarter), axis_angle_matrix(quarter, "Y"))


@pytest.mark.parametrize("order", ORDERS)
def test_euler_to_matrix_composes_elementary(order):
    angles = random_angles(16, seed=1)
    got = euler_to_matrix(angles, order).numpy()
    for k, (a, b, c) in enumerate(angles.tolist()):
        want = (elementary(order[0], a) @ elementary(order[1], b)
                @ elementary(order[2], c))
        np.testing.assert_allclose(got[k], want, atol=1e-12)


@pytest.mark.parametrize("order", ORDERS)
def test_euler_matrix_quaternion_6d_roundtrip(order):
    angles = random_angles(64, seed=2)
    matrix = euler_to_matrix(angles, order)
    assert_rotation(matrix)
    torch.testing.assert_close(matrix_to_euler(matrix, order), angles,
                               atol=1e-9, rtol=0)
    quat = euler_to_quaternion(angles, order)
    torch.testing.assert_close(quat.norm(dim=-1), torch.ones(64, dtype=quat.dtype))
    torch.testing.assert_close(quaternion_to_matrix(quat), matrix, atol=1e-12, rtol=0)
    torch.testing.assert_close(quaternion_to_euler(quat, order), angles,
                               atol=1e-9, rtol=0)
    torch.testing.assert_close(matrix_to_quaternion(matrix).abs(), quat.abs(),
                               atol=1e-12, rtol=0)
    six = matrix_to_rotation_6d(matrix)
    torch.testing.assert_close(rotation_6d_to_matrix(six), matrix, atol=1e-12, rtol=0)


@pytest.mark.parametrize("order", ORDERS)
def test_matrix_to_euler_reproduces_any_rotation(order):
    """Even near gimbal lock the angles give back the same matrix."""
    matrix = random_rotations(64, seed=3)
    near_lock = euler_to_matrix(torch.tensor([[0.3, math.pi / 2, -0.2],
                                              [1.0, -math.pi / 2, 0.5]],
                                             dtype=torch.float64), order)
    matrix = torch.cat([matrix, near_lock])
    again = euler_to_matrix(matrix_to_euler(matrix, order), order)
    torch.testing.assert_close(again, matrix, atol=1e-6, rtol=0)


def test_invalid_order():
    with pytest.raises(ValueError, match="Euler order"):
        euler_to_matrix(torch.zeros(3), "XXQ")
    with pytest.raises(ValueError, match="Euler order"):
        matrix_to_euler(torch.eye(3), "XY")
    # Lower case is accepted.
    torch.testing.assert_close(euler_to_matrix(torch.ones(3), "zxy"),
                               euler_to_matrix(torch.ones(3), "ZXY"))


def test_quaternion_convention_xyzw():
    quarter = torch.tensor(math.pi / 2, dtype=torch.float64)
    quat = matrix_to_quaternion(axis_angle_matrix(quarter, "Z"))
    s = math.sqrt(0.5)
    want = torch.tensor([0, 0, s, s], dtype=torch.float64)
    torch.testing.assert_close(quat * torch.sign(quat[3]), want)


def test_6d_layout_is_first_two_columns():
    matrix = random_rotations(5, seed=4)
    six = matrix_to_rotation_6d(matrix)
    assert six.shape == (5, 6)
    torch.testing.assert_close(six[:, :3], matrix[:, :, 0])
    torch.testing.assert_close(six[:, 3:], matrix[:, :, 1])


def test_6d_to_matrix_is_identity_on_rotations_and_projects_others():
    matrix = random_rotations(128, seed=5)
    torch.testing.assert_close(rotation_6d_to_matrix(matrix_to_rotation_6d(matrix)),
                               matrix, atol=1e-12, rtol=0)
    gen = torch.Generator().manual_seed(6)
    noisy = torch.randn(128, 6, generator=gen, dtype=torch.float64)
    out = rotation_6d_to_matrix(noisy)
    assert_rotation(out)
    # Gram-Schmidt: the first column is the normalised first 3 values.
    torch.testing.assert_close(out[:, :, 0],
                               noisy[:, :3] / noisy[:, :3].norm(dim=-1, keepdim=True))


def test_batch_shapes_and_dtypes():
    angles = torch.zeros(2, 5, 7, 3)
    assert euler_to_matrix(angles, "ZXY").shape == (2, 5, 7, 3, 3)
    assert euler_to_matrix(angles, "ZXY").dtype == torch.float32
    assert matrix_to_rotation_6d(torch.eye(3).expand(4, 2, 3, 3)).shape == (4, 2, 6)
    assert rotation_6d_to_matrix(torch.randn(4, 2, 6)).shape == (4, 2, 3, 3)
    assert matrix_to_quaternion(torch.eye(3).expand(4, 2, 3, 3)).shape == (4, 2, 4)


def test_gradcheck_euler_to_matrix():
    angles = random_angles(4, seed=7).requires_grad_()
    for order in ("ZXY", "YZX"):
        assert torch.autograd.gradcheck(lambda a: euler_to_matrix(a, order),
                                        (angles,))


def test_gradcheck_rotation_6d_to_matrix():
    gen = torch.Generator().manual_seed(8)
    six = torch.randn(4, 6, generator=gen, dtype=torch.float64, requires_grad=True)
    assert torch.autograd.gradcheck(rotation_6d_to_matrix, (six,))


def test_gradients_flow_through_conversions():
    six = torch.randn(3, 6, dtype=torch.float64, requires_grad=True)
    target = random_rotations(3, seed=9)
    loss = geodesic_angle(rotation_6d_to_matrix(six), target).sum()
    loss = loss + matrix_to_quaternion(rotation_6d_to_matrix(six)).abs().sum()
    loss.backward()
    assert six.grad is not None and torch.isfinite(six.grad).all()
    assert six.grad.abs().sum() > 0


def test_quaternion_slerp():
    gen = torch.Generator().manual_seed(10)
    axis = torch.randn(8, 3, generator=gen, dtype=torch.float64)
    axis = axis / axis.norm(dim=-1, keepdim=True)
    theta = torch.rand(8, generator=gen, dtype=torch.float64) * 3.0
    q0 = torch.tensor([0, 0, 0, 1.0], dtype=torch.float64).expand(8, 4)

    def about(t):
        return torch.cat([axis * torch.sin(t / 2)[:, None],
                          torch.cos(t / 2)[:, None]], dim=-1)

    q1 = about(theta)
    zeros, ones = torch.zeros(8), torch.ones(8)
    torch.testing.assert_close(quaternion_slerp(q0, q1, zeros), q0)
    torch.testing.assert_close(quaternion_slerp(q0, q1, ones), q1)
    mid = quaternion_slerp(q0, q1, 0.5 * ones)
    torch.testing.assert_close(mid, about(theta / 2))
    torch.testing.assert_close(mid.norm(dim=-1), torch.ones(8, dtype=mid.dtype))
    # Shortest path: -q1 is the same rotation.
    torch.testing.assert_close(quaternion_slerp(q0, -q1, 0.5 * ones), mid)
    # Constant angular speed.
    quarter = quaternion_slerp(q0, q1, 0.25 * ones)
    torch.testing.assert_close(quarter, about(theta / 4))
    # Identical inputs (no division by zero).
    same = quaternion_slerp(q1, q1, 0.3 * ones)
    torch.testing.assert_close(same, q1)


def test_geodesic_angle():
    matrix = random_rotations(6, seed=11)
    angle = torch.linspace(0.1, 3.0, 6, dtype=torch.float64)
    rotated = matrix @ axis_angle_matrix(angle, "X")
    torch.testing.assert_close(geodesic_angle(matrix, rotated), angle)
    torch.testing.assert_close(geodesic_angle(matrix, matrix),
                               torch.zeros(6, dtype=torch.float64), atol=1e-12, rtol=0)


def test_geodesic_angle_is_exact_near_zero_in_float32():
    """Small angles read as themselves in float32 (the arc cosine of the
    trace read 4.9e-4 for 0 and for 1e-5, and 0.00098 for 1e-3)."""
    matrix = random_rotations(4, seed=12).float()
    angle = torch.tensor([0.0, 1e-5, 1e-3, 3.0])
    rotated = matrix @ axis_angle_matrix(angle, "Y")
    torch.testing.assert_close(geodesic_angle(matrix, rotated), angle, atol=1e-6, rtol=1e-4)
    eye = torch.eye(3, dtype=torch.float64).expand(2, 3, 3).clone().requires_grad_(True)
    geodesic_angle(eye, eye.detach()).sum().backward()
    assert torch.isfinite(eye.grad).all()


@pytest.mark.parametrize("order", ["XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX"])
def test_reader_numpy_euler_matches_torch(order):
    from satagraph.io.bvh_reader import _euler_to_matrix
    from satagraph.ops.rotation import euler_to_matrix
    angles = np.random.default_rng(1).uniform(-math.pi, math.pi, size=(5, 10, 3))  # (*, 3)
    want = euler_to_matrix(torch.from_numpy(angles), order).numpy()
    np.testing.assert_allclose(_euler_to_matrix(angles, order), want, atol=1e-12)
