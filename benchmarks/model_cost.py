"""Parameters and forward GFLOPs of SATA-VAE, SATA-RVQ, SAME, SAME-wide and
the zero-padding RVQ-VAE, next to the SATA paper's figures.

Input: one 64-frame window (batch of one clip, encoded and decoded on its own
skeleton) of a real file per rig: a bandai human (22 joints), the dog (21
joints) and the ccbase CC_Base rig (100 joints); end sites are leaf nodes of
the frame graphs, so the node counts are larger (see the table).

FLOPs are counted with :class:`torch.utils.flop_counter.FlopCounterMode`
(2 FLOPs per multiply-add of matmuls, convolutions and attention; element-wise
ops, norms and softmax are not counted). It misses some ops, which are added by
a custom mapping and reported in their own column:

- ``aten.scatter_add_`` / ``scatter_reduce_`` / ``index_add_`` (PyG message
  aggregation and the GAT softmax): 1 FLOP per source element;
- ``aten._scaled_dot_product_flash_attention_for_cpu`` (the CPU kernel of
  fused attention; only the CUDA kernels are registered): the SDPA formula;
- the multi-head-attention inference fast path is disabled
  (``torch.backends.mha.set_fastpath_enabled(False)``), otherwise the
  whole attention block runs as one uncounted op.

Usage: ``python benchmarks/model_cost.py [--data ../shared/data]``. Prints a
markdown table and writes it to ``benchmarks/results/model_cost.md`` (and
``.json``).
"""
from __future__ import annotations

import argparse
from pathlib import Path
from typing import Dict, List, Tuple

import torch
from torch import nn
from torch.utils.flop_counter import FlopCounterMode, flop_registry, sdpa_flop_count

from results_io import SHARED_DATA, data_folder, write_results
from satagraph.experiment.config import load_config
from satagraph.data import collate_clips
from satagraph.data.dataset import DEFAULT_PREPROCESSING, preprocess_file
from satagraph.nn.bottlenecks.rvq import RVQBottleneck
from satagraph.experiment.train import module_class

ROOT = Path(__file__).resolve().parents[1]
aten = torch.ops.aten

#: (label, file under the data folder, joints in the manifest).
INPUTS = [("bandai human", "bandai/dataset-1_bow_active_001.bvh", 22),
          ("dog", "dog/D1_001_KAN01_001.bvh", 21),
          ("ccbase", "ccbase/006_01.bvh", 100)]
#: (label, config, paper parameters in M, paper GFLOPs).
MODELS = [("SATA-VAE", "sata_vae", 8.41, 29.66), ("SATA-RVQ", "sata_rvq", None, None),
          ("SAME", "same", None, None), ("SAME-wide", "same_wide", 5.98, 20.21),
          ("padded RVQ", "padded_rvq", None, None)]
WINDOW, SEMANTIC = 64, 256


# ------------------------------------------------------ missed ops
def _source_elements(*args, out_shape=None, **kwargs) -> int:
    """1 FLOP per element of the source (the last tensor argument of
    ``scatter_add_(self, dim, index, src)``, ``index_add_(..., source)``)."""
    sizes = [a.numel() for a in args if isinstance(a, torch.Size)]
    return sizes[-1] if sizes else 0


def _sdpa_cpu(query, key, value, *args, out_shape=None, **kwargs) -> int:
    return sdpa_flop_count(query, key, value)


MISSED = {aten.scatter_add_: _source_elements, aten.scatter_add: _source_elements,
          aten.scatter_reduce_: _source_elements, aten.scatter_reduce: _source_elements,
          aten.index_add_: _source_elements, aten.index_add: _source_elements,
          aten._scaled_dot_product_flash_attention_for_cpu: _sdpa_cpu}
MISSED = {k: v for k, v in MISSED.items() if k not in flop_registry}


# ----------------------------------------------------------- inputs
def load_window(data: Path, path: str):
    """The first :data:`WINDOW` frames of a file as a one-clip batch, with a
    random :data:`SEMANTIC`-D joint embedding."""
    feats = preprocess_file(str(data / path), DEFAULT_PREPROCESSING)
    if feats.num_frames < WINDOW:
        raise ValueError(f"{path}: {feats.num_frames} frames < {WINDOW}")
    gen = torch.Generator().manual_seed(0)
    semantic = torch.randn(feats.skeleton.num_joints, SEMANTIC, generator=gen)
    return collate_clips([feats.to_clip(0, WINDOW, semantic)])


def build_model(config: str) -> nn.Module:
    cfg = load_config(config)
    model = dict(cfg["model"], semantic_channels=SEMANTIC)
    return module_class(cfg["module"])(model=model).model


def count_parameters(model: nn.Module) -> int:
    return sum(p.numel() for p in model.parameters() if p.requires_grad)


@torch.no_grad()
def count_flops(model: nn.Module, batch) -> Tuple[int, int]:
    """Forward FLOPs as FlopCounterMode counts them, and the missed ones."""
    if any(isinstance(m, RVQBottleneck) for m in model.modules()):
        model.train()(batch)  # k-means initialisation of the codebooks
        model.eval()(batch)  # its first eval pass does extra (lazy) work
    model.eval()
    counter = FlopCounterMode(display=False, custom_mapping=MISSED)
    with counter:
        model(batch)
    per_op = counter.get_flop_counts()["Global"]
    missed = sum(v for k, v in per_op.items() if k in MISSED)
    return counter.get_total_flops() - missed, missed


# ------------------------------------------------------------ table
def measure(data: Path) -> List[Dict]:
    batches = [(label, joints, load_window(data, path)) for label, path, joints in INPUTS]
    rows = []
    for name, config, paper_params, paper_gflops in MODELS:
        model = build_model(config)
        params = count_parameters(model)
        for label, joints, batch in batches:
            counted, missed = count_flops(model, batch)
            rows.append(dict(model=name, config=config, params=params, input=label,
                             joints=joints, nodes=int(batch.num_nodes // WINDOW),
                             counted=counted, missed=missed, paper_params=paper_params,
                             paper_gflops=paper_gflops))
    return rows


def _fmt(value, digits: int = 2) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def markdown(rows: List[Dict]) -> str:
    head = ("| model | params (M) | input (joints / nodes, 64 frames) | GFLOPs counted "
            "| + missed ops | GFLOPs total | paper params (M) | paper GFLOPs |\n"
            "|---|---:|---|---:|---:|---:|---:|---:|")
    lines = [head]
    for r in rows:
        lines.append(
            f"| {r['model']} | {r['params'] / 1e6:.2f} | {r['input']} ({r['joints']} / "
            f"{r['nodes']}) | {r['counted'] / 1e9:.2f} | {r['missed'] / 1e9:.3f} | "
            f"{(r['counted'] + r['missed']) / 1e9:.2f} | {_fmt(r['paper_params'])} | "
            f"{_fmt(r['paper_gflops'])} |")
    return "\n".join(lines) + "\n\n" + NOTES


NOTES = f"""Notes:
- Input: one {WINDOW}-frame window, batch of one clip, encoder + bottleneck +
  decoder on its own skeleton; end sites are nodes. Semantic width D_t = {SEMANTIC}
  (random embedding; the width at which SATA-VAE has the paper's 8.41 M).
  The SATA paper does not say what input its GFLOPs are for.
- GFLOPs = 2 x multiply-adds of matmuls, convolutions and attention, as
  torch.utils.flop_counter.FlopCounterMode counts them (eval mode, MHA fast
  path disabled); element-wise ops, norms, softmax and activations are not
  counted (tools that report MACs give half these numbers).
- "missed ops": what FlopCounterMode does not count, added with a custom
  mapping: scatter_add_ / scatter_reduce_ / index_add_ (PyG aggregation, GAT
  softmax; 1 FLOP per source element) and the CPU fused-attention kernel
  _scaled_dot_product_flash_attention_for_cpu (SDPA formula).
- Parameters are trainable ones: the RVQ codebooks are EMA buffers, not
  parameters (SATA-RVQ: 6 x 1024 x 256 = 1.57 M more values; padded RVQ:
  6 x 512 x 512 = 1.57 M more).
- SAME: SAME's own widths (16 heads x 16, 32-D latent). SAME-wide: hidden
  1152 (16 x 72), 128-D latent, SAME's depth (experiments/same_wide.yaml).
- Padded RVQ: J_max = 142 (every skeleton in ../shared/data), so its cost
  hardly depends on the skeleton; MoMask sizes (width 512, 6 x 512 codes).
"""


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=data_folder, default=str(SHARED_DATA))
    parser.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "model_cost"))
    args = parser.parse_args()
    torch.backends.mha.set_fastpath_enabled(False)
    torch.manual_seed(0)
    rows = measure(Path(args.data))
    table = markdown(rows)
    print(table)
    write_results(Path(args.out), "Model cost", table, rows)


if __name__ == "__main__":
    main()
