"""Prompts in a user's words (issue 19; ``experiments/T2M.md`` section 24).

A generator knows the words of its training captions only. This benchmark
asks for motion with subjects named as a user would ("a dog", "a woman",
"a chicken", ...) and measures, per rig, what the generated motion does
with the prompt as written (``literal``) and as
:func:`~satagraph.pipelines.prompt_reading.read_prompt` reads it in the
model's words (``read``), beside the model's own subject (``own``):

- **direction**: share of forward / backward / forward-left / forward-right
  prompts travelling that way (``benchmarks/t2m.py``'s probe);
- **pace**: share of nouns whose walk < run < dash by Froude speed.

Rigs: the zoo's biped, quadruped, bird and hexapod of two rig seeds (911
and 912 for ``--split val``, 913 and 914 for ``test``), and the first
Bandai and dog files of the manifest's split (``val`` for choosing,
``test`` to report; the dog in centimetres).

    .venv/bin/python benchmarks/t2m_wording.py [--ckpt builtin] [--split val] [--seeds 2] \\
        [--json OUT.json]

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

from t2m import FPS, MANIFEST, measure, probes  # noqa: E402
from satagraph.data.features import motion_to_features  # noqa: E402
from satagraph.datasets.sources import read_manifest  # noqa: E402
from satagraph.datasets.zoo import zoo_rigs  # noqa: E402
from satagraph.datasets.zoo.motions import generate_clip  # noqa: E402
from satagraph.datasets.zoo_captions import ZOO_SUBJECTS  # noqa: E402
from satagraph.io import read_bvh  # noqa: E402
from satagraph.motion import Motion  # noqa: E402
from satagraph.pipelines.generate import generate_on, load_generator  # noqa: E402
from satagraph.pipelines.prompt_reading import article, read_prompt, vocabulary_of  # noqa: E402
from satagraph.transforms.canonical import canonicalize  # noqa: E402
from satagraph.transforms.rig_reading import with_rig  # noqa: E402
from satagraph.utils.files import atomic_write_text  # noqa: E402

#: A user's nouns per body plan.
NOUNS = {"biped": ("man", "woman", "child"), "quadruped": ("dog", "horse", "cat"),
         "bird": ("chicken", "duck", "ostrich"), "hexapod": ("ant", "beetle", "cockroach")}
#: Probe prompts (``{}``: the subject) and the action each asks for.
PROMPTS: Tuple[Tuple[str, str], ...] = (
    ("{} walks forward", "walk"), ("{} walks backward", "walk-back"),
    ("{} walks forward and to the left", "walk-left"),
    ("{} walks forward and to the right", "walk-right"), ("{} runs forward", "run"),
    ("{} dashes forward", "dash"))
#: Zoo rig seeds per split (validation: those of ``t2m_gait.py``).
ZOO_SEEDS = {"val": (911, 912), "test": (913, 914)}


def rigs(split: str) -> List[Tuple[str, str, Motion]]:
    """``(name, plan, motion)`` of every rig measured."""
    out = []
    for plan in NOUNS:
        for seed in ZOO_SEEDS[split]:
            rig = zoo_rigs([plan], seed=seed)[0]
            out.append((f"zoo {plan} {seed}", plan, generate_clip(rig, "walk", 60, seed=1)))
    if not MANIFEST.is_file():
        print(f"# {MANIFEST} not found: zoo rigs only", file=sys.stderr)
        return out
    files = read_manifest(MANIFEST)
    for dataset, plan in (("bandai", "biped"), ("dog", "quadruped")):
        pick = next((f for f in files if f.dataset == dataset and f.split == split), None)
        if pick is None:
            print(f"# no {dataset} file in the {split} split: left out", file=sys.stderr)
            continue
        motion = read_bvh(MANIFEST.parent / pick.path)
        if dataset == "dog":  # its files do not say their units
            motion = with_rig(motion, scale="cm")
        out.append((f"{dataset} {Path(pick.path).stem}", plan, motion))
    return out


def an(noun: str) -> str:
    """The noun with its indefinite article."""
    return f"{article(noun)} {noun}"


def probe(module, target: Motion, subject: str, seeds: int) -> Dict[str, object]:
    """The probes of every prompt about :obj:`subject` on :obj:`target`."""
    labels, travels, froudes = [], [], []
    for prompt, label in PROMPTS:
        for seed in range(seeds):
            motion = generate_on(module, prompt.format(subject), target, 4.0, seed)
            it = measure(motion_to_features(canonicalize(motion, fps=FPS)), [], label, "", "")
            labels.append(label), travels.append(it.travel), froudes.append(it.froude)
    return probes(labels, travels, froudes)


def measure_rig(module, plan: str, target: Motion, seeds: int) -> Dict[str, Dict[str, float]]:
    """Per way of wording (own, literal, read): direction hits and count,
    and nouns with the pace ordered and count."""
    words = vocabulary_of(module)
    ways = {"own": [ZOO_SUBJECTS[plan][0]], "literal": [an(n) for n in NOUNS[plan]],
            "read": [read_prompt(an(n), words).text for n in NOUNS[plan]]}
    out = {}
    for way, subjects in ways.items():
        hits = count = ordered = 0
        for subject in subjects:
            p = probe(module, target, subject, seeds)
            share, n = p["direction"]
            hits, count = hits + share * n, count + n
            ordered += int(bool(p.get("ordering")))
        out[way] = {"direction": hits, "n": count, "ordered": ordered, "nouns": len(subjects),
                    "subjects": subjects}
    return out


def table(rows: Dict[str, Dict[str, Dict[str, float]]]) -> str:
    ways = ("own", "literal", "read")
    lines = ["| rig | " + " | ".join(f"{w}: direction, pace ordered" for w in ways) + " |",
             "|---|" + "---|" * len(ways)]
    pooled = {w: np.zeros(4) for w in ways}
    for name, per in rows.items():
        cells = []
        for w in ways:
            r = per[w]
            cells.append(f"{r['direction'] / r['n']:.0%} ({r['n']}), {r['ordered']} of {r['nouns']}")
            pooled[w] += [r["direction"], r["n"], r["ordered"], r["nouns"]]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    lines.append("| **pooled** | " + " | ".join(
        f"**{p[0] / p[1]:.0%}** ({p[1]:.0f}), {p[2]:.0f} of {p[3]:.0f}"
        for p in pooled.values()) + " |")
    return "\n".join(lines)


def main(argv: Optional[Sequence[str]] = None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--ckpt", default="builtin")
    parser.add_argument("--split", default="val", choices=("val", "test"))
    parser.add_argument("--seeds", type=int, default=2)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--json", metavar="FILE")
    args = parser.parse_args(argv)
    torch.set_num_threads(args.threads)
    warnings.simplefilter("ignore")
    module = load_generator(args.ckpt)
    if vocabulary_of(module) is None:
        raise SystemExit(f"{args.ckpt}: keeps no record of its caption words: nothing to read")
    start = time.time()
    rows = {name: measure_rig(module, plan, target, args.seeds)
            for name, plan, target in rigs(args.split)}
    print(f"`benchmarks/t2m_wording.py --ckpt {args.ckpt} --split {args.split} "
          f"--seeds {args.seeds}` ({time.time() - start:.0f} s)\n")
    print(table(rows))
    if args.json:
        atomic_write_text(args.json, json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
