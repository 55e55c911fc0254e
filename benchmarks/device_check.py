"""Whether satagraph runs on a GPU, in under 5 minutes of a lent one: a few
training steps of the tiny SATA-RVQ (``t2m_rvq_tiny``) and of the tiny
text-to-motion model over it (``t2m_tiny``) through Lightning on the device
with bf16 autocast (``trainer.precision=bf16-mixed``), the first resumed
for two more steps (its checkpoint holds the CUDA random state), then
``satagraph retarget --device`` by the built-in autoencoder and
``satagraph generate --device`` by the built-in text-to-motion model (the
retarget's largest difference from ``--device cpu`` printed beside it).
Endless-zoo data only: no BVH files are needed.

Each check prints one ``OK`` line with its time, or one ``FAIL`` line with
its error; the exit status is 1 if any failed, 2 (one line, nothing run)
where the device is missing.

    python benchmarks/device_check.py [--device cuda] [--steps 4] [--out DIR]

``--device cpu`` runs the same checks on the CPU (slower; a dry run of the
script itself).
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
import traceback
from pathlib import Path
from typing import Callable, Dict, List, Optional, Sequence

import numpy as np
import torch

#: Zoo-only overrides of the tiny configs: small windows and batches.
ZOO = ("data.sources=[{zoo: endless, species: [biped, quadruped], windows_per_epoch: 64, "
       "val_windows: 8, test_windows: 8, fit_windows: 16}]")


def missing_device(device: str) -> Optional[str]:
    """One line saying why :obj:`device` cannot run here (the commands'
    own :func:`~satagraph.cli.arguments.check_device`), else ``None``."""
    from satagraph.cli.arguments import check_device
    try:
        check_device(device)
    except ValueError as err:
        hint = (" (torch.cuda.is_available() is False); run it where a GPU is, or --device "
                "cpu for a dry run" if "no CUDA device" in str(err) else "")
        return f"device_check: {err}{hint}"
    if torch.device(device).type not in ("cuda", "cpu"):
        return f"device_check: --device {device}: only cuda and cpu are checked"
    return None


def trainer_overrides(device: torch.device, steps: int, run: Path) -> List[str]:
    """Overrides of a tiny config: :obj:`steps` steps on :obj:`device` in
    bf16 autocast, validated every two, written under :obj:`run`."""
    where = (["trainer.accelerator=gpu", f"trainer.devices=[{device.index or 0}]"]
             if device.type == "cuda" else ["trainer.accelerator=cpu", "trainer.devices=1"])
    return where + [ZOO, f"output_dir={run}", "trainer.precision=bf16-mixed",
                    f"trainer.max_steps={steps}", "trainer.max_epochs=null",
                    "trainer.limit_train_batches=2",  # validation (and the EMA's) every 2
                    "trainer.max_time=null", "trainer.limit_val_batches=1",
                    "trainer.enable_model_summary=false", "logger.name=csv", "threads=null"]


def train_steps(config: str, overrides: List[str], resume: bool = False) -> Path:
    """Train :obj:`config` with :obj:`overrides`; its last checkpoint."""
    from satagraph.experiment.config import load_config
    from satagraph.experiment.train import train
    module, _, trainer, run_dir = train(load_config(config, overrides), resume=resume)
    loss = trainer.callback_metrics.get("train_loss_step",
                                        trainer.callback_metrics.get("train_loss"))
    if loss is not None and not torch.isfinite(loss).all():
        raise RuntimeError(f"{config}: loss {float(loss)} after {trainer.global_step} steps")
    return run_dir / "checkpoints" / "last.ckpt"


def check_sata(device: torch.device, steps: int, out: Path) -> str:
    run = out / "sata"
    ckpt = train_steps("t2m_rvq_tiny", trainer_overrides(device, steps, run))
    train_steps("t2m_rvq_tiny", trainer_overrides(device, steps + 2, run), resume=True)
    return f"{steps} steps and 2 resumed, {ckpt}"


def check_t2m(device: torch.device, steps: int, out: Path) -> str:
    ae = out / "sata" / "checkpoints" / "last.ckpt"
    if not ae.is_file():
        raise RuntimeError("needs the sata check's checkpoint, which failed")
    overrides = trainer_overrides(device, steps, out / "t2m")
    ckpt = train_steps("t2m_tiny", overrides + [f"model.autoencoder={ae}", "data.window=48",
                                                "data.min_frames=24", "data.batch_size=8"])
    return f"{steps} steps, {ckpt}"


def zoo_files(out: Path) -> Dict[str, Path]:
    """A zoo biped's walk and a zoo quadruped as BVH files under :obj:`out`."""
    from satagraph.datasets.zoo.endless import EndlessZoo
    from satagraph.io import write_bvh
    files = {}
    for species, frames in (("biped", 90), ("quadruped", 2)):
        files[species] = out / f"{species}.bvh"
        write_bvh(EndlessZoo(species=[species], seed=0).sample(0, 0, frames).motion,
                  files[species])
    return files


def cli(*argv: str) -> None:
    """``satagraph ARGV`` in this process, its exit status checked."""
    from satagraph.cli import main
    code = main(["--traceback", *argv])
    if code:
        raise RuntimeError(f"satagraph {' '.join(argv)}: exit status {code}")


def check_retarget(device: torch.device, steps: int, out: Path) -> str:
    from satagraph.io import read_bvh
    files = zoo_files(out)
    paths = [(str(device), out / "retarget.bvh"), ("cpu", out / "retarget_on_cpu.bvh")]
    for where, path in paths:
        cli("retarget", str(files["biped"]), "--target", str(files["quadruped"]), str(path),
            "--ckpt", "builtin", "--device", where)
    moved, on_cpu = (read_bvh(str(path)) for _, path in paths)
    if not np.isfinite(moved.rotations).all():
        raise RuntimeError("non-finite rotations")
    diff = float(np.abs(moved.rotations - on_cpu.rotations).max())
    return (f"satagraph retarget --device {device}: {moved.num_frames} frames, largest "
            f"rotation difference from --device cpu {diff:.2e} degrees")


def check_generate(device: torch.device, steps: int, out: Path) -> str:
    from satagraph.io import read_bvh
    files = zoo_files(out)
    path = out / "generate.bvh"
    cli("generate", "--text", "a person walks forward", "--skeleton", str(files["biped"]),
        str(path), "--seconds", "2", "--device", str(device))
    motion = read_bvh(str(path))
    if not np.isfinite(motion.rotations).all():
        raise RuntimeError("non-finite rotations")
    return f"satagraph generate --device {device}: {motion.num_frames} frames"


CHECKS: Dict[str, Callable[[torch.device, int, Path], str]] = {
    "sata": check_sata, "t2m": check_t2m, "retarget": check_retarget,
    "generate": check_generate}


def run_checks(device: torch.device, steps: int, out: Path) -> int:
    """Every check, one line each; the number that failed."""
    failed = 0
    for name, check in CHECKS.items():
        start = time.perf_counter()
        try:
            said = check(device, steps, out)
            if device.type == "cuda":
                torch.cuda.synchronize(device)
            print(f"OK {name}: {time.perf_counter() - start:.1f} s, {said}", flush=True)
        except Exception as err:  # noqa: BLE001 - every check is run and reported
            failed += 1
            traceback.print_exc(file=sys.stderr)
            line = str(err).strip().splitlines()[0] if str(err).strip() else ""
            print(f"FAIL {name}: {time.perf_counter() - start:.1f} s, "
                  f"{type(err).__name__}: {line}", flush=True)
    return failed


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--device", default="cuda", help="cuda, cuda:1, ... (default: cuda)")
    parser.add_argument("--steps", type=int, default=4, help="training steps (default: 4)")
    parser.add_argument("--out", help="folder of the runs and BVH files (default: temporary)")
    args = parser.parse_args(argv)
    refused = missing_device(args.device)
    if refused:
        print(refused, file=sys.stderr)
        return 2
    device = torch.device(args.device)
    where = torch.cuda.get_device_name(device) if device.type == "cuda" else "CPU"
    print(f"{where}, torch {torch.__version__}", flush=True)
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="device_check_") as tmp:
        out = Path(args.out or tmp)
        out.mkdir(parents=True, exist_ok=True)
        failed = run_checks(device, args.steps, out)
    print(f"{'OK' if not failed else 'FAIL'} all: {failed} of {len(CHECKS)} failed in "
          f"{time.perf_counter() - start:.1f} s", flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
