"""Feature normalisation with statistics stored as module buffers (so they
travel inside checkpoints)."""
from __future__ import annotations

from typing import Dict, Iterable, List, Optional, Sequence

import numpy as np
import torch
from torch import Tensor, nn

from satagraph.data.features import (DYNAMIC_CHANNELS, DYNAMIC_LAYOUT,
                                     ROOT_CHANNELS, STATIC_CHANNELS,
                                     MotionFeatures)

_EPS = 1e-4
#: Largest accepted mean or standard deviation of any feature channel
#: (features are in metres, seconds and radians after canonicalisation).
MAX_STAT = 1e5


class NormalizerError(ValueError):
    """Statistics that would blind or break a model (non-finite or absurd);
    the message names the file with the most extreme values."""


class FeatureNormalizer(nn.Module):
    r"""Per-channel mean/std pooled over frames and joints (SAME's scheme).

    Dynamic joint features are normalised except the contact column; root
    features ``r`` and static features ``[X_l, X_g]`` have their own
    statistics. Statistics come from the training split only
    (:meth:`fit`) and are saved with the model.
    """

    def __init__(self) -> None:
        super().__init__()
        for name, width in (("dynamic", DYNAMIC_CHANNELS), ("root", ROOT_CHANNELS),
                            ("static", STATIC_CHANNELS)):
            self.register_buffer(f"{name}_mean", torch.zeros(width))
            self.register_buffer(f"{name}_std", torch.ones(width))
        self.register_buffer("fitted", torch.zeros((), dtype=torch.bool))

    @torch.no_grad()
    def fit(self, features: Iterable[MotionFeatures],
            names: Optional[Sequence[str]] = None) -> "FeatureNormalizer":
        """Compute statistics from the (training) features.

        Args:
            features: The training features.
            names: Their files, for error messages.

        Raises:
            NormalizerError: A statistic is non-finite or larger than
                :data:`MAX_STAT` (one extreme file would blind the model to
                every other); the message names the most extreme file.
        """
        feats = list(features)
        if not feats:
            raise ValueError("FeatureNormalizer.fit: no training features")
        parts = {"dynamic": [f.dynamic.reshape(-1, DYNAMIC_CHANNELS) for f in feats],
                 "root": [f.r for f in feats], "static": [f.static for f in feats]}
        stats = {}
        for name, values in parts.items():
            stats[name] = _stats(np.concatenate(values))
            _check_stats(name, stats[name], values, names)
        self.set_stats(stats)
        return self

    @torch.no_grad()
    def set_stats(self, stats: Dict[str, tuple]) -> None:
        """Set statistics from ``{name: (mean, std)}``; contacts stay raw."""
        for name, (mean, std) in stats.items():
            mean = torch.as_tensor(np.asarray(mean), dtype=torch.float32)
            std = torch.as_tensor(np.asarray(std), dtype=torch.float32).clamp(min=_EPS)
            if name == "dynamic":
                c = DYNAMIC_LAYOUT["c"]
                mean[c], std[c] = 0.0, 1.0
            getattr(self, f"{name}_mean").copy_(mean)
            getattr(self, f"{name}_std").copy_(std)
        self.fitted.fill_(True)

    def stats(self) -> Dict[str, tuple]:
        """Statistics as plain lists (for JSON or hyperparameters)."""
        return {name: (getattr(self, f"{name}_mean").tolist(),
                       getattr(self, f"{name}_std").tolist())
                for name in ("dynamic", "root", "static")}

    def normalize(self, value: Tensor, name: str) -> Tensor:
        """``(value - mean) / std`` over the last dimension."""
        return (value - getattr(self, f"{name}_mean")) / getattr(self, f"{name}_std")

    def denormalize(self, value: Tensor, name: str,
                    columns: slice = slice(None)) -> Tensor:
        """Inverse of :meth:`normalize`, optionally for a column range."""
        mean = getattr(self, f"{name}_mean")[columns]
        return value * getattr(self, f"{name}_std")[columns] + mean


def _stats(values: np.ndarray) -> tuple:
    with np.errstate(all="ignore"):
        return values.mean(0), values.std(0)


def _check_stats(name: str, stats: tuple, values: List[np.ndarray],
                 names: Optional[Sequence[str]]) -> None:
    """Raise :class:`NormalizerError` for non-finite or absurd statistics."""
    mean, std = stats
    worst = float(np.nan_to_num(np.maximum(np.abs(mean), std), nan=np.inf).max())
    if worst <= MAX_STAT:
        return
    extreme = [float(np.nan_to_num(np.abs(v), nan=np.inf).max()) if v.size else 0.0
               for v in values]
    k = int(np.argmax(extreme))
    where = names[k] if names is not None else f"training file #{k}"
    raise NormalizerError(
        f"normalisation statistics of the {name} features are "
        f"{'non-finite' if not np.isfinite(worst) else f'absurd ({worst:.3g})'}: "
        f"the most extreme file is {where} (largest |value| {extreme[k]:.3g}); "
        "fix or leave out that file")
