"""Feet held on the floor through their stances: chains, stances, locks,
the root lowered onto them, FABRIK, and a gliding leg planted."""
from __future__ import annotations

import numpy as np
import pytest

from satagraph.io import read_bvh
from satagraph.motion import Motion
from satagraph.ops.rotation_numpy import rotation_about_numpy
from satagraph.semantics import helper_joints, hip_bones, limb_ends
from satagraph.skeleton import Skeleton
from satagraph.transforms.foot_plant import (BLEND_FRAMES, limb_chain, plant_feet, planted_track,
                                             reach, stance_drop, stance_frames)

FPS = 30.0
# root (hips), spine, hip, knee, foot, toe: the hip's parent branches
PARENTS = np.array([-1, 0, 0, 2, 3, 4])
OFFSETS = np.array([[0, 0, 0], [0, 0.6, 0], [0.1, 0, 0], [0, -0.45, 0], [0, -0.45, 0],
                    [0, -0.03, 0.1]], dtype=float)


def gliding_leg(frames: int = 20, root_speed: float = 0.6, back_speed: float = 0.3,
                bob: float = 0.0, bob_frames: int = 11) -> Motion:
    """The root travels +Z at :obj:`root_speed` while the straight leg swings
    back at only :obj:`back_speed` (its foot glides forward at the
    difference, close to the floor); the root rises :obj:`bob` and falls
    back in a raised-cosine bump over the middle :obj:`bob_frames` frames."""
    skeleton = Skeleton(names=["Hips", "Spine", "LeftUpLeg", "LeftLeg", "LeftFoot",
                               "LeftToe"], parents=PARENTS, offsets=OFFSETS)
    t = (np.arange(frames) - (frames - 1) / 2) / FPS
    rotations = np.broadcast_to(np.eye(3), (frames, 6, 3, 3)).copy()
    rotations[:, 2] = rotation_about_numpy(np.array([1.0, 0, 0]), np.arcsin(back_speed * t / 0.9))
    translations = np.broadcast_to(OFFSETS, (frames, 6, 3)).copy()
    translations[:, 0] = np.stack([np.zeros(frames), np.full(frames, 0.95),
                                   root_speed * (t - t[0])], -1)
    start = (frames - bob_frames) // 2
    bump = 0.5 - 0.5 * np.cos(2 * np.pi * np.arange(1, bob_frames + 1) / (bob_frames + 1))
    translations[start:start + bob_frames, 0, 1] += bob * bump
    return Motion(skeleton, rotations, translations, fps=FPS)


def test_limb_chain_stops_below_a_branching_joint_and_at_max_bones():
    assert limb_chain(PARENTS, 4) == [2, 3, 4]  # the hips branch: the hip is the top
    assert limb_chain(PARENTS, 5) == [2, 3, 4, 5]
    assert limb_chain(PARENTS, 5, max_bones=2) == [3, 4, 5]
    assert limb_chain(PARENTS, 1) == [1]  # the root's child: no bone to bend


# CMU's leg: root (hips), spine, hip bone, hip, knee, foot, toe, and a twist
# bone riding on the shin (CC_Base and Unreal rigs carry such helpers)
HELPED = ["Hips", "Spine", "LHipJoint", "LeftUpLeg", "LeftLeg", "LeftFoot", "LeftToeBase",
          "LeftLegTwist"]
HELPED_PARENTS = np.array([-1, 0, 0, 2, 3, 4, 5, 4])
HELPED_OFFSETS = np.array([[0, 0, 0], [0, 0.6, 0], [0, 0, 0], [0.1, -0.05, 0], [0, -0.45, 0],
                           [0, -0.45, 0], [0, -0.03, 0.1], [0, -0.2, 0]], dtype=float)


def helped_gliding_leg(frames: int = 20) -> Motion:
    """:func:`gliding_leg`'s glide on :data:`HELPED`: the hip (joint 3)
    swings back slower than the root travels, so the foot glides."""
    skeleton = Skeleton(names=HELPED, parents=HELPED_PARENTS, offsets=HELPED_OFFSETS)
    t = (np.arange(frames) - (frames - 1) / 2) / FPS
    rotations = np.broadcast_to(np.eye(3), (frames, 8, 3, 3)).copy()
    rotations[:, 3] = rotation_about_numpy(np.array([1.0, 0, 0]), np.arcsin(0.3 * t / 0.9))
    translations = np.broadcast_to(HELPED_OFFSETS, (frames, 8, 3)).copy()
    translations[:, 0] = np.stack([np.zeros(frames), np.full(frames, 0.95),
                                   0.6 * (t - t[0])], -1)
    return Motion(skeleton, rotations, translations, fps=FPS)


def test_limb_chain_skips_helpers_and_stops_below_a_hip_bone():
    helpers, rigid = np.arange(8) == 7, np.arange(8) == 2
    assert limb_chain(HELPED_PARENTS, 5) == [5]  # the knee's two children: nothing to bend
    assert limb_chain(HELPED_PARENTS, 5, helpers=helpers) == [2, 3, 4, 5]
    assert limb_chain(HELPED_PARENTS, 5, helpers=helpers, rigid=rigid) == [3, 4, 5]


def test_a_foot_above_a_twist_bone_is_held_and_the_hip_socket_stays_on_the_pelvis():
    """The semantics read the twist bone as a helper and the hip bone as
    fused to the pelvis: the gliding foot is held (before helpers were
    skipped it was left gliding), only the hip and knee turn, and the hip
    socket keeps its place relative to the root."""
    motion = helped_gliding_leg()
    before = motion.global_positions()
    planted = plant_feet(motion, ends=[5])
    after = planted.global_positions()
    glide = np.ptp(before[:, 5, 2])
    assert glide > 0.09
    assert np.ptp(after[BLEND_FRAMES:-BLEND_FRAMES, 5, 2]) < 0.02 * glide
    np.testing.assert_allclose(after[:, 3] - after[:, 0], before[:, 3] - before[:, 0], atol=1e-12)
    np.testing.assert_allclose(planted.rotations[:, 2], motion.rotations[:, 2])
    assert not np.allclose(planted.rotations[:, 3], motion.rotations[:, 3])
    for a, b in ((3, 4), (4, 5), (4, 7)):  # bones kept, the twist bone rides on the shin
        np.testing.assert_allclose(np.linalg.norm(after[:, b] - after[:, a], axis=-1),
                                   np.linalg.norm(HELPED_OFFSETS[b]), atol=1e-9)


@pytest.mark.parametrize("rel, leg", [
    ("ccbase/006_01.bvh", ["CC_Base_L_Thigh", "CC_Base_L_Calf", "CC_Base_L_Foot"]),
    ("cmu/01_01.bvh", ["LeftUpLeg", "LeftLeg", "LeftFoot"])])
def test_the_legs_of_real_rigs_bend_at_hip_and_knee(shared_data, rel: str, leg: list) -> None:
    """CC_Base's calf carries a twist and a knee share bone, CMU's thigh
    hangs from a hip bone: on both the planted chain is thigh, shin, foot."""
    skeleton = read_bvh(shared_data / rel).skeleton
    helpers, rigid = helper_joints(skeleton), hip_bones(skeleton)
    chain = limb_chain(skeleton.parents, limb_ends(skeleton)["left hind"], helpers=helpers,
                       rigid=rigid)
    assert [skeleton.names[j] for j in chain] == leg
    assert helpers.any() == rel.startswith("ccbase")
    assert all("Twist" in n or "Share" in n for n in np.array(skeleton.names)[helpers])
    assert [n for n in np.array(skeleton.names)[rigid]] == (
        ["LHipJoint", "RHipJoint"] if rel.startswith("cmu") else [])


def test_stance_is_low_and_slow_relative_to_the_body():
    frames = 30
    root = np.stack([np.zeros(frames), np.ones(frames), np.linspace(0, 1, frames)], -1)
    track = root.copy()
    track[:, 1] = 0.0
    track[10:20, 2] = track[10, 2]  # stands still for 10 frames
    lowest = np.where(np.arange(frames) < 25, 0.0, 0.5)  # lifted from frame 25
    stance = stance_frames(track, lowest, root, FPS, height=1.7)
    assert stance[11:19].all() and not stance[25:].any()
    # a stand slow on two frames only (central differences) is too short to count
    short = np.zeros(frames, dtype=bool)
    track2 = root.copy()
    track2[:, 1] = 0.0
    track2[:, 2] += np.arange(frames) * 0.1  # otherwise fast
    track2[5:9, 2] = track2[5, 2]
    assert (stance_frames(track2, np.zeros(frames), root, FPS, 1.7) == short).all()


def test_planted_track_holds_the_mean_and_fades():
    frames = 30
    track = np.stack([np.linspace(0, 1, frames), np.full(frames, 0.02),
                      np.linspace(0, 2, frames)], -1)
    stance = np.zeros(frames, dtype=bool)
    stance[10:20] = True
    out = planted_track(track, stance)
    mean = track[10:20][:, [0, 2]].mean(axis=0)
    np.testing.assert_allclose(out[10:20][:, [0, 2]], np.broadcast_to(mean, (10, 2)))
    np.testing.assert_allclose(out[:, 1], track[:, 1])  # the height as decoded
    far = np.r_[:10 - BLEND_FRAMES, 20 + BLEND_FRAMES:frames]
    np.testing.assert_allclose(out[far], track[far])
    half = 10 - (BLEND_FRAMES + 1) // 2  # halfway through the fade in
    assert 0.0 < np.linalg.norm(out[half] - track[half]) < np.linalg.norm(mean - track[half][[0, 2]])


def test_planted_track_glides_between_close_stances():
    """Two stances closer than two fades: the target jumped 64 % of the way
    from one stance's position to the next in one frame, where one fade
    gave way to the other (a pop on every quick step of a generated walk);
    it glides now, and each stance still holds its own mean."""
    frames = 30
    track = np.stack([np.linspace(0, 3, frames), np.zeros(frames), np.zeros(frames)], -1)
    stance = np.zeros(frames, dtype=bool)
    stance[5:11] = stance[15:21] = True
    out = planted_track(track, stance)[:, 0]
    first, second = track[5:11, 0].mean(), track[15:21, 0].mean()
    np.testing.assert_allclose(out[5:11], first)
    np.testing.assert_allclose(out[15:21], second)
    even = (second - first) / (15 - 10)  # the distance spread over the frames between
    assert np.abs(np.diff(out)).max() < 1.6 * even  # before: 3.2 times
    assert np.abs(np.diff(out, 2)).max() < even  # before: 2.6 times


def test_reach_keeps_bones_and_base_and_reaches():
    gen = np.random.default_rng(0)
    chain = np.cumsum(gen.normal(size=(5, 4, 3)) * 0.3, axis=1)
    lengths = np.linalg.norm(np.diff(chain, axis=1), axis=-1)
    near = chain[:, 0] + 0.5 * (chain[:, -1] - chain[:, 0])  # inside reach
    out = reach(chain, near, iterations=30)
    np.testing.assert_allclose(np.linalg.norm(np.diff(out, axis=1), axis=-1), lengths, atol=1e-9)
    np.testing.assert_allclose(out[:, 0], chain[:, 0])
    np.testing.assert_allclose(out[:, -1], near, atol=1e-3)
    far = chain[:, 0] + np.array([10.0, 0, 0])  # out of reach: stretched towards it
    out = reach(chain, far)
    np.testing.assert_allclose(np.linalg.norm(out[:, -1] - out[:, 0], axis=-1), lengths.sum(-1),
                               atol=1e-6)


def test_a_gliding_foot_is_held_and_the_rest_kept():
    motion = gliding_leg()
    before = motion.global_positions()
    planted = plant_feet(motion, ends=[4])
    after = planted.global_positions()
    glide = np.ptp(before[:, 4, 2])
    assert glide > 0.09  # the foot glides 0.1 m
    middle = slice(BLEND_FRAMES, -BLEND_FRAMES)
    assert np.ptp(after[middle, 4, 2]) < 0.02 * glide  # held
    np.testing.assert_allclose(after[:, 4, 0], 0.1, atol=1e-9)  # in its plane
    # the root's path and the spine kept, but for the root lowered onto the foot
    np.testing.assert_allclose(planted.translations[:, 0, [0, 2]], motion.translations[:, 0, [0, 2]])
    np.testing.assert_allclose(planted.translations[:, 1:], motion.translations[:, 1:])
    np.testing.assert_allclose(after[:, 1] - after[:, 0], before[:, 1] - before[:, 0], atol=1e-12)
    floor = np.median(before[..., 1].min(axis=1))
    assert (after[..., 1].min(axis=1) > floor - 1e-9).all()  # nothing below the floor
    # the leg bends, its bones do not stretch
    for a, b in ((2, 3), (3, 4), (4, 5)):
        np.testing.assert_allclose(np.linalg.norm(after[:, b] - after[:, a], axis=-1),
                                   np.linalg.norm(OFFSETS[b]), atol=1e-9)
    # the toe keeps its pose relative to the foot's parent bone
    np.testing.assert_allclose(planted.rotations[:, 4], motion.rotations[:, 4])


def test_a_standing_foot_and_a_swinging_limb_stay_as_they_are():
    fast = gliding_leg(root_speed=3.0, back_speed=-0.3)  # the foot swings faster than the body
    planted = plant_feet(fast, ends=[4])
    np.testing.assert_allclose(planted.rotations, fast.rotations)
    np.testing.assert_allclose(planted.translations, fast.translations)
    still = gliding_leg(root_speed=0.0, back_speed=0.0)
    np.testing.assert_allclose(plant_feet(still, ends=[4]).global_positions(),
                               still.global_positions(), atol=1e-9)


def test_a_body_bobbing_above_its_standing_foot_is_lowered_onto_it():
    bobbing = gliding_leg(root_speed=0.0, back_speed=0.0, bob=0.04)
    before = bobbing.global_positions()[..., 1].min(axis=1)
    planted = plant_feet(bobbing, ends=[4])
    after = planted.global_positions()[..., 1].min(axis=1)
    floor = np.median(before)
    assert (before - floor).max() > 0.035
    assert (after - floor).mean() < 0.25 * (before - floor).mean()
    assert (after > floor - 1e-9).all()
    np.testing.assert_allclose(planted.translations[:, 0, [0, 2]], bobbing.translations[:, 0, [0, 2]])


def test_a_hop_is_not_stood_on():
    """Feet that leave the floor fast (a hop of 4 cm in a few frames) are
    in the air, not standing low: the root is not lowered onto them and the
    hop keeps its height, where a slow bob of the same height is lowered."""
    hop = gliding_leg(root_speed=0.0, back_speed=0.0, bob=0.04, bob_frames=5)
    bob = gliding_leg(root_speed=0.0, back_speed=0.0, bob=0.04, bob_frames=11)
    rise = {}
    for name, motion in (("hop", hop), ("bob", bob)):
        low = plant_feet(motion, ends=[4]).global_positions()[..., 1].min(axis=1)
        rise[name] = low.max() - np.median(low)
    assert rise["hop"] > 0.039 and rise["bob"] < 0.01


def test_stance_drop_carries_between_stances_and_is_zero_without_any():
    gaps = np.full(12, np.nan)
    gaps[[2, 9]] = [0.1, 0.4]
    drop = stance_drop(gaps, frames=1)
    np.testing.assert_allclose(drop[:3], 0.1)
    np.testing.assert_allclose(drop[9:], 0.4)
    np.testing.assert_allclose(drop[2:10], np.linspace(0.1, 0.4, 8))
    np.testing.assert_allclose(stance_drop(np.full(5, np.nan)), 0.0)
    smoothed = stance_drop(np.r_[np.zeros(6), np.ones(6)], frames=5)
    assert smoothed.shape == (12,) and 0 < smoothed[5] < 1 and smoothed[0] == 0 and smoothed[-1] == 1
