"""Does a dog -> human retarget move the human's limbs in step with the dog's?

For each limb (left/right, front/hind) the terminal joint is found on both
skeletons through the semantic descriptions ("left hind limb terminal
segment", ...), and the Pearson correlation of its forward displacement
over 0.1 s in the character's facing frame (relative to the root's ground
projection) is computed between the source clip and the retargeted clip at
the model's rate. In step means clearly positive correlations. The
correlation of the forward positions themselves is shown too: it follows
slow posture changes (sitting, lying down), not steps.

Which way is forward. The facing frame follows a root-local axis; the
features take the one that faces +Z at a clip's first frame (from its
left/right joints), so one unusual first pose (a dog turning its head, a
retargeted human with crossed arms) turns a whole clip's frame. Here the
axis is the mean over all frames of the left/right facing direction in the
root's frame, for the source and the retargeted clip alike; the last column
shows the first-frame axis for comparison.

Three references come from the same run: the same model with its weights
re-initialised (chance level), the trained retargets scored against another
source clip (the next one; what a generic gait would reach, so that a high
score means this clip's own steps), and reconstruction on the source's own
rig (what this model reaches when source and target are the same skeleton).
The summary also averages the retargets over the clips whose reconstruction
is in step: where the model cannot follow a dog's limbs on the dog itself,
no retarget can.
``--source`` also takes human clips: human -> human across skeletons is the
within-species reference. Each source clip is cut
to its most active window (largest limb-end speed), since the dog test clips
open with seconds of standing.

    .venv/bin/python benchmarks/retarget_sanity.py --ckpt RUN/checkpoints/last.ckpt \
        [--source DOG.bvh ...] [--target HUMAN.bvh ...] [--frames 600]

Prints a markdown table and writes it to benchmarks/results/retarget_sanity.md.
"""
from __future__ import annotations

import argparse
import copy
import sys
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np
import torch

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from satagraph.transforms.canonical import canonicalize  # noqa: E402
from satagraph.semantics import LIMBS  # noqa: E402
from satagraph.pipelines.inference import retarget_motion  # noqa: E402
from satagraph.io import read_bvh  # noqa: E402
from satagraph.pipelines.quality import LAG, correlate, limb_tracks, most_active  # noqa: E402
from satagraph.experiment.train import load_module  # noqa: E402
from satagraph.utils.files import atomic_write_text  # noqa: E402
from results_io import SHARED_DATA  # noqa: E402

DATA = SHARED_DATA
RESULTS = ROOT / "benchmarks" / "results" / "retarget_sanity.md"


def both_limb_tracks(motion, fps: float) -> Tuple[Dict[str, np.ndarray], Dict[str, np.ndarray]]:
    """Limb tracks (:func:`satagraph.pipelines.quality.limb_tracks`) with the
    clip-averaged and with the first-frame facing axis, canonicalising the
    motion once."""
    canonical = canonicalize(motion, fps=fps)
    return limb_tracks(canonical, True), limb_tracks(canonical, False)


def reinitialised(module):
    control = copy.deepcopy(module)
    torch.manual_seed(0)
    for layer in control.modules():
        if layer is not control and hasattr(layer, "reset_parameters"):
            layer.reset_parameters()
    return control


def run(ckpt: str, sources: Sequence[Path], targets: Sequence[Path],
        frames: int) -> str:
    module = load_module(ckpt).eval()
    embed = module.embed
    fps = float(getattr(module, "fps", 30.0))
    control = reinitialised(module)
    rigs = {target: read_bvh(target) for target in targets}
    rows: List[str] = []
    means: Dict[tuple, List[float]] = {}
    sources_tracks: List[Dict[str, np.ndarray]] = []
    outputs: Dict[str, List[Dict[str, np.ndarray]]] = {}
    for path in sources:
        clip = read_bvh(path)
        src = most_active(clip, frames)
        src_tracks, src_first = both_limb_tracks(src, fps)
        sources_tracks.append(src_tracks)
        cases = [(TRAINED, module, t, rig) for t, rig in rigs.items()]
        cases += [("re-initialised (chance)", control, t, rig) for t, rig in rigs.items()]
        cases.append((RECONSTRUCTION, module, path, clip))
        for name, model, target, rig in cases:
            out_tracks, out_first = both_limb_tracks(
                retarget_motion(model, src, rig, embed), fps)
            steps = correlate(src_tracks, out_tracks)
            rows.append(_row(name, path, target, steps,
                             correlate(src_tracks, out_tracks, lag=None),
                             correlate(src_first, out_first)))
            key = (name, _target_name(target, path))
            means.setdefault(key, []).append(_mean(steps))
            if name == TRAINED:
                outputs.setdefault(key[1], []).append(out_tracks)
    means.update(shuffled(sources_tracks, outputs))
    return _header(ckpt, fps, frames) + "\n".join(rows) + "\n\n" + summary(means)


def _header(ckpt: str, fps: float, frames: int) -> str:
    head = ("| model | source clip | target | " + " | ".join(LIMBS)
            + " | mean | mean, positions | mean, first-frame facing |\n|---|---|---|"
            + "---:|" * (len(LIMBS) + 3))
    return (f"Retargeting onto other rigs, checkpoint `{ckpt}`; Pearson correlation of "
            f"each limb end's forward displacement over {LAG} frames at {fps:g} fps "
            f"(facing frame, relative to the root) per limb and their mean, and the "
            f"mean correlation of the forward positions themselves; each source clip's "
            f"most active {frames} frames. The facing frame's axis is averaged over each "
            f"clip's frames; the last column takes it from each clip's first frame "
            f"instead. The summary's shuffled control scores each trained retarget "
            f"against the next source clip.\n\n" + head + "\n")


TRAINED = "trained"
RECONSTRUCTION = "trained, reconstruction (source's own rig)"
SHUFFLED = "trained, scored against another source clip (chance)"
#: A clip counts as reconstructed in step above this mean step correlation.
IN_STEP = 0.4


def _target_name(target: Path, source: Path) -> str:
    return target.parent.name if target == source else f"{target.parent.name}/{target.name}"


def _mean(correlations: Dict[str, float]) -> float:
    return float(np.nanmean(list(correlations.values())))


def shuffled(sources: List[Dict[str, np.ndarray]],
             outputs: Dict[str, List[Dict[str, np.ndarray]]]) -> Dict[tuple, List[float]]:
    """The trained retargets scored against the NEXT source clip (cyclic):
    the level that a generic gait, not this clip's own steps, would reach.
    Empty with a single source clip."""
    if len(sources) < 2:
        return {}
    return {(SHUFFLED, target): [_mean(correlate(sources[(i + 1) % len(sources)], out))
                                 for i, out in enumerate(outs)]
            for target, outs in outputs.items()}


def summary(means: Dict[tuple, List[float]]) -> str:
    """Per (model, target): the clips' mean step correlations, their mean
    and how many are above +0.2; for the trained model, also the mean over
    the clips whose own reconstruction is in step (above :data:`IN_STEP`)."""
    recon = next((np.array(v) for (name, _), v in means.items() if name == RECONSTRUCTION),
                 None)
    lines = ["| model | target | clips | mean of clip means | min | max | clips above +0.2 "
             f"| mean over clips reconstructed above +{IN_STEP:g} |",
             "|---|---|---:|---:|---:|---:|---:|---:|"]
    for (name, target), values in means.items():
        v = np.array(values)
        good = ("-" if recon is None or name != TRAINED or not (recon > IN_STEP).any()
                else f"{v[recon > IN_STEP].mean():+.2f} ({(recon > IN_STEP).sum()} clips)")
        lines.append(f"| {name} | {target} | {len(v)} | {v.mean():+.2f} | {v.min():+.2f} "
                     f"| {v.max():+.2f} | {(v > 0.2).sum()} | {good} |")
    return "\n".join(lines) + "\n"


def _row(name: str, source: Path, target: Path, steps: Dict[str, float],
         positions: Dict[str, float], reestimated: Dict[str, float]) -> str:
    cells = " | ".join(f"{steps.get(limb, float('nan')):+.2f}" for limb in LIMBS)
    means = " | ".join(f"{np.nanmean(list(d.values())):+.2f}"
                       for d in (steps, positions, reestimated))
    return (f"| {name} | {source.name} | {target.parent.name}/{target.name} | {cells} "
            f"| {means} |")


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--ckpt", required=True)
    parser.add_argument("--source", nargs="*", type=Path, default=None,
                        help="source clips (default: the dog test split's first three)")
    parser.add_argument("--target", nargs="*", type=Path, default=None,
                        help="human rigs (default: cmu/01_01.bvh, a skeleton held out "
                             "of cpu_joint's training, and a bandai clip)")
    parser.add_argument("--frames", type=int, default=600,
                        help="frames of each source clip (its most active window)")
    parser.add_argument("--out", type=Path, default=RESULTS)
    args = parser.parse_args(argv)
    if not (args.source and args.target) and not (DATA / "manifest.tsv").is_file():
        print(f"retarget_sanity.py: {DATA} not found: the default clips need "
              "../shared/data; pass --source and --target", file=sys.stderr)
        return 2
    sources = args.source or _default_sources()
    targets = args.target or [DATA / "cmu" / "01_01.bvh",
                              DATA / "bandai" / "dataset-1_walk_normal_001.bvh"]
    table = run(args.ckpt, sources, targets, args.frames)
    print(table)
    atomic_write_text(args.out, "# Retarget sanity check\n\n" + table, create_parent=True)
    return 0


def _default_sources() -> List[Path]:
    rows = [line.split("\t") for line in (DATA / "manifest.tsv").read_text().splitlines()[1:]]
    return [DATA / r[0] for r in rows if r[1] == "dog" and r[4] == "test"][:3]


if __name__ == "__main__":
    raise SystemExit(main())
