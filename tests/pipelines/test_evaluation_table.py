"""The table ``satagraph eval`` prints, of any module's ``metrics`` hook."""
from __future__ import annotations

from types import SimpleNamespace

import torch

from satagraph.pipelines.evaluation import evaluate, format_table

PAPER = dict(JR=0.5, RT=0.1, JP=0.2, RT_h=0.05, JP_h=0.1, FS=0.01, GP=-0.02, RE=3.0)


class OwnMetrics(torch.nn.Module):
    """A module whose ``metrics`` hook gives figures of its own alone."""

    def forward(self, batch):
        return batch

    def metrics(self, out, batch):
        return {"zabs": torch.tensor([1.0, 3.0])[:len(batch.meta)]}


def test_the_paper_s_table_is_kept():
    table = format_table({"zoo": dict(PAPER, clips=4), "all": dict(PAPER, clips=4)})
    lines = table.splitlines()
    assert lines[0] == ("| dataset | clips | JR (rad) | RT (cm) | JP (cm) | RT/H | JP/H | "
                        "FS (cm/frame) | GP (cm) | RE |")
    assert lines[2] == ("| zoo | 4 | 0.5000 | 10.0000 | 20.0000 | 0.0500 | 0.1000 | 1.0000 | "
                        "-2.0000 | 3.0000 |") and lines[3].startswith("| all | 4 |")


def test_a_module_s_own_metrics_are_columns():
    """A subclass whose ``metrics`` gave its own figures (the README's hook)
    made ``satagraph eval`` fail with ``KeyError: 'JR'``; ones it gave
    beside the paper's were left out of the table."""
    loader = [SimpleNamespace(meta=[{"dataset": "zoo"}, {"dataset": "dog"}])]
    results = evaluate(OwnMetrics(), loader)
    lines = format_table(results).splitlines()
    assert lines[0] == "| dataset | clips | zabs |" and lines[1] == "|---|---|---|"
    assert lines[2:] == ["| dog | 1 | 3.0000 |", "| zoo | 1 | 1.0000 |", "| all | 2 | 2.0000 |"]
    both = format_table({"all": dict(PAPER, zabs=0.25, clips=2)}).splitlines()
    assert both[0].endswith("| RE | zabs |") and both[2].endswith("| 3.0000 | 0.2500 |")
