"""The skeleton-agnostic kinematic descriptor (issue 19, item 8)."""
from __future__ import annotations

import numpy as np
import pytest

from satagraph.data.features import motion_to_features
from satagraph.datasets.zoo.endless import EndlessZoo
from satagraph.motion import Motion
from satagraph.pipelines.motion_descriptor import (DESCRIPTOR_DIM, canonical_features,
                                                   channel_index, contact_quality,
                                                   describe_motion,
                                                   froude_speed, leg_length)


def zoo_clip(kind: str, plan: str = "biped", frames: int = 61) -> Motion:
    """The first zoo training clip of a kind and body plan."""
    zoo = EndlessZoo([plan], fps=30.0, seed=0)
    for idx in range(200):
        sample = zoo.sample(0, idx, frames, "train", False)
        if sample.kind == kind:
            return sample.motion
    raise AssertionError(f"no {kind} clip")


def describe(motion: Motion) -> np.ndarray:
    return describe_motion(motion, up_axis="+Y", unit_scale=1.0)


@pytest.fixture(scope="module")
def walk() -> Motion:
    return zoo_clip("walk")


def test_shape_and_forward_walk(walk):
    desc = describe(walk)
    assert desc.shape == (DESCRIPTOR_DIM,) and np.isfinite(desc).all()
    assert desc[channel_index("forward")] > 0.3  # leg lengths per second
    assert desc[-4:].tolist() == [1.0, 1.0, 1.0, 1.0]


def test_backward_walk_has_opposite_forward_speed(walk):
    back = walk.with_(rotations=walk.rotations[::-1].copy(),
                      translations=walk.translations[::-1].copy())
    fwd, bwd = describe(walk), describe(back)
    i = channel_index("forward")
    assert bwd[i] < 0 < fwd[i]
    assert bwd[i] == pytest.approx(-fwd[i], rel=0.1)


def test_scaling_the_skeleton_leaves_it_unchanged(walk):
    big = walk.with_(skeleton=walk.skeleton.replace(offsets=walk.skeleton.offsets * 3.0),
                     translations=walk.translations * 3.0)
    np.testing.assert_allclose(describe(big), describe(walk), atol=1e-6)


def test_standing_clip_has_about_zero_speed():
    idle = describe(zoo_clip("idle", "quadruped"))
    assert abs(idle[channel_index("forward")]) < 0.05
    assert abs(idle[channel_index("yaw_rate")]) < 0.1


def test_froude_speed_orders_idle_below_walk(walk):
    idle = zoo_clip("idle")
    assert froude_speed(canonical_features(idle, up_axis="+Y", unit_scale=1.0)) < \
        froude_speed(canonical_features(walk, up_axis="+Y", unit_scale=1.0))


def test_leg_length_falls_back_to_height(walk):
    assert leg_length(walk.skeleton, [-1, -1, -1, -1], height=1.7) == 1.7
    assert 0.2 < leg_length(walk.skeleton) / walk.height() < 0.8


def test_contact_quality_sees_sliding_feet(walk):
    feats = canonical_features(walk, up_axis="+Y", unit_scale=1.0)
    slide, hover = contact_quality(feats)
    assert slide >= 0.0 and 0.0 <= hover < 0.02  # a walk keeps its feet on the floor
    skate = walk.with_(translations=walk.translations + np.arange(walk.num_frames)[:, None,
                                                                                     None]
                       * np.array([0.0, 0.0, 0.05]))
    faster, _ = contact_quality(canonical_features(skate, up_axis="+Y", unit_scale=1.0))
    assert faster > slide + 0.1


def test_contact_quality_sees_a_body_bob_off_the_floor_wherever_the_floor_is(walk):
    """Hovering: the mean lowest joint above the floor, in heights; it
    reads a body lifted in two frames of three (two thirds of the lift),
    and not a whole clip moved."""
    feats = canonical_features(walk, up_axis="+Y", unit_scale=1.0)
    _, hover = contact_quality(feats)
    height = walk.height()
    bob = walk.translations.copy()
    bob[np.arange(walk.num_frames) % 3 > 0, 0, 1] += 0.1 * height  # 2 frames in 3 lifted
    _, bobbing = contact_quality(canonical_features(walk.with_(translations=bob),
                                                    up_axis="+Y", unit_scale=1.0))
    assert bobbing - hover == pytest.approx(0.1 * 2 / 3, abs=0.01)  # in heights
    up = walk.translations.copy()
    up[:, 0, 1] += 0.3 * height  # the whole clip a third of the height up
    lifted = motion_to_features(walk.with_(translations=up))
    np.testing.assert_allclose(contact_quality(lifted)[1],
                               contact_quality(motion_to_features(walk))[1], atol=1e-6)
