"""Sliding-window inference and retargeting with a tiny SATA module."""
from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np
import pytest
import torch

from satagraph.transforms.canonical import canonicalize
from satagraph.data.collate import collate_clips
from satagraph.data.features import motion_to_features
from satagraph.pipelines.inference import (reconstruct_motion, resample_frames, retarget_motion,
                                           target_clip, transfer, window_plan)
from satagraph.io import read_bvh, write_bvh
from satagraph.motion import Motion

DOG = "dog/D1_010_KAN01_002.bvh"                # 60 fps
HUMAN = "cmu/depressed_18_000.bvh"              # 120 fps
BANDAI = "bandai/dataset-1_dash_normal_001.bvh"  # 30 fps, 20 frames


# --------------------------------------------------------------- window plan
def _kept_frames(plan) -> list:
    return [f for start, stop, keep in plan for f in range(keep, stop)]


@pytest.mark.parametrize("num_frames", [1, 5, 31, 32, 33, 47, 48, 49, 100, 257])
def test_window_plan_covers_every_frame_once(num_frames: int) -> None:
    window, overlap = 32, 8
    plan = window_plan(num_frames, window, overlap)
    assert _kept_frames(plan) == list(range(num_frames))
    for start, stop, keep in plan:
        assert 0 <= start <= keep < stop <= num_frames
        assert stop - start == min(window, num_frames)
    # Consecutive windows share at least the overlap (the later one is cropped).
    for (a0, b0, _), (a1, _, keep1) in zip(plan, plan[1:]):
        assert keep1 == b0 and b0 - a1 >= overlap
    if num_frames <= window:
        assert plan == [(0, num_frames, 0)]


def test_window_plan_without_overlap_and_bad_overlap() -> None:
    assert window_plan(64, 16, 0) == [(0, 16, 0), (16, 32, 16), (32, 48, 32), (48, 64, 48)]
    with pytest.raises(ValueError, match="overlap"):
        window_plan(100, 16, 16)


def test_resample_frames_hits_exact_count_and_holds_last_frame(tiny_motion: Motion) -> None:
    motion = tiny_motion                       # 8 frames at 30 fps
    assert resample_frames(motion, 30.0, 8) is motion
    up = resample_frames(motion, 60.0, 16)
    assert up.num_frames == 16 and up.fps == 60.0
    np.testing.assert_allclose(up.rotations[0:16:2], motion.rotations, atol=1e-6)
    np.testing.assert_allclose(up.translations[1], motion.translations[:2].mean(0),
                               atol=1e-9)
    np.testing.assert_allclose(up.rotations[15], motion.rotations[7], atol=1e-6)
    longer = resample_frames(motion, 30.0, 10)
    np.testing.assert_allclose(longer.translations[7:], motion.translations[[7, 7, 7]])
    rot = up.rotations
    np.testing.assert_allclose(rot @ np.swapaxes(rot, -1, -2), np.broadcast_to(
        np.eye(3), rot.shape), atol=1e-6)


# -------------------------------------------------------------- sliding window
@pytest.fixture(scope="module")
def dog_features(read_real: Callable[[str], Motion]):
    """Canonical features of a short dog clip (40 frames at 30 fps)."""
    motion = read_real(DOG).slice(0, 80)
    return motion_to_features(canonicalize(motion, fps=30.0))


def _single_pass(module, feats, embed, start: int, stop: int):
    sem = embed(feats.skeleton)
    src = collate_clips([feats.to_clip(start, stop, sem)])
    tgt = collate_clips([target_clip(feats, stop - start, sem)])
    with torch.no_grad():
        return module(src, tgt)


def test_window_longer_than_clip_is_one_pass(build_tiny_module: Callable, dog_features,
                                             embed: Callable) -> None:
    module = build_tiny_module("vae").eval()
    num, joints = dog_features.num_frames, dog_features.skeleton.num_joints
    q, r, c = transfer(module, dog_features, dog_features, embed, window=num + 8, overlap=4)
    assert q.shape == (num, joints, 6) and r.shape == (num, 4) and c.shape == (num, joints)
    ref = _single_pass(module, dog_features, embed, 0, num)
    np.testing.assert_allclose(q, ref["q"].view(num, joints, 6).double().numpy(),
                               rtol=1e-5, atol=1e-5)
    np.testing.assert_allclose(r, ref["r"].double().numpy(), rtol=1e-5, atol=1e-5)
    probs = torch.sigmoid(ref["c"]).view(num, joints).double().numpy()
    np.testing.assert_allclose(c, probs, rtol=1e-5, atol=1e-6)
    assert ((c >= 0) & (c <= 1)).all()


def test_sliding_windows_cross_fade_where_they_overlap(
        build_tiny_module: Callable, dog_features, embed: Callable) -> None:
    """Frames one window alone decodes are its single pass's; frames two
    windows share move linearly from the earlier window's reading to the
    later's (cut at the seam, the pose jumped there)."""
    module = build_tiny_module("vae").eval()
    num, joints = dog_features.num_frames, dog_features.skeleton.num_joints
    window, overlap = 16, 4
    plan = window_plan(num, window, overlap)
    assert len(plan) >= 3
    # Small batches: windows are split across several forward passes.
    q, r, _ = transfer(module, dog_features, dog_features, embed, window, overlap,
                       batch_size=2)
    assert q.shape == (num, joints, 6) and np.isfinite(q).all()
    refs = []
    for start, stop, _ in plan:
        ref = _single_pass(module, dog_features, embed, start, stop)
        refs.append((ref["q"].view(-1, joints, 6).double().numpy(), ref["r"].double().numpy()))
    for i, (start, stop, keep) in enumerate(plan):
        alone = slice(keep, plan[i + 1][0] if i + 1 < len(plan) else stop)
        for got, ref in zip((q, r), refs[i]):
            np.testing.assert_allclose(got[alone], ref[alone.start - start:alone.stop - start],
                                       rtol=1e-4, atol=1e-5)
        if i == 0:
            continue
        before = plan[i - 1][0]
        fade = np.arange(1, keep - start + 1) / (keep - start + 1)
        for got, earlier, later in zip((q, r), refs[i - 1], refs[i]):
            w = fade.reshape((-1,) + (1,) * (later.ndim - 1))
            blend = (1 - w) * earlier[start - before:keep - before] + w * later[:keep - start]
            np.testing.assert_allclose(got[start:keep], blend, rtol=1e-4, atol=1e-5)


def test_transfer_restores_training_mode(build_tiny_module: Callable, dog_features,
                                         embed: Callable) -> None:
    module = build_tiny_module("vae").train()
    transfer(module, dog_features, dog_features, embed, window=16, overlap=4)
    assert module.training


# ------------------------------------------------------------------ retarget
@pytest.mark.parametrize("source,target,num_frames", [
    (DOG, HUMAN, 100),      # dog -> human, an even number of 60 fps frames
    (DOG, BANDAI, 75),
    (HUMAN, DOG, 90),       # human -> dog, 120 fps
    (BANDAI, DOG, 20),      # human -> dog, 30 fps
])
def test_retarget_writes_target_rig_at_source_timing(
        source: str, target: str, num_frames: int, build_tiny_module: Callable,
        read_real: Callable[[str], Motion], embed: Callable, tmp_path: Path,
        assert_same_hierarchy: Callable) -> None:
    module = build_tiny_module("vae")
    src, tgt = read_real(source).slice(0, num_frames), read_real(target)
    assert src.num_frames == num_frames
    out = retarget_motion(module, src, tgt, embed, window=16, overlap=4)
    path = tmp_path / "out.bvh"
    write_bvh(out, path)
    back = read_bvh(path)
    assert_same_hierarchy(back.skeleton, tgt.skeleton, atol=1e-4)
    assert back.num_frames == src.num_frames
    assert back.fps == pytest.approx(src.fps, rel=1e-4)
    assert np.isfinite(back.rotations).all() and np.isfinite(back.translations).all()
    positions = back.global_positions()
    assert np.isfinite(positions).all()
    # The motion stays in the target's units: its size matches the rig's.
    height = np.ptp(tgt.skeleton.rest_positions(), axis=0).max()
    assert np.ptp(positions[0], axis=0).max() < 3 * height


def test_reconstruct_keeps_skeleton_and_timing(build_tiny_module: Callable,
                                               read_real: Callable[[str], Motion],
                                               embed: Callable,
                                               assert_same_hierarchy: Callable) -> None:
    module = build_tiny_module("vae")
    src = read_real(HUMAN).slice(0, 64)
    out = reconstruct_motion(module, src, embed, window=16, overlap=4)
    assert_same_hierarchy(out.skeleton, src.skeleton, atol=1e-4)
    assert out.num_frames == src.num_frames and out.fps == src.fps


def test_first_frame_rest_is_undone_on_the_target_rig(build_tiny_module: Callable,
                                                      read_real: Callable[[str], Motion],
                                                      embed: Callable,
                                                      assert_same_hierarchy: Callable) -> None:
    """``rest="first-frame"`` shows the model both rigs re-rested on their
    first frame (Bandai's rest is a line) and writes the target's own rest
    back: same hierarchy and offsets, other model input than ``"file"``
    (and what ``"auto"`` does for these two rigs)."""
    from satagraph.pipelines.inference import shown_rest
    module = build_tiny_module("vae")
    src, tgt = read_real(BANDAI), read_real(DOG).slice(0, 10)
    canon = canonicalize(tgt, fps=30)
    shown, undo = shown_rest(canon, "first-frame")
    assert not np.allclose(shown.skeleton.offsets, canon.skeleton.offsets)
    from satagraph.transforms.augment import set_rest_rotations
    back = set_rest_rotations(shown, undo)
    np.testing.assert_allclose(back.skeleton.offsets, canon.skeleton.offsets, atol=1e-9)
    np.testing.assert_allclose(back.rotations, canon.rotations, atol=1e-9)
    assert shown_rest(canon.with_(rotations=canon.rotations[:0],
                                   translations=canon.translations[:0]), "first-frame")[1] is None
    plain = retarget_motion(module, src, tgt, embed, window=16, overlap=4, rest="file")
    rested = retarget_motion(module, src, tgt, embed, window=16, overlap=4, rest="first-frame")
    assert_same_hierarchy(rested.skeleton, tgt.skeleton, atol=1e-6)
    assert rested.num_frames == src.num_frames
    assert np.isfinite(rested.global_positions()).all()
    assert np.abs(rested.global_positions() - plain.global_positions()).max() > 1e-3
    # the first frame becomes the rest pose: every joint but the root unturned there
    np.testing.assert_allclose(shown.rotations[0, 1:], np.broadcast_to(np.eye(3), (
        canon.skeleton.num_joints - 1, 3, 3)), atol=1e-9)
    with pytest.raises(ValueError, match="rest must be one of"):
        retarget_motion(module, src, tgt, embed, rest="tpose")


def test_auto_rest_re_rests_on_the_mean_standing_pose(
        read_real: Callable[[str], Motion]) -> None:
    """``rest="auto"`` re-rests a line rest on the mean pose of the frames
    in which the body stands (root within 5 % of the greatest height it
    holds above its hind legs), not on a first frame that lies: this dog clip starts
    on the floor and gets up after about 3 s. In the new rest every joint
    but the root averages to no turn over those frames; the first standing
    frame itself is a pose of its own."""
    from satagraph.ops.rotation_numpy import mean_rotation_numpy
    from satagraph.pipelines.inference import (STANDING_SHARE, shown_rest, standing_frame,
                                               standing_frames)
    from satagraph.transforms.ground import support_joints
    canon = canonicalize(read_real("dog/D1_006_KAN01_002.bvh"), fps=30)
    pos = canon.global_positions()
    hind = support_joints(canon.skeleton, pos)
    names = {canon.skeleton.names[j] for j in hind}
    assert names >= {"LeftFoot", "RightFoot"} and not any("Hand" in n for n in names)
    stance = pos[:, 0, 1] - pos[:, hind, 1].min(axis=1)
    k, frames = standing_frame(canon), standing_frames(canon)
    assert stance[0] < 0.5 * stance.max()  # lying
    assert k > 30 and stance[k] >= STANDING_SHARE * stance.max()
    assert (stance[:k] < STANDING_SHARE * stance.max()).all() and frames[0] == k
    assert (stance[frames] >= STANDING_SHARE ** 2 * stance.max()).all()
    shown, undo = shown_rest(canon, "auto")
    eye = np.broadcast_to(np.eye(3), (canon.skeleton.num_joints - 1, 3, 3))
    np.testing.assert_allclose(mean_rotation_numpy(shown.rotations[frames, 1:]), eye, atol=1e-9)
    assert not np.allclose(shown.rotations[k, 1:], eye, atol=1e-3)
    assert not np.allclose(shown.rotations[0, 1:], eye, atol=1e-3)
    np.testing.assert_allclose(shown.global_positions(), pos, atol=1e-6)
    first, _ = shown_rest(canon, "first-frame")
    np.testing.assert_allclose(first.rotations[0, 1:], eye, atol=1e-9)


def test_a_jump_landing_is_not_the_standing_pose(read_real: Callable[[str], Motion]) -> None:
    """This dog jumps a hurdle: landing on its front paws, hind legs up, its
    hips stood highest above the lowest joint, so those three frames were
    its standing pose, and every retarget onto it did a handstand. Its
    standing frames are where its hind paws are on the floor."""
    from satagraph.pipelines.inference import standing_frames
    canon = canonicalize(read_real("dog/D1_ex04_KAN02_003.bvh"), fps=30)
    pos = canon.global_positions()
    frames = standing_frames(canon)
    names = canon.skeleton.names
    hind = [names.index(n) for n in ("LeftFoot_end", "RightFoot_end")]
    front = [names.index(n) for n in ("LeftHand_end", "RightHand_end")]
    above = pos[frames][..., 1] - pos[frames][..., 1].min(axis=1, keepdims=True)
    height = np.median(np.ptp(pos[..., 1], axis=1))
    assert len(frames) > 50
    assert np.median(above[:, hind]) < 0.1 * height
    assert np.median(above[:, front]) < 0.1 * height
    old = pos[:, 0, 1] - pos[:, :, 1].min(axis=1)
    landing = old >= 0.95 * old.max()
    assert np.median((pos[landing][..., 1] - pos[landing][..., 1].min(axis=1, keepdims=True))
                     [:, hind]) > 0.8 * height


def test_the_second_rest_is_the_pose_auto_does_not_choose(
        read_real: Callable[[str], Motion]) -> None:
    """``"alternate"`` shows a line rest (Bandai) on its first frame and a
    designed rest (a zoo biped's T pose) on its mean standing pose, where
    ``"auto"`` does the reverse; every rest keeps the global positions,
    and :func:`second_rest` pairs the modes."""
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    from satagraph.pipelines.inference import shown_rest
    from satagraph.transforms.rest import REST_MODES, second_rest
    line = canonicalize(read_real(BANDAI).slice(0, 20), fps=30)
    rig = next(r for r in zoo_rigs(seed=0) if r.species == "biped")
    designed = canonicalize(generate_clip(rig, "walk", frames=20, seed=0))
    for motion, alternate, auto in ((line, "first-frame", "standing"),
                                    (designed, "standing", "file")):
        for mode, same in (("alternate", alternate), ("auto", auto)):
            shown, undo = shown_rest(motion, mode)
            expect, _ = shown_rest(motion, same)
            np.testing.assert_allclose(shown.rotations, expect.rotations, atol=1e-12)
            assert (undo is None) == (same == "file")
            np.testing.assert_allclose(shown.global_positions(), motion.global_positions(),
                                       atol=1e-6)
    assert shown_rest(designed, "standing")[1] is not None
    assert {m: second_rest(m) for m in REST_MODES} == {
        "auto": "alternate", "alternate": "auto", "file": "standing",
        "first-frame": "standing", "standing": "first-frame"}


def test_auto_rest_of_a_dog_that_starts_on_its_side_faces_forward(
        read_real: Callable[[str], Motion]) -> None:
    """This dog lies on its side for 8 s (its root tilted 99 degrees from
    where it stands): re-rested on its standing frame by the root's heading
    change, its rest faced backwards and the built-in model walked it
    tail first (Bandai -> dog steps -0.53); turned by its left/right pairs,
    the rest faces +Z as the canonical frame 0 does, and a retarget onto
    it walks head first."""
    from satagraph.experiment.train import load_module
    from satagraph.pipelines.inference import retarget_canonical, shown_rest, standing_frame
    from satagraph.pipelines.quality import most_active
    from satagraph.transforms.canonical import body_forward
    from satagraph.transforms.rig_reading import with_rig
    dog = with_rig(read_real("dog/D1_031_KAN01_001.bvh"), scale="cm")
    canon = canonicalize(dog, fps=30)
    assert standing_frame(canon) > 200
    shown, _ = shown_rest(canon, "auto")
    names = canon.skeleton.names
    facing = body_forward(shown.skeleton.rest_positions(), shown.skeleton,
                          np.array([0.0, 1.0, 0.0]))
    assert facing[2] / np.linalg.norm(facing) > 0.99
    module = load_module("builtin").eval()
    walk = most_active(read_real("bandai/dataset-1_walk_sad_001.bvh"), 90)
    _, out = retarget_canonical(module, walk, dog, module.embed)
    pos = out.global_positions()
    head = pos[1:, names.index("Head"), [0, 2]] - pos[1:, 0, [0, 2]]
    step = np.diff(pos[:, 0, [0, 2]], axis=0)
    cos = (head * step).sum(-1) / (np.linalg.norm(head, axis=-1) * np.linalg.norm(step, axis=-1))
    assert np.median(cos) > 0.5


def test_the_source_facing_axis_of_a_dog_that_starts_on_its_side(
        read_real: Callable[[str], Motion]) -> None:
    """The features' facing axis is the root-local axis that points to +Z
    at frame 0; for this dog, lying on its side there, that axis points
    nearly straight up once it stands (75-85 degrees out of the
    horizontal), so its facing frames turned with every sway.
    ``standing_facing_axis`` takes the body's facing where it stands
    instead (within a few degrees of the horizontal) and leaves a walk
    whose root stays upright to the features' rule; ``turn_world`` turns a
    motion about the origin without changing it."""
    from satagraph.pipelines.inference import (shown_rest, standing_facing_axis,
                                               standing_frame, turn_world)
    from satagraph.ops.rotation_numpy import yaw_matrix_numpy
    from satagraph.transforms.rig_reading import with_rig
    lying = canonicalize(with_rig(read_real("dog/D1_031_KAN01_001.bvh"), scale="cm"), fps=30)
    rested, _ = shown_rest(lying, "auto")
    axis = standing_facing_axis(rested)
    k = standing_frame(rested)
    stands = rested.rotations[k:k + 60, 0]

    def elevation(direction: np.ndarray) -> np.ndarray:
        return np.degrees(np.arcsin(np.abs(stands @ direction)[:, 1]))

    assert np.median(elevation(axis)) < 10.0
    assert np.median(elevation(rested.rotations[0, 0].T @ [0.0, 0.0, 1.0])) > 60.0
    walk = canonicalize(read_real("bandai/dataset-1_walk_sad_001.bvh"), fps=30)
    assert standing_facing_axis(shown_rest(walk, "auto")[0]) is None
    turn = yaw_matrix_numpy(np.radians(70.0))
    turned = turn_world(walk, turn)
    np.testing.assert_allclose(turned.global_positions(), walk.global_positions() @ turn.T,
                               atol=1e-9)


def test_is_line_rest_finds_the_exporters_that_bake_joint_orients(
        read_real: Callable[[str], Motion]) -> None:
    """Bandai (right side on -X) and the dog lay every bone on their
    joint's X axis; the CMU rig and the zoo's other rest poses are poses."""
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    from satagraph.datasets.zoo.dialects import change_rest_pose
    from satagraph.pipelines.inference import is_line_rest
    assert is_line_rest(canonicalize(read_real(BANDAI), fps=30).skeleton)
    assert is_line_rest(canonicalize(read_real(DOG), fps=30).skeleton)
    assert not is_line_rest(canonicalize(read_real(HUMAN), fps=30).skeleton)
    walk = generate_clip(zoo_rigs(seed=0)[0], "walk", frames=4)
    assert is_line_rest(change_rest_pose(walk, "axis").skeleton)
    assert not any(is_line_rest(change_rest_pose(walk, r, seed=1).skeleton)
                   for r in ("native", "apose", "flat", "crouched", "random", "frame"))


@pytest.mark.parametrize("turn,line", [((2, 90.0), True), ((2, -90.0), True),
                                       ((1, -90.0), True), ((1, 90.0), True),
                                       ((0, 0.0), True)])
def test_is_line_rest_finds_every_bone_pointing_one_way(turn, line: bool) -> None:
    """The axis rest turned so that every bone points up (+Y, as
    Reallusion's CC rigs export it), down, forward or back is a line as
    well; the zoo walk's own rest, whose spine points up and legs down, is
    not, nor is a snake or a long tail lying forward (at most three
    quarters of the bone length one way on the zoo's rigs)."""
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    from satagraph.ops.rotation_numpy import axis_angle_matrix_numpy
    from satagraph.pipelines.inference import is_line_rest
    from satagraph.transforms.augment import axis_rest_rotations, set_rest_rotations
    walk = generate_clip(zoo_rigs(seed=0)[0], "walk", frames=4)
    axis, degrees = turn
    rest = axis_angle_matrix_numpy(np.radians(degrees), "XYZ"[axis]) @ axis_rest_rotations(
        walk.skeleton)
    turned = set_rest_rotations(walk, rest)
    np.testing.assert_allclose(turned.global_positions(), walk.global_positions(), atol=1e-9)
    assert is_line_rest(turned.skeleton) is line
    assert not is_line_rest(walk.skeleton)


def test_retarget_onto_a_rig_whose_bones_all_point_up(read_real: Callable[[str], Motion]
                                                      ) -> None:
    """Reallusion's CC_Base rig (ccbase) rests with every bone up, legs
    included. Read as the file has it, the built-in model walked a human
    onto it with one leg pointing up (posture -0.59 from a CMU walk: each
    joint's height above the root against the rig's own clip); ``rest="auto"`` re-rests it
    on its mean standing pose and the retarget carries it as its own clip
    does, in step. Read as the file has it but carried as its character
    (``carriage="auto"``, the default: the leg up never lands), it walks
    as the rig's own clip stands too."""
    from satagraph.experiment.train import load_module
    from satagraph.pipelines.inference import is_line_rest, retarget_canonical
    from satagraph.pipelines.quality import most_active, posture, retarget_quality
    target = read_real("ccbase/007_07.bvh")
    assert is_line_rest(canonicalize(target, fps=30).skeleton)
    module = load_module("builtin").eval()
    walk = most_active(read_real("cmu/01_01.bvh"), 240)
    own = canonicalize(target, fps=30)
    src, out = retarget_canonical(module, walk, target, module.embed)
    quality = retarget_quality(src, out, ("steps", "posture"), target=own)
    assert quality["posture"] > 0.95 and quality["steps"] > 0.7
    _, read_as_is = retarget_canonical(module, walk, target, module.embed, rest="file",
                                       carriage="never")
    assert posture(read_as_is, own) < 0.6
    _, carried = retarget_canonical(module, walk, target, module.embed, rest="file")
    assert posture(carried, own) > 0.95


def test_auto_rest_re_rests_captured_poses_but_not_designed_rests(
        read_real: Callable[[str], Motion]) -> None:
    """``rest="auto"`` re-rests a rig whose rest is a line or a captured
    pose (left and right bent differently), not a designed rest: the real
    rigs' and the zoo's T, A, crouched and flat rests bend both sides alike
    (under 1.1 degrees), an arbitrary or captured rest does not."""
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    from satagraph.datasets.zoo.dialects import change_rest_pose
    from satagraph.pipelines.inference import (POSED_REST_DEGREES, needs_rest,
                                               rest_asymmetry, shown_rest)
    for path in (HUMAN, BANDAI, DOG):
        skel = canonicalize(read_real(path), fps=30).skeleton
        assert rest_asymmetry(skel) < 1.1
    assert not needs_rest(canonicalize(read_real(HUMAN), fps=30).skeleton)
    assert needs_rest(canonicalize(read_real(BANDAI), fps=30).skeleton)  # a line
    walk = generate_clip(zoo_rigs(seed=0)[0], "walk", frames=30)
    for rest in ("native", "apose", "flat", "crouched"):
        assert rest_asymmetry(change_rest_pose(walk, rest, seed=1).skeleton) < 0.5, rest
        assert not needs_rest(change_rest_pose(walk, rest, seed=1).skeleton), rest
    posed = change_rest_pose(walk, "random", seed=1)
    assert rest_asymmetry(posed.skeleton) > POSED_REST_DEGREES and needs_rest(posed.skeleton)
    canon = canonicalize(posed, fps=30)
    shown, undo = shown_rest(canon, "auto")
    assert undo is not None
    np.testing.assert_allclose(shown.global_positions(), canon.global_positions(), atol=1e-6)
    # rotating the whole rest pose changes nothing (no up axis or facing needed)
    from satagraph.skeleton import Skeleton
    turn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    skel = posed.skeleton
    turned = Skeleton(skel.names, skel.parents, skel.offsets @ turn.T)
    assert rest_asymmetry(turned) == pytest.approx(rest_asymmetry(skel), abs=1e-9)


def test_a_line_rest_without_frames_is_no_body_to_retarget_onto(
        read_real: Callable[[str], Motion]) -> None:
    """Bandai's rig without its frames read lying along -Z (confidence
    0.02), and a retarget onto it sank 34 cm under the floor: its rest, a
    line along X, has no up axis to read; it reads as +Y, the convention,
    at confidence 0, and a retarget onto it is refused in one line."""
    from satagraph.data.validate import MotionValidationError
    from satagraph.pipelines.inference import check_shown_body
    from satagraph.transforms.rig_reading import guess_up_axis
    bandai = read_real("bandai/dataset-1_walk_normal_001.bvh")
    rig = bandai.slice(0, 0)
    guess = guess_up_axis(rig)
    assert (guess.axis, guess.confidence) == ("+Y", 0.0)
    with pytest.raises(MotionValidationError, match=r"^\S*dataset-1_walk_normal_001.bvh: a rig "
                                                    "without frames whose rest pose is a line"):
        check_shown_body(rig)
    check_shown_body(bandai)
    check_shown_body(read_real("cmu/01_01.bvh").slice(0, 0))  # a designed rest: a body


def test_a_line_rest_shown_only_at_rest_is_no_body_to_retarget_onto(
        read_real: Callable[[str], Motion]) -> None:
    """The dog's rig exported in one frame at its rest (every rotation the
    identity): a Bandai walk onto it walked on its hind legs (steps +0.45)
    and, carried as that frame, lay flat (+0.06); it shows no more body
    than the rig without frames and is refused alike. A frame of the
    dog's clip, or a designed rest at rest, is a body."""
    from satagraph.data.validate import MotionValidationError
    from satagraph.pipelines.inference import check_shown_body
    dog = read_real("dog/D1_001_KAN01_001.bvh").slice(0, 1)
    at_rest = dog.with_(rotations=np.broadcast_to(np.eye(3), dog.rotations.shape).copy())
    with pytest.raises(MotionValidationError, match=r"^\S*D1_001_KAN01_001.bvh: a rig shown "
                                                    "only at rest whose rest pose is a line"):
        check_shown_body(at_rest)
    check_shown_body(dog)
    cmu = read_real("cmu/01_01.bvh").slice(0, 1)
    check_shown_body(cmu.with_(rotations=np.broadcast_to(np.eye(3), cmu.rotations.shape).copy()))
