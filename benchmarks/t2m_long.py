"""Clips longer than the generator was trained on (issue 19, ``--seconds``).

The built-in generator's transformers learnt windows of 4 s
(``meta["window"]``). ``satagraph generate --seconds 12`` either generates
the whole clip at once (``--window 0``: past 4 s its positions were never
learnt) or window after window, each continuing the half window before it
(the default). Which one keeps what the text asks for, to the clip's end?

For each steady prompt of the zoo's prompts (walks and runs in every
direction, dashes, trots, standing idle; the prompts of ``benchmarks/t2m.py``,
on their own rigs) this generates a clip of the prompt's own length (as
``t2m.py`` does) and a clip of ``--seconds`` both ways, and scores the
first and the last stretch of the prompt's length of each long clip with
``t2m.py``'s evaluator (trained the same way, on the training split only):
R@3 in pools of 32 and FID with 95 % half-widths, the action recogniser's
accuracy, the direction of travel of the walks, and the pace: the median
over moving prompts of each stretch's Froude speed over the speed of the
prompt's own-length clip.

Usage: ``python benchmarks/t2m_long.py [--prompts val] [--seed N]
[--seconds 12] [--ckpt builtin] [--quick]``. Writes
``benchmarks/results/t2m_long.md`` and ``.json`` (``--quick``:
``t2m_long_quick.*``; ``--out`` another stem).
"""
from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from dataclasses import replace
from pathlib import Path
from typing import Callable, Dict, List, Sequence

import numpy as np
import torch

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))
import t2m  # noqa: E402
from satagraph.data.dataset import _frames  # noqa: E402
from satagraph.data.features import motion_to_features  # noqa: E402
from satagraph.pipelines.generate import (GenerationSettings, generate_on,  # noqa: E402
                                          load_generator)
from satagraph.transforms.rig_reading import RigReadingWarning  # noqa: E402
from satagraph.transforms.canonical import canonicalize  # noqa: E402
from satagraph.utils.files import atomic_write_text  # noqa: E402

#: Prompts whose motion is the same all along (a long clip should be more of it).
STEADY = ("walk", "run", "dash", "trot", "walk-back", "walk-left", "walk-right", "idle")
RESULTS = ROOT / "benchmarks" / "results"


def stretches(module, item: t2m.Item, seconds: float, seed: int,
              settings: GenerationSettings) -> Dict[str, t2m.Item]:
    """The first and last stretch of :obj:`item`'s length of a clip of
    :obj:`seconds` generated for its caption on its rig."""
    motion = generate_on(module, item.captions[0], item.motion, seconds, seed, settings)
    feats = motion_to_features(canonicalize(motion, fps=t2m.FPS, up_axis="+Y", unit_scale=1.0))
    size = int(round(item.seconds * t2m.FPS))
    out = {}
    for name, part in (("first", slice(0, size)),
                       ("last", slice(feats.num_frames - size, feats.num_frames))):
        out[name] = t2m.measure(_frames(feats, part), item.captions, item.label, item.group,
                                item.skeleton)
    return out


def pace_ratio(items: Sequence[t2m.Item], own: Sequence[t2m.Item]) -> float:
    """Median Froude speed of each moving prompt's motion over that of its
    own-length generation."""
    ratios = [a.froude / b.froude for a, b in zip(items, own)
              if a.label != "idle" and b.froude > 1e-6]
    return float(np.median(ratios))


def row(name: str, items: List[t2m.Item], test: List[t2m.Item], own: List[t2m.Item],
        model, recogniser, encode: Callable, reference: np.ndarray, reps: int) -> Dict:
    """One table row: evaluator metrics, action accuracy, direction, pace."""
    caps = [it.captions[0] for it in test]
    out = t2m.score(model, encode, caps, [it.desc for it in items],
                    None if name == "real" else reference, reps)
    labels = [it.label for it in test]
    out["action"] = recogniser.accuracy_interval([it.desc for it in items], labels)
    found = t2m.probes(labels, [it.travel for it in items], [it.froude for it in items])
    out["direction"] = found.get("direction")
    out["pace"] = pace_ratio(items, own)
    out["row"] = name
    return out


def evaluate(args: argparse.Namespace) -> Dict:
    start = time.perf_counter()
    encode = t2m.cached_encoder()
    train, test = t2m.real_items(args.quick, args.seed, args.prompts)
    test = [it for it in test if it.group == "zoo" and it.label in STEADY]
    steps = 150 if args.quick else 3000
    model = t2m.train_evaluator(train, encode, steps, args.seed)
    recogniser = t2m.train_recogniser(train, steps, args.seed)
    module = load_generator(args.ckpt)
    settings = t2m.scored(GenerationSettings())  # scored against the test clips: not carried
    own = t2m.generated_items(module, test, 1, settings)[0]
    ways = {"whole clip (--window 0)": replace(settings, window=0.0),
            "in windows (default)": settings}
    sets: Dict[str, List[t2m.Item]] = {"real": test, "own length": own}
    for way, chosen in ways.items():
        parts = [stretches(module, it, args.seconds, 0, chosen) for it in test]
        for name in ("first", "last"):
            sets[f"{args.seconds:g} s {way}: {name} stretch"] = [p[name] for p in parts]
    _, reference = t2m.embed(model, encode, [it.captions[0] for it in test],
                             [it.desc for it in test])
    reps = 3 if args.quick else 20
    rows = [row(name, items, test, own, model, recogniser, encode, reference, reps)
            for name, items in sets.items()]
    window = (module.meta or {}).get("window")
    return {"rows": rows, "facts": {
        "prompts": args.prompts, "seed": args.seed, "seconds": args.seconds,
        "ckpt": args.ckpt, "quick": args.quick, "items": len(test),
        "labels": {l: sum(it.label == l for it in test) for l in STEADY},
        "stretch_seconds": [min(it.seconds for it in test), max(it.seconds for it in test)],
        "trained_window_frames": window, "evaluator_steps": steps,
        "seconds_total": round(time.perf_counter() - start, 1)}}


def cell(value, digits: int = 3) -> str:
    """:func:`t2m.fmt`, with a dash where there is no value."""
    return t2m.fmt(value, digits) or "-"


def table(result: Dict) -> str:
    facts = result["facts"]
    stretch = facts["stretch_seconds"]
    lines = [f"# Clips longer than the trained window ({facts['seconds']:g} s; "
             f"{facts['prompts']} prompts, seed {facts['seed']})", "",
             f"{facts['items']} steady zoo prompts ({', '.join(f'{k} {v}' for k, v in facts['labels'].items() if v)}), "
             f"each on its own rig; the generator `{facts['ckpt']}` learnt windows of "
             f"{facts['trained_window_frames']} frames. Stretches are the prompt's own length "
             f"({stretch[0]:.1f}-{stretch[1]:.1f} s). Pace: median Froude speed over the "
             "own-length clip's (moving prompts).",
             "", "| motions | R@3 | FID | action | direction | pace |", "|---|---|---|---|---|---|"]
    for r in result["rows"]:
        direction = r["direction"]
        lines.append(f"| {r['row']} | {cell(r.get('R@3'))} | {cell(r['fid'])} | "
                     f"{cell(r['action'], 2)} | "
                     f"{'-' if direction is None else f'{100 * direction[0]:.0f} % of {direction[1]}'}"
                     f" | {r['pace']:.2f} |")
    lines += ["", f"{facts['seconds_total']:.0f} s in all."]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--prompts", choices=("test", "val"), default="test")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--seconds", type=float, default=12.0)
    p.add_argument("--ckpt", default="builtin")
    p.add_argument("--quick", action="store_true")
    p.add_argument("--out", default=None, help="results stem (default t2m_long[_quick])")
    args = p.parse_args(argv)
    warnings.filterwarnings("ignore", category=RigReadingWarning)  # zoo rigs: metres, +Y
    torch.manual_seed(0)
    result = evaluate(args)
    stem = args.out or ("t2m_long_quick" if args.quick else "t2m_long")
    RESULTS.mkdir(parents=True, exist_ok=True)
    text = table(result)
    atomic_write_text(RESULTS / f"{stem}.md", text)
    atomic_write_text(RESULTS / f"{stem}.json", json.dumps(result, indent=1, default=str))
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
