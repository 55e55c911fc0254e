"""Choosing a built-in checkpoint on validation material only (issue 16).

`benchmarks/pretrained.py` is the built-in model's test: its zoo rigs come
from the endless zoo's test seeds and its real clips from the test splits.
A checkpoint chosen on those rows would be tuned on its test set, so
candidates are compared here instead, the same way (whole clips through
:func:`~satagraph.pipelines.inference.retarget_canonical`, reconstruction
on the clip's own rig, root path integrated over the clip):

- **zoo**: clips of the validation seed stream, walking, trotting, running,
  turning and changing speed, a few per training body plan (median per
  plan: a plan the model cannot read yet gives errors in the hundreds);
  and, one group per kind, sidesteps, backward walks, starts, stops, jumps
  and idles of its bipeds, quadrupeds, birds and fowl (two per plan);
- **bandai**: a third of Bandai's validation split (never trained on);
- **dog**: the dog clips outside its test split (never trained on: its
  licence keeps it out of the shipped model's data); and **dog lowered**:
  those that sit or lie down for a tenth of their frames or more, cut
  where they are down the most.

and retargets between validation rigs (zoo biped, quadruped and bird of the
validation seeds; a Bandai validation walk and the dog's validation clips),
scored as `benchmarks/pretrained.py` scores its rows: steps (limb timing
against the source's) and travel (root distance in leg lengths over the
source's; the issue's target 0.8-1.25).

Columns per checkpoint: JP, the mean global joint position error in % of
the character's height (median over a group's clips, mean in brackets);
for the real groups also the joint error relative to the root, the same
with each frame turned about +Y onto the source's (the pose alone, without
the decoded facing's drift), and how far the decoded facing drifts from the source's over a
clip (degrees, mean absolute; for groups whose heads lead the body).

    .venv/bin/python benchmarks/pretrained_val.py --ckpt builtin RUN/epoch=3.ckpt ... [--out P]
"""
from __future__ import annotations

import argparse
import itertools
import os
import sys
import time
import warnings
from functools import lru_cache
from pathlib import Path
from typing import Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from pretrained import (DATA, HOLDOUT, TRAIN_SPECIES, RECON_FRAMES, joint_error,  # noqa: E402
                        real_clip, recon_window)
from pretrained_rule import STILL  # noqa: E402
from results_io import missing_data, write_results  # noqa: E402
from satagraph.datasets.sources import read_manifest  # noqa: E402
from satagraph.datasets.zoo.endless import EndlessZoo, ZooSample  # noqa: E402
from satagraph.experiment.train import load_module  # noqa: E402
from satagraph.motion import Motion  # noqa: E402
from satagraph.pipelines.inference import (reconstruct_canonical,  # noqa: E402
                                           retarget_canonical)
from satagraph.pipelines.quality import (knee_bend, leg_length, retarget_quality,  # noqa: E402
                                         root_travel)
from satagraph.transforms.canonical import canonicalize  # noqa: E402
from satagraph.transforms.rig_reading import with_rig  # noqa: E402

OUT = ROOT / "benchmarks" / "results" / "pretrained_val"
#: Farthest a still source's root ends from its start, in leg lengths.
STILL_SOURCE = 0.5
#: ``--settle`` and ``--still`` -> the settings measured.
SETTINGS = {"off": (False,), "on": (True,), "both": (False, True)}
#: Kinds of the zoo's other groups (one group each), per plan of these plans.
MORE_KINDS = ("side", "back", "start", "stop", "jump", "idle")
KIND_PLANS, KIND_PER_PLAN = ("biped", "quadruped", "bird", "fowl"), 2
#: The dog's lowered frames: hips below this share of their standing
#: height; clips with at least :data:`LOW_SHARE` of them form a group.
LOW_HIPS, LOW_SHARE = 0.7, 0.1
#: Zoo clips per body plan, and the kinds that travel.
ZOO_PER_PLAN, ZOO_KINDS = 6, ("walk", "trot", "run", "turn", "speed")


@lru_cache(maxsize=None)
def zoo_sample(index: int) -> ZooSample:
    """Sample :obj:`index` of the zoo's validation stream (drawn once)."""
    return EndlessZoo(species=TRAIN_SPECIES, holdout=HOLDOUT).sample(0, index, RECON_FRAMES, "val")


@lru_cache(maxsize=None)
def real_file(rel: str) -> Motion:
    """:func:`pretrained.real_clip`, read once."""
    return real_clip(rel)


def manifest_paths(dataset: str, keep: Callable[[str], bool]) -> List[str]:
    """Paths (relative to the data folder) of a dataset's files whose split
    :obj:`keep` accepts, in the manifest's order."""
    return [os.path.relpath(f.path, DATA) for f in read_manifest(DATA / "manifest.tsv", dataset)
            if keep(f.split)]


def zoo_clips(per_plan: int = ZOO_PER_PLAN) -> List[Tuple[str, str, Motion]]:
    """``(group, name, motion)`` of validation-seed zoo clips, :obj:`per_plan`
    of each body plan (the first of the stream, so a larger count keeps
    the smaller one's clips)."""
    count: Dict[str, int] = {}
    out = []
    for index in range(100 * per_plan):
        sample = zoo_sample(index)
        if sample.kind not in ZOO_KINDS or count.get(sample.species, 0) >= per_plan:
            continue
        count[sample.species] = count.get(sample.species, 0) + 1
        out.append((f"zoo {sample.species}", f"{sample.plan} {sample.kind} ({sample.rest} rest)",
                    sample.motion))
        if all(count.get(species, 0) >= per_plan for species in TRAIN_SPECIES):
            break
    return out


def zoo_kind_clips() -> List[Tuple[str, str, Motion]]:
    """``(group, name, motion)`` of validation-seed zoo clips of the kinds
    :data:`MORE_KINDS`, one group per kind, :data:`KIND_PER_PLAN` per
    plan of :data:`KIND_PLANS` (sidesteps, backward walks, starts and
    stops travel as walks do not: a decoder can glide them)."""
    count: Dict[Tuple[str, str], int] = {}
    out = []
    for index in range(800):
        sample = zoo_sample(index)
        key = (sample.kind, sample.species)
        if (sample.kind not in MORE_KINDS or sample.species not in KIND_PLANS
                or count.get(key, 0) >= KIND_PER_PLAN):
            continue
        count[key] = count.get(key, 0) + 1
        out.append((f"zoo {sample.kind}", f"{sample.plan} ({sample.rest} rest)", sample.motion))
    return sorted(out, key=lambda item: MORE_KINDS.index(item[0][4:]))


def real_clips() -> List[Tuple[str, str, Motion]]:
    """Bandai's validation clips (every third) and the dog's non-test clips,
    each cut to its most active :data:`RECON_FRAMES` frames at 30 fps."""
    bandai = manifest_paths("bandai", lambda split: split == "val")[::3]
    dog = sorted(manifest_paths("dog", lambda split: split != "test"))
    return [(group, rel, recon_window(real_file(rel)))
            for group, paths in (("bandai (val)", bandai), ("dog (not test)", dog))
            for rel in paths]


def hips(motion: Motion) -> np.ndarray:
    """The root's height above the lowest joint, per frame (metres, canonical)."""
    pos = canonicalize(motion, fps=None).global_positions()
    return pos[:, 0, 1] - pos[:, :, 1].min(axis=1)


def lowered_clips() -> List[Tuple[str, str, Motion]]:
    """The dog's non-test clips that go down (hips below :data:`LOW_HIPS`
    of their standing height, the 90th percentile, in at least
    :data:`LOW_SHARE` of the frames), each cut to the
    :data:`RECON_FRAMES` frames (at 30 fps) with the most such frames.
    Read +Y up, as the dog's files are: a window in which the dog lies
    throughout can be guessed on its side (a low-confidence guess that
    `satagraph` warns about), and this group measures the model, not the
    guess."""
    out = []
    for rel in sorted(manifest_paths("dog", lambda split: split != "test")):
        motion = with_rig(real_file(rel), up_axis="+Y")
        height = hips(motion)
        low = (height < LOW_HIPS * np.percentile(height, 90)).astype(np.float64)
        frames = int(RECON_FRAMES * motion.fps / 30.0)
        if low.mean() < LOW_SHARE or motion.num_frames <= frames:
            continue
        start = int(np.argmax(np.convolve(low, np.ones(frames), mode="valid")))
        out.append(("dog lowered (not test)", rel, motion.slice(start, start + frames)))
    return out


def retarget_pairs() -> List[Tuple[str, Motion, Motion]]:
    """``(name, source, target)`` of validation retargets: zoo walks of
    the validation seeds between bipeds, quadrupeds and birds (two pairs
    each way), a Bandai validation walk to and from the dog's
    validation clips, and onto the validation clips of Reallusion's
    CC_Base rig (ccbase: every bone up in its files' rest)."""
    walks: Dict[str, List[Motion]] = {}
    for index in range(300):
        sample = zoo_sample(index)
        if sample.kind in ("walk", "trot") and sample.species in ("biped", "quadruped", "bird"):
            walks.setdefault(sample.species, []).append(sample.motion)
    out = []
    for a, b in (("biped", "quadruped"), ("quadruped", "biped"), ("biped", "bird")):
        for k in range(2):
            out.append((f"zoo {a} -> {b}", walks[a][k], walks[b][k + 2]))
    walk = next(p for p in manifest_paths("bandai", lambda split: split == "val")
                if "_walk_" in p)
    human = real_file(walk)
    for rel in manifest_paths("dog", lambda split: split == "val"):
        dog = real_file(rel)
        out.append(("bandai -> dog", human, dog))
        out.append(("dog -> bandai", recon_window(dog), human))
    for rel in manifest_paths("ccbase", lambda split: split == "val"):
        out.append(("bandai -> CC_Base rig", human, real_file(rel)))
    return out


def displacement(canonical: Motion) -> np.ndarray:
    """Where the root ends, horizontally, from where it starts, in leg
    lengths (a canonical motion)."""
    root = canonical.translations[:, 0, [0, 2]]
    return (root[-1] - root[0]) / leg_length(canonical)


def still_pairs() -> List[Tuple[str, Motion, Motion]]:
    """``(name, source, target)`` of validation retargets whose source
    stands (its root ends under :data:`STILL_SOURCE` leg lengths from its
    start, canonical): the dog's clips outside its test split (never
    trained on, as in :func:`real_clips`) onto a Bandai validation walk's
    rig, and every third Bandai validation clip onto the dog's first
    validation clip's rig (each cut to its most active
    :data:`RECON_FRAMES` frames at 30 fps)."""
    dogs = sorted(manifest_paths("dog", lambda split: split != "test"))
    bandai = manifest_paths("bandai", lambda split: split == "val")
    human = real_file(next(p for p in bandai if "_walk_" in p))
    dog = real_file(manifest_paths("dog", lambda split: split == "val")[0])
    out = []
    for name, paths, target in ((f"{STILL} dog -> bandai", dogs, human),
                                (f"{STILL} bandai -> dog", bandai[::3], dog)):
        for rel in paths:
            source = recon_window(real_file(rel))
            if np.linalg.norm(displacement(canonicalize(source, fps=30.0))) < STILL_SOURCE:
                out.append((name, source, target))
    return out


def retarget_scores(module, pairs: List[Tuple[str, Motion, Motion]],
                    plant: bool = False, settle: bool = False,
                    still: bool = True, mirror: bool = False) -> Dict[str, dict]:
    """Mean steps, the share of travel ratios within 0.8-1.25, the
    median of ``sideways`` (degrees off the source's heading gap,
    :func:`~satagraph.pipelines.quality.heading_gap`), of the stride
    ratio (:func:`~satagraph.pipelines.quality.stride`), the lowest
    posture (:func:`~satagraph.pipelines.quality.posture` against the
    target's own clip) and lands (:func:`~satagraph.pipelines.quality.lands`,
    likewise) and the median ``gap`` between the retarget's and
    the source's :func:`displacement` (leg lengths) per pair name."""
    got: Dict[str, List[dict]] = {}
    for name, source, target in pairs:
        src, out = retarget_canonical(module, source, target, module.embed, plant=plant,
                                      settle=settle, still=still, mirror=mirror)
        own = canonicalize(target, fps=float(module.fps))
        quality = retarget_quality(src, out, ("steps", "travel", "sideways", "stride",
                                              "posture", "lands"), target=own)
        quality["gap"] = float(np.linalg.norm(displacement(out) - displacement(src)))
        got.setdefault(name, []).append(quality)
    return {name: dict(n=len(v), steps=float(np.mean([q["steps"] for q in v])),
                       travel=float(np.median([q["travel"] for q in v])),
                       travel_ok=float(np.mean([0.8 <= q["travel"] <= 1.25 for q in v])),
                       sideways=_median([q["sideways"] for q in v]),
                       stride=_median([q["stride"] for q in v]),
                       posture=_lowest([q["posture"] for q in v]),
                       lands=_lowest([q["lands"] for q in v]),
                       gap=float(np.median([q["gap"] for q in v])))
            for name, v in got.items()}


def _lowest(values: Sequence[Optional[float]]) -> Optional[float]:
    """The least of the values that are not ``None`` (``None`` if none are)."""
    kept = [v for v in values if v is not None]
    return float(min(kept)) if kept else None


def _median(values: Sequence[Optional[float]]) -> Optional[float]:
    """The median of the values that are not ``None`` (``None`` if none are)."""
    kept = [v for v in values if v is not None]
    return float(np.median(kept)) if kept else None


def _facing(positions: np.ndarray, names: Sequence[str]) -> Optional[np.ndarray]:
    """Yaw (degrees, unwrapped) of the root-to-head direction, or None
    when the rig has no head or it sits above the root (upright bodies)."""
    heads = [j for j, n in enumerate(names) if "head" in n.lower() and "end" not in n.lower()]
    if not heads:
        return None
    d = positions[:, heads[0]] - positions[:, 0]
    if np.median(np.linalg.norm(d[:, [0, 2]], axis=-1)) < 0.5 * np.median(np.abs(d[:, 1])):
        return None
    return np.degrees(np.unwrap(np.arctan2(d[:, 0], d[:, 2])))


def measure(module, motion: Motion, plant: bool = False, settle: bool = False,
            mirror: bool = False, refine: int = 0) -> dict:
    """JP, root-relative JP (fractions of the height), facing drift and the
    stride ratio (:func:`~satagraph.pipelines.quality.stride`, output over
    source); read in one rest pose (``two_rests=False``), as every rule
    that used it was measured; :obj:`refine` steps fit each latent first."""
    src, out = reconstruct_canonical(module, motion, module.embed, ground=False, plant=plant,
                                     settle=settle, mirror=mirror, two_rests=False,
                                     refine=refine)
    n = min(src.num_frames, out.num_frames)
    fa = _facing(src.global_positions()[:n], src.skeleton.names)
    fb = _facing(out.global_positions()[:n], src.skeleton.names)
    drift = None if fa is None or fb is None else float(np.abs((fb - fa) - (fb - fa)[0]).mean())
    knees = knee_bend(out), knee_bend(src)
    return dict(jp=joint_error(src, out), pose=joint_error(src, out, relative=True),
                local=joint_error(src, out, heading=True), drift=drift,
                stride=retarget_quality(src, out, ("stride",))["stride"],
                path=root_travel(out) - root_travel(src),
                knee=None if None in knees else knees[0] - knees[1])


def summarise(values: List[dict]) -> dict:
    jp = np.array([v["jp"] for v in values])
    drift = [v["drift"] for v in values if v["drift"] is not None]
    return dict(n=len(values), median=float(np.median(jp)), mean=float(jp.mean()),
                jp_clips=jp.tolist(), pose_clips=[v["pose"] for v in values],
                pose=float(np.median([v["pose"] for v in values])),
                local=float(np.median([v["local"] for v in values])),
                drift=float(np.mean(drift)) if 2 * len(drift) > len(values) else None,
                stride=_median([v.get("stride") for v in values]),
                path=_median([v.get("path") for v in values]),
                knee=_median([v.get("knee") for v in values]))


def table(summary: Dict[str, Dict[str, dict]], seconds: float,
          retargets: Optional[Dict[str, Dict[str, dict]]] = None) -> str:
    names = list(summary)
    lines = [f"Validation material only (the zoo's validation seeds, Bandai's val split, the "
             f"dog outside its test split); {seconds:.0f} s.", "",
             "JP, % of the height: median (mean) over a group's clips; real groups also give "
             "the median root-relative error (pose; in brackets with each frame turned about "
             "+Y onto the source's: the pose alone, without the decoded facing's drift) and the "
             "mean facing drift (degrees) and the median of how much farther the decoded root "
             "goes on the ground than the source's (path, leg lengths) and how much more its "
             "knees bend (knee, degrees: the median over clips of knee_bend's gap); stride: "
             "the median "
             "stride ratio (limb ends' fore-aft swing, output over source).", "",
             "| group | n | " + " | ".join(f"`{Path(k).name}`" for k in names) + " |",
             "|---|---:|" + "---:|" * len(names)]
    for group in summary[names[0]]:
        cells = []
        for k in names:
            s = summary[k][group]
            cell = f"{100 * s['median']:.1f} ({100 * s['mean']:.1f})"
            if not group.startswith("zoo"):
                cell += f", pose {100 * s['pose']:.1f} ({100 * s['local']:.1f})"
                if s["drift"] is not None:
                    cell += f", drift {s['drift']:.0f}"
                if s.get("path") is not None:
                    cell += f", path {s['path']:+.2f}"
                if s.get("knee") is not None:
                    cell += f", knee {s['knee']:+.0f}"
            if s.get("stride") is not None:
                cell += f", stride {s['stride']:.2f}"
            cells.append(cell)
        lines.append(f"| {group} | {summary[names[0]][group]['n']} | " + " | ".join(cells) + " |")
    if retargets:
        lines += ["", "Retargets: mean steps, median travel ratio (share within 0.8-1.25), "
                  "median degrees sideways of the source's heading, median stride ratio, "
                  "lowest posture, lowest lands, median gap between the retarget's and the source's "
                  "displacement (leg lengths).", "",
                  "| retarget | n | " + " | ".join(f"`{Path(k).name}`" for k in names) + " |",
                  "|---|---:|" + "---:|" * len(names)]
        for pair in retargets[names[0]]:
            cells = [f"{r['steps']:+.2f}, {r['travel']:.2f} ({100 * r['travel_ok']:.0f}%)"
                     + ("" if r.get("sideways") is None else f", {r['sideways']:.0f} deg")
                     + ("" if r.get("stride") is None else f", stride {r['stride']:.2f}")
                     + ("" if r.get("posture") is None else f", posture {r['posture']:.2f}")
                     + ("" if r.get("lands") is None else f", lands {r['lands']:.2f}")
                     + ("" if r.get("gap") is None else f", gap {r['gap']:.2f}")
                     for r in (retargets[k][pair] for k in names)]
            lines.append(f"| {pair} | {retargets[names[0]][pair]['n']} | " + " | ".join(cells)
                         + " |")
    return "\n".join(lines) + "\n"


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--ckpt", nargs="+", default=["builtin"],
                        help="checkpoints, .safetensors weights files or builtin")
    parser.add_argument("--out", type=Path, default=OUT, help="results path without suffix")
    parser.add_argument("--zoo-per-plan", type=int, default=ZOO_PER_PLAN, metavar="N",
                        help="zoo clips per body plan (the first N of the validation "
                             "stream; more: less noisy medians, slower)")
    parser.add_argument("--plant", action="store_true",
                        help="plant the feet of every output (retarget_canonical's plant)")
    parser.add_argument("--settle", choices=("off", "on", "both"), default="off",
                        help="hold the root still where the decoded body stands still "
                             "(retarget_canonical's settle); both: each checkpoint twice, "
                             "the second column named '+settle'")
    parser.add_argument("--still", choices=("off", "on", "both"), default="on",
                        help="retargets: keep the root still where the source stands "
                             "(retarget_canonical's still; reconstructions never); both: "
                             "each checkpoint twice, the second column named '+still'")
    parser.add_argument("--mirror", choices=("off", "on", "both"), default="off",
                        help="average each decoding with its mirror image's "
                             "(retarget_canonical's mirror); both: each checkpoint twice, "
                             "the second column named '+mirror'")
    parser.add_argument("--refine", type=int, default=0, metavar="STEPS",
                        help="reconstructions: fit each window's latent to the clip by "
                             "STEPS steps first (reconstruct --refine; retargets are read "
                             "as the encoder reads them); columns named '+refine STEPS'")
    args = parser.parse_args(argv)
    missing = missing_data("pretrained_val.py", DATA, "the real groups")
    if missing:
        print(missing, file=sys.stderr)
        return 2
    start = time.perf_counter()
    if args.zoo_per_plan < 1:
        parser.error(f"--zoo-per-plan must be at least 1, got {args.zoo_per_plan}")
    if args.refine < 0:
        parser.error(f"--refine must be 0 or more, got {args.refine}")
    clips = zoo_clips(args.zoo_per_plan) + zoo_kind_clips() + real_clips() + lowered_clips()
    pairs = retarget_pairs() + still_pairs()
    summary: Dict[str, Dict[str, dict]] = {}
    retargets: Dict[str, Dict[str, dict]] = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for ckpt in args.ckpt:
            module = load_module(ckpt).eval()
            for settle, mirror in itertools.product(SETTINGS[args.settle],
                                                    SETTINGS[args.mirror]):
                groups: Dict[str, List[dict]] = {}
                for group, _, motion in clips:  # reconstructions: never ``still``
                    groups.setdefault(group, []).append(
                        measure(module, motion, args.plant, settle, mirror, args.refine))
                for still in SETTINGS[args.still]:
                    name = ckpt + (" +settle" if settle and args.settle == "both" else "") \
                        + (" +mirror" if mirror and args.mirror == "both" else "") \
                        + (" +still" if still and args.still == "both" else "") \
                        + (f" +refine {args.refine}" if args.refine else "")
                    summary[name] = {g: summarise(v) for g, v in groups.items()}
                    retargets[name] = retarget_scores(module, pairs, args.plant, settle, still,
                                                      mirror)
    text = table(summary, time.perf_counter() - start, retargets)
    print(text)
    write_results(args.out, "Built-in model candidates on validation material "
                  "(benchmarks/pretrained_val.py)", text,
                  {"reconstruction": summary, "retarget": retargets,
                   "zoo_per_plan": args.zoo_per_plan})
    return 0


if __name__ == "__main__":
    sys.exit(main())
