"""The one override merger (:func:`~satagraph.experiment.config.merge_overrides`),
used by ``load_config``, the demo and sweeps."""
from __future__ import annotations

import pytest

from satagraph.experiment.config import load_config, merge_overrides

BASE = {"a": {"b": 1, "c": [1, 2]}, "d": "x"}


def test_nested_keys_lists_and_mappings():
    out = merge_overrides(BASE, ["a.b=2", "a.c=[3, 4, 5]", "e.f.g={k: v}", "a.h=[{p: q}]"])
    assert out == {"a": {"b": 2, "c": [3, 4, 5], "h": [{"p": "q"}]}, "d": "x",
                   "e": {"f": {"g": {"k": "v"}}}}
    assert BASE == {"a": {"b": 1, "c": [1, 2]}, "d": "x"}  # the input is not changed


@pytest.mark.parametrize("value, expected", [
    ("3", 3), ("3.5", 3.5), ("1.0e-3", 1.0e-3), ("true", True), ("false", False),
    ("null", None), ("abc", "abc"), ("'3'", "3"), ("00:00:05:00", "00:00:05:00")])
def test_values_are_typed_as_yaml(value, expected):
    out = merge_overrides(BASE, [f"d={value}"])["d"]
    assert out == expected and type(out) is type(expected)


def test_bad_overrides_are_one_line():
    with pytest.raises(ValueError, match="not of the form key=value"):
        merge_overrides(BASE, ["a.b"])
    with pytest.raises(ValueError, match="where: cannot apply") as err:
        merge_overrides(BASE, ["d=${nowhere}"], where="where")
    assert "\n" not in str(err.value)


def test_an_item_of_a_list_is_set_by_its_index():
    """``data.sources.0.scale=0.01`` failed as 'Cannot merge incompatible
    container types', naming no override; a list's item is set in place."""
    base = {"data": {"sources": [{"path": "a", "scale": 1.0}, "b"]}, "d": 1}
    out = merge_overrides(base, ["data.sources.0.scale=0.01", "d=2"])
    assert out == {"data": {"sources": [{"path": "a", "scale": 0.01}, "b"]}, "d": 2}
    assert base["data"]["sources"][0]["scale"] == 1.0
    with pytest.raises(ValueError, match=r"^where: override data.sources.5.scale=2: cannot be "
                       r"applied \(.*index out of range") as err:
        merge_overrides(base, ["d=3", "data.sources.5.scale=2"], where="where")
    assert "\n" not in str(err.value)


def test_text_where_a_number_stands_is_one_line():
    """``optim.lr=abc`` failed as a TypeError deep in the optimiser."""
    with pytest.raises(ValueError, match=r"optim.lr=abc: a number is expected \(the config "
                       r"has 0.001\)"):
        merge_overrides({"optim": {"lr": 1e-3}}, ["optim.lr=abc"])
    # where text may stand for a number: units for a factor
    assert merge_overrides({"data": {"scale": 0.01}}, ["data.scale=cm"])["data"]["scale"] == "cm"


def test_load_config_applies_overrides_after_inheritance():
    cfg = load_config("cpu_joint_finetune", ["optim.lr=2e-3", "data.window=16",
                                             "data.sources=[a, b]"])
    assert cfg["optim"]["lr"] == 2e-3 and cfg["optim"]["warmup_epochs"] == 1
    assert cfg["data"]["window"] == 16 and cfg["data"]["sources"] == ["a", "b"]
    assert cfg["model"]["hidden_channels"] == 64  # from cpu_joint


def test_demo_uses_the_same_merger(tmp_path):
    from satagraph.experiment.demo import DemoOptions, demo_config
    options = DemoOptions(overrides=["data.batch_size=3", "trainer.max_steps=2"], minutes=1)
    cfg = demo_config(options, ["zoo/manifest.tsv"], tmp_path)
    assert cfg["data"]["batch_size"] == 3 and cfg["trainer"]["max_steps"] == 2
    assert cfg["trainer"]["max_time"] == {"minutes": 1.0}
    assert cfg["data"]["sources"] == ["zoo/manifest.tsv"]
    with pytest.raises(ValueError, match="unknown config key 'data.batchsize'"):
        demo_config(DemoOptions(overrides=["data.batchsize=3"]), [], tmp_path)
