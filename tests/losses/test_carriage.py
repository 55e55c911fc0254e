r"""The carriage term of cross-skeleton retargeting
(:func:`~satagraph.losses.carriage_loss`) on a hand-made batch whose answer
is worked out in the comments.

The partners' own batch holds two clips (nodes frame-major, node = t * J + j
within a clip, clip A first):

- A: a 3-joint chain, 2 frames, height 2;
- B: a 2-joint chain, 3 frames, height 1.

Each clip is decoded onto the other's rig with its own length: the target
batch holds B's rig for 2 frames (partner 1) and A's rig for 3 frames
(partner 0).
"""
from __future__ import annotations

import pytest
import torch

from satagraph.data.collate import collate_clips
from satagraph.losses import carriage_loss, carried_heights
from tests.metrics.test_metrics import _clip

A, B = [-1, 0, 1], [-1, 0]
PARTNERS = torch.tensor([1, 0])


def _positions(heights) -> torch.Tensor:
    """Positions (N, 3) whose y are :obj:`heights` (a list of frames of
    joints, clip after clip) and x, z a fixed pattern."""
    y = torch.tensor([h for clip in heights for frame in clip for h in frame],
                     dtype=torch.float64)
    side = torch.arange(y.numel(), dtype=torch.float64) * 0.1
    return torch.stack([side, y, -side], 1)


@pytest.fixture
def batches():
    partner = collate_clips([_clip(A, 2, 2.0), _clip(B, 3, 1.0)])
    target = collate_clips([_clip(B, 2, 1.0), _clip(A, 3, 2.0)])
    return partner, target


#: The partners' own clips: A's root at 1, its joint 1 at 1.4 and 1.6 (mean
#: 0.5 above the root, 0.25 heights), joint 2 at 0 (-1, -0.5 heights); B's
#: root at 0.5 and 0.3 (it bobs), its joint 1 0.2 above it (0.2 heights).
PARTNER = [[[1.0, 1.4, 0.0], [1.0, 1.6, 0.0]],
           [[0.5, 0.7], [0.3, 0.5], [0.5, 0.7]]]


def test_carried_heights_are_means_above_the_root_in_heights(batches):
    partner, _ = batches
    carried = carried_heights(_positions(PARTNER), partner)
    assert torch.allclose(carried, torch.tensor([0.0, 0.25, -0.5, 0.0, 0.2],
                                                dtype=torch.float64))


def test_carriage_loss_value_by_hand(batches):
    partner, target = batches
    # on B's rig (height 1): joint 1 0.5 above a root at 3 (partner: 0.2),
    # gaps 0, 0.3 -> mean square 0.045; on A's rig (height 2): joint 1 at
    # 0.25 heights (as A), joint 2 1.6 below the root (-0.8 heights, A: -0.5),
    # gaps 0, 0, 0.3 -> 0.03; the pairs' mean 0.0375
    decoded = [[[3.0, 3.5], [3.0, 3.5]],
               [[2.0, 2.5, 0.4], [2.0, 2.5, 0.4], [2.0, 2.5, 0.4]]]
    loss = carriage_loss(_positions(decoded), _positions(PARTNER).float(), target, partner,
                         PARTNERS)
    assert loss.dtype == torch.float64
    assert loss.item() == pytest.approx(0.0375, abs=1e-7)  # the partner in float32


def test_carriage_loss_is_zero_for_the_partners_carriage_at_any_root_height(batches):
    partner, target = batches
    # B's carriage (joint 1 0.2 above the root) and A's (0.5 and -1 above it)
    # over other frames and root heights: only the mean height above the root counts
    decoded = [[[0.9, 1.0], [0.7, 1.0]],
               [[1.0, 1.5, 0.0], [1.3, 1.7, 0.2], [0.7, 1.3, -0.2]]]
    loss = carriage_loss(_positions(decoded), _positions(PARTNER), target, partner, PARTNERS)
    assert loss.item() == pytest.approx(0.0, abs=1e-12)


def test_carriage_loss_sends_gradients_to_the_decoded_positions(batches):
    partner, target = batches
    decoded = _positions([[[3.0, 3.5], [3.0, 3.5]],
                          [[2.0, 2.5, 0.4], [2.0, 2.5, 0.4], [2.0, 2.5, 0.4]]])
    decoded.requires_grad_(True)
    carriage_loss(decoded, _positions(PARTNER), target, partner, PARTNERS).backward()
    grad = decoded.grad
    assert grad[:, [0, 2]].abs().sum() == 0  # heights only
    # B's joint 1 too high: pushed down, its root up; A's joint 2 too low: up
    assert (grad[[1, 3], 1] > 0).all() and (grad[[0, 2], 1] < 0).all()
    assert (grad[[6, 9, 12], 1] < 0).all() and (grad[[5, 8, 11], 1] == 0).all()
