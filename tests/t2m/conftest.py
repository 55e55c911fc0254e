"""Fixtures of the text-to-motion tests: an untrained tiny SATA-RVQ saved as
a checkpoint (random codebooks, normaliser fitted on zoo windows), a tiny
text-to-motion module on it and its checkpoint, and zoo skeleton files."""
from __future__ import annotations

from pathlib import Path

import pytest
import torch

from satagraph.data.datamodule import semantic_embedder
from satagraph.datasets.zoo import zoo_rigs
from satagraph.datasets.zoo.dialects import export_dialect
from satagraph.datasets.zoo.endless import EndlessZoo
from satagraph.datasets.zoo.motions import generate_clip
from satagraph.data.captioned import ZooCaptionWindows
from satagraph.io import write_bvh
from satagraph.lightning import SATARVQModule
from satagraph.lightning.text_to_motion import TextToMotionModule
from tests.conftest import save_module_checkpoint

#: Sizes of the tiny autoencoder and generators.
AE_MODEL = {"hidden_channels": 16, "heads": 2, "ff_channels": 32, "num_blocks": 1,
            "dropout": 0.0, "latent_channels": 16, "num_quantizers": 3, "codebook_size": 32,
            "kmeans_init": False, "semantic_channels": 256}
T2M_MODEL = {"text_encoder": "offline:32",
             "skeleton": {"hidden_channels": 16, "out_channels": 16, "heads": 2,
                          "num_layers": 1},
             "masked": {"hidden_channels": 32, "heads": 2, "num_layers": 1, "dropout": 0.0,
                        "mask_floor": 0.2, "pool": 2},
             "residual": {"hidden_channels": 32, "heads": 2, "num_layers": 1, "dropout": 0.0,
                          "pool": 2},
             "length": {"hidden_channels": 16, "max_seconds": 3.0, "dropout": 0.0}}


def zoo_windows(count: int = 8, mirror: float = 0.0, seed: int = 0,
                species=("biped", "quadruped"), scale: float = 0.0) -> ZooCaptionWindows:
    """Captioned zoo clips of 16 to 40 frames."""
    return ZooCaptionWindows(EndlessZoo(species=list(species), seed=seed), count, 40, 16,
                             semantic=semantic_embedder("offline"), mirror=mirror, seed=seed,
                             scale=scale)


save_checkpoint = save_module_checkpoint  # the name this folder's tests import


@pytest.fixture(scope="session")
def autoencoder_ckpt(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """An untrained tiny SATA-RVQ checkpoint with a fitted normaliser."""
    torch.manual_seed(0)
    module = SATARVQModule(model=dict(AE_MODEL), meta={
        "module": "rvq", "semantic_encoder": "offline", "window": 32})
    zoo = EndlessZoo(species=["biped", "quadruped"], seed=0)
    from satagraph.transforms.canonical import canonicalize
    from satagraph.data.features import motion_to_features
    feats = [motion_to_features(canonicalize(zoo.sample(0, i, 33).motion, up_axis="+Y",
                                             unit_scale=1.0)) for i in range(4)]
    module.normalizer.fit(feats, [f"zoo {i}" for i in range(4)])
    return save_checkpoint(module, tmp_path_factory.mktemp("ae") / "rvq.ckpt")


def build_t2m(autoencoder_ckpt: Path, seed: int = 0) -> TextToMotionModule:
    """A tiny untrained text-to-motion module on the test autoencoder."""
    torch.manual_seed(seed)
    return TextToMotionModule(model=dict(T2M_MODEL, autoencoder=str(autoencoder_ckpt)),
                              meta={"module": "t2m", "semantic_encoder": "offline"})


@pytest.fixture(scope="session")
def t2m_ckpt(autoencoder_ckpt: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A checkpoint of a tiny text-to-motion module trained for a few steps."""
    module = build_t2m(autoencoder_ckpt)
    batch = zoo_batch()
    opt = torch.optim.AdamW([p for p in module.parameters() if p.requires_grad], 3e-3)
    module.train()
    for step in range(3):
        loss = module.compute_losses(batch, torch.Generator().manual_seed(step))["loss"]
        opt.zero_grad()
        loss.backward()
        opt.step()
    return save_checkpoint(module.eval(), tmp_path_factory.mktemp("t2m") / "t2m.ckpt")


def zoo_batch(count: int = 6, mirror: float = 0.0):
    """A collated batch of captioned zoo clips (training keys)."""
    from satagraph.data.collate import collate_clips
    ds = zoo_windows(count, mirror)
    return collate_clips([ds[(0, i)] for i in range(count)])


@pytest.fixture(scope="session")
def zoo_skeletons(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """BVH files of a zoo biped (+Z up, centimetres), quadruped and bird
    (+Y up, metres)."""
    folder = tmp_path_factory.mktemp("skeletons")
    out = {}
    for rig in zoo_rigs(["biped", "quadruped", "bird"], seed=3):
        if rig.species in out:
            continue
        motion = generate_clip(rig, "walk", frames=12, seed=0)
        if rig.species == "biped":
            motion = export_dialect(motion, "+Z", 0.01)
        path = folder / f"{rig.species}.bvh"
        write_bvh(motion, path)
        out[rig.species] = path
    return out


def tiny_train_overrides(autoencoder_ckpt: Path, run: Path, windows: int = 8) -> list:
    """Overrides of ``t2m_tiny`` for a few steps of the tiny module on
    :obj:`windows` zoo bipeds an epoch (two epochs, one validation batch)."""
    out = [f"model.autoencoder={autoencoder_ckpt}", f"output_dir={run}",
           "model.text_encoder=offline:32",
           f"data.sources=[{{zoo: endless, species: [biped], windows_per_epoch: {windows}, "
           "val_windows: 4, test_windows: 4}]",
           "data.window=24", "data.min_frames=12", "data.batch_size=4",
           "trainer.max_epochs=2", "trainer.max_time=null", "trainer.limit_val_batches=1",
           "trainer.enable_model_summary=false", "loss_log=false"]
    for key in ("skeleton", "masked", "residual", "length"):
        out += [f"model.{key}.{k}={v}" for k, v in T2M_MODEL[key].items()]
    return out
