r"""Validation and test figures per dataset, for modules trained on several
at once.

A model trained on many datasets keeps the checkpoint with the lowest
validation loss over all of them, and a small source (a tenth of the
windows: the zoo's gestures, ``experiments/T2M.md`` section 28) barely
moves it: the lowest loss came before its captions were learnt. Each
module logs its per-clip figures again per ``meta["dataset"]`` as
``{stage}/{dataset}/{name}`` (epoch means, weighted as the overall
figure is), which a run can watch or keep its checkpoints by
(``trainer.monitor=val/zoo-gestures/masked``).

The steps add each figure's weighted sum and weight up
(:func:`log_per_dataset`); the epoch's end (:class:`PerDatasetFigures`'
hooks) divides them, after a distributed run has summed them over its
processes, so every process logs the figures of the whole validation set.
A dataset may be in one process's batches and not another's: the
processes first agree on the keys (their union), then sum.
"""
from __future__ import annotations

from typing import Dict, List, Optional, Sequence, Tuple

import torch
import torch.distributed as dist
from torch import Tensor

#: Per key ``{stage}/{dataset}/{name}``: the weighted sum and the weight.
Sums = Dict[str, Tuple[float, float]]


def dataset_of(meta: Sequence[dict]) -> list:
    """``meta["dataset"]`` of every clip of a batch (``"unknown"`` where a
    clip names none)."""
    return [str(m.get("dataset") or "unknown") for m in meta]


def log_per_dataset(module, stage: str, values: Dict[str, Tensor], datasets: Sequence[str],
                    weights: Optional[Tensor] = None) -> None:
    r"""Add a batch's per-clip values to :obj:`module`'s epoch sums per
    dataset (``{stage}/{dataset}/{name}``), weighted by :obj:`weights`
    (default: one per clip; e.g. a clip's masked tokens, so that the mean
    is the one over tokens); clips of weight 0 do not count. The module's
    :class:`PerDatasetFigures` hooks log the means at the epoch's end.

    Args:
        module: The :class:`~lightning.pytorch.LightningModule` logging.
        stage (str): ``"val"`` or ``"test"``.
        values (dict): Name to per-clip values.
        datasets (list[str]): The dataset of every clip.
        weights (Tensor, optional): Per-clip weights (non-negative).

    Shapes:
        - every value, **weights**: :math:`(B,)`
    """
    if not values:
        return
    sums = module.__dict__.setdefault("_per_dataset_sums", {})
    device = next(iter(values.values())).device
    weights = torch.ones(len(datasets), device=device) if weights is None else weights
    weights = weights.detach().double()
    for name in dict.fromkeys(datasets):
        keep = torch.tensor([d == name for d in datasets], device=device)
        w = weights[keep]
        # one transfer to the host per dataset: its weight, then each value's sum
        total, *added = torch.stack([w.sum()] + [(v.detach()[keep].double() * w).sum()
                                                 for v in values.values()]).tolist()
        if total <= 0:
            continue
        for key, add in zip(values, added):
            old = sums.get(f"{stage}/{name}/{key}", (0.0, 0.0))
            sums[f"{stage}/{name}/{key}"] = (old[0] + add, old[1] + total)


def summed_over_processes(sums: Sums, device: torch.device) -> Sums:
    """:obj:`sums` added up over the processes of a distributed run (every
    process gets the union of their keys); unchanged in a single process."""
    if not (dist.is_available() and dist.is_initialized()) or dist.get_world_size() == 1:
        return dict(sums)
    keys: List[Optional[List[str]]] = [None] * dist.get_world_size()
    dist.all_gather_object(keys, sorted(sums))
    union = sorted(set().union(*keys))
    table = torch.tensor([sums.get(k, (0.0, 0.0)) for k in union], dtype=torch.float64,
                         device=device).view(len(union), 2)
    dist.all_reduce(table)
    return {k: (float(s), float(w)) for k, (s, w) in zip(union, table.tolist())}


def epoch_means(module, stage: str) -> Dict[str, float]:
    """The means of :obj:`stage`'s per-dataset sums of the epoch (over every
    process), which it forgets."""
    sums = module.__dict__.get("_per_dataset_sums", {})
    mine = {k: v for k, v in sums.items() if k.startswith(f"{stage}/")}
    for key in mine:
        del sums[key]
    total = summed_over_processes(mine, module.device)
    return {k: s / w for k, (s, w) in total.items() if w > 0}


class PerDatasetFigures:
    """Mixin of a LightningModule that calls :func:`log_per_dataset` in its
    validation and test steps: logs the epoch's per-dataset means (a
    subclass overriding these hooks calls ``super()``)."""

    def _log_epoch_means(self, stage: str) -> None:
        means = epoch_means(self, stage)
        if means:  # every process logs the same keys and values
            self.log_dict(means, sync_dist=True, add_dataloader_idx=False)

    def on_validation_epoch_end(self) -> None:
        self._log_epoch_means("val")

    def on_test_epoch_end(self) -> None:
        self._log_epoch_means("test")


__all__ = ["dataset_of", "log_per_dataset", "summed_over_processes", "epoch_means",
           "PerDatasetFigures"]
