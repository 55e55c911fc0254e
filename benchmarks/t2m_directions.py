"""Which way a generated person walks, on real human rigs (issue 19;
``experiments/T2M.md`` sections 64-66).

``benchmarks/t2m.py`` probes direction on one rig per body plan. The zoo's
bipeds walk backward in their captions and the captioned real human data
(CMU, CC_Base) did not, so a sampling or a model can keep the zoo's
directions and lose them on real human rigs. This benchmark asks "a
person walks forward / backward / forward and to the left / right" for
4 s on each rig with several seeds, per sampling (:data:`SAMPLINGS`;
``default``: :class:`GenerationSettings`'s), and counts the generations
that travel the asked way (``t2m.py``'s direction probe).

Rigs: the manifest's human validation files of CMU and CC_Base by default
(``--split test`` for the test files, or ``--rigs`` paths).

    .venv/bin/python benchmarks/t2m_directions.py [--ckpt builtin] [--split val] \\
        [--seeds 6] [--sampling default logits candidates masked-candidates] \\
        [--smooth F] [--output-smooth F] [--root-smooth F] [--draw-guidance G] [--json OUT.json]

Prints a markdown table: one row per rig and sampling, ``k / n`` per
prompt.
"""
from __future__ import annotations

import argparse
import json
import sys
import warnings
from pathlib import Path
from typing import Dict, List, Optional, Sequence

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from t2m import DIRECTIONS, FPS, MANIFEST, PROBE_PROMPTS, direction_ok, measure  # noqa: E402
from satagraph.data.features import motion_to_features  # noqa: E402
from satagraph.datasets.sources import read_manifest  # noqa: E402
from satagraph.io import read_bvh  # noqa: E402
from satagraph.motion import Motion  # noqa: E402
from satagraph.pipelines.generate import (GenerationSettings, generate_on,  # noqa: E402
                                          load_generator)
from satagraph.transforms.canonical import canonicalize  # noqa: E402
from satagraph.utils.files import atomic_write_text  # noqa: E402

#: Sampling name -> :class:`GenerationSettings` overrides: ``logits``,
#: both transformers drawing from their guided logits (the default before
#: stop 57); ``candidates``, both among candidates; ``masked-candidates``,
#: the masked transformer among candidates and the residual one from its
#: guided logits (the default since, ``experiments/T2M.md`` section 66).
SAMPLINGS = {"default": {}, "logits": {"guide": "logits", "residual_guide": "logits"},
             "candidates": {"guide": "candidates", "residual_guide": "candidates"},
             "masked-candidates": {"guide": "candidates", "residual_guide": "logits"}}
PROMPTS = [(p.format("a person"), label) for p, label in PROBE_PROMPTS if label in DIRECTIONS]


def human_rigs(split: str) -> List[str]:
    """The manifest's CMU and CC_Base files of a split."""
    if not MANIFEST.is_file():
        return []
    return [str(f.path) for f in read_manifest(MANIFEST)
            if f.dataset in ("cmu", "ccbase") and f.split == split]


def walked(model, target: Motion, prompt: str, label: str, seeds: int,
           settings: GenerationSettings) -> int:
    """How many of :obj:`seeds` 4-s generations on :obj:`target`'s rig
    travel the asked way."""
    count = 0
    for seed in range(seeds):
        motion = generate_on(model, prompt, target, 4.0, seed, settings)
        item = measure(motion_to_features(canonicalize(motion, fps=FPS)), [], label, "", "")
        count += int(direction_ok(label, item.travel))
    return count


def table(model, rigs: Sequence[str], samplings: Sequence[str], seeds: int,
          overrides: Optional[Dict] = None) -> List[Dict]:
    """One row per rig and sampling (printed as it comes): the counts per
    direction prompt; :obj:`overrides` (:class:`GenerationSettings` fields)
    apply on top of every sampling."""
    rows = []
    for rig in rigs:
        target = read_bvh(rig)
        for name in samplings:
            settings = GenerationSettings(**{**SAMPLINGS[name], **(overrides or {})})
            counts = {label: walked(model, target, prompt, label, seeds, settings)
                      for prompt, label in PROMPTS}
            rows.append({"rig": Path(rig).stem, "sampling": name, "seeds": seeds, **counts})
            print(_row(rows[-1]), flush=True)
    return rows


def _row(row: Dict) -> str:
    cells = [f"{row[label]} / {row['seeds']}" for _, label in PROMPTS]
    return "| " + " | ".join([row["rig"], row["sampling"], *cells]) + " |"


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--ckpt", default="builtin", help="a generator (default: built-in)")
    parser.add_argument("--split", choices=("val", "test"), default="val")
    parser.add_argument("--rigs", nargs="*", default=None, help="BVH files (default: the split's)")
    parser.add_argument("--seeds", type=int, default=6)
    parser.add_argument("--sampling", nargs="+", choices=sorted(SAMPLINGS),
                        default=["default"])
    parser.add_argument("--smooth", type=float, default=None,
                        help="latent smoothing in frames, every sampling (default: generate's)")
    parser.add_argument("--output-smooth", type=float, default=None,
                        help="smoothing of the decoded motion in frames, every sampling")
    parser.add_argument("--root-smooth", type=float, default=None,
                        help="smoothing of the decoded root features in frames, every sampling")
    parser.add_argument("--draw-guidance", type=float, default=None,
                        help="GenerationSettings.draw_guidance, every sampling")
    parser.add_argument("--residual-guidance", type=float, default=None,
                        help="GenerationSettings.residual_guidance, every sampling")
    parser.add_argument("--json", default=None, help="also write the rows as JSON")
    args = parser.parse_args(argv)
    overrides = {k: getattr(args, k) for k in ("smooth", "output_smooth", "root_smooth",
                                               "draw_guidance", "residual_guidance")
                 if getattr(args, k) is not None}
    warnings.simplefilter("ignore")
    rigs = args.rigs or human_rigs(args.split)
    if not rigs:
        raise SystemExit(f"no human rigs: {MANIFEST} not found (give --rigs)")
    print(f"generator {args.ckpt}; {args.seeds} seeds a prompt, 4 s")
    print("| rig | sampling | " + " | ".join(label for _, label in PROMPTS) + " |")
    print("|---|---|" + "---:|" * len(PROMPTS))
    rows = table(load_generator(args.ckpt), rigs, args.sampling, args.seeds, overrides)
    if args.json:
        atomic_write_text(args.json, json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
