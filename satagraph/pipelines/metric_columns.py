"""The columns of the printed tables of motion metrics (``satagraph
eval``'s and a sweep's): one definition of each figure's heading, unit and
format (imports nothing heavy: the sweep module reads it)."""
from __future__ import annotations

from typing import NamedTuple, Optional


class MetricColumn(NamedTuple):
    """A figure of :func:`~satagraph.metrics.motion_metrics` in a table:
    its key, its heading, and the factor to the unit the heading names."""

    name: str
    heading: str
    factor: float = 1.0

    def cell(self, value: Optional[float]) -> str:
        """:obj:`value` in the heading's unit, four decimals (``-``: none)."""
        return "-" if value is None else f"{value * self.factor:.4f}"


#: The paper's figures of :func:`~satagraph.metrics.motion_metrics`, in
#: table order.
METRIC_COLUMNS = (MetricColumn("JR", "JR (rad)"), MetricColumn("RT", "RT (cm)", 100.0),
                  MetricColumn("JP", "JP (cm)", 100.0), MetricColumn("RT_h", "RT/H"),
                  MetricColumn("JP_h", "JP/H"), MetricColumn("FS", "FS (cm/frame)", 100.0),
                  MetricColumn("GP", "GP (cm)", 100.0), MetricColumn("RE", "RE"))

__all__ = ["MetricColumn", "METRIC_COLUMNS"]
