"""Wall time of ``satagraph --help`` and ``satagraph inspect FILE``, and of
each ``--command`` given, each in a fresh Python process, optionally against a
baseline checkout in the same run.

Usage: ``python benchmarks/cli_start.py [--file X.bvh] [--repeat 5]
[--command "retarget --help" ...] [--baseline DIR] [--out FILE.md]`` where a
command is a ``satagraph`` command line that exits with 0 (absolute paths: it
runs in the tree's folder) and DIR holds another copy of the ``satagraph``
package (e.g. ``git archive REV satagraph | tar -x -C DIR``). The runs of the two
trees alternate, so both see the same load on a shared machine. Prints a
markdown table and writes it to ``benchmarks/results/cli_start.md``.
"""
from __future__ import annotations

import argparse
import os
import shlex
import subprocess
import sys
import time
from pathlib import Path
from typing import Dict, List, Optional, Sequence

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "benchmarks" / "results" / "cli_start.md"


def _example_file(folder: Path) -> Path:
    """The built-in example walk written by ``satagraph demo --quick``."""
    path = folder / "example_walk.bvh"
    subprocess.run([sys.executable, "-m", "satagraph", "demo", "--quick",
                    "--output", str(path)], cwd=ROOT, check=True,
                   capture_output=True, env=_env(ROOT))
    return path


def _env(tree: Path) -> Dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(tree), "OMP_NUM_THREADS": "1"}


def _wall(tree: Path, args: Sequence[str]) -> float:
    """Seconds for one ``python -m satagraph ARGS`` importing :obj:`tree`."""
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "satagraph", *args], cwd=tree,
                   check=True, capture_output=True, env=_env(tree))
    return time.perf_counter() - start


def measure(trees: List[Path], commands: List[List[str]], repeat: int
            ) -> List[List[float]]:
    """Best wall time per (command, tree), the trees alternating."""
    best = [[float("inf")] * len(trees) for _ in commands]
    for _ in range(repeat):
        for c, args in enumerate(commands):
            for t, tree in enumerate(trees):
                best[c][t] = min(best[c][t], _wall(tree, args))
    return best


def table(commands: List[List[str]], best: List[List[float]],
          baseline: Optional[Path]) -> str:
    """The markdown table: one row per command."""
    head = "| command | this tree (s) |"
    rule = "|---|---:|"
    if baseline is not None:
        head += " baseline (s) | speed-up |"
        rule += "---:|---:|"
    lines = [head, rule]
    for args, row in zip(commands, best):
        name = "satagraph " + " ".join(Path(a).name for a in args)
        cells = f"| {name} | {row[0]:.2f} |"
        if baseline is not None:
            cells += f" {row[1]:.2f} | {row[1] / row[0]:.1f}x |"
        lines.append(cells)
    return "\n".join(lines)


def main(argv: Optional[List[str]] = None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--file", default=None,
                        help="BVH file for inspect (default: the example walk)")
    parser.add_argument("--repeat", type=int, default=5,
                        help="best of this many runs per cell")
    parser.add_argument("--out", type=Path, default=OUT,
                        help="the table's path (default benchmarks/results/cli_start.md)")
    parser.add_argument("--baseline", type=Path, default=None,
                        help="folder holding a baseline satagraph package")
    parser.add_argument("--command", action="append", default=[], metavar="ARGS",
                        help="another satagraph command line to time, quoted (e.g. "
                        "\"retarget --help\"); repeat it for several")
    args = parser.parse_args(argv)
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(args.file) if args.file else _example_file(Path(tmp))
        commands = [["--help"], ["inspect", str(path)]] + [shlex.split(c) for c in args.command]
        trees = [ROOT] + ([args.baseline.resolve()] if args.baseline else [])
        best = measure(trees, commands, args.repeat)
    text = (f"Fresh process per run, best of {args.repeat}, OMP_NUM_THREADS=1, "
            f"{sys.executable}; the trees alternate run by run"
            + (f"; baseline: {args.baseline}" if args.baseline else "") + ".\n\n"
            + table(commands, best, args.baseline))
    print(text)
    sys.path.insert(0, str(ROOT))  # this tree's satagraph, imported at the end alone
    from satagraph.utils.files import atomic_write_text
    atomic_write_text(args.out, text + "\n", create_parent=True)


if __name__ == "__main__":
    main()
