"""How long ``satagraph generate`` takes (issue 19 target: a 4-second
motion in under 1 s on 2 CPU cores, 10 decoding steps, guidance on).

For each model size (the generator and its SATA-RVQ of a config, weights
untrained: time does not depend on their values), one 4-second motion on
a zoo biped and on a zoo quadruped, timed with 1 and 2 torch threads:
median and worst of ``--reps`` generations after one warm-up. Model load,
file reading and writing are left out (the CLI prints them apart).

    .venv/bin/python benchmarks/t2m_speed.py [--reps 5]

Run it on an idle machine: another busy process makes the 2-thread rows
meaningless (the threads wait for each other).
"""
from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Dict, List

import torch

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from satagraph.data.features import motion_to_features  # noqa: E402
from satagraph.datasets.zoo.endless import EndlessZoo  # noqa: E402
from satagraph.experiment.config import load_config  # noqa: E402
from satagraph.lightning import SATARVQModule  # noqa: E402
from satagraph.lightning.text_to_motion import TextToMotionModule  # noqa: E402
from satagraph.pipelines.generate import GenerationSettings, generate_on  # noqa: E402
from satagraph.transforms.canonical import canonicalize  # noqa: E402

#: (row name, generator config, autoencoder config).
SIZES = (("t2m_tiny", "t2m_tiny", "t2m_rvq_tiny"), ("t2m_cpu", "t2m_cpu", "t2m_rvq_cpu"),
         ("t2m_builtin (SATA-RVQ of the built-in model's size)", "t2m_builtin",
          "t2m_rvq_from_builtin"),
         ("t2m (paper-sized SATA-RVQ)", "t2m", "sata_rvq"))


def build(generator: str, autoencoder: str, folder: Path) -> TextToMotionModule:
    """An untrained generator of config :obj:`generator` over an untrained
    SATA-RVQ of config :obj:`autoencoder`."""
    ae_cfg = load_config(autoencoder)
    torch.manual_seed(0)
    ae = SATARVQModule(model=dict(ae_cfg["model"], semantic_channels=256),
                       meta={"module": "rvq", "semantic_encoder": "offline", "window": 64})
    zoo = EndlessZoo(species=["biped", "quadruped"])
    feats = [motion_to_features(canonicalize(zoo.sample(0, i, 40).motion, up_axis="+Y",
                                             unit_scale=1.0)) for i in range(4)]
    ae.normalizer.fit(feats, [f"zoo {i}" for i in range(4)])
    path = folder / f"{autoencoder}.ckpt"
    torch.save({"state_dict": ae.state_dict(), "hyper_parameters": dict(ae.hparams)}, path)
    cfg = load_config(generator)
    return TextToMotionModule(model=dict(cfg["model"], autoencoder=str(path)),
                              meta={"module": "t2m", "semantic_encoder": "offline"}).eval()


def time_generation(module, target, threads: int, reps: int,
                    plant: bool = False) -> List[float]:
    torch.set_num_threads(threads)
    settings = GenerationSettings(steps=10, plant=plant)
    generate_on(module, "a person walks forward", target, 4.0, 0, settings)  # warm-up
    out = []
    for seed in range(reps):
        start = time.perf_counter()
        generate_on(module, "a person walks forward and turns to the left", target, 4.0,
                    seed, settings)
        out.append(time.perf_counter() - start)
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--reps", type=int, default=5)
    parser.add_argument("--plant", action="store_true",
                        help="plant the feet of each generated motion (generate --plant)")
    args = parser.parse_args(argv)
    zoo = EndlessZoo(species=["biped", "quadruped"])
    targets = {"zoo biped": zoo.sample(0, 0, 40, "test").motion,
               "zoo quadruped": zoo.sample(0, 1, 40, "test").motion}
    rows: List[Dict[str, object]] = []
    with tempfile.TemporaryDirectory() as tmp, torch.no_grad():
        for name, generator, autoencoder in SIZES:
            module = build(generator, autoencoder, Path(tmp))
            params = sum(p.numel() for n, p in module.named_parameters()
                         if not n.startswith("autoencoder."))
            ae_params = sum(p.numel() for p in module.autoencoder.parameters())
            for target_name, target in targets.items():
                for threads in (1, 2):
                    times = time_generation(module, target, threads, args.reps, args.plant)
                    rows.append(dict(size=name, params=params, ae_params=ae_params,
                                     target=target_name, threads=threads,
                                     median=statistics.median(times), worst=max(times)))
    print("| model | generator params | SATA-RVQ params | skeleton | threads | median (s) "
          "| worst (s) | under 1 s |")
    print("|---|---:|---:|---|---:|---:|---:|---|")
    for r in rows:
        print(f"| {r['size']} | {r['params'] / 1e6:.2f} M | {r['ae_params'] / 1e6:.2f} M | "
              f"{r['target']} | {r['threads']} | {r['median']:.3f} | {r['worst']:.3f} | "
              f"{'yes' if r['worst'] < 1.0 else 'no'} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
