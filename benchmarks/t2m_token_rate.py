"""Token rate of a SATA-RVQ for text-to-motion (issue 19, item 3): run
lengths of identical consecutive codes per RVQ layer on held-out windows.

SATA's RVQ gives one code stack per frame (30 per second, against MoMask's
5). Long runs of one layer-0 code would make per-frame masked modelling a
copy of the neighbours (pool tokens); short runs mean every frame carries
information (keep per-frame tokens, with a masking floor).

    .venv/bin/python benchmarks/t2m_token_rate.py --ckpt runs/t2m_rvq_tiny/checkpoints/last.ckpt

Prints a markdown table (per dataset and layer: runs, mean / median / p90
run length in frames, share of length-1 runs, distinct codes, codes per
second) and the decision rule's verdict.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Dict, List

import torch

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from satagraph.data.collate import collate_clips  # noqa: E402
from satagraph.data.caption_datamodule import CaptionDataModule  # noqa: E402
from satagraph.data.features import DYNAMIC_LAYOUT  # noqa: E402
from satagraph.nn.generators import (code_run_lengths, merge_codes, pool_codes,  # noqa: E402
                                     split_codes, unpool_codes)
from satagraph.experiment.train import load_module  # noqa: E402

#: A token covers at most this share of the mean layer-0 run: stride
#: ``floor(mean run * POOL_SHARE)`` (1: per-frame tokens).
POOL_SHARE = 2.0 / 3.0


def held_out_batches(data: CaptionDataModule, split: str, max_windows: int) -> List:
    """Batches of 8 windows of one dataset each, up to :obj:`max_windows`
    windows per dataset of :obj:`split`."""
    chosen: Dict[str, List] = {}
    ds = data.datasets[split]
    for i in range(len(ds)):
        name = ds.group(i).split("/")[0]
        if len(chosen.setdefault(name, [])) < max_windows:
            chosen[name].append(i)
    return [collate_clips([ds[i] for i in idx[k:k + 8]])
            for idx in chosen.values() for k in range(0, len(idx), 8)]


def held_out_codes(module, batches: List) -> Dict[str, List[torch.Tensor]]:
    """Per dataset, the ``[T, Q]`` codes of every window."""
    out: Dict[str, List[torch.Tensor]] = {}
    for batch in batches:
        codes = split_codes(module.codes(batch), batch.clip_num_frames)
        for meta, row, length in zip(batch.meta, codes, batch.clip_num_frames.tolist()):
            out.setdefault(str(meta["dataset"]), []).append(row[:length])
    return out


@torch.no_grad()
def pooling_error(module, batches: List, stride: int) -> Dict[str, float]:
    """Mean absolute difference of the decoded local rotations (6D) and
    root features between pooled codes (one frame's stack every
    :obj:`stride` frames, :func:`pool_codes` then :func:`unpool_codes`)
    and the per-frame codes, next to the per-frame codes' own
    reconstruction error, per dataset."""
    sums: Dict[str, List[float]] = {}
    for batch in batches:
        norm = module.normalize_batch(batch)
        lengths = batch.clip_num_frames
        codes = split_codes(module.codes(batch), lengths)
        pooled, _ = pool_codes(codes, lengths, stride, "mode")
        frames = unpool_codes(pooled, lengths, stride)
        bottleneck = module.model.bottleneck
        full = module.denormalize_output(module.decode(
            bottleneck.decode_codes(merge_codes(codes, lengths)), norm), batch)
        coarse = module.denormalize_output(module.decode(
            bottleneck.decode_codes(merge_codes(frames, lengths)), norm), batch)
        q_true = batch.x[:, DYNAMIC_LAYOUT["q"]]
        name = str(batch.meta[0]["dataset"])
        row = sums.setdefault(name, [0.0, 0.0, 0.0, 0.0, 0])
        row[0] += float((coarse["q"] - full["q"]).abs().mean())
        row[1] += float((full["q"] - q_true).abs().mean())
        row[2] += float((coarse["r"] - full["r"]).abs().mean())
        row[3] += float((full["r"] - batch.root).abs().mean())
        row[4] += 1
    return {k: tuple(x / v[4] for x in v[:4]) for k, v in sums.items()}


def run_stats(seqs: List[torch.Tensor], layer: int, fps: float) -> Dict[str, float]:
    """Run-length statistics of one layer over sequences ``[T, Q]``."""
    lengths = torch.tensor([len(s) for s in seqs])
    padded = torch.nn.utils.rnn.pad_sequence([s[:, layer] for s in seqs], batch_first=True)
    runs = code_run_lengths(padded, lengths).float()
    return {"windows": len(seqs), "frames": int(lengths.sum()), "runs": int(runs.numel()),
            "mean": float(runs.mean()), "median": float(runs.median()),
            "p90": float(runs.quantile(0.9)), "ones": float((runs == 1).float().mean()),
            "distinct": int(torch.cat([s[:, layer] for s in seqs]).unique().numel()),
            "per_second": float(runs.numel() / lengths.sum() * fps)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--ckpt", required=True)
    parser.add_argument("--data", nargs="*", default=["../shared/data/manifest.tsv"])
    parser.add_argument("--split", default="test")
    parser.add_argument("--max-windows", type=int, default=96)
    args = parser.parse_args(argv)
    torch.set_num_threads(1)
    module = load_module(args.ckpt).eval()
    semantic = module.meta.get("semantic_encoder", "offline")
    zoo = {"zoo": "endless", "species": ["biped", "quadruped", "bird", "hexapod"],
           "val_windows": args.max_windows, "test_windows": args.max_windows}
    sources = [zoo] + [{"path": p, "exclude": ["dog", "fixtures"]} for p in args.data
                       if Path(p).exists()]
    window = int(module.meta.get("window", 64))
    data = CaptionDataModule(sources, window=window, min_frames=window,
                             semantic_encoder=semantic, mirror=0.0)
    data.setup()
    batches = held_out_batches(data, args.split, args.max_windows)
    codes = held_out_codes(module, batches)
    print(f"| dataset | layer | windows | runs | mean run (frames) | median | p90 | "
          f"share of 1-frame runs | distinct codes | runs per second |\n"
          "|---|---|---|---|---|---|---|---|---|---|")
    frames = runs = 0
    for name, seqs in sorted(codes.items()):
        for layer in range(seqs[0].size(-1)):
            s = run_stats(seqs, layer, module.fps)
            if layer == 0:
                frames, runs = frames + s["frames"], runs + s["runs"]
            print(f"| {name} | {layer} | {s['windows']} | {s['runs']} | {s['mean']:.2f} | "
                  f"{s['median']:.0f} | {s['p90']:.0f} | {s['ones']:.2f} | "
                  f"{s['distinct']} | {s['per_second']:.1f} |")
    print("\n| dataset | stride | rotation change by pooling (6D, mean abs) | "
          "per-frame reconstruction error (6D) | root change by pooling | "
          "per-frame root reconstruction error |\n|---|---|---|---|---|---|")
    for stride in (2, 3, 4):
        for name, (pool_q, rec_q, pool_r, rec_r) in sorted(
                pooling_error(module, batches, stride).items()):
            print(f"| {name} | {stride} | {pool_q:.4f} | {rec_q:.4f} | {pool_r:.4f} | "
                  f"{rec_r:.4f} |")
    mean = frames / max(runs, 1)
    stride = max(1, int(mean * POOL_SHARE))
    verdict = (f"pool: {stride} (one token every {stride} frames)" if stride > 1
               else "per-frame tokens with a masking floor")
    print(f"\nlayer-0 mean run length over all windows: {mean:.2f} frames -> {verdict}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
