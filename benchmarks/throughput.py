"""Training and inference throughput of SATA-VAE, SATA-RVQ, SAME-wide and the
zero-padding RVQ-VAE at the paper's sizes, and their model FLOP utilisation.

Training input: one fixed real batch of 4 x 64-frame windows (the first 64
frames of the first four bandai files of the manifest's training split with
at least 64 frames; bandai human, 22 joints, 26 frame-graph nodes with end
sites), a random 256-D semantic embedding per joint (as
``benchmarks/model_cost.py``). A training step is the whole Lightning step
without logging: normalisation, model, :class:`~satagraph.losses.MotionLoss`,
backward, gradient clipping (0.5) and Adam.

- Throughput: best (and median) step time of ``--steps`` steps after one
  warm-up step; frames/s = 256 / step time, joint-frames/s = 256 x 22 / step
  time.
- Peak memory: CPU: growth of the process's peak resident set size
  (``resource.getrusage`` ``ru_maxrss``) over the warm-up and timed steps,
  from a baseline taken after the model, batch and optimizer are built; each
  model runs in its own spawned process so that the peaks do not mask each
  other. CUDA: ``torch.cuda.max_memory_allocated`` minus the memory
  allocated before the first step.
- Model FLOP utilisation (MFU): FLOPs of one training step as
  :class:`~torch.utils.flop_counter.FlopCounterMode` counts them on the
  forward, the losses and the backward (with the extra ops of
  ``model_cost.MISSED`` on the forward), divided by the best step time,
  as a fraction of the dense float32 matmul peak (best of 4096^2 and 8192^2
  on CUDA, of 1024^2 to 3072^2 on CPU, 5 products each) measured in the same
  process before and after the timed steps. The
  usual 3 x forward estimate is shown next to it.
- Inference: real-time factor (clip duration / wall time, higher is faster)
  of :func:`satagraph.pipelines.inference.retarget_motion` with SATA-VAE at paper size
  (untrained weights, normaliser fitted on the training batch) of
  ``cmu/01_01.bvh`` repeated three times (2752 frames at 120 fps, x3 = 68.8 s)
  onto the bandai skeleton: canonicalisation, features, 64-frame windows with
  16 frames of overlap in batches of 16, decoding and the BVH-ready motion.

Usage: ``python benchmarks/throughput.py [--steps 5] [--models SATA-VAE,...]
[--devices cpu,cuda] [--no-inference]``. Prints markdown tables and writes
``benchmarks/results/throughput.md`` (and ``.json``). CUDA rows are added
when a GPU is available.
"""
from __future__ import annotations

import argparse
import csv
import json
import resource
import statistics
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).resolve().parent))
from model_cost import MISSED  # noqa: E402
from results_io import SHARED_DATA, data_folder, write_results  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DATA = SHARED_DATA
#: (label, config).
MODELS = [("SATA-VAE", "sata_vae"), ("SATA-RVQ", "sata_rvq"),
          ("SAME-wide", "same_wide"), ("padded RVQ", "padded_rvq")]
CLIPS, WINDOW, SEMANTIC = 4, 64, 256
INFER_FILE, INFER_REPEATS, INFER_TARGET = "cmu/01_01.bvh", 3, "bandai"


# ----------------------------------------------------------- inputs
def training_files(data: Path, dataset: str = "bandai", count: int = CLIPS,
                   frames: int = WINDOW) -> List[str]:
    """The first :obj:`count` training files of :obj:`dataset` in the
    manifest with at least :obj:`frames` frames."""
    with open(data / "manifest.tsv", newline="") as f:
        rows = [r for r in csv.DictReader(f, delimiter="\t")
                if r["dataset"] == dataset and r["split"] == "train"
                and int(r["frames"]) >= frames]
    if len(rows) < count:
        raise ValueError(f"{data}: only {len(rows)} {dataset} files of {frames} frames")
    return [str(data / r["path"]) for r in rows[:count]]


def random_semantic(num_joints: int, channels: int = SEMANTIC) -> torch.Tensor:
    """A fixed random embedding per joint count (timing only)."""
    gen = torch.Generator().manual_seed(num_joints)
    return torch.randn(num_joints, channels, generator=gen)


def training_batch(paths: Sequence[str], window: int = WINDOW):
    """The first :obj:`window` frames of each file as one batch, and the
    files' features (for the normaliser)."""
    from satagraph.data import collate_clips
    from satagraph.data.dataset import DEFAULT_PREPROCESSING, preprocess_file
    feats = [preprocess_file(p, DEFAULT_PREPROCESSING) for p in paths]
    clips = [f.to_clip(0, window, random_semantic(f.skeleton.num_joints)) for f in feats]
    return collate_clips(clips), feats


def build_module(config: str, features, overrides: Sequence[str] = ()):
    """The LightningModule of a config with :data:`SEMANTIC` semantic
    channels and a normaliser fitted on :obj:`features`."""
    from satagraph.experiment.config import load_config
    from satagraph.experiment.train import module_class
    cfg = load_config(config, overrides)
    model = dict(cfg["model"], semantic_channels=SEMANTIC)
    module = module_class(cfg["module"])(model=model, loss=cfg.get("loss"),
                                         optim=cfg.get("optim"))
    module.normalizer.fit(features)
    return module


# ---------------------------------------------------------- measures
def synchronize(device: torch.device) -> None:
    if device.type == "cuda":
        torch.cuda.synchronize(device)


def _matmul_rate(device: torch.device, size: int, repeats: int) -> float:
    a = torch.randn(size, size, device=device)
    b = torch.randn(size, size, device=device)
    torch.mm(a, b)
    best = float("inf")
    for _ in range(repeats):
        synchronize(device)
        start = time.perf_counter()
        torch.mm(a, b)
        synchronize(device)
        best = min(best, time.perf_counter() - start)
    return 2 * size ** 3 / best / 1e9


def matmul_peak(device: torch.device, sizes: Optional[Sequence[int]] = None,
                repeats: int = 5) -> float:
    """Dense float32 matmul GFLOP/s: the best over square sizes
    (:obj:`sizes`, default 1024-3072 on CPU, 4096 and 8192 on CUDA) of
    :obj:`repeats` products each."""
    sizes = sizes or ((4096, 8192) if device.type == "cuda" else (1024, 2048, 3072))
    return max(_matmul_rate(device, size, repeats) for size in sizes)


def train_step(module, opt: torch.optim.Optimizer, batch, clip: float = 0.5) -> float:
    """One training step (model, losses, backward, clipping, Adam); the loss."""
    out = module(batch)
    loss = module.compute_losses(out, batch)["loss"]
    opt.zero_grad(set_to_none=True)
    loss.backward()
    torch.nn.utils.clip_grad_norm_(module.parameters(), clip)
    opt.step()
    return float(loss.detach())


def peak_memory(device: torch.device) -> float:
    """Peak memory so far in MB (CPU: max RSS; CUDA: max allocated)."""
    if device.type == "cuda":
        return torch.cuda.max_memory_allocated(device) / 2 ** 20
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def memory_baseline(device: torch.device) -> float:
    if device.type == "cuda":
        torch.cuda.reset_peak_memory_stats(device)
        return torch.cuda.memory_allocated(device) / 2 ** 20
    return peak_memory(device)


def count_step_flops(module, batch) -> Tuple[int, int]:
    """FLOPs of a training forward, and of forward + losses + backward."""
    from torch.utils.flop_counter import FlopCounterMode
    module.train()
    counter = FlopCounterMode(display=False, custom_mapping=MISSED)
    with counter:
        out = module(batch)
        loss = module.compute_losses(out, batch)["loss"]
    forward = counter.get_total_flops()
    with counter:
        loss.backward()
    module.zero_grad(set_to_none=True)
    return forward, forward + counter.get_total_flops()


def time_steps(step: Callable[[], Any], device: torch.device, steps: int) -> List[float]:
    """Wall time of :obj:`steps` calls (after the caller's warm-up)."""
    times = []
    for _ in range(steps):
        synchronize(device)
        start = time.perf_counter()
        step()
        synchronize(device)
        times.append(time.perf_counter() - start)
    return times


def measure_training(label: str, config: str, device: str = "cpu", steps: int = 5,
                     data: str = str(DATA), overrides: Sequence[str] = ()) -> Dict:
    """Throughput, memory and MFU of one model's training step."""
    torch.manual_seed(0)
    dev = torch.device(device)
    batch, feats = training_batch(training_files(Path(data)))
    module = build_module(config, feats, overrides).to(dev).train()
    batch = batch.to(dev)
    opt = torch.optim.Adam(module.parameters(), lr=1e-4)
    peak_before = matmul_peak(dev)
    base = memory_baseline(dev)
    train_step(module, opt, batch)  # warm-up (RVQ k-means initialisation)
    times = time_steps(lambda: train_step(module, opt, batch), dev, steps)
    memory = peak_memory(dev) - base
    forward, total = count_step_flops(module, batch)
    # The machine's speed drifts (shared cores): the peak is the best of
    # measurements before and after the steps, so that MFU is not inflated.
    peak = max(peak_before, matmul_peak(dev))
    best = min(times)
    frames = int(batch.root.shape[0])
    nodes = int((batch.clip_num_joints * batch.clip_num_frames).sum())
    return dict(model=label, config=config, device=device,
                params=sum(p.numel() for p in module.parameters() if p.requires_grad),
                steps=steps, best_s=best, median_s=statistics.median(times),
                frames=frames, nodes=nodes, frames_per_s=frames / best,
                node_frames_per_s=nodes / best, peak_mb=memory,
                forward_gflop=forward / 1e9, step_gflop=total / 1e9,
                achieved_gflops=total / best / 1e9, matmul_gflops=peak,
                mfu=total / best / 1e9 / peak, threads=torch.get_num_threads())


def tiled_motion(motion, repeats: int):
    """:obj:`motion` played :obj:`repeats` times in a row (the root jumps
    back at each repeat; timing only)."""
    return motion.with_(rotations=np.concatenate([motion.rotations] * repeats),
                        translations=np.concatenate([motion.translations] * repeats))


def measure_inference(device: str = "cpu", repeats: int = 1, data: str = str(DATA),
                      config: str = "sata_vae", overrides: Sequence[str] = (),
                      tile: int = INFER_REPEATS) -> Dict:
    """Real-time factor of sliding-window retargeting with SATA-VAE."""
    from satagraph.pipelines.inference import default_windows, retarget_motion
    from satagraph.io import read_bvh
    torch.manual_seed(0)
    dev = torch.device(device)
    _, feats = training_batch(training_files(Path(data)))
    module = build_module(config, feats, overrides).to(dev).eval()
    source = tiled_motion(read_bvh(str(Path(data) / INFER_FILE)), tile)
    target = read_bvh(training_files(Path(data), INFER_TARGET, 1)[0])

    def semantic(skeleton):
        return random_semantic(skeleton.num_joints)
    retarget_motion(module, source.slice(0, 300), target, semantic)  # warm-up
    times = time_steps(lambda: retarget_motion(module, source, target, semantic),
                       dev, repeats)
    window, overlap = default_windows(module)
    frames_30 = int(round(source.duration * 30.0))
    best = min(times)
    return dict(model="SATA-VAE", device=device, file=INFER_FILE, tile=tile,
                source_frames=source.num_frames, source_fps=source.fps,
                seconds=source.duration, frames_30fps=frames_30, window=window,
                overlap=overlap, windows=-(-(frames_30 - overlap) // (window - overlap)),
                best_s=best, median_s=statistics.median(times),
                rtf=source.duration / best, frames_per_s=frames_30 / best,
                target_joints=target.num_joints, threads=torch.get_num_threads())


def isolated(fn: Callable, *args, **kwargs):
    """:obj:`fn` in a fresh spawned process (its own peak RSS)."""
    with ProcessPoolExecutor(1, mp_context=get_context("spawn")) as pool:
        return pool.submit(fn, *args, **kwargs).result()


# ------------------------------------------------------------ tables
def training_table(rows: List[Dict]) -> str:
    lines = ["| model | device | params (M) | step (s, best / median) | frames/s "
             "| node-frames/s | peak mem (MB) | GFLOP/step fwd+bwd (3 x fwd) "
             "| GFLOP/s | matmul peak GFLOP/s | MFU |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(
            f"| {r['model']} | {r['device']} | {r['params'] / 1e6:.2f} | "
            f"{r['best_s']:.3f} / {r['median_s']:.3f} | {r['frames_per_s']:.1f} | "
            f"{r['node_frames_per_s']:.0f} | {r['peak_mb']:.0f} | "
            f"{r['step_gflop']:.1f} ({3 * r['forward_gflop']:.1f}) | "
            f"{r['achieved_gflops']:.1f} | {r['matmul_gflops']:.1f} | "
            f"{100 * r['mfu']:.1f}% |")
    return "\n".join(lines)


def inference_table(rows: List[Dict]) -> str:
    lines = ["| model | device | clip | duration (s) | windows (64, overlap 16) "
             "| wall (s, best / median) | real-time factor | frames/s (30 fps) |",
             "|---|---|---|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(
            f"| {r['model']} | {r['device']} | {r['file']} x{r['tile']} "
            f"({r['source_frames']} frames at {r['source_fps']:g} fps) | "
            f"{r['seconds']:.1f} | {r['windows']} | {r['best_s']:.2f} / "
            f"{r['median_s']:.2f} | {r['rtf']:.1f}x | {r['frames_per_s']:.0f} |")
    return "\n".join(lines)


def notes(steps: int) -> str:
    return f"""Notes:
- Input: {CLIPS} x {WINDOW}-frame windows of bandai human files (22 joints,
  26 nodes with end sites), random {SEMANTIC}-D semantic embedding; a step
  is normalisation + model + MotionLoss + backward + clipping + Adam.
  Best / median of {steps} steps after one warm-up step.
- Peak mem: CPU = growth of the peak RSS of a fresh process over the
  steps (activations, gradients, Adam states, allocator caches); CUDA =
  max_memory_allocated above the memory before the first step.
- GFLOP/step: FlopCounterMode on forward + losses + backward (matmuls,
  convolutions, attention; scatter and CPU fused attention added on the
  forward only); 3 x fwd is the usual estimate. MFU = achieved GFLOP/s /
  dense float32 matmul GFLOP/s measured in the same process (best of
  1024^2, 2048^2 and 3072^2 products, 5 each, before and after the steps).
- CPU timings share 2 cores with other jobs: compare rows of one run only.
- Inference: retarget_motion (SATA-VAE, paper size, untrained weights) of
  {INFER_FILE} played {INFER_REPEATS} times onto a bandai skeleton, end to end
  (canonicalisation, features, windows in batches of 16, decoding, BVH-ready
  motion); real-time factor = clip duration / wall time.
"""


def main(argv: Optional[Sequence[str]] = None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=data_folder, default=str(DATA))
    parser.add_argument("--steps", type=int, default=5, help="timed training steps")
    parser.add_argument("--models", default=",".join(m for m, _ in MODELS),
                        help="comma-separated model labels")
    parser.add_argument("--devices", default=None,
                        help="comma-separated devices (default: cpu, and cuda if present)")
    parser.add_argument("--infer-repeats", type=int, default=1)
    parser.add_argument("--no-inference", action="store_true")
    parser.add_argument("--merge", action="store_true",
                        help="keep the rows of other models/devices already in --out")
    parser.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "throughput"))
    args = parser.parse_args(argv)
    devices = (args.devices.split(",") if args.devices
               else ["cpu"] + (["cuda"] if torch.cuda.is_available() else []))
    wanted = [m.strip() for m in args.models.split(",")]
    unknown = set(wanted) - {m for m, _ in MODELS}
    if unknown:
        parser.error(f"unknown models {sorted(unknown)}; known: {[m for m, _ in MODELS]}")
    out = Path(args.out)
    train_rows, infer_rows = previous_rows(out) if args.merge else ([], [])
    for device in devices:
        for label, config in MODELS:
            if label in wanted:
                row = isolated(measure_training, label, config, device, args.steps,
                               args.data)
                train_rows = replace_row(train_rows, row, ("model", "device"))
                print(training_table([row]).splitlines()[-1], flush=True)
                write(out, train_rows, infer_rows, args.steps)
        if not args.no_inference:
            row = isolated(measure_inference, device, args.infer_repeats, args.data)
            infer_rows = replace_row(infer_rows, row, ("model", "device"))
    print(write(out, train_rows, infer_rows, args.steps))


def previous_rows(out: Path) -> Tuple[List[Dict], List[Dict]]:
    """Rows of an earlier run at :obj:`out` (``--merge``)."""
    path = out.with_suffix(".json")
    if not path.is_file():
        return [], []
    old = json.loads(path.read_text())
    return old.get("training", []), old.get("inference", [])


def replace_row(rows: List[Dict], row: Dict, keys: Sequence[str]) -> List[Dict]:
    """:obj:`rows` with :obj:`row` replacing the one with the same keys."""
    kept = [r for r in rows if any(r.get(k) != row[k] for k in keys)]
    return kept + [row]


def write(out: Path, train_rows: List[Dict], infer_rows: List[Dict], steps: int) -> str:
    """Write the markdown and JSON results; returns the markdown."""
    order = {m: i for i, (m, _) in enumerate(MODELS)}
    train_rows = sorted(train_rows, key=lambda r: (r["device"], order.get(r["model"], 9)))
    text = (f"## Training step\n\n{training_table(train_rows)}\n\n"
            + (f"## Inference\n\n{inference_table(infer_rows)}\n\n" if infer_rows else "")
            + notes(steps))
    write_results(out, "Throughput", text, {"training": train_rows, "inference": infer_rows,
                                            "torch": torch.__version__})
    return text


if __name__ == "__main__":
    main()
