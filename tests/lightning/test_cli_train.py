"""``satagraph train | eval`` in-process, and the default offline W&B logger."""
from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any, Dict, List

import numpy as np
import pytest
import torch

from satagraph.cli import main
from satagraph.io import read_bvh
from satagraph.experiment.train import build_logger, train


DOG = "dog/D1_010_KAN01_002.bvh"
HUMAN = "cmu/depressed_18_000.bvh"


def _train_args(config_overrides: List[str], run: Path, *extra: str) -> List[str]:
    return ["--traceback", "train", "tiny", *config_overrides, f"output_dir={run}",
            "data.max_files=2", "trainer.max_epochs=1", "trainer.limit_train_batches=2",
            "trainer.limit_val_batches=1", *extra]


def _checkpoint(path: Path) -> Dict[str, Any]:
    return torch.load(path, map_location="cpu", weights_only=True)


def _model_weights(ckpt: Dict[str, Any]) -> Dict[str, torch.Tensor]:
    return {k: v for k, v in ckpt["state_dict"].items() if k.startswith("model.")}


def _table_rows(text: str) -> Dict[str, List[str]]:
    """``dataset -> cells`` of the markdown table printed by ``eval``."""
    rows = {}
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if line.startswith("| ") and cells[0] != "dataset":
            rows[cells[0]] = cells[1:]
    return rows


@pytest.mark.slow
def test_train_resume_init_from_and_eval(config_overrides: List[str], tmp_path: Path,
                                         capsys: pytest.CaptureFixture,
                                         monkeypatch: pytest.MonkeyPatch) -> None:
    run = tmp_path / "run"
    last = run / "checkpoints" / "last.ckpt"
    assert main(_train_args(config_overrides, run)) == 0
    assert "trained tiny for 2 steps (1 epoch)" in capsys.readouterr().out
    first = _checkpoint(last)
    assert first["global_step"] == 2
    assert first["hyper_parameters"]["meta"]["data"]["max_files"] == 2

    # --resume continues from last.ckpt: two more steps, not a restart.
    assert main(_train_args(config_overrides, run, "trainer.max_epochs=2", "--resume")) == 0
    assert "trained tiny from step 2 to 4 (2 epochs)" in capsys.readouterr().out
    # resumed where its limit stops it: it says so instead of "trained"
    assert main(_train_args(config_overrides, run, "trainer.max_epochs=2", "--resume")) == 0
    assert "nothing to train: tiny stood at step 4" in capsys.readouterr().out
    resumed = _checkpoint(last)
    assert resumed["global_step"] == 4 and resumed["epoch"] > first["epoch"]

    # --init-from loads the weights (reading the file once); with lr = 0 they
    # stay exactly as loaded.
    from satagraph.experiment import train as train_module
    reads = []
    read = train_module.load_weights_or_checkpoint
    monkeypatch.setattr(train_module, "load_weights_or_checkpoint",
                        lambda *a, **k: reads.append(a[0]) or read(*a, **k))
    other = tmp_path / "finetune"
    args = _train_args(config_overrides, other, "optim.lr=0.0", "--init-from", str(last))
    assert main(args) == 0
    assert reads == [str(last)]
    capsys.readouterr()
    tuned = _model_weights(_checkpoint(other / "checkpoints" / "last.ckpt"))
    source = _model_weights(resumed)
    assert tuned.keys() == source.keys()
    for key, value in source.items():
        torch.testing.assert_close(tuned[key], value, rtol=0, atol=0, msg=key)

    # eval: one row per dataset of the test split, plus "all".
    table = tmp_path / "table.json"
    assert main(["--traceback", "eval", "--ckpt", str(last), "--split", "test",
                 "--json", str(table), "--retarget"]) == 0
    text = capsys.readouterr().out
    metrics, retarget = text.split("retarget error")
    rows = _table_rows(metrics)
    assert list(rows) == ["bandai", "dog", "all"]
    assert all(len(cells) == 9 for cells in rows.values())
    assert int(rows["bandai"][0]) + int(rows["dog"][0]) == int(rows["all"][0]) > 0
    assert all(math.isfinite(float(v)) for cells in rows.values() for v in cells)
    errors = _table_rows(retarget)
    assert list(errors) == ["bandai", "dog", "all"]
    assert all(float(v[0]) >= 0 and math.isfinite(float(v[0])) for v in errors.values())
    saved = json.loads(table.read_text())
    assert set(saved) == {"bandai", "dog", "all"}
    assert saved["dog"]["clips"] == int(rows["dog"][0])
    assert saved["all"]["retarget"] == pytest.approx(float(errors["all"][0]), abs=1e-3)


def test_eval_reads_the_whole_split_whatever_training_read(
        config_overrides: List[str], tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """A run trained on one file per split (``data.max_files=1``) is still
    evaluated on every file of the split asked for."""
    run = tmp_path / "run"
    assert main(_train_args(config_overrides, run, "data.max_files=1")) == 0
    capsys.readouterr()
    # the whole resolved config is recorded beside the checkpoints, and reloads as it ran
    from satagraph.experiment.config import load_config
    recorded = load_config(str(run / "config.yaml"))
    assert recorded["data"]["max_files"] == 1 and recorded["output_dir"] == str(run)
    assert "trainer" in recorded and "checkpoint" in recorded
    assert main(["--traceback", "eval", "--ckpt", str(run / "checkpoints" / "last.ckpt"),
                 "--split", "test"]) == 0
    assert list(_table_rows(capsys.readouterr().out)) == ["bandai", "dog", "all"]


def test_resume_without_checkpoint_is_a_usage_error(config_overrides: List[str],
                                                    tmp_path: Path,
                                                    monkeypatch: pytest.MonkeyPatch,
                                                    capsys: pytest.CaptureFixture) -> None:
    monkeypatch.setenv("HOME", str(tmp_path))
    args = _train_args(config_overrides, Path("~/none"), "--resume")[1:]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    # The message names the expanded run folder ("~" is the user's home).
    assert f"--resume: no checkpoint at {tmp_path / 'none'}" in err


def test_retarget_and_reconstruct_commands(config_overrides: List[str], shared_data: Path,
                                           tmp_path: Path,
                                           capsys: pytest.CaptureFixture) -> None:
    run = tmp_path / "run"
    assert main(_train_args(config_overrides, run, "trainer.limit_train_batches=1",
                            "trainer.limit_val_batches=0")) == 0
    ckpt = str(run / "checkpoints" / "last.ckpt")
    dog, human = shared_data / DOG, shared_data / HUMAN
    out = tmp_path / "dog_as_human.bvh"
    assert main(["--traceback", "retarget", "--ckpt", ckpt, "--window", "32",
                 "--overlap", "8", str(dog), "--target", str(human), str(out)]) == 0
    src, tgt, back = read_bvh(dog), read_bvh(human), read_bvh(out)
    assert back.skeleton.names == tgt.skeleton.names
    assert back.skeleton.channels == tgt.skeleton.channels
    assert back.num_frames == src.num_frames and back.fps == pytest.approx(src.fps)
    out = tmp_path / "human.bvh"
    assert main(["--traceback", "reconstruct", "--ckpt", ckpt, str(human), str(out)]) == 0
    back = read_bvh(out)
    assert back.skeleton.names == tgt.skeleton.names
    assert back.num_frames == tgt.num_frames and np.isfinite(back.rotations).all()
    assert "wrote" in capsys.readouterr().out


@pytest.mark.slow
def test_default_wandb_logger_is_offline_under_run_dir(tiny_config: Dict[str, Any],
                                                       tmp_path: Path,
                                                       monkeypatch: pytest.MonkeyPatch,
                                                       no_internet: None) -> None:
    """The default logger trains and resumes in one W&B run in the run
    folder, without a connection beyond the machine."""
    wandb = pytest.importorskip("wandb")
    env_dir = tmp_path / "wandb_env"
    for name, value in (("WANDB_MODE", "offline"), ("WANDB_DIR", env_dir),
                        ("WANDB_CONFIG_DIR", tmp_path / "wandb_config"),
                        ("WANDB_CACHE_DIR", tmp_path / "wandb_cache"),
                        ("WANDB_DATA_DIR", tmp_path / "wandb_data"),
                        ("WANDB_SILENT", "true"), ("WANDB_API_KEY", "")):
        monkeypatch.setenv(name, str(value))
    cfg = {k: v for k, v in tiny_config.items() if k != "logger"}
    run_dir = Path(cfg["output_dir"])
    logger = build_logger(cfg, run_dir)
    assert type(logger).__name__ == "WandbLogger"
    try:
        train(cfg, max_steps=1, limit_train_batches=1, limit_val_batches=0)
        runs = list((run_dir / "wandb").glob("offline-run-*"))
        assert len(runs) == 1, sorted(p.name for p in run_dir.rglob("*"))[:20]
        assert list(runs[0].glob("run-*.wandb"))
        train(cfg, resume=True, max_steps=2, limit_train_batches=2, limit_val_batches=0)
        resumed = sorted(p.name for p in (run_dir / "wandb").glob("offline-run-*"))
        assert len(resumed) == 2 and {p.rsplit("-", 1)[1] for p in resumed} == {
            runs[0].name.rsplit("-", 1)[1]}
    finally:
        wandb.finish()
    assert not env_dir.exists() or not any(env_dir.rglob("offline-run-*"))


def test_init_from_weights_of_other_facing_features_is_refused() -> None:
    """Weights trained on smoothed facing frames (``data.preprocessing.
    facing_smooth``) read root features another config would not give
    them: ``--init-from`` says which value to set, in one line; equal
    values, and files without a data section, pass."""
    from satagraph.experiment.config import load_config
    from satagraph.experiment.train import check_init_features

    def payload(smooth: float) -> Dict[str, Any]:
        return {"hyper_parameters": {"meta": {"data": {"preprocessing": {
            "fps": 30.0, "facing_smooth": smooth}}}}}

    cfg = load_config("tiny", [])
    with pytest.raises(ValueError, match=r"^--init-from w.ckpt: trained with "
                       r"data.preprocessing.facing_smooth=0.25, this config has 0; "
                       r"set data.preprocessing.facing_smooth=0.25$"):
        check_init_features(payload(0.25), cfg, "w.ckpt")
    check_init_features(payload(0.0), cfg, "w.ckpt")
    check_init_features({"state_dict": {}}, cfg, "w.ckpt")
    smooth = load_config("tiny", ["data.preprocessing={facing_smooth: 0.25}"])
    check_init_features(payload(0.25), smooth, "w.ckpt")
    # a generator keeps its own autoencoder: the checkpoint's facing is not its data's
    check_init_features(payload(0.0), dict(smooth, module="t2m"), "w.ckpt")


def test_online_wandb_without_a_login_is_one_line_before_any_data(tmp_path, monkeypatch,
                                                                  capsys) -> None:
    monkeypatch.delenv("WANDB_API_KEY", raising=False)
    monkeypatch.delenv("WANDB_MODE", raising=False)
    monkeypatch.setenv("HOME", str(tmp_path))  # no ~/.netrc
    monkeypatch.setenv("NETRC", str(tmp_path / "none"))
    assert main(["train", "tiny", "logger.name=wandb", "logger.offline=false",
                 "data.sources=[nowhere]", f"output_dir={tmp_path / 'run'}"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert "W&B needs a login" in err[-1] and not (tmp_path / "run").exists()


def test_wandb_that_does_not_import_is_one_line_before_any_data(tmp_path, monkeypatch,
                                                                 capsys) -> None:
    """A broken W&B install (its import raises) was a traceback once the
    data had loaded."""
    import sys
    monkeypatch.setitem(sys.modules, "wandb", None)  # `import wandb` raises ImportError
    assert main(["train", "tiny", "logger.name=wandb", "data.sources=[nowhere]",
                 f"output_dir={tmp_path / 'run'}"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("satagraph: error: logger.name=wandb: the "
                                               "wandb package does not import (")
    assert err[0].endswith("pip install wandb, or logger.name=csv")
    assert not (tmp_path / "run").exists()


@pytest.fixture(scope="module")
def trained_run(config_overrides: List[str], tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A run folder of :func:`_train_args` trained by ``satagraph train``,
    once a module, for the tests that only read it (``eval``)."""
    run = tmp_path_factory.mktemp("trained") / "run"
    assert main(_train_args(config_overrides, run)) == 0
    return run


def test_eval_scores_a_manifest_of_test_files_only(trained_run: Path,
                                                   small_manifest: Path, tmp_path: Path,
                                                   capsys: pytest.CaptureFixture) -> None:
    """A trained model carries its statistics: ``eval --data`` needs no
    training files beside the ones it scores."""
    run = trained_run
    rows = small_manifest.read_text().splitlines()
    only_test = tmp_path / "test_only.tsv"
    only_test.write_text("\n".join([rows[0]] + [r for r in rows[1:] if r.endswith("\ttest")]))
    capsys.readouterr()
    assert main(["--traceback", "eval", "--ckpt", str(run / "checkpoints" / "last.ckpt"),
                 "--data", str(only_test)]) == 0
    assert list(_table_rows(capsys.readouterr().out)) == ["bandai", "dog", "all"]


def test_eval_of_one_split_is_not_stopped_by_a_bad_file_of_another(
        trained_run: Path, small_manifest: Path, tmp_path: Path,
        capsys: pytest.CaptureFixture) -> None:
    """``eval --split test`` read every split: a broken training file failed
    it in one line that said to set ``data.on_error=skip``, which ``eval``
    cannot set."""
    run = trained_run
    broken = tmp_path / "broken.bvh"
    broken.write_text("HIERARCHY\nROOT Hips\n{\n")
    rows = small_manifest.read_text().splitlines()
    mended = [rows[0]] + [f"{broken}\t" + r.split("\t", 1)[1] if r.endswith("\ttrain") else r
                          for r in rows[1:]]
    (tmp_path / "bad_train.tsv").write_text("\n".join(mended) + "\n")
    capsys.readouterr()
    assert main(["eval", "--ckpt", str(run), "--data", str(tmp_path / "bad_train.tsv"),
                 "--split", "test"]) == 0
    assert list(_table_rows(capsys.readouterr().out)) == ["bandai", "dog", "all"]
    # scoring the split that holds it: stopped, saying how to go on; --on-error skip goes on
    first = next(i for i, r in enumerate(rows) if r.endswith("\ttrain"))
    one_bad = rows[:first] + [f"{broken}\t" + rows[first].split("\t", 1)[1]] + rows[first + 1:]
    (tmp_path / "one_bad.tsv").write_text("\n".join(one_bad) + "\n")
    args = ["eval", "--ckpt", str(run), "--data", str(tmp_path / "one_bad.tsv"),
            "--split", "train"]
    assert main(args) == 2
    assert "eval --on-error skip" in capsys.readouterr().err
    with pytest.warns(UserWarning, match=r"(?s)data.on_error=skip: left out 1 of 4 .*broken.bvh"):
        assert main(args + ["--on-error", "skip"]) == 0
    assert "all" in _table_rows(capsys.readouterr().out)


def test_a_monitor_of_a_dataset_without_validation_windows_is_refused_first(
        config_overrides: List[str], small_manifest: Path, tmp_path: Path,
        capsys: pytest.CaptureFixture) -> None:
    """``trainer.monitor=val/dog/JP_h`` where no dog file is in the 'val'
    split: the run trained a whole epoch, then stopped in a traceback naming
    every logged key; now one line before any step, after a warning that
    says which dataset goes unvalidated."""
    rows = small_manifest.read_text().splitlines()
    no_dog_val = tmp_path / "no_dog_val.tsv"
    no_dog_val.write_text("\n".join(r[:-len("val")] + "train" if "\tdog\t" in r
                                    and r.endswith("\tval") else r for r in rows) + "\n")
    overrides = [o for o in config_overrides if not o.startswith("data.sources")]
    run = tmp_path / "run"
    with pytest.warns(UserWarning, match="no validation windows of 'dog'"):
        assert main(_train_args(overrides + [f"data.sources=[{no_dog_val}]"], run,
                                "trainer.monitor=val/dog/JP_h")[1:]) == 2  # no --traceback
    err = capsys.readouterr().err
    assert err.strip().splitlines()[-1] == (
        "satagraph: error: trainer.monitor=val/dog/JP_h: no validation window is of "
        "dataset 'dog' (validation datasets: bandai)")
    assert not (run / "checkpoints").exists()


def test_train_data_names_the_folders_to_train_on(config_overrides: List[str],
                                                  small_manifest: Path, tmp_path: Path,
                                                  capsys: pytest.CaptureFixture) -> None:
    """``train CONFIG --data PATH`` (as ``eval`` and ``demo`` take it) in place of
    ``data.sources``; overrides after it stay overrides."""
    run = tmp_path / "run"
    args = _train_args([o for o in config_overrides if not o.startswith("data.sources")],
                       run)
    assert main(args[:3] + ["--data", str(small_manifest)] + args[3:]) == 0
    ckpt = torch.load(run / "checkpoints" / "last.ckpt", weights_only=True)
    assert ckpt["hyper_parameters"]["meta"]["data"]["sources"] == [str(small_manifest)]


def test_the_epochs_a_run_trained_are_counted_from_its_steps() -> None:
    """A run that ``trainer.max_time`` stopped 0.6 of the way into its second
    epoch was said to have trained "for 2 epochs"."""
    from types import SimpleNamespace
    from satagraph.cli.train import _epochs_done
    run = SimpleNamespace(num_training_batches=23, accumulate_grad_batches=1,
                          global_step=37, current_epoch=2)
    assert _epochs_done(run) == "1.6 epochs"
    assert _epochs_done(SimpleNamespace(**dict(vars(run), global_step=23))) == "1 epoch"
    assert _epochs_done(SimpleNamespace(**dict(vars(run), global_step=46))) == "2 epochs"
    assert _epochs_done(SimpleNamespace(**dict(vars(run), num_training_batches=float("inf")))) \
        == "epoch 2"


def test_a_run_stopped_before_its_first_validation_is_not_warned_of_val_loss(
        tiny_config: Dict[str, Any], recwarn: pytest.WarningsRecorder) -> None:
    """A run that ends within its first epoch (``trainer.max_steps``, ``sweep
    --steps`` shorter than an epoch) has no best epoch to keep: Lightning's
    best checkpoint warned that it could not find ``val_loss``, naming every
    logged key (about 2,000 characters, once per sweep row)."""
    cfg = dict(tiny_config, logger={"name": "none"})
    _, _, trainer, run_dir = train(cfg, max_steps=1, limit_train_batches=2)
    assert trainer.global_step == 1 and (run_dir / "checkpoints" / "last.ckpt").is_file()
    assert not [w for w in recwarn if "monitored key" in str(w.message)]
