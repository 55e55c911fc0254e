"""The data module's set-up stages: the normaliser is fitted on the
training split whichever stage reads the splits first."""
from __future__ import annotations

import pickle
from pathlib import Path
from typing import Any, Dict

import pytest
import torch

from satagraph.data.datamodule import MotionDataModule
from satagraph.experiment.train import build_datamodule, build_module, train


def test_fit_after_validate_still_fits_the_normalizer(_base_config: Dict[str, Any],
                                                      datamodule: MotionDataModule) -> None:
    # trainer.validate before trainer.fit: the splits are read at "validate",
    # and the normaliser stayed at mean 0, std 1 for the whole training run
    dm = build_datamodule(_base_config)
    dm.setup("validate")
    assert not bool(dm.normalizer.fitted)  # scoring reads a model's own statistics
    dm.setup("fit")
    assert bool(dm.normalizer.fitted)
    for name, value in datamodule.normalizer.state_dict().items():
        assert torch.equal(dm.normalizer.state_dict()[name], value), name


def test_semantic_channels_before_setup_says_what_to_do(_base_config: Dict[str, Any]) -> None:
    """``build_module(cfg, datamodule)`` before ``setup`` failed with
    ``KeyError: 'train'``."""
    dm = build_datamodule(_base_config)
    with pytest.raises(RuntimeError, match=r"not read yet: call datamodule.setup\('fit'\)"):
        build_module(_base_config, dm)


def test_spawned_loader_workers_get_picklable_windows(datamodule: MotionDataModule) -> None:
    """DataLoader workers started by ``spawn`` (macOS and Windows) get the
    dataset pickled: ``data.num_workers=2`` failed there with ``Can't
    pickle local object 'semantic_embedder.<locals>.embed'``."""
    dataset = datamodule._loader("train", True).dataset
    copy = pickle.loads(pickle.dumps(dataset))
    assert torch.equal(copy[0].semantic, dataset[0].semantic)
    assert copy[0].semantic.abs().sum() > 0


def test_a_script_without_a_main_guard_is_told_in_a_spawned_worker(
        tiny_config: Dict[str, Any]) -> None:
    """A spawned worker runs the calling script again as ``__mp_main__``:
    its ``train(cfg)`` started a second run there ("output_dir is in use by
    another live run"), and the first said only "DataLoader worker exited
    unexpectedly"."""
    script = compile("train(cfg)", "my_training.py", "exec")
    with pytest.raises(RuntimeError, match="if __name__ == \"__main__\""):
        exec(script, {"__name__": "__mp_main__", "train": train, "cfg": tiny_config})
    assert not Path(tiny_config["output_dir"]).exists()
