"""Which rest pose to show the model (``--rest``): reconstruction error of the
zoo's VALIDATION-seed rigs (never in ``benchmarks/pretrained.py``) per rest
dialect, read in the file's rest, re-rested on the first frame, with the
line-only rule of 26 Nov (re-rest a line rest on the first frame only) and
with ``auto`` (:func:`satagraph.pipelines.inference.needs_rest`: a line or a
captured pose, re-rested on its mean standing pose). The error is root-relative
(poses, not drift), in % of the height.

    python benchmarks/rest_modes.py [--ckpt builtin] [--per-rest 10] [--out DIR]

Prints a markdown table (and writes ``rest_modes.md`` / ``.json`` to
``--out``).
"""
from __future__ import annotations

import argparse
import collections
import json
import sys
import time
import warnings
from pathlib import Path
from typing import Dict, List

import numpy as np
import torch

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from satagraph.datasets.zoo.dialects import REST_POSES  # noqa: E402
from satagraph.datasets.zoo.endless import EndlessZoo  # noqa: E402
from satagraph.experiment.train import load_module  # noqa: E402
from satagraph.motion import Motion  # noqa: E402
from satagraph.pipelines.inference import (is_line_rest, needs_rest,  # noqa: E402
                                           reconstruct_canonical)
from satagraph.transforms.canonical import canonicalize  # noqa: E402
from satagraph.utils.files import atomic_write_text  # noqa: E402

#: The body plans of the built-in model's training (stage 1).
SPECIES = ("biped", "quadruped", "bird", "fowl")
KINDS = ("walk", "trot", "run", "idle", "turn", "back", "side")
MODES = ("file", "first-frame", "auto")


def pose_error(module, motion: Motion, rest: str) -> float:
    """Root-relative joint error of a reconstruction, in heights."""
    src, out = reconstruct_canonical(module, motion, module.embed, ground=False, rest=rest)
    a, b = src.global_positions(), out.global_positions()
    n = min(len(a), len(b))
    rel = (a[:n] - a[:n, :1]) - (b[:n] - b[:n, :1])
    return float(np.linalg.norm(rel, axis=-1).mean() / src.height())


def validation_rows(module, per_rest: int, frames: int = 120) -> List[Dict]:
    """Up to :obj:`per_rest` validation-seed clips of each rest dialect."""
    zoo = EndlessZoo(species=list(SPECIES))
    count: collections.Counter = collections.Counter()
    rows = []
    for index in range(3000):
        sample = zoo.sample(0, index, frames, "val", False)
        if sample.kind not in KINDS or count[sample.rest] >= per_rest:
            continue
        count[sample.rest] += 1
        skeleton = canonicalize(sample.motion, fps=30.0).skeleton
        row = {"rest": sample.rest, "species": sample.species, "kind": sample.kind,
               "line": is_line_rest(skeleton), "re-rested by auto": needs_rest(skeleton)}
        row.update({mode: pose_error(module, sample.motion, mode) for mode in MODES})
        row["line only"] = row["first-frame"] if row["line"] else row["file"]
        rows.append(row)
        if len(rows) >= per_rest * len(REST_POSES):
            break
    return rows


def table(rows: List[Dict]) -> str:
    """Medians per rest dialect and over all clips (means beside)."""
    cols = ("file", "first-frame", "line only", "auto")
    out = ["| rest | n | " + " | ".join(cols) + " | auto re-rests | auto better / worse than line only |",
           "|---|---:|" + "---:|" * len(cols) + "---:|---|"]
    groups = collections.defaultdict(list)
    for r in rows:
        groups[r["rest"]].append(r)
    for name, group in sorted(groups.items()) + [("all (median; mean)", rows)]:
        med = [100 * np.median([r[c] for r in group]) for c in cols]
        cells = [f"{m:.1f}" for m in med]
        if group is rows:
            cells = [f"{m:.1f}; {100 * np.mean([r[c] for r in group]):.1f}"
                     for m, c in zip(med, cols)]
        better = sum(r["auto"] < r["line only"] - 1e-9 for r in group)
        worse = sum(r["auto"] > r["line only"] + 1e-9 for r in group)
        share = np.mean([r["re-rested by auto"] for r in group])
        out.append(f"| {name} | {len(group)} | " + " | ".join(cells)
                   + f" | {100 * share:.0f}% | {better} / {worse} |")
    return "\n".join(out)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--ckpt", default="builtin")
    parser.add_argument("--per-rest", type=int, default=10)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args(argv)
    torch.set_num_threads(1)
    warnings.simplefilter("ignore")
    start = time.perf_counter()
    module = load_module(args.ckpt).eval()
    rows = validation_rows(module, args.per_rest)
    text = (f"Model `{args.ckpt}`, zoo validation seeds ({', '.join(SPECIES)}), root-relative "
            f"reconstruction error in % of the height; {time.perf_counter() - start:.0f} s.\n\n"
            + table(rows) + "\n")
    print(text)
    if args.out:
        atomic_write_text(args.out / "rest_modes.md", text, create_parent=True)
        atomic_write_text(args.out / "rest_modes.json", json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
