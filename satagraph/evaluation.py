"""Evaluation loops: metrics per dataset, and paired retargeting error."""
from __future__ import annotations

from collections import defaultdict
from dataclasses import replace
from typing import Callable, Dict, Optional, Sequence

import torch

from satagraph.data.augment import scale_bones
from satagraph.data.canonical import canonicalize
from satagraph.data.features import features_to_motion, motion_to_features
from satagraph.data.sources import MotionFile
from satagraph.inference import transfer
from satagraph.io import read_bvh


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
                    max_frames: int = 600) -> Dict[str, float]:
    r"""Retargeting error onto differently proportioned skeletons.

    Each file's motion is retargeted onto a copy of its skeleton with bone
    lengths scaled per axis in ``[low, high]``; the ground truth is the same
    local motion on that skeleton (:func:`~satagraph.data.augment.scale_bones`).
    Returns the mean ``1000 * mean ||p - p_hat||^2 / H^2`` per dataset.
    """
    fps = float(getattr(module, "fps", 30.0))
    sums, counts = defaultdict(float), defaultdict(int)
    for i, f in enumerate(files):
        src = canonicalize(read_bvh(f.path), fps=fps).slice(0, max_frames)
        gt = scale_bones(src, low, high, seed + i)
        src_f, gt_f = motion_to_features(src), motion_to_features(gt)
        q, r, _ = transfer(module, src_f, gt_f, semantic)
        pred = features_to_motion(replace(gt_f, q=q, r=r), q=q, r=r, use_positions=False)
        err = ((pred.global_positions() - gt.global_positions()) ** 2).sum(-1).mean()
        value = 1000 * err / gt_f.height ** 2
        for group in (f.dataset, "all"):
            sums[group] += value
            counts[group] += 1
    return {g: sums[g] / counts[g] for g in sums}


def format_table(results: Dict[str, Dict[str, float]]) -> str:
    """Markdown table: one row per dataset (RT, JP, FS, GP in cm)."""
    cols = ["JR", "RT", "JP", "RT_h", "JP_h", "FS", "GP", "RE"]
    lines = ["| dataset | clips | JR (rad) | RT (cm) | JP (cm) | RT/H | JP/H | FS (cm) "
             "| GP (cm) | RE |", "|---" * 10 + "|"]
    for name in sorted(results, key=lambda g: (g == "all", g)):
        r = results[name]
        vals = [r[c] * (100 if c in ("RT", "JP", "FS", "GP") else 1) for c in cols]
        lines.append(f"| {name} | {r['clips']} | " + " | ".join(f"{v:.4f}" for v in vals) + " |")
    return "\n".join(lines)

