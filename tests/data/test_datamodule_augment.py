"""On-the-fly skeleton augmentation of training windows (``data.augment``)."""
from pathlib import Path

import numpy as np
import pytest
import torch

from satagraph.transforms.augment import mirror_pairs
from satagraph.data.datamodule import MotionDataModule
from satagraph.data.dataset import WindowAugment
from satagraph.datasets.zoo import write_zoo

ALL_OPS = {"scale": 1.0, "mirror": 0.5, "drop": 0.5, "merge": 0.5, "insert": 0.5}


@pytest.fixture(scope="module")
def zoo(tmp_path_factory) -> Path:
    """A small zoo: 4 bipeds and 4 quadrupeds, 3 clips of 40 frames each
    (train, train, val), one held-out test skeleton per species."""
    out = tmp_path_factory.mktemp("zoo")
    write_zoo(out, species=["biped", "quadruped"], clips=3, frames=40)
    return out / "manifest.tsv"


def datamodule(zoo: Path, augment=None, seed: int = 0,
               window: int = 16) -> MotionDataModule:
    """A set-up data module of the zoo, its features cached beside it (one
    cache a module: each file is preprocessed once)."""
    dm = MotionDataModule(str(zoo), window=window, stride=window, batch_size=8,
                          semantic_encoder="offline", cache_dir=str(zoo.parent / "cache"),
                          augment=augment, seed=seed)
    dm.setup("fit")
    return dm


def batches(loader, count: int = 2) -> list:
    out = []
    for batch in loader:
        out.append(batch)
        if len(out) == count:
            break
    return out


def test_config_section():
    assert WindowAugment.from_config(None) is None
    assert WindowAugment.from_config(False) is None
    default = WindowAugment.from_config(True)
    assert default.p_mirror == 0.5 and default.skeleton_augment["p_scale"] == 0.5
    custom = WindowAugment.from_config({"drop": 0.2, "low": 0.5, "high": 2.0})
    assert custom.skeleton_augment["p_drop"] == 0.2
    assert custom.skeleton_augment["scale_range"] == (0.5, 2.0)
    with pytest.raises(ValueError, match="unknown keys"):
        WindowAugment.from_config({"rotate": 0.5})
    with pytest.raises(ValueError, match="must be in"):
        WindowAugment.from_config({"drop": 1.5})
    with pytest.raises(ValueError, match="low <= high"):
        WindowAugment.from_config({"low": 1.2, "high": 0.8})


def test_off_by_default(zoo):
    dm = datamodule(zoo)
    assert dm.augment is None
    assert not dm.train_dataloader().sampler.keys  # plain indices


def test_no_op_augmentation_is_lossless(zoo):
    """All probabilities 0: the window goes through motion and back
    unchanged, including the velocities of its first frame."""
    dm = datamodule(zoo, augment={"scale": 0.0, "mirror": 0.0})
    ds = dm.datasets["train"]
    for idx in (0, 1, 2):  # starts 0, 16, 32 of the first file
        raw, aug = ds[idx], ds[(0, idx)]
        assert aug.meta["start"] == raw.meta["start"]
        for name in ("dynamic", "root", "static", "semantic", "edge_attr"):
            torch.testing.assert_close(getattr(aug, name), getattr(raw, name),
                                       atol=1e-4, rtol=1e-4)


def test_mirror_reflects_the_window(zoo):
    """Mirroring reflects positions in the facing frame and swaps the data
    of left and right joints; the turning rate and sideways speed flip."""
    dm = datamodule(zoo, augment={"scale": 0.0, "mirror": 1.0})
    ds = dm.datasets["train"]
    idx = len(ds) - 1  # a quadruped (its root frame is not aligned with +Z)
    raw, aug = ds[idx], ds[(0, idx)]
    pair = torch.from_numpy(mirror_pairs(ds.features[ds.index[idx][0]].skeleton))
    flip = torch.tensor([-1.0, 1.0, 1.0])
    torch.testing.assert_close(aug.dynamic[:, :, 6:9], raw.dynamic[:, pair, 6:9] * flip,
                               atol=1e-4, rtol=1e-4)
    torch.testing.assert_close(aug.root[:, :2], -raw.root[:, :2], atol=1e-4, rtol=1e-4)
    torch.testing.assert_close(aug.root[:, 2:], raw.root[:, 2:], atol=1e-4, rtol=1e-4)


def test_training_batches_are_augmented(zoo):
    """Training batches hold skeletons of other joint counts and
    proportions than their source files', with finite features."""
    dm = datamodule(zoo, augment=ALL_OPS)
    ds = dm.datasets["train"]
    statics = {f.path: torch.from_numpy(s.static).float()
               for f, s in zip(ds.files, ds.features)}
    loader = dm.train_dataloader()
    assert loader.sampler.keys  # (epoch, index) keys
    joints_changed = proportions_changed = clips = 0
    for batch in batches(loader, 3):
        assert torch.isfinite(batch.x).all() and torch.isfinite(batch.root).all()
        assert torch.isfinite(batch.joint_static).all()
        assert batch.joint_semantic.shape[0] == batch.num_streams
        offsets = torch.cumsum(batch.clip_num_joints, 0) - batch.clip_num_joints
        for meta, start, joints in zip(batch.meta, offsets.tolist(),
                                       batch.clip_num_joints.tolist()):
            assert meta["augmented"]
            source = statics[meta["path"]]
            clips += 1
            joints_changed += joints != source.shape[0]
            proportions_changed += joints == source.shape[0] and not torch.allclose(
                batch.joint_static[start:start + joints], source, atol=1e-4)
    assert clips == 24 and joints_changed > 0 and proportions_changed > 0


def test_augmented_skeletons_differ_from_sources(zoo):
    dm = datamodule(zoo, augment={"scale": 1.0, "mirror": 0.0})
    ds = dm.datasets["train"]
    for idx in range(0, len(ds), 5):
        raw, aug = ds[idx], ds[(0, idx)]
        assert aug.num_joints == raw.num_joints
        assert not torch.allclose(aug.static, raw.static, atol=1e-3)
        assert torch.isfinite(aug.dynamic).all() and torch.isfinite(aug.root).all()
        assert aug.dynamic.shape == raw.dynamic.shape


def test_val_and_test_untouched(zoo):
    plain = datamodule(zoo)
    aug = datamodule(zoo, augment=ALL_OPS)
    for split in ("val", "test"):
        assert aug.datasets[split].augment is None
        loaders = plain._loader(split, False), aug._loader(split, False)
        for a, b in zip(*loaders):
            torch.testing.assert_close(a.x, b.x)
            torch.testing.assert_close(a.joint_static, b.joint_static)
            assert not any(m.get("augmented") for m in b.meta)
    torch.testing.assert_close(plain.normalizer.dynamic_std, aug.normalizer.dynamic_std)


def test_deterministic_given_seed(zoo):
    def first(dm: MotionDataModule, epoch: int):
        loader = dm.train_dataloader()
        loader.sampler.set_epoch(epoch)
        return batches(loader, 1)[0]

    a = first(datamodule(zoo, augment=ALL_OPS, seed=3), 0)
    b = first(datamodule(zoo, augment=ALL_OPS, seed=3), 0)
    assert a.clip_num_joints.tolist() == b.clip_num_joints.tolist()
    torch.testing.assert_close(a.x, b.x)
    torch.testing.assert_close(a.joint_static, b.joint_static)
    # Same window, another epoch or seed: another skeleton.
    ds = datamodule(zoo, augment={"scale": 1.0}, seed=3).datasets["train"]
    assert not torch.allclose(ds[(0, 4)].static, ds[(1, 4)].static)
    other = datamodule(zoo, augment={"scale": 1.0}, seed=4).datasets["train"]
    assert not torch.allclose(ds[(0, 4)].static, other[(0, 4)].static)
    torch.testing.assert_close(ds[(2, 4)].static, ds[(2, 4)].static)
