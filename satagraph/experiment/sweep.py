r"""Equal-budget sweeps: train several configs for the same wall-clock time
(or the same number of steps) on the same data, evaluate each on the same
split, and tabulate (the SATA paper's Table 4 layout: one row per config).

Example::

    from satagraph.experiment.sweep import run_sweep
    rows = run_sweep(["tiny", "tiny"], budget_minutes=0.5, output="sweep",
                     variants=[[], ["model.local_conv=gin"]])

Every config gets the data section of the first one (``same_data``), a CSV
logger, no progress bar, ``trainer.max_time`` set to the budget (or
``trainer.max_steps`` to the steps) and no other limit, and its own run folder under the output folder. The metrics
are those of the final weights (not the best checkpoint) on the test split,
read as ``satagraph eval`` reads it
(:func:`~satagraph.pipelines.evaluation.scoring_data`: each skeleton in the rest pose ``reconstruct`` shows it;
:func:`~satagraph.pipelines.evaluation.evaluate`).
"""
from __future__ import annotations

import contextlib
import copy
import json
import math
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence

import torch
from torch.utils.data import DataLoader

from satagraph.experiment.config import dotted_settings, load_config
from satagraph.experiment.schema import resolve_data
from satagraph.pipelines.metric_columns import METRIC_COLUMNS, MetricColumn
from satagraph.utils.files import atomic_write_text

#: Steps the "train loss" column averages (see :class:`~satagraph.lightning.TrailingLoss`).
TRAILING_STEPS = 50

#: Splits a sweep scores its rows on (``--split``): ``val`` to choose among
#: them, ``test`` to report the ones chosen.
SPLITS = ("val", "test")

#: Retargeting columns of the table (setting: header), as the SATA paper's Table 4.
RETARGET_HEADERS = {"internal": "retarget int.", "cross": "retarget cross"}

#: Metric columns of the table: the paper's Table 4 ones of ``satagraph eval``'s
#: (:data:`~satagraph.pipelines.metric_columns.METRIC_COLUMNS`).
COLUMNS = tuple(c for c in METRIC_COLUMNS if c.name in ("JR", "RT", "JP", "FS", "GP"))


@dataclass
class SweepRow:
    r"""The outcome of one config of a sweep.

    Args:
        name (str): Row label (the config's name, made unique).
        config (str): The config as given.
        params (int): Trainable parameters.
        steps (int): Optimizer steps done within the budget.
        epochs (int): Epochs started.
        seconds (float): Wall time of the training (set-up included).
        train_loss (float): Mean training loss over the last
            :obj:`TRAILING_STEPS` steps (``nan`` if none).
        loss_steps (int): The steps :attr:`train_loss` averages: fewer than
            :obj:`TRAILING_STEPS` in a short run, or in one resumed near its
            end (the steps after the resume); 0 in rows of older sweeps.
        metrics (dict): ``{dataset: {metric: value, "clips": n}}`` on the
            evaluation split (and extra loaders).
        retarget (dict): Retarget error ``{setting: {group: value}}``, setting
            ``"internal"`` or ``"cross"`` (see
            :data:`~satagraph.pipelines.evaluation.RETARGET_SETTINGS`), group a file
            label or ``"label:dataset"`` (empty when not asked).
        run_dir (str): The run folder (checkpoints, CSV logs).
        error (str): Why the config failed (empty when it did not); its
            row is kept, the others go on.
        split (str): The split :attr:`metrics` and :attr:`retarget` read.
    """

    name: str
    config: str
    params: int = 0
    steps: int = 0
    epochs: int = 0
    seconds: float = 0.0
    train_loss: float = math.nan
    loss_steps: int = 0
    metrics: Dict[str, Dict[str, float]] = field(default_factory=dict)
    retarget: Dict[str, Dict[str, float]] = field(default_factory=dict)
    run_dir: str = ""
    error: str = ""
    split: str = "test"


# ----------------------------------------------------------- configs
def split_arguments(items: Sequence[str]) -> tuple:
    """Configs and ``key=value`` overrides from one positional list;
    ``config=NAME`` names a config too (what a wandb sweep agent passes)."""
    configs, overrides = [], []
    for item in items:
        if "=" not in item or item.startswith("config="):
            configs.append(item.split("=", 1)[-1])
        else:
            overrides.append(item)
    return configs, overrides


#: Trainer limits a sweep sets itself (:func:`budget_config`): an override
#: of one is refused, not dropped.
BUDGET_KEYS = ("trainer.max_steps", "trainer.max_epochs", "trainer.max_time",
               "trainer.min_steps", "trainer.min_epochs")


def budget_config(cfg: Dict[str, Any], budget_minutes: float, run_dir: Path,
                  data: Optional[Dict[str, Any]] = None,
                  logger: Optional[str] = "csv",
                  steps: Optional[int] = None) -> Dict[str, Any]:
    r"""A copy of :obj:`cfg` bound by :obj:`budget_minutes` of training
    (``trainer.max_time: {seconds: ...}``, no epoch or step limit), or by
    :obj:`steps` optimizer steps where given (``trainer.max_steps``, no time
    or epoch limit: equal work, :obj:`budget_minutes` unused), writing into
    :obj:`run_dir`, on :obj:`data` when given. :obj:`logger`: ``"csv"``,
    ``"tensorboard"``, ``"none"``, ``"wandb"`` (online, e.g. under a wandb
    sweep agent) or ``None`` (the config's own logger)."""
    cfg = copy.deepcopy(cfg)
    if data is not None:
        cfg["data"] = copy.deepcopy(data)
    trainer = dict(cfg.get("trainer") or {})
    for key in BUDGET_KEYS:  # a config's own limits: the budget alone ends a run
        trainer.pop(key.split(".", 1)[1], None)
    trainer.update(max_epochs=-1, progress=False, enable_model_summary=False,
                   enable_progress_bar=False)
    trainer.update({"max_steps": int(steps)} if steps is not None
                   else {"max_time": {"seconds": 60.0 * float(budget_minutes)}})
    trainer.setdefault("log_every_n_steps", 10)
    cfg["trainer"] = trainer
    if logger is not None:
        cfg["logger"] = {"name": logger, "offline": False} if logger == "wandb" else {
            "name": logger}
    cfg["output_dir"] = str(run_dir)
    return cfg


@dataclass
class SweepRun:
    r"""One config of a sweep, ready to train.

    Args:
        cfg (dict): The budgeted config (:func:`budget_config`).
        source (str): The config as given (name or path).
    """

    cfg: Dict[str, Any]
    source: str


def sweep_configs(configs: Sequence[str], overrides: Sequence[str] = (),
                  variants: Optional[Sequence[Sequence[str]]] = None,
                  budget_minutes: float = 5.0, output: str = "sweeps/latest",
                  same_data: bool = True,
                  logger: Optional[str] = "csv",
                  steps: Optional[int] = None) -> List[SweepRun]:
    r"""Loaded, budgeted configs of a sweep.

    Args:
        configs (list[str]): Config names or paths.
        overrides (list[str]): Overrides applied to every config.
        variants (list[list[str]], optional): Extra overrides per config.
        budget_minutes (float): Training budget of each config.
        output (str): Output folder; config :math:`i` runs in
            ``output/<i>_<name>``, its W&B run in the group named after the
            folder (unless ``logger.group`` names one).
        same_data (bool): Give every config the first one's data section.
        logger (str, optional): See :func:`budget_config`.
        steps (int, optional): Train each config this many steps instead
            (:func:`budget_config`).
    """
    variants = list(variants or [[] for _ in configs])
    if len(variants) != len(configs):
        raise ValueError(f"{len(variants)} variants for {len(configs)} configs")
    for item in list(overrides) + [o for v in variants for o in v]:
        key = item.split("=", 1)[0].lstrip("+~")
        if key in BUDGET_KEYS:
            raise ValueError(f"sweep: {item}: every config trains for the budget "
                             "(--budget minutes or --steps) and no other limit, "
                             "so that its rows compare at equal time or work: drop it")
    loaded = [load_config(c, list(overrides) + list(v)) for c, v in zip(configs, variants)]
    data = loaded[0]["data"] if same_data and loaded else None
    out, names = [], []
    for i, (cfg, spec) in enumerate(zip(loaded, configs)):
        label = _label(cfg["name"], variants[i], names)
        names.append(label)
        cfg = budget_config(cfg, budget_minutes, Path(output) / f"{i}_{label}", data,
                            logger, steps)
        cfg["name"] = label
        # a W&B project holds the rows of every sweep and run: one group per sweep
        cfg["logger"] = dict(cfg["logger"], group=cfg["logger"].get("group")
                             or Path(output).resolve().name)
        out.append(SweepRun(cfg, spec))
    return out


def _label(name: str, extra: Sequence[str], taken: Sequence[str]) -> str:
    """A unique row label: the config name, its variant overrides, a count."""
    label = name + "".join(
        f"+{o.split('=', 1)[0].split('.')[-1]}={o.split('=', 1)[1]}" for o in extra)
    base, k = label, 2
    while label in taken:
        label, k = f"{base}_{k}", k + 1
    return label


# ---------------------------------------------------------- training
def train_budgeted(cfg: Dict[str, Any], resume: bool = False):
    r"""Train one budgeted config (see :func:`budget_config`); :obj:`resume`:
    go on from its ``last.ckpt`` with the rest of its budget.

    Returns:
        The module, the data module, the trainer, the wall time and the
        :class:`~satagraph.lightning.trailing_loss.TrailingLoss` of the last
        :obj:`TRAILING_STEPS` steps.
    """
    from satagraph.lightning.trailing_loss import TrailingLoss
    from satagraph.experiment.train import train
    trailing = TrailingLoss(TRAILING_STEPS)
    start = time.perf_counter()
    module, dm, trainer, _ = train(cfg, resume=resume, callbacks=[trailing])
    return module, dm, trainer, time.perf_counter() - start, trailing


@contextlib.contextmanager
def threads_kept():
    """torch's intra-op thread count back as it was after a row: a config's
    ``threads`` (``torch.set_num_threads``) ran every later row of the
    sweep with its count, which their budget and settings did not say."""
    threads = torch.get_num_threads()
    try:
        yield
    finally:
        torch.set_num_threads(threads)


@threads_kept()
def run_config(run: SweepRun, eval_split: str = "test",
               extra_loaders: Optional[Dict[str, Any]] = None,
               retarget_files: Optional[Dict[str, Sequence]] = None,
               max_batches: Optional[int] = None, resume: bool = False) -> SweepRow:
    r"""Train one budgeted config and evaluate it (torch's thread count
    kept: :func:`threads_kept`).

    Args:
        run (SweepRun): A config from :func:`sweep_configs`.
        eval_split (str): Split of the config's data to evaluate on.
        extra_loaders (dict, optional): ``{label: callable(module) -> loader}``
            of further evaluation data (e.g. a held-out dataset); their
            results are stored under ``label``.
        retarget_files (dict, optional): ``{label: files}`` for
            :func:`~satagraph.pipelines.evaluation.retarget_errors`; ``"split"`` as the
            value's key takes the evaluation split's files.
        max_batches (int, optional): Evaluation batches per loader.
        resume (bool): Go on from the run folder's ``last.ckpt`` (a stopped
            sweep's), with the rest of the budget.
    """
    from satagraph.pipelines.evaluation import evaluate, split_loader
    from satagraph.lightning.autoencoder import count_parameters
    cfg = run.cfg
    module, dm, trainer, seconds, trailing = train_budgeted(cfg, resume)
    row = SweepRow(name=cfg["name"], config=run.source,
                   params=count_parameters(module), steps=int(trainer.global_step),
                   epochs=int(trainer.current_epoch), seconds=seconds,
                   train_loss=trailing.value, loss_steps=len(trailing.losses),
                   run_dir=cfg["output_dir"], split=eval_split)
    scored = _scored(cfg, dm, eval_split)
    row.metrics = evaluate(module, split_loader(scored, eval_split), max_batches)
    for label, make_loader in (extra_loaders or {}).items():
        for group, values in evaluate(module, make_loader(module), max_batches).items():
            row.metrics[f"{label}" if group == "all" else f"{label}:{group}"] = values
    if retarget_files is not None:
        row.retarget = retarget_table(module, scored, retarget_files, eval_split)
    close_logger(trainer, {f"{eval_split}/{key}" if group == "all" else
                           f"{eval_split}/{group}/{key}": value
                           for group, values in row.metrics.items()
                           for key, value in values.items()})
    return row


def close_logger(trainer, metrics: Dict[str, float]) -> None:
    """Log a row's scores to its run's logger and close the run: a W&B
    run stayed open, and every later config of the sweep was logged into
    it (one run, named after the first config, its steps starting over)."""
    logger = trainer.logger
    if not logger:
        return
    numbers = {k: float(v) for k, v in metrics.items() if isinstance(v, (int, float))}
    logger.log_metrics(numbers, step=int(trainer.global_step))
    logger.finalize("success")
    experiment = logger.experiment  # started by log_metrics: reading it starts nothing
    if hasattr(experiment, "finish"):  # a W&B run
        experiment.finish()


def _scored(cfg: Dict[str, Any], dm, split: str):
    """The data a row is scored on (its :obj:`split` alone): as ``satagraph eval`` reads it
    (:func:`~satagraph.pipelines.evaluation.scoring_data`: each skeleton in
    the rest pose ``reconstruct`` shows it), for the motion data module;
    another module's own data module as it trained."""
    from satagraph.data.datamodule import MotionDataModule
    from satagraph.experiment.train import data_section
    from satagraph.pipelines.evaluation import scoring_data
    return scoring_data(data_section(cfg), split=split) if type(dm) is MotionDataModule else dm


def retarget_table(module, dm, files: Dict[str, Sequence], split: str,
                   settings: Optional[Sequence[str]] = None
                   ) -> Dict[str, Dict[str, float]]:
    r"""Retarget errors (paired ground truth) per setting, label and dataset:
    ``{setting: {"label": all files, "label:dataset": value}}``.

    Args:
        module: The trained module.
        dm: Its data module (for ``"split"``).
        files (dict): ``{label: files}``; ``"split"`` takes the files of
            :obj:`split`.
        split (str): Split whose files ``"split"`` stands for.
        settings (list[str], optional): Retargeting settings (default:
            every one of :data:`~satagraph.pipelines.evaluation.RETARGET_SETTINGS`).
    """
    from satagraph.pipelines.evaluation import retarget_error_table
    embed = module.embed
    out: Dict[str, Dict[str, float]] = {}
    for label, chosen in files.items():
        chosen = dm.datasets[split].files if chosen == "split" else chosen
        table = retarget_error_table(module, chosen, embed, settings=settings)
        for setting, errors in table.items():
            out.setdefault(setting, {}).update({label if group == "all" else f"{label}:{group}": value
                                 for group, value in errors.items()})
    return out


def held_out_loader(data: Dict[str, Any], sources: Any, batch_size: Optional[int] = None):
    r"""A function ``module -> DataLoader`` over every file of
    :obj:`sources` (all splits: a dataset held out of training), cut into
    evaluation windows as :obj:`data` (a config's data section) says."""
    def make(module) -> DataLoader:
        from satagraph.data.collate import collate_clips
        from satagraph.data.datamodule import semantic_embedder
        from satagraph.data.dataset import MotionDataset, load_features
        from satagraph.datasets.sources import resolve_sources
        files = resolve_sources(sources)
        feats = load_features(files, spec["preprocessing"], spec["cache_dir"])
        window = int(spec["window"])
        ds = MotionDataset(files, feats, semantic_embedder(spec["semantic_encoder"]),
                           window, int(spec["eval_stride"] or window))
        return DataLoader(ds, batch_size=batch_size or int(spec["batch_size"]),
                          collate_fn=collate_clips)
    spec = resolve_data(data)
    return make


def run_sweep(configs: Sequence[str], budget_minutes: float = 5.0,
              output: str = "sweeps/latest", overrides: Sequence[str] = (),
              variants: Optional[Sequence[Sequence[str]]] = None,
              retarget: bool = False, max_batches: Optional[int] = None,
              logger: Optional[str] = "csv", log=print,
              resume: bool = False, split: str = "test",
              steps: Optional[int] = None) -> List[SweepRow]:
    r"""Train every config for :obj:`budget_minutes` (or :obj:`steps`) on the same data,
    evaluate each on :obj:`split` and write ``sweep.md`` and
    ``sweep.json`` into :obj:`output`.

    Args:
        configs (list[str]): Config names or paths.
        budget_minutes (float): Wall-clock training budget per config.
        output (str): Output folder.
        overrides (list[str]): Overrides for every config.
        variants (list[list[str]], optional): Extra overrides per config.
        retarget (bool): Also the retarget error on the split's files.
        max_batches (int, optional): Evaluation batches (default: all).
        logger (str, optional): Training logger (see :func:`budget_config`).
        log (callable): Progress lines.
        resume (bool): Go on with a sweep stopped in :obj:`output`: the rows
            it finished are kept, a config it stopped in goes on from its
            ``last.ckpt`` with the rest of its budget (:func:`finished_rows`).
        split (str): :data:`SPLITS`: ``"val"`` to choose among the rows
            (a choice made on the test split is no test result), ``"test"``
            to report the rows chosen.
        steps (int, optional): Train every config this many optimizer steps
            instead of :obj:`budget_minutes` (equal work; the table's ``train
            (min)`` column then compares their speed).
    """
    if steps is not None and steps < 1:
        raise ValueError(f"sweep: --steps must be at least 1, got {steps}")
    if max_batches is not None and max_batches < 1:
        raise ValueError(f"sweep: --max-batches must be at least 1, got {max_batches}")
    if split not in SPLITS:
        raise ValueError(f"sweep: --split must be one of {SPLITS}, got {split!r}")
    cfgs = sweep_configs(configs, overrides, variants, budget_minutes, output,
                         logger=logger, steps=steps)
    started = check_runs(cfgs, resume)
    from satagraph.lightning.reliability import run_lock
    with run_lock(Path(output), "--output"):  # two sweeps there mixed their rows
        done = finished_rows([r for r in cfgs if r.cfg["name"] in started], Path(output), split)
        rows = []
        for i, run in enumerate(cfgs):
            if run.cfg["name"] in done:
                log(f"[{i + 1}/{len(cfgs)}] {run.cfg['name']}: kept (finished before)")
                rows.append(done[run.cfg["name"]])
                continue
            log(f"[{i + 1}/{len(cfgs)}] {run.cfg['name']}: training for "
                f"{budget_words(budget_minutes, steps)}")
            try:
                row = run_config(run, eval_split=split,
                                 retarget_files={split: "split"} if retarget else None,
                                 max_batches=max_batches, resume=run.cfg["name"] in started)
            except (ValueError, RuntimeError, OSError) as err:  # the other rows go on
                message = str(err).splitlines()[0] if str(err) else type(err).__name__
                log(f"    failed: {message}")
                rows.append(SweepRow(name=run.cfg["name"], config=run.source,
                                     run_dir=run.cfg["output_dir"], error=message, split=split))
                continue
            log(f"    {row.steps} steps, train loss (last {TRAILING_STEPS} steps) "
                f"{row.train_loss:.4f}")
            rows.append(row)
            if len(rows) < len(cfgs):  # a sweep stopped later (Ctrl-C) keeps these rows
                _write_so_far(rows, cfgs, output, budget_minutes, overrides, max_batches, steps)
        # all share the first's data
        write_results(rows, Path(output), budget_minutes, overrides,
                      data=cfgs[0].cfg["data"]["sources"] if cfgs else None,
                      differences=config_differences(cfgs), max_batches=max_batches, steps=steps)
    return rows



def _write_so_far(rows: Sequence[SweepRow], cfgs: Sequence[SweepRun], output: str,
                  budget_minutes: float, overrides: Sequence[str],
                  max_batches: Optional[int], steps: Optional[int] = None) -> None:
    """``sweep.md`` and ``sweep.json`` of the configs done so far, said to
    be a part (the whole sweep's replace them)."""
    write_results(rows, Path(output), budget_minutes, overrides,
                  data=cfgs[0].cfg["data"]["sources"],
                  differences=config_differences(cfgs[:len(rows)]), max_batches=max_batches,
                  planned=len(cfgs), steps=steps)


def check_runs(runs: Sequence[SweepRun], resume: bool = False) -> set:
    """Every config of a sweep checked before any trains: its keys and
    values, its model built, and a run folder that holds no trained run,
    or, with :obj:`resume`, one trained with the same settings
    (:func:`refuse_other_settings`).

    Returns:
        set: The names of the configs whose folder holds a trained run.

    Raises:
        ValueError: One line naming the config.
    """
    from satagraph.experiment.train import build_module, check_config, refuse_trained_folder
    started = set()
    for run in runs:
        folder = Path(run.cfg["output_dir"])
        try:
            refuse_trained_folder(folder)
        except ValueError:  # train's advice names train's options
            if not resume:
                raise ValueError(f"sweep: config {run.cfg['name']} ({run.source}): {folder} "
                                 "holds a trained run (a sweep stopped before: its sweep.md "
                                 "lists the configs it finished); --resume goes on with it, "
                                 "another --output runs the sweep again") from None
            started.add(run.cfg["name"])
        try:
            cfg = check_config(run.cfg)
            build_module(cfg)
        except (ValueError, KeyError, TypeError) as err:
            raise ValueError(f"sweep: config {run.cfg['name']} ({run.source}): "
                             f"{str(err).splitlines()[0]}") from None
        if run.cfg["name"] in started:
            refuse_other_settings(run, cfg)
    return started


def refuse_other_settings(run: SweepRun, cfg: Dict[str, Any]) -> None:
    """Refuse to go on with a run folder trained with other settings than
    :obj:`run`'s (resolved: :obj:`cfg`): another budget, override or
    config, whose row would sit in one table with the others unsaid.
    Where a run logs (``logger.*``: a W&B group or project, csv) changes
    no row and is not compared.

    Raises:
        ValueError: One line naming the config and the first setting.
    """
    from omegaconf import OmegaConf
    path = Path(run.cfg["output_dir"]) / "config.yaml"
    before = (dotted_settings(OmegaConf.to_container(OmegaConf.load(path)))
              if path.is_file() else {})
    now = dotted_settings(OmegaConf.to_container(OmegaConf.create(cfg)))
    differ = [k for k in sorted(set(before) | set(now))
              if before.get(k) != now.get(k) and not k.startswith("logger.")]
    if differ:
        key = differ[0]
        raise ValueError(f"sweep --resume: config {run.cfg['name']} ({run.source}): "
                         f"{path.parent} was trained with {key}={before.get(key)} (here "
                         f"{now.get(key)}): resume with the stopped sweep's configs, overrides "
                         "and --budget or --steps, or run this one with another --output")


def finished_rows(runs: Sequence[SweepRun], output: Path,
                  split: str = "test") -> Dict[str, SweepRow]:
    """The rows of :obj:`output`'s ``sweep.json`` (a stopped sweep's) that
    finished a config of :obj:`runs` (those whose folder holds a run
    trained with their settings, :func:`check_runs`) in its run folder, by
    name, scored on :obj:`split` (rows that failed train again; rows of
    another split are scored again)."""
    path = output / "sweep.json"
    if not path.is_file():
        return {}
    folders = {run.cfg["name"]: str(run.cfg["output_dir"]) for run in runs}
    rows = [SweepRow(**row) for row in json.loads(path.read_text()).get("rows", [])]
    return {r.name: r for r in rows
            if not r.error and folders.get(r.name) == r.run_dir and r.split == split}


#: Config sections whose settings a sweep's rows may differ in (``data`` is
#: the first config's for every row; names, folders and loggers are a row's
#: own).
COMPARED = ("module", "module_args", "seed", "threads", "model", "loss", "optim", "trainer")


def config_differences(runs: Sequence[SweepRun]) -> Dict[str, List[Any]]:
    """Every setting (dotted key) in which the rows' configs differ, with
    each row's value (``None``: not set): what a row's name does not say."""
    tables = [dotted_settings({k: run.cfg.get(k) for k in COMPARED}) for run in runs]
    keys = sorted(set().union(*tables)) if tables else []
    return {k: [t.get(k) for t in tables] for k in keys
            if len({json.dumps(t.get(k), sort_keys=True, default=str) for t in tables}) > 1}


# ------------------------------------------------------------- table
def budget_words(budget_minutes: float, steps: Optional[int] = None) -> str:
    """A sweep's budget in words: ``"10 min"`` or ``"500 steps"``."""
    return f"{steps} steps" if steps is not None else f"{budget_minutes:g} min"


def _metric(row: SweepRow, group: str, column: MetricColumn) -> str:
    return column.cell((row.metrics.get(group) or {}).get(column.name))


def _averaged(row: SweepRow) -> str:
    """What a row's train loss averages where it is not the last
    :data:`TRAILING_STEPS` steps: ``"all N"`` (a run of N steps) or ``"last
    N"`` (the N steps after a resume); empty otherwise."""
    n = row.loss_steps or row.steps  # older rows keep no count
    if not 0 < n < TRAILING_STEPS or row.error:
        return ""
    return f"all {n}" if n >= row.steps else f"last {n}"


def _train_loss(row: SweepRow) -> str:
    """A row's train loss, saying what it averages where that is fewer than
    :data:`TRAILING_STEPS` steps (see :func:`_legend`)."""
    averaged = _averaged(row)
    return f"{row.train_loss:.4f}" + (f" ({averaged})" if averaged else "")


def format_sweep(rows: Sequence[SweepRow], group: str = "all") -> str:
    """Table 4 layout: one row per config; metrics of :obj:`group` on each
    row's split."""
    settings = [s for s in RETARGET_HEADERS if any(s in r.retarget for r in rows)]
    head = ["config", "params (M)", "steps", "train (min)", "train loss"]
    head += [c.heading for c in COLUMNS]
    head += [RETARGET_HEADERS[s] for s in settings]
    lines = ["| " + " | ".join(head) + " |", "|---" + "|---:" * (len(head) - 1) + "|"]
    for r in rows:
        if r.error:
            lines.append(f"| {r.name} | failed: {r.error} |" + " |" * (len(head) - 2))
            continue
        cells = [r.name, f"{r.params / 1e6:.3g}", str(r.steps), f"{r.seconds / 60:.2f}",
                 _train_loss(r)]
        cells += [_metric(r, group, c) for c in COLUMNS]
        for setting in settings:
            label = r.split if group == "all" else f"{r.split}:{group}"
            value = r.retarget.get(setting, {}).get(label)
            cells.append("-" if value is None else f"{value:.3f}")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def write_results(rows: Sequence[SweepRow], output: Path, budget_minutes: float,
                  overrides: Sequence[str] = (), data: Any = None,
                  differences: Optional[Dict[str, List[Any]]] = None,
                  max_batches: Optional[int] = None, planned: Optional[int] = None,
                  steps: Optional[int] = None) -> str:
    """Write ``sweep.md`` and ``sweep.json``; returns the markdown.

    Args:
        rows (list[SweepRow]): One per config.
        output (Path): Output folder.
        budget_minutes (float): Training budget per config.
        overrides (list[str]): Overrides applied to every config (recorded).
        data (Any, optional): The data sources of the sweep (recorded).
        differences (dict, optional): :func:`config_differences` of the rows.
        max_batches (int, optional): Evaluation batches each row was scored on.
        planned (int, optional): The sweep's configs, where :obj:`rows` are
            those done so far.
        steps (int, optional): Steps each config trained instead of
            :obj:`budget_minutes`.
    """
    output.mkdir(parents=True, exist_ok=True)
    done = (f"{len(rows)} of {planned} configs so far" if planned and planned > len(rows)
            else f"{len(rows)} configs")
    text = (f"# Sweep: {done}, {budget_words(budget_minutes, steps)} of training each\n\n"
            f"{format_sweep(rows)}\n\n{_legend(rows, overrides, data, max_batches, differences)}\n"
            f"{_differences(rows, differences)}")
    atomic_write_text(output / "sweep.md", text)
    payload = {"budget_minutes": None if steps else budget_minutes, "steps": steps,
               "torch": torch.__version__,
               "configs": planned or len(rows),
               "overrides": list(overrides), "data": data, "max_batches": max_batches,
               "differences": differences or {},
               "rows": [asdict(r) for r in rows]}
    atomic_write_text(output / "sweep.json", json.dumps(payload, indent=1, default=float))
    return text


def _differences(rows: Sequence[SweepRow], differences: Optional[Dict[str, List[Any]]]
                 ) -> str:
    """The settings the rows differ in, a column per row (``sweep.md``);
    nothing for one row (a stopped sweep's first: it differs from none)."""
    if differences is None or len(rows) < 2:
        return ""
    if not differences:
        return "\nThe configs differ in no setting but their names.\n"
    head = "| setting | " + " | ".join(r.name for r in rows) + " |"
    lines = ["", "How the configs differ (every setting but the data, which is the first "
             "config's for all):", "", head, "|---" * (len(rows) + 1) + "|"]
    lines += ["| " + " | ".join([f"`{k}`"] + ["-" if v is None else str(v) for v in values])
              + " |" for k, values in differences.items()]
    return "\n".join(lines) + "\n"


#: Settings whose difference makes the rows' train losses different sums
#: (:func:`_legend`).
LOSS_SETTINGS = ("module", "module_args", "loss")


def _legend(rows: Sequence[SweepRow], overrides: Sequence[str], data: Any,
            max_batches: Optional[int] = None,
            differences: Optional[Dict[str, List[Any]]] = None) -> str:
    scope = ("every window" if max_batches is None
             else f"the first {max_batches} batch(es) of windows")
    split = next((r.split for r in rows), "test")
    lines = ["train (min): wall time of the training, set-up included, one row at a time "
             "on this machine.",
             f"train loss: mean over the last {TRAILING_STEPS} steps. Metrics of the "
             f"final weights over {scope} of the {split} split (all datasets; sweep.json has "
             "each dataset's), each skeleton read in the rest pose `reconstruct` shows it "
             "(as `satagraph eval` reads it); RT, JP, FS, GP in cm."]
    if split == "test":
        lines.append("Choose among the rows on a sweep with --split val: a choice made on "
                     "these test figures leaves no test result for it.")
    averaged = {a.split()[0] for a in map(_averaged, rows) if a}
    if "all" in averaged:
        lines.append(f"(all N): the run trained N < {TRAILING_STEPS} steps, so its train "
                     "loss is the mean of every step from the first: higher for that alone, "
                     "not comparable with the others (a longer --budget or --steps is).")
    if "last" in averaged:
        lines.append(f"(last N): a run resumed (--resume) trained N < {TRAILING_STEPS} steps "
                     "after it, whose mean its train loss is: a noisier figure.")
    differ = sorted({k.split(".")[0] for k in differences or {}} & set(LOSS_SETTINGS))
    if differ:
        lines.append(f"The rows differ in {', '.join(differ)}: their train losses are "
                     "different sums, not comparable; the metrics are.")
    if any(r.retarget for r in rows):
        lines.append(f"Retarget: 1000 x mean squared joint error / H^2 over the {split} files; "
                     "int.: onto bone-scaled copies of each source skeleton; cross: onto "
                     "copies with a leaf chain dropped, a bone split and bones scaled "
                     "(paired ground truth from the augmentation).")
    if data is not None:
        lines.append(f"Data (every config): `{json.dumps(data)}`.")
    if overrides:
        lines.append("Overrides (every config): " + " ".join(f"`{o}`" for o in overrides) + ".")
    return "\n".join(lines)


__all__ = ["SweepRow", "SweepRun", "SPLITS", "TRAILING_STEPS", "split_arguments",
           "budget_config", "budget_words", "sweep_configs",
           "train_budgeted", "threads_kept", "run_config", "retarget_table", "held_out_loader",
           "run_sweep", "check_runs", "refuse_other_settings", "finished_rows",
           "config_differences", "format_sweep",
           "write_results"]
