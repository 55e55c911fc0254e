r"""Value tests of every metric of :mod:`satagraph.metrics.motion` on a hand-made
batch whose answers are worked out by hand in the comments.

The batch holds two clips (nodes are frame-major: node = t * J + j within a
clip, clip A first):

- A: a 3-joint chain 0 -> 1 -> 2, 2 frames, height 2 (6 nodes, 0-5);
- B: a 2-joint chain 0 -> 1, 3 frames, height 1 (6 nodes, 6-11).
"""
from __future__ import annotations

import math

import pytest
import torch

from satagraph.data.clip import MotionClip
from satagraph.data.collate import collate_clips
from satagraph.metrics.motion import (SLIDE_HEIGHT, foot_sliding, ground_penetration,
                                      joint_position_error, joint_rotation_error,
                                      motion_metrics, root_trajectory_error, retarget_error)

HEIGHTS = (2.0, 1.0)
#: float32 rounding of the rotations' products: equal rotations are 0 rad
#: apart (they read 4.9e-4 when the angle was the arc cosine of a clamped trace).
ANGLE_ATOL = 1e-6


def _clip(parents, frames: int, height: float) -> MotionClip:
    joints = len(parents)
    return MotionClip(
        dynamic=torch.zeros(frames, joints, 1), root=torch.zeros(frames, 4),
        static=torch.zeros(joints, 6), semantic=torch.zeros(joints, 0),
        parents=torch.tensor(parents), edge_attr=torch.zeros(2 * (joints - 1), 2),
        meta={"height": height})


@pytest.fixture
def batch():
    return collate_clips([_clip([-1, 0, 1], 2, HEIGHTS[0]),
                          _clip([-1, 0], 3, HEIGHTS[1])])


def node(clip: str, t: int, j: int) -> int:
    """Index of joint j at frame t of clip A or B."""
    return t * 3 + j if clip == "A" else 6 + t * 2 + j


def rot_y(angle: float) -> torch.Tensor:
    c, s = math.cos(angle), math.sin(angle)
    return torch.tensor([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]],
                        dtype=torch.float64)


def test_node_layout(batch):
    assert batch.num_nodes == 12
    assert batch.node_time.tolist() == [0, 0, 0, 1, 1, 1, 0, 0, 1, 1, 2, 2]
    assert batch.root_node.tolist() == [node("A", 0, 0), node("A", 1, 0),
                                        node("B", 0, 0), node("B", 1, 0), node("B", 2, 0)]


def test_joint_rotation_error(batch):
    true = torch.eye(3, dtype=torch.float64).repeat(12, 1, 1)
    pred = true.clone()
    pred[node("A", 0, 1)] = rot_y(math.pi / 2)  # inner joint: counts
    pred[node("A", 1, 2)] = rot_y(math.pi)  # leaf: ignored
    for t in range(3):
        pred[node("B", t, 0)] = rot_y(0.3)  # B's only inner joint, every frame
        pred[node("B", t, 1)] = rot_y(2.0)  # leaf: ignored
    # A: inner joints 0 and 1 over 2 frames: (pi/2) / 4 = pi/8
    # B: inner joint 0 over 3 frames: 3 * 0.3 / 3 = 0.3
    got = joint_rotation_error(pred, true, batch)
    torch.testing.assert_close(got, torch.tensor([math.pi / 8, 0.3], dtype=got.dtype),
                               rtol=0, atol=ANGLE_ATOL)


def test_joint_rotation_error_of_clips_with_few_inner_joints():
    # a lone root (no inner joint: 0, not 0 / 0) and a 2-joint chain of one
    # frame (one inner node: its angle itself)
    batch = collate_clips([_clip([-1], 2, 1.0), _clip([-1, 0], 1, 1.0)])
    true = torch.eye(3, dtype=torch.float64).repeat(4, 1, 1)
    pred = true.clone()
    pred[0] = pred[1] = rot_y(1.0)  # the lone root's two frames: leaves, ignored
    pred[2] = rot_y(0.3)  # the chain's root
    got = joint_rotation_error(pred, true, batch)
    torch.testing.assert_close(got, torch.tensor([0.0, 0.3], dtype=got.dtype),
                               rtol=0, atol=ANGLE_ATOL)


def _positions():
    """True positions (anything) and predictions off by hand-picked steps."""
    true = torch.arange(36, dtype=torch.float).reshape(12, 3)
    pred = true.clone()
    pred[node("A", 0, 0)] += torch.tensor([0.0, 5.0, 0.0])  # vertical only
    pred[node("A", 1, 0)] += torch.tensor([3.0, 0.0, 4.0])  # horizontal 5
    for t in range(3):
        pred[node("B", t, 0)] += torch.tensor([1.0, 0.0, 0.0])
    return pred, true


def test_root_trajectory_error(batch):
    pred, true = _positions()
    # A: root xz errors 0 (the 5 is vertical) and 5 -> 2.5; B: 1 every frame
    torch.testing.assert_close(root_trajectory_error(pred, true, batch),
                               torch.tensor([2.5, 1.0]))


def test_joint_position_error(batch):
    pred, true = _positions()
    # A: distances 5 and 5 over 6 nodes -> 5/3; B: 1 on 3 of 6 nodes -> 0.5
    torch.testing.assert_close(joint_position_error(pred, true, batch),
                               torch.tensor([5 / 3, 0.5]))


def test_retarget_error(batch):
    pred, true = _positions()
    # A: 1000 * (25 + 25) / 6 / 2^2 = 2083.33; B: 1000 * 3 / 6 / 1^2 = 500
    torch.testing.assert_close(retarget_error(pred, true, batch),
                               torch.tensor([50 / 24 * 1000, 500.0]))


def _contact_positions():
    """A: joint 2 at height h0 * log2(1.5) (weight 2 - 1.5 = 0.5) moves
    (0.3, 0, 0.4) from frame 0 to 1, the rest stands still. B: joint 0 on
    the ground 0.2 below it (weight 1) slides 0.1 along x per frame; joint
    1 is high (weight 0) and moves fast."""
    pos = torch.zeros(12, 3)
    h0_a = SLIDE_HEIGHT * HEIGHTS[0]
    pos[node("A", 0, 2)] = torch.tensor([0.0, h0_a * math.log2(1.5), 0.0])
    pos[node("A", 1, 2)] = torch.tensor([0.3, h0_a * math.log2(1.5), 0.4])
    for t in range(3):
        pos[node("B", t, 0)] = torch.tensor([0.1 * t, -0.2, 0.0])
        pos[node("B", t, 1)] = torch.tensor([10.0 * t, 1.0, 0.0])
    return pos


def test_foot_sliding(batch):
    # A: 0.5 * 0.5 over the 3 nodes of frame 1 -> 1/12
    # B: weight 2 - 2^(-0.2 / h0) clamps to 1: 0.1 + 0.1 over 4 nodes -> 0.05
    torch.testing.assert_close(foot_sliding(_contact_positions(), batch),
                               torch.tensor([1 / 12, 0.05]))


def test_foot_sliding_of_short_clips():
    # a lone root on the ground (weight 1) slides 0.3 between its two frames:
    # one moving node, so 0.3, not 0.15; a one-frame chain has no moving
    # node: 0, not 0 / 0
    batch = collate_clips([_clip([-1], 2, 1.0), _clip([-1, 0], 1, 1.0)])
    pos = torch.zeros(4, 3)
    pos[1] = torch.tensor([0.3, 0.0, 0.0])
    torch.testing.assert_close(foot_sliding(pos, batch), torch.tensor([0.3, 0.0]))


def test_ground_penetration(batch):
    # A: nothing below 0; B: -0.2 on 3 of 6 nodes -> -0.1
    torch.testing.assert_close(ground_penetration(_contact_positions(), batch),
                               torch.tensor([0.0, -0.1]))


def test_motion_metrics_heights(batch):
    pred, true = _positions()
    rot = torch.eye(3, dtype=torch.float64).repeat(12, 1, 1)
    out = motion_metrics(rot, pred, rot, true, batch)
    assert set(out) == {"JR", "RT", "RT_h", "JP", "JP_h", "FS", "GP", "RE"}
    torch.testing.assert_close(out["JR"], torch.zeros(2, dtype=torch.float64),
                               rtol=0, atol=ANGLE_ATOL)
    # divided by the heights 2 and 1
    torch.testing.assert_close(out["RT_h"], torch.tensor([1.25, 1.0]))
    torch.testing.assert_close(out["JP_h"], torch.tensor([5 / 6, 0.5]))
