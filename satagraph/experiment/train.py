"""Build the data module, model and trainer from a config, and train."""
from __future__ import annotations

import contextlib
import inspect
import json
import logging
import os
import re
import signal
import threading
import warnings
import weakref
from dataclasses import fields
from pathlib import Path
from typing import Any, Dict, Optional, Tuple

import lightning as L
import torch
from torch import Tensor

from satagraph.experiment.config import dotted_settings, expand_path
# module_class and register_module: re-exported, the registry's face here
from satagraph.experiment.registry import (ModuleSections, build_registered,  # noqa: F401
                                           class_arguments, module_class, module_entry,
                                           register_module)
from satagraph.experiment.schema import (LoggerConfig, TrainerExtras, check_keys, fill,
                                         resolve_config, resolve_trainer)
from satagraph.data.datamodule import MotionDataModule, dataset_names
from satagraph.data.dataset import DEFAULT_PREPROCESSING
from satagraph.io.checkpoint import CheckpointError, check_finite_weights
from satagraph.io.weights import NORMALIZER_PREFIX, load_weights_or_checkpoint
from satagraph.utils.files import atomic_write_text, is_temp_file, sweep_stale_temps
from satagraph.lightning.reliability import (LossLog, NonFiniteGuard, ResumeCheckpoint,
                                             SafeCheckpointIO, resume_checkpoint,
                                             run_lock)

def data_section(cfg: Dict[str, Any]) -> Dict[str, Any]:
    """The ``data`` section of a resolved config; its sampling and
    augmentation seed is the run's ``seed`` unless ``data.seed`` sets one."""
    data = dict(cfg["data"])
    if "seed" in data and data["seed"] is None:
        data["seed"] = int(cfg["seed"])
    return data


def build_datamodule(cfg: Dict[str, Any]):
    """The data module of a config: the module's registered one
    (:class:`MotionDataModule` by default) on :func:`data_section`."""
    cfg = resolve_config(cfg)
    return (module_entry(cfg["module"]).datamodule or MotionDataModule)(**data_section(cfg))


def module_sections(cfg: Dict[str, Any], dm: Optional[Any] = None) -> ModuleSections:
    """The module's own sections of a resolved config (``module_args`` as
    :attr:`~ModuleSections.extra`); the semantic width comes from the data
    module :obj:`dm` when it is not set."""
    model, data = dict(cfg["model"]), data_section(cfg)
    if dm is not None and model.get("semantic_channels") is None \
            and hasattr(dm, "semantic_channels"):
        model["semantic_channels"] = dm.semantic_channels
    preprocessing = dict(DEFAULT_PREPROCESSING, **(data.get("preprocessing") or {}))
    meta = {"module": cfg["module"], "semantic_encoder": data.get("semantic_encoder"),
            "window": int(data["window"]), "data": data}
    return ModuleSections(model=model, loss=cfg["loss"], optim=cfg["optim"],
                          fps=float(preprocessing["fps"]), meta=meta,
                          extra=dict(cfg.get("module_args") or {}))


def check_config(cfg: Dict[str, Any]) -> Dict[str, Any]:
    """The config resolved and every key checked, the module's sections and
    the trainer's included, and an online logger's login, before any data
    is read."""
    cfg = resolve_config(cfg)
    module_entry(cfg["module"]).check(module_sections(cfg))
    check_local_conv(cfg["model"].get("local_conv"))
    if (cfg.get("data") or {}).get("train_transform"):
        from satagraph.data.window_transform import window_transform
        window_transform(cfg["data"]["train_transform"])  # registered, before any data is read
    check_keys("trainer", cfg["trainer"], trainer_keys())
    check_accelerator(cfg["trainer"])
    check_logger(cfg["logger"])
    check_wandb_login(cfg["logger"])
    return cfg


def check_accelerator(trainer: Dict[str, Any]) -> None:
    """A ``trainer.accelerator`` Lightning does not know, one this machine
    lacks (``gpu`` or ``cuda`` without CUDA, ``mps`` without MPS) or more
    GPUs in ``trainer.devices`` than it has is one line before any data is
    read (it was Lightning's error after the data was read).

    Raises:
        ValueError: What the trainer needs and what runs here.
    """
    from lightning.pytorch.accelerators import AcceleratorRegistry
    given = trainer.get("accelerator") or "auto"
    known = sorted(set(AcceleratorRegistry.available_accelerators()) | {"auto", "gpu"})
    if isinstance(given, str) and given not in known:
        raise ValueError(f"trainer.accelerator={given}: not an accelerator ({', '.join(known)})")
    kind = str(given).lower()
    if kind in ("gpu", "cuda"):
        have = torch.cuda.device_count() if torch.cuda.is_available() else 0
        devices = trainer.get("devices")
        wanted = devices if isinstance(devices, int) and devices > 0 else 1
        if have < wanted:
            raise ValueError(f"trainer.accelerator={kind}: needs {wanted} CUDA GPU(s), this "
                             f"machine has {have}; trainer.accelerator=auto runs on what "
                             "there is")
    if kind == "mps" and not torch.backends.mps.is_available():
        raise ValueError("trainer.accelerator=mps: no MPS device on this machine; "
                         "trainer.accelerator=auto runs on what there is")


#: The loggers ``logger.name`` takes.
LOGGERS = ("wandb", "csv", "tensorboard", "none")
_BAD_PROJECT = re.compile(r"[/\\#?%:]")


def check_logger(logger: Dict[str, Any]) -> None:
    """A logger that cannot log is one line before any data is read: an
    unknown name, TensorBoard without its package (a message naming no
    package, after loading), W&B missing or failing to import (a traceback
    once the data was read), a W&B project name W&B refuses (a 50-line
    traceback) or an empty one (the run went into ``lightning_logs``).

    Raises:
        ValueError: What to set.
    """
    import importlib.util
    name = logger.get("name")
    if name not in LOGGERS:
        raise ValueError(f"logger.name={name}: use {', '.join(LOGGERS)}")
    if name == "tensorboard" and not any(importlib.util.find_spec(m)
                                         for m in ("tensorboard", "tensorboardX")):
        raise ValueError("logger.name=tensorboard needs the tensorboard package, which is "
                         "not installed: pip install tensorboard (or logger.name=csv)")
    if name == "wandb":
        check_wandb_imports()
    project = str(logger.get("project") or "")
    if name == "wandb" and (not project.strip() or _BAD_PROJECT.search(project)):
        raise ValueError(f"logger.project={project!r}: W&B needs a non-empty name without "
                         "/ \\ # ? % : (default satagraph)")


def check_wandb_imports() -> None:
    """The W&B package imports (a broken install raises on import, past
    Lightning's check of its version).

    Raises:
        ValueError: One line naming the import error and the ways on.
    """
    try:
        import wandb  # noqa: F401
    except ImportError as err:
        detail = " ".join(str(err).split())[:160]
        raise ValueError(f"logger.name=wandb: the wandb package does not import ({detail}): "
                         "pip install wandb, or logger.name=csv") from None


def check_local_conv(name: Any) -> None:
    """A ``model.local_conv`` that names no layer is one line before any
    data is read (it was one after).

    Raises:
        ValueError: The known names, and how to add one.
    """
    from satagraph.nn.layers.local_conv import check_local_conv as known
    try:
        known(name)
    except ValueError as err:
        raise ValueError(f"model.local_conv: {err}, in a file SATAGRAPH_PLUGINS names "
                         "for the command line") from None


def check_registered_conv(name: Any, ckpt: str) -> None:
    """A checkpoint's ``model.local_conv`` that this process has not
    registered (:func:`~satagraph.nn.register_local_conv`) is one line
    naming the file, after the :data:`~satagraph.experiment.registry.PLUGIN_VARIABLE`
    plugins are imported (it was the registry's bare line, naming no file).

    Raises:
        CheckpointError: The layer is not registered here.
    """
    from satagraph.experiment.registry import import_user_plugins
    from satagraph.nn.layers.local_conv import check_local_conv as known
    try:
        known(name)
        return
    except ValueError:
        import_user_plugins()
    try:
        known(name)
    except ValueError:
        raise CheckpointError(f"{ckpt}: its model.local_conv {name!r} is not registered here: "
                              "import the code that registers it (register_local_conv) first, "
                              "or name it in SATAGRAPH_PLUGINS for the command line") from None


def check_wandb_login(logger: Dict[str, Any]) -> None:
    """Online W&B logging needs a login (``WANDB_API_KEY``, or the
    ``~/.netrc`` entry ``wandb login`` writes); without one it failed with a
    50-line traceback once the data had loaded.

    Raises:
        ValueError: One line saying what to do.
    """
    import netrc
    if logger.get("name") != "wandb" or logger.get("offline", True):
        return
    if os.environ.get("WANDB_API_KEY") or os.environ.get("WANDB_MODE") in ("offline",
                                                                            "disabled"):
        return
    try:
        host = os.environ.get("WANDB_BASE_URL", "https://api.wandb.ai").split("//")[-1]
        if netrc.netrc().authenticators(host):
            return
    except (OSError, netrc.NetrcParseError):
        pass
    raise ValueError("logger.offline=false: W&B needs a login (`wandb login`, or "
                     "WANDB_API_KEY); logger.offline=true logs into the run folder instead, "
                     "to `wandb sync` later (in `satagraph sweep`, whose --logger wandb is "
                     "online: --logger config keeps each config's own logger)")


def build_module(cfg: Dict[str, Any], dm: Optional[Any] = None):
    """The LightningModule for a config, built by its registered builder
    from its own sections (:func:`module_sections`)."""
    cfg = resolve_config(cfg)
    module = build_registered(cfg["module"], module_sections(cfg, dm))
    if dm is not None and hasattr(dm, "normalizer"):
        module.normalizer.load_state_dict(dm.normalizer.state_dict())
    return module


def build_logger(cfg: Dict[str, Any], run_dir: Path, resume: bool = False):
    """``logger.name``: ``wandb`` (offline by default: :func:`wandb_mode`),
    ``csv``, ``tensorboard`` or ``none``; resuming, a W&B run goes on under
    the run folder's last run id (it started a new run). A W&B run's config
    is the run's whole config, ``output_dir`` the run folder's absolute path
    (it held the module's sections alone: no seed, trainer or run folder to
    find the checkpoints by)."""
    spec = fill("logger", LoggerConfig, cfg.get("logger"))
    name = spec.pop("name")
    if name == "none":
        return False
    if name == "csv":
        return L.pytorch.loggers.CSVLogger(str(run_dir), name="logs")
    if name == "tensorboard":
        return L.pytorch.loggers.TensorBoardLogger(str(run_dir), name="logs")
    if name == "wandb":
        from lightning.pytorch.loggers import WandbLogger
        finish_started_wandb_runs()
        previous = _last_wandb_id(run_dir) if resume else None
        extra = {"id": previous, "resume": "allow"} if previous else {}
        logger = WandbLogger(name=cfg["name"], save_dir=str(run_dir),
                             mode=wandb_mode(spec.pop("offline")),
                             config=dict(cfg, output_dir=str(run_dir.absolute())), **spec,
                             **extra)
        _WANDB_LOGGERS.add(logger)
        return logger
    raise ValueError(f"unknown logger {name!r}: use {', '.join(LOGGERS)}")


#: The W&B loggers :func:`build_logger` made (held weakly).
_WANDB_LOGGERS: "weakref.WeakSet" = weakref.WeakSet()


def finish_started_wandb_runs() -> None:
    """Finish the W&B run an earlier :func:`build_logger` of this process
    started, where nothing finished it (a script's or notebook's earlier
    :func:`train`): Lightning logs into a run in progress, so the next run
    logged into that one (under its name and config, its steps starting
    over), a resume too. A run of one's own (``wandb.init()`` before
    training) is still the one logged into."""
    import wandb
    for logger in list(_WANDB_LOGGERS):
        run = getattr(logger, "_experiment", None)
        if run is not None and run is wandb.run:
            run.finish()
    _WANDB_LOGGERS.clear()


def wandb_mode(offline: bool) -> Optional[str]:
    """The ``mode`` of a W&B run: ``disabled`` where ``WANDB_MODE`` says so,
    else ``offline`` for :obj:`offline`, else ``WANDB_MODE``'s (online by
    default). Lightning's own ``offline=True`` set ``WANDB_MODE`` for the
    whole process: ``WANDB_MODE=disabled`` was overridden, and a later online
    run of the same process (a sweep's, a notebook's) went offline without
    a word."""
    if os.environ.get("WANDB_MODE") == "disabled":
        return "disabled"
    return "offline" if offline else None


def _last_wandb_id(run_dir: Path) -> Optional[str]:
    """The id of the last W&B run under :obj:`run_dir` (its folder
    ``wandb/[offline-]run-<date>_<time>-<id>``), or ``None``."""
    runs = sorted((run_dir / "wandb").glob("*run-*-*"), key=lambda p: p.name.split("run-")[-1])
    return runs[-1].name.rsplit("-", 1)[-1] if runs else None


def trainer_keys() -> set:
    """The ``trainer`` keys: :class:`lightning.Trainer`'s arguments and
    :class:`~satagraph.experiment.schema.TrainerExtras`'; ``callbacks`` and
    ``plugins`` are added to the run's own."""
    return set(inspect.signature(L.Trainer).parameters) | set(
        f.name for f in fields(TrainerExtras))


def build_trainer(cfg: Dict[str, Any], run_dir: Path, resume: bool = False,
                  **overrides: Any) -> L.Trainer:
    """The trainer of a config: ``last.ckpt`` by :class:`ResumeCheckpoint`
    (``checkpoint.every_n_steps`` / ``every_minutes``, and every epoch end),
    the best ``val_loss`` by :class:`ModelCheckpoint` (every epoch's with
    ``checkpoint.keep_every_epoch``), non-finite losses and
    gradients handled by :class:`NonFiniteGuard` (``nonfinite``: ``stop`` or
    ``skip``), checkpoints written atomically and loaded safely
    (:class:`SafeCheckpointIO`); ``loss_log: true`` appends every step's
    loss to ``<run>/losses.tsv`` (:class:`LossLog`); ``optim.ema`` > 0
    validates and checkpoints a moving average of the weights
    (:func:`weight_average`)."""
    from lightning.pytorch.callbacks import ModelCheckpoint, RichProgressBar
    cfg = resolve_config(cfg)
    own = {k: overrides.pop(k) for k in ("logger", "default_root_dir") if k in overrides}
    opts = resolve_trainer(dict(cfg["trainer"], **overrides))
    check_keys("trainer", opts, trainer_keys())
    opts["gradient_clip_val"] = cfg["optim"]["grad_clip"]
    folder = run_dir / "checkpoints"
    spec = cfg["checkpoint"]
    last = ResumeCheckpoint(str(folder), spec["every_n_steps"], spec["every_minutes"])
    monitor = opts.pop("monitor")
    if opts.get("limit_val_batches") == 0:  # nothing validated: no 40-key warning about it
        monitor = None
    best = ModelCheckpoint(dirpath=str(folder), save_last=False, mode="min",
                           monitor=monitor,
                           save_top_k=-1 if spec["keep_every_epoch"] else 1)
    guard = NonFiniteGuard(cfg["nonfinite"], str(last.last_path))
    # the average is updated before any checkpoint of the same step is written
    callbacks = [weight_average(cfg["optim"]["ema"])] if cfg["optim"]["ema"] else []
    callbacks += [best, last, guard] + list(opts.pop("callbacks", None) or [])
    if cfg["loss_log"]:
        callbacks.append(LossLog(str(run_dir / "losses.tsv")))
    if opts.pop("progress"):
        callbacks.append(RichProgressBar())
    plugins = list(opts.pop("plugins", None) or []) + [SafeCheckpointIO()]
    logger = own["logger"] if "logger" in own else build_logger(cfg, run_dir, resume)
    with _without_tips():
        return L.Trainer(logger=logger,
                         default_root_dir=own.get("default_root_dir", str(run_dir)),
                         callbacks=callbacks, plugins=plugins, **opts)


#: Where Lightning 2.6 says its info lines, among them a tip advertising a
#: cloud logger at every trainer's construction.
LIGHTNING_INFO = "lightning.pytorch.utilities.rank_zero"


class _NoTips(logging.Filter):
    """Drops Lightning's "Tip" lines (a cloud logging service advertised
    to every run), keeping its other info lines."""

    def filter(self, record: logging.LogRecord) -> bool:
        return "Tip:" not in str(record.msg)


@contextlib.contextmanager
def _without_tips():
    """Lightning's :class:`_NoTips` filter on its info logger while a
    trainer is built."""
    log, tips = logging.getLogger(LIGHTNING_INFO), _NoTips()
    log.addFilter(tips)
    try:
        yield
    finally:
        log.removeFilter(tips)


def weight_average(decay: float) -> L.Callback:
    r"""An exponential moving average of the weights, updated after every
    optimiser step (:math:`\bar\theta \leftarrow d\,\bar\theta + (1 - d)\,\theta`,
    a horizon of about :math:`1 / (1 - d)` steps): validation, the best
    checkpoint's choice and every checkpoint's ``state_dict`` (what
    ``--init-from``, :func:`load_module` and the weights export read) are
    the average's; the optimiser's own weights go on in
    ``current_model_state`` and resume from there. Buffers (codebooks,
    normalisers) follow the trained module unaveraged.

    Raises:
        ValueError: :obj:`decay` outside (0, 1).
    """
    from lightning.pytorch.callbacks import EMAWeightAveraging
    if not 0.0 < float(decay) < 1.0:
        raise ValueError(f"optim.ema must be 0 (none) or a decay in (0, 1), got {decay!r}")
    return EMAWeightAveraging(decay=float(decay), use_buffers=False)


def last_checkpoint(trainer: L.Trainer) -> str:
    """The ``last.ckpt`` path of a trainer built by :func:`build_trainer`."""
    for callback in trainer.callbacks:
        if isinstance(callback, ResumeCheckpoint):
            return str(callback.last_path)
    return trainer.checkpoint_callback.last_model_path


#: A VAE bottleneck's projection (mean, then log-variance) and an RVQ
#: bottleneck's (the latent it quantises).
_VAE_PROJ, _RVQ_PROJ = "model.bottleneck.lin.", "model.bottleneck.proj."


def vae_to_rvq(state: Dict[str, Tensor], own: Dict[str, Tensor]) -> Dict[str, Tensor]:
    r"""A VAE's weights for an RVQ module: the RVQ's projection starts as the
    VAE's mean half, so that the decoder first sees the latents it was
    trained on (the codebooks are then fitted to them by k-means). Other
    states pass unchanged."""
    key = _RVQ_PROJ + "weight"
    if key not in own or _VAE_PROJ + "weight" not in state:
        return state
    width = own[key].shape[0]
    out = {k: v for k, v in state.items() if not k.startswith(_VAE_PROJ)}
    for part in ("weight", "bias"):
        mean = state[_VAE_PROJ + part][:width]
        if mean.shape == own[_RVQ_PROJ + part].shape:
            out[_RVQ_PROJ + part] = mean
    return out


#: Where a fine-tune's normaliser comes from (``--init-normalizer``): fitted
#: on the new data, or the checkpoint's own.
INIT_NORMALIZERS = ("data", "checkpoint")


def init_weights(module: L.LightningModule, ckpt: str, normalizer: str = "data",
                 payload: Optional[Dict[str, Any]] = None) -> None:
    """Load another run's weights into :obj:`module` for fine-tuning.

    The module keeps its own normaliser (fitted on the new data) when
    :obj:`normalizer` is ``"data"``; the checkpoint's loads when it is
    ``"checkpoint"`` or when parts of the module are frozen
    (``optim.frozen``: a frozen encoder reads the data as the checkpoint's
    normaliser did). A network can be very sensitive to a refit: `builtin`
    reads zoo bipeds at 3.1 % of their height with its own normaliser and
    at 16.9 % with one refitted on ``pretrain_zoo_lie``'s data
    (``experiments/PRETRAIN.md`` section 32). The module also keeps what
    its ``init_keeps`` prefixes name (a text-to-motion module's frozen
    autoencoder: the one its config gives, not the checkpoint's).
    :obj:`ckpt` is a checkpoint, a ``.safetensors`` weights file or
    ``"builtin"``. A VAE's bottleneck starts an RVQ's (:func:`vae_to_rvq`);
    a module with ``init_meta`` is given the checkpoint's ``meta`` (a
    text-to-motion module keeps the words its weights learnt).
    Warns about weights the checkpoint lacks, has in excess (e.g. another
    bottleneck) or has in another shape (e.g. another codebook size), which
    keep their initialisation. :obj:`payload`: :obj:`ckpt` already read
    (:func:`load_weights_or_checkpoint`), not read again."""
    frozen = getattr(module, "frozen_parts", lambda: [])()
    if normalizer not in INIT_NORMALIZERS:
        raise ValueError(f"--init-normalizer must be one of {INIT_NORMALIZERS}, got "
                         f"{normalizer!r}")
    refit = not frozen and normalizer == "data"
    keep = ((NORMALIZER_PREFIX,) if refit else ()) + tuple(getattr(module, "init_keeps", ()))
    own = module.state_dict()
    if payload is None:
        payload = load_weights_or_checkpoint(ckpt, kind=builtin_kind(module))
    if hasattr(module, "init_meta"):
        module.init_meta((payload.get("hyper_parameters") or {}).get("meta") or {})
    state = payload["state_dict"]
    _warn_other_kept_part(ckpt, state, own, tuple(getattr(module, "init_keeps", ())))
    state = vae_to_rvq({k: v for k, v in state.items() if not k.startswith(keep)}, own)
    reshaped = [k for k, v in state.items() if k in own and own[k].shape != v.shape]
    state = {k: v for k, v in state.items() if k not in reshaped}
    _refuse_other_architecture(ckpt, payload, module, own, state, keep)
    result = module.load_state_dict(state, strict=False)
    missing = [k for k in result.missing_keys if not k.startswith(keep) and k not in reshaped]
    if missing or result.unexpected_keys or reshaped:
        warnings.warn(f"--init-from {ckpt}: {len(missing)} weights not in the checkpoint "
                      f"(kept at initialisation: {missing[:5]}), "
                      f"{len(result.unexpected_keys)} unused "
                      f"({result.unexpected_keys[:5]}), {len(reshaped)} of another shape "
                      f"(kept at initialisation: {reshaped[:5]})", stacklevel=2)


def _warn_other_kept_part(ckpt: str, state: Dict[str, torch.Tensor],
                          own: Dict[str, torch.Tensor], kept: Tuple[str, ...]) -> None:
    """Warn when the part a module keeps (``init_keeps``: a text-to-motion
    module's frozen autoencoder) is another in the checkpoint, its decoder
    aside: the checkpoint's transformers learnt that part's codes, which
    mean something else here (a warning, not a refusal: the length model
    alone reads no codes, and may be taught so)."""
    for key in sorted(k for k in own if k.startswith(kept) and ".decoder." not in f".{k}"):
        theirs = state.get(key)
        if theirs is not None and (theirs.shape != own[key].shape
                                   or not torch.equal(theirs.to(own[key].dtype), own[key])):
            part = key.split(".")[0]
            warnings.warn(f"--init-from {ckpt}: trained over another {part} than this "
                          f"config's ({key} differs): the weights that read its codes learnt "
                          f"that one's; set model.{part} to the checkpoint it was trained "
                          "over, unless only what reads no codes trains (the length model)",
                          stacklevel=3)
            return


def builtin_kind(module: Any) -> str:
    """Which built-in weights ``"builtin"`` names for a module or module
    class (its ``builtin_kind``; :data:`~satagraph.io.weights.BUILTIN_FILES`):
    an autoencoder's unless the class says otherwise."""
    return getattr(module, "builtin_kind", "autoencoder")


#: The config that fine-tunes each kind of built-in weights.
BUILTIN_FINETUNES = {"autoencoder": "finetune_builtin", "text-to-motion": "finetune_t2m_builtin"}


#: Fewest of a module's weights (a fraction) that ``--init-from`` must fill;
#: below it the checkpoint is another architecture and training would start
#: from scratch under a fine-tune's name.
MIN_INIT_FRACTION = 0.5


def _refuse_other_architecture(ckpt: str, payload: Dict[str, Any], module: L.LightningModule,
                               own: Dict[str, torch.Tensor], state: Dict[str, torch.Tensor],
                               keep: Tuple[str, ...]) -> None:
    """One line when fewer than :data:`MIN_INIT_FRACTION` of the module's
    weights would load, naming the model settings that differ."""
    wanted = [k for k in own if not k.startswith(keep)]
    filled = sum(k in state for k in wanted)
    if not wanted or filled >= MIN_INIT_FRACTION * len(wanted):
        return
    theirs = dotted_settings((payload.get("hyper_parameters") or {}).get("model") or {}, "model")
    ours = dotted_settings(dict(getattr(module, "hparams", {}).get("model") or {}), "model")
    skip = ("model.semantic_channels",) + tuple(f"model.{k}" for k in keep)
    differ = [f"{k}={v}" for k, v in sorted(theirs.items())
              if k in ours and ours[k] != v and not k.startswith(skip)]
    hint = (f"train with its settings ({' '.join(differ[:6])})" if differ
            else "train with the config that made it")
    raise ValueError(f"--init-from {ckpt}: only {filled} of {len(wanted)} weights fit this "
                     f"model: it is another architecture; {hint}"
                     + (f"; for the built-in model: satagraph train "
                        f"{BUILTIN_FINETUNES[builtin_kind(module)]} --init-from builtin "
                        "--data FOLDER" if str(ckpt).startswith("builtin") else ""))


def _spawns_workers(trainer: L.Trainer) -> bool:
    """Whether :meth:`~lightning.pytorch.Trainer.fit` pickles its arguments
    into new processes (``strategy="ddp_spawn"``)."""
    launcher = getattr(trainer.strategy, "launcher", None)
    return getattr(launcher, "_start_method", None) in ("spawn", "forkserver")


def check_init_features(payload: Dict[str, Any], cfg: Dict[str, Any], name: str) -> None:
    """Refuses to start from weights whose features turn the facing frame
    otherwise than :obj:`cfg`'s (``data.preprocessing.facing_smooth``): the
    root features would mean something else to them. A module that keeps
    its own autoencoder rather than the checkpoint's (``init_keeps``: a
    text-to-motion generator) is not asked: it checks its data against that
    autoencoder when built."""
    from satagraph.data.dataset import data_facing_smooth
    meta = (payload.get("hyper_parameters") or {}).get("meta") or {}
    if "data" not in meta or getattr(module_class(cfg["module"]), "init_keeps", ()):
        return
    theirs, ours = data_facing_smooth(meta["data"]), data_facing_smooth(data_section(cfg))
    if theirs != ours:
        raise ValueError(f"--init-from {name}: trained with data.preprocessing.facing_smooth="
                         f"{theirs:g}, this config has {ours:g}; set "
                         f"data.preprocessing.facing_smooth={theirs:g}")


def _refuse_spawned_import() -> None:
    """Refuse a run started while a worker process imports the script that
    called :func:`train`: ``data.num_workers`` > 0 starts workers by
    ``spawn`` on macOS and Windows, which run the script again, and a
    script without a main guard started a second run in each worker (a
    lock error there, "DataLoader worker exited unexpectedly" here)."""
    frame = inspect.currentframe()
    while frame is not None and not (frame.f_code.co_name == "<module>"
                                     and frame.f_globals.get("__name__") == "__mp_main__"):
        frame = frame.f_back
    if frame is not None:
        raise RuntimeError("train(): called while a worker process imports your script "
                           "(workers start by 'spawn' on macOS and Windows and run it "
                           "again): put the training code under "
                           "'if __name__ == \"__main__\":'")


def train(cfg: Dict[str, Any], resume: bool = False, init_from: Optional[str] = None,
          init_normalizer: str = "data",
          **trainer_overrides: Any) -> Tuple[Any, MotionDataModule, L.Trainer, Path]:
    r"""Train a model from a config dict (see ``experiments/``).

    Args:
        cfg (dict): The config (plain containers).
        resume (bool): Continue from ``<run>/checkpoints/last.ckpt``.
        init_from (str, optional): Start from another run's weights (fine-
            tuning on a new dataset); the normaliser of the new data is used
            unless :obj:`init_normalizer` is ``"checkpoint"`` (see
            :func:`init_weights`).
        init_normalizer (str): ``"data"`` (default) or ``"checkpoint"``.
        **trainer_overrides: Keyword arguments of :class:`lightning.Trainer`
            over the config's ``trainer`` section (``callbacks=[...]`` are
            added to the run's own; ``logger=`` replaces the config's
            ``logger``; ``default_root_dir=`` is Lightning's own folder,
            while the run's checkpoints and records stay in ``output_dir``).

    Returns:
        The trained module, the data module, the trainer and the run folder.
    """
    _refuse_spawned_import()
    cfg = check_config(cfg)
    run_dir = Path(expand_path(cfg["output_dir"] or f"runs/{cfg['name']}"))
    if run_dir.exists() and not run_dir.is_dir():
        raise ValueError(f"{run_dir}: output_dir is not a folder")
    if resume and not (run_dir / "checkpoints").is_dir():
        raise FileNotFoundError(f"--resume: no checkpoint at "
                                f"{run_dir / 'checkpoints' / 'last.ckpt'}")
    if init_from:  # a bad file, or one of other features, fails before any work
        payload = load_weights_or_checkpoint(init_from,
                                             kind=builtin_kind(module_class(cfg["module"])))
        check_init_features(payload, cfg, init_from)
    if cfg["threads"]:
        torch.set_num_threads(int(cfg["threads"]))
    with _lock(run_dir):
        if not resume:  # under the lock: a run that ended meanwhile is seen
            refuse_trained_folder(run_dir)
        last = resume_checkpoint(run_dir / "checkpoints") if resume else None
        if last is not None:
            check_resumable(last, cfg)
        sweep_stale_temps(run_dir / "checkpoints")
        L.seed_everything(int(cfg["seed"]), workers=True)
        dm = build_datamodule(cfg)
        dm.setup("fit")
        if _no_validation(dm):  # said by the data module; nothing to validate
            trainer_overrides = dict(trainer_overrides, monitor=None, limit_val_batches=0)
        else:
            check_monitor(trainer_overrides.get("monitor", cfg["trainer"].get("monitor")), dm)
        _record_skipped(dm, run_dir)
        module = build_module(cfg, dm)
        if init_from:
            init_weights(module, init_from, init_normalizer, payload)
        _record_config(cfg, run_dir)  # once nothing refuses the run
        _record_data_files(dm, run_dir, resumed=last is not None)
        trainer = build_trainer(cfg, run_dir, resume=last is not None, **trainer_overrides)
        # Spawned workers get the data module pickled: hand them one that is not
        # set up (its datasets hold the semantic embedder, a closure); each worker
        # sets it up from the feature cache.
        fit_dm = build_datamodule(cfg) if _spawns_workers(trainer) else dm
        with warnings.catch_warnings():
            # the sampler resumes mid-epoch itself (ResumeCheckpoint)
            warnings.filterwarnings("ignore", message=".*dataloader is not resumable")
            # Lightning 2.6's loaders build torch's deprecated LeafSpec (torch 2.13), once
            # per fit and validation: a line of every run that no user can act on
            warnings.filterwarnings("ignore", message=r"`isinstance\(treespec, LeafSpec\)`",
                                    category=FutureWarning,
                                    module=r"lightning\.pytorch\.utilities\._pytree")
            # a run stopped before its first validation (sweep --steps shorter than an
            # epoch) has no best epoch yet: Lightning said so naming every logged key
            warnings.filterwarnings("ignore", message=r"`ModelCheckpoint\(monitor=.* could not "
                                    "find the monitored key")
            if last is not None:  # a resume's own folder, which it expects full (only it)
                own = re.escape(os.path.realpath(run_dir / "checkpoints"))
                warnings.filterwarnings("ignore", message=f"Checkpoint directory {own} exists "
                                        "and is not empty")
            _fit_interruptibly(trainer, module, fit_dm, last)
    return module, dm, trainer, run_dir


def check_monitor(monitor: Optional[str], dm) -> None:
    """Refuse, before any step, a ``trainer.monitor`` of one dataset's
    figures (``val/<dataset>/<name>``) that no validation window is of: the
    run trained a whole epoch, then stopped in a traceback naming every
    logged key.

    Raises:
        ValueError: One line naming the monitor and the validation datasets.
    """
    val = (getattr(dm, "datasets", None) or {}).get("val")
    if not monitor or not monitor.startswith("val/") or monitor.count("/") < 2 \
            or val is None:
        return
    dataset, names = monitor[len("val/"):monitor.rindex("/")], dataset_names(val)
    if names is not None and dataset not in names:
        raise ValueError(f"trainer.monitor={monitor}: no validation window is of dataset "
                         f"{dataset!r} (validation datasets: {', '.join(sorted(names))})")


def _no_validation(dm) -> bool:
    """Whether a data module holds a validation split without a window (a
    registered module's own data module may keep its splits otherwise)."""
    val = (getattr(dm, "datasets", None) or {}).get("val")
    return val is not None and len(val) == 0


def check_resumable(path: Path, cfg: Dict[str, Any]) -> None:
    """Refuse to resume a run with a model of other settings (its weights
    would not load) or on other data (the run would go on silently, its
    record then naming data it mostly did not see).

    Raises:
        ValueError: One line naming the checkpoint and what differs.
    """
    from satagraph.io.checkpoint import load_checkpoint
    hp = load_checkpoint(path).get("hyper_parameters") or {}
    theirs, ours = hp.get("model") or {}, cfg.get("model") or {}
    differ = [f"model.{k}={_short(theirs[k])} (here {_short(ours[k])})" for k in sorted(theirs)
              if k in ours and ours[k] is not None and not _same_setting(ours[k], theirs[k])]
    theirs_optim, ours_optim = hp.get("optim") or {}, cfg.get("optim") or {}
    differ += [f"optim.{k}={theirs_optim[k]} (here {ours_optim[k]}: a resume keeps the "
               "optimiser's own state)" for k in sorted(theirs_optim)
               if k in ours_optim and ours_optim[k] != theirs_optim[k]]
    differ += [f"module_args.{k}={hp[k]} (here {v})"
               for k, v in sorted((cfg.get("module_args") or {}).items())
               if k in hp and hp[k] != v]
    differ += _data_differences((hp.get("meta") or {}).get("data"), data_section(cfg))
    if differ:
        raise ValueError(f"--resume {path}: the run was trained with {'; '.join(differ[:4])}; "
                         "resume with its own settings, or start from its weights in another "
                         "output_dir with --init-from")


#: ``data`` settings a resume may change: where and how fast the same
#: windows are read, not which.
RESUME_MAY_CHANGE = ("num_workers", "cache_dir", "on_error")


def _data_differences(before: Optional[Dict[str, Any]], now: Dict[str, Any]) -> list:
    """The ``data`` settings a run recorded that a resume would change (the
    sources, windows, batch size, augmentation, preprocessing, ...: the
    run went on silently on other windows, and its config recorded
    only the new ones), but those of :data:`RESUME_MAY_CHANGE`."""
    if before is None:  # a run of before meta.data
        return []
    flat_before, flat_now = (dotted_settings({"data": d}) for d in (before, now))
    free = tuple(f"data.{k}" for k in RESUME_MAY_CHANGE)
    return [f"{k}={_short(flat_before[k])} (here {_short(flat_now[k])})"
            for k in sorted(set(flat_before) & set(flat_now))  # a newer key: its default
            if not k.startswith(free) and json.dumps(flat_before[k], sort_keys=True, default=str)
            != json.dumps(flat_now[k], sort_keys=True, default=str)]


def _same_setting(ours: Any, theirs: Any) -> bool:
    """Whether a config value is what a run recorded: a text-to-motion run
    records its autoencoder as ``{"checkpoint": path, "hparams": ...}``
    where the config names the path (resuming one was always refused)."""
    if isinstance(theirs, dict) and "checkpoint" in theirs and isinstance(ours, str):
        theirs = theirs["checkpoint"]
        if isinstance(theirs, str) and os.path.exists(ours) and os.path.exists(theirs):
            return os.path.samefile(ours, theirs)
        return os.path.normpath(str(theirs)) == os.path.normpath(ours)
    return ours == theirs


def _short(value: Any, limit: int = 80) -> str:
    """A setting as a message shows it (a recorded autoencoder by its path)."""
    if isinstance(value, dict) and "checkpoint" in value:
        value = value["checkpoint"]
    text = str(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def refuse_trained_folder(run_dir: Path) -> None:
    """Refuse to start a new run in a folder that holds a trained one: its
    checkpoints would be replaced and its loss log mixed with the new run's.

    Raises:
        ValueError: One line naming the folder and the ways on.
    """
    folder = run_dir / "checkpoints"
    kept = sorted(p.name for p in folder.glob("*.ckpt")  # not a write a kill cut short
                  if not is_temp_file(p.name)) if folder.is_dir() else []
    if kept:
        raise ValueError(f"{run_dir}: holds a trained run ({len(kept)} checkpoint(s): "
                         f"{', '.join(kept[:3])}{', ...' if len(kept) > 3 else ''}); "
                         "--resume continues it, another output_dir starts a new one "
                         "(or delete the folder to start over)")


def _fit_interruptibly(trainer: L.Trainer, module: L.LightningModule, datamodule,
                       last: Optional[Path]) -> None:
    """:meth:`~lightning.pytorch.Trainer.fit`, a Ctrl-C given back as the
    :class:`KeyboardInterrupt` it was (Lightning ends one with ``exit(1)``
    and leaves Ctrl-C ignored), so that the command says how to resume and
    exits 130, and a notebook keeps its Ctrl-C; its argument is the step of
    the ``last.ckpt`` the interrupt wrote, where it wrote one
    (:meth:`ResumeCheckpoint.on_exception`). While it trains, a SIGTERM is
    Lightning's alone (it stops at the end of the batch, which
    :class:`ResumeCheckpoint` saves), not the command's handler's
    (:func:`~satagraph.cli.terminate_as_interrupt`: at once, in any step)."""
    handler = signal.getsignal(signal.SIGINT)
    main = threading.current_thread() is threading.main_thread()
    term = signal.signal(signal.SIGTERM, signal.SIG_DFL) if main else None
    try:
        trainer.fit(module, datamodule=datamodule, ckpt_path=str(last) if last else None)
    except SystemExit:
        if not trainer.interrupted:
            raise
        if main:
            signal.signal(signal.SIGINT, handler)
        saved = [c.interrupted_step for c in trainer.callbacks
                 if isinstance(c, ResumeCheckpoint) and c.interrupted_step is not None]
        raise KeyboardInterrupt(*saved[:1]) from None
    finally:
        if main and term is not None:
            signal.signal(signal.SIGTERM, term)


def _lock(run_dir: Path):
    """:func:`run_lock` in the launching process; processes that Lightning
    starts for distributed training (``LOCAL_RANK`` > 0) share it."""
    if int(os.environ.get("LOCAL_RANK", "0") or 0) > 0:
        return contextlib.nullcontext()
    return run_lock(run_dir)


def _record_config(cfg: Dict[str, Any], run_dir: Path) -> None:
    """Write the run's whole resolved config to ``<run>/config.yaml`` (the
    checkpoint's hyperparameters hold the module's sections only: not the
    trainer's, the seed, the checkpoint or logger settings); a resume
    writes the config it goes on with."""
    from omegaconf import OmegaConf
    atomic_write_text(run_dir / "config.yaml", OmegaConf.to_yaml(OmegaConf.create(cfg)),
                      create_parent=True)


#: The files a run started on, ``split<TAB>path`` a line, in its folder.
DATA_FILES = "data_files.txt"


def _data_files(dm) -> Optional[set]:
    """``(split, path)`` of every file the splits of a data module read
    (an endless zoo's windows aside), or ``None`` where its datasets name
    no files (a registered module's own data module)."""
    datasets = getattr(dm, "datasets", None) or {}
    if not datasets or not all(hasattr(ds, "files") for ds in datasets.values()):
        return None
    return {(split, str(getattr(f, "path", f))) for split, ds in datasets.items()
            for f in ds.files}


def _record_data_files(dm, run_dir: Path, resumed: bool) -> None:
    """Write the files a run starts on to ``<run>/data_files.txt`` (also
    over the record of a run stopped before its first checkpoint); a
    resumed run keeps it and says in one line how many were added to and
    removed from its data since (it went on silently): it trains on the
    files there now, each in its split (a folder's by file name, a
    manifest's by its column), with the normaliser of its first start,
    which its checkpoint holds (the one fitted on the files there now is
    not used: the model learnt its features in the first one's units). A
    resumed run without the record (deleted, or a run of before it) says in
    one line that it cannot tell, and records the files there now."""
    now, path = _data_files(dm), run_dir / DATA_FILES
    if now is None:
        return
    if not resumed or not path.is_file():  # the first start (or a run of before the record)
        if resumed:
            warnings.warn(f"--resume: no {path}: whether the data changed since the run "
                          "started cannot be checked; it goes on with the files there now "
                          "and records them", stacklevel=3)
        atomic_write_text(path, "".join(f"{s}\t{f}\n" for s, f in sorted(now)),
                          create_parent=True)
        return
    before = _read_data_files(path)
    added, removed = now - before, before - now
    if added or removed:
        warnings.warn(_changed_data_note(added, removed, path), stacklevel=3)


def _read_data_files(path: Path) -> set:
    """The ``(split, path)`` pairs of a run's :data:`DATA_FILES`.

    Raises:
        ValueError: A line that is not ``split<TAB>path``, or text that is
            not the UTF-8 the run wrote (one line naming the file).
    """
    redo = "delete the file to record the files there now"
    try:
        text = path.read_text(encoding="utf-8")  # as written, whatever the locale's
    except UnicodeDecodeError as err:
        raise ValueError(f"{path}: not UTF-8 as the run wrote it (byte {err.start}); "
                         f"{redo}") from None
    pairs = set()
    for number, line in enumerate(text.splitlines(), start=1):
        if not line:
            continue
        if "\t" not in line:
            raise ValueError(f"{path}:{number}: not 'split<TAB>path' as the run wrote it; "
                             f"{redo}")
        pairs.add(tuple(line.split("\t", 1)))
    return pairs


def _changed_data_note(added: set, removed: set, record: Path) -> str:
    """The line of a resume whose data changed: how many files, per split."""
    def change(split: str) -> str:
        counts = [(sign, sum(s == split for s, _ in files))
                  for sign, files in (("+", added), ("-", removed))]
        return f"{split} " + " ".join(f"{sign}{n}" for sign, n in counts if n)

    per = ", ".join(change(split) for split in sorted({s for s, _ in added | removed}))
    return (f"--resume: {len(added)} file(s) added to and {len(removed)} removed from the "
            f"data since the run started ({per}; its files: {record}); it goes on with the "
            "files there now, each in its split, and keeps the normaliser of its first start "
            "(in its checkpoint; not refitted to them)")


def _record_skipped(dm: MotionDataModule, run_dir: Path) -> None:
    """Write the files ``data.on_error=skip`` left out to
    ``<run>/skipped_files.txt`` (one ``split: path: reason`` per line), or
    remove the file when none was left out."""
    path = run_dir / "skipped_files.txt"
    if dm.skipped:
        atomic_write_text(path, "\n".join(dm.skipped) + "\n", create_parent=True)
    else:  # a resumed run whose files were mended since
        path.unlink(missing_ok=True)


def load_module(ckpt: str = "builtin", map_location: str = "cpu"):
    """A trained module, whatever its class, loaded safely: from a
    checkpoint (``weights_only=True``), a weights file (``.safetensors``,
    :mod:`satagraph.io.weights`) or ``"builtin"`` (the package's weights),
    in evaluation mode (a VAE's latent is then its mean, so the same input
    decodes the same; ``.train()`` before fine-tuning it by hand, which
    ``Trainer.fit`` does itself).

    Args:
        ckpt (str): A checkpoint path, a ``.safetensors`` weights file,
            ``"builtin"`` or ``"builtin-wide"``.
        map_location (str): Device the weights are loaded to.

    Returns:
        LightningModule: The module of the class its hyperparameters name
        (``meta.module``: :func:`~satagraph.experiment.registry.module_entry`),
        a subclass's own constructor arguments included
        (:func:`~satagraph.experiment.registry.class_arguments`).

    Raises:
        CheckpointError: The file is not a satagraph model checkpoint or
            weights file, is damaged, or holds non-finite weights; its
            ``meta.module`` or ``model.local_conv`` is not registered here
            (:func:`check_registered_conv`); or ``"builtin"`` and none ship
            (one line naming it).
    """
    data = load_weights_or_checkpoint(ckpt, require=("state_dict", "hyper_parameters"))
    hparams = dict(data["hyper_parameters"])
    if not isinstance(hparams.get("model"), dict):
        raise CheckpointError(f"{ckpt}: not a satagraph model checkpoint (no model "
                              "hyperparameters)")
    check_finite_weights(data, ckpt)
    check_registered_conv(hparams["model"].get("local_conv"), ckpt)
    meta = hparams.get("meta") or {}
    named, name = "module" in meta, meta.get("module", "vae")
    if not named:
        warnings.warn(f"{ckpt}: its hyperparameters name no module (meta.module): read as "
                      "the built-in 'vae' (a module of your own: build it with "
                      "meta={'module': NAME, ...}, as build_module does)", stacklevel=2)
    try:
        entry = module_entry(name)
    except ValueError as err:  # a subclass registered in code this process has not run
        raise CheckpointError(f"{ckpt}: a {name!r} model, which is not registered here: "
                              "import the code that registers it (register_module) first "
                              f"({' '.join(str(err).split())})") from None
    sections = ModuleSections(**{k: hparams[k] for k in ("model", "loss", "optim", "fps",
                                                         "meta") if hparams.get(k) is not None},
                              extra=class_arguments(entry.cls, hparams))
    module = entry.build(sections)
    module.on_load_checkpoint(data)
    try:
        module.load_state_dict(data["state_dict"])
    except RuntimeError as err:
        lines = [line.strip() for line in str(err).strip().splitlines()]
        detail = " ".join(lines[:2])[:200]
        if named:
            raise CheckpointError(f"{ckpt}: weights do not fit the {name!r} model its "
                                  f"hyperparameters describe ({detail})") from None
        raise CheckpointError(f"{ckpt}: its hyperparameters name no module (meta.module), "
                              f"so it was read as {name!r}, whose weights do not fit: build "
                              "a registered module with meta={'module': NAME, ...} (as "
                              f"build_module does), or load it with its own class ({detail})"
                              ) from None
    return module.to(map_location).eval()
