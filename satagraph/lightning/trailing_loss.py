"""The mean training loss over a run's last steps, comparable across runs
whatever their epoch boundaries."""
from __future__ import annotations

import math
from collections import deque
from typing import Any, Deque, Mapping

import lightning as L
import torch
from torch import Tensor


class TrailingLoss(L.Callback):
    r"""Keeps the training loss of the last :obj:`window` training batches.

    An epoch-mean loss is not comparable between runs stopped by a time
    budget: a run that just began a new epoch reports the mean of a few late
    steps, one still in its first epoch the mean from step 0. The mean over
    the last :obj:`window` steps is. Losses are kept as detached tensors, so
    no step waits for the device.

    Args:
        window (int): Training batches to average (optimizer steps when
            gradients are not accumulated). (default: :obj:`50`)
    """

    def __init__(self, window: int = 50) -> None:
        if window < 1:
            raise ValueError(f"TrailingLoss: window must be at least 1, got {window}")
        self.window = window
        self.losses: Deque[Tensor] = deque(maxlen=window)

    def on_train_batch_end(self, trainer: L.Trainer, pl_module: L.LightningModule,
                           outputs: Any, batch: Any, batch_idx: int) -> None:
        loss = outputs.get("loss") if isinstance(outputs, Mapping) else outputs
        if isinstance(loss, Tensor):
            self.losses.append(loss.detach())

    @property
    def value(self) -> float:
        """The mean over the kept steps (``nan`` before the first step)."""
        if not self.losses:
            return math.nan
        return torch.stack(list(self.losses)).float().mean().item()


__all__ = ["TrailingLoss"]
