"""Feature normalisation with statistics stored as module buffers (so they
travel inside checkpoints)."""
from __future__ import annotations

from typing import Dict, Iterable

import numpy as np
import torch
from torch import Tensor, nn

from satagraph.data.features import (DYNAMIC_CHANNELS, DYNAMIC_LAYOUT,
                                     ROOT_CHANNELS, STATIC_CHANNELS,
                                     MotionFeatures)

_EPS = 1e-4


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
    def fit(self, features: Iterable[MotionFeatures]) -> "FeatureNormalizer":
        """Compute statistics from the (training) features."""
        feats = list(features)
        if not feats:
            raise ValueError("FeatureNormalizer.fit: no training features")
        dyn = np.concatenate([f.dynamic.reshape(-1, DYNAMIC_CHANNELS) for f in feats])
        root = np.concatenate([f.r for f in feats])
        static = np.concatenate([f.static for f in feats])
        self.set_stats({"dynamic": _stats(dyn), "root": _stats(root),
                        "static": _stats(static)})
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
    return values.mean(0), values.std(0)
