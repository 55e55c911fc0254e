"""The data module's set-up stages: the normaliser is fitted on the
training split whichever stage reads the splits first."""
from __future__ import annotations

from typing import Any, Dict

import pytest
import torch

from satagraph.data.datamodule import MotionDataModule
from satagraph.experiment.train import build_datamodule, build_module


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
