"""Transforms of one's own on the training windows (``data.train_transform``)."""
from __future__ import annotations

import pickle
from pathlib import Path

import pytest
import torch

from satagraph.data.datamodule import MotionDataModule
from satagraph.data.window_transform import (_TRANSFORMS, TransformedCollate,
                                             register_window_transform, window_transform)
from satagraph.datasets.zoo import write_zoo


def zero_root(clip):
    """A module-level transform (picklable): the root features zeroed."""
    clip.root = torch.zeros_like(clip.root)
    clip.meta["transformed"] = True
    return clip


@pytest.fixture
def registered():
    register_window_transform("zero_root", zero_root)
    yield "zero_root"
    _TRANSFORMS.pop("zero_root", None)


def test_a_registered_transform_changes_the_training_windows_only(tmp_path: Path,
                                                                  registered: str) -> None:
    """The extensibility audit found no way to transform a window but by
    overriding the data module's private ``_loader``."""
    write_zoo(tmp_path / "zoo", species=["biped"], clips=3, frames=40)
    dm = MotionDataModule(str(tmp_path / "zoo" / "manifest.tsv"), window=16, stride=16,
                          batch_size=4, cache_dir=str(tmp_path / "cache"),
                          train_transform=registered)
    dm.setup("fit")
    train = next(iter(dm.train_dataloader()))
    val = next(iter(dm.val_dataloader()))
    assert torch.count_nonzero(train.root) == 0 and torch.count_nonzero(val.root) > 0
    collate = dm.train_dataloader().collate_fn
    assert isinstance(collate, TransformedCollate)
    assert pickle.loads(pickle.dumps(collate)).transform is zero_root  # spawned workers


def test_an_unknown_transform_is_one_line_before_any_data_is_read(registered: str) -> None:
    from satagraph.experiment.config import load_config
    from satagraph.experiment.train import check_config
    with pytest.raises(ValueError, match=r"data.train_transform 'nope' is not registered "
                       r"\(registered: zero_root\): register_window_transform"):
        check_config(load_config("tiny", ["data.train_transform=nope"]))
    check_config(load_config("tiny", ["data.train_transform=zero_root"]))
    assert window_transform(None) is None and window_transform(zero_root) is zero_root
    with pytest.raises(ValueError, match="registered already"):
        register_window_transform("zero_root", zero_root)
