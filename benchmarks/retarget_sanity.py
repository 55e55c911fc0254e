"""Does a dog -> human retarget move the human's limbs in step with the dog's?

For each limb (left/right, front/hind) the terminal joint is found on both
skeletons through the semantic descriptions ("left hind limb terminal
segment", ...), and the Pearson correlation of its forward velocity in the
character's facing frame (relative to the root) is computed between the
source clip and the retargeted clip, frame by frame at the model's rate. In
step means clearly positive correlations; the same model with its weights
re-initialised gives the chance level in the same run.

    .venv/bin/python benchmarks/retarget_sanity.py --ckpt RUN/checkpoints/last.ckpt \
        [--source DOG.bvh] [--target HUMAN.bvh] [--frames 300]

Prints a markdown table and writes it to benchmarks/results/retarget_sanity.md.
"""
from __future__ import annotations

import argparse
import copy
import sys
from pathlib import Path
from typing import Dict, List, Optional, Sequence

import numpy as np
import torch

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from satagraph.data.canonical import canonicalize  # noqa: E402
from satagraph.data.datamodule import semantic_embedder  # noqa: E402
from satagraph.data.features import motion_to_features  # noqa: E402
from satagraph.data.semantics import describe_joints  # noqa: E402
from satagraph.inference import retarget_motion  # noqa: E402
from satagraph.io import read_bvh  # noqa: E402
from satagraph.train import load_module  # noqa: E402

DATA = ROOT.parent / "shared" / "data"
LIMBS = ["left front", "right front", "left hind", "right hind"]
RESULTS = ROOT / "benchmarks" / "results" / "retarget_sanity.md"


def limb_ends(skeleton) -> Dict[str, int]:
    """Terminal joint of each limb, by description."""
    found: Dict[str, int] = {}
    for j, text in enumerate(describe_joints(skeleton)):
        for limb in LIMBS:
            if text.startswith(f"{limb} limb terminal segment") and limb not in found:
                found[limb] = j
    return found


def forward_track(motion, fps: float) -> np.ndarray:
    """Forward coordinate of every joint relative to the root, facing frame,
    :math:`(T, J)`."""
    feats = motion_to_features(canonicalize(motion, fps=fps))
    return feats.x_rel[..., 2]


def correlations(source, output, fps: float) -> Dict[str, float]:
    src_ends, out_ends = limb_ends(source.skeleton), limb_ends(output.skeleton)
    a, b = forward_track(source, fps), forward_track(output, fps)
    frames = min(len(a), len(b))
    out = {}
    for limb in LIMBS:
        if limb in src_ends and limb in out_ends:
            x = np.diff(a[:frames, src_ends[limb]])  # velocities: less
            y = np.diff(b[:frames, out_ends[limb]])  # autocorrelation than positions
            out[limb] = float(np.corrcoef(x, y)[0, 1])
    return out


def reinitialised(module):
    control = copy.deepcopy(module)
    torch.manual_seed(0)
    for layer in control.modules():
        if layer is not control and hasattr(layer, "reset_parameters"):
            layer.reset_parameters()
    return control


def run(ckpt: str, sources: Sequence[Path], target: Path, frames: int) -> str:
    module = load_module(ckpt).eval()
    embed = semantic_embedder(module.meta.get("semantic_encoder", "offline"))
    fps = float(getattr(module, "fps", 30.0))
    tgt = read_bvh(target)
    rows: List[str] = []
    for name, model in (("trained", module), ("re-initialised (chance)", reinitialised(module))):
        for path in sources:
            src = read_bvh(path).slice(0, frames)
            out = retarget_motion(model, src, tgt, embed)
            corr = correlations(src, out, fps)
            cells = " | ".join(f"{corr.get(limb, float('nan')):+.2f}" for limb in LIMBS)
            mean = np.nanmean(list(corr.values()))
            rows.append(f"| {name} | {path.name} | {cells} | {mean:+.2f} |")
    head = ("| model | dog clip | " + " | ".join(LIMBS) + " | mean |\n|---|---|"
            + "---|" * (len(LIMBS) + 1))
    return (f"Dog -> human ({target.name}) retargeting, checkpoint `{ckpt}`; Pearson "
            f"correlation of each limb end's forward velocity (facing frame, relative "
            f"to the root), first {frames} frames of each clip.\n\n"
            + head + "\n" + "\n".join(rows) + "\n")


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--ckpt", required=True)
    parser.add_argument("--source", nargs="*", type=Path, default=None,
                        help="dog clips (default: the dog test split's first three)")
    parser.add_argument("--target", type=Path, default=DATA / "cmu" / "01_01.bvh")
    parser.add_argument("--frames", type=int, default=300)
    parser.add_argument("--out", type=Path, default=RESULTS)
    args = parser.parse_args(argv)
    sources = args.source or _default_sources()
    table = run(args.ckpt, sources, args.target, args.frames)
    print(table)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text("# Retarget sanity check\n\n" + table)
    return 0


def _default_sources() -> List[Path]:
    rows = [line.split("\t") for line in (DATA / "manifest.tsv").read_text().splitlines()[1:]]
    return [DATA / r[0] for r in rows if r[1] == "dog" and r[4] == "test"][:3]


if __name__ == "__main__":
    raise SystemExit(main())
