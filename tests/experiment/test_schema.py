"""The config schema: one default per key, in one place, and one error line
for an unknown key (naming it, the known keys and the closest)."""
from __future__ import annotations

import inspect
import json
import os
import re
from dataclasses import asdict, fields
from pathlib import Path
from types import SimpleNamespace

import pytest

from satagraph.experiment.config import load_config
from satagraph.experiment.schema import (GRAD_CLIP, CheckpointConfig, DataConfig,
                                         ExperimentConfig, defaults, resolve_config)


@pytest.mark.parametrize("override, message", [
    ("seeds=1", r"unknown config key 'seeds' \(did you mean 'seed'\?\); known: "),
    ("data.batchsize=4", r"'data.batchsize' \(did you mean 'batch_size'\?\)"),
    ("data.augment={scael: 0.5}", r"'data.augment.scael' \(did you mean 'scale'\?\)"),
    ("data.preprocessing={facing_smoth: 0.25}",
     r"'data.preprocessing.facing_smoth' \(did you mean 'facing_smooth'\?\)"),
    ("logger.nmae=csv", r"'logger.nmae' \(did you mean 'name'\?\)"),
    ("checkpoint.every_n_step=5", r"did you mean 'every_n_steps'"),
    ("module=vea", r"unknown module 'vea' \(did you mean 'vae'\?\); known: .*padded_rvq"),
])
def test_unknown_key_is_one_line_with_the_closest(override, message):
    with pytest.raises(ValueError, match=message) as err:
        load_config("tiny", [override])
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("fps", ["null", "0", "-5", "abc"])
def test_a_frame_rate_that_is_none_is_one_line(fps):
    """``data.preprocessing.fps=null`` (keep each file's rate) failed as a
    ``TypeError`` traceback, ``0`` kept 30 and 60 fps clips apart until a
    batch mixed them, and ``-5`` left out every file."""
    from satagraph.experiment.train import check_config
    with pytest.raises(ValueError, match=rf"^data.preprocessing.fps='?{fps}'?: a frame rate "
                                         "above 0 is expected"):
        check_config(load_config("tiny", [f"data.preprocessing.fps={fps}"]))


def test_known_keys_are_listed():
    with pytest.raises(ValueError) as err:
        load_config("tiny", ["outputdir=x"])
    line = str(err.value)
    assert "did you mean 'output_dir'" in line
    assert all(f.name in line for f in fields(ExperimentConfig))


def test_module_sections_checked_when_built():
    from satagraph.experiment.train import build_module
    with pytest.raises(ValueError, match=r"'model.hidden_chanels' \(did you mean "
                       r"'hidden_channels'\?\)"):
        build_module(load_config("tiny", ["model.hidden_chanels=8"]))
    with pytest.raises(ValueError, match=r"'optim.lrr' \(did you mean 'lr'\?\)"):
        build_module(load_config("tiny", ["optim.lrr=0.1"]))


def test_trainer_keys_checked(tmp_path):
    from satagraph.experiment.train import build_trainer
    with pytest.raises(ValueError, match=r"'trainer.max_epoch' \(did you mean "
                       r"'max_epochs'\?\)"):
        build_trainer(load_config("tiny", ["trainer.max_epoch=1"]), tmp_path)


def test_every_default_is_filled_and_resolving_is_idempotent():
    cfg = load_config("tiny")
    assert set(cfg) == {f.name for f in fields(ExperimentConfig)}
    assert set(cfg["data"]) == {f.name for f in fields(DataConfig)}
    assert cfg["checkpoint"] == asdict(CheckpointConfig())
    assert resolve_config(cfg) == cfg
    assert cfg["name"] == "tiny" and cfg["seed"] == 0 and cfg["loss_log"] is False


def test_data_defaults_are_the_data_module_s():
    """The schema's ``data`` defaults are the ones MotionDataModule documents
    (its signature serves Python callers; a config passes every key)."""
    from satagraph.data.datamodule import MotionDataModule
    signature = inspect.signature(MotionDataModule).parameters
    schema = defaults(DataConfig)
    assert set(schema) == set(signature)
    for name, value in schema.items():
        if name in ("sources", "seed", "preprocessing"):
            continue  # required; None: the run's seed; None and {} alike
        assert signature[name].default == value, name


def test_one_set_of_augmentation_defaults():
    from satagraph.data.dataset import AUGMENT_DEFAULTS, WindowAugment
    from satagraph.transforms.augment import AUGMENT, SkeletonAugment
    assert AUGMENT_DEFAULTS == asdict(AUGMENT)
    window = inspect.signature(WindowAugment).parameters
    assert {k: window[k].default for k in AUGMENT_DEFAULTS} == AUGMENT_DEFAULTS
    skeleton = SkeletonAugment()
    assert (skeleton.p_scale, skeleton.p_mirror, skeleton.p_drop, skeleton.p_merge,
            skeleton.p_insert, skeleton.p_rest) == (AUGMENT.scale, AUGMENT.mirror,
                                                    AUGMENT.drop, AUGMENT.merge,
                                                    AUGMENT.insert, AUGMENT.rest)
    assert skeleton.scale_range == (AUGMENT.low, AUGMENT.high)


def test_grad_clip_has_one_owner(tmp_path):
    from satagraph.experiment.train import build_trainer
    from satagraph.lightning.autoencoder import DEFAULT_OPTIM
    assert "grad_clip" not in DEFAULT_OPTIM
    assert load_config("tiny")["optim"]["grad_clip"] == GRAD_CLIP
    cfg = load_config("tiny", ["optim.grad_clip=0.25", "logger.name=none",
                               "trainer.progress=false"])
    assert build_trainer(cfg, tmp_path).gradient_clip_val == 0.25
    with pytest.raises(ValueError, match="optim.grad_clip"):
        load_config("tiny", ["trainer.gradient_clip_val=1.0"])


@pytest.mark.parametrize("key,value,says", [
    ("default_root_dir", "/tmp/x", "set output_dir"), ("logger", "false", "logger.name"),
    ("enable_checkpointing", "false", "checkpoint.every_n_steps")])
def test_what_a_run_sets_itself_is_refused_in_a_config(key, value, says):
    """These passed the key check, then failed with a traceback (a keyword
    given twice, or Lightning refusing a checkpoint callback) once the data
    had loaded."""
    with pytest.raises(ValueError, match=f"trainer.{key}: .*{says}"):
        load_config("tiny", [f"trainer.{key}={value}"])


@pytest.mark.parametrize("overrides,says", [
    (["logger.name=bogus"], "logger.name=bogus: use wandb, csv, tensorboard, none"),
    (["logger.name=wandb", "logger.project=bad/proj"], "W&B needs a non-empty name"),
    (["logger.name=wandb", "logger.project="], "W&B needs a non-empty name")])
def test_a_logger_that_cannot_log_is_one_line_before_the_data(overrides, says):
    """A bad W&B project was a 50-line traceback once the data had loaded;
    an empty one logged into ``lightning_logs``."""
    from satagraph.experiment.train import check_config
    with pytest.raises(ValueError, match=re.escape(says)):
        check_config(load_config("tiny", overrides))


def test_a_resumed_run_logs_into_its_own_w_and_b_run(tmp_path):
    """A resume started a new W&B run beside the first (its steps from 0)."""
    from satagraph.experiment.train import _last_wandb_id, build_logger
    cfg = load_config("tiny", ["logger.name=wandb"])
    assert _last_wandb_id(tmp_path) is None
    for name in ("offline-run-20261130_120000-aaa", "offline-run-20261130_130000-bbb",
                 "run-20261130_110000-ccc"):
        (tmp_path / "wandb" / name).mkdir(parents=True)
    assert _last_wandb_id(tmp_path) == "bbb"
    logger = build_logger(cfg, tmp_path, resume=True)
    assert logger._wandb_init["id"] == "bbb" and logger._wandb_init["resume"] == "allow"
    assert build_logger(cfg, tmp_path)._wandb_init.get("id") is None
    # the trainer's own checkpoint callback was named like the flag and took its
    # place: every new run went on under a W&B id left in its folder
    from satagraph.experiment.train import build_trainer
    assert build_trainer(cfg, tmp_path).logger._wandb_init.get("id") is None
    assert build_trainer(cfg, tmp_path, resume=True).logger._wandb_init["id"] == "bbb"


@pytest.fixture
def wandb_starts(monkeypatch):
    """``wandb.init`` replaced by a recorder: ``(kwargs, WANDB_MODE then)``
    of every W&B run a logger starts (nothing written, no network)."""
    wandb = pytest.importorskip("wandb")
    started = []
    monkeypatch.setattr(wandb, "init", lambda **kwargs: started.append(
        (kwargs, os.environ.get("WANDB_MODE"))) or SimpleNamespace())
    monkeypatch.setenv("WANDB_MODE", "online")  # put back however a logger changes it
    return started


def test_a_w_and_b_run_s_mode_is_its_own_not_the_process_s(tmp_path, monkeypatch,
                                                             wandb_starts):
    """An offline logger set ``WANDB_MODE`` for the whole process: an online
    run started after it in the same process (a sweep's next config, a
    notebook's next run) went offline, and ``WANDB_MODE=disabled`` logged
    offline into the run folder."""
    from satagraph.experiment.train import build_logger
    offline = load_config("tiny", ["logger.name=wandb"])
    online = load_config("tiny", ["logger.name=wandb", "logger.offline=false"])
    assert build_logger(offline, tmp_path).experiment is not None
    assert build_logger(online, tmp_path).experiment is not None
    assert [(kwargs.get("mode"), env) for kwargs, env in wandb_starts] == [
        ("offline", "online"), (None, "online")]
    monkeypatch.setenv("WANDB_MODE", "disabled")
    for cfg in (offline, online):
        assert build_logger(cfg, tmp_path).experiment is not None
    assert [kwargs.get("mode") for kwargs, _ in wandb_starts[2:]] == ["disabled", "disabled"]


def test_a_w_and_b_run_holds_the_whole_config_and_its_folder(tmp_path, monkeypatch,
                                                               wandb_starts):
    """The W&B config held the module's hyperparameters alone: no seed, no
    trainer, no run folder to find the checkpoints by."""
    from satagraph.experiment.schema import resolve_config
    from satagraph.experiment.train import build_logger
    monkeypatch.chdir(tmp_path)
    cfg = resolve_config(load_config("tiny", ["logger.name=wandb", "seed=7"]))
    assert build_logger(cfg, Path("runs/tiny")).experiment is not None
    logged = wandb_starts[-1][0]["config"]
    assert logged == dict(cfg, output_dir=str(tmp_path / "runs" / "tiny"))
    assert logged["seed"] == 7 and logged["trainer"]["max_epochs"] == 2
    assert json.loads(json.dumps(logged)) == logged  # plain values, no object's repr


def test_a_second_run_of_one_process_is_a_w_and_b_run_of_its_own(tmp_path, monkeypatch):
    """Lightning logs into a W&B run in progress: a script's second
    ``train()`` (or an in-process resume) logged into the first's run, under
    its name and config; a run of one's own is still logged into."""
    wandb = pytest.importorskip("wandb")
    from satagraph.experiment.train import build_logger
    monkeypatch.setattr(wandb, "run", None)

    def start(name: str) -> SimpleNamespace:
        wandb.run = SimpleNamespace(name=name, finish=lambda: setattr(wandb, "run", None))
        return wandb.run

    monkeypatch.setattr(wandb, "init", lambda **kwargs: start(kwargs["name"]))
    first = build_logger(load_config("tiny", ["logger.name=wandb", "name=first"]), tmp_path)
    assert first.experiment.name == "first"
    second = build_logger(load_config("tiny", ["logger.name=wandb", "name=second"]), tmp_path)
    assert second.experiment.name == "second" and wandb.run is second.experiment
    own = start("own")  # wandb.init() by the user, before training
    with pytest.warns(UserWarning, match="already in progress"):
        assert build_logger(load_config("tiny", ["logger.name=wandb"]), tmp_path
                            ).experiment is own


def test_tensorboard_without_its_package_is_said(monkeypatch):
    import importlib.util
    from satagraph.experiment.train import check_logger
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None)
    with pytest.raises(ValueError, match="needs the tensorboard package"):
        check_logger({"name": "tensorboard"})


def test_no_validation_asked_monitors_nothing(tmp_path):
    """``trainer.limit_val_batches=0`` left the best checkpoint watching
    ``val_loss``: Lightning warned of it with every logged key (40)."""
    from satagraph.experiment.train import build_trainer
    cfg = load_config("tiny", ["logger.name=none", "trainer.progress=false",
                               "trainer.limit_val_batches=0"])
    assert build_trainer(cfg, tmp_path).checkpoint_callback.monitor is None
    cfg = load_config("tiny", ["logger.name=none", "trainer.progress=false"])
    assert build_trainer(cfg, tmp_path).checkpoint_callback.monitor == "val_loss"


def test_python_may_hand_the_trainer_its_own_logger_and_folder(tmp_path):
    from lightning.pytorch.loggers import CSVLogger
    from satagraph.experiment.train import build_trainer
    cfg = load_config("tiny", ["logger.name=none", "trainer.progress=false"])
    mine = CSVLogger(str(tmp_path / "mine"))
    trainer = build_trainer(cfg, tmp_path / "run", logger=mine,
                            default_root_dir=str(tmp_path / "elsewhere"))
    assert trainer.logger is mine and trainer.default_root_dir == str(tmp_path / "elsewhere")
    assert build_trainer(cfg, tmp_path / "run").logger is None


def test_train_checks_every_key_before_reading_data(tmp_path):
    from satagraph.experiment.train import train
    for override in ("model.hidden_chanels=8", "trainer.max_epoch=1"):
        cfg = load_config("tiny", [override, "data.sources=[/nowhere]",
                                   f"output_dir={tmp_path / 'run'}"])
        with pytest.raises(ValueError, match="did you mean"):
            train(cfg)
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize("override, message", [
    ("seed=abc", "seed='abc': an integer is expected"),
    ("data.balanced=maybe", "data.balanced='maybe': true or false is expected"),
    ("data.window=-5", "data.window=-5: at least 2 is expected"),
    ("data.batch_size=0", "data.batch_size=0: at least 1 is expected"),
    ("trainer.max_steps=abc", "trainer.max_steps='abc': an integer is expected"),
    ("trainer.limit_val_batches=all", "trainer.limit_val_batches='all': a number"),
    ("checkpoint.every_minutes=soon", "checkpoint.every_minutes='soon': a number is expected"),
])
def test_a_value_of_the_wrong_type_is_one_line(override, message):
    """Values the schema can type are checked where they are given, not
    where they fail (an ``IndexError`` in windowing, a ``TypeError`` in
    Lightning)."""
    with pytest.raises(ValueError, match=re.escape(message)):
        load_config("tiny", [override])
    assert load_config("tiny", ["data.max_files=null", "threads=null", "seed=3"])["seed"] == 3
    # a folder named by a number reads as one: names and folders take any value
    assert load_config("tiny", ["output_dir=2024"])["output_dir"] == 2024


def test_heads_must_divide_the_width():
    from satagraph.nn.layers.spatio_temporal import SpatioTemporalBlock
    with pytest.raises(ValueError, match="hidden_channels=33 must be a multiple of "
                                         "model.heads=4"):
        SpatioTemporalBlock(33, heads=4)


@pytest.mark.parametrize("override, module", [
    ("seed=-1", "vae"), ("data.seed=-1", "vae"), ("seed=4294967296", "vae"),
    ("data.seed=-1", "t2m")])
def test_a_seed_out_of_range_is_one_line_before_training(override, module):
    """``data.seed=-1`` trained until the first augmented or zoo window and
    then failed as ``expected non-negative integer``; ``seed=-1`` failed in
    Lightning without naming the key. Both are one line naming it."""
    with pytest.raises(ValueError, match=rf"^{re.escape(override)}: a seed from 0 to "
                                         "4294967295 is expected$"):
        load_config("tiny", [f"module={module}", override])
    assert load_config("tiny", ["seed=4294967295", "data.seed=0"])["data"]["seed"] == 0


def test_a_zoo_entry_seed_out_of_range_is_one_line_before_training():
    """A zoo entry's ``seed: -1`` trained until its first zoo window and
    then failed as ``expected non-negative integer``."""
    with pytest.raises(ValueError, match=r"^data.sources\[1\].seed=-1: a seed from 0 to "):
        load_config("t2m_rvq_tiny", ["data.sources=[/data, {zoo: endless, seed: -1}]"])
    cfg = load_config("t2m_rvq_tiny", ["data.sources=[{zoo: endless, seed: 7}]"])
    assert cfg["data"]["sources"][0]["seed"] == 7


@pytest.mark.parametrize("config, overrides, says", [
    ("tiny", ["trainer.accelerator=gpu"],
     "trainer.accelerator=gpu: needs 1 CUDA GPU(s), this machine has 0; "
     "trainer.accelerator=auto runs on what there is"),
    ("pretrain_zoo_gpu", ["trainer.accelerator=cuda", "trainer.devices=2"],
     "trainer.accelerator=cuda: needs 2 CUDA GPU(s), this machine has 0"),
])
def test_a_gpu_this_machine_lacks_is_one_line_before_the_data(monkeypatch, config,
                                                              overrides, says):
    """``trainer.accelerator=gpu`` without a GPU was Lightning's traceback
    ('No supported gpu backend found!') once the data had been read."""
    import torch
    from satagraph.experiment.train import check_config
    monkeypatch.setattr(torch.cuda, "is_available", lambda: False)
    with pytest.raises(ValueError, match=re.escape(says)):
        check_config(load_config(config, overrides))


def test_an_unknown_accelerator_is_one_line_before_the_data():
    """``trainer.accelerator=gpus`` (a typo) read the data, wrote the run's
    config.yaml and then failed in Lightning ('You selected an invalid
    accelerator name')."""
    from satagraph.experiment.train import check_config
    for typo in ("gpus", "CPU"):   # Lightning's names are lower case
        with pytest.raises(ValueError, match=rf"^trainer.accelerator={typo}: not an "
                                             r"accelerator \(auto, cpu, cuda, gpu, mps, tpu\)$"):
            check_config(load_config("tiny", [f"trainer.accelerator={typo}"]))
    assert check_config(load_config("tiny", ["trainer.accelerator=cpu"]))


def test_the_gpu_configs_pass_where_a_gpu_is(monkeypatch):
    """``accelerator: auto`` (the GPU configs) passes anywhere; ``gpu`` where
    CUDA is."""
    import torch
    from satagraph.experiment.train import check_config
    monkeypatch.setattr(torch.cuda, "is_available", lambda: True)
    monkeypatch.setattr(torch.cuda, "device_count", lambda: 1)
    for name in ("pretrain_zoo_gpu", "pretrain_zoo_wide_gpu"):
        check_config(load_config(name, ["trainer.accelerator=gpu"]))
        monkeypatch.setattr(torch.cuda, "is_available", lambda: False)
        assert check_config(load_config(name))["trainer"]["accelerator"] == "auto"
        monkeypatch.setattr(torch.cuda, "is_available", lambda: True)
