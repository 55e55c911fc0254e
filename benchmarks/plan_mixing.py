"""How fast the pretrain_zoo model learns limb timing, by how many body plans
it is trained on (issue 16, "learning per minute").

Trains the ``pretrain_zoo`` model (its model and loss sections) on windows of
walks and trots of :obj:`--rigs` endless-zoo rigs of the given plans (the
training stream), and every ``--steps / 3`` steps measures the limb step
correlation (:func:`satagraph.pipelines.quality.step_correlation`) of
reconstructions of 4 of those rigs and of 4 rigs of the test stream (never
trained on). Prints a markdown table.

Usage::

    python benchmarks/plan_mixing.py --plans biped --rigs 8 --steps 450
    python benchmarks/plan_mixing.py --plans biped,quadruped,bird,fowl --rigs 16

Needs no data beyond the zoo; about 0.8 s a step on one thread of a 2-core
CPU.
"""
from __future__ import annotations

import argparse
import time
from typing import List, Optional, Sequence

import torch

from satagraph.data import motion_to_features
from satagraph.data.collate import collate_clips
from satagraph.datasets.zoo.endless import EndlessZoo
from satagraph.experiment.config import load_config
from satagraph.experiment.train import module_class
from satagraph.motion import Motion
from satagraph.pipelines.inference import reconstruct_canonical
from satagraph.pipelines.quality import retarget_quality
from satagraph.transforms import canonicalize

FRAMES, WINDOW, BATCH = 64, 32, 8


def walks(zoo: EndlessZoo, stream: str, count: int) -> List[Motion]:
    """The first :obj:`count` walks or trots of a zoo stream."""
    out = []
    for index in range(4000):
        sample = zoo.sample(0, index, FRAMES, stream)
        if sample.kind in ("walk", "trot"):
            out.append(sample.motion)
            if len(out) == count:
                return out
    raise LookupError(f"fewer than {count} walks in the {stream} stream")


def steps_of(module, motions: Sequence[Motion]) -> List[float]:
    """Reconstruction step correlation of each motion."""
    module.eval()
    out = []
    for motion in motions:
        src, rec = reconstruct_canonical(module, motion)
        steps = retarget_quality(src, rec, ("steps",))["steps"]
        out.append(float("nan") if steps is None else steps)
    module.train()
    return out


def run(plans: List[str], rigs: int, steps: int, lr: float, seed: int) -> List[str]:
    torch.manual_seed(seed)
    cfg = load_config("pretrain_zoo")
    zoo = EndlessZoo(species=plans)
    train, test = walks(zoo, "train", rigs), walks(zoo, "test", 4)
    module = module_class(cfg["module"])(model=cfg["model"], loss=cfg["loss"],
                                         meta={"semantic_encoder": "offline",
                                               "window": WINDOW})
    feats = [motion_to_features(canonicalize(m, fps=30.0)) for m in train]
    module.normalizer.fit(feats)
    clips = [f.to_clip(a, a + WINDOW, module.embed(f.skeleton))
             for f in feats for a in range(0, FRAMES - WINDOW + 1, WINDOW // 2)]
    opt = torch.optim.Adam(module.parameters(), lr=lr)
    gen = torch.Generator().manual_seed(seed)
    rows, start = [], time.perf_counter()
    for step in range(steps + 1):
        batch = collate_clips([clips[i] for i in
                               torch.randperm(len(clips), generator=gen)[:BATCH]])
        loss = module.compute_losses(module(batch), batch)["loss"]
        opt.zero_grad()
        loss.backward()
        torch.nn.utils.clip_grad_norm_(module.parameters(), 0.5)
        opt.step()
        if step and step % max(steps // 3, 1) == 0:
            seconds = time.perf_counter() - start
            fmt = " ".join(f"{v:+.2f}" for v in steps_of(module, train[:4]))
            held = " ".join(f"{v:+.2f}" for v in steps_of(module, test))
            rows.append(f"| {', '.join(plans)} | {rigs} | {step} | {seconds:.0f} "
                        f"| {loss.item():.2f} | {fmt} | {held} |")
            print(rows[-1], flush=True)
    return rows


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--plans", default="biped",
                        help="comma-separated training body plans")
    parser.add_argument("--rigs", type=int, default=8, help="training rigs")
    parser.add_argument("--steps", type=int, default=450)
    parser.add_argument("--lr", type=float, default=1e-3)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--threads", type=int, default=1)
    args = parser.parse_args(argv)
    torch.set_num_threads(args.threads)
    print("| body plans | rigs | steps | seconds | loss | steps, training rigs "
          "| steps, unseen rigs |\n|---|---:|---:|---:|---:|---|---|")
    run(args.plans.split(","), args.rigs, args.steps, args.lr, args.seed)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
