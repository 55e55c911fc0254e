"""Peak memory and wall time of ``satagraph retarget`` and ``reconstruct``
(built-in model, default flags) on long takes: a real clip's frames
repeated to 5 000, 20 000 and 60 000 frames (the header kept, the frames
written again and again).

Each command runs in its own process; its peak resident memory is that
process's ``ru_maxrss`` (:func:`os.wait4`), so the interpreter, torch and
the model (about 0.55 GB) are in every row. What grows with the take is
the difference between rows.

Usage: ``python benchmarks/long_take.py [--data ../shared/data]
[--frames 5000 20000 60000] [--commands retarget reconstruct] [--keep DIR] [--out PATH]``.
Prints a markdown table and writes it to ``benchmarks/results/long_take.md``
(and ``.json``).
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Dict, List, Optional, Sequence

from results_io import SHARED_DATA, data_folder, write_results  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SOURCE = "bandai/dataset-1_walk_normal_001.bvh"  # 195 frames at 30 fps
TARGET = "cmu/01_01.bvh"


def repeated_take(source: Path, num_frames: int, out: Path) -> Path:
    """:obj:`source` with its frames repeated (in order, from the first
    again) to :obj:`num_frames` frames, written to :obj:`out`."""
    lines = source.read_text().splitlines()
    motion = next(i for i, line in enumerate(lines) if line.strip() == "MOTION")
    frames = [line for line in lines[motion + 3:] if line.strip()]
    with open(out, "w") as f:
        f.write("\n".join(lines[:motion + 1]))
        f.write(f"\nFrames: {num_frames}\n{lines[motion + 2]}\n")
        for i in range(num_frames):
            f.write(frames[i % len(frames)] + "\n")
    return out


def run_measured(argv: Sequence[str]) -> Dict[str, float]:
    """Runs ``python -m satagraph ARGV`` with one thread: its wall time
    (seconds) and peak resident memory (MB)."""
    env = dict(os.environ, OMP_NUM_THREADS="1", PYTHONPATH=str(ROOT))
    start = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-m", "satagraph", *argv], env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    if os.waitstatus_to_exitcode(status):
        raise RuntimeError(f"satagraph {' '.join(argv)}: {proc.stderr.read().decode()}")
    return {"wall_s": wall, "peak_mb": usage.ru_maxrss / 1024}


def measure(data: Path, frames: Sequence[int], commands: Sequence[str],
            keep: Optional[str] = None) -> List[dict]:
    """One row per take length and command (the takes and outputs written
    to :obj:`keep` where given, else to a folder deleted afterwards)."""
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        tmp = keep or scratch
        Path(tmp).mkdir(parents=True, exist_ok=True)
        for num in frames:
            take = repeated_take(data / SOURCE, num, Path(tmp) / f"take_{num}.bvh")
            for command in commands:
                extra = ["--target", str(data / TARGET)] if command == "retarget" else []
                out = Path(tmp) / f"{command}_{num}.bvh"
                row = run_measured([command, str(take), str(out), *extra])
                rows.append(dict(row, frames=num, command=command))
                print(f"{command} {num}: {row['peak_mb']:.0f} MB, {row['wall_s']:.1f} s",
                      file=sys.stderr)
    return rows


def table(rows: List[dict]) -> str:
    """The rows as a markdown table, with the growth per 1 000 frames past
    each command's first row."""
    lines = ["| command | frames | peak RSS (MB) | wall (s) | MB per 1k frames more |",
             "|---|---:|---:|---:|---:|"]
    first: Dict[str, dict] = {}
    for row in rows:
        base = first.setdefault(row["command"], row)
        grown = (row["peak_mb"] - base["peak_mb"]) / max(row["frames"] - base["frames"], 1)
        slope = "" if row is base else f"{1000 * grown:.1f}"
        lines.append(f"| {row['command']} | {row['frames']} | {row['peak_mb']:.0f} | "
                     f"{row['wall_s']:.1f} | {slope} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=data_folder,
                        default=str(SHARED_DATA))
    parser.add_argument("--frames", type=int, nargs="+", default=[5000, 20000, 60000])
    parser.add_argument("--commands", nargs="+", default=["retarget", "reconstruct"],
                        choices=["retarget", "reconstruct"])
    parser.add_argument("--keep", help="a folder to keep the takes and the outputs in")
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results" / "long_take",
                        help="results path without suffix (default "
                        "benchmarks/results/long_take)")
    args = parser.parse_args()
    rows = measure(Path(args.data), args.frames, args.commands, args.keep)
    text = table(rows)
    print(text)
    write_results(args.out, "Long takes: peak memory "
                  "and wall time of retarget and reconstruct", text, rows)


if __name__ == "__main__":
    main()
