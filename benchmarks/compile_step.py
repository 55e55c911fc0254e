"""Do ``torch.compile`` or torch-scatter speed up the SATA training step on
this machine?

Same input and step as ``benchmarks/throughput.py`` (4 x 64-frame bandai
windows, normalisation + model + losses + backward + clipping + Adam); all
variants run in one process, one after the other, so that the ratios share
the machine's state:

- ``eager``: the module as trained by ``satagraph train``;
- ``compile``: every :class:`~satagraph.nn.SpatioTemporalBlock` (where the
  FLOPs are) compiled in place with ``nn.Module.compile`` (inductor, default
  mode, shapes specialised on the first batch);
- ``compile-dynamic``: the same with ``dynamic=True``, the variant a
  training run over batches of varying node counts would need;
- ``torch-scatter``: eager with PyG's torch-scatter kernels (the optional
  ``scatter`` extra, ``make scatter``). PyG reads its switch
  ``torch_geometric.typing.WITH_TORCH_SCATTER`` at call time, so every
  other variant runs with it off and this one with it on, in one process.
  Left out, with a note, when torch-scatter is not installed.

For each: the first (compiling) step's time, best and median of ``--steps``
steps, the speed-up over eager, the loss difference from eager on the same
weights, the time of a first step on a second batch with other skeletons
(dog + ccbase), where a specialised graph recompiles, and the number of
``torch_scatter::`` operator calls in one profiled step (whether the
kernels are on the step's path at all).

Usage: ``python benchmarks/compile_step.py [--steps 5] [--config sata_vae]
[key=value ...]``. Prints a markdown table and writes
``benchmarks/results/compile.md`` (and ``.json``).
"""
from __future__ import annotations

import argparse
import contextlib
import copy
import statistics
import sys
import time
from pathlib import Path
from typing import Callable, Dict, Iterator, List, Optional, Sequence

import torch
import torch_geometric.typing as pyg_typing
from torch.profiler import ProfilerActivity, profile

from satagraph.nn import SpatioTemporalBlock

sys.path.insert(0, str(Path(__file__).resolve().parent))
from results_io import data_folder, write_results  # noqa: E402
from throughput import (DATA, build_module, time_steps, train_step,  # noqa: E402
                        training_batch, training_files)

ROOT = Path(__file__).resolve().parents[1]
#: Variant: options of ``nn.Module.compile`` (``None``: eager).
VARIANTS = {"eager": None, "compile": {}, "compile-dynamic": {"dynamic": True},
            "torch-scatter": None}
#: The variant run with PyG's torch-scatter kernels (the others without).
SCATTER = "torch-scatter"
#: Whether torch-scatter imported (PyG's switch as PyG set it at import).
SCATTER_INSTALLED = bool(pyg_typing.WITH_TORCH_SCATTER)


@contextlib.contextmanager
def pyg_scatter(enabled: bool) -> Iterator[None]:
    """PyG's torch-scatter switch set to :obj:`enabled` within the block."""
    if enabled and not SCATTER_INSTALLED:
        raise RuntimeError("torch-scatter is not installed (make scatter)")
    before = pyg_typing.WITH_TORCH_SCATTER
    pyg_typing.WITH_TORCH_SCATTER = enabled
    try:
        yield
    finally:
        pyg_typing.WITH_TORCH_SCATTER = before


def op_calls(step: Callable[[], object], prefix: str) -> int:
    """Calls of operators whose name starts with :obj:`prefix` (e.g.
    ``"torch_scatter::"``) in one profiled run of :obj:`step`."""
    with profile(activities=[ProfilerActivity.CPU]) as prof:
        step()
    return sum(e.count for e in prof.key_averages() if e.key.startswith(prefix))


def second_batch(data: Path):
    """A batch of other skeletons: two dog and one ccbase 64-frame window."""
    paths = training_files(data, "dog", 2) + training_files(data, "ccbase", 1)
    return training_batch(paths)[0]


def measure(label: str, template, batch, other, steps: int) -> Dict:
    """Step times of one variant on a copy of :obj:`template`, with PyG's
    torch-scatter switch on for :data:`SCATTER` only."""
    with pyg_scatter(label == SCATTER):
        return _measure(label, template, batch, other, steps)


def _measure(label: str, template, batch, other, steps: int) -> Dict:
    module = copy.deepcopy(template).train()
    options = VARIANTS[label]
    if options is not None:
        for block in module.modules():
            if isinstance(block, SpatioTemporalBlock):
                block.compile(**options)
    opt = torch.optim.Adam(module.parameters(), lr=1e-4)
    torch.manual_seed(0)
    start = time.perf_counter()
    first_loss = train_step(module, opt, batch)
    first = time.perf_counter() - start
    times = time_steps(lambda: train_step(module, opt, batch), torch.device("cpu"), steps)
    start = time.perf_counter()
    train_step(module, opt, other)
    other_first = time.perf_counter() - start
    scatter_ops = op_calls(lambda: train_step(module, opt, batch), "torch_scatter::")
    return dict(variant=label, first_s=first, best_s=min(times),
                median_s=statistics.median(times), first_loss=first_loss,
                other_first_s=other_first, scatter_ops=scatter_ops)


def table(rows: List[Dict]) -> str:
    eager = rows[0]
    lines = ["| variant | first step (s) | step (s, best / median) | speed-up (best) "
             "| first-step loss - eager | first step on other skeletons (s) "
             "| torch_scatter ops / step |",
             "|---|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(
            f"| {r['variant']} | {r['first_s']:.2f} | {r['best_s']:.3f} / "
            f"{r['median_s']:.3f} | {eager['best_s'] / r['best_s']:.2f}x | "
            f"{r['first_loss'] - eager['first_loss']:+.2e} | {r['other_first_s']:.2f} | "
            f"{r['scatter_ops']} |")
    return "\n".join(lines)


def main(argv: Optional[Sequence[str]] = None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=lambda t: Path(data_folder(t)), default=str(DATA))
    parser.add_argument("--steps", type=int, default=5)
    parser.add_argument("--config", default="sata_vae")
    parser.add_argument("--variants", default=",".join(VARIANTS))
    parser.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "compile"))
    parser.add_argument("overrides", nargs="*", help="config overrides, key=value")
    args = parser.parse_args(argv)
    variants = [v for v in args.variants.split(",") if v != "eager"]
    if set(variants) - set(VARIANTS):
        parser.error(f"unknown variants {sorted(set(variants) - set(VARIANTS))}; "
                     f"known: {list(VARIANTS)}")
    notes = []
    if SCATTER in variants and not SCATTER_INSTALLED:
        variants.remove(SCATTER)
        notes.append("torch-scatter is not installed: its row is left out "
                     "(`make scatter` builds it).")
    torch.manual_seed(0)
    batch, feats = training_batch(training_files(args.data))
    other = second_batch(args.data)
    template = build_module(args.config, feats, args.overrides)
    rows = []
    for label in ["eager"] + variants:
        rows.append(measure(label, template, batch, other, args.steps))
        print(table(rows).splitlines()[-1], flush=True)
    notes.append("Every variant but torch-scatter runs with PyG's torch-scatter switch "
                 "off; torch_scatter ops: operator calls in one profiled step.")
    text = (f"Config `{args.config}` {' '.join(args.overrides)}; CPU, "
            f"{torch.get_num_threads()} threads, torch {torch.__version__}; "
            f"{args.steps} timed steps after the first.\n\n{table(rows)}\n\n"
            + "\n".join(notes) + "\n")
    write_results(Path(args.out), "torch.compile and torch-scatter on the SATA training step",
                  text, {"rows": rows, "config": args.config, "overrides": args.overrides,
                         "torch": torch.__version__, "torch_scatter": SCATTER_INSTALLED})
    print(text)


if __name__ == "__main__":
    main()
