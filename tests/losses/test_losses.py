"""Motion losses: zero at the target, gradients, geometry against the
features and the metrics' global motion, weights."""
from __future__ import annotations

import pytest
import roma
import torch

from satagraph.data import collate_clips
from satagraph.data.clip import MotionClip
from satagraph.data.examples import example_motion
from satagraph.data.features import motion_to_features
from satagraph.data.normalizer import FeatureNormalizer
from satagraph.losses import (DEFAULT_WEIGHTS, MotionLoss, amplitude_loss, facing_positions,
                              limb_end_streams,
                              foot_sliding_loss, penetration_loss, rotation_loss,
                              smoothness_loss, stance_loss, time_difference, to_global,
                              velocity_loss)
from satagraph.ops.motion_batch import batch_global_motion
from satagraph.ops.rotation import matrix_to_rotation_6d

FPS = 30.0
ZERO_AT_TARGET = ("rotation", "position", "global_position", "velocity", "root", "contact",
                  "smoothness", "stance", "amplitude")


def walk_clip(frames: int = 20, start: int = 0) -> MotionClip:
    feats = motion_to_features(example_motion(40, fps=FPS))
    return feats.to_clip(start, start + frames, meta={"name": "walk"})


def random_clip(frames: int, joints: int, seed: int) -> MotionClip:
    gen = torch.Generator().manual_seed(seed)
    parents = torch.tensor([-1] + [int(torch.randint(0, j, (1,), generator=gen))
                                   for j in range(1, joints)])
    dyn = torch.randn(frames, joints, 22, generator=gen)
    dyn[..., :6] = matrix_to_rotation_6d(roma.rotvec_to_rotmat(
        0.5 * torch.randn(frames, joints, 3, generator=gen)))
    dyn[..., 21] = (torch.rand(frames, joints, generator=gen) > 0.5).float()
    root = torch.randn(frames, 4, generator=gen)
    root[:, 3] = 1.0 + 0.1 * root[:, 3]
    return MotionClip(dynamic=dyn, root=root, static=0.2 * torch.randn(joints, 6, generator=gen),
                      semantic=torch.zeros(joints, 0), parents=parents,
                      edge_attr=torch.ones(2 * (joints - 1), 2), meta={"height": 1.5})


@pytest.fixture
def batch():
    return collate_clips([walk_clip(20), random_clip(6, 5, 1), walk_clip(12, 7)])


def perfect(batch, logit: float = 40.0):
    """Predictions equal to the batch's targets (contacts as sharp logits)."""
    c = batch.x[:, 21:22]
    return {"q": batch.x[:, :6].clone(), "r": batch.root.clone(), "c": (2 * c - 1) * logit}


def noisy(batch, seed: int = 0):
    gen = torch.Generator().manual_seed(seed)
    out = perfect(batch, logit=1.0)
    for key in out:
        out[key] = (out[key] + 0.1 * torch.randn(out[key].shape, generator=gen)
                    ).requires_grad_(True)
    return out


# ---------------------------------------------------------------- geometry
def test_facing_positions_match_features():
    batch = collate_clips([walk_clip(20), walk_clip(10, 5)])
    pos = facing_positions(batch.x[:, :6], batch.root, batch)
    torch.testing.assert_close(pos, batch.x[:, 6:9], atol=1e-4, rtol=0)


def test_global_positions_match_batch_global_motion(batch):
    pos = to_global(facing_positions(batch.x[:, :6], batch.root, batch), batch.root, batch, FPS)
    _, _, ref = batch_global_motion(batch.x[:, :6], batch.root, batch, FPS)
    torch.testing.assert_close(pos, ref, atol=1e-4, rtol=1e-4)


def test_time_difference_within_clips(batch):
    value = batch.node_time.float()[:, None] ** 2
    diff, valid = time_difference(value, batch, order=2)
    assert torch.allclose(diff[valid], torch.full_like(diff[valid], 2.0))
    assert torch.equal(valid, batch.node_time >= 2)


# ------------------------------------------------------------------ terms
def test_zero_at_target(batch):
    terms = MotionLoss()(perfect(batch), batch, fps=FPS)
    for name in ZERO_AT_TARGET:
        assert terms[name].item() == pytest.approx(0.0, abs=1e-8), name


def test_root_loss_uses_normalised_r_with_normalizer(batch):
    norm = FeatureNormalizer()
    norm.set_stats({"root": (torch.ones(4), 2 * torch.ones(4))})
    out = perfect(batch)
    out["r_norm"] = norm.normalize(batch.root, "root", batch.heights("frame"))
    crit = MotionLoss()
    assert crit(out, batch, norm, fps=FPS)["root"].item() == pytest.approx(0.0, abs=1e-10)
    out["r_norm"] = out["r_norm"] + 1.0
    assert crit(out, batch, norm, fps=FPS)["root"].item() == pytest.approx(1.0)


def test_all_terms_have_finite_gradients(batch):
    out = noisy(batch)
    out["kl"] = torch.tensor(0.5, requires_grad=True)
    terms = MotionLoss()(out, batch, fps=FPS)
    for name, value in terms.items():
        assert value.ndim == 0 and torch.isfinite(value), name
    terms["loss"].backward()
    for key in ("q", "r", "c"):
        assert out[key].grad is not None and torch.isfinite(out[key].grad).all()
        assert out[key].grad.abs().sum() > 0
    for name in ZERO_AT_TARGET + ("foot_sliding", "penetration"):
        q = out["q"].detach().requires_grad_(True)
        r = out["r"].detach().requires_grad_(True)
        value = MotionLoss()(dict(out, q=q, r=r), batch, fps=FPS)[name]
        if value.requires_grad:
            (gq, gr) = torch.autograd.grad(value, (q, r), allow_unused=True)
            assert all(g is None or torch.isfinite(g).all() for g in (gq, gr)), name


def test_global_position_sees_the_drift_of_a_biased_yaw_rate(batch):
    """A yaw rate off by a constant leaves every facing-frame position
    right (``position`` 0) but turns the integrated path away from the
    target's: ``global_position`` grows with the bias."""
    crit = MotionLoss()
    values = []
    for bias in (0.1, 0.3):
        out = perfect(batch)
        out["r"][:, 0] += bias
        terms = crit(out, batch, fps=FPS)
        assert terms["position"].item() == pytest.approx(0.0, abs=1e-6)
        values.append(terms["global_position"].item())
    assert 0.0 < values[0] < values[1]


def test_rotation_loss_ignores_leaves(batch):
    q = batch.x[:, :6].clone()
    leaves = torch.ones(batch.num_nodes, dtype=torch.bool)
    leaves[batch.node_parent[batch.node_parent >= 0]] = False
    q[leaves] = torch.tensor([0.0, 1.0, 0.0, -1.0, 0.0, 0.0])
    assert rotation_loss(q, batch.x[:, :6], batch).item() == pytest.approx(0.0, abs=1e-10)
    q[~leaves] = torch.tensor([0.0, 1.0, 0.0, -1.0, 0.0, 0.0])
    assert rotation_loss(q, batch.x[:, :6], batch).item() > 0


def test_velocity_loss_ignores_constant_offset(batch):
    pos = torch.randn(batch.num_nodes, 3)
    assert velocity_loss(pos + 3.0, pos, batch).item() == pytest.approx(0.0, abs=1e-10)
    assert velocity_loss(pos * 2.0, pos, batch).item() > 0


def test_penetration():
    pos = torch.tensor([[0.0, 1.0, 0.0], [0.0, -0.5, 0.0], [1.0, 0.0, 0.0]])
    assert penetration_loss(pos).item() == pytest.approx(0.25 / 3)
    assert penetration_loss(pos.abs()).item() == 0.0


def test_foot_sliding(batch):
    still = torch.zeros(batch.num_nodes, 3)
    contact = torch.ones(batch.num_nodes, 1)
    assert foot_sliding_loss(still, contact, batch).item() == 0.0
    sliding = batch.node_time.float()[:, None] * torch.tensor([[0.3, 5.0, 0.4]])
    value = foot_sliding_loss(sliding, contact, batch).item()
    assert value == pytest.approx(0.5)  # horizontal only, mean over moving frames
    assert foot_sliding_loss(sliding, 0 * contact, batch).item() == 0.0


def test_stance_is_the_stride_of_joints_in_contact(batch):
    """Zero at the target; a constant offset of the facing-frame positions
    costs nothing (no root in it); a contact joint whose stride is off by
    (0.3, _, 0.4) per frame costs 0.25, vertical motion and joints out of
    contact nothing."""
    true = torch.randn(batch.num_nodes, 3, generator=torch.Generator().manual_seed(0))
    contact = torch.ones(batch.num_nodes, 1)
    assert stance_loss(true, true, contact, batch).item() == 0.0
    assert stance_loss(true + 2.0, true, contact, batch).item() == pytest.approx(0.0, abs=1e-10)
    off = true + batch.node_time.float()[:, None] * torch.tensor([[0.3, 5.0, 0.4]])
    assert stance_loss(off, true, contact, batch).item() == pytest.approx(0.25)
    assert stance_loss(off, true, 0 * contact, batch).item() == 0.0
    half = (torch.arange(batch.num_nodes) % 2).float()[:, None]
    assert 0 < stance_loss(off, true, half, batch).item() < 0.25


def test_amplitude_scores_the_swing_not_the_phase(batch):
    """Zero at the target, for a constant offset and for the motion played
    mirrored about each joint's mean (same swing, every frame wrong); a
    swing of half the size costs a quarter of the true spreads' mean
    squared norm, and its gradient widens the swing."""
    true = torch.randn(batch.num_nodes, 3, generator=torch.Generator().manual_seed(0))
    assert amplitude_loss(true, true, batch).item() == 0.0
    assert amplitude_loss(true + 2.0, true, batch).item() == pytest.approx(0.0, abs=1e-6)
    mean = torch.zeros(batch.num_streams, 3).index_reduce_(
        0, batch.node_stream, true, "mean", include_self=False)[batch.node_stream]
    assert amplitude_loss(2 * mean - true, true, batch).item() == pytest.approx(0.0, abs=1e-6)
    spread = true.new_zeros(batch.num_streams, 3).index_reduce_(
        0, batch.node_stream, (true - mean).pow(2), "mean", include_self=False)
    half = (mean + 0.5 * (true - mean)).requires_grad_(True)
    loss = amplitude_loss(half, true, batch)
    assert loss.item() == pytest.approx(0.25 * spread.sum(-1).mean().item(), rel=1e-4)
    loss.backward()
    wider = (half - 0.1 * half.grad).detach()
    assert amplitude_loss(wider, true, batch) < loss


def test_limb_amplitude_sees_the_limb_ends_alone(batch):
    """`limb_end_streams` are each clip's limb-end joints as streams; a
    swing shrunk on other joints costs the limb term nothing, on a limb end
    it costs both terms."""
    batch.clip_limb_ends = torch.tensor([[2, 4, -1, -1], [1, -1, -1, -1], [3, 0, -1, -1]])
    first = [0] + batch.clip_num_joints.cumsum(0).tolist()[:-1]
    streams = limb_end_streams(batch)
    assert streams.tolist() == [2, 4, first[1] + 1, first[2] + 3, first[2]]
    true = torch.randn(batch.num_nodes, 3, generator=torch.Generator().manual_seed(1))
    other = torch.ones(batch.num_streams, dtype=torch.bool)
    other[streams] = False
    for shrunk, limb_cost in ((other, False), (~other, True)):
        pred = true.clone()
        pred[shrunk[batch.node_stream]] *= 0.5
        assert amplitude_loss(pred, true, batch).item() > 0
        assert (amplitude_loss(pred, true, batch, streams).item() > 0) == limb_cost


def test_smoothness(batch):
    line = batch.node_time.float()[:, None].expand(-1, 3)  # constant velocity
    assert smoothness_loss(line, batch).item() == pytest.approx(0.0, abs=1e-10)
    curve = line ** 2
    assert smoothness_loss(curve, batch).item() == pytest.approx(12.0)  # |(2,2,2)|^2
    assert smoothness_loss(curve, batch, curve).item() == 0.0
    assert smoothness_loss(curve, batch, order=3).item() == pytest.approx(0.0, abs=1e-8)


def test_positions_scale_with_character_height(batch):
    out = noisy(batch)
    crit = MotionLoss()
    base = crit(out, batch, fps=FPS)["position"].item()
    batch.clip_height = 2 * batch.clip_height  # the batch owns its clips' heights
    # lengths are measured in character heights: twice as tall, a quarter the MSE
    assert crit(out, batch, fps=FPS)["position"].item() == pytest.approx(base / 4, rel=1e-4)


# ---------------------------------------------------------------- weights
def test_weights_and_total(batch):
    out = noisy(batch)
    out["commit"] = torch.tensor(0.3)
    crit = MotionLoss(weights={"rotation": 2.0}, contact=0.0, commit=1.0)
    terms = crit(out, batch, fps=FPS)
    assert crit.weights["rotation"] == 2.0 and crit.weights["contact"] == 0.0
    expected = sum(crit.weights[k] * v for k, v in terms.items() if k != "loss")
    torch.testing.assert_close(terms["loss"], expected)
    assert "commit" in terms and "kl" not in terms


def test_defaults_and_unknown_weight():
    assert set(MotionLoss().weights) == set(DEFAULT_WEIGHTS)
    with pytest.raises(ValueError, match="unknown terms"):
        MotionLoss(jerkk=1.0)
