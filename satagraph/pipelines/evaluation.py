"""Evaluation loops: metrics per dataset, and paired retargeting error."""
from __future__ import annotations

from collections import defaultdict
from dataclasses import replace
from typing import Any, Callable, Dict, Mapping, Optional, Sequence

import torch

from satagraph.transforms.augment import restructure, scale_bones
from satagraph.transforms.canonical import canonicalize
from satagraph.data.features import (MotionFeatures, features_to_motion,
                                     motion_to_features)
from satagraph.datasets.sources import MotionFile
from satagraph.pipelines.metric_columns import METRIC_COLUMNS, MetricColumn
from satagraph.pipelines.inference import facing_smooth_of, transfer
from satagraph.motion import Motion

#: How each retargeting setting builds the target skeleton and its paired
#: ground truth from a source motion, ``(motion, low, high, seed) -> Motion``:
#: "internal" keeps the skeleton's structure and changes its proportions,
#: "cross" also drops a leaf chain and splits a bone.
RETARGET_SETTINGS: Dict[str, Callable] = {"internal": scale_bones, "cross": restructure}


#: The rest pose each skeleton is read in when a model is scored: the one
#: ``reconstruct`` shows it (``eval --rest``, and every sweep row).
SCORING_REST = "auto"


def scoring_data(data: Mapping[str, Any], rest: str = SCORING_REST, sources: Any = None,
                 up_axis: Optional[str] = None, scale: Any = None,
                 split: Optional[str] = None, on_error: Optional[str] = None):
    r"""The data a trained model is scored on, the one rule of ``eval`` and
    of sweeps: its data section (:obj:`sources` in place of its sources),
    every file of each split whatever ``data.max_files`` training read, each
    skeleton in the rest pose :obj:`rest`, the rig read as :obj:`up_axis`
    and :obj:`scale` where given; set up for testing (no training file is
    needed: the model has its own statistics). With :obj:`split`, only that
    split's files are read (a bad training file stopped ``eval --split
    test``); :obj:`on_error` (``"raise"`` or ``"skip"``) replaces the data
    section's ``on_error`` where given (``eval --on-error``).

    Returns:
        MotionDataModule: Its ``datasets[split]`` and :func:`split_loader`.

    Raises:
        ValueError: No sources.
    """
    from satagraph.data.datamodule import MotionDataModule
    data = dict(data, max_files=None)
    if sources:
        data["sources"] = sources
    if not data.get("sources"):
        raise ValueError("the checkpoint does not name its data: pass --data")
    prep = dict(data.get("preprocessing") or {}, rest=rest)
    prep.update({k: v for k, v in (("up_axis", up_axis), ("scale", scale)) if v is not None})
    if on_error is not None:
        data["on_error"] = on_error
    dm = MotionDataModule(**dict(data, preprocessing=prep))
    if split is not None:
        dm.splits = (split,)
    dm.setup("test")
    return dm


def split_loader(dm, split: str):
    """The evaluation loader of one split (unshuffled)."""
    return dm.test_dataloader() if split == "test" else dm._loader(split, False)


def evaluate(module, loader, max_batches: Optional[int] = None) -> Dict[str, Dict[str, float]]:
    """Mean metrics per dataset (and ``all``) over a data loader."""
    sums: Dict[str, Dict[str, float]] = defaultdict(lambda: defaultdict(float))
    counts: Dict[str, int] = defaultdict(int)
    module.eval()
    with torch.no_grad():
        for i, batch in enumerate(loader):
            if max_batches is not None and i >= max_batches:
                break
            metrics = module.metrics(module(batch), batch)
            for k, meta in enumerate(batch.meta):
                for group in (meta.get("dataset", "?"), "all"):
                    counts[group] += 1
                    for name, values in metrics.items():
                        sums[group][name] += float(values[k])
    return {g: dict({n: v / counts[g] for n, v in m.items()}, clips=counts[g])
            for g, m in sums.items()}


def retarget_errors(module, files: Sequence[MotionFile], semantic: Optional[Callable] = None,
                    low: float = 0.8, high: float = 1.2, seed: int = 0,
                    max_frames: int = 600, setting: str = "internal") -> Dict[str, float]:
    r"""Retargeting error onto skeletons with paired ground truth, in one
    setting: the mean per dataset (and ``"all"``) of
    :func:`retarget_error_table` (see there for the arguments)."""
    return retarget_error_table(module, files, semantic, low, high, seed, max_frames,
                                (setting,))[setting]


def retarget_error_table(module, files: Sequence[MotionFile],
                         semantic: Optional[Callable] = None, low: float = 0.8,
                         high: float = 1.2, seed: int = 0, max_frames: int = 600,
                         settings: Optional[Sequence[str]] = None
                         ) -> Dict[str, Dict[str, float]]:
    r"""Retargeting error onto skeletons with paired ground truth.

    Each file's motion is retargeted onto a copy of its skeleton built by
    each setting (see :data:`RETARGET_SETTINGS`: bone lengths scaled per
    axis in ``[low, high]``, and for ``"cross"`` a leaf chain dropped and a
    bone split too); the ground truth is the same motion on that skeleton.
    Each file is read once for every setting. Returns ``{setting: {group:
    mean of 1000 * mean ||p - p_hat||^2 / H^2}}`` per dataset and ``"all"``,
    with :math:`H` the target's height.

    Args:
        module: A trained autoencoder module.
        files (list[MotionFile]): The source files.
        semantic (callable, optional): Semantic embedder of the module.
        low (float): Smallest per-axis bone scale.
        high (float): Largest per-axis bone scale.
        seed (int): Seed of the first file's target (file ``i`` gets
            ``seed + i``).
        max_frames (int): Frames of each file used (from the start).
        settings (list[str], optional): Among ``"internal"`` and ``"cross"``
            (default: every one of :data:`RETARGET_SETTINGS`).
    """
    settings = tuple(RETARGET_SETTINGS) if settings is None else tuple(settings)
    unknown = sorted(set(settings) - set(RETARGET_SETTINGS))
    if unknown:
        raise ValueError(f"retarget_error_table: unknown setting {unknown[0]!r}; "
                         f"known: {sorted(RETARGET_SETTINGS)}")
    fps = float(getattr(module, "fps", 30.0))
    sums = {s: defaultdict(float) for s in settings}
    counts: Dict[str, int] = defaultdict(int)
    for i, f in enumerate(files):
        src = canonicalize(f.read(), fps=fps).slice(0, max_frames)
        src_f = motion_to_features(src, facing_smooth=facing_smooth_of(module))
        for group in (f.dataset, "all"):
            counts[group] += 1
        for setting in settings:
            value = _paired_error(module, src_f, RETARGET_SETTINGS[setting](
                src, low, high, seed + i), semantic)
            for group in (f.dataset, "all"):
                sums[setting][group] += value
    return {s: {g: sums[s][g] / counts[g] for g in counts} for s in settings}


def _paired_error(module, source: MotionFeatures, truth: Motion,
                  semantic: Optional[Callable]) -> float:
    """``1000 * mean ||p - p_hat||^2 / H^2`` of retargeting :obj:`source`
    onto :obj:`truth`'s skeleton, against :obj:`truth`."""
    target = motion_to_features(truth)
    q, r, _ = transfer(module, source, target, semantic)
    pred = features_to_motion(replace(target, q=q, r=r), q=q, r=r, use_positions=False)
    err = ((pred.global_positions() - truth.global_positions()) ** 2).sum(-1).mean()
    return float(1000 * err / target.height ** 2)


#: The paper's figures of :func:`~satagraph.metrics.motion_metrics`: name,
#: column header, factor to the unit shown (one definition with the sweep's).
TABLE_COLUMNS = METRIC_COLUMNS


def format_table(results: Dict[str, Dict[str, float]]) -> str:
    """Markdown table: one row per dataset, a column per figure of
    :func:`evaluate`: the paper's that the module's ``metrics`` gives (RT,
    JP, FS, GP in cm), then a subclass's own by name (it had none, and a
    module without the paper's was a ``KeyError``)."""
    names = {n for r in results.values() for n in r if n != "clips"}
    known = {c.name for c in TABLE_COLUMNS}
    cols = [c for c in TABLE_COLUMNS if c.name in names] + [MetricColumn(n, n)
                                                            for n in sorted(names - known)]
    lines = ["| dataset | clips | " + " | ".join(c.heading for c in cols) + " |",
             "|---" * (len(cols) + 2) + "|"]
    for name in sorted(results, key=lambda g: (g == "all", g)):
        r = results[name]
        vals = [c.cell(r.get(c.name)) for c in cols]
        lines.append(f"| {name} | {r['clips']} | " + " | ".join(vals) + " |")
    return "\n".join(lines)

