"""Forward kinematics over parent arrays (single and concatenated skeletons)."""
from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from satagraph.ops.fk import fk_levels, forward_kinematics
from satagraph.ops.rotation import axis_angle_matrix, rotation_6d_to_matrix


def reference_fk(rotation: np.ndarray, offset: np.ndarray, parent: np.ndarray):
    """Joint-by-joint FK in numpy (parents before children)."""
    glob_rot, glob_pos = rotation.copy(), offset.copy()
    for j, p in enumerate(parent):
        if p >= 0:
            glob_rot[..., j, :, :] = glob_rot[..., p, :, :] @ rotation[..., j, :, :]
            glob_pos[..., j, :] = glob_pos[..., p, :] + (
                glob_rot[..., p, :, :] @ offset[..., j, :, None])[..., 0]
    return glob_rot, glob_pos


def random_rotation(*shape: int, seed: int = 0) -> torch.Tensor:
    gen = torch.Generator().manual_seed(seed)
    return rotation_6d_to_matrix(torch.randn(*shape, 6, generator=gen,
                                             dtype=torch.float64))


def test_three_joint_chain_by_hand():
    quarter = torch.tensor(math.pi / 2, dtype=torch.float64)
    rz = axis_angle_matrix(quarter, "Z")
    rotation = torch.stack([rz, rz, torch.eye(3, dtype=torch.float64)])
    offset = torch.tensor([[1.0, 2.0, 3.0], [1.0, 0.0, 0.0], [1.0, 0.0, 0.0]],
                          dtype=torch.float64)
    parent = torch.tensor([-1, 0, 1])
    glob_rot, glob_pos = forward_kinematics(rotation, offset, parent)
    # Root at (1, 2, 3) turned 90 deg about Z; joint 1 one unit along the
    # root's rotated x (= +y); joint 2 one unit along -x (turned 180 deg).
    want = torch.tensor([[1.0, 2.0, 3.0], [1.0, 3.0, 3.0], [0.0, 3.0, 3.0]],
                        dtype=torch.float64)
    torch.testing.assert_close(glob_pos, want)
    torch.testing.assert_close(glob_rot[1], axis_angle_matrix(2 * quarter, "Z"))
    torch.testing.assert_close(glob_rot[2], glob_rot[1])


def test_matches_reference_with_frames(tiny_skeleton):
    parent = torch.from_numpy(tiny_skeleton.parents)
    rotation = random_rotation(7, 10, seed=1)
    offset = torch.from_numpy(tiny_skeleton.offsets)
    glob_rot, glob_pos = forward_kinematics(rotation, offset, parent)
    assert glob_rot.shape == (7, 10, 3, 3) and glob_pos.shape == (7, 10, 3)
    ref_rot, ref_pos = reference_fk(rotation.numpy(),
                                    np.broadcast_to(tiny_skeleton.offsets,
                                                    (7, 10, 3)).copy(),
                                    tiny_skeleton.parents)
    np.testing.assert_allclose(glob_rot.numpy(), ref_rot, atol=1e-12)
    np.testing.assert_allclose(glob_pos.numpy(), ref_pos, atol=1e-10)


def test_identity_rotations_give_rest_pose(tiny_skeleton):
    eye = torch.eye(3, dtype=torch.float64).expand(10, 3, 3)
    _, pos = forward_kinematics(eye, torch.from_numpy(tiny_skeleton.offsets),
                                torch.from_numpy(tiny_skeleton.parents))
    np.testing.assert_allclose(pos.numpy() - tiny_skeleton.offsets[0],
                               tiny_skeleton.rest_positions(), atol=1e-12)


def test_concatenated_different_skeletons(tiny_skeleton):
    """Two different skeletons in one call (global parent indices) give the
    same result as each alone."""
    parent_a = torch.from_numpy(tiny_skeleton.parents)  # 10 joints, depth 3
    parent_b = torch.tensor([-1, 0, 1, 2, 3, 1])  # 6-joint chain, depth 4
    gen = torch.Generator().manual_seed(2)
    offset_a = torch.from_numpy(tiny_skeleton.offsets)
    offset_b = torch.randn(5, 6, 3, generator=gen, dtype=torch.float64)
    rot_a = random_rotation(5, 10, seed=3)
    rot_b = random_rotation(5, 6, seed=4)
    parent = torch.cat([parent_a, torch.where(parent_b >= 0, parent_b + 10, -1)])
    rotation = torch.cat([rot_a, rot_b], dim=1)
    offset = torch.cat([offset_a.expand(5, 10, 3), offset_b], dim=1)
    glob_rot, glob_pos = forward_kinematics(rotation, offset, parent)
    rot_a_ref, pos_a_ref = forward_kinematics(rot_a, offset_a, parent_a)
    rot_b_ref, pos_b_ref = forward_kinematics(rot_b, offset_b, parent_b)
    torch.testing.assert_close(glob_rot[:, :10], rot_a_ref)
    torch.testing.assert_close(glob_pos[:, :10], pos_a_ref)
    torch.testing.assert_close(glob_rot[:, 10:], rot_b_ref)
    torch.testing.assert_close(glob_pos[:, 10:], pos_b_ref)


def test_levels():
    parent = torch.tensor([-1, 0, 1, 0, -1, 4, 5, 6])
    levels = fk_levels(parent)
    assert [lv.tolist() for lv in levels] == [[0, 4], [1, 3, 5], [2, 6], [7]]
    depth = torch.tensor([0, 1, 2, 1, 0, 1, 2, 3])
    assert [lv.tolist() for lv in fk_levels(parent, depth)] == \
        [lv.tolist() for lv in levels]
    with pytest.raises(ValueError, match="before children"):
        fk_levels(torch.tensor([-1, 2, 0]))


def test_precomputed_levels_and_no_input_mutation(tiny_skeleton):
    parent = torch.from_numpy(tiny_skeleton.parents)
    rotation = random_rotation(3, 10, seed=5)
    offset = torch.from_numpy(tiny_skeleton.offsets).expand(3, 10, 3).clone()
    rot_copy, off_copy = rotation.clone(), offset.clone()
    out1 = forward_kinematics(rotation, offset, parent)
    out2 = forward_kinematics(rotation, offset, parent, levels=fk_levels(parent))
    torch.testing.assert_close(out1, out2)
    torch.testing.assert_close(rotation, rot_copy, rtol=0, atol=0)
    torch.testing.assert_close(offset, off_copy, rtol=0, atol=0)


def test_grad_path_matches_no_grad_path(tiny_skeleton):
    parent = torch.from_numpy(tiny_skeleton.parents)
    rotation = random_rotation(2, 10, seed=6)
    offset = torch.from_numpy(tiny_skeleton.offsets)
    with torch.no_grad():
        fast = forward_kinematics(rotation, offset, parent)
    slow = forward_kinematics(rotation.clone().requires_grad_(), offset, parent)
    torch.testing.assert_close(slow[0].detach(), fast[0])
    torch.testing.assert_close(slow[1].detach(), fast[1])


def test_gradcheck():
    parent = torch.tensor([-1, 0, 1, 0])
    gen = torch.Generator().manual_seed(7)
    six = torch.randn(2, 4, 6, generator=gen, dtype=torch.float64, requires_grad=True)
    offset = torch.randn(4, 3, generator=gen, dtype=torch.float64, requires_grad=True)

    def fk(six, offset):
        rot, pos = forward_kinematics(rotation_6d_to_matrix(six), offset, parent)
        return rot, pos

    assert torch.autograd.gradcheck(fk, (six, offset))


def test_float32_and_shared_offsets(tiny_skeleton):
    parent = torch.from_numpy(tiny_skeleton.parents)
    rotation = random_rotation(4, 10, seed=8).float()
    offset = torch.from_numpy(tiny_skeleton.offsets)  # float64 offsets
    rot, pos = forward_kinematics(rotation, offset, parent)
    assert rot.dtype == pos.dtype == torch.float32
    assert pos.shape == (4, 10, 3)


@pytest.mark.skipif(not torch.cuda.is_available(), reason="needs CUDA")
def test_cuda_matches_cpu(tiny_skeleton):
    parent = torch.from_numpy(tiny_skeleton.parents)
    rotation = random_rotation(4, 10, seed=9)
    offset = torch.from_numpy(tiny_skeleton.offsets)
    cpu = forward_kinematics(rotation, offset, parent)
    gpu = forward_kinematics(rotation.cuda(), offset.cuda(), parent)
    torch.testing.assert_close(gpu[1].cpu(), cpu[1])


@pytest.mark.parametrize("frames", [0, 1, 7, 1100])
def test_numpy_fk_matches_torch(tiny_skeleton, frames):
    from satagraph.ops.fk import forward_kinematics_numpy
    parent = tiny_skeleton.parents
    rotation = random_rotation(frames, 10, seed=3)
    offset = np.broadcast_to(tiny_skeleton.offsets, (frames, 10, 3)).copy()
    offset[:, 0] += np.random.default_rng(0).normal(size=(frames, 3))  # moving root
    want_rot, want_pos = forward_kinematics(rotation, torch.from_numpy(offset),
                                            torch.from_numpy(parent))
    rot, pos = forward_kinematics_numpy(rotation.numpy(), offset, parent)
    np.testing.assert_allclose(rot, want_rot.numpy(), atol=1e-12)
    np.testing.assert_allclose(pos, want_pos.numpy(), atol=1e-10)
    leaves_skipped, pos2 = forward_kinematics_numpy(rotation.numpy(), offset, parent,
                                                    rotations=False)
    np.testing.assert_allclose(pos2, pos, atol=1e-12)


@pytest.mark.parametrize("moving", ["root", "every joint"])
def test_numpy_fk_in_steps_with_moving_offsets(tiny_skeleton, monkeypatch, moving):
    """Several steps over frames; per-frame offsets on children (position
    channels) as well as constant ones."""
    from satagraph.ops import fk
    monkeypatch.setattr(fk, "FK_CHUNK_JOINT_FRAMES", 70)  # 7 frames a step
    parent, frames = tiny_skeleton.parents, 50
    rotation = random_rotation(frames, 10, seed=4)
    offset = np.broadcast_to(tiny_skeleton.offsets, (frames, 10, 3)).copy()
    joints = 1 if moving == "root" else 10
    offset[:, :joints] += np.random.default_rng(1).normal(size=(frames, joints, 3))
    want_rot, want_pos = forward_kinematics(rotation, torch.from_numpy(offset),
                                            torch.from_numpy(parent))
    rot, pos = fk.forward_kinematics_numpy(rotation.numpy(), offset, parent)
    np.testing.assert_allclose(rot, want_rot.numpy(), atol=1e-12)
    np.testing.assert_allclose(pos, want_pos.numpy(), atol=1e-10)
    none, pos2 = fk.forward_kinematics_numpy(rotation.numpy(), offset, parent,
                                             rotations=False)
    assert none is None
    np.testing.assert_allclose(pos2, pos, atol=1e-12)


def test_numpy_fk_several_roots():
    from satagraph.ops.fk import forward_kinematics_numpy
    parent = np.array([-1, 0, 1, -1, 3, 3, 5])
    rotation = random_rotation(6, 7, seed=5).numpy()
    offset = np.random.default_rng(2).normal(size=(6, 7, 3))
    want_rot, want_pos = reference_fk(rotation, offset, parent)
    rot, pos = forward_kinematics_numpy(rotation, offset, parent)
    np.testing.assert_allclose(rot, want_rot, atol=1e-12)
    np.testing.assert_allclose(pos, want_pos, atol=1e-12)


def test_numpy_fk_rejects_unordered_parents():
    from satagraph.ops.fk import forward_kinematics_numpy
    with pytest.raises(ValueError, match="parents must come before"):
        forward_kinematics_numpy(np.eye(3)[None, None].repeat(2, 1), np.zeros((1, 2, 3)),
                                 np.array([1, -1]))


@pytest.mark.parametrize("grad", [False, True])
def test_runs_in_full_precision_under_bf16_autocast(grad):
    """bf16 autocast of a training step must not put FK's chains of products
    in half precision: same float32 result, with or without autograd."""
    gen = torch.Generator().manual_seed(0)
    rot = rotation_6d_to_matrix(torch.randn(5, 6, 6, generator=gen)).requires_grad_(grad)
    off = torch.randn(6, 3, generator=gen)
    parent = torch.tensor([-1, 0, 1, 2, 3, 4])
    ref_rot, ref_pos = forward_kinematics(rot, off, parent)
    with torch.autocast("cpu", dtype=torch.bfloat16):
        glob_rot, glob_pos = forward_kinematics(rot, off, parent)
    assert glob_rot.dtype == glob_pos.dtype == torch.float32
    torch.testing.assert_close(glob_pos, ref_pos)
    torch.testing.assert_close(glob_rot, ref_rot)
    # half-precision input is promoted, not propagated
    _, half_pos = forward_kinematics(rot.detach().bfloat16(), off, parent)
    assert half_pos.dtype == torch.float32
