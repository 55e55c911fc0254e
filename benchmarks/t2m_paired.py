"""Paired differences of two samplings over several seeds of ``benchmarks/t2m.py``.

A decoding or sampling rule reads the candidate against the baseline on
the same material. Within one ``t2m.py`` seed the two runs share their
prompts, their evaluator and (for a decoding change) their drawn codes, so
each cell's difference is paired; across seeds the evaluator and the
prompts change, and the paired differences scatter more than one run's
pool half-width says (``experiments/T2M.md`` section 72: Bandai's R@3
moved -0.016 to +0.023 on four seeds whose half-widths were 0.009-0.014).
This reads the JSON files of such runs, pairs them by seed and prints, per
cell, each seed's difference, their mean, their standard deviation and a
95 % Student-t interval of the mean.

    .venv/bin/python benchmarks/t2m_paired.py --baseline B19/t2m_val.json B20/t2m_val.json \\
        --candidate C19/t2m_val.json C20/t2m_val.json \\
        [--cell "zoo|generator (GT length)|fid" ...] [--out OUT.md]

Cells are ``group|row|metric`` (metrics: ``R@1``-``R@3``, ``fid``, ``kid``,
``action``, ``diversity``, ``matching``, ``slide``, ``hover``, and
``action:LABEL``, the action accuracy on the prompts asking for LABEL); by default
:data:`CELLS`, what sections 69-72's and 83-85's rules read.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Dict, List, Sequence, Tuple

#: The cells a decoding or sampling rule reads (``experiments/T2M.md``
#: sections 69 and 83-85): the zoo generator's R@3, FID, action accuracy,
#: diversity and foot sliding, Bandai's generator R@3, FID and action
#: accuracy, the baseline the FID target names, and the RVQ's
#: reconstruction.
CELLS = ("zoo|generator (GT length)|R@3", "zoo|generator (GT length)|fid",
         "zoo|generator (GT length)|action", "zoo|generator (GT length)|diversity",
         "zoo|generator (GT length)|slide",
         "bandai (val)|generator (GT length)|R@3", "bandai (val)|generator (GT length)|fid",
         "bandai (val)|generator (GT length)|action",
         "zoo|retrieval (retargeted)|fid", "zoo|retrieval (retargeted)|diversity",
         "zoo|reconstruction (SATA-RVQ)|R@3")

#: Two-sided 95 % Student-t quantiles by degrees of freedom (1-30); above
#: 30, the normal's 1.96.
T95 = (12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228,
       2.201, 2.179, 2.160, 2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086,
       2.080, 2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048, 2.045, 2.042)


def load_run(path: str) -> Dict:
    """One ``t2m.py`` JSON file (a clear error naming the file otherwise)."""
    try:
        run = json.loads(Path(path).read_text())
    except (OSError, ValueError) as err:
        raise SystemExit(f"{path}: not a readable t2m.py JSON file ({err})")
    if not isinstance(run, dict) or "rows" not in run or "facts" not in run:
        raise SystemExit(f"{path}: no 'rows' and 'facts': not written by benchmarks/t2m.py")
    return {**run, "path": path}


def cell_value(run: Dict, cell: str) -> float:
    """A cell's value (a ``[mean, half-width]`` pair gives its mean)."""
    try:
        group, row, metric = cell.split("|")
    except ValueError:
        raise SystemExit(f"cell {cell!r}: not GROUP|ROW|METRIC")
    for r in run["rows"]:
        if r["group"] == group and r["row"] == row:
            value = _metric(r, metric)
            if value is None:
                break
            return float(value[0] if isinstance(value, (list, tuple)) else value)
    raise SystemExit(f"{run.get('path', 'a run')}: no cell {cell!r}")


def _metric(row: Dict, metric: str):
    """A row's metric; ``action:LABEL`` is the action accuracy on the
    prompts asking for LABEL (``None`` where the row has none)."""
    if metric.startswith("action:"):
        label = (row.get("action_by_label") or {}).get(metric.split(":", 1)[1])
        return None if label is None else label.get("accuracy")
    return row.get(metric)


def pair_runs(baseline: Sequence[str], candidate: Sequence[str]) -> List[Tuple[int, Dict, Dict]]:
    """The runs paired in order, each pair checked to share its seed and
    its prompts: ``(seed, baseline run, candidate run)``."""
    if len(baseline) != len(candidate) or not baseline:
        raise SystemExit(f"{len(baseline)} baseline and {len(candidate)} candidate files: "
                         "give one of each per seed, in the same order")
    pairs = []
    for b_path, c_path in zip(baseline, candidate):
        b, c = load_run(b_path), load_run(c_path)
        for key in ("seed", "prompts", "bandai_val", "evaluator_steps"):
            if b["facts"].get(key) != c["facts"].get(key):
                raise SystemExit(f"{b_path} and {c_path}: not a pair ({key} "
                                 f"{b['facts'].get(key)!r} against {c['facts'].get(key)!r})")
        pairs.append((b["facts"]["seed"], b, c))
    return pairs


def summary(diffs: Sequence[float]) -> Tuple[float, float, float]:
    """Mean, sample standard deviation and 95 % t half-width of paired
    differences (the last two NaN for one pair)."""
    n = len(diffs)
    mean = sum(diffs) / n
    if n < 2:
        return mean, math.nan, math.nan
    sd = math.sqrt(sum((d - mean) ** 2 for d in diffs) / (n - 1))
    t = T95[n - 2] if n - 1 <= len(T95) else 1.96
    return mean, sd, t * sd / math.sqrt(n)


def table(pairs: Sequence[Tuple[int, Dict, Dict]], cells: Sequence[str]) -> str:
    """The markdown table: per cell, each seed's baseline -> candidate
    (difference), the mean difference, its standard deviation and 95 %
    interval."""
    seeds = [seed for seed, _, _ in pairs]
    head = ("| cell | " + " | ".join(f"seed {s}" for s in seeds)
            + " | mean difference | sd | 95 % interval |")
    lines = [head, "|---|" + "---|" * len(seeds) + "---:|---:|---|"]
    for cell in cells:
        values = [(cell_value(b, cell), cell_value(c, cell)) for _, b, c in pairs]
        diffs = [c - b for b, c in values]
        mean, sd, half = summary(diffs)
        per_seed = [f"{b:.3f} -> {c:.3f} ({c - b:+.3f})" for b, c in values]
        interval = "" if math.isnan(half) else f"{mean - half:+.3f} to {mean + half:+.3f}"
        sd_text = "" if math.isnan(sd) else f"{sd:.3f}"
        lines.append(f"| {cell.replace('|', ' / ')} | " + " | ".join(per_seed)
                     + f" | {mean:+.3f} | {sd_text} | {interval} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--baseline", nargs="+", required=True, metavar="JSON",
                        help="t2m.py JSON files of the baseline, one per seed")
    parser.add_argument("--candidate", nargs="+", required=True, metavar="JSON",
                        help="the candidate's, the same seeds in the same order")
    parser.add_argument("--cell", action="append", default=None, metavar="GROUP|ROW|METRIC",
                        help="a cell to read (repeatable; default: the rule cells, CELLS)")
    parser.add_argument("--out", default=None, help="also write the table here")
    args = parser.parse_args(argv)
    pairs = pair_runs(args.baseline, args.candidate)
    text = (f"Paired differences, candidate minus baseline, over {len(pairs)} seeds "
            f"(prompts: {pairs[0][1]['facts'].get('prompts')})\n\n"
            + table(pairs, args.cell or CELLS) + "\n")
    if args.out:
        sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this tree's
        from satagraph.utils.files import atomic_write_text
        atomic_write_text(args.out, text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
