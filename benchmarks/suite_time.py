"""Wall time of ``make test`` (the README's test command), optionally against
a baseline checkout in the same run.

Usage: ``python benchmarks/suite_time.py [--repeat 2] [--baseline DIR] [--out FILE.md]``
where DIR is another checkout of the repository (e.g. ``git worktree add DIR
REV``); it runs with this tree's virtual environment. The runs of the two
trees alternate, so both see the same load on a shared machine; the first
run of each tree also compiles its bytecode, so the table gives the best of
the repeats. Prints a markdown table and writes it to
``benchmarks/results/suite_time.md``.
"""
from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import time
from pathlib import Path
from typing import List, Optional, Sequence, Tuple

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "benchmarks" / "results" / "suite_time.md"


def _run(tree: Path) -> Tuple[float, float, str]:
    """``make test`` in :obj:`tree`: (wall seconds, pytest's own seconds,
    its summary line)."""
    venv = tree / ".venv"
    if not venv.exists():
        venv.symlink_to(ROOT / ".venv")
    start = time.perf_counter()
    done = subprocess.run(["make", "-o", ".venv/.installed", "test"], cwd=tree,
                          capture_output=True, text=True, env=dict(os.environ))
    wall = time.perf_counter() - start
    summary = done.stdout.strip().splitlines()[-1] if done.stdout.strip() else done.stderr[-200:]
    if done.returncode:
        raise RuntimeError(f"make test failed in {tree}: {summary}")
    inner = re.search(r" in ([\d.]+)s", summary)
    return wall, float(inner.group(1)) if inner else float("nan"), summary


def _label(tree: Path) -> str:
    """The tree and its commit (``+`` where its files differ from it)."""
    rev = subprocess.run(["git", "describe", "--always", "--dirty=+"], cwd=tree,
                         capture_output=True, text=True).stdout.strip()
    return f"{tree} ({rev})" if rev else str(tree)


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--baseline", type=Path, default=None)
    parser.add_argument("--out", type=Path, default=OUT,
                        help="the table's path (default benchmarks/results/suite_time.md)")
    args = parser.parse_args(argv)
    trees = [ROOT] + ([args.baseline.resolve()] if args.baseline else [])
    runs: List[List[Tuple[float, float, str]]] = [[] for _ in trees]
    for _ in range(args.repeat):
        for i, tree in enumerate(trees):
            runs[i].append(_run(tree))
    rows = ["| tree | wall, best (s) | pytest's own, best (s) | every wall (s) | tests |",
            "|---|---:|---:|---|---|"]
    for tree, got in zip(trees, runs):
        walls = ", ".join(f"{w:.1f}" for w, _, _ in got)
        summary = got[-1][2].split(" in ")[0]
        rows.append(f"| {_label(tree)} | {min(w for w, _, _ in got):.1f} | "
                    f"{min(p for _, p, _ in got):.1f} | {walls} | {summary} |")
    text = (f"`make test`, {args.repeat} runs a tree, the trees alternating, "
            f"{os.cpu_count()} CPUs.\n\n" + "\n".join(rows) + "\n")
    print(text)
    sys.path.insert(0, str(ROOT))  # this tree's satagraph, imported at the end alone
    from satagraph.utils.files import atomic_write_text
    atomic_write_text(args.out, "# Test suite time (benchmarks/suite_time.py)\n\n" + text,
                      create_parent=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
