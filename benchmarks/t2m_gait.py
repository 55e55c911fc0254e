"""Do generated walks have a gait? (issue 19; experiments/T2M.md sections 19-20)

For each body plan and validation-style rig seed, the zoo's real walk on
that rig is compared with "<subject> walks forward" generated on it (4 s,
several seeds), read back in the canonical frame:

- **Froude**: root ground speed over sqrt(g * leg length);
- **stride**: fore-aft swing of the limb ends in leg lengths
  (:func:`~satagraph.pipelines.quality.stride`);
- **cadence**: the limbs' dominant fore-aft frequency in Hz
  (:func:`~satagraph.pipelines.quality.cadence`);
- **heading gap**: degrees between the body's facing and its travel
  (:func:`~satagraph.pipelines.quality.heading_gap`): 0 for a walk, the
  crab angle of a walk read as a side-step.

``--spread`` adds a row per model and spread of the decoding
(:class:`~satagraph.pipelines.generate.GenerationSettings`).

With ``--infill`` the masked transformer is also given the real walk's own
layer-0 tokens, every k-th of them kept (k = 1, 2, 4, 8; "none": nothing
kept, plain generation), and fills in the rest (the residual layers by the
residual transformer, as in generation): the stride over the real walk's
and the cadence say how long a gap it fills by the gait's rhythm.

    .venv/bin/python benchmarks/t2m_gait.py --ckpt shipped=builtin cand=run.safetensors \\
        [--plans biped quadruped bird] [--rig-seeds 911 912] [--seeds 3] [--infill] \\
        [--spread 0 1] [--json OUT.json]

Prints markdown tables.
"""
from __future__ import annotations

import argparse
import json
import sys
import warnings
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np
import torch

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from satagraph.data.features import motion_to_features  # noqa: E402
from satagraph.datasets.zoo import zoo_rigs  # noqa: E402
from satagraph.datasets.zoo.motions import generate_clip  # noqa: E402
from satagraph.motion import Motion  # noqa: E402
from satagraph.pipelines.generate import (GenerationSettings, encode_windows,  # noqa: E402
                                          generate_on, load_generator, rig_inputs)
from satagraph.pipelines.inference import facing_smooth_of  # noqa: E402
from satagraph.pipelines.motion_descriptor import froude_speed  # noqa: E402
from satagraph.pipelines.quality import cadence, heading_gap, stride  # noqa: E402
from satagraph.transforms.canonical import canonicalize  # noqa: E402
from satagraph.utils.files import atomic_write_text  # noqa: E402

#: Subject of the walking prompt per body plan (the zoo captions' wording).
SUBJECTS = {"biped": "a person", "quadruped": "a four-legged animal", "bird": "a bird",
            "hexapod": "an insect"}
#: Tokens kept in the infill test: every k-th (``None``: none).
EVERY = (1, 2, 4, 8, None)


def gait(motion: Motion) -> List[float]:
    """Froude speed, stride, cadence and heading gap of a canonical motion."""
    gap = heading_gap(motion)
    return [froude_speed(motion_to_features(motion)), stride(motion) or 0.0,
            cadence(motion) or 0.0, float("nan") if gap is None else gap]


def real_walk(plan: str, rig_seed: int, frames: int = 120) -> Motion:
    """The zoo's walk on the first rig of :obj:`plan` drawn with :obj:`rig_seed`."""
    rig = zoo_rigs([plan], seed=rig_seed)[0]
    return canonicalize(generate_clip(rig, "walk", frames=frames, seed=1), fps=30.0)


@torch.no_grad()
def infill(module, text: str, real: Motion, every: Optional[int], seed: int,
           settings: GenerationSettings) -> Motion:
    """:obj:`real` re-generated with every :obj:`every`-th of its own
    layer-0 tokens kept (``None``: none kept)."""
    rig = rig_inputs(module, real)
    feats = motion_to_features(rig.shown, facing_smooth=facing_smooth_of(module))
    codes = encode_windows(module.autoencoder, feats, rig.semantic)
    tokens, _ = module.masked.to_tokens(codes[None], torch.tensor([codes.size(0)]))
    keep = torch.zeros_like(tokens, dtype=torch.bool)
    if every is not None:
        keep[:, ::every] = True
    out = generate_on(module, text, real, codes.size(0) / module.fps, seed, settings,
                      known=tokens, keep=keep)
    return canonicalize(out, fps=30.0)


def walk_rows(models: Dict[str, Tuple[object, GenerationSettings]],
              reals: Dict[str, List[Motion]], seeds: int) -> Dict[str, Dict[str, List[float]]]:
    """Mean Froude, stride, cadence and heading gap per row (real, then each
    model with its settings) and plan (the keys of :obj:`reals`, each plan's
    real walks)."""
    out: Dict[str, Dict[str, List[float]]] = {"real": {}}
    for plan, walks in reals.items():
        out["real"][plan] = np.nanmean([gait(r) for r in walks], 0).tolist()
        for name, (module, settings) in models.items():
            rows = [gait(canonicalize(generate_on(module, f"{SUBJECTS[plan]} walks forward", r,
                                                  4.0, seed, settings), fps=30.0))
                    for r in walks for seed in range(seeds)]
            out.setdefault(name, {})[plan] = np.nanmean(rows, 0).tolist()
    return out


def infill_rows(models: Dict[str, Tuple[object, GenerationSettings]], plans: Sequence[str],
                reals: Dict[str, List[Motion]], seeds: int) -> Dict[str, Dict[str, List[float]]]:
    """Per model and ``plan/every``: stride over the real walk's, cadence,
    the real walk's cadence."""
    out: Dict[str, Dict[str, List[float]]] = {}
    for name, (module, settings) in models.items():
        for plan in plans:
            for every in EVERY:
                rows = []
                for real in reals[plan]:
                    swing, rate = stride(real), cadence(real)
                    for seed in range(seeds):
                        got = infill(module, f"{SUBJECTS[plan]} walks forward", real, every,
                                     seed, settings)
                        rows.append([(stride(got) or 0.0) / swing, cadence(got) or 0.0, rate])
                out.setdefault(name, {})[f"{plan}/{every or 'none'}"] = np.mean(rows, 0).tolist()
    return out


def walk_table(rows: Dict[str, Dict[str, List[float]]], plans: Sequence[str]) -> str:
    head = " / ".join(plans)
    lines = [f"| row | Froude ({head}) | stride, leg lengths | cadence, Hz | heading gap, deg |",
             "|---|---|---|---|---|"]
    for name, per_plan in rows.items():
        cells = [" / ".join(f"{per_plan[p][k]:.2f}" for p in plans) for k in range(3)]
        cells.append(" / ".join(f"{per_plan[p][3]:+.1f}" for p in plans))
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def infill_table(rows: Dict[str, Dict[str, List[float]]], plans: Sequence[str]) -> str:
    kept = [f"every {k}" if k else "none" for k in EVERY]
    lines = ["| model, plan | " + " | ".join(f"{k}: stride ratio, Hz" for k in kept) +
             " | real Hz |", "|---|" + "---|" * (len(kept) + 1)]
    for name, cells in rows.items():
        for plan in plans:
            vals = [cells[f"{plan}/{k or 'none'}"] for k in EVERY]
            lines.append(f"| {name}, {plan} | " + " | ".join(f"{v[0]:.2f}, {v[1]:.2f}"
                                                             for v in vals) +
                         f" | {vals[0][2]:.2f} |")
    return "\n".join(lines)


def main(argv: Optional[Sequence[str]] = None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--ckpt", nargs="+", default=["shipped=builtin"],
                        help="NAME=CKPT (a checkpoint, a weights file or builtin)")
    parser.add_argument("--plans", nargs="+", default=["biped", "quadruped", "bird"],
                        choices=sorted(SUBJECTS))
    parser.add_argument("--rig-seeds", nargs="+", type=int, default=[911, 912])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--infill", action="store_true",
                        help="also the infill test (biped and quadruped)")
    parser.add_argument("--spread", nargs="+", type=float, default=[0.0],
                        help="decoding spreads to try (a row each; default 0)")
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--json", metavar="FILE")
    args = parser.parse_args(argv)
    torch.set_num_threads(args.threads)
    warnings.simplefilter("ignore")
    models = {}
    for spec in args.ckpt:
        name, _, path = spec.rpartition("=")
        module = load_generator(path).eval()
        for spread in args.spread:
            row = (name or path) if args.spread == [0.0] else f"{name or path}, spread {spread:g}"
            models[row] = (module, GenerationSettings(spread=spread))
    reals = {plan: [real_walk(plan, s) for s in args.rig_seeds] for plan in args.plans}
    result = {"walks": walk_rows(models, reals, args.seeds)}
    print(walk_table(result["walks"], args.plans))
    if args.infill:
        plans = [p for p in args.plans if p in ("biped", "quadruped")]
        result["infill"] = infill_rows(models, plans, reals, max(1, args.seeds - 1))
        print()
        print(infill_table(result["infill"], plans))
    if args.json:
        atomic_write_text(args.json, json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
