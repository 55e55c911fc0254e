"""TrailingLoss: the mean training loss over a run's last steps."""
from __future__ import annotations

import math

import pytest
import torch

from satagraph.lightning import TrailingLoss


def test_mean_over_the_last_window_steps():
    cb = TrailingLoss(window=3)
    assert math.isnan(cb.value)
    for i, loss in enumerate([10.0, 1.0, 2.0, 3.0]):
        # Lightning hands a dict for automatic optimisation; a bare tensor
        # and a step without a loss (None) are taken too.
        out = {"loss": torch.tensor(loss, requires_grad=True)} if i % 2 else torch.tensor(loss)
        cb.on_train_batch_end(None, None, out, None, i)
    cb.on_train_batch_end(None, None, None, None, 4)
    assert cb.value == pytest.approx(2.0)
    assert all(not x.requires_grad for x in cb.losses)


def test_window_must_be_positive():
    with pytest.raises(ValueError, match="window"):
        TrailingLoss(window=0)


def test_train_passes_extra_callbacks(tiny_config):
    from satagraph.experiment.train import train
    cb = TrailingLoss(window=2)
    cfg = dict(tiny_config, logger={"name": "none"})
    _, _, trainer, _ = train(cfg, max_epochs=1, limit_train_batches=3, limit_val_batches=0,
                             num_sanity_val_steps=0, callbacks=[cb])
    assert cb in trainer.callbacks
    assert len(cb.losses) == 2 and math.isfinite(cb.value)
