r"""Exact resume after ``kill -9``: losses step by step against a run that
was never stopped.

A tiny SATA-VAE trains on a small procedural zoo (no data needed) with the
documented deterministic CPU settings (``threads=1``,
``trainer.deterministic=true``, ``OMP_NUM_THREADS=1``), on-the-fly
augmentation and dropout on, a checkpoint every ``--every`` steps and
``loss_log=true``. The reference run goes to the end; then, for each kill
point (steps drawn with ``--seed``, 0 by default, unless ``--at`` gives
them), a fresh run is killed with ``SIGKILL`` once it has logged that step
and continued with ``--resume``. Writes ``benchmarks/results/resume.md``.
The kill points repeat from run to run (they were drawn unseeded unless
``--seed`` was given, so no two tables killed at the same steps); the step
a kill lands after may still run on by one or two where the machine is slow.

Usage::

    .venv/bin/python benchmarks/resume.py [--kills 3] [--every 5] [--epochs 4]
"""
from __future__ import annotations

import argparse
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Dict, List, Optional, Sequence

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from satagraph.datasets.zoo import write_zoo  # noqa: E402
from satagraph.utils.files import atomic_write_text  # noqa: E402
from satagraph.lightning.reliability import read_loss_log  # noqa: E402


def overrides(root: Path, every: int, epochs: int) -> List[str]:
    return [f"data.sources=[{root / 'zoo' / 'manifest.tsv'}]",
            f"data.cache_dir={root / 'cache'}", "data.window=16", "data.stride=16",
            "data.batch_size=4", "data.max_files=null", "data.augment.scale=0.5",
            "model.dropout=0.1", "logger.name=none", "trainer.progress=false",
            "trainer.enable_model_summary=false", f"trainer.max_epochs={epochs}",
            "trainer.limit_train_batches=null", "trainer.limit_val_batches=1",
            "trainer.deterministic=true", "threads=1", f"checkpoint.every_n_steps={every}",
            "loss_log=true"]


def command(args: Sequence[str]) -> List[str]:
    return [sys.executable, "-m", "satagraph", "train", "tiny", *args]


ENV = dict(os.environ, OMP_NUM_THREADS="1", PYTHONPATH=str(REPO))


def kill_at(cmd: List[str], log: Path, step: int) -> int:
    """Run :obj:`cmd`; ``SIGKILL`` once :obj:`log` has :obj:`step` lines;
    the last step logged."""
    proc = subprocess.Popen(cmd, env=ENV, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    while proc.poll() is None:
        if log.is_file() and len(log.read_text().splitlines()) >= step:
            break
        time.sleep(0.02)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    return max(read_loss_log(log))


#: Seed of the drawn kill points (``--seed``).
DEFAULT_SEED = 0


def kill_points(steps: int, every: int, count: int, seed: int = DEFAULT_SEED) -> List[int]:
    """:obj:`count` steps to kill after, drawn with :obj:`seed` between the
    first checkpoint and the run's last step."""
    return sorted(random.Random(seed).sample(range(every + 1, steps - 1), count))


def checkpoint_step(path: Path) -> int:
    import torch
    return int(torch.load(path, map_location="cpu", weights_only=True)["global_step"])


def run(root: Path, kills: Optional[List[int]], count: int, every: int,
        epochs: int, seed: int = DEFAULT_SEED) -> str:
    write_zoo(root / "zoo", species=["biped", "quadruped"], clips=3, frames=48)
    base = overrides(root, every, epochs)
    start = time.monotonic()
    subprocess.run(command(base + [f"output_dir={root / 'ref'}"]), env=ENV, check=True,
                   capture_output=True)
    reference = read_loss_log(root / "ref" / "losses.tsv")
    steps = len(reference)
    drawn = not kills
    kills = kills or kill_points(steps, every, count, seed)
    rows, detail = [], ""
    for k, kill in enumerate(kills):
        out = root / f"run{k}"
        args = base + [f"output_dir={out}"]
        killed = kill_at(command(args), out / "losses.tsv", kill)
        saved = checkpoint_step(out / "checkpoints" / "last.ckpt")
        subprocess.run(command(args + ["--resume"]), env=ENV, check=True,
                       capture_output=True)
        resumed = read_loss_log(out / "losses.tsv")
        after = [s for s in reference if s > saved]
        diff = max(abs(resumed[s] - reference[s]) for s in after)
        same = all(resumed[s] == reference[s] for s in reference)
        rows.append(f"| {killed} | {saved} | {killed - saved} | {len(after)} | "
                    f"{diff:.3g} | {'yes' if same else 'NO'} |")
        if k == 0:
            detail = _detail(reference, resumed, saved)
    return (f"Tiny SATA-VAE on a 16-clip zoo (biped, quadruped), batch 4, window 16, "
            f"augmentation and dropout on; {steps} steps ({epochs} epochs of "
            f"{steps // epochs}), a checkpoint every {every} steps and at every epoch end; "
            "`threads=1 trainer.deterministic=true`, `OMP_NUM_THREADS=1`. Each run is "
            "killed with SIGKILL once it has logged the step, then continued with "
            "`satagraph train ... --resume`"
            + (f" (kill points drawn with --seed {seed})" if drawn else "") + ".\n\n"
            "| killed after step | resumed from step | steps lost | steps compared "
            "| max abs loss difference | every step identical |\n|---|---|---|---|---|---|\n"
            + "\n".join(rows) + f"\n\nFirst kill, step by step:\n\n{detail}\n"
            f"Total {time.monotonic() - start:.0f} s.\n")


def _detail(reference: Dict[int, float], resumed: Dict[int, float], saved: int) -> str:
    lines = ["| step | uninterrupted | resumed |", "|---|---|---|"]
    for s in sorted(reference):
        if saved - 2 <= s <= saved + 6:
            mark = " (first resumed step)" if s == saved + 1 else ""
            lines.append(f"| {s}{mark} | {reference[s]!r} | {resumed[s]!r} |")
    return "\n".join(lines) + "\n"


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--kills", type=int, default=3, help="random kill points")
    parser.add_argument("--seed", type=int, default=DEFAULT_SEED,
                        help=f"seed of the kill points (default {DEFAULT_SEED}, said in the "
                        "table)")
    parser.add_argument("--at", type=int, nargs="*", help="kill after these steps")
    parser.add_argument("--every", type=int, default=5)
    parser.add_argument("--epochs", type=int, default=4)
    parser.add_argument("--out", type=Path, default=REPO / "benchmarks" / "results" /
                        "resume.md")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="satagraph-resume-") as tmp:
        text = run(Path(tmp), args.at, args.kills, args.every, args.epochs, args.seed)
    atomic_write_text(args.out, "# Exact resume after kill -9\n\n" + text)
    print(text)
    return 0 if "| NO |" not in text else 1


if __name__ == "__main__":
    sys.exit(main())
