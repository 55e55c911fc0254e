"""Where a training step of the built-in model's config goes, and what
bf16, batch and window sizes buy on a CPU or a GPU (issue 16, item 4).

Builds the ``pretrain_zoo`` module (its model and loss sections; ``--width``
changes the hidden width, 256 being the paper's) on endless-zoo walks and
times whole training steps (forward, :class:`~satagraph.losses.MotionLoss`,
backward, clipping, Adam) for each combination of precision (float32, or
bf16 autocast on the CPU), batch size and window length: best and median
of ``--steps`` steps after two warm-ups, and windows and frames per second.
With ``--profile``, the top operators of one float32 step
(``torch.profiler``). ``--device cuda`` times on the GPU (synchronised;
the peak memory a step allocated is a column of its own) and profiles its
kernels.

    python benchmarks/step_cost.py [--widths 64,256] [--threads 1] [--profile] [--device cuda]

Run it on an idle machine (it times).
"""
from __future__ import annotations

import argparse
import contextlib
import statistics
import time
from typing import Dict, List, Optional, Sequence

import torch

from satagraph.data import motion_to_features
from satagraph.data.collate import collate_clips
from satagraph.datasets.zoo.endless import EndlessZoo
from satagraph.experiment.config import load_config
from satagraph.experiment.train import module_class
from satagraph.transforms import canonicalize

FRAMES = 96


def build(width: int):
    """The pretrain_zoo module at :obj:`width` (heads and feed-forward
    scaled with it) and zoo walk features of its four training plans."""
    torch.manual_seed(0)
    cfg = load_config("pretrain_zoo")
    model = dict(cfg["model"], hidden_channels=width, ff_channels=2 * width)
    module = module_class(cfg["module"])(model=model, loss=cfg["loss"],
                                         meta={"semantic_encoder": "offline", "window": 32})
    zoo = EndlessZoo(species=["biped", "quadruped", "bird", "fowl"])
    feats = [motion_to_features(canonicalize(zoo.sample(0, i, FRAMES).motion, fps=30.0))
             for i in range(16)]
    module.normalizer.fit(feats)
    return module, feats


def batches(module, feats, batch: int, window: int, count: int):
    """:obj:`count` batches of :obj:`batch` windows of :obj:`window` frames,
    on the module's device."""
    clips = [f.to_clip(a, a + window, module.embed(f.skeleton))
             for f in feats for a in range(0, FRAMES - window + 1, window // 2)]
    gen = torch.Generator().manual_seed(0)
    return [collate_clips([clips[i] for i in torch.randperm(len(clips), generator=gen)[:batch]])
            .to(_device(module)) for _ in range(count)]


def _device(module) -> torch.device:
    return next(module.parameters()).device


def _sync(device: torch.device) -> None:
    if device.type == "cuda":
        torch.cuda.synchronize(device)


def step(module, opt, batch, bf16: bool) -> None:
    kind = _device(module).type
    ctx = (torch.autocast(kind, dtype=torch.bfloat16) if bf16 else contextlib.nullcontext())
    with ctx:
        loss = module.compute_losses(module(batch), batch)["loss"]
    opt.zero_grad()
    loss.float().backward()
    torch.nn.utils.clip_grad_norm_(module.parameters(), 0.5)
    opt.step()


def time_steps(module, feats, batch: int, window: int, bf16: bool, steps: int) -> List[float]:
    opt = torch.optim.Adam(module.parameters(), lr=1e-4)
    data = batches(module, feats, batch, window, steps + 2)
    out, device = [], _device(module)
    for i, b in enumerate(data):
        _sync(device)
        start = time.perf_counter()
        step(module, opt, b, bf16)
        _sync(device)
        if i >= 2:
            out.append(time.perf_counter() - start)
    return out


def profile(module, feats, top: int = 12) -> str:
    from torch.profiler import ProfilerActivity, profile as prof
    opt = torch.optim.Adam(module.parameters(), lr=1e-4)
    data = batches(module, feats, 8, 32, 2)
    device = _device(module)
    cuda = device.type == "cuda"
    step(module, opt, data[0], False)
    activities = [ProfilerActivity.CPU] + ([ProfilerActivity.CUDA] if cuda else [])
    with prof(activities=activities) as p:
        step(module, opt, data[1], False)
        _sync(device)
    key = "self_device_time_total" if cuda else "self_cpu_time_total"
    return p.key_averages().table(sort_by=key, row_limit=top)


def peak_memory(device: torch.device) -> str:
    """GiB the steps since the last reset allocated at most (GPU only)."""
    if device.type != "cuda":
        return ""
    peak = torch.cuda.max_memory_allocated(device) / 2 ** 30
    torch.cuda.reset_peak_memory_stats(device)
    return f"{peak:.2f}"


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--widths", default="64,256")
    parser.add_argument("--batches", default="8,16")
    parser.add_argument("--windows", default="32,64")
    parser.add_argument("--steps", type=int, default=4)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--profile", action="store_true")
    parser.add_argument("--device", default="cpu", help="cpu or cuda")
    args = parser.parse_args(argv)
    torch.set_num_threads(args.threads)
    device = torch.device(args.device)
    where = torch.cuda.get_device_name(device) if device.type == "cuda" else "CPU"
    print(f"{where}, {args.threads} thread(s)\n\n| width | batch | window | precision "
          "| best step (s) | median (s) | windows/s | frames/s | bf16 speed-up "
          "| peak GiB |\n|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|")
    for width in map(int, args.widths.split(",")):
        module, feats = build(width)
        module.to(device)
        for batch in map(int, args.batches.split(",")):
            for window in map(int, args.windows.split(",")):
                best: Dict[bool, float] = {}
                for bf16 in (False, True):
                    times = time_steps(module, feats, batch, window, bf16, args.steps)
                    best[bf16] = min(times)
                    ratio = f"{best[False] / best[True]:.2f}x" if bf16 else ""
                    print(f"| {width} | {batch} | {window} | {'bf16' if bf16 else 'float32'} "
                          f"| {min(times):.3f} | {statistics.median(times):.3f} "
                          f"| {batch / min(times):.1f} | {batch * window / min(times):.0f} "
                          f"| {ratio} | {peak_memory(device)} |", flush=True)
        if args.profile:
            print(f"\nwidth {width}, batch 8, window 32, float32:\n")
            print(profile(module, feats))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
