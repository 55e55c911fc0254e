"""Baselines: SAME and the zero-padding RVQ-VAE (shapes, gradients,
invariances, padding mask, sizes) and their LightningModules."""
from __future__ import annotations

from dataclasses import replace

import lightning as L
import pytest
import torch
from torch.utils.data import DataLoader

from satagraph.experiment.config import load_config
from satagraph.data import collate_clips
from satagraph.data.examples import example_motion
from satagraph.pipelines.inference import reconstruct_motion
from satagraph.lightning.baselines import PaddedRVQModule, SAMEModule
from satagraph.losses import MotionLoss
from satagraph.nn.autoencoders.padded import (PaddedRVQ, from_padded, latent_mask, padding_mask,
                                              to_padded)
from satagraph.nn.autoencoders.same import SAME
from satagraph.experiment.train import build_module, load_module, module_class
from test_sata_modules import (assert_finite_grads, count, make_clips, output_sum,
                               per_clip)

MIXED = [(8, 4), (5, 7), (8, 4), (6, 7)]  # two skeletons, several lengths
TINY_SAME = dict(hidden_channels=16, heads=2, latent_channels=8)
TINY_PADDED = dict(max_joints=9, hidden_channels=16, latent_channels=8, depth=1,
                   num_quantizers=2, codebook_size=8, quantize_dropout=0.0)


@pytest.fixture
def clips():
    return make_clips(MIXED)


@pytest.fixture
def batch(clips):
    return collate_clips(clips)


def check_shapes(out, batch) -> None:
    assert out["q"].shape == (batch.num_nodes, 6)
    assert out["r"].shape == (batch.root.shape[0], 4)
    assert out["c"].shape == (batch.num_nodes, 1)


# ------------------------------------------------------------------- SAME
@pytest.mark.parametrize("conv", ["gat", "gatv2"])
@pytest.mark.parametrize("latent_every_layer", [True, False])
def test_same_shapes_and_gradients(conv, latent_every_layer, batch):
    model = SAME(conv=conv, latent_every_layer=latent_every_layer, **TINY_SAME)
    out = model(batch)
    check_shapes(out, batch)
    assert out["z"].shape == (batch.root.shape[0], 8)
    assert not {"kl", "commit"} & set(out)
    output_sum(out).backward()
    assert_finite_grads(model)


def test_same_losses_backward(batch):
    model = SAME(**TINY_SAME)
    MotionLoss()(model(batch), batch)["loss"].backward()
    assert_finite_grads(model)


def test_same_decodes_on_another_skeleton():
    source = collate_clips(make_clips([(5, 4), (3, 7)]))
    target = collate_clips(make_clips([(5, 9), (3, 3)], seed=10))
    model = SAME(**TINY_SAME).eval()
    out = model(source, target)
    check_shapes(out, target)
    with pytest.raises(ValueError, match="latents"):
        model.decode(out["z"][:-1], target)


def test_same_clip_order_invariance(clips):
    model = SAME(**TINY_SAME).eval()
    order = [2, 3, 0, 1]
    permuted = [clips[i] for i in order]
    with torch.no_grad():
        out, out_p = model(collate_clips(clips)), model(collate_clips(permuted))
    for new, old in enumerate(order):
        a, b = per_clip(out, clips, old), per_clip(out_p, permuted, new)
        for key in a:
            torch.testing.assert_close(a[key], b[key], atol=1e-5, rtol=1e-5)


def test_same_is_per_frame(clips):
    """No temporal layers: a frame's latent and output depend on it only."""
    model = SAME(**TINY_SAME).eval()
    clip = clips[0]
    short = replace(clip, dynamic=clip.dynamic[2:5], root=clip.root[2:5])
    with torch.no_grad():
        out = model(collate_clips([clip]))
        out_s = model(collate_clips([short]))
    joints = clip.num_joints
    torch.testing.assert_close(out["z"][2:5], out_s["z"])
    torch.testing.assert_close(out["q"][2 * joints:5 * joints], out_s["q"])


def test_same_wide_parameter_count():
    cfg = load_config("same_wide")
    module = module_class(cfg["module"])(model=cfg["model"])
    assert isinstance(module, SAMEModule)
    assert abs(count(module.model) - 5.98e6) / 5.98e6 < 0.05, count(module.model)
    own = count(SAME())  # SAME's own width: about 0.3 M
    assert 0.25e6 < own < 0.35e6, own


def test_unknown_conv():
    with pytest.raises(ValueError, match="unknown SAME conv"):
        SAME(conv="gcn")


# -------------------------------------------------------------- padded
def test_padding_round_trip(batch):
    x = torch.randn(batch.num_nodes, 7)
    root = torch.randn(batch.root.shape[0], 4)
    dense = to_padded(x, root, batch, max_joints=9)
    assert dense.shape == (4, 8, 4 + 9 * 7)
    out = from_padded(dense, batch, max_joints=9)
    torch.testing.assert_close(out["q"], x[:, :6])
    torch.testing.assert_close(out["c"], x[:, 6:])
    torch.testing.assert_close(out["r"], root)
    mask = padding_mask(batch, 9)
    assert mask.shape == (4, 8, 9) and int(mask.sum()) == batch.num_nodes
    assert not mask[:, :, 7:].any()  # no skeleton has more than 7 joints
    assert not mask[1, 5:].any()  # clip 1 has 5 frames
    joints = dense[..., 4:].view(4, 8, 9, 7)
    assert (joints[~mask] == 0).all()  # padding is zeros


def test_padded_shapes_and_gradients(batch):
    model = PaddedRVQ(**TINY_PADDED).train()
    out = model(batch)
    check_shapes(out, batch)
    steps = sum((t + 3) // 4 for t, _ in MIXED)
    assert out["z"].shape == (steps, 8) and out["codes"].shape == (steps, 2)
    assert out["mask"].shape == (4, 8, 9)
    output_sum(out).backward()
    assert_finite_grads(model)


def test_padded_joints_excluded_from_loss(batch):
    """Losses see real nodes only: zero gradient on every padded slot."""
    model = PaddedRVQ(**TINY_PADDED).eval()
    with torch.no_grad():
        model.train()(batch)  # k-means init
    model.eval()
    z = model.encode(batch)["z"]
    dense = model.decode_dense(z, batch).detach().requires_grad_(True)
    out = from_padded(dense, batch, model.max_joints)
    MotionLoss()(out, batch)["loss"].backward()
    grad = dense.grad[..., 4:].reshape(4, 8, 9, 7).abs().sum(-1)
    mask = padding_mask(batch, 9)
    assert (grad[~mask] == 0).all()
    assert (grad[mask] > 0).any()
    assert (dense.grad[..., :4].abs().sum(-1)[mask.any(-1)] > 0).any()


def test_padded_rejects_too_many_joints(batch):
    model = PaddedRVQ(**dict(TINY_PADDED, max_joints=5))
    with pytest.raises(ValueError, match="max_joints"):
        model(batch)


def test_padded_latent_mask(batch):
    mask = latent_mask(batch, 4)
    assert mask.tolist() == [[True, True], [True, True], [True, True], [True, True]]
    short = collate_clips(make_clips([(9, 4), (3, 4)]))
    assert latent_mask(short, 4).tolist() == [[True, True, True], [True, False, False]]


def test_padded_clip_order_invariance(clips):
    model = PaddedRVQ(**TINY_PADDED).train()
    model(collate_clips(clips))
    model.eval()
    order = [3, 1, 2, 0]
    permuted = [clips[i] for i in order]
    with torch.no_grad():
        out, out_p = model(collate_clips(clips)), model(collate_clips(permuted))
    for new, old in enumerate(order):
        a, b = per_clip(out, clips, old), per_clip(out_p, permuted, new)
        for key in ("q", "c", "r"):
            torch.testing.assert_close(a[key], b[key], atol=1e-5, rtol=1e-5)


# ---------------------------------------------------------- lightning
def test_registered_modules():
    assert module_class("same") is SAMEModule
    assert module_class("padded_rvq") is PaddedRVQModule
    assert load_config("padded_rvq")["module"] == "padded_rvq"


def tiny_config(name: str, **model) -> dict:
    overrides = [f"model.{k}={v}" for k, v in model.items()]
    return load_config(name, overrides + ["optim.lr=1e-3", "optim.warmup_epochs=1"])


@pytest.mark.parametrize("name,model", [
    ("same", dict(hidden_channels=16, heads=2, latent_channels=8)),
    ("padded_rvq", dict(max_joints=10, hidden_channels=16, latent_channels=8, depth=1,
                        num_quantizers=2, codebook_size=8)),
])
def test_two_training_steps(name, model, tmp_path):
    cfg = tiny_config(name, **model)
    module = build_module(cfg)
    loader = DataLoader(make_clips([(8, 4), (8, 7), (6, 5), (8, 4)]), batch_size=2,
                        collate_fn=collate_clips)
    trainer = L.Trainer(max_steps=2, accelerator="cpu", devices=1, logger=False,
                        enable_checkpointing=False, enable_progress_bar=False,
                        enable_model_summary=False, limit_val_batches=1,
                        num_sanity_val_steps=0, default_root_dir=str(tmp_path))
    before = [p.detach().clone() for p in module.model.parameters()]
    trainer.fit(module, train_dataloaders=loader, val_dataloaders=loader)
    assert trainer.global_step == 2
    assert torch.isfinite(trainer.callback_metrics["train_loss"])
    after = list(module.model.parameters())
    assert any(not torch.equal(a, b) for a, b in zip(before, after))
    trainer.save_checkpoint(tmp_path / "last.ckpt")
    loaded = load_module(str(tmp_path / "last.ckpt"))
    assert type(loaded) is type(module)
    motion = example_motion(num_frames=20)
    out = reconstruct_motion(loaded, motion, window=16, overlap=4)
    assert out.num_frames == motion.num_frames and out.num_joints == motion.num_joints


def test_latent_rate_is_part_of_the_contract(batch):
    """SATA and SAME give one latent per frame graph; the padded model one
    per latent_rate frames of each clip, and a module refuses the
    cross-skeleton term (which decodes per-frame latents onto other
    skeletons' frames) instead of failing inside a step."""
    from satagraph.nn import SATA, MotionAutoencoder
    padded = PaddedRVQ(**TINY_PADDED)
    assert isinstance(padded, MotionAutoencoder) and padded.latent_rate == 4
    steps = sum(-(-t // padded.latent_rate) for t, _ in MIXED)
    assert padded.encode(batch)["z"].shape[0] == steps
    for model in (SAME(hidden_channels=16, latent_channels=8),
                  SATA(hidden_channels=16, heads=2, ff_channels=16, num_blocks=1,
                       latent_channels=8)):
        assert model.latent_rate == 1
        assert model.encode(batch)["z"].shape[0] == batch.root.shape[0]
    with pytest.raises(ValueError, match="one latent per frame"):
        PaddedRVQModule(model=TINY_PADDED, loss={"retarget": 0.1})
