"""Build the data module, model and trainer from a config, and train."""
from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any, Dict, Optional, Tuple

import lightning as L
import torch

from satagraph.config import expand_path
from satagraph.data.datamodule import MotionDataModule
from satagraph.lightning import (PaddedRVQModule, SAMEModule, SATARVQModule,
                                 SATAVAEModule)

MODULES = {"vae": SATAVAEModule, "rvq": SATARVQModule, "same": SAMEModule,
           "padded_rvq": PaddedRVQModule}


def register_module(name: str, cls) -> None:
    """Make a LightningModule class selectable as ``module: name``."""
    MODULES[name] = cls


def module_class(name: str):
    """The LightningModule class registered under :obj:`name`."""
    if name not in MODULES:
        raise ValueError(f"unknown module {name!r}; known: {sorted(MODULES)}")
    return MODULES[name]


def build_datamodule(cfg: Dict[str, Any]) -> MotionDataModule:
    """The data module of a config; its sampling and augmentation seed is the
    run's ``seed`` unless ``data.seed`` sets one."""
    data = dict(cfg["data"])
    data.setdefault("seed", int(cfg.get("seed", 0)))
    return MotionDataModule(**data)


def build_module(cfg: Dict[str, Any], dm: Optional[MotionDataModule] = None):
    """The LightningModule for a config; the semantic width comes from the
    data when it is not set."""
    model = dict(cfg.get("model", {}))
    if dm is not None and model.get("semantic_channels") is None:
        model["semantic_channels"] = dm.semantic_channels
    name = cfg.get("module", "vae")
    data = cfg["data"]
    meta = {"module": name, "semantic_encoder": data.get("semantic_encoder", "offline"),
            "window": int(data.get("window", 64)), "data": data}
    module = module_class(name)(
        model=model, loss=cfg.get("loss"), optim=cfg.get("optim"),
        fps=float((data.get("preprocessing") or {}).get("fps", 30.0)), meta=meta)
    if dm is not None:
        module.normalizer.load_state_dict(dm.normalizer.state_dict())
    return module


def build_logger(cfg: Dict[str, Any], run_dir: Path):
    """``logger.name``: ``wandb`` (offline by default), ``csv``,
    ``tensorboard`` or ``none``."""
    spec = dict(cfg.get("logger") or {"name": "wandb"})
    name = spec.pop("name", "wandb")
    if name == "none":
        return False
    if name == "csv":
        return L.pytorch.loggers.CSVLogger(str(run_dir), name="logs")
    if name == "tensorboard":
        return L.pytorch.loggers.TensorBoardLogger(str(run_dir), name="logs")
    if name == "wandb":
        from lightning.pytorch.loggers import WandbLogger
        spec.setdefault("offline", True)
        spec.setdefault("project", "satagraph")
        return WandbLogger(name=cfg["name"], save_dir=str(run_dir), **spec)
    raise ValueError(f"unknown logger {name!r}: use wandb, csv, tensorboard or none")


def build_trainer(cfg: Dict[str, Any], run_dir: Path, **overrides: Any) -> L.Trainer:
    from lightning.pytorch.callbacks import ModelCheckpoint, RichProgressBar
    opts = dict(cfg.get("trainer") or {})
    opts.update(overrides)
    opts.setdefault("gradient_clip_val", (cfg.get("optim") or {}).get("grad_clip", 0.5))
    ckpt = ModelCheckpoint(dirpath=str(run_dir / "checkpoints"), save_last=True,
                           monitor=opts.pop("monitor", "val_loss"), mode="min")
    callbacks = [ckpt] + list(opts.pop("callbacks", None) or [])
    if opts.pop("progress", True):
        callbacks.append(RichProgressBar())
    return L.Trainer(default_root_dir=str(run_dir), logger=build_logger(cfg, run_dir),
                     callbacks=callbacks, **opts)


def init_weights(module: L.LightningModule, ckpt: str) -> None:
    """Load another run's weights into :obj:`module` for fine-tuning; the
    module keeps its own normaliser (the new data's). Warns about weights
    the checkpoint lacks or has in excess (e.g. another bottleneck)."""
    state = torch.load(ckpt, map_location="cpu", weights_only=True)["state_dict"]
    state = {k: v for k, v in state.items() if not k.startswith("normalizer.")}
    result = module.load_state_dict(state, strict=False)
    missing = [k for k in result.missing_keys if not k.startswith("normalizer.")]
    if missing or result.unexpected_keys:
        warnings.warn(f"--init-from {ckpt}: {len(missing)} weights not in the checkpoint "
                      f"(kept at initialisation: {missing[:5]}), "
                      f"{len(result.unexpected_keys)} unused "
                      f"({result.unexpected_keys[:5]})", stacklevel=2)


def _spawns_workers(trainer: L.Trainer) -> bool:
    """Whether :meth:`~lightning.pytorch.Trainer.fit` pickles its arguments
    into new processes (``strategy="ddp_spawn"``)."""
    launcher = getattr(trainer.strategy, "launcher", None)
    return getattr(launcher, "_start_method", None) in ("spawn", "forkserver")


def train(cfg: Dict[str, Any], resume: bool = False, init_from: Optional[str] = None,
          **trainer_overrides: Any) -> Tuple[Any, MotionDataModule, L.Trainer, Path]:
    r"""Train a model from a config dict (see ``experiments/``).

    Args:
        cfg (dict): The config (plain containers).
        resume (bool): Continue from ``<run>/checkpoints/last.ckpt``.
        init_from (str, optional): Start from another run's weights (fine-
            tuning on a new dataset); the normaliser of the new data is used.

    Returns:
        The trained module, the data module, the trainer and the run folder.
    """
    run_dir = Path(expand_path(cfg.get("output_dir") or f"runs/{cfg['name']}"))
    last = run_dir / "checkpoints" / "last.ckpt"
    if resume and not last.is_file():
        raise FileNotFoundError(f"--resume: no checkpoint at {last}")
    L.seed_everything(int(cfg.get("seed", 0)), workers=True)
    dm = build_datamodule(cfg)
    dm.setup("fit")
    module = build_module(cfg, dm)
    if init_from:
        init_weights(module, init_from)
    trainer = build_trainer(cfg, run_dir, **trainer_overrides)
    # Spawned workers get the data module pickled: hand them one that is not
    # set up (its datasets hold the semantic embedder, a closure); each worker
    # sets it up from the feature cache.
    fit_dm = build_datamodule(cfg) if _spawns_workers(trainer) else dm
    trainer.fit(module, datamodule=fit_dm, ckpt_path=str(last) if resume else None)
    return module, dm, trainer, run_dir


def load_module(ckpt: str, map_location: str = "cpu"):
    """A trained module from a checkpoint, whatever its class."""
    hparams = torch.load(ckpt, map_location="cpu", weights_only=True).get("hyper_parameters", {})
    name = (hparams.get("meta") or {}).get("module", "vae")
    cls = module_class(name)
    return cls.load_from_checkpoint(ckpt, map_location=map_location)
