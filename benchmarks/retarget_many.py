"""Many clips onto one rig from Python: :func:`retarget_motion` once per
clip (the target canonicalised, mirrored and featured every time) against
one :class:`~satagraph.pipelines.inference.Retargeter` called on the list
(the target's work done once), on a CPU with the built-in model.

The first :obj:`--clips` Bandai clips (by name) onto the dog's 1531-frame
``D1_001_KAN01_001``, in one process after a warm-up, the two ways
alternating clip by clip (which goes first alternating too), over all
clips :obj:`--repeat` times; the median wall and CPU seconds of each way
are shown, and every output is checked to be ``retarget_motion``'s to the
bit.

Usage: ``python benchmarks/retarget_many.py [--data ../shared/data]
[--clips 10] [--repeat 3] [--threads 2] [--out PATH]``. Prints a markdown
table and writes it to ``benchmarks/results/retarget_many.md`` (and
``.json``). Without the real files it says so in one line and exits.
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
import warnings
from pathlib import Path
from typing import Dict, List, Optional

import numpy as np

from results_io import SHARED_DATA, missing_data, write_results  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
TARGET = "dog/D1_001_KAN01_001.bvh"  # 1531 frames at 60 fps
SOURCES = "bandai"  # its first --clips clips by name
WAYS = ("retarget_motion per clip", "one Retargeter(model, dog)")


def measure(model, target, sources: List, repeat: int) -> Dict[str, Dict[str, List[float]]]:
    """Wall and CPU seconds of both ways over all :obj:`sources`,
    :obj:`repeat` passes; the ways alternate clip by clip (which goes first
    alternating too), so that a neighbour's load falls on both alike. Each
    pass makes its :class:`Retargeter` afresh (the target's work in its
    first clip); every output is checked to be ``retarget_motion``'s to the
    bit."""
    from satagraph.pipelines.inference import Retargeter, retarget_motion
    seconds = {way: {"wall": [], "cpu": []} for way in WAYS}
    for _ in range(repeat):
        onto = Retargeter(model, target, model.embed)
        run = {WAYS[0]: lambda s: retarget_motion(model, s, target, model.embed),
               WAYS[1]: onto}
        took = {way: [0.0, 0.0] for way in WAYS}
        for i, source in enumerate(sources):
            outs = []
            for way in (WAYS if i % 2 == 0 else WAYS[::-1]):
                wall, cpu = time.perf_counter(), time.process_time()
                outs.append(run[way](source))
                took[way][0] += time.perf_counter() - wall
                took[way][1] += time.process_time() - cpu
            if not (np.array_equal(outs[0].rotations, outs[1].rotations)
                    and np.array_equal(outs[0].translations, outs[1].translations)):
                raise RuntimeError(f"{source.source}: the two ways differ")
        for way, (wall, cpu) in took.items():
            seconds[way]["wall"].append(wall)
            seconds[way]["cpu"].append(cpu)
    return seconds


def table(seconds: Dict[str, Dict[str, List[float]]], clips: int) -> str:
    """The markdown table: median wall and CPU seconds, wall per clip, and
    the speed-up over ``retarget_motion`` of each."""
    base = {kind: statistics.median(seconds[WAYS[0]][kind]) for kind in ("wall", "cpu")}
    lines = ["| way | wall s (median) | wall s per clip | wall s per pass | speed-up (wall) "
             "| CPU s (median) | speed-up (CPU) |", "|---|---:|---:|---|---:|---:|---:|"]
    for way, runs in seconds.items():
        wall, cpu = (statistics.median(runs[kind]) for kind in ("wall", "cpu"))
        lines.append(f"| {way} | {wall:.2f} | {wall / clips:.3f} | "
                     f"{', '.join(f'{r:.2f}' for r in runs['wall'])} | "
                     f"{base['wall'] / wall:.2f}x | {cpu:.2f} | {base['cpu'] / cpu:.2f}x |")
    return "\n".join(lines)


def main(argv: Optional[List[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=SHARED_DATA,
                        help="the real BVH files (default ../shared/data)")
    parser.add_argument("--clips", type=int, default=10, help="Bandai clips (default 10)")
    parser.add_argument("--repeat", type=int, default=3,
                        help="passes of each way, alternating (median shown)")
    parser.add_argument("--threads", type=int, default=2, help="torch threads (default 2)")
    parser.add_argument("--out", type=Path,
                        default=ROOT / "benchmarks" / "results" / "retarget_many",
                        help="results path without suffix")
    args = parser.parse_args(argv)
    missing = missing_data("retarget_many.py", args.data, "the clips timed")
    if missing:
        print(f"{missing}; pass --data DIR", file=sys.stderr)
        return 2
    import torch

    from satagraph.experiment.train import load_module
    from satagraph.io import read_bvh
    from satagraph.pipelines.inference import retarget_motion
    torch.set_num_threads(args.threads)
    warnings.simplefilter("ignore")  # the dog's units: the commands silence it too
    model = load_module("builtin")
    target = read_bvh(str(args.data / TARGET))
    sources = [read_bvh(str(p)) for p in sorted((args.data / SOURCES).glob("*.bvh"))[:args.clips]]
    retarget_motion(model, sources[0], target, model.embed)  # warm-up
    seconds = measure(model, target, sources, args.repeat)
    frames = sum(s.num_frames for s in sources)
    text = (f"{len(sources)} Bandai clips ({frames} frames) onto the dog's {TARGET} "
            f"({target.num_frames} frames), built-in model, default settings, "
            f"{args.threads} torch threads, one process, the two ways alternating clip by clip, "
            f"median of {args.repeat} passes over all clips; each pass makes its Retargeter "
            "afresh (the target's work in its first clip); outputs identical to the bit; CPU: "
            "this process's, all threads.\n\n" + table(seconds, len(sources)) + "\n")
    print(text)
    write_results(args.out, "Many clips onto one rig (benchmarks/retarget_many.py)", text,
                  {"clips": len(sources), "frames": frames, "threads": args.threads,
                   "repeat": args.repeat, "seconds": seconds})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
