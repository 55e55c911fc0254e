"""Motion features: layout, invariances and the lossless round trip."""
import glob

import numpy as np
import torch
import pytest

from satagraph.transforms.canonical import canonicalize
from satagraph.data.features import (DYNAMIC_CHANNELS, DYNAMIC_LAYOUT,
                                     features_to_motion, integrate_root,
                                     motion_to_features)
from satagraph.io import read_bvh


def test_manifest_lists_every_file(shared_data, manifest):
    files = sorted(glob.glob(str(shared_data / "*" / "*.bvh")))
    assert len(files) == len(manifest) == 247


def test_lossless_on_every_real_file(every_file_row, shared_data):
    """BVH -> canonical -> features -> motion reproduces global positions to
    1e-4 of the character height on every file in ../shared/data (one file
    per skeleton by default, all 247 with --slow)."""
    path = shared_data / every_file_row["path"]
    motion = canonicalize(read_bvh(path), fps=None)
    feats = motion_to_features(motion)
    back = features_to_motion(feats)
    err = np.abs(back.global_positions() - motion.global_positions()).max()
    assert err <= 1e-4 * feats.height, (path, err / feats.height)


@pytest.fixture(scope="module")
def dog_features(shared_data):
    motion = canonicalize(read_bvh(shared_data / "dog" / "D1_001_KAN01_001.bvh"))
    return motion, motion_to_features(motion)


def test_layout_and_shapes(dog_features):
    motion, feats = dog_features
    T, J = motion.num_frames, motion.num_joints
    assert feats.dynamic.shape == (T, J, DYNAMIC_CHANNELS)
    assert feats.r.shape == (T, 4) and feats.static.shape == (J, 6)
    assert feats.edge_attr.shape == (2 * (J - 1), 2)
    dyn = feats.dynamic
    np.testing.assert_array_equal(dyn[..., DYNAMIC_LAYOUT["x"]], feats.x)
    np.testing.assert_array_equal(dyn[..., DYNAMIC_LAYOUT["c"]][..., 0], feats.c)
    clip = feats.to_clip(10, 74)
    assert clip.dynamic.shape == (64, J, DYNAMIC_CHANNELS)
    assert clip.root.shape == (64, 4)


def test_root_in_facing_frame(dog_features):
    """The root sits at (0, h, 0) of its facing frame; frame 0 faces +Z at
    the origin, so the first yaw velocity and xz velocity are zero."""
    _, feats = dog_features
    np.testing.assert_allclose(feats.x[:, 0, [0, 2]], 0, atol=1e-9)
    np.testing.assert_allclose(feats.x[:, 0, 1], feats.r[:, 3])
    np.testing.assert_allclose(feats.r[0, :3], 0, atol=1e-9)


def test_features_invariant_to_world_yaw_and_position(dog_features):
    """Rotating and moving the whole motion about +Y changes only r[0]."""
    motion, feats = dog_features
    c, s = np.cos(0.7), np.sin(0.7)
    yaw = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    rot = motion.rotations.copy()
    rot[:, 0] = yaw @ rot[:, 0]
    trans = motion.translations.copy()
    trans[:, 0] = trans[:, 0] @ yaw.T + np.array([3.0, 0.0, -2.0])
    moved = motion_to_features(motion.with_(rotations=rot, translations=trans),
                               facing_axis=feats.facing_axis)
    for key in ("q", "x", "x_rel", "v_q", "v_x", "c"):
        np.testing.assert_allclose(getattr(moved, key), getattr(feats, key),
                                   atol=1e-8, err_msg=key)
    np.testing.assert_allclose(moved.r[1:], feats.r[1:], atol=1e-8)


def test_root_offset_is_not_a_static_feature(dog_features):
    """The dog's file places its root 4.7 m from the origin through the
    root's OFFSET; X_l ignores it (the root has no bone) and every other
    joint keeps its offset, so the same rig with its root offset zeroed has
    the same static features."""
    motion, feats = dog_features
    assert np.linalg.norm(motion.skeleton.offsets[0]) > 1.0
    np.testing.assert_array_equal(feats.x_local[0], 0.0)
    np.testing.assert_array_equal(feats.x_local[1:], motion.skeleton.offsets[1:])
    offsets = motion.skeleton.offsets.copy()
    offsets[0] = 0.0
    moved = motion_to_features(motion.with_(skeleton=motion.skeleton.replace(offsets=offsets)))
    np.testing.assert_array_equal(moved.static, feats.static)


def test_integrate_root_inverts_root_features(dog_features):
    motion, feats = dog_features
    _, origin = integrate_root(feats.r, feats.fps)
    np.testing.assert_allclose(origin[:, [0, 2]],
                               motion.translations[:, 0, [0, 2]], atol=1e-9)


def test_contacts_scale_with_height(dog_features):
    motion, feats = dog_features
    assert 0.05 < feats.c.mean() < 0.6  # paws touch the ground some of the time
    strict = motion_to_features(motion, contact_height=-1.0)
    assert strict.c.sum() == 0
    loose = motion_to_features(motion, contact_height=10.0, contact_speed=1e3)
    assert loose.c.min() == 1


def test_velocities_match_positions(dog_features):
    motion, feats = dog_features
    pos = motion.global_positions()
    speed = np.linalg.norm(pos[1:] - pos[:-1], axis=-1) * motion.fps
    np.testing.assert_allclose(np.linalg.norm(feats.v_x[1:], axis=-1), speed,
                               atol=1e-8)


def test_clips_carry_their_leg_length(dog_features):
    """Every clip says its character's leg length (the root's median height
    above its lowest joint over the whole file), which the batch collates
    beside the height: the dog's hips stand almost as high as its head."""
    from satagraph.data.collate import collate_clips
    from satagraph.motion import leg_length
    motion, feats = dog_features
    assert feats.leg_length == leg_length(motion.global_positions(), motion.height())
    assert 0.8 < feats.leg_length / feats.height < 1.0
    batch = collate_clips([feats.to_clip(0, 16), feats.to_clip(16, 40)])
    assert torch.allclose(batch.clip_leg, torch.tensor([feats.leg_length] * 2).float())
    assert torch.equal(batch.legs("frame"), batch.clip_leg[batch.frame_clip])


def test_facing_smoothing_keeps_the_motion_and_calms_the_yaw_rate(shared_data):
    """A trotting dog's pelvis swings its yaw (the facing frame's) by
    hundreds of degrees a clip: smoothed over a quarter second the facing
    yaw rate keeps the clip's turn and loses most of its swing (into the
    root's rotation), the first frame's yaw is kept, and the round trip
    stays lossless."""
    from satagraph.transforms.rig_reading import with_rig
    motion = canonicalize(with_rig(read_bvh(shared_data / "dog" / "D1_009_KAN01_001.bvh"),
                                   scale="cm"), fps=30)
    plain, smooth = motion_to_features(motion), motion_to_features(motion, facing_smooth=0.25)
    swing = [np.abs(f.r[1:, 0]).sum() / 30 for f in (plain, smooth)]
    assert swing[1] < 0.25 * swing[0]
    turn = [f.r[:, 0].sum() / 30 for f in (plain, smooth)]
    assert abs(turn[1] - turn[0]) < np.radians(20)
    assert smooth.r[0, 0] == pytest.approx(plain.r[0, 0], abs=1e-12)
    back = features_to_motion(smooth)
    err = np.abs(back.global_positions() - motion.global_positions()).max()
    assert err <= 1e-6 * smooth.height
    np.testing.assert_array_equal(smooth.x[..., 1], plain.x[..., 1])  # heights: no yaw


def test_smooth_yaw_unwraps_across_pi():
    """A steady turn through +-180 degrees stays a steady turn."""
    from satagraph.data.features import smooth_yaw
    theta = np.angle(np.exp(1j * np.linspace(2.5, 4.0, 40)))  # wraps at pi
    out = smooth_yaw(theta, 3.0)
    np.testing.assert_allclose(np.diff(out)[10:-10], np.diff(np.unwrap(theta))[10:-10], atol=1e-9)
    assert out[0] == theta[0]
    np.testing.assert_array_equal(smooth_yaw(theta, 0.0), theta)


@pytest.mark.parametrize("chunk", [1, 7, 64])
def test_features_in_chunks_are_the_whole_takes(shared_data, chunk):
    """Per-frame features computed a chunk of frames at a time (temporaries
    of a chunk, not of a long take) are the whole take's to the bit: the
    velocities across a chunk's first frame read the frame before it, and
    the facing smoothing, height and contacts stay those of the take."""
    from satagraph.transforms.rig_reading import with_rig
    motion = canonicalize(with_rig(read_bvh(shared_data / "dog" / "D1_009_KAN01_001.bvh"),
                                   scale="cm"), fps=30)
    assert motion.num_frames > 3 * chunk
    whole = motion_to_features(motion, facing_smooth=0.25, chunk=motion.num_frames)
    parts = motion_to_features(motion, facing_smooth=0.25, chunk=chunk)
    for key in ("q", "x", "x_rel", "v_q", "v_x", "c", "r"):
        np.testing.assert_array_equal(getattr(parts, key), getattr(whole, key), err_msg=key)
    assert (parts.height, parts.leg_length) == (whole.height, whole.leg_length)
    assert np.abs(whole.v_x[chunk]).max() > 0  # a chunk's first frame moves: read across
    with pytest.raises(ValueError, match="chunk"):
        motion_to_features(motion, chunk=0)
