"""What the length model says: the duration `satagraph generate` draws
when no `--seconds` is given (`experiments/T2M.md` section 33).

For every checkpoint, on one rig of each zoo plan (validation seeds) and
on real rigs (Bandai, CMU, CC_Base, the dog), the length model reads the
probe prompts of `benchmarks/t2m.py`; the table gives the mean drawn
duration, the share of draws under 2 s and how far the prompts move the
mean (largest minus smallest). On Bandai's test clips, whose captioned
durations are known (their files), it gives the median absolute error of
the model's median duration against the clip's (both clipped to the
model's longest bin) and the mean negative log-likelihood of the clip's
bin.

    .venv/bin/python benchmarks/t2m_length.py [--ckpt builtin CKPT ...] [--out P]
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).resolve().parent))
from results_io import write_results  # noqa: E402
from t2m import MANIFEST, PROBE_PROMPTS, SUBJECTS, manifest_motion  # noqa: E402
from satagraph.data.collate import collate_clips  # noqa: E402
from satagraph.datasets import captions_for  # noqa: E402
from satagraph.datasets.sources import read_manifest, select  # noqa: E402
from satagraph.datasets.zoo.endless import EndlessZoo  # noqa: E402
from satagraph.motion import Motion  # noqa: E402
from satagraph.pipelines.generate import load_generator, rig_inputs  # noqa: E402
from satagraph.pipelines.inference import target_clip  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "benchmarks" / "results" / "t2m_length"
ZOO_PLANS = ("biped", "quadruped", "bird", "hexapod")
#: Real rigs: (name, dataset, split, subject).
REAL_RIGS = (("bandai", "bandai", "test", "human"), ("cmu 01_01", "cmu", "train", "human"),
             ("ccbase", "ccbase", "test", "human"), ("dog", "dog", "test", "dog"))


def rigs() -> Dict[str, Tuple[str, Motion]]:
    """Name -> (subject, motion) of every rig read."""
    zoo = EndlessZoo(list(ZOO_PLANS), fps=30.0, seed=0)
    out = {}
    for i, plan in enumerate(ZOO_PLANS):
        out[f"zoo {plan}"] = (SUBJECTS[plan], zoo.sample(0, i, 60, "val").motion)
    if not MANIFEST.is_file():
        return out
    files = read_manifest(MANIFEST)
    for name, dataset, split, subject in REAL_RIGS:
        motion = manifest_motion(files, dataset, split, "01_01" if name == "cmu 01_01" else "")
        if motion is not None:
            out[name] = (SUBJECTS[subject], motion)
    return out


@torch.no_grad()
def skeleton_token(module, motion: Motion) -> torch.Tensor:
    """The skeleton embedding of a rig as ``generate`` shows it."""
    rig = rig_inputs(module, motion)
    return module.skeleton_embedding(collate_clips([target_clip(rig.feats, 1, rig.semantic)]))


@torch.no_grad()
def distribution(module, text: Optional[str], skel: torch.Tensor) -> np.ndarray:
    """The length model's probabilities over its bins for a prompt on a rig
    (its :func:`skeleton_token`)."""
    emb = None if text is None else module.encode_text([text])
    module.length.eval()
    return module.length(emb, skel).softmax(-1)[0].double().numpy()


def rig_row(module, subject: str, motion: Motion) -> Dict[str, float]:
    """Mean duration, share under 2 s and spread over the probe prompts."""
    seconds = module.length.bins_to_seconds(torch.arange(module.length.num_bins)).numpy()
    skel = skeleton_token(module, motion)
    means, short = [], []
    for prompt, _ in PROBE_PROMPTS:
        p = distribution(module, prompt.format(subject), skel)
        means.append(float(p @ seconds))
        short.append(float(p[seconds < 2.0].sum()))
    return {"mean": float(np.mean(means)), "short": float(np.mean(short)),
            "spread": float(max(means) - min(means))}


def bandai_seconds(split: str) -> List[Tuple[str, float]]:
    """(path, duration in seconds) of Bandai's clips of a split."""
    files = [f for f in select(read_manifest(MANIFEST), split) if f.dataset == "bandai"]
    out = []
    for f in files:
        motion = f.read()
        out.append((f.path, motion.num_frames / motion.fps))
    return out


def known_durations(module, motion: Motion, train: Sequence[float],
                    test: Sequence[Tuple[str, float]]) -> Dict[str, float]:
    """On Bandai's test clips (their file's duration is their caption's):
    the median absolute error of the model's median and the NLL, and the
    error of one constant, the median of Bandai's training clips' durations
    :obj:`train`."""
    lm = module.length
    seconds = lm.bins_to_seconds(torch.arange(lm.num_bins)).numpy()
    longest = float(seconds[-1])
    constant = min(float(np.median(train)), longest)
    skel = skeleton_token(module, motion)
    errors, nll, flat = [], [], []
    for path, duration in test:
        truth = min(duration, longest)
        flat.append(abs(constant - truth))
        p = distribution(module, captions_for(path, "bandai")[0].text, skel)
        median = float(seconds[np.searchsorted(np.cumsum(p), 0.5)])
        errors.append(abs(median - truth))
        nll.append(-np.log(p[int(lm.seconds_to_bins(torch.tensor(truth)))] + 1e-12))
    return {"n": len(errors), "error": float(np.median(errors)), "nll": float(np.mean(nll)),
            "constant": constant, "constant_error": float(np.median(flat))}


def measure(ckpts: Sequence[str]) -> Dict[str, Dict[str, object]]:
    targets = rigs()
    bandai = targets.get("bandai")
    if bandai is not None:  # read once for every checkpoint
        train = [d for _, d in bandai_seconds("train")]
        test = bandai_seconds("test")
    results = {}
    for ckpt in ckpts:
        module = load_generator(ckpt).eval()
        rows = {name: rig_row(module, subject, motion)
                for name, (subject, motion) in targets.items()}
        results[ckpt] = {"rigs": rows,
                         "bandai": (known_durations(module, bandai[1], train, test)
                                    if bandai is not None else None),
                         "longest": float(module.length.bins_to_seconds(
                             torch.tensor(module.length.num_bins - 1)))}
    return results


def table(results: Dict[str, Dict[str, object]], seconds: float) -> str:
    lines = [f"`.venv/bin/python benchmarks/t2m_length.py --ckpt {' '.join(results)}` "
             f"({seconds:.0f} s). Mean drawn duration in seconds over the probe prompts of "
             "`benchmarks/t2m.py`, the share of draws under 2 s, and the largest minus the "
             "smallest prompt's mean.", "",
             "| checkpoint | rig | mean duration, s | draws under 2 s | spread over prompts, s |",
             "|---|---|---:|---:|---:|"]
    for ckpt, res in results.items():
        for name, row in res["rigs"].items():
            lines.append(f"| {ckpt} | {name} | {row['mean']:.2f} | {row['short']:.0%} | "
                         f"{row['spread']:.2f} |")
    lines += ["", "Bandai's test clips (known durations, clipped to the longest bin):", "",
              "| checkpoint | n | median error of the median, s | NLL of the clip's bin | "
              "median error of one constant (Bandai's training median), s |",
              "|---|---:|---:|---:|---:|"]
    for ckpt, res in results.items():
        b = res["bandai"]
        if b:
            lines.append(f"| {ckpt} | {b['n']} | {b['error']:.2f} | {b['nll']:.2f} | "
                         f"{b['constant_error']:.2f} ({b['constant']:.2f} s) |")
    return "\n".join(lines) + "\n"


def main(argv: Optional[List[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--ckpt", nargs="+", default=["builtin"],
                        help="generators to read (default: builtin)")
    parser.add_argument("--out", type=Path, default=OUT, help="results path, no suffix")
    args = parser.parse_args(argv)
    torch.set_num_threads(1)
    start = time.perf_counter()
    results = measure(args.ckpt)
    text = table(results, time.perf_counter() - start)
    print(text)
    write_results(args.out, "The length model (benchmarks/t2m_length.py)", text, results)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
