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

In a distributed run they are each process's own, not synced: a dataset
may be in one process's batches and not another's, and a sync over keys
that differ from process to process would pair the wrong values or hang.
"""
from __future__ import annotations

from typing import Dict, Optional, Sequence

import torch
from torch import Tensor


def dataset_of(meta: Sequence[dict]) -> list:
    """``meta["dataset"]`` of every clip of a batch (``"unknown"`` where a
    clip names none)."""
    return [str(m.get("dataset") or "unknown") for m in meta]


def log_per_dataset(module, stage: str, values: Dict[str, Tensor], datasets: Sequence[str],
                    weights: Optional[Tensor] = None) -> None:
    r"""Log the mean of each per-clip value over the clips of every
    dataset in the batch as ``{stage}/{dataset}/{name}``, weighted by
    :obj:`weights` (default: one per clip; e.g. a clip's masked tokens, so
    that the mean is the one over tokens); clips of weight 0 do not count.

    Args:
        module: The :class:`~lightning.pytorch.LightningModule` logging.
        stage (str): ``"val"`` or ``"test"``.
        values (dict): Name to per-clip values.
        datasets (list[str]): The dataset of every clip.
        weights (Tensor, optional): Per-clip weights (non-negative integers).

    Shapes:
        - every value, **weights**: :math:`(B,)`
    """
    if not values:
        return
    device = next(iter(values.values())).device
    weights = torch.ones(len(datasets), device=device) if weights is None else weights.float()
    for name in dict.fromkeys(datasets):
        keep = torch.tensor([d == name for d in datasets], device=device)
        total = weights[keep].sum()
        if float(total) <= 0:
            continue
        module.log_dict({f"{stage}/{name}/{key}": (value[keep].float() * weights[keep]).sum()
                         / total for key, value in values.items()},
                        batch_size=int(round(float(total))), on_step=False, on_epoch=True,
                        sync_dist=False, add_dataloader_idx=False)


__all__ = ["dataset_of", "log_per_dataset"]
