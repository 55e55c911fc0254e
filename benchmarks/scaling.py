"""Cost of a training step against skeleton size and skeleton mixing: SATA
(padding-free per-frame attention) against the zero-padding RVQ-VAE.

Inputs:

- one skeleton per batch: synthetic random trees (each joint's parent is one
  of the three joints before it, random offsets, rest pose; no end sites)
  with 20 to 150 joints, ``--clips`` clips of ``--frames`` frames;
- a mixed batch: one clip each of the dog (21 joints, 27 nodes), a bandai
  human (22 / 26) and the ccbase rig (100 / 141), ``--frames`` frames each.

Models: SATA-VAE at the paper's sizes (``experiments/sata_vae.yaml``, 256-D
random semantic embedding), the padded RVQ-VAE (``experiments/padded_rvq.yaml``,
MoMask sizes) with ``max_joints = 150`` so that it holds every input, and, on
the mixed batch only (a single-skeleton batch has no padding), two padded
variants of the same SATA:

- "PyG padded attention": PyG's :class:`~torch_geometric.nn.conv.GPSConv`
  attention, which pads every frame to the batch's largest skeleton inside
  the attention only;
- "every frame padded": the cost of a model that pads every frame to J_max in
  every layer, as padded Transformers do (the SATA paper's argument against
  padding): each clip of the batch is replaced by one of the batch's largest
  skeleton with the same frame count, so every layer runs on J_max nodes per
  frame. This is a cost proxy only: its outputs are not used.

A step is normalisation + model + losses + backward + clipping + Adam
(``throughput.train_step``). Time: best of ``--repeat`` steps after a
warm-up, per frame of the batch. Memory: growth of the peak RSS over the
steps in a fresh spawned process per point (CPU), or
``torch.cuda.max_memory_allocated`` (CUDA), per frame.

Usage: ``python benchmarks/scaling.py [--joints 20,40,70,100,150] [--frames 16]
[--clips 2] [--repeat 2] [--device cpu]``. Writes
``benchmarks/results/scaling.md`` (and ``.json``).
"""
from __future__ import annotations

import argparse
import contextlib
import sys
from pathlib import Path
from typing import Dict, List, Optional, Sequence
from unittest import mock

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).resolve().parent))
from results_io import data_folder, write_results  # noqa: E402
from throughput import (DATA, build_module, isolated, memory_baseline,  # noqa: E402
                        peak_memory, random_semantic, time_steps, train_step)

ROOT = Path(__file__).resolve().parents[1]
#: label -> (config, overrides, padding mode: "", "attention" or "every frame").
MODELS = {"SATA": ("sata_vae", (), ""),
          "SATA, PyG padded attention": ("sata_vae", (), "attention"),
          "SATA, every frame padded": ("sata_vae", (), "every frame"),
          "padded RVQ": ("padded_rvq", ("model.max_joints=150",), "")}
#: Models measured on the mixed batch only.
MIXED_ONLY = ("SATA, PyG padded attention", "SATA, every frame padded")
#: Real files of the mixed batch.
MIXED = ["dog/D1_001_KAN01_001.bvh", "bandai/dataset-1_bow_active_001.bvh",
         "ccbase/006_01.bvh"]


# ----------------------------------------------------------- inputs
def synthetic_motion(num_joints: int, frames: int, seed: int = 0):
    """A random tree of :obj:`num_joints` joints in its rest pose."""
    from satagraph.motion import Motion
    from satagraph.skeleton import Skeleton
    rng = np.random.default_rng(seed)
    parents = np.array([-1] + [int(rng.integers(max(0, j - 3), j))
                               for j in range(1, num_joints)])
    offsets = rng.normal(size=(num_joints, 3)) * 0.1
    offsets[:, 1] = np.abs(offsets[:, 1]) + 0.05
    skeleton = Skeleton([f"joint{j}" for j in range(num_joints)], parents, offsets)
    rotations = np.broadcast_to(np.eye(3), (frames, num_joints, 3, 3)).copy()
    translations = np.broadcast_to(skeleton.offsets, (frames, num_joints, 3)).copy()
    translations[:, 0] += np.linspace(0, 1, frames)[:, None] * np.array([1.0, 0, 0])
    return Motion(skeleton, rotations, translations, fps=30.0)


def batch_of(features: Sequence, frames: int):
    """The first :obj:`frames` frames of each feature set as one batch."""
    from satagraph.data import collate_clips
    clips = [f.to_clip(0, frames, random_semantic(f.skeleton.num_joints)) for f in features]
    return collate_clips(clips)


def synthetic_features(num_joints: int, frames: int, clips: int) -> List:
    from satagraph.data.features import motion_to_features
    return [motion_to_features(synthetic_motion(num_joints, frames, seed))
            for seed in range(clips)]


def mixed_features(data: Path) -> List:
    from satagraph.data.dataset import DEFAULT_PREPROCESSING, preprocess_file
    return [preprocess_file(str(data / p), DEFAULT_PREPROCESSING) for p in MIXED]


def padded_to_largest(features: Sequence) -> List:
    """Every clip replaced by the largest skeleton's: the nodes per frame of
    a model that pads each frame to J_max."""
    largest = max(features, key=lambda f: f.skeleton.num_joints)
    return [largest] * len(features)


# ---------------------------------------------------------- measure
def _padded_gps_forward(self, x, edge_index, batch=None, frames=None, **kwargs):
    """:class:`FrameGPSConv` as plain PyG :class:`GPSConv` (padded attention)."""
    from torch_geometric.nn import GPSConv
    return GPSConv.forward(self, x, edge_index, batch, **kwargs)


def measure_point(model: str, input_spec: Dict, frames: int, repeat: int = 2,
                  device: str = "cpu", data: str = str(DATA)) -> Dict:
    r"""Time and memory per frame of one model on one input
    (``{"kind": "synthetic", "joints": J, "clips": B}`` or
    ``{"kind": "mixed"}``)."""
    from satagraph.nn.layers.frame_gps import FrameGPSConv
    torch.manual_seed(0)
    dev = torch.device(device)
    if input_spec["kind"] == "mixed":
        feats = mixed_features(Path(data))
    else:
        feats = synthetic_features(input_spec["joints"], frames, input_spec["clips"])
    config, overrides, padding = MODELS[model]
    batch = batch_of(feats, frames)
    joints = batch.clip_num_joints.tolist()
    if padding == "every frame":
        feats = padded_to_largest(feats)
        batch = batch_of(feats, frames)
    module = build_module(config, feats, overrides).to(dev).train()
    batch = batch.to(dev)
    opt = torch.optim.Adam(module.parameters(), lr=1e-4)
    patch = (mock.patch.object(FrameGPSConv, "forward", _padded_gps_forward)
             if padding == "attention" else contextlib.nullcontext())
    with patch:
        base = memory_baseline(dev)
        train_step(module, opt, batch)
        times = time_steps(lambda: train_step(module, opt, batch), dev, repeat)
        memory = peak_memory(dev) - base
    num_frames = int(batch.root.shape[0])
    return dict(model=model, input=input_spec, joints=joints, frames=num_frames,
                nodes=int(batch.num_nodes), best_s=min(times),
                ms_per_frame=1000 * min(times) / num_frames,
                mb=memory, mb_per_frame=memory / num_frames, device=device)


# ------------------------------------------------------------ tables
def _input_label(row: Dict) -> str:
    if row["input"]["kind"] == "mixed":
        return "mixed: dog + bandai + ccbase (" + " / ".join(map(str, row["joints"])) + ")"
    return f"synthetic tree, {row['joints'][0]} joints x {len(row['joints'])} clips"


def table(rows: List[Dict]) -> str:
    """One line per input: each model's ms and MB per frame, and the
    padded / SATA ratios."""
    models = [m for m in MODELS if any(r["model"] == m for r in rows)]
    head = ["input", "frames"]
    for m in models:
        head += [f"{m} ms/frame", f"{m} MB/frame"]
    head += ["time padded RVQ / SATA", "memory padded RVQ / SATA"]
    padded = [m for m in MIXED_ONLY if m in models]
    head += [f"time {m} / SATA" for m in padded]
    lines = ["| " + " | ".join(head) + " |", "|---" + "|---:" * (len(head) - 1) + "|"]
    inputs: Dict[str, Dict[str, Dict]] = {}
    for r in rows:
        inputs.setdefault(_input_label(r), {})[r["model"]] = r
    for label, by_model in inputs.items():
        frames = next(iter(by_model.values()))["frames"]
        cells = [label, str(frames)]
        for m in models:
            r = by_model.get(m)
            cells += ["-", "-"] if r is None else [f"{r['ms_per_frame']:.1f}",
                                                   f"{r['mb_per_frame']:.2f}"]
        cells += [_ratio(by_model, "padded RVQ", "ms_per_frame"),
                  _ratio(by_model, "padded RVQ", "mb_per_frame")]
        cells += [_ratio(by_model, m, "ms_per_frame") for m in padded]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _ratio(by_model: Dict[str, Dict], model: str, key: str) -> str:
    if model not in by_model or "SATA" not in by_model:
        return "-"
    base = by_model["SATA"][key]
    return f"{by_model[model][key] / base:.2f}" if base > 0 else "-"


def notes(args) -> str:
    return f"""Notes:
- A training step (model + losses + backward + clipping + Adam); best of
  {args.repeat} steps after a warm-up, divided by the frames of the batch;
  device {args.device}, {torch.get_num_threads()} threads. Memory: growth of
  the peak RSS over the steps in a fresh process per point (CPU; allocator
  caching and RSS granularity make small values noisy), per frame.
- Synthetic batches: {args.clips} clips x {args.frames} frames of one random
  tree (nodes = joints). Mixed batch: one {args.frames}-frame clip each of
  the dog, a bandai human and the ccbase rig (nodes with end sites).
- SATA: paper sizes (8.47 M parameters with a 256-D semantic embedding),
  padding-free per-frame attention (satagraph.nn.layers.frame_gps). "PyG padded
  attention": the same model through torch_geometric's GPSConv.forward,
  which pads every frame to the batch's largest skeleton in the attention.
  "Every frame padded": the same model with every clip on the batch's
  largest skeleton (same frames), the cost of padding each frame to J_max
  in every layer as padded Transformers do (a cost proxy). Padded RVQ:
  MoMask sizes, max_joints = 150 for every input (its cost per frame does
  not depend on the skeleton).
- Shared 2-core CPU: compare ratios within one run only.
"""


def main(argv: Optional[Sequence[str]] = None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=data_folder, default=str(DATA))
    parser.add_argument("--joints", default="20,40,70,100,150")
    parser.add_argument("--frames", type=int, default=16)
    parser.add_argument("--clips", type=int, default=2)
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--no-mixed", action="store_true")
    parser.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "scaling"))
    args = parser.parse_args(argv)
    points = [(m, {"kind": "synthetic", "joints": int(j), "clips": args.clips})
              for j in args.joints.split(",") for m in ("SATA", "padded RVQ")]
    if not args.no_mixed:
        points += [(m, {"kind": "mixed"}) for m in MODELS]
    rows = []
    for model, spec in points:
        rows.append(isolated(measure_point, model, spec, args.frames, args.repeat,
                             args.device, args.data))
        print(f"{model:<28} {_input_label(rows[-1]):<55} "
              f"{rows[-1]['ms_per_frame']:8.1f} ms/frame {rows[-1]['mb_per_frame']:7.2f} "
              "MB/frame", flush=True)
    text = table(rows) + "\n\n" + notes(args)
    print(text)
    write_results(Path(args.out), "Scaling with skeleton size and mixing", text, rows)


if __name__ == "__main__":
    main()
