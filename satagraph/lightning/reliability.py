r"""Training that cannot end green with a broken model, and exact resume.

- :class:`NonFiniteGuard` checks the loss before the backward pass and the
  gradients before the optimizer step: a non-finite value stops the run
  (:class:`TrainingStopped`, naming the batch's files; the weights are not
  updated, so the last checkpoint stays good) or, with ``mode="skip"``,
  drops that batch's update and counts it, and stops the run where an
  epoch's worth of batches in a row is non-finite (a diverged model).
- :class:`ResumeCheckpoint` writes ``last.ckpt`` every N steps and/or M
  minutes, at every epoch end and at a Ctrl-C or SIGTERM, keeping the previous
  one as ``last.prev.ckpt``; the checkpoint carries every random state (torch,
  CUDA, numpy, Python), restored just before the first resumed step, while
  the loop state in it gives the sampler's position
  (:class:`~satagraph.data.sampler.ResumableSampler`).
- :class:`SafeCheckpointIO` saves atomically and loads with
  ``weights_only=True`` and one-line errors.
- :func:`run_lock` keeps a second live run out of an ``output_dir``.
"""
from __future__ import annotations

import contextlib
import os
import random
import re
import socket
import time
import warnings
from pathlib import Path
from typing import Any, Callable, Dict, Iterator, List, Optional, Tuple

import lightning as L
import numpy as np
import torch
from lightning.fabric.plugins.io.torch_io import TorchCheckpointIO
from lightning.pytorch.callbacks import Checkpoint
from lightning.pytorch.utilities.exceptions import SIGTERMException

from satagraph.io.checkpoint import CheckpointError, load_checkpoint, save_checkpoint
from satagraph.utils.files import (append_whole, is_temp_file, keep_copy, lock_fd,
                                   names_fd)

#: Names of the resume checkpoints in ``<run>/checkpoints``.
LAST, PREVIOUS, DAMAGED = "last.ckpt", "last.prev.ckpt", "last.damaged.ckpt"
#: ``nonfinite`` config values.
NONFINITE_MODES = ("stop", "skip")
#: Most batches in a row that ``nonfinite=skip`` skips before it stops the
#: run (fewer where an epoch has fewer batches, never fewer than 2).
MAX_SKIPPED_IN_A_ROW = 100


class TrainingStopped(RuntimeError):
    """Training stopped on a non-finite loss or gradient; one line naming
    the step, the batch's files and the last good checkpoint."""


class RunLockedError(RuntimeError):
    """Another live run writes to the same ``output_dir``."""


# ------------------------------------------------------------- safe IO
class SafeCheckpointIO(TorchCheckpointIO):
    """Lightning checkpoint IO: atomic saves (fsynced temporary file and
    rename), loads with ``weights_only=True`` and clean errors."""

    def save_checkpoint(self, checkpoint: Dict[str, Any], path: Any,
                        storage_options: Optional[Any] = None) -> None:
        save_checkpoint(checkpoint, path)

    def load_checkpoint(self, path: Any, map_location: Optional[Callable] = None,
                        weights_only: Optional[bool] = None) -> Dict[str, Any]:
        return load_checkpoint(path, map_location=map_location or "cpu", require=(),
                               what="Lightning checkpoint")


# ------------------------------------------------------------ non-finite
def _batch_files(batch: Any) -> List[str]:
    meta = getattr(batch, "meta", None) or []
    return [str(m.get("path", "?")) for m in meta if isinstance(m, dict)]


class NonFiniteGuard(L.Callback):
    r"""Stop (or skip the update) on a non-finite loss or gradient.

    Args:
        mode (str): ``"stop"`` raises :class:`TrainingStopped` before the
            weights change; ``"skip"`` clears the gradients of that batch
            (the optimizer leaves the weights as they are) and counts it in
            :attr:`skipped` (its step in :attr:`skipped_steps`, numbered as
            ``losses.tsv`` numbers it; one line at the end of training names
            them), and raises :class:`TrainingStopped` where as
            many batches in a row as an epoch has (2 to
            :data:`MAX_SKIPPED_IN_A_ROW`) were skipped: a model that gives
            no finite loss any more has diverged, and skipping on ended the
            run green.
        last_checkpoint (str, optional): Named in the error message.
    """

    def __init__(self, mode: str = "stop", last_checkpoint: Optional[str] = None) -> None:
        if mode not in NONFINITE_MODES:
            raise ValueError(f"nonfinite must be one of {NONFINITE_MODES}, got {mode!r}")
        self.mode, self.last_checkpoint = mode, last_checkpoint
        self.skipped = 0
        #: The steps whose update ``mode="skip"`` left out, from 1 as
        #: :class:`LossLog` numbers them (the ``global_step`` after the step).
        self.skipped_steps: List[int] = []
        self._in_a_row = 0
        self._files: List[str] = []
        self._bad_loss: Optional[float] = None

    def on_train_batch_start(self, trainer: L.Trainer, pl_module: L.LightningModule,
                             batch: Any, batch_idx: int) -> None:
        self._files, self._bad_loss = _batch_files(batch), None

    def on_before_backward(self, trainer: L.Trainer, pl_module: L.LightningModule,
                           loss: torch.Tensor) -> None:
        if not bool(torch.isfinite(loss.detach()).all()):
            self._bad_loss = float(loss.detach().float().sum())
            if self.mode == "stop":
                raise self._error(trainer, f"non-finite loss ({self._bad_loss})")

    def on_before_optimizer_step(self, trainer: L.Trainer, pl_module: L.LightningModule,
                                 optimizer: torch.optim.Optimizer) -> None:
        params = [p for group in optimizer.param_groups for p in group["params"]
                  if p.grad is not None]
        finite = self._bad_loss is None and (not params or bool(torch.isfinite(
            torch.stack([p.grad.detach().float().sum() for p in params])).all()))
        if finite:
            self._in_a_row = 0
            return
        if self.mode == "stop":
            raise self._error(trainer, "non-finite gradient")
        for p in params:
            p.grad = None
        self.skipped += 1
        self.skipped_steps.append(trainer.global_step + 1)  # counted after this batch
        self._in_a_row += 1
        if self._in_a_row >= _skip_limit(trainer):
            raise self._diverged(trainer)

    def _error(self, trainer: L.Trainer, what: str) -> TrainingStopped:
        files = ", ".join(dict.fromkeys(self._files)) or "?"
        last = self.last_checkpoint
        keep = (f"; last good checkpoint: {last}" if last and os.path.isfile(last)
                else "; no checkpoint was written yet")
        return TrainingStopped(
            f"training stopped at step {trainer.global_step}: {what} on the batch of "
            f"{files}; the weights were not updated{keep} (nonfinite=skip skips such "
            "batches)")

    def _diverged(self, trainer: L.Trainer) -> TrainingStopped:
        last = self.last_checkpoint
        keep = (f"; last checkpoint: {last}" if last and os.path.isfile(last)
                else "; no checkpoint was written yet")
        return TrainingStopped(
            f"training stopped at step {trainer.global_step}: {self._in_a_row} batches in a "
            "row had a non-finite loss or gradient (nonfinite=skip skipped them), the last on "
            f"the batch of {', '.join(dict.fromkeys(self._files)) or '?'}: the model has "
            f"diverged{keep} "
            "(a lower optim.lr may keep it finite)")

    def on_train_end(self, trainer: L.Trainer, pl_module: L.LightningModule) -> None:
        if self.skipped and trainer.is_global_zero:  # every process skipped the same steps
            # raised here, not in Lightning's caller: a filter of Lightning's warnings
            # (module="lightning") hid it
            warnings.warn(_skipped_note(self.skipped_steps))


def _skipped_note(steps: List[int], shown: int = 10) -> str:
    """The one line that says which steps ``nonfinite=skip`` left out (at
    most :obj:`shown` named)."""
    named = ", ".join(map(str, steps[:shown])) + (", ..." if len(steps) > shown else "")
    return (f"nonfinite=skip: skipped the weight update of {len(steps)} batch(es) with a "
            f"non-finite loss or gradient, at step(s) {named} (as losses.tsv numbers them)")


def _skip_limit(trainer: L.Trainer) -> int:
    """Batches in a row :class:`NonFiniteGuard` skips before it stops: an
    epoch's, from 2 to :data:`MAX_SKIPPED_IN_A_ROW`."""
    per_epoch = trainer.num_training_batches
    if not per_epoch or per_epoch == float("inf"):
        return MAX_SKIPPED_IN_A_ROW
    return max(2, min(int(per_epoch), MAX_SKIPPED_IN_A_ROW))


# ------------------------------------------------------------ random states
def rng_states() -> Dict[str, Any]:
    """Every random state a training step may draw from, in a form that
    loads with ``weights_only=True``."""
    kind, keys, pos, has_gauss, gauss = np.random.get_state()
    states = {"torch": torch.get_rng_state(),
              "numpy": [kind, torch.from_numpy(keys.astype(np.int64)), int(pos),
                        int(has_gauss), float(gauss)],
              "python": random.getstate()}
    if torch.cuda.is_available() and torch.cuda.is_initialized():
        states["cuda"] = torch.cuda.get_rng_state_all()
    return states


def set_rng_states(states: Dict[str, Any]) -> None:
    """Restore what :func:`rng_states` returned."""
    torch.set_rng_state(states["torch"])
    kind, keys, pos, has_gauss, gauss = states["numpy"]
    np.random.set_state((kind, np.asarray(keys, dtype=np.int64).astype(np.uint32),
                         pos, has_gauss, gauss))
    version, internal, gauss_next = states["python"]
    random.setstate((version, tuple(internal), gauss_next))
    if "cuda" in states and torch.cuda.is_available():
        torch.cuda.set_rng_state_all(states["cuda"])


# ------------------------------------------------------------ checkpoints
class ResumeCheckpoint(Checkpoint):
    r"""Write ``<dirpath>/last.ckpt`` every :obj:`every_n_steps` training
    steps and/or :obj:`every_minutes` minutes, and at every epoch end,
    keeping the one it replaces as ``last.prev.ckpt``.

    It is a :class:`~lightning.pytorch.callbacks.Checkpoint`, so Lightning
    runs it with the other checkpoint callbacks, after everything else, in
    the order given: placed after a best-checkpoint callback, the epoch-end
    ``last.ckpt`` holds that epoch's best (a run resumed from it compares
    the next epochs with it, and deletes it when beaten).

    Its state in the checkpoint holds every random state (restored at the
    first training batch after a resume) and the position of the run
    (epoch, batches done in it, step), which the training sampler resumes
    from, and the sums of the epoch's training averages so far
    (:func:`epoch_logs`, put back in the resumed run: :func:`add_epoch_logs`).
    A run stopped inside an epoch (``max_time``, ``max_steps``,
    ``should_stop``) resumes with that epoch's remaining batches, and one
    bounded by ``max_steps`` goes on past an epoch's end: the losses are
    those of a run never stopped, where Lightning 2.6 alone would count the
    cut epoch as finished or skip the next one
    (:meth:`on_load_checkpoint`). A Ctrl-C or SIGTERM writes ``last.ckpt``
    at the last training step that ended (:meth:`on_exception`), also in
    the validation that follows it, so that ``--resume`` goes on from
    there.

    Args:
        dirpath (str): The checkpoint folder.
        every_n_steps (int, optional): Steps between checkpoints.
        every_minutes (float, optional): Minutes between checkpoints.
    """

    def __init__(self, dirpath: str, every_n_steps: Optional[int] = None,
                 every_minutes: Optional[float] = None) -> None:
        if every_n_steps is not None and int(every_n_steps) < 1:
            raise ValueError(f"checkpoint.every_n_steps must be >= 1, got {every_n_steps}")
        if every_minutes is not None and not float(every_minutes) > 0:
            raise ValueError(f"checkpoint.every_minutes must be > 0, got {every_minutes}")
        self.dirpath = Path(dirpath)
        self.every_n_steps = int(every_n_steps) if every_n_steps else None
        self.every_seconds = 60.0 * float(every_minutes) if every_minutes else None
        self._last_time = time.monotonic()
        self._batches_done = 0
        self._saved_step = -1
        self._pending: Optional[Dict[str, Any]] = None
        self._max_steps: Optional[int] = None
        self._unsaved = False  # a training step ended since the last save
        self._stepping = False  # from an optimizer step to the end of its batch
        self._interrupting = False
        self._step_rng: Optional[Dict[str, Any]] = None  # at the last step's end
        self._step_logs: List[Dict[str, Any]] = []  # the epoch's sums then (epoch_logs)
        self._carried: List[Dict[str, Any]] = []  # added after the first resumed batch
        self.saves = 0
        #: The step of the checkpoint a Ctrl-C wrote (``None``: none).
        self.interrupted_step: Optional[int] = None
        #: The step of the checkpoint a resumed run started from (``None``:
        #: not resumed); the command compares it with where the run ended.
        self.resumed_step: Optional[int] = None

    @property
    def last_path(self) -> Path:
        return self.dirpath / LAST

    @property
    def previous_path(self) -> Path:
        return self.dirpath / PREVIOUS

    @property
    def state_key(self) -> str:
        return "ResumeCheckpoint"

    def state_dict(self) -> Dict[str, Any]:
        trainer = getattr(self, "_trainer", None)
        epoch = trainer.current_epoch if trainer is not None else 0
        step = trainer.global_step if trainer is not None else 0
        total = trainer.num_training_batches if trainer is not None else float("inf")
        done = self._batches_done >= total
        # the next epoch starts anew; one cut short (max_steps, max_time) goes on
        ending = done and trainer is not None and _ending_epoch(trainer)
        return {"epoch": epoch, "batches": self._batches_done, "step": step,
                "epoch_done": done,
                "rng": self._step_rng if self._interrupting else rng_states(),
                "epoch_logs": [] if ending else self._step_logs}

    @property
    def resume_position(self) -> Optional[Dict[str, Any]]:
        """``{"epoch", "batches", "epoch_done"}`` of the checkpoint being
        resumed from (until its first training batch), else ``None``."""
        if self._pending is None:
            return None
        return {k: self._pending[k] for k in ("epoch", "batches", "epoch_done")}

    def load_state_dict(self, state_dict: Dict[str, Any]) -> None:
        self._pending = state_dict

    def on_load_checkpoint(self, trainer: L.Trainer, pl_module: L.LightningModule,
                           checkpoint: Dict[str, Any]) -> None:
        """Lightning 2.6 restores the loops of a run bounded by ``max_steps``
        as if its checkpoint were left mid-epoch, so one written at an
        epoch's end loses the next epoch (Lightning-AI/pytorch-lightning
        #19617). The loops are restored without the step bound, as an
        epoch-bounded run's are (the same for a checkpoint left mid-epoch),
        and :meth:`on_train_start` puts it back; an epoch that a stop cut
        short is counted back as unfinished (:func:`_reopen_cut_epoch`)."""
        self.resumed_step = int(checkpoint.get("global_step", 0))
        if trainer.max_steps >= 0:
            self._max_steps = trainer.max_steps
            trainer.fit_loop.epoch_loop.max_steps = -1
        _reopen_cut_epoch(checkpoint)

    def on_train_start(self, trainer: L.Trainer, pl_module: L.LightningModule) -> None:
        if self._max_steps is not None:
            trainer.fit_loop.epoch_loop.max_steps, self._max_steps = self._max_steps, None
        if self._pending is not None and self._pending["epoch_done"]:  # its end comes first
            restore_epoch_logs(trainer, self._pending.get("epoch_logs") or [])

    def setup(self, trainer: L.Trainer, pl_module: L.LightningModule, stage: str) -> None:
        self._trainer = trainer
        self._last_time = time.monotonic()

    def on_train_epoch_start(self, trainer: L.Trainer, pl_module: L.LightningModule) -> None:
        if self._pending is None:
            self._batches_done = 0

    def on_train_batch_start(self, trainer: L.Trainer, pl_module: L.LightningModule,
                             batch: Any, batch_idx: int) -> None:
        if self._pending is not None:
            set_rng_states(self._pending["rng"])
            logs = self._pending.get("epoch_logs") or []
            if self._pending["epoch_done"]:  # logged at that epoch's end: this one logs anew
                _forget_epoch_logs(trainer, logs)
            else:  # added to this batch's own logs (the module's arguments may have changed)
                self._carried = self._step_logs = logs
            self._pending = None

    def on_train_batch_end(self, trainer: L.Trainer, pl_module: L.LightningModule,
                           outputs: Any, batch: Any, batch_idx: int) -> None:
        self._batches_done = batch_idx + 1
        due = self.every_n_steps is not None and trainer.global_step % self.every_n_steps == 0
        if self.every_seconds is not None:
            late = time.monotonic() - self._last_time >= self.every_seconds
            due = due or bool(trainer.strategy.broadcast(late, src=0))
        self._step_rng = rng_states()  # also of a step saved here: see on_exception
        if self._carried:
            add_epoch_logs(trainer, self._carried)
            self._carried = []
        self._step_logs = epoch_logs(trainer)
        if due:
            self.save(trainer)
        else:
            self._unsaved = True
        self._stepping = False

    def on_before_optimizer_step(self, trainer: L.Trainer, pl_module: L.LightningModule,
                                 optimizer: torch.optim.Optimizer) -> None:
        self._stepping = True

    def on_exception(self, trainer: L.Trainer, pl_module: L.LightningModule,
                     exception: BaseException) -> None:
        """Ctrl-C or SIGTERM (what a cluster sends before it kills a job;
        Lightning stops at the end of the batch it falls in): write
        ``last.ckpt`` at the last training step that ended, as an
        every-N-steps save there would have (its random states, its loop
        counts), so that ``--resume`` goes on from it; in the validation
        of a training run, the resumed run validates again, whole
        (:func:`_before_validation`); at an epoch's end (its validation
        done), the epoch checkpoints that Lightning had not written yet
        (``checkpoint.keep_every_epoch``'s, the best one's) are written
        first and its training averages logged, as the end of that epoch
        would have (the resumed run goes on with the next epoch:
        :func:`_keep_epoch_checkpoints`, :func:`_log_epoch_averages`). Nothing is
        written where that checkpoint is already ``last.ckpt`` (but in the
        validation after a step saved at its batch's end: that save resumes
        past the validation; nor at an epoch's end), or where the
        stop fell in the sanity check or between an optimizer step and the
        end of its batch (the weights may be half updated), or in a distributed
        run (its other processes would not join the save); nor for other
        errors (a non-finite loss keeps the last good checkpoint). A save
        that fails is a warning: the interrupt goes on, and ``last.ckpt``
        stays the one before (writes are atomic)."""
        ending = _ending_epoch(trainer)
        if (not isinstance(exception, (KeyboardInterrupt, SIGTERMException))
                or not (self._unsaved or self._saved_step_validating(trainer) or ending)
                or self._stepping or trainer.world_size > 1
                or not (trainer.training or _validating_in_fit(trainer))):
            return
        self._interrupting = True
        try:
            if ending:
                _keep_epoch_checkpoints(trainer, pl_module)
            self.save(trainer)
        except Exception as err:  # the interrupt is what the user asked for
            warnings.warn(f"interrupted: could not write {self.last_path} "
                          f"({' '.join(str(err).split())}); it is left as it was",
                          stacklevel=2)
            return
        finally:
            self._interrupting = False
        self.interrupted_step = trainer.global_step
        if ending:
            _log_epoch_averages(trainer)

    def _saved_step_validating(self, trainer: L.Trainer) -> bool:
        """Whether the validation of a training run follows a step that this
        run saved at its batch's end (``every_n_steps`` or ``every_minutes``
        due at the step before an epoch's validation): Lightning resumes
        that save after the validation, which it skips."""
        return _validating_in_fit(trainer) and self._saved_step == trainer.global_step

    def on_save_checkpoint(self, trainer: L.Trainer, pl_module: L.LightningModule,
                           checkpoint: Dict[str, Any]) -> None:
        if self._interrupting and _validating_in_fit(trainer):
            _before_validation(checkpoint)
        elif self._interrupting:
            _as_batch_end(checkpoint)

    def on_train_epoch_end(self, trainer: L.Trainer, pl_module: L.LightningModule) -> None:
        self.save(trainer)

    def save(self, trainer: L.Trainer) -> None:
        """Write ``last.ckpt``; the one it replaces becomes
        ``last.prev.ckpt`` unless it was written at the same step."""
        step = trainer.global_step
        if (trainer.is_global_zero and self.last_path.is_file()
                and step != self._saved_step):
            keep_copy(self.last_path, self.previous_path)
        trainer.save_checkpoint(self.last_path, weights_only=False)
        self._last_time, self._saved_step = time.monotonic(), step
        self._unsaved = False
        self.saves += 1


def _as_batch_end(checkpoint: Dict[str, Any]) -> None:
    """The loop counts of a checkpoint written at a Ctrl-C as those of one
    written at the end of the last training batch that ended (whose counts
    Lightning resumes after that batch): a batch begun after it is counted
    back as never begun, and the one that ended was not its epoch's last.
    Counts at that batch's end, or at the epoch's end (its last batch
    done: the epoch-end save's), are left as they are."""
    loop = checkpoint["loops"]["fit_loop"]
    batches = loop["epoch_loop.batch_progress"]
    total = batches["total"]
    if total["processed"] != total["completed"] or (
            total["ready"] == total["completed"] and batches["is_last_batch"]):
        return
    for counts in (batches["total"], batches["current"]):
        done = counts["processed"]
        counts.update(ready=done, started=done, processed=done, completed=done - 1)
    batches["is_last_batch"] = False
    state = loop.get("epoch_loop.state_dict") or {}
    if "_batches_that_stepped" in state:  # counted at that batch's end
        state["_batches_that_stepped"] -= 1


#: The hook whose ``self.log`` sums :func:`epoch_logs` keeps.
_STEP_FX = "training_step"


def epoch_logs(trainer: L.Trainer) -> List[Dict[str, Any]]:
    """What the training metrics logged with ``on_epoch=True`` (``self.log``
    in ``training_step``) have summed in this epoch so far, in a form that
    loads with ``weights_only=True``: Lightning keeps them out of its
    checkpoints, so a run resumed inside an epoch, or before its
    validation, logged that epoch's averages over the resumed batches
    alone, or none (:func:`restore_epoch_logs`, :func:`add_epoch_logs`).
    None in a distributed run (each process sums its own)."""
    results = trainer.fit_loop.epoch_loop._results
    if trainer.world_size > 1 or results is None:
        return []
    logs = []
    for metric in results.values():
        meta = metric.meta
        if (meta.fx != _STEP_FX or not (metric.is_tensor and meta.on_epoch)
                or meta.enable_graph or meta.sync.group):
            continue
        logs.append({"fx": meta.fx, "name": meta.name, "prog_bar": meta.prog_bar,
                     "logger": meta.logger, "on_step": meta.on_step,
                     "reduce_fx": meta.reduce_fx.__name__,
                     "add_dataloader_idx": meta.add_dataloader_idx,
                     "metric_attribute": meta.metric_attribute, "sync_dist": meta.sync.should,
                     "rank_zero_only": meta.sync.rank_zero_only,
                     "value": metric.value.detach().cpu().clone(),
                     "batch_size": (metric.cumulated_batch_size.detach().cpu().clone()
                                    if meta.is_mean_reduction else None)})
    return logs


def restore_epoch_logs(trainer: L.Trainer, logs: List[Dict[str, Any]]) -> None:
    """Put back the sums :func:`epoch_logs` kept, as the same ``self.log``
    calls would have left them: the epoch's averages are those of a run
    never stopped. Lightning clears a hook's sums at its first ``self.log``
    of a run but where that hook logged last (an epoch's first batch
    starts anew: the sums are of the batches before, here)."""
    results = trainer.fit_loop.epoch_loop._results
    device = trainer.strategy.root_device
    for log in logs:
        log = dict(log)
        value, count = log.pop("value"), log.pop("batch_size")
        fx, name, sync = log.pop("fx"), log.pop("name"), log.pop("sync_dist")
        results.log(fx, name, value.new_zeros((), device=device), on_epoch=True,
                    sync_dist=sync, sync_dist_fn=trainer.strategy.reduce, batch_size=1, **log)
        metric = results[f"{fx}.{name}"]
        metric.value = value.to(device)
        if count is not None:
            metric.cumulated_batch_size = count.to(device)
        metric._forward_cache = None  # no step value: the resumed steps log their own
    if logs:
        trainer._logger_connector._current_fx = _STEP_FX


def add_epoch_logs(trainer: L.Trainer, logs: List[Dict[str, Any]]) -> None:
    """Add the sums :func:`epoch_logs` kept to those of the same metrics
    that the first batch of a run resumed inside that epoch has logged: the
    epoch's averages are those of a run never stopped, whatever else of
    ``self.log``'s arguments (``prog_bar``, ...) changed since (Lightning
    refuses a metric logged again with other arguments). One that batch did
    not log is put back as it was (:func:`restore_epoch_logs`); one reduced
    otherwise now is left out."""
    results = trainer.fit_loop.epoch_loop._results
    logged = [f"{log['fx']}.{log['name']}" in results for log in logs]
    restore_epoch_logs(trainer, [log for log, was in zip(logs, logged) if not was])
    for log in (log for log, was in zip(logs, logged) if was):
        metric = results[f"{log['fx']}.{log['name']}"]
        if not metric.is_tensor or metric.meta.reduce_fx.__name__ != log["reduce_fx"]:
            continue
        value = log["value"].to(metric.value)
        if metric.meta.is_max_reduction or metric.meta.is_min_reduction:
            metric.value = metric.meta.reduce_fx(torch.stack([metric.value, value]))
        else:
            metric.value = metric.value + value
        if metric.meta.is_mean_reduction and log["batch_size"] is not None:
            metric.cumulated_batch_size = (metric.cumulated_batch_size
                                           + log["batch_size"].to(metric.cumulated_batch_size))


def _forget_epoch_logs(trainer: L.Trainer, logs: List[Dict[str, Any]]) -> None:
    """Drop the metrics :func:`restore_epoch_logs` put back for an epoch's
    end once it is logged: the next epoch's ``self.log`` registers them
    with its own arguments."""
    results = trainer.fit_loop.epoch_loop._results
    for log in logs:
        results.pop(f"{log['fx']}.{log['name']}", None)


def _ending_epoch(trainer: L.Trainer) -> bool:
    """Whether the training loop is in an epoch's end hooks (its batches
    and validation done, the epoch not counted as completed yet)."""
    progress = trainer.fit_loop.epoch_progress.current
    return trainer.training and progress.processed > progress.completed


def _keep_epoch_checkpoints(trainer: L.Trainer, pl_module: L.LightningModule) -> None:
    """Run the epoch-end save of every
    :class:`~lightning.pytorch.callbacks.ModelCheckpoint` (Lightning calls
    the checkpoint callbacks last): an interrupt in an earlier epoch-end
    hook stopped them, and a run resumed from that epoch's end never
    wrote that epoch's checkpoint. One that saved at this step already
    leaves it as it is."""
    from lightning.pytorch.callbacks import ModelCheckpoint
    for callback in trainer.checkpoint_callbacks:
        if isinstance(callback, ModelCheckpoint):
            callback.on_train_epoch_end(trainer, pl_module)


def _log_epoch_averages(trainer: L.Trainer) -> None:
    """Log the epoch's training averages (``train_loss_epoch``, ...) as
    Lightning logs them after the epoch-end hooks, which an interrupt in
    one of them stopped: a run resumed from that epoch's end goes on with
    the next, so no run logged them. A log that fails is a warning."""
    loop = trainer.fit_loop.epoch_loop
    loop._batches_that_stepped -= 1  # the step of the epoch's last batch, as Lightning's
    try:
        trainer._logger_connector.update_train_epoch_metrics()
    except Exception as err:  # the interrupt is what the user asked for
        warnings.warn(f"interrupted: could not log epoch {trainer.current_epoch}'s training "
                      f"averages ({' '.join(str(err).split())})", stacklevel=2)
    finally:
        loop._batches_that_stepped += 1


def _validating_in_fit(trainer: L.Trainer) -> bool:
    """Whether :meth:`~lightning.pytorch.Trainer.fit` is validating (its
    sanity check aside: no step has ended)."""
    return (trainer.validating and not trainer.sanity_checking
            and trainer.state.fn == "fit")


def _before_validation(checkpoint: Dict[str, Any]) -> None:
    """The validation counts of a checkpoint written at a Ctrl-C in the
    validation of a training run as those of one cut in its first batch:
    Lightning 2.6 resumes such a run by validating again, from the first
    batch, before the next training batch (its losses of the batches done
    are not in the checkpoint), and the loss of every step and every
    epoch's validation is that of a run never stopped (counted as at the end
    of the training batch before, the epoch's validation was skipped). The
    training counts stay as they are (the last batch done)."""
    loop = checkpoint["loops"]["fit_loop"]
    val = loop["epoch_loop.val_loop.batch_progress"]
    for key in ("ready", "started", "processed", "completed"):
        val["total"][key] -= val["current"][key] - (key in ("ready", "started"))
        val["current"][key] = int(key in ("ready", "started"))
    val["is_last_batch"] = False


def _reopen_cut_epoch(checkpoint: Dict[str, Any]) -> None:
    """An epoch that a stop cut short (``max_time``, ``max_steps``,
    ``should_stop``) is counted as processed when its end hooks write the
    checkpoint; counted back as unfinished, a resumed run trains its
    remaining batches, as a run never stopped would."""
    loop = checkpoint.get("loops", {}).get("fit_loop", {})
    batches = loop.get("epoch_loop.batch_progress", {})
    epochs = loop.get("epoch_progress", {})
    if not batches or not epochs or batches.get("is_last_batch", True):
        return
    for counts in (epochs["total"], epochs["current"]):
        ended = counts["completed"] == counts["processed"] - 1
        if counts["processed"] == counts["started"] and ended:
            counts["processed"] -= 1


_STEP = re.compile(r"(?:^|-)step=(\d+)(?:-v\d+)?\.ckpt$")


def epoch_checkpoints(checkpoints: Path) -> List[Path]:
    """The checkpoints a run keeps besides ``last.ckpt`` (the best epoch's,
    or every epoch's: ``epoch=E-step=S.ckpt``), newest step first; never the
    temporary file of a write that a kill cut short."""
    found = []
    with contextlib.suppress(OSError):
        for path in checkpoints.iterdir():
            match = _STEP.search(path.name)
            if match and not is_temp_file(path.name) and path.is_file():
                found.append((int(match.group(1)), path.name, path))
    return [path for *_, path in sorted(found, reverse=True)]


def resume_checkpoint(checkpoints: Path) -> Path:
    """The checkpoint ``--resume`` starts from: ``last.ckpt``, or
    ``last.prev.ckpt`` when the last one is damaged, or the newest epoch
    checkpoint where neither is whole (the run stopped before its first
    ``last.ckpt`` was written whole, or both are damaged), with a warning
    for either fallback; a damaged ``last.ckpt`` is moved aside to
    ``last.damaged.ckpt``.

    Raises:
        FileNotFoundError: None exists.
        CheckpointError: None can be loaded (every reason given).
    """
    last = checkpoints / LAST
    present = [c for c in (last, checkpoints / PREVIOUS) if c.exists()]
    newest = epoch_checkpoints(checkpoints)[:1]
    if not present and not newest:
        raise FileNotFoundError(f"--resume: no checkpoint at {last}")
    reasons = []
    for path in present + newest:
        try:
            ckpt = load_checkpoint(path, require=("state_dict", "loops", "optimizer_states"),
                                   what="resumable training checkpoint")
            del ckpt
        except CheckpointError as err:
            reasons.append(str(err))
            continue
        if path not in newest and not reasons:
            return path
        moved = bool(reasons) and last.exists()
        if moved:
            last.replace(checkpoints / DAMAGED)  # never rotated over a good one (replace:
            # Windows renames onto no existing file)
        warnings.warn(_fallback_note(checkpoints, path, reasons, moved), stacklevel=2)
        return path
    raise CheckpointError("--resume: no usable checkpoint: " + "; ".join(reasons))


def _fallback_note(checkpoints: Path, path: Path, reasons: List[str], moved: bool) -> str:
    """The warning of a resume from other than ``last.ckpt``: why (the
    damaged files, and whether ``last.ckpt`` was :obj:`moved` aside), and
    which checkpoint it goes on from."""
    if not reasons:  # stopped (kill -9, a full disk) before the first last.ckpt was whole
        why = f"no {LAST} in {checkpoints} (the run stopped before its first was written whole)"
    else:
        why = "; ".join(reasons) + (f" (moved to {checkpoints / DAMAGED})" if moved else "")
    which = "the previous checkpoint" if path.name == PREVIOUS else "its newest epoch checkpoint"
    return f"--resume: {why}; resuming from {which} {path}"


class LossLog(L.Callback):
    r"""Append ``step<TAB>loss<TAB>time`` (the exact float, then the wall
    clock in Unix seconds) to a file after every training step, written at
    once and whole (:func:`~satagraph.utils.files.append_whole`: a line a
    full disk cut short is taken back, where the resumed run's first line
    ran on from it): a record that survives ``kill -9``, and the time axis
    of a run's learning curve (:func:`read_loss_times`). A resumed run appends the
    steps it replays; the last line of a step counts (:func:`read_loss_log`).

    Args:
        path (str): The log file (``<run>/losses.tsv``).
    """

    def __init__(self, path: str) -> None:
        self.path = Path(path)

    def on_train_batch_end(self, trainer: L.Trainer, pl_module: L.LightningModule,
                           outputs: Any, batch: Any, batch_idx: int) -> None:
        loss = outputs.get("loss") if isinstance(outputs, dict) else outputs
        if loss is None or not trainer.is_global_zero:
            return
        append_whole(self.path, f"{trainer.global_step}\t{float(loss)!r}\t"
                     f"{time.time():.1f}\n".encode(), create_parent=True)


def read_loss_log(path: Path) -> Dict[int, float]:
    """``{step: loss}`` of a :class:`LossLog` file (the last line of each
    step)."""
    return {step: loss for step, (loss, _) in _loss_lines(path).items()}


def read_loss_times(path: Path) -> Dict[int, float]:
    """``{step: Unix time}`` of a :class:`LossLog` file (the last line of
    each step; lines written before times were logged are left out)."""
    return {step: when for step, (_, when) in _loss_lines(path).items() if when is not None}


def _loss_lines(path: Path) -> Dict[int, Tuple[float, Optional[float]]]:
    out: Dict[int, Tuple[float, Optional[float]]] = {}
    for line in Path(path).read_text().splitlines():
        fields = line.split("\t")
        if len(fields) >= 2 and fields[1]:
            out[int(fields[0])] = (float(fields[1]),
                                   float(fields[2]) if len(fields) > 2 else None)
    return out


# ------------------------------------------------------------ lock
def _holder(lock: Path) -> str:
    with contextlib.suppress(OSError):
        return lock.read_text().strip() or "unknown"
    return "unknown"


@contextlib.contextmanager
def run_lock(run_dir: Path, flag: str = "output_dir") -> Iterator[Path]:
    """Hold ``<run_dir>/.lock`` (see :func:`~satagraph.utils.files.lock_fd`:
    released by the system when the process ends, even by ``kill -9``) while
    training (a sweep: while it trains its configs; :obj:`flag` names the
    folder's setting).

    Raises:
        RunLockedError: Another live process holds it.
    """
    lock = run_dir / ".lock"
    fd, made = _take_lock(run_dir, flag)
    try:
        os.ftruncate(fd, 0)
        os.write(fd, f"pid {os.getpid()} on {socket.gethostname()}\n".encode())
        yield lock
    finally:
        if made:
            _drop_if_empty(made, lock)
        lock_fd(fd, take=False)
        os.close(fd)


def _take_lock(run_dir: Path, flag: str) -> Tuple[int, List[Path]]:
    """Open and lock ``<run_dir>/.lock``, making the folders it needs; again
    where the file was removed or replaced between the open and the lock
    (:func:`_drop_if_empty` of the run that held it): a lock on a removed
    file keeps no other run out.

    Returns:
        The descriptor, holding the lock, and the folders made (deepest first).

    Raises:
        RunLockedError: Another live process holds it.
    """
    lock = run_dir / ".lock"
    while True:
        made = [d for d in (run_dir, *run_dir.parents) if not d.exists()]  # deepest first
        run_dir.mkdir(parents=True, exist_ok=True)
        try:
            fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
        except FileNotFoundError:  # its folder removed meanwhile
            continue
        try:
            if not lock_fd(fd):
                raise RunLockedError(
                    f"{run_dir}: {flag} is in use by another live run ({_holder(lock)}); "
                    f"wait for it or choose another {flag}")
        except BaseException:
            os.close(fd)
            raise
        if names_fd(lock, fd):
            return fd, made
        lock_fd(fd, take=False)
        os.close(fd)


def _drop_if_empty(made: List[Path], lock: Path) -> None:
    """Remove the folders a run made (deepest first) where it left nothing
    but its lock: a run refused before its first step leaves no empty
    folders behind."""
    try:
        if [p.name for p in made[0].iterdir()] != [lock.name]:
            return
        lock.unlink()
        for folder in made:
            folder.rmdir()  # stops at the first that is not empty
    except OSError:
        pass


__all__ = ["TrainingStopped", "RunLockedError", "SafeCheckpointIO", "NonFiniteGuard",
           "ResumeCheckpoint", "resume_checkpoint", "epoch_checkpoints", "run_lock",
           "LossLog", "read_loss_log", "read_loss_times", "rng_states",
           "set_rng_states", "LAST", "PREVIOUS", "NONFINITE_MODES"]
