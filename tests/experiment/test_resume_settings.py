"""``--resume`` goes on only with the settings a run was trained with."""
from __future__ import annotations

from pathlib import Path

import pytest

from satagraph.experiment.config import load_config
from tests.conftest import save_module_checkpoint
from satagraph.experiment.train import build_module, check_config, check_resumable


@pytest.fixture
def tiny_ckpt(tmp_path: Path) -> Path:
    """A checkpoint of the tiny config (as trained: its hyperparameters)."""
    module = build_module(load_config("tiny", ["model.semantic_channels=0"]))
    path = tmp_path / "last.ckpt"
    save_module_checkpoint(module, path)
    return path


def _resume(ckpt: Path, *overrides: str) -> None:
    check_resumable(ckpt, check_config(load_config("tiny", ["model.semantic_channels=0",
                                                            *overrides])))


def test_a_resume_on_other_windows_is_refused(tiny_ckpt: Path) -> None:
    """A resume with another data.window, batch size or file limit went on
    silently, on other windows than the run's, and its config.yaml then
    recorded only the new settings."""
    before = load_config("tiny")["data"]
    with pytest.raises(ValueError, match=rf"data.window={before['window']} \(here 16\)"):
        _resume(tiny_ckpt, "data.window=16")
    with pytest.raises(ValueError, match=r"data.batch_size=.* \(here 3\)"):
        _resume(tiny_ckpt, "data.batch_size=3")
    with pytest.raises(ValueError, match=r"data.preprocessing.fps=.* \(here 24"):
        _resume(tiny_ckpt, "data.preprocessing.fps=24")


def test_a_resume_may_read_the_same_windows_otherwise(tiny_ckpt: Path, tmp_path: Path) -> None:
    _resume(tiny_ckpt)
    _resume(tiny_ckpt, "data.num_workers=2", f"data.cache_dir={tmp_path}",
            "data.on_error=skip")
