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


def test_retarget_stage_adds_only_the_cross_skeleton_term():
    base, stage = load_config("cpu_joint_finetune"), load_config("cpu_joint_retarget")
    assert stage["loss"] == dict(base["loss"], retarget=0.01)
    assert stage["model"] == base["model"] and stage["data"] == base["data"]


def test_augment_stage_draws_new_rigs_with_new_rest_poses():
    base, stage = load_config("cpu_joint_retarget"), load_config("cpu_joint_augment")
    assert stage["loss"] == base["loss"] and stage["model"] == base["model"]
    assert stage["data"]["augment"]["rest"] > 0


def test_long_retarget_stage_doubles_the_term_with_a_new_data_order():
    base, stage = load_config("cpu_joint_retarget"), load_config("cpu_joint_retarget_long")
    assert stage["loss"] == dict(base["loss"], retarget=0.02)
    assert stage["model"] == base["model"] and stage["data"] == base["data"]
    assert stage["seed"] != base.get("seed", 0)
