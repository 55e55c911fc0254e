"""Paired retargeting error in the internal and cross settings, on real
clips with a tiny module."""
from __future__ import annotations

from typing import Callable

import numpy as np
import pytest

import satagraph.pipelines.evaluation as evaluation
from satagraph.data.datamodule import MotionDataModule
from satagraph.pipelines.evaluation import retarget_errors


@pytest.fixture
def test_files(datamodule: MotionDataModule):
    """One bandai and one dog test file."""
    return datamodule.datasets["test"].files


@pytest.mark.parametrize("setting", ["internal", "cross"])
def test_an_oracle_decoder_has_no_retarget_error(setting, build_tiny_module, test_files,
                                                 embed: Callable, monkeypatch):
    """Decoding the ground truth's own rotations and root features onto the
    target skeleton reproduces the ground truth, in both settings: the
    paired targets are reachable by a rotation-only decoder, so the error
    measures the model alone."""
    def oracle(module, source, target, semantic=None):
        return target.q, target.r, np.zeros(target.q.shape[:2])
    monkeypatch.setattr(evaluation, "transfer", oracle)
    errors = retarget_errors(build_tiny_module(), test_files, embed, max_frames=48,
                             setting=setting)
    assert set(errors) == {"bandai", "dog", "all"}
    assert all(v < 1e-6 for v in errors.values())


def test_retarget_errors_of_a_model_per_setting(build_tiny_module, test_files,
                                                embed: Callable):
    module = build_tiny_module()
    internal = retarget_errors(module, test_files, embed, max_frames=48)
    cross = retarget_errors(module, test_files, embed, max_frames=48, setting="cross")
    for errors in (internal, cross):
        assert set(errors) == {"bandai", "dog", "all"}
        assert all(np.isfinite(v) and v > 0 for v in errors.values())
        assert errors["all"] == pytest.approx((errors["bandai"] + errors["dog"]) / 2)
    assert cross["all"] != pytest.approx(internal["all"])
    with pytest.raises(ValueError, match="unknown setting 'mixed'"):
        retarget_errors(module, test_files, embed, setting="mixed")


def test_error_table_reads_each_file_once_and_agrees_per_setting(build_tiny_module, test_files,
                                                                 embed: Callable, monkeypatch):
    module = build_tiny_module()
    single = {s: retarget_errors(module, test_files, embed, max_frames=48, setting=s)
              for s in ("internal", "cross")}
    reads = []
    import satagraph.io
    real = satagraph.io.read_bvh
    monkeypatch.setattr(satagraph.io, "read_bvh", lambda path: reads.append(path) or real(path))
    table = evaluation.retarget_error_table(module, test_files, embed, max_frames=48)
    assert len(reads) == len(test_files)
    assert set(table) == {"internal", "cross"}
    for setting, errors in single.items():
        assert table[setting] == pytest.approx(errors)
