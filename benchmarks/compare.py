"""SATA-VAE, SATA-RVQ, SAME-wide and the zero-padding RVQ-VAE trained for the
same wall-clock budget on the same data, evaluated on the same test split.

Data: ``../shared/data/manifest.tsv`` without one dataset (``--held-out``,
default ``cmu``), 32-frame windows, batches of 8. Each model trains for
``--minutes`` (``trainer.max_time``) with the :mod:`satagraph.experiment.sweep`
machinery, then its final weights are evaluated:

- Table 1 layout: JR, RT, JP, FS, GP per test dataset, and zero-shot on every
  file of the held-out dataset (a skeleton never seen in training);
- Table 3 layout: retarget error (:func:`satagraph.pipelines.evaluation.retarget_errors`:
  1000 x mean squared joint error / H^2) with paired ground truth from
  skeleton augmentation, on ``--retarget-files`` test files per dataset and
  on the held-out dataset, in the SATA paper's two settings: "internal"
  (bone-scaled copies of the source skeleton: same structure, other
  proportions) and "cross" (copies with a leaf chain dropped, a bone split
  and bones scaled: another structure and other proportions). The datasets'
  skeletons differ, but no file has a paired counterpart on another
  dataset's skeleton, so retargeting between datasets has no ground truth
  here.

By default the models are narrowed so that the whole run fits ~30 minutes
on 2 CPU cores (see :data:`REDUCED`); ``--paper-sizes`` keeps the configs'
sizes. The output says which.

Usage: ``python benchmarks/compare.py [--minutes 5] [--paper-sizes]``.
Writes ``benchmarks/results/compare.md`` (and ``.json``).
"""
from __future__ import annotations

import argparse
from collections import defaultdict
from dataclasses import asdict
from pathlib import Path
from typing import Dict, List, Optional, Sequence

import torch

from results_io import SHARED_DATA, data_folder, write_results
from satagraph.datasets.sources import MotionFile, resolve_sources, select
from satagraph.experiment.sweep import (COLUMNS, RETARGET_HEADERS, TRAILING_STEPS, SweepRow,
                                        held_out_loader, run_config, sweep_configs)

ROOT = Path(__file__).resolve().parents[1]
DATA = SHARED_DATA
#: (label, config).
MODELS = [("SATA-VAE", "sata_vae"), ("SATA-RVQ", "sata_rvq"),
          ("SAME-wide", "same_wide"), ("padded RVQ", "padded_rvq")]
#: Narrow widths per config (the default; ``--paper-sizes`` drops them).
REDUCED = {
    "sata_vae": ["model.hidden_channels=64", "model.ff_channels=128", "model.num_blocks=2",
                 "model.latent_channels=32", "model.dropout=0.0"],
    "sata_rvq": ["model.hidden_channels=64", "model.ff_channels=128", "model.num_blocks=2",
                 "model.latent_channels=64", "model.codebook_size=256", "model.dropout=0.0"],
    "same_wide": ["model.hidden_channels=256", "model.latent_channels=32"],
    "padded_rvq": ["model.hidden_channels=128", "model.latent_channels=128",
                   "model.codebook_size=256"],
}
#: Shared data and trainer settings.
COMMON = ["data.window=32", "data.stride=16", "data.batch_size=8",
          "optim.lr=1.0e-3", "optim.warmup_epochs=1", "trainer.accelerator=cpu",
          "trainer.limit_val_batches=4", "trainer.log_every_n_steps=20"]
HELD_OUT_LABEL = "zero-shot"


def retarget_files(manifest: Path, held_out: str, per_dataset: int) -> Dict[str, List]:
    """Test files (at most :obj:`per_dataset` per dataset) and held-out files
    for the retargeting table."""
    test = select(resolve_sources({"path": str(manifest), "exclude": [held_out]}), "test")
    chosen: Dict[str, List[MotionFile]] = defaultdict(list)
    for f in test:
        if len(chosen[f.dataset]) < per_dataset:
            chosen[f.dataset].append(f)
    unseen = resolve_sources({"path": str(manifest), "dataset": held_out})[:per_dataset]
    return {"test": [f for files in chosen.values() for f in files],
            HELD_OUT_LABEL: unseen}


def run(minutes: float, data: Path, held_out: str, paper_sizes: bool,
        output: Path, per_dataset: int, models: Sequence[str],
        max_batches: Optional[int]) -> List[SweepRow]:
    """Train and evaluate every model; the sweep rows."""
    manifest = data / "manifest.tsv"
    chosen = [(label, cfg) for label, cfg in MODELS if label in models]
    common = COMMON + [f"data.sources=[{{path: {manifest}, exclude: [{held_out}]}}]"]
    variants = [[] if paper_sizes else REDUCED[cfg] for _, cfg in chosen]
    cfgs = sweep_configs([cfg for _, cfg in chosen], common, variants, minutes,
                         str(output))
    loaders = {HELD_OUT_LABEL: held_out_loader(cfgs[0].cfg["data"], {
        "path": str(manifest), "dataset": held_out})}
    files = retarget_files(manifest, held_out, per_dataset)
    rows = []
    for (label, _), cfg in zip(chosen, cfgs):
        print(f"{label}: training for {minutes:g} min", flush=True)
        row = run_config(cfg, extra_loaders=loaders, retarget_files=files,
                         max_batches=max_batches)
        row.name = label
        print(f"    {row.steps} steps, train loss (last {TRAILING_STEPS} steps) "
              f"{row.train_loss:.4f}", flush=True)
        rows.append(row)
    return rows


# ------------------------------------------------------------ tables
def table1(rows: Sequence[SweepRow]) -> str:
    """Metrics per evaluation dataset (test split, then zero-shot)."""
    groups = sorted({g for r in rows for g in r.metrics},
                    key=lambda g: (g.startswith(HELD_OUT_LABEL), g == "all", g))
    head = ["data", "model", "clips"] + [c.heading for c in COLUMNS]
    lines = ["| " + " | ".join(head) + " |", "|---|---" + "|---:" * (len(head) - 2) + "|"]
    for group in groups:
        if group.startswith(HELD_OUT_LABEL + ":"):
            continue  # the held-out dataset is one group
        for r in rows:
            m = r.metrics.get(group)
            if m is None:
                continue
            label = "all (test)" if group == "all" else group
            cells = [label, r.name, str(m["clips"])]
            cells += [c.cell(m[c.name]) for c in COLUMNS]
            lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def table3(rows: Sequence[SweepRow]) -> str:
    """Retarget error per model and setting: per test dataset, all test
    files, and the held-out dataset."""
    groups = sorted({g for r in rows for errors in r.retarget.values() for g in errors
                     if g.startswith("test:")})
    head = (["model", "setting"] + [g.split(":", 1)[1] for g in groups]
            + ["all (test)", HELD_OUT_LABEL])
    lines = ["| " + " | ".join(head) + " |", "|---|---" + "|---:" * (len(head) - 2) + "|"]
    for r in rows:
        for setting in RETARGET_HEADERS:
            errors = r.retarget.get(setting)
            if errors is None:
                continue
            cells = [r.name, setting] + [f"{errors[k]:.3f}" if k in errors else "-"
                                         for k in groups + ["test", HELD_OUT_LABEL]]
            lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def report(rows: Sequence[SweepRow], args) -> str:
    sizes = "paper sizes" if args.paper_sizes else "REDUCED widths (not the paper's sizes)"
    runs = "\n".join(f"- {r.name}: {r.params / 1e6:.2f} M parameters, {r.steps} steps "
                     f"in {r.seconds:.0f} s (set-up included), train loss over the last "
                     f"{TRAILING_STEPS} steps "
                     f"{r.train_loss:.4f}" for r in rows)
    return f"""Budget: {args.minutes:g} min of training per model on CPU, {sizes};
data: {args.data}/manifest.tsv without {args.held_out}, 32-frame windows, batch 8;
final weights; torch {torch.__version__}.

{runs}

## Table 1 layout: reconstruction per test dataset and zero-shot on {args.held_out}

{table1(rows)}

RT, JP, FS, GP in cm. {HELD_OUT_LABEL}: every {args.held_out} file (all splits),
a skeleton absent from training.

## Table 3 layout: retargeting error (x1000 / H^2)

{table3(rows)}

internal: onto bone-scaled copies (x0.8-1.2 per axis) of the source skeleton
(same structure, other proportions); cross: onto copies with a leaf chain of
up to two joints dropped, a bone split by a new joint and bones scaled (another
structure and other proportions). Ground truth: the same motion on that
skeleton (satagraph.transforms.augment). {args.retarget_files} test files per dataset
(first 600 frames); {HELD_OUT_LABEL}: {args.retarget_files} {args.held_out} files.
"""


def main(argv: Optional[Sequence[str]] = None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--minutes", type=float, default=5.0,
                        help="training minutes per model (default 5)")
    parser.add_argument("--paper-sizes", action="store_true",
                        help="train the configs' (paper) sizes instead of reduced widths")
    parser.add_argument("--data", type=data_folder, default=str(DATA))
    parser.add_argument("--held-out", default="cmu")
    parser.add_argument("--models", default=",".join(m for m, _ in MODELS))
    parser.add_argument("--retarget-files", type=int, default=2,
                        help="files per dataset for the retargeting table")
    parser.add_argument("--max-batches", type=int, default=None,
                        help="evaluation batches per loader (default: all)")
    parser.add_argument("--runs", default=str(ROOT / "runs" / "compare"),
                        help="run folders (checkpoints, logs)")
    parser.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "compare"))
    args = parser.parse_args(argv)
    rows = run(args.minutes, Path(args.data), args.held_out, args.paper_sizes,
               Path(args.runs), args.retarget_files,
               [m.strip() for m in args.models.split(",")], args.max_batches)
    text = report(rows, args)
    print(text)
    write_results(Path(args.out), "Equal-budget comparison", text,
                  {"args": vars(args), "rows": [asdict(r) for r in rows]})


if __name__ == "__main__":
    main()
