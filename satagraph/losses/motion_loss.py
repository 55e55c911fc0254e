""":class:`MotionLoss`: the weighted sum of the loss terms (weights and
units: :mod:`satagraph.losses`)."""
from __future__ import annotations

from typing import Dict, Optional

import torch.nn.functional as F
from torch import Tensor, nn

from satagraph.losses.positions import (POSITION_SCALE, facing_positions, position_scale,
                                        to_global)
from satagraph.losses.terms import (contact_loss, foot_sliding_loss, limb_end_streams,
                                    penetration_loss, rotation_loss, smoothness_loss,
                                    spread_error, stance_loss, stream_mean, velocity_loss)
from satagraph.typing import DYNAMIC_LAYOUT

DEFAULT_WEIGHTS: Dict[str, float] = {
    "rotation": 5.0, "position": 0.01, "global_position": 0.0, "velocity": 1.0,
    "root": 10.0, "contact": 1.0,
    "foot_sliding": 6.0, "penetration": 0.1, "smoothness": 0.015, "kl": 1e-4,
    "commit": 0.02, "retarget": 0.0, "retarget_root": 0.0,
    "retarget_carriage": 0.0, "stance": 0.0,
    "amplitude": 0.0, "limb_amplitude": 0.0,
}


class MotionLoss(nn.Module):
    r"""Weighted sum of the motion losses (see the module docstring).

    Args:
        weights (dict, optional): Weights by term name (overrides).
        position_scale (float, optional): Units per character height of the
            position terms.
        smooth_order (int, optional): Order of the smoothness differences.
        smooth_match_target (bool, optional): Penalise the difference to the
            target's time differences (``False``: the predicted ones, SAME).
        **kwargs (float): Weights by term name, e.g. ``rotation=5.0``.

    Call with ``(out, batch, normalizer=None, fps=None)`` (``fps``: the
    batch's frame rate unless given): :obj:`out` holds
    physical ``q`` :math:`(N, 6)`, ``r`` :math:`(G, 4)`, contact logits
    ``c`` :math:`(N, 1)`, optionally ``r_norm`` (normalised ``r``, used for
    the root term with :obj:`normalizer`, as SAME), ``kl`` and ``commit``.
    Returns every term (unweighted) and their weighted sum under ``"loss"``.
    """

    def __init__(self, weights: Optional[Dict[str, float]] = None,
                 position_scale: float = POSITION_SCALE, smooth_order: int = 2,
                 smooth_match_target: bool = True, **kwargs: float) -> None:
        super().__init__()
        self.weights = dict(DEFAULT_WEIGHTS, **(weights or {}), **kwargs)
        unknown = set(self.weights) - set(DEFAULT_WEIGHTS)
        if unknown:
            raise ValueError(f"MotionLoss: unknown terms {sorted(unknown)}; "
                             f"known: {sorted(DEFAULT_WEIGHTS)}")
        self.position_scale, self.smooth_order = position_scale, smooth_order
        self.smooth_match_target = smooth_match_target

    def _root(self, out: Dict[str, Tensor], batch, normalizer) -> Tensor:
        if normalizer is not None and "r_norm" in out:
            return F.mse_loss(out["r_norm"], normalizer.normalize(
                batch.root, "root", batch.heights("frame"), batch.legs("frame")))
        return F.mse_loss(out["r"], batch.root.to(out["r"].dtype))

    def _positions(self, q: Tensor, r: Tensor, batch, fps: Optional[float]):
        scale = position_scale(batch, self.position_scale)
        local = facing_positions(q, r, batch)
        return local * scale, to_global(local, r, batch, fps) * scale

    def terms(self, out: Dict[str, Tensor], batch, normalizer=None,
              fps: Optional[float] = None) -> Dict[str, Tensor]:
        """Every unweighted term."""
        q_true = batch.x[:, DYNAMIC_LAYOUT["q"]].to(out["q"].dtype)
        c_true = batch.x[:, DYNAMIC_LAYOUT["c"]]
        local_p, glob_p = self._positions(out["q"], out["r"], batch, fps)
        local_t, glob_t = self._positions(q_true, batch.root.to(out["r"].dtype), batch, fps)
        smooth_ref = glob_t if self.smooth_match_target else None
        spread = spread_error(local_p, local_t, batch)  # both amplitude terms
        terms = {
            "rotation": rotation_loss(out["q"], q_true, batch),
            "position": F.mse_loss(local_p, local_t),
            "global_position": F.mse_loss(glob_p, glob_t),
            "velocity": velocity_loss(glob_p, glob_t, batch),
            "root": self._root(out, batch, normalizer),
            "contact": contact_loss(out["c"], c_true),
            "foot_sliding": foot_sliding_loss(glob_p, c_true, batch),
            "stance": stance_loss(local_p, local_t, c_true, batch),
            "amplitude": stream_mean(spread),
            "limb_amplitude": stream_mean(spread, limb_end_streams(batch)),
            "penetration": penetration_loss(local_p),
            "smoothness": smoothness_loss(glob_p, batch, smooth_ref, self.smooth_order),
        }
        terms.update({k: out[k] for k in ("kl", "commit") if k in out})
        return terms

    def forward(self, out: Dict[str, Tensor], batch, normalizer=None,
                fps: Optional[float] = None) -> Dict[str, Tensor]:
        terms = self.terms(out, batch, normalizer, fps)
        terms["loss"] = sum(self.weights[k] * v for k, v in terms.items())
        return terms


__all__ = ["DEFAULT_WEIGHTS", "MotionLoss"]
