"""Kinematic probes of text-to-motion output on any skeleton (issue 19,
a first part of item 8): for each skeleton file and prompt, several seeds
of ``satagraph generate``'s motion are read back in the canonical frame
(+Y up, metres, facing +Z at frame 0) and measured:

- **turn**: degrees a second by which the body's facing turns from start to
  end (positive: to the left; :func:`~satagraph.pipelines.quality.turn_rate`),
  mean over seeds, and the share of seeds turning the prompt's way (left /
  right prompts);
- **speed**: mean ground speed of the root in m/s (still prompts should be
  slow, walks faster);
- **time**: median wall time of one generation (10 decoding steps,
  guidance on), seconds.

    .venv/bin/python benchmarks/t2m_probe.py --ckpt runs/t2m_tiny/checkpoints/last.ckpt \\
        --skeleton biped=A.bvh quadruped=B.bvh bird=C.bvh [--seconds 4] [--seeds 3]

Prints a markdown table. No evaluator is trained here: these probes read
the motion itself, on any skeleton.
"""
from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path
from typing import Dict, List, Tuple

import numpy as np
import torch

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from satagraph.transforms.canonical import canonicalize  # noqa: E402
from satagraph.data.features import motion_to_features  # noqa: E402
from satagraph.transforms.rig_reading import normalize_up_axis, parse_units, with_rig  # noqa: E402
from satagraph.pipelines.generate import generate_on, load_generator  # noqa: E402
from satagraph.pipelines.quality import turn_rate  # noqa: E402
from satagraph.io import read_bvh  # noqa: E402
from satagraph.motion import Motion  # noqa: E402

#: Subject of the prompts per body plan (the zoo captions' wording).
SUBJECTS = {"biped": "a person", "quadruped": "a quadruped", "bird": "a bird",
            "hexapod": "an insect", "human": "a person", "dog": "a four-legged animal"}
#: Prompts (``{}``: the subject) and the turn side they ask for.
PROMPTS: Tuple[Tuple[str, str], ...] = (
    ("{} walks forward and turns to the left", "left"),
    ("{} walks forward and turns to the right", "right"),
    ("{} walks forward", ""),
    ("{} stands still, swaying gently", ""),
)


def turn_and_speed(motion: Motion, fps: float = 30.0) -> Tuple[float, float]:
    """Turn rate (degrees a second, left positive; 0 for a body without
    left/right pairs) and mean root ground speed (m/s) of a motion, in the
    canonical frame."""
    canon = canonicalize(motion, fps=fps)
    feats = motion_to_features(canon)
    return turn_rate(canon) or 0.0, float(np.linalg.norm(feats.r[:, 1:3], axis=1).mean())


def probe(module, subject: str, target: Motion, seconds: float,
          seeds: int) -> List[Dict[str, float]]:
    """One row per prompt: mean turn, share turning the asked way, mean
    speed and median time over :obj:`seeds` seeds."""
    rows = []
    for prompt, side in PROMPTS:
        text = prompt.format(subject)
        yaws, speeds, times = [], [], []
        for seed in range(seeds):
            start = time.perf_counter()
            motion = generate_on(module, text, target, seconds, seed)
            times.append(time.perf_counter() - start)
            yaw, speed = turn_and_speed(motion, module.fps)
            yaws.append(yaw)
            speeds.append(speed)
        sign = {"left": 1.0, "right": -1.0}.get(side)
        right_way = float(np.mean([np.sign(y) == sign for y in yaws])) if sign else float("nan")
        rows.append({"text": text, "turn": float(np.mean(yaws)), "right_way": right_way,
                     "speed": float(np.mean(speeds)), "time": float(np.median(times))})
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--ckpt", required=True)
    parser.add_argument("--skeleton", nargs="+", required=True, metavar="PLAN=FILE")
    parser.add_argument("--seconds", type=float, default=4.0)
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--up-axis", default=None, help="up axis of every file (zoo: +Y)")
    parser.add_argument("--units", default=None, help="units of every file (e.g. cm)")
    args = parser.parse_args(argv)
    torch.set_num_threads(args.threads)
    warnings.simplefilter("ignore")
    module = load_generator(args.ckpt)
    print("| skeleton | prompt | turn (deg/s, mean) | seeds turning the asked way | "
          "speed (m/s) | time (s) |\n|---|---|---|---|---|---|")
    for item in args.skeleton:
        plan, _, path = item.partition("=")
        target = with_rig(read_bvh(path), args.up_axis and normalize_up_axis(args.up_axis),
                          args.units and parse_units(args.units))
        for row in probe(module, SUBJECTS.get(plan, "a character"), target, args.seconds,
                         args.seeds):
            way = "" if np.isnan(row["right_way"]) else f"{row['right_way']:.0%}"
            print(f"| {plan} | {row['text']} | {row['turn']:+.1f} | {way} | "
                  f"{row['speed']:.2f} | {row['time']:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
