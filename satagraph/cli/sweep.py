"""``satagraph sweep``: train several configs for the same wall-clock budget
(or the same number of steps) and compare them in one table.

Example::

    satagraph sweep --budget 30 --output sweeps/gnn \\
        sata_vae ablation_no_gnn gnn_gin trainer.accelerator=cpu data.batch_size=16
    satagraph sweep --steps 2000 --output sweeps/gnn_steps sata_vae gnn_gin

Options go before the configs and overrides (argparse does not take
positional items on both sides of an option). ``config=NAME`` names a
config too, which is how a wandb sweep agent passes it
(``experiments/sweeps/wandb_sweep.yaml``).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import List


#: Training minutes per config without --budget or --steps.
DEFAULT_BUDGET = 5.0


def add_sweep_parser(sub: "argparse._SubParsersAction") -> argparse.ArgumentParser:
    """Register the ``sweep`` subcommand.

    Args:
        sub: The object returned by
            :meth:`argparse.ArgumentParser.add_subparsers`.

    Returns:
        argparse.ArgumentParser: The ``sweep`` parser (``func``:
        :func:`run_sweep_command`).
    """
    p = sub.add_parser(
        "sweep", help="train configs for the same time or steps and tabulate",
        description="Train each CONFIG for the same wall-clock budget "
        "(trainer.max_time), or the same number of steps (--steps: equal work, the "
        "table's train (min) column comparing their speed), on the first config's data, "
        "evaluate each on the "
        "test split (--split val: the validation split, to choose among them) and write "
        "sweep.md and sweep.json (one row per config) "
        "into --output. key=value items override every config. Each config keeps its "
        "own model, losses, optimiser and trainer settings: the table lists every "
        "setting the rows differ in. Every config is checked before any trains; one "
        "that fails while training is a row saying why, and the others go on (exit "
        "code 2). For example: satagraph sweep --budget 10 sata_vae gnn_gin "
        "ablation_no_gnn data.batch_size=8")
    p.add_argument("items", nargs="+", metavar="CONFIG|key=value",
                   help="config names or paths, and dotted overrides for all")
    budget = p.add_mutually_exclusive_group()
    budget.add_argument("--budget", type=float, default=None, metavar="MINUTES",
                        help=f"training minutes per config (default {DEFAULT_BUDGET:g})")
    budget.add_argument("--steps", type=int, default=None, metavar="N",
                        help="train each config N optimizer steps instead (equal work "
                        "rather than equal time)")
    p.add_argument("--output", default="sweeps/latest", metavar="DIR",
                   help="output folder (default sweeps/latest)")
    p.add_argument("--retarget", action="store_true",
                   help="also the retarget error of the test files in the internal "
                   "(bone-scaled) and cross (restructured) settings")
    p.add_argument("--logger", default="csv",
                   choices=["csv", "tensorboard", "wandb", "none", "config"],
                   help="training logger (default csv; wandb: online, for a wandb "
                   "sweep agent; config: each config's own)")
    p.add_argument("--resume", action="store_true",
                   help="go on with a sweep stopped in --output (the same configs, "
                   "overrides and budget): its finished rows are kept, a config it "
                   "stopped in goes on from its last.ckpt with the rest of its budget")
    p.add_argument("--split", choices=("val", "test"), default="test",
                   help="the split every row is scored on (default test, to report rows "
                   "chosen; val to choose among them, leaving the test split untouched)")
    p.add_argument("--max-batches", type=int, default=None,
                   help="evaluation batches per config (default: all; the table says so)")
    p.set_defaults(func=run_sweep_command)
    return p


def run_sweep_command(args: argparse.Namespace) -> int:
    """Run a sweep from parsed arguments and print its table; exit code 1
    (one line on stderr) when another live sweep holds the output folder."""
    from satagraph.experiment.sweep import run_sweep, split_arguments
    from satagraph.lightning.reliability import RunLockedError
    configs, overrides = split_arguments(args.items)
    if not configs:
        raise ValueError("sweep: name at least one config")
    budget = DEFAULT_BUDGET if args.budget is None else args.budget
    if not budget > 0:
        raise ValueError(f"sweep: --budget must be positive, got {budget}")
    logger = None if args.logger == "config" else args.logger
    try:
        rows = run_sweep(configs, budget, args.output, overrides, retarget=args.retarget,
                         max_batches=args.max_batches, logger=logger, resume=args.resume,
                         split=args.split, steps=args.steps)
    except RunLockedError as err:  # another sweep writes there
        print(f"satagraph: error: {err}", file=sys.stderr)
        return 1
    print((Path(args.output) / "sweep.md").read_text(encoding="utf-8"))
    return 2 if any(r.error for r in rows) else 0


__all__: List[str] = ["add_sweep_parser", "run_sweep_command"]
