"""Collating a batch of clips of mixed skeletons into frame graphs.

Usage: ``python benchmarks/collate.py [--data ../shared/data] [--clips 32]
[--frames 64] [--repeat 50] [--out benchmarks/results/collate]``.

Builds real clips from the dog (MANN, 21 joints without end sites) and
ccbase (100 joints without end sites) files, half of each, interleaved, and
times :func:`satagraph.data.collate_clips` on them, with one torch thread
(as in :class:`~torch.utils.data.DataLoader` workers, which set it so) and
with torch's default thread count (as with ``num_workers=0``). Prints a
markdown table and writes it to ``--out`` with ``.md`` (and ``.json``), once
the run is over; a quick run (``--repeat 1``) can leave the committed table
alone with ``--out /tmp/collate``.
"""
from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path
from typing import List, Optional

import torch

from satagraph.data.clip import MotionClip
from satagraph.data.collate import collate_clips
from satagraph.data.dataset import DEFAULT_PREPROCESSING, preprocess_file
from satagraph.memory import retain_freed_memory
from results_io import SHARED_DATA, data_folder, write_results  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SOURCES = ("dog", "ccbase")


def _clips_from(folder: Path, count: int, frames: int) -> List[MotionClip]:
    """:obj:`count` windows of :obj:`frames` frames from the files of a
    folder (a few files, several windows each)."""
    clips: List[MotionClip] = []
    for path in sorted(folder.glob("*.bvh")):
        feats = preprocess_file(str(path), DEFAULT_PREPROCESSING)
        for start in range(0, feats.num_frames - frames + 1, frames):
            clips.append(feats.to_clip(start, start + frames,
                                       meta={"path": str(path)}))
            if len(clips) == count:
                return clips
    raise SystemExit(f"not enough {frames}-frame windows under {folder}")


def build_clips(data: Path, count: int, frames: int) -> List[MotionClip]:
    """Clips alternating between the skeletons of :data:`SOURCES`."""
    per = [_clips_from(data / name, (count + 1) // 2, frames) for name in SOURCES]
    mixed = [clip for pair in zip(*per) for clip in pair]
    return mixed[:count]


def time_collate(clips: List[MotionClip], repeat: int,
                 threads: int) -> List[float]:
    """Seconds per :func:`collate_clips` call with :obj:`threads` torch
    threads, after one warm-up call."""
    torch.set_num_threads(threads)
    collate_clips(clips)
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        collate_clips(clips)
        times.append(time.perf_counter() - start)
    return times


def time_rows(clips: List[MotionClip], repeat: int, thread_counts: List[int],
              allocator: str) -> List[dict]:
    """Median and best collate time for each torch thread count."""
    rows = []
    for threads in thread_counts:
        times = time_collate(clips, repeat, threads)
        rows.append({"allocator": allocator, "threads": threads,
                     "median_s": statistics.median(times), "best_s": min(times)})
    return rows


def main(argv: Optional[List[str]] = None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=data_folder,
                        default=str(SHARED_DATA))
    parser.add_argument("--clips", type=int, default=32)
    parser.add_argument("--frames", type=int, default=64)
    parser.add_argument("--repeat", type=int, default=50)
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results" / "collate",
                        help="results path without suffix (default "
                             "benchmarks/results/collate)")
    args = parser.parse_args(argv)
    clips = build_clips(Path(args.data), args.clips, args.frames)
    batch = collate_clips(clips)
    joints = sorted({c.num_joints for c in clips})
    lines = [
        f"{len(clips)} clips x {args.frames} frames, skeletons of "
        f"{' and '.join(map(str, joints))} joints (end sites included): "
        f"{batch.num_nodes:,} nodes, {batch.edge_index.shape[1]:,} edges, "
        f"{batch.num_graphs:,} frame graphs; {args.repeat} repeats, one process.",
        "", "| allocator | torch threads | median ms | best ms |", "|---|---:|---:|---:|",
    ]
    thread_counts = sorted({1, torch.get_num_threads()})
    # glibc defaults first: retain_freed_memory cannot be undone in-process.
    rows = time_rows(clips, args.repeat, thread_counts, "glibc default")
    if retain_freed_memory():
        rows += time_rows(clips, args.repeat, thread_counts, "retain_freed_memory")
    lines += [f"| {r['allocator']} | {r['threads']} | {r['median_s'] * 1e3:.2f} | "
              f"{r['best_s'] * 1e3:.2f} |" for r in rows]
    lines += ["", "retain_freed_memory (satagraph.memory, called by the satagraph "
              "command) keeps freed memory in the process, so large batches do not "
              "page-fault on every call."]
    table = "\n".join(lines)
    print(table)
    result = {"clips": len(clips), "frames": args.frames, "joints": joints,
              "nodes": batch.num_nodes, "rows": rows}
    write_results(args.out, "Collating mixed skeletons (benchmarks/collate.py)",
                  table + "\n", result)


if __name__ == "__main__":
    main()
