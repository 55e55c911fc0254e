"""One yaw rule: rotation about +Y, +Z turned towards +X, the same in
numpy (:mod:`satagraph.ops.rotation_numpy`) and torch."""
from __future__ import annotations

import numpy as np
import pytest
import torch

from satagraph.motion import CanonicalTransform
from satagraph.ops.rotation import axis_angle_matrix, yaw_matrix
from satagraph.ops.rotation_numpy import (axis_angle_matrix_numpy, matrix_to_quaternion_numpy,
                                          mean_rotation_numpy, quaternion_to_matrix_numpy,
                                          rotation_about_numpy, rotation_between_numpy,
                                          yaw_matrix_numpy, yaw_of)


def test_yaw_of_a_quarter_turn_maps_z_to_x():
    z = np.array([0.0, 0.0, 1.0])
    assert np.allclose(yaw_matrix_numpy(np.pi / 2) @ z, [1.0, 0.0, 0.0])
    assert np.allclose(yaw_matrix(torch.tensor(np.pi / 2, dtype=torch.float64)).numpy() @ z, [1.0, 0.0, 0.0])
    assert np.isclose(yaw_of(np.array([1.0, 0.3, 0.0])), np.pi / 2)


@pytest.mark.parametrize("axis", ["X", "Y", "Z"])
def test_numpy_and_torch_agree(axis):
    angle = np.random.default_rng(0).uniform(-np.pi, np.pi, size=(4, 5))
    expected = axis_angle_matrix(torch.from_numpy(angle), axis).numpy()
    assert np.allclose(axis_angle_matrix_numpy(angle, axis), expected)
    assert np.allclose(axis_angle_matrix_numpy(angle, "XYZ".index(axis)), expected)
    if axis == "Y":
        assert np.allclose(yaw_matrix_numpy(angle), yaw_matrix(torch.from_numpy(angle)).numpy())


def test_yaw_of_inverts_the_yaw_matrix():
    yaw = np.linspace(-3.0, 3.0, 7)
    assert np.allclose(yaw_of(yaw_matrix_numpy(yaw) @ np.array([0.0, 0.0, 1.0])), yaw)


def test_canonical_transform_uses_the_rule():
    tf = CanonicalTransform(up_axis="+Y", up_rotation=np.eye(3), yaw=0.4, scale=1.0,
                            source_fps=30.0)
    assert np.allclose(tf.rotation, yaw_matrix_numpy(0.4))


def test_rotation_about_an_axis_matches_the_coordinate_axes_and_keeps_its_axis():
    angles = np.linspace(-3.0, 3.0, 7)
    for i, name in enumerate("XYZ"):
        axis = np.eye(3)[i]
        np.testing.assert_allclose(rotation_about_numpy(axis, angles),
                                   axis_angle_matrix_numpy(angles, name), atol=1e-12)
    axis = np.array([1.0, 2.0, -2.0]) / 3.0
    rot = rotation_about_numpy(axis, 0.7)
    np.testing.assert_allclose(rot @ axis, axis, atol=1e-12)
    np.testing.assert_allclose(rot @ rot.T, np.eye(3), atol=1e-12)
    assert np.isclose(np.linalg.det(rot), 1.0)


@pytest.mark.parametrize("b", [[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [0.6, 0.0, 0.8],
                               [0.0, 1.0, 0.0]])
def test_rotation_between_takes_a_onto_b(b):
    a = np.array([0.0, 1.0, 0.0])
    rot = rotation_between_numpy(a, np.array(b))
    np.testing.assert_allclose(rot @ a, b, atol=1e-12)
    np.testing.assert_allclose(rot @ rot.T, np.eye(3), atol=1e-12)
    assert np.isclose(np.linalg.det(rot), 1.0)


def test_rotation_between_is_batched():
    """A batch (opposite pairs included) gives each pair's own rotation."""
    gen = np.random.default_rng(0)
    a = gen.normal(size=(7, 3))
    a /= np.linalg.norm(a, axis=-1, keepdims=True)
    b = gen.normal(size=(7, 3))
    b /= np.linalg.norm(b, axis=-1, keepdims=True)
    b[2], b[5] = -a[2], a[5]  # a half turn, and no turn
    a[4] = b[4] = [1.0, 0.0, 0.0]
    b[4] = -b[4]  # opposite along the first fallback axis
    rot = rotation_between_numpy(a, b)
    assert rot.shape == (7, 3, 3)
    np.testing.assert_allclose(np.einsum("nij,nj->ni", rot, a), b, atol=1e-12)
    np.testing.assert_allclose(rot @ rot.transpose(0, 2, 1), np.broadcast_to(np.eye(3), (7, 3, 3)),
                               atol=1e-12)
    np.testing.assert_allclose(rot[5], np.eye(3), atol=1e-12)
    for k in range(7):
        np.testing.assert_allclose(rot[k], rotation_between_numpy(a[k], b[k]), atol=1e-12)


def test_mean_rotation_of_turns_about_one_axis_is_the_mean_turn():
    """Turns about one axis by 10, 30 and 50 degrees average to 30 (the
    spread is symmetric); equal rotations average to themselves."""
    angles = np.radians([10.0, 30.0, 50.0])
    for axis in "XYZ":
        mean = mean_rotation_numpy(axis_angle_matrix_numpy(angles, axis))
        np.testing.assert_allclose(mean, axis_angle_matrix_numpy(np.radians(30.0), axis),
                                   atol=1e-12)
    r = rotation_about_numpy(np.array([1.0, 2.0, 3.0]) / np.sqrt(14.0), 1.2)
    np.testing.assert_allclose(mean_rotation_numpy(np.stack([r, r, r])), r, atol=1e-12)


def test_mean_rotation_is_a_batched_rotation_and_turns_with_its_inputs():
    """The mean is a proper rotation per batch entry, and turning every
    input by A on the left and B on the right turns the mean the same way."""
    rng = np.random.default_rng(0)
    axes = rng.normal(size=(5, 4, 3))
    axes /= np.linalg.norm(axes, axis=-1, keepdims=True)
    rots = rotation_about_numpy(axes, rng.uniform(0, 1.5, size=(5, 4)))
    mean = mean_rotation_numpy(rots)
    assert mean.shape == (4, 3, 3)
    np.testing.assert_allclose(mean @ np.swapaxes(mean, -1, -2),
                               np.broadcast_to(np.eye(3), (4, 3, 3)), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(mean), 1.0, atol=1e-12)
    a, b = rotation_about_numpy(np.array([0.0, 0.6, 0.8]), 0.7), yaw_matrix_numpy(2.0)
    np.testing.assert_allclose(mean_rotation_numpy(a @ rots @ b), a @ mean @ b, atol=1e-12)


def _awkward_rotations() -> np.ndarray:
    """Seeded random rotations with the awkward ones: identity, half
    turns about each axis (every branch of Markley's method), slightly
    non-orthonormal matrices."""
    import roma
    torch.manual_seed(0)
    random = roma.random_rotmat(4092, dtype=torch.float64).numpy()
    half = np.stack([np.diag(d) for d in ([1.0, -1, -1], [-1.0, 1, -1], [-1.0, -1, 1])])
    noisy = random[:64] + 1e-6 * np.random.default_rng(0).normal(size=(64, 3, 3))
    return np.concatenate([np.eye(3)[None], half, random, noisy])


def test_matrix_to_quaternion_numpy_is_roma_to_an_ulp():
    # the same operations in the same order: bit for bit on the VM; an ulp
    # allowed where another CPU's torch sums a norm in another order
    import roma
    matrix = _awkward_rotations()
    expected = roma.rotmat_to_unitquat(torch.from_numpy(matrix)).numpy()
    ulp = dict(rtol=0, atol=1e-15)
    np.testing.assert_allclose(matrix_to_quaternion_numpy(matrix), expected, **ulp)
    grid = matrix.reshape(-1, 4, 3, 3)  # leading shape kept, strided input read right
    np.testing.assert_allclose(matrix_to_quaternion_numpy(grid), expected.reshape(-1, 4, 4), **ulp)
    np.testing.assert_allclose(matrix_to_quaternion_numpy(matrix[::3]), expected[::3], **ulp)


def test_quaternion_to_matrix_numpy_is_roma_to_an_ulp():
    import roma
    quat = roma.rotmat_to_unitquat(torch.from_numpy(_awkward_rotations())).numpy()
    expected = roma.unitquat_to_rotmat(torch.from_numpy(quat)).numpy()
    ulp = dict(rtol=0, atol=1e-15)
    np.testing.assert_allclose(quaternion_to_matrix_numpy(quat), expected, **ulp)
    np.testing.assert_allclose(quaternion_to_matrix_numpy(quat.reshape(-1, 4, 4)),
                               expected.reshape(-1, 4, 3, 3), **ulp)
