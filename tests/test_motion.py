"""Motion: validation, FK on real files, slicing and raw channels."""
from __future__ import annotations

import numpy as np
import pytest

from satagraph.io import channel_values, read_bvh, write_bvh
from satagraph.motion import CanonicalTransform, Motion


def test_global_positions_real_file(skeleton_row, read_real):
    motion = read_real(skeleton_row["path"])
    pos = motion.global_positions()
    assert pos.shape == (motion.num_frames, motion.num_joints, 3)
    assert np.isfinite(pos).all()
    rot, pos2 = motion.global_transforms()
    assert rot.shape == (motion.num_frames, motion.num_joints, 3, 3)
    np.testing.assert_array_equal(pos, pos2)
    # The root moves with its position channels.
    np.testing.assert_allclose(pos[:, 0], motion.root_translation)
    assert motion.height() > 0


def test_bone_lengths_constant_without_position_channels(read_real):
    motion = read_real("cmu/neutral_01_000.bvh")
    pos = motion.global_positions()
    skel = motion.skeleton
    child = np.arange(1, skel.num_joints)
    lengths = np.linalg.norm(pos[:, child] - pos[:, skel.parents[child]], axis=-1)
    np.testing.assert_allclose(lengths, np.broadcast_to(
        np.linalg.norm(skel.offsets[child], axis=-1), lengths.shape), rtol=1e-9,
        atol=1e-9)


def test_slice_keeps_raw_channels_consistent(read_real, tmp_path):
    motion = read_real("dog/D1_010_KAN01_002.bvh")
    part = motion.slice(10, 25)
    assert part.num_frames == 15 and part.fps == motion.fps
    np.testing.assert_array_equal(part.raw_channels, motion.raw_channels[10:25])
    np.testing.assert_array_equal(part.rotations, motion.rotations[10:25])
    np.testing.assert_array_equal(part.translations, motion.translations[10:25])
    # The raw channels still describe the sliced rotations.
    write_bvh(part, tmp_path / "part.bvh")
    again = read_bvh(tmp_path / "part.bvh")
    np.testing.assert_allclose(again.rotations, part.rotations, atol=1e-6)
    np.testing.assert_allclose(again.global_positions(), part.global_positions(),
                               atol=1e-4)
    assert channel_values(part) is part.raw_channels
    # An empty slice stays consistent too.
    assert motion.slice(5, 5).raw_channels.shape == (0, motion.skeleton.num_channels)


def test_with_drops_raw_channels(tiny_motion):
    raw = channel_values(tiny_motion)
    motion = tiny_motion.with_(raw_channels=raw)
    assert motion.raw_channels is raw
    assert motion.with_().raw_channels is None
    assert motion.with_(fps=60).fps == 60 and motion.with_(fps=60).raw_channels is None
    assert motion.with_(raw_channels=raw).raw_channels is raw


def test_properties(tiny_motion):
    assert tiny_motion.num_frames == 8 and tiny_motion.num_joints == 10
    assert tiny_motion.duration == pytest.approx(8 / 30)
    assert tiny_motion.root_translation.shape == (8, 3)
    assert "frames=8" in repr(tiny_motion)


def test_height_uses_rest_pose_and_first_frame(tiny_skeleton):
    eye = np.broadcast_to(np.eye(3), (2, 10, 3, 3))
    motion = Motion(tiny_skeleton, eye, np.broadcast_to(tiny_skeleton.offsets,
                                                        (2, 10, 3)), fps=30)
    rest = tiny_skeleton.rest_positions()[:, 1]
    assert motion.height() == pytest.approx(rest.max() - rest.min())
    assert motion.slice(0, 0).height() == pytest.approx(rest.max() - rest.min())


@pytest.mark.parametrize("rot_shape, trans_shape, fps, match", [
    ((2, 9, 3, 3), (2, 9, 3), 30, "rotations"),
    ((2, 10, 3), (2, 10, 3), 30, "rotations"),
    ((2, 10, 3, 3), (3, 10, 3), 30, "translations"),
    ((2, 10, 3, 3), (2, 10, 3), 0, "fps"),
    ((2, 10, 3, 3), (2, 10, 3), -1, "fps"),
])
def test_validation(tiny_skeleton, rot_shape, trans_shape, fps, match):
    with pytest.raises(ValueError, match=match):
        Motion(tiny_skeleton, np.zeros(rot_shape), np.zeros(trans_shape), fps=fps)


def test_canonical_transform_summary():
    tf = CanonicalTransform(up_axis="+Z", yaw=np.pi / 2, scale=0.01,
                            source_fps=120.0)
    rot = tf.rotation
    np.testing.assert_allclose(rot @ rot.T, np.eye(3), atol=1e-12)
    summary = tf.to_dict()
    assert summary["up_axis"] == "+Z"
    assert summary["yaw_degrees"] == pytest.approx(90)
    assert summary["removed_root"] is None


def test_one_contact_rule(read_real):
    """Features, the renderer and ground_contacts share one rule: below 5 cm
    and slower than 0.4 m/s for a 1.75 m character, frame 0 by height."""
    from satagraph.data.features import motion_to_features
    from satagraph.motion import CONTACT_HEIGHT, CONTACT_SPEED, ground_contacts
    from satagraph.transforms.canonical import canonicalize
    from satagraph.viz.render import contacts

    assert np.isclose(CONTACT_HEIGHT * 1.75, 0.05) and np.isclose(CONTACT_SPEED * 1.75, 0.4)
    motion = canonicalize(read_real("cmu/01_01.bvh").slice(0, 60))
    c = contacts(motion)
    assert c.any() and not c.all()
    np.testing.assert_array_equal(motion_to_features(motion).c, c.astype(float))
    pos = np.zeros((3, 2, 3))
    pos[:, 1, 1] = 0.02  # 2 cm high, for a 1 m character
    pos[1:, 0, 0] = [0.0, 0.1]  # joint 0 moves 0.1 m at 30 fps: 3 m/s
    assert ground_contacts(pos, 30.0, 1.0).tolist() == [[True, True], [True, True], [False, True]]
    assert not ground_contacts(pos, 30.0, 0.5)[:, 1].any()  # 2 cm > 0.5 * 5/175 m


def test_one_first_pose_rule(tiny_motion):
    """Motion.first_pose: frame 0's global positions, the rest pose without
    frames (canonical's facing, augment's leg ratio and rig reading use it)."""
    np.testing.assert_allclose(tiny_motion.first_pose(), tiny_motion.global_positions()[0])
    empty = tiny_motion.slice(0, 0)
    np.testing.assert_allclose(empty.first_pose(), tiny_motion.skeleton.rest_positions())
    assert tiny_motion.first_pose().shape == (tiny_motion.num_joints, 3)
