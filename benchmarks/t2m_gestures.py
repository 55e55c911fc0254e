"""Gestures asked of the generator (issue 19; ``experiments/T2M.md`` section 26).

Bandai's ``bow`` and ``bye`` prompts ("a person bows", "a person waves
goodbye with one hand") generated walks: the generator's captioned data
held no such motion. This benchmark asks for them, with a walk as the
control, on human rigs of one split, and reads what the generated motion
does with measures that need no model:

- **still**: share of motions whose root stays put (Froude speed below
  ``benchmarks/t2m.py``'s ``STILL_FROUDE``);
- **bend** (:func:`~satagraph.pipelines.quality.trunk_bend`): the largest
  angle (degrees) by which the line from the root to the head leans away
  from where it pointed at the first frame: a bow bends it, a wave does not;
- **raise** (:func:`~satagraph.pipelines.quality.joint_raise`): the largest
  height any joint gains over its first frame, in body heights: a raised
  hand gains half a height, a walk's feet a tenth;

and with ``benchmarks/t2m.py``'s action recogniser (trained on the same
training items as there; it knows Bandai's ``bow``, ``bye``, ``byebye`` and
``guide``): **recognised**, the share read as the action asked for (a wave
read as ``bye`` or ``byebye``).

Rigs: the Bandai ``bow`` and ``bye`` files of the manifest's split (``val``
for choosing, ``test`` to report), and the zoo's bipeds of two rig seeds (911
and 912 for ``val``, 913 and 914 for ``test``). The ``real`` row reads the
split's Bandai ``bow``, ``bye`` and ``walk`` files themselves.

    .venv/bin/python benchmarks/t2m_gestures.py [--ckpt builtin [--ckpt B.safetensors]] \\
        [--split val] [--seeds 3] [--json OUT.json]

Prints a markdown table.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np
import torch

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from t2m import (FPS, MANIFEST, STILL_FROUDE, bandai_parts, measure, real_items,  # noqa: E402
                 train_recogniser)
from satagraph.data.features import motion_to_features  # noqa: E402
from satagraph.datasets.sources import read_manifest  # noqa: E402
from satagraph.datasets.zoo import zoo_rigs  # noqa: E402
from satagraph.datasets.zoo.motions import generate_clip  # noqa: E402
from satagraph.io import read_bvh  # noqa: E402
from satagraph.motion import Motion  # noqa: E402
from satagraph.pipelines.generate import generate_on, load_generator  # noqa: E402
from satagraph.pipelines.quality import joint_raise, trunk_bend  # noqa: E402
from satagraph.transforms.canonical import canonicalize  # noqa: E402
from satagraph.utils.files import atomic_write_text  # noqa: E402

#: Prompts and the action each asks for.
PROMPTS: Tuple[Tuple[str, str], ...] = (
    ("a person bows", "bow"), ("a person waves goodbye with one hand", "bye"),
    ("a person walks forward", "walk"))
#: Labels the recogniser may give a motion of each asked action to count as it.
ACCEPTED = {"bow": ("bow",), "bye": ("bye", "byebye"), "walk": ("walk",)}
#: Zoo rig seeds per split (those of ``t2m_wording.py``).
ZOO_SEEDS = {"val": (911, 912), "test": (913, 914)}


def rigs(split: str) -> Tuple[List[Tuple[str, Motion]], List[Tuple[str, str, Motion]]]:
    """Targets ``(name, motion)`` and the real gestures ``(name, action,
    motion)`` of a split."""
    targets = [(f"zoo biped {seed}", generate_clip(zoo_rigs(["biped"], seed=seed)[0], "walk",
                                                   60, seed=1))
               for seed in ZOO_SEEDS[split]]
    if not MANIFEST.is_file():
        print(f"# {MANIFEST} not found: zoo rigs only", file=sys.stderr)
        return targets, []
    real = []
    for f in read_manifest(MANIFEST):
        if f.dataset != "bandai" or f.split != split:
            continue
        action = bandai_parts(f.path)[0]
        if action in ACCEPTED:
            motion = read_bvh(MANIFEST.parent / f.path)
            real.append((Path(f.path).stem, action, motion))
            if action != "walk":  # one rig serves: the gestures' files are the targets
                targets.append((f"bandai {Path(f.path).stem}", motion))
    return targets, real


def reading(motion: Motion, action: str, recogniser) -> Dict[str, object]:
    """What one motion does: still, bend, raise, recognised as asked."""
    canonical = canonicalize(motion, fps=FPS)
    it = measure(motion_to_features(canonical), [], action, "", "")
    bend, rise = trunk_bend(canonical), joint_raise(canonical)
    got = recogniser.predict([it.desc], [action])
    return {"still": bool(it.froude < STILL_FROUDE), "bend": bend, "raise": rise,
            "recognised": bool(got and got[0][1] in ACCEPTED[action]),
            "as": got[0][1] if got else None}


def summary(readings: Sequence[Dict[str, object]]) -> Dict[str, float]:
    """Shares of still and recognised motions, median bend and raise."""
    return {"n": len(readings),
            "still": float(np.mean([r["still"] for r in readings])),
            "bend": float(np.median([r["bend"] for r in readings])),
            "raise": float(np.median([r["raise"] for r in readings])),
            "recognised": float(np.mean([r["recognised"] for r in readings]))}


def generated(module, targets: Sequence[Tuple[str, Motion]], seeds: int,
              recogniser) -> Dict[str, List[Dict[str, object]]]:
    """Readings per asked action over every target and seed."""
    out: Dict[str, List[Dict[str, object]]] = {a: [] for _, a in PROMPTS}
    for _, target in targets:
        for prompt, action in PROMPTS:
            for seed in range(seeds):
                motion = generate_on(module, prompt, target, 4.0, seed)
                out[action].append(reading(motion, action, recogniser))
    return out


def table(rows: Dict[str, Dict[str, Dict[str, float]]]) -> str:
    actions = [a for _, a in PROMPTS]
    lines = ["| row | " + " | ".join(f"{a}: still, bend (deg), raise (H), recognised"
                                     for a in actions) + " |",
             "|---|" + "---|" * len(actions)]
    for name, per in rows.items():
        cells = []
        for a in actions:
            s = per.get(a)
            cells.append("" if s is None else
                         f"{s['still']:.0%}, {s['bend']:.0f}, {s['raise']:.2f}, "
                         f"{s['recognised']:.0%} (n={s['n']})")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv: Optional[Sequence[str]] = None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--ckpt", action="append", help="generator bundles (default: builtin)")
    parser.add_argument("--split", default="val", choices=("val", "test"))
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--steps", type=int, default=3000, help="recogniser training steps")
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--json", metavar="FILE")
    args = parser.parse_args(argv)
    torch.set_num_threads(args.threads)
    warnings.simplefilter("ignore")
    start = time.time()
    train, _ = real_items(False, 0, "test")
    recogniser = train_recogniser(train, args.steps, 0)
    targets, real = rigs(args.split)
    rows = {}
    if real:
        rows["real (Bandai clips)"] = {
            a: summary([reading(m, a, recogniser) for _, act, m in real if act == a])
            for a in ACCEPTED if any(act == a for _, act, _m in real)}
    for ckpt in args.ckpt or ["builtin"]:
        per = generated(load_generator(ckpt), targets, args.seeds, recogniser)
        rows[ckpt] = {a: summary(r) for a, r in per.items()}
    names = ", ".join(name for name, _ in targets)
    print(f"`benchmarks/t2m_gestures.py {' '.join(sys.argv[1:] if argv is None else argv)}` "
          f"({time.time() - start:.0f} s; rigs: {names}; {args.seeds} seeds each)\n")
    print(table(rows))
    if args.json:
        atomic_write_text(args.json, json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
