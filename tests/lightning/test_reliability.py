"""Training that cannot end green with a broken model, exact resume after
``kill -9``, safe loading, one live run per output folder."""
from __future__ import annotations

import contextlib
import copy
import errno
import os
import pickle
import random
import re
import signal
import subprocess
import sys
import time
import warnings
from pathlib import Path
from typing import Any, Dict, List

import lightning as L
import pytest
import torch

from satagraph.cli import main
from satagraph.experiment.config import load_config
from satagraph.datasets.zoo import write_zoo
from satagraph.io.checkpoint import CheckpointError, load_checkpoint
from satagraph.lightning import reliability
from satagraph.lightning.reliability import (LAST, PREVIOUS, RunLockedError,
                                             TrainingStopped, read_loss_log,
                                             resume_checkpoint, run_lock)
from satagraph.experiment import train as train_mod
from satagraph.experiment.train import load_module, train

REPO = Path(__file__).resolve().parents[2]
EVERY = 4  # steps between checkpoints in the resume test


@pytest.fixture(scope="module")
def zoo_overrides(tmp_path_factory: pytest.TempPathFactory) -> List[str]:
    """Overrides of ``tiny`` for a deterministic CPU run on a small zoo:
    9 steps per epoch, a checkpoint every :data:`EVERY` steps, one thread,
    deterministic algorithms, every step's loss logged."""
    root = tmp_path_factory.mktemp("reszoo")
    write_zoo(root / "zoo", species=["biped", "quadruped"], clips=3, frames=48)
    return [f"data.sources=[{root / 'zoo' / 'manifest.tsv'}]",
            f"data.cache_dir={root / 'cache'}", "data.window=16", "data.stride=16",
            "data.batch_size=4", "data.max_files=null", "data.augment.scale=0.5",
            "model.dropout=0.1", "logger.name=none", "trainer.progress=false",
            "trainer.enable_model_summary=false", "trainer.max_epochs=2",
            "trainer.limit_train_batches=null", "trainer.limit_val_batches=1",
            "trainer.num_sanity_val_steps=0", "trainer.deterministic=true", "threads=1",
            f"checkpoint.every_n_steps={EVERY}", "loss_log=true"]


def _kill_at(cmd: List[str], log: Path, step: int, env: Dict[str, str]) -> int:
    """Run :obj:`cmd`, ``kill -9`` it once :obj:`log` has :obj:`step`
    lines; returns the last step it logged."""
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 240
    while time.monotonic() < deadline and proc.poll() is None:
        if log.is_file() and len(log.read_text().splitlines()) >= step:
            break
        time.sleep(0.02)
    assert proc.poll() is None, f"the run ended before step {step}: {proc.stderr.read()}"
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    return max(read_loss_log(log))


@pytest.mark.slow
def test_kill9_then_resume_gives_the_same_losses(zoo_overrides: List[str],
                                                 tmp_path: Path) -> None:
    """A real training process killed at a random step; ``--resume``
    continues with bit-identical losses, losing at most one checkpoint
    interval. Deterministic CPU settings: ``threads=1``,
    ``trainer.deterministic=true`` (and ``OMP_NUM_THREADS=1``)."""
    reference = load_config("tiny", zoo_overrides + [f"output_dir={tmp_path / 'a'}"])
    train(reference)
    full = read_loss_log(tmp_path / "a" / "losses.tsv")
    assert len(full) == 18

    run = tmp_path / "b"
    cmd = [sys.executable, "-m", "satagraph", "train", "tiny", *zoo_overrides,
           f"output_dir={run}"]
    env = dict(os.environ, OMP_NUM_THREADS="1", PYTHONPATH=str(REPO))
    kill_step = random.Random().randint(EVERY + 1, len(full) - 2)
    killed = _kill_at(cmd, run / "losses.tsv", kill_step, env)
    saved = load_checkpoint(run / "checkpoints" / LAST)["global_step"]
    assert saved > 0 and 0 <= killed - saved <= EVERY  # at most one interval lost

    assert main(["train", "tiny", *zoo_overrides, f"output_dir={run}", "--resume"]) == 0
    resumed = read_loss_log(run / "losses.tsv")
    assert resumed == full, (kill_step, saved)


class _StopAt(L.Callback):
    """Stops training after step :obj:`step`, as Lightning's ``max_time``
    timer does when time is up (``trainer.should_stop``)."""

    def __init__(self, step: int) -> None:
        self.step = step

    def on_train_batch_end(self, trainer: L.Trainer, *args: Any) -> None:
        if trainer.global_step >= self.step:
            trainer.should_stop = True


@pytest.mark.slow
@pytest.mark.parametrize("stop", ["max_time", "max_steps"])
def test_a_run_stopped_inside_an_epoch_resumes_with_the_same_losses(
        zoo_overrides: List[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        stop: str) -> None:
    """Stopped at step 4 of a 9-step epoch, by the clock (a callback
    setting ``should_stop``, as the ``max_time`` timer does) or by
    ``max_steps``, then resumed: the epoch's remaining batches are trained
    and every loss is the one a run never stopped gives, bit for bit."""
    reference = load_config("tiny", zoo_overrides + [f"output_dir={tmp_path / 'a'}"])
    train(reference)
    full = read_loss_log(tmp_path / "a" / "losses.tsv")
    cfg = load_config("tiny", zoo_overrides + [f"output_dir={tmp_path / 'b'}"])
    if stop == "max_time":
        build = train_mod.build_trainer

        def stopping(*args: Any, **kwargs: Any) -> L.Trainer:
            trainer = build(*args, **kwargs)
            trainer.callbacks.insert(0, _StopAt(4))
            return trainer

        with monkeypatch.context() as patch:
            patch.setattr(train_mod, "build_trainer", stopping)
            train(cfg)
    else:
        train(cfg, max_steps=4)
    assert max(read_loss_log(tmp_path / "b" / "losses.tsv")) == 4
    train(cfg, resume=True)
    assert read_loss_log(tmp_path / "b" / "losses.tsv") == full


def test_nonfinite_loss_stops_naming_files_and_keeps_the_checkpoint(
        tiny_config: Dict[str, Any], monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture) -> None:
    from satagraph.lightning.autoencoder import MotionAutoencoderModule
    original = MotionAutoencoderModule.compute_losses

    poison = {"from": 2}

    def poisoned(self, out, batch):
        losses = original(self, out, batch)
        if self.global_step >= poison["from"] or self.global_step in poison.get("at", ()):
            losses["loss"] = losses["loss"] * float("nan")
        return losses

    monkeypatch.setattr(MotionAutoencoderModule, "compute_losses", poisoned)
    cfg = dict(tiny_config, checkpoint={"every_n_steps": 1})
    with pytest.raises(TrainingStopped, match=r"step 2: non-finite loss.*\.bvh") as info:
        train(cfg)
    last = Path(cfg["output_dir"]) / "checkpoints" / LAST
    assert str(last) in str(info.value)
    ckpt = load_checkpoint(last)
    assert ckpt["global_step"] == 2
    assert all(torch.isfinite(v).all() for v in ckpt["state_dict"].values()
               if v.is_floating_point())

    # skip: the bad batches (not an epoch's in a row) are counted, the weights stay finite
    poison.update({"from": 99, "at": (1, 3)})
    cfg = dict(copy.deepcopy(tiny_config), nonfinite="skip")
    cfg["output_dir"] += "-skip"
    with pytest.warns(UserWarning, match=r"weight update of 2 batch\(es\).*step\(s\) 2, 4 \("):
        module, _, trainer, _ = train(cfg, max_steps=4)
    assert all(torch.isfinite(p).all() for p in module.parameters())


def test_skip_stops_a_run_that_gives_no_finite_loss_any_more(
        tiny_config: Dict[str, Any], monkeypatch: pytest.MonkeyPatch) -> None:
    """``nonfinite=skip`` on a diverged model (every loss non-finite from
    step 1: an absurd learning rate) stops where an epoch's worth of
    batches in a row (here 2) was skipped; it skipped every batch to the
    end and said 'trained ... for N epochs', exit 0."""
    from satagraph.lightning.autoencoder import MotionAutoencoderModule
    original = MotionAutoencoderModule.compute_losses

    def diverged(self, out, batch):
        losses = original(self, out, batch)
        if self.global_step >= 1:
            losses["loss"] = losses["loss"] * float("nan")
        return losses

    monkeypatch.setattr(MotionAutoencoderModule, "compute_losses", diverged)
    cfg = dict(tiny_config, nonfinite="skip")
    cfg["trainer"] = dict(cfg["trainer"], max_epochs=5)
    with pytest.raises(TrainingStopped, match=r"step 2: 2 batches in a row had a non-finite "
                       r"loss.*\.bvh: the model has diverged; last checkpoint: .*last\.ckpt"):
        train(cfg)
    ckpt = load_checkpoint(Path(cfg["output_dir"]) / "checkpoints" / LAST)
    assert ckpt["global_step"] == 2


def test_skip_says_in_one_line_which_steps_it_skipped(
        config_overrides: List[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``satagraph train ... nonfinite=skip`` ends with one
    ``satagraph: warning:`` line naming the skipped steps; Lightning,
    imported after the command began, had replaced the warning format, so
    it came out as ``.../lightning/pytorch/trainer/call.py:228: ...``."""
    import warnings

    from lightning.fabric.utilities.warnings import _custom_format_warning
    from satagraph.lightning.autoencoder import MotionAutoencoderModule
    original = MotionAutoencoderModule.compute_losses

    def poisoned(self, out, batch):
        warnings.formatwarning = _custom_format_warning  # Lightning's import, mid-command
        losses = original(self, out, batch)
        if self.global_step == 1:
            losses["loss"] = losses["loss"] * float("nan")
        return losses

    shown: List[str] = []

    def show(message, category, filename, lineno, file=None, line=None):
        shown.append(warnings.formatwarning(message, category, filename, lineno, line))

    monkeypatch.setattr(MotionAutoencoderModule, "compute_losses", poisoned)
    monkeypatch.setattr(warnings, "showwarning", show)
    assert main(["train", "tiny", *config_overrides, "nonfinite=skip", "trainer.max_epochs=1",
                 "trainer.limit_val_batches=0", f"output_dir={tmp_path / 'run'}"]) == 0
    skipped = [line for line in shown if "nonfinite=skip" in line]
    assert skipped == ["satagraph: warning: nonfinite=skip: skipped the weight update of 1 "
                       "batch(es) with a non-finite loss or gradient, at step(s) 2 (as losses.tsv "
                       "numbers them)\n"]


def test_cli_train_exit_code_when_stopped(tiny_config: Dict[str, Any], tmp_path: Path,
                                          monkeypatch: pytest.MonkeyPatch,
                                          capsys: pytest.CaptureFixture) -> None:
    import satagraph.experiment.train as train_mod

    def stopped(*args, **kwargs):
        raise TrainingStopped("training stopped at step 3: non-finite loss")

    monkeypatch.setattr(train_mod, "train", stopped)
    assert main(["train", "tiny", f"output_dir={tmp_path}"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("satagraph: error: training stopped") and "Traceback" not in err


def test_resume_falls_back_from_a_truncated_last_checkpoint(
        tiny_config: Dict[str, Any]) -> None:
    cfg = dict(tiny_config, checkpoint={"every_n_steps": 1})
    train(cfg, max_steps=2)
    folder = Path(cfg["output_dir"]) / "checkpoints"
    assert load_checkpoint(folder / PREVIOUS)["global_step"] == 1
    data = (folder / LAST).read_bytes()
    (folder / LAST).write_bytes(data[: len(data) // 2])
    with pytest.warns(UserWarning, match="resuming from the previous"):
        assert resume_checkpoint(folder) == folder / PREVIOUS
    assert (folder / "last.damaged.ckpt").is_file() and not (folder / LAST).exists()
    (folder / LAST).write_bytes(b"")
    (folder / PREVIOUS).write_bytes(b"")
    [best] = folder.glob("epoch=*.ckpt")
    with pytest.warns(UserWarning, match="resuming from its newest epoch checkpoint"):
        assert resume_checkpoint(folder) == best
    best.write_bytes(b"")
    with pytest.raises(CheckpointError, match="no usable checkpoint"):
        resume_checkpoint(folder)


def test_a_second_damaged_last_checkpoint_replaces_the_first(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Windows renames onto no existing file: the second resume from a
    damaged ``last.ckpt`` failed there with ``FileExistsError``."""
    def windows_rename(self: Path, target: Any) -> Path:
        if Path(target).exists():
            raise FileExistsError(183, "Cannot create a file when that file already "
                                  "exists", str(self), None, str(target))
        return os.rename(self, target) or Path(target)
    monkeypatch.setattr(Path, "rename", windows_rename)
    torch.save({"state_dict": {}, "loops": {}, "optimizer_states": []}, tmp_path / PREVIOUS)
    (tmp_path / "last.damaged.ckpt").write_bytes(b"PK first")
    (tmp_path / LAST).write_bytes(b"PK second")
    with pytest.warns(UserWarning, match="resuming from the previous"):
        assert resume_checkpoint(tmp_path) == tmp_path / PREVIOUS
    assert (tmp_path / "last.damaged.ckpt").read_bytes() == b"PK second"


def test_resume_after_a_truncated_first_last_checkpoint_goes_on_from_the_epoch_one(
        tiny_config: Dict[str, Any]) -> None:
    """The first epoch's ``last.ckpt`` truncated (a crash; no
    ``last.prev.ckpt`` yet): ``--resume`` goes on from that epoch's own
    checkpoint, the damaged file moved aside (it said 'no usable
    checkpoint', the epoch checkpoint beside it unused)."""
    cfg = copy.deepcopy(tiny_config)
    cfg["trainer"]["max_epochs"] = 1
    train(cfg)
    folder = Path(cfg["output_dir"]) / "checkpoints"
    [best] = folder.glob("epoch=*.ckpt")
    assert not (folder / PREVIOUS).exists()
    data = (folder / LAST).read_bytes()
    (folder / LAST).write_bytes(data[: len(data) // 3])
    cfg["trainer"]["max_epochs"] = 2
    with pytest.warns(UserWarning, match=f"resuming from its newest epoch checkpoint {best}"):
        _, _, trainer, _ = train(cfg, resume=True)
    assert trainer.current_epoch == 2 and trainer.global_step == 4
    assert (folder / "last.damaged.ckpt").read_bytes() == data[: len(data) // 3]
    assert load_checkpoint(folder / LAST)["global_step"] == 4


@pytest.mark.slow
def test_epoch_end_checkpoint_knows_that_epochs_best(tiny_config: Dict[str, Any]) -> None:
    """``last.ckpt`` is written after the best checkpoint at an epoch's
    end: resumed from it, a run compares later epochs with that epoch's and
    leaves no best checkpoint behind that it no longer tracks."""
    train(tiny_config, max_epochs=1)
    folder = Path(tiny_config["output_dir"]) / "checkpoints"
    (best,) = folder.glob("epoch=*.ckpt")
    callbacks = load_checkpoint(folder / LAST)["callbacks"]
    state = next(v for k, v in callbacks.items() if k.startswith("ModelCheckpoint"))
    assert Path(state["best_model_path"]) == best
    train(tiny_config, resume=True, max_epochs=3)
    assert len(list(folder.glob("epoch=*.ckpt"))) == 1


@pytest.mark.parametrize("first", [2] + [pytest.param(f, marks=pytest.mark.slow) for f in (1, 3)])
def test_a_run_bounded_by_steps_resumes_as_far_as_one_never_stopped(
        tiny_config: Dict[str, Any], first: int) -> None:
    """Stopped by ``max_steps`` at an epoch's end (step 2, 2 batches an
    epoch) or inside one (step 1, step 3 of the last), then resumed with
    ``max_steps=4``, a run ends where one never stopped ends. Lightning 2.6
    alone ends each short: it takes a finished epoch for an unfinished one
    (Lightning-AI/pytorch-lightning#19617) and counts one cut short as
    finished."""
    whole = dict(tiny_config, output_dir=tiny_config["output_dir"] + "_whole")
    _, _, never_stopped, _ = train(whole, max_steps=4, max_epochs=2)
    train(tiny_config, max_steps=first, max_epochs=2)
    _, _, resumed, _ = train(tiny_config, resume=True, max_steps=4, max_epochs=2)
    assert never_stopped.global_step == 4 and resumed.max_steps == 4
    assert (resumed.global_step, resumed.current_epoch) == (4, never_stopped.current_epoch)


@pytest.mark.slow
def test_keep_every_epoch_keeps_one_checkpoint_per_epoch(tiny_config: Dict[str, Any]) -> None:
    """``checkpoint.keep_every_epoch`` keeps each epoch's end, across a
    resume, each holding the weights of its own step."""
    tiny_config["checkpoint"]["keep_every_epoch"] = True
    train(tiny_config, max_epochs=2)
    train(tiny_config, resume=True, max_epochs=3)
    folder = Path(tiny_config["output_dir"]) / "checkpoints"
    kept = sorted(folder.glob("epoch=*.ckpt"))
    assert [p.name.split("-")[0] for p in kept] == ["epoch=0", "epoch=1", "epoch=2"]
    steps = [load_checkpoint(p)["global_step"] for p in kept]
    assert steps[0] < steps[1] < steps[2] == load_checkpoint(folder / LAST)["global_step"]
    first, last = (load_checkpoint(p)["state_dict"] for p in (kept[0], kept[2]))
    assert any(not torch.equal(first[k], last[k]) for k in first)


def test_a_live_run_holds_its_output_dir(tmp_path: Path) -> None:
    with run_lock(tmp_path):
        with pytest.raises(RunLockedError, match=f"pid {os.getpid()}"):
            with run_lock(tmp_path):
                pass
    with run_lock(tmp_path):  # released: free again
        pass


class _FakeMsvcrt:
    """``msvcrt.locking`` as Windows does it: a byte range of a file, held
    by one descriptor; another one's non-blocking lock fails with EACCES."""
    LK_UNLCK, LK_NBLCK = 0, 2

    def __init__(self) -> None:
        self.held: Dict[Any, int] = {}

    def locking(self, fd: int, mode: int, nbytes: int) -> None:
        key = (os.fstat(fd).st_ino, os.lseek(fd, 0, os.SEEK_CUR), nbytes)
        if mode == self.LK_UNLCK:
            assert self.held.pop(key) == fd
        elif self.held.setdefault(key, fd) != fd:
            raise OSError(errno.EACCES, "Permission denied")


def test_the_run_lock_works_without_fcntl(tmp_path: Path,
                                          monkeypatch: pytest.MonkeyPatch) -> None:
    """Windows has no ``fcntl``: ``satagraph train`` failed there with
    "needs the Python package 'fcntl', which is not installed"."""
    monkeypatch.setitem(sys.modules, "fcntl", None)  # import fcntl: ImportError
    fake = _FakeMsvcrt()
    monkeypatch.setitem(sys.modules, "msvcrt", fake)
    with run_lock(tmp_path) as lock:
        assert fake.held
        with pytest.raises(RunLockedError, match=f"pid {os.getpid()}"):
            with run_lock(tmp_path):
                pass
        assert lock.read_text().startswith(f"pid {os.getpid()} ")
    assert not fake.held  # released
    with run_lock(tmp_path):
        pass


def test_a_run_that_made_nothing_leaves_no_folder(tmp_path: Path) -> None:
    """The folders a run made go again when it leaves nothing but its lock
    (a run refused before its first step); folders that were there, or that
    hold something, stay."""
    made = tmp_path / "runs" / "tiny"
    with run_lock(made):
        pass
    assert not (tmp_path / "runs").exists()
    with run_lock(made):
        (made / "losses.tsv").write_text("step\n")
    assert (made / "losses.tsv").is_file()
    kept = tmp_path / "kept"
    kept.mkdir()
    with run_lock(kept):
        pass
    assert kept.is_dir()


def test_a_lock_removed_between_open_and_lock_is_taken_anew(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A run refused before its first step removes ``.lock`` and the folder
    it made; a second run that had opened ``.lock`` just before then locked
    the removed file, and a third made a new ``.lock`` and took the folder
    too: two runs each held it."""
    made = tmp_path / "runs" / "tiny"
    first = contextlib.ExitStack()
    first.enter_context(run_lock(made))
    taken, ended = reliability.lock_fd, []

    def first_ends_meanwhile(fd: int, take: bool = True) -> bool:
        if take and not ended:  # the second run has .lock open
            ended.append(first.close())  # drops .lock and runs/, then releases
        return taken(fd, take)
    monkeypatch.setattr(reliability, "lock_fd", first_ends_meanwhile)
    with run_lock(made) as lock:
        assert ended
        with pytest.raises(RunLockedError, match=f"pid {os.getpid()}"):
            with run_lock(made):  # the third
                pass
        assert lock.is_file()
    assert not (tmp_path / "runs").exists()  # the folders it made again go again


class _Payload:
    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self):
        return (os.system, (f"touch {self.marker}",))


def test_loading_is_safe_and_errors_are_one_line(
        tiny_config: Dict[str, Any], tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture) -> None:
    monkeypatch.setenv("TORCH_FORCE_NO_WEIGHTS_ONLY_LOAD", "1")
    marker = tmp_path / "pwned"
    evil = tmp_path / "evil.ckpt"
    torch.save({"state_dict": _Payload(marker)}, evil)  # a planted pickle
    raw = tmp_path / "raw.ckpt"
    with open(raw, "wb") as f:
        pickle.dump({"state_dict": _Payload(marker)}, f)
    good = tmp_path / "good.ckpt"
    torch.save({"state_dict": {"w": torch.zeros(2)}, "hyper_parameters": {}}, good)
    truncated = tmp_path / "cut.ckpt"
    truncated.write_bytes(good.read_bytes()[:100])
    text = tmp_path / "walk.bvh"
    text.write_text("HIERARCHY\n")
    cases = {evil: "safe loading refuses", raw: "not a readable checkpoint", truncated: "not a readable checkpoint",
             text: "not a readable checkpoint", good: "no model hyperparameters",
             tmp_path: "a folder without checkpoints/last.ckpt"}
    write_zoo(tmp_path / "zoo", species=["biped"], clips=1, frames=16)
    clip = next((tmp_path / "zoo").rglob("*.bvh"))  # a good input: the model is what fails
    for path, words in cases.items():
        code = main(["reconstruct", "--ckpt", str(path), str(clip), str(tmp_path / "o.bvh")])
        err = capsys.readouterr().err
        assert code == 2 and err.count("\n") == 1, err
        assert err.startswith(f"satagraph: error: {path}") and words in err, err
        assert "weights_only" not in err and "Traceback" not in err
    assert not marker.exists()

    # --resume loads the run's own last.ckpt safely too
    run = Path(tiny_config["output_dir"]) / "checkpoints"
    run.mkdir(parents=True)
    (run / LAST).write_bytes(evil.read_bytes())
    with pytest.raises(CheckpointError, match="safe loading refuses"):
        train(tiny_config, resume=True)
    assert not marker.exists()


def test_diverged_weights_are_refused(tiny_config: Dict[str, Any], tmp_path: Path) -> None:
    train(tiny_config, max_steps=1)
    last = Path(tiny_config["output_dir"]) / "checkpoints" / LAST
    ckpt = load_checkpoint(last)
    key = next(k for k, v in ckpt["state_dict"].items() if k.startswith("model."))
    ckpt["state_dict"][key] = ckpt["state_dict"][key] * float("nan")
    bad = tmp_path / "nan.ckpt"
    torch.save(ckpt, bad)
    with pytest.raises(CheckpointError, match="non-finite"):
        load_module(str(bad))


def test_loss_log_keeps_the_wall_clock_and_reads_old_files(tmp_path: Path) -> None:
    """``losses.tsv`` lines carry the time of the step (the x axis of a
    learning curve against wall time); files written before without it
    still read, and the last line of a replayed step counts."""
    from types import SimpleNamespace
    from satagraph.lightning.reliability import LossLog, read_loss_times
    path = tmp_path / "losses.tsv"
    path.write_text("1\t2.5\n")  # an old line, no time
    log = LossLog(str(path))
    trainer = SimpleNamespace(global_step=2, is_global_zero=True)
    before = time.time()
    log.on_train_batch_end(trainer, None, {"loss": torch.tensor(1.25)}, None, 0)
    trainer.global_step = 3
    log.on_train_batch_end(trainer, None, torch.tensor(0.5), None, 1)
    assert read_loss_log(path) == {1: 2.5, 2: 1.25, 3: 0.5}
    times = read_loss_times(path)
    assert sorted(times) == [2, 3] and before - 1 <= times[2] <= times[3] <= time.time() + 1


def test_a_loss_line_a_full_disk_cuts_short_is_taken_back(tmp_path: Path,
                                                         file_size_limit) -> None:
    """The file system refusing a ``losses.tsv`` line half-way (a full disk;
    here the file size limit): the error names the file (it said ``[Errno
    28] No space left on device`` alone), and the half line is taken back,
    so the resumed run's replay of that step is a line of its own (it ran
    on from the half line: a cut loss, or a loss read as the time)."""
    from types import SimpleNamespace
    from satagraph.lightning.reliability import LossLog
    path = tmp_path / "losses.tsv"
    log = LossLog(str(path))
    trainer = SimpleNamespace(global_step=1, is_global_zero=True)
    log.on_train_batch_end(trainer, None, torch.tensor(2.5), None, 0)
    first = path.read_text()
    trainer.global_step = 2
    with file_size_limit(len(first) + 6), pytest.raises(OSError) as err:
        log.on_train_batch_end(trainer, None, torch.tensor(1.0 / 3.0), None, 1)
    assert path.read_text() == first
    assert err.value.filename == str(path)
    log.on_train_batch_end(trainer, None, torch.tensor(1.0 / 3.0), None, 1)  # the replay
    assert read_loss_log(path) == {1: 2.5, 2: float(torch.tensor(1.0 / 3.0))}


@pytest.mark.slow
def test_ema_checkpoints_the_average_and_resumes_the_trained_weights(
        tiny_config: Dict[str, Any]) -> None:
    """``optim.ema``: every checkpoint's ``state_dict`` (what loading and
    ``--init-from`` read) is the moving average, the optimiser's weights go
    on in ``current_model_state``; ``--resume`` takes both back."""
    decay = 0.5
    cfg = dict(copy.deepcopy(tiny_config), checkpoint={"every_n_steps": 1})
    cfg["optim"] = dict(cfg.get("optim") or {}, ema=decay)
    cfg["trainer"] = dict(cfg["trainer"], limit_train_batches=4)  # steps 1-3: one epoch
    train(cfg, max_steps=2)
    folder = Path(cfg["output_dir"]) / "checkpoints"
    first, second = load_checkpoint(folder / PREVIOUS), load_checkpoint(folder / LAST)
    assert (first["global_step"], second["global_step"]) == (1, 2)
    # step 1: the average starts at the weights; step 2: d * avg + (1 - d) * weights
    name = next(k for k, v in second["state_dict"].items()
                if v.is_floating_point() and not torch.equal(
                    v, first["current_model_state"][k]))
    expected = (decay * first["current_model_state"][name]
                + (1 - decay) * second["current_model_state"][name])
    torch.testing.assert_close(first["state_dict"][name], first["current_model_state"][name])
    torch.testing.assert_close(second["state_dict"][name], expected)
    assert not torch.equal(second["state_dict"][name], second["current_model_state"][name])
    module = load_module(str(folder / LAST))
    torch.testing.assert_close(module.state_dict()[name], expected)

    module, _, trainer, _ = train(cfg, resume=True, max_steps=3)
    assert trainer.global_step == 3
    third = load_checkpoint(folder / LAST)
    torch.testing.assert_close(
        third["state_dict"][name],
        decay * expected + (1 - decay) * third["current_model_state"][name])


@pytest.mark.parametrize("decay", [1.0, -0.1])
def test_ema_outside_its_range_is_one_line(tiny_config: Dict[str, Any], decay: float) -> None:
    cfg = dict(copy.deepcopy(tiny_config), optim={"ema": decay})
    with pytest.raises(ValueError, match=r"optim.ema must be 0 \(none\) or a decay in"):
        train(cfg, max_steps=1)


def test_a_run_without_validation_data_says_so_once(tiny_config: Dict[str, Any],
                                                     small_manifest: Path) -> None:
    """Sources whose files are all in 'train': one warning naming them, no
    validation loop, and the run ends with its checkpoints."""
    rows = small_manifest.read_text().splitlines()
    only_train = small_manifest.parent / "train_only.tsv"
    only_train.write_text("\n".join([rows[0]] + [r for r in rows[1:]
                                                 if r.endswith("\ttrain")]) + "\n")
    cfg = copy.deepcopy(tiny_config)
    cfg["data"]["sources"] = [str(only_train)]
    cfg["trainer"].update(max_epochs=1, limit_train_batches=1)
    with pytest.warns(UserWarning, match="no validation windows") as caught:
        _, dm, trainer, run_dir = train(cfg)
    assert not len(dm.datasets["val"]) and len(dm.datasets["train"])
    assert not any("could not find the monitored key" in str(w.message) for w in caught)
    assert trainer.global_step == 1
    assert (run_dir / "checkpoints" / "last.ckpt").is_file()


def test_a_new_run_never_replaces_a_trained_one(tiny_config: Dict[str, Any]) -> None:
    """Training again into a folder that holds a run, without ``--resume``,
    is refused in one line; its checkpoints and loss log stay as they were."""
    cfg = copy.deepcopy(tiny_config)
    cfg["trainer"].update(max_epochs=1, limit_train_batches=1)
    cfg["loss_log"] = True
    _, _, _, run_dir = train(cfg)
    last = run_dir / "checkpoints" / LAST
    before = last.read_bytes(), (run_dir / "losses.tsv").read_text()
    with pytest.raises(ValueError, match="holds a trained run .*--resume continues it"):
        train(cfg)
    assert (last.read_bytes(), (run_dir / "losses.tsv").read_text()) == before


def test_a_run_that_ends_while_another_starts_is_not_replaced(
        tiny_config: Dict[str, Any], monkeypatch: pytest.MonkeyPatch) -> None:
    """Two ``train`` on one folder: the second looked for a trained run
    before it took the lock, so a first that saved its checkpoint and ended
    in between (while ``--init-from`` loaded) was trained over."""
    run_dir = Path(tiny_config["output_dir"])
    taken = train_mod._lock

    def first_run_ends_meanwhile(folder: Path):
        (folder / "checkpoints").mkdir(parents=True)
        (folder / "checkpoints" / LAST).write_bytes(b"the first run's")
        return taken(folder)
    monkeypatch.setattr(train_mod, "_lock", first_run_ends_meanwhile)
    with pytest.raises(ValueError, match="holds a trained run .*--resume continues it"):
        train(copy.deepcopy(tiny_config))
    assert (run_dir / "checkpoints" / LAST).read_bytes() == b"the first run's"


@pytest.fixture(scope="module")
def one_step_run(_base_config: Dict[str, Any],
                 tmp_path_factory: pytest.TempPathFactory) -> Dict[str, Any]:
    """The config of a one-epoch, one-batch run, trained once a module for
    the resumes refused before they touch it."""
    cfg = copy.deepcopy(_base_config)
    cfg["output_dir"] = str(tmp_path_factory.mktemp("one_step") / "run")
    cfg["trainer"].update(max_epochs=1, limit_train_batches=1)
    train(cfg)
    return cfg


@pytest.mark.parametrize("change, said", [
    ({"model": {"hidden_channels": 48}}, "model.hidden_channels=32 (here 48)"),
    ({"data": {"sources": ["elsewhere"]}}, "data.sources="),
    # the optimiser resumed with its own learning rate while W&B logged the new one
    ({"optim": {"lr": 0.0005}}, "(here 0.0005: a resume keeps the optimiser's own state)"),
])
def test_resume_with_another_model_or_data_is_refused(one_step_run: Dict[str, Any],
                                                      change: Dict[str, Any], said: str) -> None:
    """``--resume`` with other model settings (a 133-line size mismatch) or
    other data (silently re-recorded): one line, the run untouched."""
    cfg, run_dir = one_step_run, Path(one_step_run["output_dir"])
    before = (run_dir / "checkpoints" / LAST).read_bytes()
    other = copy.deepcopy(cfg)
    for section, values in change.items():
        other[section].update(values)
    with pytest.raises(ValueError, match=re.escape(said)):
        train(other, resume=True)
    assert (run_dir / "checkpoints" / LAST).read_bytes() == before


def test_ctrl_c_is_given_back_as_an_interrupt(tiny_config: Dict[str, Any]) -> None:
    """Lightning ends a Ctrl-C with ``exit(1)`` and leaves Ctrl-C ignored:
    ``train`` gives the interrupt back (the command then says how to resume,
    exit 130) with the process's own Ctrl-C handler."""
    class Interrupt(L.Callback):
        def on_train_batch_start(self, *args) -> None:
            raise KeyboardInterrupt

    cfg = copy.deepcopy(tiny_config)
    before = signal.getsignal(signal.SIGINT)
    with pytest.raises(KeyboardInterrupt):
        train(cfg, callbacks=[Interrupt()])
    assert signal.getsignal(signal.SIGINT) is before


@pytest.mark.slow
def test_skipped_files_are_listed_and_the_list_goes_once_they_read(
        tiny_config: Dict[str, Any], tmp_path: Path) -> None:
    """``data.on_error=skip``: the run lists what it left out in
    ``skipped_files.txt``; resumed after the file was mended, the list goes."""
    from satagraph.datasets.zoo import write_zoo
    write_zoo(tmp_path / "zoo", species=["biped"], clips=3, frames=40)
    victim = sorted((tmp_path / "zoo").rglob("*.bvh"))[0]
    good = victim.read_text()
    victim.write_text(good[: len(good) // 2])
    cfg = copy.deepcopy(tiny_config)
    cfg["data"].update(sources=[str(tmp_path / "zoo")], on_error="skip", max_files=None)
    cfg["trainer"].update(max_epochs=1, limit_train_batches=1)
    with pytest.warns(UserWarning, match="left out 1 of"):
        _, _, _, run_dir = train(cfg)
    listed = (run_dir / "skipped_files.txt").read_text()
    assert victim.name in listed and len(listed.splitlines()) == 1
    victim.write_text(good)
    cfg["trainer"].update(max_epochs=2)
    train(cfg, resume=True)
    assert not (run_dir / "skipped_files.txt").exists()


class _InterruptAt(L.Callback):
    """Ctrl-C at step :obj:`step`: as the next batch starts (``start``), in
    its backward pass (``backward``: its forward pass has drawn its
    dropout), in the validation after it (``validation``) or at the end of
    the epoch that step ends (``epoch_end``, before the epoch-end save);
    :obj:`then` runs first."""

    def __init__(self, step: int, where: str = "backward", then: Any = None) -> None:
        self.step, self.where, self.then = step, where, then

    def on_train_batch_start(self, trainer: L.Trainer, *args: Any) -> None:
        self._stop(trainer, "start")

    def on_before_backward(self, trainer: L.Trainer, *args: Any) -> None:
        self._stop(trainer, "backward")

    def on_train_epoch_end(self, trainer: L.Trainer, *args: Any) -> None:
        self._stop(trainer, "epoch_end")

    def on_validation_batch_start(self, trainer: L.Trainer, *args: Any) -> None:
        if not trainer.sanity_checking:
            self._stop(trainer, "validation")

    def _stop(self, trainer: L.Trainer, where: str) -> None:
        if where == self.where and trainer.global_step == self.step:
            if self.then is not None:
                self.then()
            raise KeyboardInterrupt


def _interruptible(cfg: Dict[str, Any]) -> Dict[str, Any]:
    """The tiny config for three exactly repeatable 2-step epochs, each
    step's loss logged, dropout drawing from the random state."""
    cfg = copy.deepcopy(cfg)
    cfg["trainer"].update(max_epochs=3, deterministic=True, num_sanity_val_steps=0)
    cfg["model"]["dropout"] = 0.1
    cfg.update(threads=1, loss_log=True)
    return cfg


@pytest.fixture(scope="module")
def reference_run(_base_config: Dict[str, Any],
                  tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The folder of an :func:`_interruptible` run never stopped, every
    epoch's checkpoint kept: what the Ctrl-C and SIGTERM tests resume
    towards, trained once a module (read only)."""
    cfg = _interruptible(dict(_base_config,
                              output_dir=str(tmp_path_factory.mktemp("reference") / "a")))
    cfg["checkpoint"]["keep_every_epoch"] = True
    train(cfg)
    return Path(cfg["output_dir"])


def _epoch_scores(run: Path) -> Dict[str, float]:
    """``{file name: monitored score}`` of a run's ``epoch=*.ckpt`` files
    (each file read once)."""
    return {p.name: float(next(v["current_score"] for k, v in load_checkpoint(p)[
        "callbacks"].items() if k.startswith("ModelCheckpoint")))
        for p in (run / "checkpoints").glob("epoch=*.ckpt")}


def _train_averages(run: Path) -> Dict[str, Dict[str, str]]:
    """``{epoch: {name: value}}`` of the training epoch averages
    (``train*_epoch``) in every CSV log of a run (a resumed run writes its
    own ``version_N``)."""
    import csv
    found: Dict[str, Dict[str, str]] = {}
    for log in sorted(run.glob("logs/version_*/metrics.csv")):
        with open(log, newline="") as f:
            for row in csv.DictReader(f):
                found.setdefault(row["epoch"], {}).update(
                    {k: v for k, v in row.items() if k.startswith("train") and
                     k.endswith("_epoch") and v})
    return {epoch: names for epoch, names in found.items() if names}


def test_ctrl_c_in_validation_keeps_that_epoch_s_training_averages(
        tiny_config: Dict[str, Any], reference_run: Path) -> None:
    """Ctrl-C in epoch 0's validation: the resumed run validated again and
    logged its ``val/*`` rows, but not ``train_loss_epoch`` and the other
    training averages of epoch 0 (Lightning keeps their sums out of the
    checkpoint); they are logged, as a run never stopped logs them."""
    expected = {"0": _train_averages(reference_run)["0"]}
    assert "train_loss_epoch" in expected["0"]
    cfg = _interruptible(tiny_config)
    cfg["trainer"]["max_epochs"] = 1
    with pytest.raises(KeyboardInterrupt):
        train(cfg, callbacks=[_InterruptAt(2, "validation")])
    assert _train_averages(Path(cfg["output_dir"])) == {}
    train(cfg, resume=True)
    assert _train_averages(Path(cfg["output_dir"])) == expected


@pytest.mark.slow
@pytest.mark.parametrize("stop, every", [(3, None), (1, 1)])
def test_run_cut_inside_an_epoch_keeps_that_epoch_s_training_averages(
        tiny_config: Dict[str, Any], tmp_path: Path, stop: int, every: Any) -> None:
    """A run stopped by ``trainer.max_steps`` inside an epoch ends it (its
    end hooks run, ``last.ckpt`` written there) but ``--resume`` goes on
    with its remaining batches: that epoch's ``train_loss_epoch`` and other
    averages are those of a run never stopped, not of the resumed batches
    alone (epoch 1 read 3028.9 for 2718.2 at ``max_steps=3``)."""
    reference = _interruptible(dict(tiny_config, output_dir=str(tmp_path / "a")))
    train(reference)
    expected = _train_averages(tmp_path / "a")
    assert list(expected) == ["0", "1", "2"]
    cfg = _interruptible(tiny_config)
    cfg["checkpoint"]["every_n_steps"] = every
    cut = copy.deepcopy(cfg)
    cut["trainer"]["max_steps"] = stop
    train(cut)
    train(cfg, resume=True)
    assert _train_averages(Path(cfg["output_dir"])) == expected


@pytest.mark.slow
@pytest.mark.parametrize("where, step", [("start", 3), ("validation", 2)])
def test_resume_keeps_the_epoch_s_averages_of_metrics_logged_with_other_arguments(
        tiny_config: Dict[str, Any], tmp_path: Path, where: str, step: int) -> None:
    """A checkpoint whose training metrics were logged with other
    ``self.log`` arguments (``prog_bar`` here: a module or satagraph changed
    since) stopped ``--resume`` at its first step with Lightning's 'You
    called self.log(train/rotation, ...) twice in training_step with
    different arguments'; the averages are those of a run never stopped."""
    reference = _interruptible(dict(tiny_config, output_dir=str(tmp_path / "a")))
    train(reference)
    expected = _train_averages(tmp_path / "a")
    cfg = _interruptible(tiny_config)
    with pytest.raises(KeyboardInterrupt):
        train(cfg, callbacks=[_InterruptAt(step, where)])
    last = Path(cfg["output_dir"]) / "checkpoints" / LAST
    ckpt = torch.load(last, weights_only=False)
    logs = ckpt["callbacks"]["ResumeCheckpoint"]["epoch_logs"]
    assert logs
    for log in logs:
        log["prog_bar"] = not log["prog_bar"]
    torch.save(ckpt, last)
    train(cfg, resume=True)
    assert _train_averages(Path(cfg["output_dir"])) == expected


@pytest.mark.parametrize("where, step", [("start", 3), ("backward", 3), ("epoch_end", 4),
                                         pytest.param("validation", 4, marks=pytest.mark.slow)])
def test_ctrl_c_saves_where_it_stopped_and_resume_goes_on_from_there(
        tiny_config: Dict[str, Any], reference_run: Path, where: str, step: int) -> None:
    """Ctrl-C as step 4 starts or inside it writes ``last.ckpt`` at step 3
    (its optimizer state too), at the second epoch's end or in its
    validation at step 4 (in validation it wrote none: ``--resume`` trained
    steps 3 and 4 again); the first epoch's at step 2 is kept as
    ``last.prev.ckpt``; ``--resume`` goes on from there with the losses of
    a run never stopped (the interrupted step's dropout is drawn again),
    validating every epoch (an interrupted validation again, whole)."""
    full = read_loss_log(reference_run / "losses.tsv")
    assert max(full) == 6
    cfg = _interruptible(tiny_config)
    cfg["checkpoint"]["keep_every_epoch"] = True
    folder = Path(cfg["output_dir"]) / "checkpoints"
    with pytest.raises(KeyboardInterrupt) as stop:
        train(cfg, callbacks=[_InterruptAt(step, where)])
    assert stop.value.args == (step,)
    ckpt = load_checkpoint(folder / LAST)
    assert ckpt["global_step"] == step
    assert [float(s["step"]) for s in ckpt["optimizer_states"][0]["state"].values()][:1] == \
        [float(step)]
    assert load_checkpoint(folder / PREVIOUS)["global_step"] == 2
    assert resume_checkpoint(folder) == folder / LAST
    _, _, trainer, _ = train(cfg, resume=True)
    assert trainer.global_step == 6
    assert read_loss_log(Path(cfg["output_dir"]) / "losses.tsv") == full
    scores = [_epoch_scores(run) for run in (reference_run, Path(cfg["output_dir"]))]
    assert len(scores[0]) == 3
    assert scores[1] == scores[0]  # at the epoch's end: its epoch=1 checkpoint was never kept
    # inside epoch 1 they were of the resumed batches alone; at its end, in no log
    assert _train_averages(Path(cfg["output_dir"])) == _train_averages(reference_run)


@pytest.mark.slow
def test_ctrl_c_in_validation_after_a_step_save_resumes_with_that_validation(
        tiny_config: Dict[str, Any], tmp_path: Path) -> None:
    """``checkpoint.every_n_steps`` due at an epoch's last step: Ctrl-C in
    the validation after it wrote nothing (that step was saved), and
    ``--resume`` from that batch-end save skipped the epoch's validation
    (no ``epoch=1`` checkpoint, no val_loss); it now writes ``last.ckpt``
    again, to validate again, as where that step was not saved."""
    def run(name: str) -> Dict[str, Any]:
        cfg = _interruptible(dict(tiny_config, output_dir=str(tmp_path / name)))
        cfg["checkpoint"].update(keep_every_epoch=True, every_n_steps=2)
        return cfg

    train(run("a"))
    cfg = run("b")
    with pytest.raises(KeyboardInterrupt) as stop:
        train(cfg, callbacks=[_InterruptAt(4, "validation")])
    assert stop.value.args == (4,)
    train(cfg, resume=True)
    assert read_loss_log(tmp_path / "b" / "losses.tsv") == \
        read_loss_log(tmp_path / "a" / "losses.tsv")
    assert len(_epoch_scores(tmp_path / "a")) == 3
    assert _epoch_scores(tmp_path / "b") == _epoch_scores(tmp_path / "a")


class _TerminateAt(L.Callback):
    """A real SIGTERM to this process as the batch after step :obj:`step`
    starts (what a cluster sends before it kills a job)."""

    def __init__(self, step: int) -> None:
        self.step = step

    def on_train_batch_start(self, trainer: L.Trainer, *args: Any) -> None:
        if trainer.global_step == self.step:
            os.kill(os.getpid(), signal.SIGTERM)


def test_sigterm_saves_where_it_stopped_and_resume_goes_on_from_there(
        tiny_config: Dict[str, Any], reference_run: Path) -> None:
    """SIGTERM in step 3 (Lightning stops at that batch's end) writes
    ``last.ckpt`` at step 3, as Ctrl-C does: it kept the epoch-end one of
    step 2, so the steps since were trained again; ``--resume`` goes on
    with the losses of a run never stopped."""
    full = read_loss_log(reference_run / "losses.tsv")
    cfg = _interruptible(tiny_config)
    folder = Path(cfg["output_dir"]) / "checkpoints"
    with pytest.raises(KeyboardInterrupt) as stop:
        train(cfg, callbacks=[_TerminateAt(2)])
    assert stop.value.args == (3,)
    assert load_checkpoint(folder / LAST)["global_step"] == 3
    assert load_checkpoint(folder / PREVIOUS)["global_step"] == 2
    _, _, trainer, _ = train(cfg, resume=True)
    assert trainer.global_step == 6
    assert read_loss_log(Path(cfg["output_dir"]) / "losses.tsv") == full


def test_a_ctrl_c_save_that_fails_leaves_nothing_to_resume_from(
        tiny_config: Dict[str, Any], monkeypatch: pytest.MonkeyPatch) -> None:
    """A full disk half-way through the Ctrl-C save: a warning, no
    ``last.ckpt`` nor temporary file, so ``--resume`` finds nothing (the
    first checkpoint was not due yet) and the interrupt says none was
    written."""
    import errno

    import satagraph.io.checkpoint as checkpoint_mod
    from satagraph.utils.files import atomic_write, is_temp_file

    def half_then_full(path: Any, data: bytes, create_parent: bool = False) -> None:
        def write(f: Any) -> None:
            f.write(bytes(data)[: len(data) // 2])
            raise OSError(errno.ENOSPC, "No space left on device")
        atomic_write(path, write, binary=True, create_parent=create_parent)

    def disk_full() -> None:
        monkeypatch.setattr(checkpoint_mod, "atomic_write_bytes", half_then_full)

    cfg = _interruptible(tiny_config)
    folder = Path(cfg["output_dir"]) / "checkpoints"
    with pytest.warns(UserWarning, match="could not write .*last.ckpt.*No space left"):
        with pytest.raises(KeyboardInterrupt) as stop:
            train(cfg, callbacks=[_InterruptAt(1, then=disk_full)])
    assert stop.value.args == ()
    assert [p.name for p in folder.iterdir() if p.name == LAST or is_temp_file(p.name)] == []
    with pytest.raises(FileNotFoundError, match="no checkpoint"):
        resume_checkpoint(folder)


def test_a_damaged_data_files_record_is_one_line_naming_it(tmp_path: Path) -> None:
    """A ``data_files.txt`` line without its tab (edited by hand) stopped
    ``--resume`` with ``not enough values to unpack (expected 2, got 1)``;
    it is one line naming the file and line, and saying what to do."""
    from types import SimpleNamespace
    from satagraph.experiment.train import _record_data_files
    files = [SimpleNamespace(path=str(tmp_path / n)) for n in ("a.bvh", "b.bvh")]
    dm = SimpleNamespace(datasets={"train": SimpleNamespace(files=files[:1]),
                                   "val": SimpleNamespace(files=files[1:])})
    _record_data_files(dm, tmp_path, resumed=False)
    record = tmp_path / "data_files.txt"
    assert record.read_text() == f"train\t{files[0].path}\nval\t{files[1].path}\n"
    _record_data_files(dm, tmp_path, resumed=True)  # the same files: nothing said
    record.write_text(f"train\t{files[0].path}\nval {files[1].path}\n")
    with pytest.raises(ValueError, match=rf"^{re.escape(str(record))}:2: not 'split<TAB>path'"):
        _record_data_files(dm, tmp_path, resumed=True)


def test_a_data_files_record_not_utf8_is_one_line_naming_it(tmp_path: Path) -> None:
    """A ``data_files.txt`` saved in another encoding (edited by hand) stopped
    ``--resume`` with ``'utf-8' codec can't decode byte 0xe4``, no file named."""
    from types import SimpleNamespace
    from satagraph.experiment.train import _record_data_files
    dm = SimpleNamespace(datasets={"train": SimpleNamespace(files=[
        SimpleNamespace(path=str(tmp_path / "a.bvh"))])})
    record = tmp_path / "data_files.txt"
    record.write_bytes(f"train\t{tmp_path}/Bewegung_\xe4.bvh\n".encode("latin-1"))
    with pytest.raises(ValueError, match=rf"^{re.escape(str(record))}: not UTF-8 .* delete"):
        _record_data_files(dm, tmp_path, resumed=True)


@pytest.mark.slow
def test_a_non_ascii_data_path_resumes_under_any_locale(tmp_path: Path) -> None:
    """The record is written in UTF-8 and was read in the locale's encoding:
    a resume of a run on ``Bewegung_ä.bvh`` under an ASCII locale stopped with
    ``'ascii' codec can't decode byte 0xc3`` (in cp1252, Windows', it said
    the data had changed)."""
    code = ("import sys, warnings; from pathlib import Path; from types import SimpleNamespace; "
            "from satagraph.experiment.train import _record_data_files; "
            "warnings.simplefilter('error'); run = Path(sys.argv[1]); "
            "dm = SimpleNamespace(datasets={'train': SimpleNamespace(files=["
            "SimpleNamespace(path=str(run / 'Bewegung_\\xe4.bvh'))])}); "
            "_record_data_files(dm, run, resumed=False); _record_data_files(dm, run, resumed=True)")
    env = dict(os.environ, LC_ALL="C", PYTHONCOERCECLOCALE="0", PYTHONUTF8="0")
    done = subprocess.run([sys.executable, "-c", code, str(tmp_path)], env=env,
                          cwd=Path(__file__).resolve().parents[2], capture_output=True,
                          text=True, timeout=120)
    assert (done.returncode, done.stderr) == (0, "")
    assert "Bewegung_\xe4.bvh" in (tmp_path / "data_files.txt").read_text(encoding="utf-8")


@pytest.mark.slow
def test_resume_says_how_the_data_folder_changed_and_keeps_its_normaliser(
        tmp_path: Path) -> None:
    """``--resume`` after files were added to and removed from the data
    folder went on silently: one line now says how many, per split, and
    the run keeps the normaliser of its first start (its checkpoint's), not
    the one the data module fits to the files there now."""
    write_zoo(tmp_path / "zoo", species=["biped", "quadruped"], clips=3, frames=40)
    data = tmp_path / "data"
    data.mkdir()
    for bvh in sorted((tmp_path / "zoo" / "biped").glob("*.bvh")):
        (data / bvh.name).write_bytes(bvh.read_bytes())
    cfg = load_config("tiny", [f"data.sources=[{data}]", f"data.cache_dir={tmp_path / 'c'}",
                               "data.window=16", "data.stride=16", "data.max_files=null",
                               "logger.name=none", "trainer.progress=false",
                               "trainer.enable_model_summary=false", "trainer.max_epochs=1",
                               "trainer.limit_train_batches=1", "trainer.limit_val_batches=0",
                               "trainer.num_sanity_val_steps=0", "threads=1",
                               f"output_dir={tmp_path / 'run'}"])
    _, _, _, run_dir = train(cfg)
    started = load_checkpoint(run_dir / "checkpoints" / LAST)["state_dict"]
    record = (run_dir / "data_files.txt").read_text()
    biped = sorted(data.glob("*.bvh"))
    assert sorted(line.split("\t")[1] for line in record.splitlines()) == list(map(str, biped))
    (data / biped[0].name).unlink()
    for bvh in sorted((tmp_path / "zoo" / "quadruped").glob("*.bvh")):
        (data / bvh.name).write_bytes(bvh.read_bytes())
    cfg["trainer"]["max_epochs"] = 2
    with pytest.warns(UserWarning) as said:
        module, dm, _, _ = train(cfg, resume=True)
    lines = [str(w.message) for w in said if str(w.message).startswith("--resume:")]
    assert len(lines) == 1 and lines[0].startswith(
        "--resume: 12 file(s) added to and 1 removed from the data since the run started (")
    assert "keeps the normaliser of its first start" in lines[0]
    assert (run_dir / "data_files.txt").read_text() == record
    for name in ("dynamic_mean", "dynamic_std"):
        kept = getattr(module.normalizer, name)
        assert torch.equal(kept, started[f"normalizer.{name}"])
        assert not torch.equal(kept, getattr(dm.normalizer, name))


def test_a_new_start_after_a_run_that_saved_nothing_records_its_own_files(
        tiny_config: Dict[str, Any]) -> None:
    """A run stopped before its first checkpoint (Ctrl-C as its first step
    starts) left ``data_files.txt``; a new run in that folder (no
    ``--resume``: nothing to resume) on other files said ``--resume: ...``
    and kept the stopped run's list, which a later ``--resume``
    compared with: a new start writes its own."""
    cfg = _interruptible(tiny_config)
    cfg["trainer"]["max_epochs"] = 1
    with pytest.raises(KeyboardInterrupt):
        train(cfg, callbacks=[_InterruptAt(0, "start")])
    record = Path(cfg["output_dir"]) / train_mod.DATA_FILES
    first = record.read_text()
    cfg["data"]["max_files"] = 1
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        _, dm, _, _ = train(cfg)
    assert not [w for w in said if str(w.message).startswith("--resume:")]
    now = record.read_text()
    assert now != first
    assert now == "".join(f"{s}\t{f}\n" for s, f in sorted(train_mod._data_files(dm)))


def test_skip_names_the_skipped_steps_as_the_loss_log_does(
        tiny_config: Dict[str, Any], monkeypatch: pytest.MonkeyPatch) -> None:
    """The line of ``nonfinite=skip`` named a skipped batch by Lightning's
    ``global_step`` before its update (from 0), which ``losses.tsv`` numbers
    one more (from 1): the step it names is the line of its non-finite loss."""
    from satagraph.lightning.autoencoder import MotionAutoencoderModule
    original = MotionAutoencoderModule.compute_losses

    def poisoned(self, out, batch):
        losses = original(self, out, batch)
        if self.global_step == 2:  # the third batch
            losses["loss"] = losses["loss"] * float("nan")
        return losses

    monkeypatch.setattr(MotionAutoencoderModule, "compute_losses", poisoned)
    cfg = dict(_interruptible(tiny_config), nonfinite="skip")
    cfg["trainer"]["max_epochs"] = 2
    with pytest.warns(UserWarning, match=r"nonfinite=skip: .* 1 batch\(es\).*") as said:
        train(cfg)
    line = next(str(w.message) for w in said if "nonfinite=skip" in str(w.message))
    step = int(re.search(r"at step\(s\) (\d+)", line).group(1))
    losses = read_loss_log(Path(cfg["output_dir"]) / "losses.tsv")
    assert sorted(losses) == [1, 2, 3, 4]
    assert [s for s, loss in losses.items() if loss != loss] == [step] == [3]


def test_training_shows_no_third_party_leafspec_warning(tiny_config: Dict[str, Any]) -> None:
    """Every run printed ``satagraph: warning: `isinstance(treespec, LeafSpec)`
    is deprecated ...``: Lightning's loaders build torch's deprecated
    ``LeafSpec``; that one warning is silenced where ``fit`` runs, no other."""
    cfg = _interruptible(tiny_config)
    cfg["trainer"]["max_epochs"] = 1
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        train(cfg)
    assert not [w for w in said if "LeafSpec" in str(w.message)]
    with warnings.catch_warnings(record=True) as said:  # the filter ends with the run
        warnings.simplefilter("always")
        from lightning.pytorch.utilities._pytree import _tree_flatten
        _tree_flatten([1])
    assert [w.category for w in said if "LeafSpec" in str(w.message)] == [FutureWarning]


def test_a_resume_without_its_data_files_record_says_it_cannot_check(tmp_path: Path) -> None:
    """``--resume`` after ``data_files.txt`` was deleted wrote the files
    there now without a word, so it could not tell whether the data had
    changed; it says so in one line, goes on and records them."""
    from types import SimpleNamespace
    from satagraph.experiment.train import _record_data_files
    dm = SimpleNamespace(datasets={"train": SimpleNamespace(files=[
        SimpleNamespace(path=str(tmp_path / "a.bvh"))])})
    record = tmp_path / "data_files.txt"
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        _record_data_files(dm, tmp_path, resumed=False)  # a first start: nothing to say
        assert said == []
        record.unlink()
        _record_data_files(dm, tmp_path, resumed=True)
    assert [str(w.message) for w in said] == [
        f"--resume: no {record}: whether the data changed since the run started cannot be "
        "checked; it goes on with the files there now and records them"]
    assert record.read_text() == f"train\t{tmp_path / 'a.bvh'}\n"
