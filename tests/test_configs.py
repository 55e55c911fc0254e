"""Every config in experiments/ loads, resolves its defaults and names a
module, a model and data sources."""
from __future__ import annotations

from pathlib import Path

import pytest

from satagraph.config import load_config

CONFIGS = sorted(p.stem for p in (Path(__file__).resolve().parents[1] / "experiments")
                 .glob("*.yaml"))


@pytest.mark.parametrize("name", CONFIGS)
def test_config_loads(name: str):
    cfg = load_config(name)
    assert cfg["module"] and cfg["model"] and cfg["data"]["sources"]


def test_finetune_stage_inherits_cpu_joint():
    base, stage = load_config("cpu_joint"), load_config("cpu_joint_finetune")
    assert stage["model"] == base["model"]
    assert stage["loss"]["position"] == 0.005 and base["loss"]["position"] == 0.001
    assert stage["data"] == base["data"]
