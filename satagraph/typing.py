"""Feature layouts shared by data, models and losses (the contract between
:mod:`satagraph.data.features`, which writes features, and the networks and
losses that read them), importable without torch."""
from __future__ import annotations

from typing import Dict

#: Column ranges of the per-joint dynamic features: 6D local rotation ``q``,
#: position ``x`` and position relative to the parent ``x_rel`` in the
#: facing frame, rotation velocity ``v_q``, velocity ``v_x``, contact ``c``.
DYNAMIC_LAYOUT: Dict[str, slice] = {
    "q": slice(0, 6), "x": slice(6, 9), "x_rel": slice(9, 12),
    "v_q": slice(12, 18), "v_x": slice(18, 21), "c": slice(21, 22),
}
#: Width of the per-joint dynamic features.
DYNAMIC_CHANNELS = 22
#: Width of the per-joint static features ``[X_l, X_g]``.
STATIC_CHANNELS = 6
#: Width of the per-frame root features (yaw velocity, x and z velocity in
#: the facing frame, root height).
ROOT_CHANNELS = 4

__all__ = ["DYNAMIC_LAYOUT", "DYNAMIC_CHANNELS", "STATIC_CHANNELS", "ROOT_CHANNELS"]
