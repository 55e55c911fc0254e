"""SATA LightningModules: checkpoints, optimiser schedule and logging."""
from __future__ import annotations

import copy
import warnings
from pathlib import Path
from typing import Any, Callable, Dict, List, Tuple

import lightning as L
import pytest
import torch
from torch.utils.data import DataLoader

from satagraph.data.collate import FrameBatch, collate_clips
from satagraph.lightning import SATARVQModule, SATAVAEModule, lr_factor
from satagraph.experiment.train import build_module, init_weights, load_module

METRICS = ("JR", "RT", "RT_h", "JP", "JP_h", "FS", "GP", "RE")


def _quiet_trainer(**kwargs: Any) -> L.Trainer:
    opts = dict(accelerator="cpu", devices=1, logger=False, enable_checkpointing=False,
                enable_progress_bar=False, enable_model_summary=False)
    opts.update(kwargs)
    return L.Trainer(**opts)


def _normalizer_state(module: L.LightningModule) -> Dict[str, torch.Tensor]:
    return {k: v.clone() for k, v in module.normalizer.state_dict().items()}


# -------------------------------------------------------------- normaliser
def test_a_data_module_of_ones_own_trains_and_an_unfitted_normaliser_warns(
        build_tiny_module: Callable, datamodule) -> None:
    """A LightningDataModule without a ``normalizer`` failed in the set-up
    of a module without fitted statistics (AttributeError: 'Windows' object
    has no attribute 'normalizer'); plain loaders trained such a module on
    mean 0, std 1 without a word."""
    class Windows(L.LightningDataModule):
        def train_dataloader(self) -> DataLoader:
            return datamodule._loader("train", False)

    module = build_tiny_module()
    with warnings.catch_warnings():
        warnings.filterwarnings("error", message=".*unfitted feature normaliser")
        _quiet_trainer(max_steps=1, limit_val_batches=0).fit(module, datamodule=Windows())
    module = build_tiny_module()
    module.normalizer.fitted.fill_(False)
    with pytest.warns(UserWarning, match="unfitted feature normaliser"):
        _quiet_trainer(max_steps=1, limit_val_batches=0).fit(module, datamodule=Windows())


# ---------------------------------------------------------------- checkpoints
@pytest.mark.parametrize("name,cls", [("vae", SATAVAEModule), ("rvq", SATARVQModule)])
def test_checkpoint_round_trip(name: str, cls: type, build_tiny_module: Callable,
                               datamodule, train_batch: FrameBatch,
                               tmp_path: Path) -> None:
    module = build_tiny_module(name)
    trainer = _quiet_trainer(max_steps=2, limit_val_batches=0)
    trainer.fit(module, train_dataloaders=datamodule._loader("train", False))
    path = tmp_path / "model.ckpt"
    trainer.save_checkpoint(path)

    loaded = load_module(str(path))
    assert type(loaded) is cls
    assert loaded.meta["module"] == name and loaded.fps == module.fps

    # Normaliser statistics come from the checkpoint (not the default 0/1).
    expected = _normalizer_state(module)
    assert bool(expected["fitted"]) and expected["dynamic_std"].ne(1).any()
    for key, value in _normalizer_state(loaded).items():
        torch.testing.assert_close(value, expected[key], rtol=0, atol=0, msg=key)

    module.eval(), loaded.eval()
    with torch.no_grad():
        a, b = module(train_batch), loaded(train_batch)
    assert a.keys() == b.keys()
    for key in ("q", "r", "c", "z"):
        assert torch.isfinite(a[key]).all()
        torch.testing.assert_close(b[key], a[key], rtol=0, atol=0, msg=key)


def test_init_weights_loads_network_and_keeps_normalizer(build_tiny_module: Callable,
                                                        tmp_path: Path) -> None:
    source = build_tiny_module("vae")
    with torch.no_grad():
        for param in source.parameters():
            param.add_(1.0)
        source.normalizer.dynamic_mean.add_(5.0)
    path = tmp_path / "source.ckpt"
    torch.save({"state_dict": source.state_dict()}, path)

    module = build_tiny_module("vae")
    own = _normalizer_state(module)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        init_weights(module, str(path))
    for (name, a), b in zip(module.named_parameters(), source.parameters()):
        torch.testing.assert_close(a, b, rtol=0, atol=0, msg=name)
    for key, value in _normalizer_state(module).items():
        torch.testing.assert_close(value, own[key], rtol=0, atol=0, msg=key)

    # Another bottleneck: the shared weights load, the rest is reported.
    rvq = build_tiny_module("rvq")
    with pytest.warns(UserWarning, match="not in the checkpoint"):
        init_weights(rvq, str(path))
    torch.testing.assert_close(rvq.model.encoder.state_dict(),
                               source.model.encoder.state_dict(), rtol=0, atol=0)
    # ... and the RVQ's projection is the VAE's mean half (vae_to_rvq).
    width = rvq.model.bottleneck.proj.out_features
    torch.testing.assert_close(rvq.model.bottleneck.proj.weight,
                               source.model.bottleneck.lin.weight[:width], rtol=0, atol=0)
    torch.testing.assert_close(rvq.model.bottleneck.proj.bias,
                               source.model.bottleneck.lin.bias[:width], rtol=0, atol=0)
    # Weights of another shape (another codebook size) keep their
    # initialisation, named in the warning; the others load.
    rvq_path = tmp_path / "rvq.ckpt"
    torch.save({"state_dict": rvq.state_dict()}, rvq_path)
    small = build_tiny_module("rvq", codebook_size=8)
    before = {k: v.clone() for k, v in small.state_dict().items()}
    with pytest.warns(UserWarning, match=r"[1-9]\d* of another shape"):
        init_weights(small, str(rvq_path))
    loaded = rvq.state_dict()
    reshaped = [k for k, v in small.state_dict().items() if v.shape != loaded[k].shape]
    assert reshaped and all("codebook" in k or "embed" in k or "cluster" in k for k in reshaped)
    for key, value in small.state_dict().items():
        expected = before[key] if key in reshaped else loaded[key]
        if not key.startswith("normalizer."):
            torch.testing.assert_close(value, expected, rtol=0, atol=0, msg=key)


def test_frozen_parts_keep_their_weights_codebooks_and_normaliser(
        tiny_config: Dict[str, Any], datamodule, tmp_path: Path) -> None:
    """``optim.frozen``: a decoder fine-tune under a frozen encoder and
    quantiser; the codes of a batch stay the same, the decoder moves."""
    from satagraph.experiment.train import build_module
    L.seed_everything(0, verbose=False)
    cfg = dict(tiny_config, module="rvq")
    cfg["model"] = dict(cfg["model"], codebook_size=16, num_quantizers=2)
    source = build_module(cfg, datamodule)
    batch = next(iter(datamodule._loader("train", False)))
    source.eval().codes(batch)  # codebooks initialised (k-means), as a trained RVQ's
    with torch.no_grad():
        source.normalizer.dynamic_mean.add_(0.5)
    path = tmp_path / "source.ckpt"
    torch.save({"state_dict": source.state_dict()}, path)

    cfg["optim"] = dict(cfg["optim"], frozen=["model.encoder", "model.bottleneck"], lr=1e-2)
    module = build_module(cfg, datamodule)
    init_weights(module, str(path))
    # the frozen encoder reads the data as the checkpoint's normaliser did
    for key, value in _normalizer_state(module).items():
        torch.testing.assert_close(value, _normalizer_state(source)[key], rtol=0, atol=0)
    codes = copy.deepcopy(module).eval().codes(batch)
    frozen = {k: v.clone() for k, v in module.state_dict().items()
              if k.startswith(("model.encoder.", "model.bottleneck."))}
    decoder = {k: v.clone() for k, v in module.model.decoder.state_dict().items()}
    optimizer = module.configure_optimizers()["optimizer"]
    assert sum(p.numel() for g in optimizer.param_groups for p in g["params"]) == sum(
        p.numel() for p in module.model.decoder.parameters())
    trainer = _quiet_trainer(max_steps=3, limit_val_batches=0)
    trainer.fit(module, train_dataloaders=datamodule._loader("train", False))
    assert module.train().model.decoder.training
    assert not module.model.encoder.training and not module.model.bottleneck.training
    for key, value in module.state_dict().items():
        if key in frozen:  # codebooks too: no EMA update, no dead-code reset
            torch.testing.assert_close(value, frozen[key], rtol=0, atol=0, msg=key)
    moved = [k for k, v in module.model.decoder.state_dict().items()
             if v.is_floating_point() and not torch.equal(v, decoder[k])]
    assert moved
    assert torch.equal(module.eval().codes(batch), codes)


def test_frozen_names_a_part(tiny_config: Dict[str, Any], datamodule) -> None:
    from satagraph.experiment.train import build_module
    cfg = dict(tiny_config, module="vae")
    cfg["optim"] = dict(cfg["optim"], frozen=["model.encodr"])
    with pytest.raises(ValueError, match=r"optim.frozen: 'model.encodr' is not a part of "
                                         r"SATAVAEModule; its parts: model.encoder"):
        build_module(cfg, datamodule)


# ------------------------------------------------------------------ schedule
def test_lr_factor_warmup_decay_floor() -> None:
    warm, decay, floor = 4, 0.5, 0.1
    factors = [lr_factor(e, warm, decay, floor) for e in range(11)]
    # Linear warm-up reaching 1 at the last warm-up epoch.
    assert factors[:4] == pytest.approx([0.25, 0.5, 0.75, 1.0])
    # Exponential decay after warm-up, never below the floor.
    assert factors[4:8] == pytest.approx([1.0, 0.5, 0.25, 0.125])
    assert factors[8:] == pytest.approx([floor] * 3)
    assert all(a >= b for a, b in zip(factors[3:], factors[4:]))
    assert lr_factor(1000, 30, 0.99, 0.01) == pytest.approx(0.01)
    assert lr_factor(40, 30, 0.99, 0.01) == pytest.approx(0.99 ** 10)
    # No warm-up: starts at full rate.
    assert lr_factor(0, 0, 0.9, 0.01) == pytest.approx(1.0)


def test_configure_optimizers_adam_with_schedule(build_tiny_module: Callable) -> None:
    module = build_tiny_module("vae")
    module.optim.update(lr=2e-3, warmup_epochs=3, decay=0.5, floor=0.2)
    conf = module.configure_optimizers()
    opt, sched = conf["optimizer"], conf["lr_scheduler"]["scheduler"]
    assert isinstance(opt, torch.optim.Adam)
    assert conf["lr_scheduler"]["interval"] == "epoch"
    params = {id(p) for g in opt.param_groups for p in g["params"]}
    assert params == {id(p) for p in module.parameters()}
    lrs = []
    for _ in range(8):
        lrs.append(opt.param_groups[0]["lr"])
        opt.step(), sched.step()
    expected = [2e-3 * lr_factor(e, 3, 0.5, 0.2) for e in range(8)]
    assert lrs == pytest.approx(expected)
    assert lrs[0] == pytest.approx(2e-3 / 3) and min(lrs) == pytest.approx(2e-3 * 0.2)


# ------------------------------------------------------------------- logging
def _spy_logs(module: L.LightningModule) -> List[Tuple[str, float, int]]:
    """Record ``(name, value, batch_size)`` of every ``self.log`` call."""
    calls: List[Tuple[str, float, int]] = []
    original = module.log

    def log(name: str, value: Any, *args: Any, **kwargs: Any) -> None:
        calls.append((name, float(value), kwargs.get("batch_size")))
        original(name, value, *args, **kwargs)

    module.log = log
    return calls


def _loader(datamodule, split: str, sizes: Tuple[int, ...]) -> DataLoader:
    """A loader of batches of the given numbers of clips from a split."""
    ds, start, groups = datamodule.datasets[split], 0, []
    for size in sizes:
        groups.append([ds[i] for i in range(start, start + size)])
        start += size
    return DataLoader(groups, batch_size=1, collate_fn=lambda g: collate_clips(g[0]))


def test_every_term_logged_with_number_of_clips(build_tiny_module: Callable,
                                                datamodule, train_batch) -> None:
    module = build_tiny_module("vae")
    calls = _spy_logs(module)
    trainer = _quiet_trainer(max_steps=1, limit_val_batches=0)
    trainer.fit(module, train_dataloaders=_loader(datamodule, "train", (4,)))
    terms = set(module.compute_losses(module(train_batch), train_batch))
    assert {"loss", "rotation", "position", "kl"} <= terms
    parts = terms - {"loss"}  # the total is logged once, as train_loss
    train_logged = {n: b for n, _, b in calls if n.startswith("train")}
    assert set(train_logged) == {f"train/{t}" for t in parts} | {"train_loss"}
    assert set(train_logged.values()) == {len(train_batch.meta)} == {4}
    assert {f"train/{t}_step" for t in parts} <= set(trainer.logged_metrics)

    # Validation: uneven batches (3 + 1 clips); epoch values are means
    # weighted by the number of clips of each batch.
    calls.clear()
    trainer = _quiet_trainer()
    trainer.validate(module, dataloaders=_loader(datamodule, "val", (3, 1)),
                     verbose=False)
    names = {f"val/{t}" for t in parts} | {f"val/{m}" for m in METRICS} | {"val_loss"}
    for name in names:
        logged = [(v, b) for n, v, b in calls if n == name]
        assert [b for _, b in logged] == [3, 1], name
        mean = sum(v * b for v, b in logged) / 4
        assert float(trainer.callback_metrics[name]) == pytest.approx(mean, rel=1e-5), name
    # (and again per dataset: test_metrics_are_logged_per_dataset_too)
    assert {n for n, _, _ in calls if n.count("/") < 2} == names


def test_metrics_are_logged_per_dataset_too(build_tiny_module: Callable, datamodule) -> None:
    """A batch of Bandai and dog clips logs each metric per dataset as
    ``val/<dataset>/<metric>``, each over its own clips; their clip-weighted
    mean is the overall figure."""
    module = build_tiny_module("vae")
    calls = _spy_logs(module)
    ds = datamodule.datasets["val"]
    clips = [ds[i] for i in range(len(ds))]
    picked = [c for d in ("bandai", "dog") for c in [c for c in clips
                                                      if c.meta["dataset"] == d][:2]]
    loader = DataLoader([picked], batch_size=1, collate_fn=lambda g: collate_clips(g[0]))
    trainer = _quiet_trainer()
    trainer.validate(module, dataloaders=loader, verbose=False)
    for metric in METRICS:
        counts = {d: len([n for n, _, _ in calls if n == f"val/{d}/{metric}"])
                  for d in ("bandai", "dog")}
        assert counts == {"bandai": 1, "dog": 1}, metric  # once, at the epoch's end
        values = [float(trainer.callback_metrics[f"val/{d}/{metric}"]) for d in ("bandai", "dog")]
        assert float(trainer.callback_metrics[f"val/{metric}"]) == pytest.approx(
            sum(values) / 2, rel=1e-5), metric
    assert values[0] != pytest.approx(values[1])  # each dataset its own clips


# ------------------------------------------------------------------ embed
def test_module_owns_its_semantic_encoder(build_tiny_module: Callable, embed: Callable,
                                          tmp_path: Path) -> None:
    """module.embed gives what the data module's embedder gave in training,
    builds the encoder once, leaves it out of pickles, and follows
    set_semantic_cache."""
    import pickle
    from satagraph.datasets.zoo import zoo_rigs
    module = build_tiny_module("vae")
    skeleton = zoo_rigs(["quadruped"])[0].skeleton
    torch.testing.assert_close(module.embed(skeleton), embed(skeleton))
    first = module.__dict__["_embedder"]
    module.embed(skeleton)
    assert module.__dict__["_embedder"] is first
    assert "_embedder" not in pickle.loads(pickle.dumps(module)).__dict__
    module.set_semantic_cache(str(tmp_path / "cache"))
    torch.testing.assert_close(module.embed(skeleton), embed(skeleton))
    assert module.__dict__["_embedder"] is not first
    assert any((tmp_path / "cache").rglob("*"))
    module.meta["semantic_encoder"] = "none"
    module.set_semantic_cache(None)
    assert module.embed(skeleton).shape == (skeleton.num_joints, 0)


def test_setup_refuses_semantics_the_network_would_not_read(build_tiny_module: Callable,
                                                           datamodule) -> None:
    """A module built without ``semantic_channels`` trained on the data's
    semantic features without reading them, silently."""
    width = datamodule.semantic_channels
    assert width > 0
    build_tiny_module("vae", semantic_channels=width)._check_semantic_width(datamodule)
    build_tiny_module("vae", semantic_channels=0, use_text=False)._check_semantic_width(
        datamodule)
    for ours in (0, width // 2):
        with pytest.raises(ValueError, match=f"semantic features are {width} wide .* "
                           f"model.semantic_channels={width}"):
            build_tiny_module("vae", semantic_channels=ours)._check_semantic_width(datamodule)


def test_trainer_predict_decodes_the_test_split_in_order(build_tiny_module: Callable,
                                                         datamodule) -> None:
    module = build_tiny_module("vae").eval()
    trainer = L.Trainer(accelerator="cpu", logger=False, enable_progress_bar=False,
                        enable_model_summary=False, limit_predict_batches=2)
    predicted = trainer.predict(module, datamodule=datamodule)
    batches = list(datamodule.test_dataloader())[:2]
    assert len(predicted) == len(batches) == 2
    with torch.no_grad():
        for out, batch in zip(predicted, batches):
            torch.testing.assert_close(out["q"], module(batch)["q"])


def test_rvq_module_codes_round_trip(build_tiny_module: Callable, train_batch) -> None:
    """codes() refuses training mode; decode_codes of a batch's codes gives
    the module's own evaluation-mode prediction."""
    module = build_tiny_module("rvq")
    module.train()
    with pytest.raises(RuntimeError, match="eval"):
        module.codes(train_batch)
    module.eval()
    codes = module.codes(train_batch)
    assert codes.shape[0] == train_batch.root.shape[0] and bool((codes >= 0).all())
    with torch.no_grad():
        direct = module(train_batch)
    decoded = module.decode_codes(codes, train_batch)
    torch.testing.assert_close(decoded["q"], direct["q"], atol=1e-5, rtol=1e-5)
    torch.testing.assert_close(decoded["r"], direct["r"], atol=1e-5, rtol=1e-5)


def test_latent_smooth_is_applied_once(build_tiny_module: Callable, train_batch) -> None:
    """A network that smooths its latents (``latent_smooth``) decodes like
    the same weights without it fed smoothed latents; decode_codes adds
    only the remainder of the asked width (widths add in squares)."""
    from satagraph.ops.smoothing import gaussian_smooth
    plain = build_tiny_module("rvq").eval()
    codes = plain.codes(train_batch)  # first: k-means initialises the codebooks
    smooth = build_tiny_module("rvq", latent_smooth=1.5).eval()
    smooth.load_state_dict(plain.state_dict())
    frames = train_batch.clip_num_frames
    once = smooth.decode_codes(codes, train_batch, smooth=1.5)
    torch.testing.assert_close(once["q"], plain.decode_codes(codes, train_batch, 1.5)["q"])
    torch.testing.assert_close(smooth.decode_codes(codes, train_batch, smooth=0.0)["q"],
                               once["q"])  # never less than its own
    with torch.no_grad():
        z = plain.encode(plain.normalize_batch(train_batch))["z"]
        target = plain.normalize_batch(train_batch)
        wider = gaussian_smooth(gaussian_smooth(z, frames, 2.0), frames, 1.5)  # 2.5 in all
        expect = plain.denormalize_output(plain.decode(wider, target), train_batch)["q"]
    twice = smooth.decode_codes(codes, train_batch, smooth=2.5)["q"]
    torch.testing.assert_close(twice, expect, atol=1e-5, rtol=1e-5)
    assert not torch.allclose(once["q"], twice, atol=1e-3)
    with torch.no_grad():
        direct = smooth(train_batch)["q"]
        fed = plain.denormalize_output(plain.decode(gaussian_smooth(z, frames, 1.5), target),
                                       train_batch)["q"]
    torch.testing.assert_close(direct, fed, atol=1e-5, rtol=1e-5)


def test_a_float64_batch_reads_as_float32(build_tiny_module: Callable,
                                          train_batch: FrameBatch) -> None:
    """Features built in float64 (numpy's default) failed deep in the
    encoder: "mat1 and mat2 must have the same dtype, but got Double and
    Float"."""
    module = build_tiny_module().eval()
    wide = copy.copy(train_batch)
    wide.x, wide.root = train_batch.x.double(), train_batch.root.double()
    wide.joint_static = train_batch.joint_static.double()
    with torch.no_grad():
        out, ref = module(wide), module(train_batch)
        losses = module.compute_losses(out, wide)
    assert out["q"].dtype == torch.float32
    torch.testing.assert_close(out["q"], ref["q"])
    assert torch.isfinite(losses["loss"])


def test_setup_refuses_data_at_another_frame_rate(build_tiny_module: Callable,
                                                   datamodule) -> None:
    """A module built by hand (fps 30, the default) trained on 60 fps
    windows without a word, and inference then fed it 30 fps motion."""
    class Faster(L.LightningDataModule):
        preprocessing = dict(datamodule.preprocessing, fps=60.0)

        def train_dataloader(self) -> DataLoader:
            return datamodule._loader("train", False)

    module = build_tiny_module()
    assert module.fps == 30.0
    with pytest.raises(ValueError, match="at 60 fps .* module's fps is 30"):
        _quiet_trainer(max_steps=1, limit_val_batches=0).fit(module, datamodule=Faster())


def test_a_module_built_without_meta_takes_the_data_s_window_and_encoder(
        tiny_config: Dict[str, Any], datamodule, tmp_path: Path) -> None:
    """Built by hand with ``meta={}``, a module trained on 16-frame windows
    was read by inference in 64-frame ones (``default_windows``); one that
    says another window is refused."""
    hparams = build_module(tiny_config, datamodule).hparams
    sections = {k: hparams[k] for k in ("model", "loss", "optim", "fps")}
    module = SATAVAEModule(**sections, meta={})
    module.normalizer.load_state_dict(datamodule.normalizer.state_dict())
    trainer = _quiet_trainer(max_steps=1, limit_val_batches=0)
    trainer.fit(module, datamodule=datamodule)
    path = tmp_path / "model.ckpt"
    trainer.save_checkpoint(path)
    meta = torch.load(path, weights_only=True)["hyper_parameters"]["meta"]
    assert meta["window"] == datamodule.window == 16
    assert meta["semantic_encoder"] == datamodule.semantic_encoder == "offline"
    other = SATAVAEModule(**sections, meta={"window": 64})
    with pytest.raises(ValueError, match="the data's window is 16 .* meta says 64"):
        _quiet_trainer(max_steps=1, limit_val_batches=0).fit(other, datamodule=datamodule)
