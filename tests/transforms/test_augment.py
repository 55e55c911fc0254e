"""Skeleton augmentation: mirroring, bone scaling, topology changes."""
from __future__ import annotations

import numpy as np
import pytest

from satagraph.transforms.augment import (SkeletonAugment, axis_rest_rotations,
                                          drop_leaf_chain, insert_joint, merge_segments,
                                          mean_pose_rotations, mirror, mirror_pairs,
                                          new_rest, paired, rebase_rest, rebase_rotations, restructure, scale_bones,
                                          set_rest_rotations, swap_side)
from satagraph.transforms.canonical import canonicalize
from satagraph.data.dataset import WindowAugment
from satagraph.data.examples import example_motion
from satagraph.data.features import motion_to_features
from satagraph.datasets.zoo import generate_clip, zoo_rigs
from satagraph.io import read_bvh, write_bvh

RIGS = {r.species: r for r in zoo_rigs(seed=0)}


@pytest.fixture(scope="module", params=["biped", "quadruped", "hexapod", "snake"])
def motion(request):
    return generate_clip(RIGS[request.param], "walk", frames=16, seed=0)


def _valid(motion):
    skel = motion.skeleton
    assert (skel.parents[1:] < np.arange(1, skel.num_joints)).all()
    assert skel.parents[0] == -1
    assert len(set(skel.names)) == skel.num_joints
    assert (np.linalg.norm(skel.offsets[1:], axis=1) > 1e-9).all()
    assert np.isfinite(motion.global_positions()).all()


def _common(a, b):
    """Global positions of the joints both motions share (by name)."""
    names = [n for n in a.skeleton.names if n in b.skeleton.names]
    ia = [a.skeleton.names.index(n) for n in names]
    ib = [b.skeleton.names.index(n) for n in names]
    return a.global_positions()[:, ia], b.global_positions()[:, ib]


@pytest.mark.parametrize("name,other", [
    ("LeftUpLeg", "RightUpLeg"), ("thigh.L", "thigh.R"), ("l_hip", "r_hip"),
    ("LHipJoint", "RHipJoint"), ("L_Fr_UpLeg", "R_Fr_UpLeg"),
    ("antenna_r", "antenna_l"), ("HandL", "HandR"), ("Spine1", "Spine1"),
    ("LowerBack", "LowerBack"), ("Head", "Head"), ("root", "root")])
def test_swap_side(name, other):
    assert swap_side(name) == other
    assert swap_side(other) == name


def test_mirror_twice_is_identity(motion):
    twice = mirror(mirror(motion))
    assert twice.skeleton.names == motion.skeleton.names
    assert np.allclose(twice.rotations, motion.rotations)
    assert np.allclose(twice.translations, motion.translations)
    assert np.allclose(twice.skeleton.offsets, motion.skeleton.offsets)


def test_mirror_reflects_positions(motion):
    mirrored = mirror(motion)
    _valid(mirrored)
    pair = mirror_pairs(motion.skeleton)
    expected = motion.global_positions()[:, pair] * np.array([-1.0, 1.0, 1.0])
    assert np.allclose(mirrored.global_positions(), expected, atol=1e-9)
    sided = sum(swap_side(n) != n for n in motion.skeleton.names)
    assert (pair != np.arange(len(pair))).sum() == sided  # sides swapped


def test_mirror_round_trips_through_bvh(tmp_path):
    motion = generate_clip(RIGS["biped"], "turn", frames=10, seed=1)
    write_bvh(mirror(motion), tmp_path / "m.bvh")
    back = read_bvh(tmp_path / "m.bvh")
    assert np.allclose(back.global_positions(), mirror(motion).global_positions(),
                       atol=1e-4)


def test_scale_bones_and_paired_keep_rotations(motion):
    scaled = scale_bones(motion, seed=3)
    _valid(scaled)
    assert np.array_equal(scaled.rotations, motion.rotations)
    assert not np.allclose(scaled.skeleton.offsets, motion.skeleton.offsets)
    source, target = paired(motion, seed=3)
    assert source is motion
    assert np.array_equal(target.rotations, source.rotations)
    assert target.skeleton.names == source.skeleton.names


@pytest.mark.parametrize("seed", range(4))
def test_drop_leaf_chain(motion, seed):
    dropped = drop_leaf_chain(motion, seed=seed, max_length=3)
    _valid(dropped)
    assert 1 <= motion.num_joints - dropped.num_joints <= 3
    a, b = _common(dropped, motion)
    assert np.allclose(a, b, atol=1e-12)


@pytest.mark.parametrize("seed", range(4))
def test_merge_segments(motion, seed, tmp_path):
    merged = merge_segments(motion, seed=seed)
    _valid(merged)
    assert merged.num_joints == motion.num_joints - 1
    a, b = _common(merged, motion)
    assert a.shape[1] == merged.num_joints
    assert np.allclose(a, b, atol=1e-9)
    write_bvh(merged, tmp_path / "m.bvh")  # position channels carry the bend
    back = read_bvh(tmp_path / "m.bvh")
    assert np.allclose(back.global_positions(), merged.global_positions(),
                       atol=1e-4)


@pytest.mark.parametrize("seed", range(4))
def test_insert_joint(motion, seed):
    split = insert_joint(motion, seed=seed)
    _valid(split)
    assert split.num_joints == motion.num_joints + 1
    a, b = _common(split, motion)
    assert a.shape[1] == motion.num_joints
    assert np.allclose(a, b, atol=1e-9)
    new = next(n for n in split.skeleton.names if n not in motion.skeleton.names)
    assert new.endswith("_split")


@pytest.mark.parametrize("seed", range(3))
def test_restructure_changes_structure_and_keeps_the_motion(motion, seed):
    """The cross-setting target: a leaf chain dropped and a bone split, the
    kept joints with their own local rotations; without bone scaling every
    kept joint stays exactly where it was (a reachable ground truth)."""
    target = restructure(motion, seed=seed)
    _valid(target)
    names = target.skeleton.names
    assert sum(n.endswith("_split") for n in names) == 1
    assert 1 <= len(set(motion.skeleton.names) - set(names)) <= 2
    kept = [n for n in names if n in motion.skeleton.names]
    src = motion.skeleton.names
    assert np.array_equal(target.rotations[:, [names.index(n) for n in kept]],
                          motion.rotations[:, [src.index(n) for n in kept]])
    assert not np.allclose(_common(target, motion)[0], _common(target, motion)[1])
    unscaled = restructure(motion, low=1.0, high=1.0, seed=seed)
    assert unscaled.skeleton.names == names
    a, b = _common(unscaled, motion)
    assert a.shape[1] == len(kept)
    assert np.allclose(a, b, atol=1e-9)
    again = restructure(motion, seed=seed)
    assert np.array_equal(again.global_positions(), target.global_positions())


def test_skeleton_augment_is_seeded_and_valid():
    motion = generate_clip(RIGS["quadruped"], "walk", frames=8, seed=0)
    kwargs = dict(p_scale=1.0, p_mirror=1.0, p_drop=1.0, p_merge=1.0,
                  p_insert=1.0, seed=7)
    a, b = SkeletonAugment(**kwargs), SkeletonAugment(**kwargs)
    outs = [a(motion) for _ in range(3)]
    for out, again in zip(outs, (b(motion) for _ in range(3))):
        _valid(out)
        assert out.skeleton.names == again.skeleton.names
        assert np.allclose(out.global_positions(), again.global_positions())
    assert SkeletonAugment(p_scale=0, p_mirror=0, p_drop=0, p_merge=0,
                           p_insert=0)(motion) is motion
    with pytest.raises(ValueError):
        SkeletonAugment(p_mirror=1.5)


def test_example_motion_still_works():
    motion = example_motion(num_frames=5)
    assert np.allclose(mirror(mirror(motion)).global_positions(),
                       motion.global_positions())
    _valid(drop_leaf_chain(motion))
    _valid(insert_joint(motion))


# ------------------------------------------------------------- rest pose
def test_rebase_rest_keeps_the_motion_and_takes_the_frames_pose(motion):
    rebased = rebase_rest(motion, frame=5)
    _valid(rebased)
    np.testing.assert_allclose(rebased.global_positions(), motion.global_positions(),
                               atol=1e-9)
    # every joint but the root is at rest in the chosen frame
    np.testing.assert_allclose(rebased.rotations[5, 1:],
                               np.broadcast_to(np.eye(3), rebased.rotations[5, 1:].shape),
                               atol=1e-9)
    # bone lengths are kept; the names and hierarchy too
    np.testing.assert_allclose(np.linalg.norm(rebased.skeleton.offsets, axis=1),
                               np.linalg.norm(motion.skeleton.offsets, axis=1), atol=1e-9)
    assert rebased.skeleton.names == motion.skeleton.names
    with pytest.raises(ValueError, match="frame 16"):
        rebase_rest(motion, frame=16)


def test_mean_pose_rest_averages_the_frames_and_keeps_the_motion(motion):
    """The mean pose of one frame is that frame's rest; over a walk's
    frames every joint but the root averages to no turn in the new rest,
    which keeps the motion, the bone lengths and the root's facing."""
    np.testing.assert_allclose(mean_pose_rotations(motion, [5], 5),
                               rebase_rotations(motion, 5), atol=1e-12)
    rest = mean_pose_rotations(motion, range(16), 5)
    rebased = set_rest_rotations(motion, rest)
    _valid(rebased)
    np.testing.assert_allclose(rebased.global_positions(), motion.global_positions(), atol=1e-9)
    local = rebased.rotations[:, 1:]
    u, _, vt = np.linalg.svd(local.mean(axis=0))
    np.testing.assert_allclose(u @ vt, np.broadcast_to(np.eye(3), u.shape), atol=1e-9)
    np.testing.assert_allclose(rest[0], rebase_rotations(motion, 5)[0], atol=1e-12)
    with pytest.raises(ValueError, match="frames outside a 16-frame motion"):
        mean_pose_rotations(motion, [3, 16], 3)
    with pytest.raises(ValueError, match="frames outside"):
        mean_pose_rotations(motion, [], 3)


def test_mean_pose_rest_of_a_walk_has_its_legs_side_by_side():
    """In any frame of a walk one leg is forward of the other; in the walk's
    mean pose the two feet are nearly level fore and aft (within a tenth of the gap
    in the frame where they are furthest apart)."""
    walk = generate_clip(RIGS["biped"], "walk", frames=60, seed=0)
    names = walk.skeleton.names
    feet = [names.index(n) for n in names if "foot" in n.lower() and "end" not in n.lower()][:2]
    canon = canonicalize(walk, fps=30)
    pos = canon.global_positions()[:, feet]
    gap = np.abs(pos[:, 0, 2] - pos[:, 1, 2]).max()
    rest = set_rest_rotations(canon, mean_pose_rotations(canon, range(60), 0)).skeleton
    feet_rest = rest.rest_positions()[feet]
    assert gap > 0.1 * canon.height()
    assert abs(feet_rest[0, 2] - feet_rest[1, 2]) < 0.1 * gap


@pytest.mark.parametrize("species", ["biped", "quadruped", "hexapod"])
def test_rebase_rest_faces_like_frame_0_when_the_root_tilts_in_between(species):
    """A body pitched 80 degrees over at frame 0 (rearing, lying) and turned
    120 degrees: the root's heading change says nothing of the turn then,
    so the rest (frame 5's pose) is turned by the facing of its left/right
    joint pairs nearest the root and faces exactly as frame 0 does (the root's heading rule
    missed by 8-38 degrees here)."""
    from satagraph.ops.rotation_numpy import yaw_matrix_numpy, yaw_of
    from satagraph.transforms.canonical import body_forward
    walk = generate_clip(RIGS[species], "walk", frames=16, seed=0)
    c, s = np.cos(np.radians(-80)), np.sin(np.radians(-80))
    pitch = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    rotations = walk.rotations.copy()
    rotations[0, 0] = yaw_matrix_numpy(np.radians(120)) @ pitch @ rotations[0, 0]
    tilted = walk.with_(rotations=rotations)
    up = np.array([0.0, 1.0, 0.0])
    rebased = rebase_rest(tilted, frame=5)
    first = yaw_of(body_forward(tilted.global_positions()[0], walk.skeleton, up))
    rest = yaw_of(body_forward(rebased.skeleton.rest_positions(), rebased.skeleton, up))
    assert np.degrees(abs((rest - first + np.pi) % (2 * np.pi) - np.pi)) < 0.5
    np.testing.assert_allclose(rebased.global_positions(), tilted.global_positions(),
                               atol=1e-9)


def test_axis_rest_is_a_line_with_one_roll_convention():
    """Every first child on its joint's +X; the roll is the documented one:
    a downward leg has the rig's left on local +Y and forward on local +Z
    (Bandai's legs), whatever the bone lengths."""
    walk = generate_clip(RIGS["biped"], "walk", frames=8, seed=0)
    for motion in (walk, scale_bones(walk, seed=3)):
        rest = axis_rest_rotations(motion.skeleton)
        moved = set_rest_rotations(motion, rest)
        np.testing.assert_allclose(moved.global_positions(), motion.global_positions(),
                                   atol=1e-9)
        np.testing.assert_allclose(rest @ np.swapaxes(rest, -1, -2),
                                   np.broadcast_to(np.eye(3), rest.shape), atol=1e-12)
        knee = motion.skeleton.names.index("LeftLeg")
        np.testing.assert_allclose(rest[knee] @ [1.0, 0.0, 0.0] @ [0.0, 1.0, 0.0], 1.0, atol=0.2)
        np.testing.assert_allclose(rest[knee] @ [0.0, 0.0, 1.0] @ [0.0, 0.0, 1.0], 1.0, atol=0.2)


def test_new_rest_draws_both_conventions_and_keeps_positions(motion):
    drawn = [new_rest(motion, np.random.default_rng(s)) for s in range(8)]
    lines = [m for m in drawn
             if np.allclose(m.skeleton.offsets[m.skeleton.children[0][0]][1:], 0.0)]
    assert 0 < len(lines) < len(drawn)
    for m in drawn:
        np.testing.assert_allclose(m.global_positions(), motion.global_positions(), atol=1e-9)


def test_rebase_rest_makes_lying_rest_poses_upright(shared_data):
    """bandai's rest pose has every bone along one axis (0.13 m tall for a
    1.33 m character); the rebased rest pose stands like the motion."""
    walk = canonicalize(read_bvh(shared_data / "bandai" / "dataset-1_walk_normal_001.bvh"),
                        fps=30).slice(0, 20)
    rest = rebase_rest(walk, frame=10).skeleton.rest_positions()
    assert np.ptp(walk.skeleton.rest_positions()[:, 1]) < 0.2 * walk.height()
    assert np.ptp(rest[:, 1]) == pytest.approx(walk.height(), rel=0.05)


def test_window_augment_rest_changes_rotations_not_positions(shared_data):
    """A new rest-pose convention changes q and the static features; the
    positions, root features and contacts the model must reproduce stay."""
    feats = motion_to_features(canonicalize(
        read_bvh(shared_data / "dog" / "D1_001_KAN01_001.bvh"), fps=30))
    plain, _ = WindowAugment(scale=0, mirror=0)(feats, 10, 42, 0, 0)
    rebased, _ = WindowAugment(scale=0, mirror=0, rest=1.0)(feats, 10, 42, 0, 0)
    for key in ("x", "r", "c"):
        np.testing.assert_allclose(getattr(rebased, key), getattr(plain, key), atol=1e-8)
    assert np.abs(rebased.q - plain.q).max() > 0.5
    assert np.abs(rebased.static - plain.static).max() > 0.1


def test_window_augment_shows_windows_as_inference_shows_rigs(shared_data):
    """``data.preprocessing.rest: auto`` (``show_rest``): an augmented
    window whose rest became a line or a captured frame is shown re-rested
    on its mean standing pose, as ``retarget``'s ``rest="auto"`` shows a
    rig, so no line rest reaches the model; the positions, root features
    and contacts stay; an unknown mode is refused by name."""
    from satagraph.transforms.rest import is_line_rest
    from satagraph.data.features import features_to_motion
    feats = motion_to_features(canonicalize(
        read_bvh(shared_data / "dog" / "D1_001_KAN01_001.bvh"), fps=30))
    assert is_line_rest(feats.skeleton)
    plain, _ = WindowAugment(scale=0, mirror=0)(feats, 10, 42, 0, 0)
    shown, _ = WindowAugment(scale=0, mirror=0, rest=1.0, show_rest="auto")(feats, 10, 42, 0, 0)
    for key in ("x", "r", "c"):
        np.testing.assert_allclose(getattr(shown, key), getattr(plain, key), atol=1e-8)
    assert not is_line_rest(shown.skeleton)
    as_is, _ = WindowAugment(scale=0, mirror=0, show_rest="file")(feats, 10, 42, 0, 0)
    assert is_line_rest(as_is.skeleton)
    np.testing.assert_allclose(features_to_motion(shown).global_positions(),
                               features_to_motion(plain).global_positions(), atol=1e-6)
    with pytest.raises(ValueError, match="data.preprocessing.rest must be one of"):
        WindowAugment(show_rest="mean")


def test_augmented_windows_keep_their_clips_height_and_contacts(shared_data):
    """A window of a dog clip that lies down at first measures 1.41 times
    its clip's height on its own: mirrored, reversed or left as it is, an
    augmented window keeps its clip's height, so its contacts are the
    clip's (mirrored: exchanged left/right; reversed: the height test of
    the same frames)."""
    from satagraph.data.captioned import mirror_features, reverse_features
    from satagraph.data.dataset import feature_options
    feats = motion_to_features(canonicalize(
        read_bvh(shared_data / "dog" / "D1_009_KAN01_002.bvh"), fps=30, replace_bind=False))
    start, stop, options = 32, 96, feature_options()
    pair = mirror_pairs(feats.skeleton)
    plain, lead = WindowAugment(scale=0, mirror=0)(feats, start, stop, 0, 0)
    mirrored, _ = WindowAugment(scale=0, mirror=1)(feats, start, stop, 0, 0)
    by_text, _ = mirror_features(feats, start, stop, options)
    backwards, first = reverse_features(feats, start, stop, options)
    for out in (plain, mirrored, by_text, backwards):
        assert out.height == pytest.approx(feats.height, rel=1e-9)
    np.testing.assert_array_equal(plain.c[lead:], feats.c[start:stop])
    np.testing.assert_array_equal(mirrored.c[lead:], feats.c[start:stop, pair])
    np.testing.assert_array_equal(by_text.c[lead:], feats.c[start:stop, pair])
    low = feats.x[start:stop, :, 1] < options["contact_height"] * feats.height
    np.testing.assert_array_equal(backwards.c[first:] <= low[::-1], True)
