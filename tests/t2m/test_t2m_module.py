"""TextToMotionModule: codes of a frozen autoencoder on the fly, losses that
fall on a fixed batch, gradients only into the generators, guidance that
never drops the skeleton, checkpoints that check their text encoder, and
`satagraph train` with ``module: t2m``."""
from __future__ import annotations

import copy

import pytest
import torch

from satagraph.experiment.config import load_config
from satagraph.io.checkpoint import CheckpointError
from satagraph.experiment.train import build_module, load_module, train
from tests.t2m.conftest import build_t2m, save_checkpoint, tiny_train_overrides, zoo_batch


def test_codes_come_from_the_frozen_autoencoder(autoencoder_ckpt):
    module = build_t2m(autoencoder_ckpt)
    batch = zoo_batch(3)
    codes, lengths = module.batch_codes(batch)
    assert codes.shape == (3, int(lengths.max()), 3)
    assert torch.equal(lengths, batch.clip_num_frames)
    real = codes[torch.arange(codes.size(1)) < lengths[:, None]]
    assert real.min() >= 0 and real.max() < 32
    module.train()
    assert not module.autoencoder.training  # never trained, no quantiser dropout
    assert not any(p.requires_grad for p in module.autoencoder.parameters())


def test_training_steps_lower_the_loss_and_reach_every_generator(autoencoder_ckpt):
    module = build_t2m(autoencoder_ckpt).train()
    batch = zoo_batch(6)
    ae_before = copy.deepcopy(module.autoencoder.state_dict())
    opt = torch.optim.AdamW([p for p in module.parameters() if p.requires_grad], 3e-3)
    losses = []
    for step in range(12):
        out = module.compute_losses(batch, torch.Generator().manual_seed(0))
        opt.zero_grad()
        out["loss"].backward()
        if step == 0:
            for name in ("skeleton", "masked", "residual", "length"):
                grads = [p.grad for p in getattr(module, name).parameters()
                         if p.grad is not None]
                assert grads and any(float(g.abs().sum()) > 0 for g in grads), name
        opt.step()
        losses.append(out["loss"].item())
    assert losses[-1] < 0.8 * losses[0]
    after = module.autoencoder.state_dict()
    assert all(torch.equal(ae_before[k], after[k]) for k in ae_before)


def test_the_length_model_trains_alone_without_coding_the_windows(autoencoder_ckpt,
                                                                  monkeypatch):
    """optim.frozen keeps every other part as it was; zero-weighted
    transformers are not run, so no window is coded."""
    torch.manual_seed(0)
    from tests.t2m.conftest import T2M_MODEL
    from satagraph.lightning.text_to_motion import TextToMotionModule
    module = TextToMotionModule(model=dict(T2M_MODEL, autoencoder=str(autoencoder_ckpt)),
                                loss={"masked": 0.0, "residual": 0.0, "length": 1.0},
                                optim={"frozen": ["skeleton", "masked", "residual"]},
                                meta={"module": "t2m", "semantic_encoder": "offline"}).train()
    assert not module.masked.training and module.length.training
    monkeypatch.setattr(module, "batch_codes", lambda batch: pytest.fail("coded"))
    before = copy.deepcopy(module.state_dict())
    batch = zoo_batch(6)
    trained = module.configure_optimizers()["optimizer"].param_groups[0]["params"]
    assert {id(p) for p in trained} == {id(p) for p in module.length.parameters()}
    opt = torch.optim.AdamW(trained, 3e-3)
    losses = []
    for _ in range(30):
        out = module.compute_losses(batch, torch.Generator().manual_seed(0))
        assert set(out) == {"length", "loss"}
        opt.zero_grad()
        out["loss"].backward()
        opt.step()
        losses.append(out["loss"].item())
    assert losses[-1] < 0.5 * losses[0]
    after = module.state_dict()
    changed = {k.split(".")[0] for k in before if not torch.equal(before[k], after[k])}
    assert changed == {"length"}


def test_an_unknown_frozen_part_is_named(autoencoder_ckpt):
    from tests.t2m.conftest import T2M_MODEL
    from satagraph.lightning.text_to_motion import TextToMotionModule
    with pytest.raises(ValueError, match="'lenght' is not a part of TextToMotionModule; its "
                       "parts: skeleton, masked, residual, length"):
        TextToMotionModule(model=dict(T2M_MODEL, autoencoder=str(autoencoder_ckpt)),
                           optim={"frozen": ["lenght"]},
                           meta={"module": "t2m", "semantic_encoder": "offline"})


def test_guidance_drops_the_text_but_never_the_skeleton(autoencoder_ckpt):
    module = build_t2m(autoencoder_ckpt).eval()
    batch = zoo_batch(2)
    skel = module.skeleton_embedding(batch)
    text = module.encode_text(["a person walks forward"] * 2)
    tokens = torch.zeros(2, 5, dtype=torch.long)
    lengths = torch.tensor([5, 5])
    null = module.masked(tokens, None, skel, lengths)
    dropped = module.masked(tokens, text, skel, lengths, drop_text=torch.ones(2, dtype=bool))
    assert torch.allclose(null, dropped, atol=1e-6)  # drop = the null text token
    other_skel = module.masked(tokens, None, skel.flip(0), lengths)
    assert not torch.allclose(null, other_skel)  # the skeleton still conditions


def test_checkpoint_round_trip_checks_the_text_encoder(autoencoder_ckpt, t2m_ckpt, tmp_path):
    module = load_module(str(t2m_ckpt)).eval()
    assert type(module).__name__ == "TextToMotionModule"
    saved = torch.load(t2m_ckpt, weights_only=True)
    assert saved["text_encoder"] == {"id": module.text_encoder.id, "width": 32}
    assert all(torch.equal(saved["state_dict"][k], v)
               for k, v in module.state_dict().items())
    # the autoencoder travels inside: no need for its file any more
    assert "hparams" in saved["hyper_parameters"]["model"]["autoencoder"]
    other = dict(saved, text_encoder={"id": "glove:other", "width": 32})
    bad = tmp_path / "other.ckpt"
    torch.save(other, bad)
    with pytest.raises(ValueError, match="text encoder mismatch"):
        load_module(str(bad))
    assert saved["hyper_parameters"]["meta"]["text_encoder"] == saved["text_encoder"]
    missing = {k: v for k, v in saved.items() if k != "text_encoder"}
    missing["hyper_parameters"] = copy.deepcopy(saved["hyper_parameters"])
    del missing["hyper_parameters"]["meta"]["text_encoder"]
    torch.save(missing, bad)
    with pytest.raises(CheckpointError, match="no text encoder record"):
        load_module(str(bad))


def test_a_non_rvq_autoencoder_is_refused(tmp_path):
    from satagraph.lightning import SATAVAEModule
    vae = SATAVAEModule(model={"hidden_channels": 8, "heads": 2, "ff_channels": 8,
                               "num_blocks": 1, "latent_channels": 8,
                               "semantic_channels": 256},
                        meta={"module": "vae", "semantic_encoder": "offline"})
    path = save_checkpoint(vae, tmp_path / "vae.ckpt")
    with pytest.raises(CheckpointError, match="SATA-RVQ"):
        build_t2m(path)


def test_semantic_encoder_must_be_the_autoencoders(autoencoder_ckpt):
    cfg = {"module": "t2m", "model": {"autoencoder": str(autoencoder_ckpt),
                                      "text_encoder": "offline:16"},
           "data": {"semantic_encoder": "none", "sources": []}}
    with pytest.raises(ValueError, match="semantic_encoder"):
        build_module(cfg)


@pytest.mark.parametrize("monitor", ["val_loss", pytest.param("val/zoo-endless/masked",
                                                         marks=pytest.mark.slow)])
def test_satagraph_train_t2m_selects_on_validation(autoencoder_ckpt, tmp_path, monitor):
    """`satagraph train t2m_tiny` (module: t2m) end to end for a few steps,
    keeping the best checkpoint by the overall loss or one dataset's."""
    overrides = tiny_train_overrides(autoencoder_ckpt, tmp_path / "run")
    cfg = load_config("t2m_tiny", overrides + [f"trainer.monitor={monitor}"])
    module, data, trainer, run_dir = train(cfg)
    best = trainer.checkpoint_callback
    assert best.monitor == monitor and best.best_model_path
    assert torch.isfinite(trainer.callback_metrics[monitor])  # logged under that key
    assert "val_loss" in trainer.callback_metrics
    loaded = load_module(best.best_model_path)
    assert type(loaded).__name__ == "TextToMotionModule"


@pytest.mark.parametrize("name", ["t2m", "t2m_tiny"])
def test_t2m_configs_build_on_an_autoencoder(name, autoencoder_ckpt):
    cfg = load_config(name, [f"model.autoencoder={autoencoder_ckpt}"])
    for key in ("masked", "residual"):
        cfg["model"][key].update(hidden_channels=16, ff_channels=16, num_layers=1, heads=2)
    module = build_module(cfg)
    assert type(module).__name__ == "TextToMotionModule"
    assert module.masked.pool == 2 and module.residual.pool == 2


def test_the_length_only_config_trains_the_length_model_alone(autoencoder_ckpt):
    """experiments/t2m_length_bandai.yaml: every part but the length model
    frozen, the transformers not run, Bandai's long takes in 0.5 s bins."""
    from satagraph.experiment.train import module_class
    cfg = load_config("t2m_length_bandai", [f"model.autoencoder={autoencoder_ckpt}"])
    assert [s["dataset"] for s in cfg["data"]["sources"]] == ["bandai"]
    cfg["meta"] = {"module": "t2m", "semantic_encoder": "offline"}
    module = module_class("t2m")(model=cfg["model"], loss=cfg["loss"],
                                 optim={k: v for k, v in cfg["optim"].items()
                                        if k not in ("grad_clip", "ema")},
                                 meta=cfg["meta"])
    trained = {n.split(".")[0] for n, p in module.named_parameters() if p.requires_grad}
    assert trained == {"length"}
    assert module.loss_weights["masked"] == module.loss_weights["residual"] == 0.0
    assert module.length.num_bins == 32 and module.length.bin_seconds == 0.5


def test_a_missing_autoencoder_is_named(tmp_path):
    cfg = load_config("t2m_tiny", [f"model.autoencoder={tmp_path / 'none.ckpt'}"])
    with pytest.raises(CheckpointError, match="none.ckpt: no such autoencoder"):
        build_module(cfg)


def test_exported_weights_keep_the_text_encoder_record(t2m_ckpt, tmp_path):
    from satagraph.io.weights import save_weights
    module = load_module(str(t2m_ckpt))
    path = tmp_path / "t2m.safetensors"
    save_weights(module, str(path))
    again = load_module(str(path))
    assert type(again).__name__ == "TextToMotionModule"
    assert again.meta["text_encoder"] == {"id": module.text_encoder.id, "width": 32}
    assert all(torch.equal(v, again.state_dict()[k]) for k, v in module.state_dict().items())


def test_init_from_keeps_the_configured_autoencoder(autoencoder_ckpt, t2m_ckpt):
    """``--init-from`` a text-to-motion checkpoint takes its generators and
    leaves the frozen autoencoder the config names (here: a changed one),
    not the checkpoint's, saying that its codes are another's (it said
    nothing); over the same autoencoder it says nothing."""
    import warnings
    from satagraph.experiment.train import init_weights
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        init_weights(build_t2m(autoencoder_ckpt), str(t2m_ckpt))
    module = build_t2m(autoencoder_ckpt)
    saved = torch.load(t2m_ckpt, map_location="cpu", weights_only=False)["state_dict"]
    with torch.no_grad():
        for p in module.parameters():
            p.add_(1.0)
    ours = {k: v.clone() for k, v in module.state_dict().items() if k.startswith("autoencoder.")}
    with pytest.warns(UserWarning, match="trained over another autoencoder than this config's"):
        init_weights(module, str(t2m_ckpt))
    state = module.state_dict()
    for k, v in ours.items():
        assert torch.equal(state[k], v), k
    generator = [k for k in saved if k.startswith(("masked.", "residual."))]
    assert generator and all(torch.equal(state[k], saved[k]) for k in generator)


def test_the_schedule_warms_up_then_follows_a_cosine_to_its_floor(autoencoder_ckpt):
    from satagraph.lightning.text_to_motion import warmup_cosine
    assert warmup_cosine(0, 10, 0, 0.1) == pytest.approx(0.1)
    assert warmup_cosine(50, 10, 0, 0.1) == 1.0  # no decay: constant
    assert warmup_cosine(10, 10, 100, 0.1) == pytest.approx(1.0)
    assert warmup_cosine(60, 10, 100, 0.1) == pytest.approx(0.55)  # half way
    assert warmup_cosine(110, 10, 100, 0.1) == pytest.approx(0.1)
    assert warmup_cosine(500, 10, 100, 0.1) == pytest.approx(0.1)
    module = build_t2m(autoencoder_ckpt)
    module.optim.update(lr=1e-3, warmup_steps=2, decay_steps=4, floor=0.2)
    conf = module.configure_optimizers()
    opt, sched = conf["optimizer"], conf["lr_scheduler"]["scheduler"]
    lrs = []
    for _ in range(8):
        lrs.append(opt.param_groups[0]["lr"])
        opt.step()
        sched.step()
    assert lrs[:2] == pytest.approx([5e-4, 1e-3])
    assert lrs[4] == pytest.approx(6e-4)
    assert lrs[6:] == pytest.approx([2e-4, 2e-4])


def test_facing_frame_must_be_the_autoencoders(autoencoder_ckpt, tmp_path):
    from satagraph.io.checkpoint import load_checkpoint
    payload = load_checkpoint(autoencoder_ckpt)
    payload["hyper_parameters"]["meta"]["data"] = {"preprocessing": {"facing_smooth": 0.25}}
    smoothed = tmp_path / "smoothed.ckpt"
    torch.save(payload, smoothed)

    def build(facing):
        return build_module({"module": "t2m",
                             "model": {"autoencoder": str(smoothed), "text_encoder": "offline:16"},
                             "data": {"sources": [], "preprocessing": {"facing_smooth": facing}}})
    with pytest.raises(ValueError, match=r"facing_smooth=0 is not the autoencoder's \(0.25\)"):
        build(0.0)
    assert build(0.25).meta["data"]["preprocessing"]["facing_smooth"] == 0.25


def test_validation_logs_the_masked_loss_per_dataset(autoencoder_ckpt, monkeypatch):
    """Validation logs the masked loss and accuracy of each dataset's
    clips (``val/<dataset>/masked``) over its masked tokens: their
    token-weighted mean is the overall figure; training logs none."""
    import lightning as L
    from torch.utils.data import DataLoader
    import satagraph.lightning.text_to_motion as t2m_module
    from satagraph.lightning.per_dataset import log_per_dataset

    tokens_of = {}

    def spy(module, stage, values, datasets, weights=None):
        for d in set(datasets):
            tokens_of[d] = sum(int(w) for w, e in zip(weights, datasets) if e == d)
        log_per_dataset(module, stage, values, datasets, weights)

    monkeypatch.setattr(t2m_module, "log_per_dataset", spy)
    module = build_t2m(autoencoder_ckpt)
    batch = zoo_batch(6)
    for i, meta in enumerate(batch.meta):
        meta["dataset"] = "zoo" if i < 4 else "zoo-gestures"
    calls = []
    original = module.log

    def log(name, value, *args, **kwargs):
        calls.append((name, float(value), kwargs.get("batch_size")))
        original(name, value, *args, **kwargs)

    module.log = log
    trainer = L.Trainer(accelerator="cpu", devices=1, logger=False, enable_checkpointing=False,
                        enable_progress_bar=False, enable_model_summary=False)
    trainer.validate(module, DataLoader([batch], batch_size=None), verbose=False)
    for name in ("masked_acc", "masked"):
        logged = {d: [(v, tokens_of[d]) for n, v, _ in calls if n == f"val/{d}/{name}"]
                  for d in ("zoo", "zoo-gestures")}
        assert all(len(v) == 1 and v[0][1] > 0 for v in logged.values()), logged
        tokens = sum(v[0][1] for v in logged.values())
        mean = sum(v[0][0] * v[0][1] for v in logged.values()) / tokens
        assert float(trainer.callback_metrics[f"val/{name}"]) == pytest.approx(mean, rel=1e-4)
    assert logged["zoo"][0][0] != pytest.approx(logged["zoo-gestures"][0][0])  # the loss
    calls.clear()
    module.train()
    module.compute_losses(batch, torch.Generator().manual_seed(0))
    assert not calls
