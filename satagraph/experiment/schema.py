r"""The experiment config schema: typed sections, each key with one default.

A config (``experiments/*.yaml`` after inheritance and overrides) has the
top-level keys of :class:`ExperimentConfig` and these sections:

- ``data`` (:class:`DataConfig`): the data module's arguments;
  ``data.augment`` takes the keys of
  :class:`~satagraph.transforms.augment.AugmentConfig`.
- ``model``, ``loss``, ``optim``: the module's own sections, checked by the
  module's builder (see :mod:`satagraph.experiment.registry`); ``module_args``:
  the registered class's own constructor arguments beyond these (a
  subclass's ``z_weight``), or what a builder function reads from
  :attr:`~satagraph.experiment.registry.ModuleSections.extra`; the
  autoencoders take the network's arguments, the
  :class:`~satagraph.losses.MotionLoss` weights and ``lr``,
  ``warmup_epochs``, ``decay``, ``floor``, ``frozen`` (parts not trained,
  e.g. ``[model.encoder, model.bottleneck]``). ``optim.grad_clip``
  (:data:`GRAD_CLIP`) is the trainer's gradient clipping and ``optim.ema``
  (:data:`EMA`) its moving average of the weights, for every module.
- ``trainer``: keyword arguments of :class:`lightning.Trainer` and the
  keys of :class:`TrainerExtras`.
- ``logger`` (:class:`LoggerConfig`), ``checkpoint``
  (:class:`CheckpointConfig`).

:func:`resolve_config` checks every key (one error line naming an unknown
key, the known ones and the closest) and fills the defaults; it is
idempotent and returns plain containers.
"""
from __future__ import annotations

import difflib
from dataclasses import MISSING, dataclass, field, fields, make_dataclass
from typing import Any, Dict, Iterable, Mapping, Optional

#: Default of ``optim.grad_clip``: gradient norm clipping of the trainer
#: (Lightning's ``gradient_clip_val``), its only owner.
GRAD_CLIP = 0.5
#: Default of ``optim.ema``: the decay of an exponential moving average of
#: the weights, validated and checkpointed in their place (0: none).
EMA = 0.0
#: The ``optim`` keys of the trainer, taken by every module.
TRAINER_OPTIM = ("grad_clip", "ema")


@dataclass
class DataConfig:
    r"""``data``: arguments of :class:`~satagraph.data.MotionDataModule`
    (see there); :obj:`seed` ``None`` is the run's ``seed``."""

    sources: Any = None
    window: int = 64
    stride: int = 32
    eval_stride: Optional[int] = None
    batch_size: int = 32
    balanced: bool = True
    preprocessing: Dict[str, Any] = field(default_factory=dict)
    semantic_encoder: Optional[str] = "offline"
    cache_dir: Optional[str] = None
    num_workers: int = 0
    max_files: Optional[int] = None
    seed: Optional[int] = None
    augment: Any = None
    on_error: str = "raise"
    body_relative: bool = True
    root_unit: str = "height"
    train_transform: Optional[str] = None


@dataclass
class LoggerConfig:
    r"""``logger``: :obj:`name` is ``wandb``, ``csv``, ``tensorboard`` or
    ``none``; :obj:`offline`, :obj:`project` and :obj:`group` (runs shown
    together: a sweep's, named after its output folder) are wandb's."""

    name: str = "wandb"
    offline: bool = True
    project: str = "satagraph"
    group: Optional[str] = None


@dataclass
class CheckpointConfig:
    r"""``checkpoint``: ``last.ckpt`` every :obj:`every_n_steps` steps
    and/or :obj:`every_minutes` minutes of training (and every epoch end);
    ``null`` turns one off. :obj:`keep_every_epoch` keeps a checkpoint of
    every epoch's end (``epoch=E-step=S.ckpt``) instead of only the best
    one, so that a run can be chosen from by a benchmark afterwards."""

    every_n_steps: Optional[int] = 500
    every_minutes: Optional[float] = 10.0
    keep_every_epoch: bool = False


@dataclass
class TrainerExtras:
    r"""``trainer`` keys that are not :class:`lightning.Trainer` arguments:
    :obj:`monitor` (the metric the best checkpoint keeps) and
    :obj:`progress` (a rich progress bar)."""

    monitor: Optional[str] = "val_loss"
    progress: bool = True


@dataclass
class ExperimentConfig:
    r"""A whole config.

    Args:
        name (str): Run name (default: the config file's stem).
        module (str): Registered module (:mod:`satagraph.experiment.registry`).
        seed (int): Run seed (weights, data order, augmentation).
        threads (int, optional): ``torch.set_num_threads``.
        output_dir (str, optional): Run folder (default ``runs/<name>``).
        loss_log (bool): Append every step's loss to ``<run>/losses.tsv``.
        nonfinite (str): ``stop`` or ``skip`` on a non-finite loss.
        module_args (dict): The module's own constructor arguments beyond
            its sections
            (:attr:`~satagraph.experiment.registry.ModuleSections.extra`), e.g. ``{z_weight: 0.5}``.
    """

    name: str = ""
    module: str = "vae"
    seed: int = 0
    threads: Optional[int] = None
    output_dir: Optional[str] = None
    loss_log: bool = False
    nonfinite: str = "stop"
    module_args: Dict[str, Any] = field(default_factory=dict)
    model: Dict[str, Any] = field(default_factory=dict)
    loss: Dict[str, Any] = field(default_factory=dict)
    optim: Dict[str, Any] = field(default_factory=dict)
    data: Dict[str, Any] = field(default_factory=dict)
    trainer: Dict[str, Any] = field(default_factory=dict)
    logger: Dict[str, Any] = field(default_factory=dict)
    checkpoint: Dict[str, Any] = field(default_factory=dict)


def signature_schema(target: Any, name: str, **defaults_: Any) -> type:
    r"""A dataclass schema of the keyword arguments of :obj:`target` (e.g.
    a data module of a module of its own), their defaults its signature's
    (one place) unless :obj:`defaults_` sets them (``seed=None``: the run's
    seed); a required argument defaults to ``None``."""
    import inspect
    specs = []
    for param in inspect.signature(target).parameters.values():
        if param.kind in (param.VAR_POSITIONAL, param.VAR_KEYWORD):
            continue
        value = defaults_.get(param.name, None if param.default is param.empty
                              else param.default)
        specs.append((param.name, Any, field(default_factory=lambda v=value: v)))
    return make_dataclass(name, specs)


def unknown_key_error(where: str, key: str, known: Iterable[str],
                      what: str = "config key") -> ValueError:
    """One line naming an unknown :obj:`key` of section :obj:`where`, the
    known keys and the closest of them."""
    known = sorted(known)
    close = difflib.get_close_matches(str(key), known, n=1)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    name = f"{where}.{key}" if where else str(key)
    return ValueError(f"unknown {what} {name!r}{hint}; known: {', '.join(known)}")


def check_keys(where: str, values: Mapping[str, Any], known: Iterable[str]) -> None:
    """Raise :func:`unknown_key_error` for the first key of :obj:`values`
    not in :obj:`known`."""
    known = set(known)
    for key in values:
        if key not in known:
            raise unknown_key_error(where, key, known)


def defaults(schema: type) -> Dict[str, Any]:
    """The default of every field of a dataclass :obj:`schema`."""
    out = {}
    for f in fields(schema):
        out[f.name] = f.default_factory() if f.default is MISSING else f.default
    return out


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value: Any) -> bool:
    return _is_int(value) or isinstance(value, float)


#: What a field of each annotation accepts (the others, ``str`` among them,
#: accept anything: ``output_dir=2024`` reads as a number and names a folder).
TYPE_CHECKS = {"int": (_is_int, "an integer"), "float": (_is_number, "a number"),
               "bool": (lambda v: isinstance(v, bool), "true or false")}


def check_types(where: str, schema: type, values: Mapping[str, Any]) -> None:
    """One line for a value of the wrong type in a field annotated ``int``,
    ``float`` or ``bool`` (or ``Optional`` of one, which also takes
    ``null``): ``seed=abc`` or ``data.balanced=maybe``, before anything
    fails on it far from the cause."""
    for f in fields(schema):
        if f.name in values:
            check_value(f"{where}.{f.name}" if where else f.name, values[f.name], str(f.type))


def check_value(name: str, value: Any, kind: str) -> None:
    """:obj:`value` against an annotation (:data:`TYPE_CHECKS`; another
    annotation takes anything).

    Raises:
        ValueError: One line naming :obj:`name`.
    """
    optional = kind.startswith("Optional[")
    check = TYPE_CHECKS.get(kind[9:-1] if optional else kind)
    if check is not None and not (check[0](value) or (optional and value is None)):
        raise ValueError(f"{name}={value!r}: {check[1]} is expected"
                         f"{' (or null)' if optional else ''}")


#: Largest seed: ``seed`` and ``data.seed`` seed Lightning's
#: ``seed_everything`` and numpy's generators, which take 0 to 2**32 - 1
#: (``data.seed=-1`` trained until its first augmented or zoo window, then
#: failed as ``expected non-negative integer``).
MAX_SEED = 2 ** 32 - 1


def check_seed(name: str, value: Any) -> None:
    """A seed (``seed``, ``data.seed``, a zoo entry's ``seed``; ``None``
    passes where the schema allows it): a whole number from 0 to :data:`MAX_SEED`.

    Raises:
        ValueError: One line naming :obj:`name`.
    """
    if _is_int(value) and not 0 <= value <= MAX_SEED:
        raise ValueError(f"{name}={value}: a seed from 0 to {MAX_SEED} is expected")


def fill(where: str, schema: type, values: Optional[Mapping[str, Any]]) -> Dict[str, Any]:
    """:obj:`values` checked against the fields of :obj:`schema` (their
    names and simple types, :func:`check_types`), with the defaults of the
    missing ones."""
    values = dict(values or {})
    check_keys(where, values, (f.name for f in fields(schema)))
    check_types(where, schema, values)
    return dict(defaults(schema), **values)


#: Smallest value of the ``data`` counts (``data.window=-5`` failed as an
#: ``IndexError`` far from the cause).
DATA_AT_LEAST = {"window": 2, "stride": 1, "eval_stride": 1, "batch_size": 1,
                 "max_files": 1, "num_workers": 0}

#: ``trainer`` keys of :class:`lightning.Trainer` that take a whole number
#: (``-1``: no limit, where Lightning says so) or a number, as annotations.
TRAINER_TYPES = {**dict.fromkeys(("max_epochs", "min_epochs", "max_steps", "min_steps",
                                  "log_every_n_steps", "accumulate_grad_batches",
                                  "num_sanity_val_steps", "check_val_every_n_epoch"),
                                 "Optional[int]"),
                 **dict.fromkeys(("limit_train_batches", "limit_val_batches",
                                  "limit_test_batches", "val_check_interval"),
                                 "Optional[float]")}


def resolve_data(data: Optional[Mapping[str, Any]],
                 schema: type = DataConfig) -> Dict[str, Any]:
    """The ``data`` section checked against :obj:`schema` (``augment`` and
    ``preprocessing`` included) and filled."""
    from satagraph.data.dataset import DEFAULT_PREPROCESSING
    from satagraph.transforms.augment import AugmentConfig
    out = fill("data", schema, data)
    check_seed("data.seed", out.get("seed"))
    sources = out.get("sources")
    for i, source in enumerate(sources if isinstance(sources, (list, tuple)) else [sources]):
        if isinstance(source, Mapping):  # a zoo entry's own seed
            check_seed(f"data.sources[{i}].seed", source.get("seed"))
    for key, least in DATA_AT_LEAST.items():
        value = out.get(key)
        if _is_number(value) and value < least:
            raise ValueError(f"data.{key}={value}: at least {least} is expected")
    check_keys("data.preprocessing", out.get("preprocessing") or {}, DEFAULT_PREPROCESSING)
    check_frame_rate(dict(DEFAULT_PREPROCESSING, **(out.get("preprocessing") or {}))["fps"])
    augment = out.get("augment")
    if isinstance(augment, Mapping):
        check_keys("data.augment", augment, (f.name for f in fields(AugmentConfig)))
    elif augment not in (None, True, False):
        raise ValueError(f"data.augment must be null, true, false or a mapping, "
                         f"got {augment!r}")
    return out


def check_frame_rate(fps: Any) -> None:
    """``data.preprocessing.fps``, the rate every clip is resampled to: a
    number above 0. ``null`` failed as a ``TypeError`` traceback, ``0`` kept
    each file's own rate until a batch mixed 30 and 60 fps clips, and ``-5``
    left out every file (``no training windows``).

    Raises:
        ValueError: One line naming the key.
    """
    if not (_is_number(fps) and fps > 0):
        shown = "null" if fps is None else repr(fps)
        raise ValueError(f"data.preprocessing.fps={shown}: a frame rate above 0 is expected "
                         "(every clip is resampled to it, so that files of 30, 60 and "
                         "120 fps train together)")


#: Trainer arguments that a run sets itself, and the config keys that set
#: them (from Python, ``train(cfg, logger=..., default_root_dir=...)`` may
#: still replace the first two).
RUN_TRAINER_KEYS = {
    "gradient_clip_val": "set optim.grad_clip instead (the one owner of gradient clipping)",
    "default_root_dir": "the run's folder is output_dir (runs/<name> by default): set output_dir",
    "logger": "set logger.name (wandb, csv, tensorboard or none)",
    "enable_checkpointing": "every run writes checkpoints (last.ckpt resumes it); "
                            "checkpoint.every_n_steps and every_minutes set how often",
}


def resolve_trainer(trainer: Optional[Mapping[str, Any]]) -> Dict[str, Any]:
    """The ``trainer`` section with :class:`TrainerExtras` filled; what a
    run sets itself (:data:`RUN_TRAINER_KEYS`) is refused."""
    trainer = dict(trainer or {})
    for key in RUN_TRAINER_KEYS:
        if key in trainer:
            raise ValueError(f"trainer.{key}: {RUN_TRAINER_KEYS[key]}")
    for key, kind in TRAINER_TYPES.items():
        if key in trainer:
            check_value(f"trainer.{key}", trainer[key], kind)
    out = dict(defaults(TrainerExtras), **trainer)
    check_types("trainer", TrainerExtras, out)
    return out


def resolve_config(cfg: Mapping[str, Any]) -> Dict[str, Any]:
    r"""A config checked against the schema, with every default filled.

    The ``data`` section is checked against the module's data schema
    (:class:`DataConfig` unless it registered another); the module's own
    sections (``model``, ``loss``, ``optim`` but :data:`TRAINER_OPTIM`) and
    ``module_args`` are checked when it is built.

    Raises:
        ValueError: An unknown key (one line: the key, the known ones and
            the closest).
    """
    from satagraph.experiment.registry import module_entry
    out = fill("", ExperimentConfig, cfg)
    check_seed("seed", out["seed"])
    out["data"] = resolve_data(out["data"], module_entry(out["module"]).data)
    out["trainer"] = resolve_trainer(out["trainer"])
    out["logger"] = fill("logger", LoggerConfig, out["logger"])
    out["checkpoint"] = fill("checkpoint", CheckpointConfig, out["checkpoint"])
    out["optim"] = dict(out["optim"] or {})
    out["optim"].setdefault("grad_clip", GRAD_CLIP)
    out["optim"].setdefault("ema", EMA)
    out["model"], out["loss"] = dict(out["model"] or {}), dict(out["loss"] or {})
    if not isinstance(out["module_args"] or {}, Mapping):
        raise ValueError(f"module_args={out['module_args']!r}: a mapping of the module's "
                         "own constructor arguments is expected (module_args.NAME=VALUE)")
    out["module_args"] = dict(out["module_args"] or {})
    return out


__all__ = ["ExperimentConfig", "DataConfig", "LoggerConfig", "CheckpointConfig",
           "TrainerExtras", "GRAD_CLIP", "EMA", "TRAINER_OPTIM", "resolve_config",
           "resolve_data", "check_frame_rate", "fill", "check_keys", "check_types",
           "check_value", "check_seed", "MAX_SEED", "unknown_key_error",
           "defaults", "DATA_AT_LEAST",
           "signature_schema"]
