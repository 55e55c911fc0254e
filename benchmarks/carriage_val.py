"""Retargets carried as their characters, on validation material
(``experiments/PRETRAIN.md`` section 55).

Every pair is retargeted by the built-in model twice, ``carriage="never"``
(the decoder's carriage) and ``"auto"`` (the default: carried as the target
character carries itself in the target file's standing frames wherever the
retarget never puts down a limb the character stands on there), and read
without a ground truth by :mod:`satagraph.pipelines.quality` against the
target's own clip. Pairs:

- **zoo**: validation-seed clips of the endless zoo (walks, trots, runs,
  turns and speed changes) between bipeds, quadrupeds, birds and fowl, the
  first :obj:`--per-pair` of each way, each onto the next target clip of
  its plan;
- **real**: Bandai's validation clips (every kind: walks, runs, bows,
  dances...; their most active 128 frames) onto the dog's clips outside
  its test split that stand on their paws (``down`` can be read against
  them), and the dog's standing clips onto a Bandai validation walk.

Per group: how many pairs the gate carried, the median ``lands`` (1: each
limb the character stands on comes down as often as in its clip; 0: one
never does), the mean limb in-step correlation, the share of travel ratios
in 0.8-1.25, the median ``posture`` (which the carriage reads from the same
clip it copies, so it rises by construction) and the median foot slide
(heights a second; a paw that now comes near the floor counts in it).

    .venv/bin/python benchmarks/carriage_val.py [--per-pair 8] [--out PATH]

Writes ``benchmarks/results/carriage_val.md`` (and ``.json``). Without the
real files the real groups are left out.
"""
from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from pretrained_val import (RECON_FRAMES, manifest_paths, real_file,  # noqa: E402
                            zoo_sample)
from results_io import SHARED_DATA, write_results  # noqa: E402
from satagraph.experiment.train import load_module  # noqa: E402
from satagraph.motion import Motion  # noqa: E402
from satagraph.pipelines.inference import retarget_canonical  # noqa: E402
from satagraph.pipelines.quality import (most_active, retarget_quality,  # noqa: E402
                                         standing_shares, stood_on)
from satagraph.transforms.canonical import canonicalize  # noqa: E402

OUT = Path(__file__).resolve().parent / "results" / "carriage_val"
#: Source plan -> target plans of the zoo groups.
WAYS = (("biped", "quadruped"), ("quadruped", "biped"), ("biped", "bird"), ("biped", "fowl"),
        ("quadruped", "bird"))
KINDS = ("walk", "trot", "run", "turn", "speed")
KEYS = ("steps", "travel", "posture", "lands", "slide")
Pair = Tuple[str, Motion, Motion]


def zoo_pairs(per_pair: int) -> List[Pair]:
    """``(group, source, target)``: per way of :data:`WAYS`, the first
    :obj:`per_pair` validation clips of the source plan, each onto the
    next unused clip of the target plan."""
    clips: Dict[str, List[Motion]] = {}
    for index in range(40 * per_pair):
        sample = zoo_sample(index)
        if sample.kind in KINDS:
            clips.setdefault(sample.species, []).append(sample.motion)
    out = []
    for a, b in WAYS:
        for k in range(per_pair):
            out.append((f"zoo {a} -> {b}", clips[a][k], clips[b][(k + 1) % len(clips[b])]))
    return out


def standing_dogs() -> List[Motion]:
    """The dog's clips outside its test split that ``lands`` can be read
    against: some paw down in half their standing frames or more, from the
    floor they stand on (:func:`~satagraph.pipelines.quality.lands`)."""
    out = []
    for rel in manifest_paths("dog", lambda split: split != "test"):
        own = canonicalize(real_file(rel), fps=30.0)
        if stood_on(standing_shares(own, own_floor=True)):
            out.append(real_file(rel))
    return out


def real_pairs() -> List[Pair]:
    """Bandai's validation clips (every other, most active frames) onto
    each standing dog clip in turn, and each standing dog clip onto a
    Bandai validation walk."""
    bandai = manifest_paths("bandai", lambda split: split == "val")
    dogs = standing_dogs()
    walk = real_file(next(p for p in bandai if "_walk_" in p))
    out = [("Bandai -> dog", most_active(real_file(rel), RECON_FRAMES), dogs[i % len(dogs)])
           for i, rel in enumerate(bandai[::2])]
    out += [("dog -> Bandai", most_active(dog, RECON_FRAMES), walk) for dog in dogs]
    return out


def measure(module, pairs: Sequence[Pair]) -> Dict[str, Dict[str, List[dict]]]:
    """Per group and carriage mode, each pair's quality (and whether the
    gate carried it: ``carried``)."""
    got: Dict[str, Dict[str, List[dict]]] = {}
    for group, source, target in pairs:
        own = canonicalize(target, fps=float(module.fps))
        outs = {}
        for mode in ("never", "auto"):
            src, outs[mode] = retarget_canonical(module, source, target, module.embed,
                                                 carriage=mode)
            q = retarget_quality(src, outs[mode], KEYS, target=own)
            q["carried"] = mode == "auto" and not np.array_equal(outs["auto"].rotations,
                                                                 outs["never"].rotations)
            got.setdefault(group, {}).setdefault(mode, []).append(q)
    return got


def _median(values: Sequence[Optional[float]]) -> str:
    kept = [v for v in values if v is not None]
    return f"{np.median(kept):.2f}" if kept else "-"


def _mean(values: Sequence[float]) -> str:
    return f"{np.mean(values):+.2f}"


def _band(values: Sequence[float]) -> str:
    """The share of travel ratios within 0.8-1.25."""
    return f"{np.mean([0.8 <= v <= 1.25 for v in values]):.0%}"


def table(got: Dict[str, Dict[str, List[dict]]], seconds: float) -> str:
    lines = [f"Built-in model (`auto`), `carriage` never -> auto; {seconds:.0f} s.", "",
             "| group | pairs | carried | lands (median) | steps (mean) | travel in 0.8-1.25 "
             "| posture (median) | slide, H/s (median) |",
             "|---|---:|---:|---|---|---|---|---|"]
    for group, modes in got.items():
        never, auto = modes["never"], modes["auto"]

        def pair(key: str, how) -> str:
            return f"{how([q[key] for q in never])} -> {how([q[key] for q in auto])}"

        lines.append(f"| {group} | {len(never)} | {sum(q['carried'] for q in auto)} "
                     f"| {pair('lands', _median)} | {pair('steps', _mean)} "
                     f"| {pair('travel', _band)} | {pair('posture', _median)} "
                     f"| {pair('slide', _median)} |")
    return "\n".join(lines) + "\n"


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--per-pair", type=int, default=8,
                        help="zoo pairs per way of retargeting (default 8)")
    parser.add_argument("--out", type=Path, default=OUT, help="results path without suffix")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    pairs = zoo_pairs(args.per_pair)
    if (SHARED_DATA / "manifest.tsv").is_file():
        pairs += real_pairs()
    else:
        print("carriage_val.py: no ../shared/data: the real groups are left out",
              file=sys.stderr)
    module = load_module("builtin").eval()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        got = measure(module, pairs)
    text = table(got, time.perf_counter() - start)
    print(text)
    write_results(args.out, "Retargets carried as their characters, validation material "
                  "(benchmarks/carriage_val.py)", text, {"per_pair": args.per_pair, **got})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
