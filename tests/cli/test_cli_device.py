"""``--device`` of reconstruct, retarget and generate: refused in one line
where this machine lacks it, before any file is read; else the model is
loaded onto it (the pipelines follow the model's device:
tests/t2m/test_t2m_device_mixing.py)."""
from __future__ import annotations

from pathlib import Path
from typing import List

import pytest
import torch

from satagraph.cli import main
from satagraph.io import write_bvh

from tests.conftest import _random_motion


@pytest.fixture
def bvh(tiny_skeleton, tmp_path) -> Path:
    path = tmp_path / "tiny.bvh"
    write_bvh(_random_motion(tiny_skeleton, 16), path)
    return path


def _argv(command: str, bvh: Path, out: Path) -> List[str]:
    return {"reconstruct": ["reconstruct", str(bvh), str(out)],
            "retarget": ["retarget", str(bvh), "--target", str(bvh), str(out)],
            "generate": ["generate", "--text", "a person walks", "--skeleton", str(bvh),
                         str(out), "--seconds", "1"]}[command]


def _no_cuda(monkeypatch, count: int = 0) -> None:
    monkeypatch.setattr(torch.cuda, "is_available", lambda: count > 0)
    monkeypatch.setattr(torch.cuda, "device_count", lambda: count)


@pytest.mark.parametrize("command", ["reconstruct", "retarget", "generate"])
@pytest.mark.parametrize("device, count, says", [
    ("cuda", 0, "--device cuda: no CUDA device on this machine"),
    ("cuda:1", 1, "--device cuda:1: this machine has 1 CUDA device(s), cuda:0 to cuda:0"),
    ("meta", 0, "--device meta: not a device satagraph runs on"),
    ("gpu", 0, "--device gpu: not a device (cpu, cuda, cuda:1, mps)"),
])
def test_a_device_this_machine_lacks_is_one_line(bvh, tmp_path, capsys, monkeypatch,
                                                command, device, count, says):
    """``--device`` was no option of these commands (argparse's
    'unrecognized arguments'): they always ran on the CPU."""
    _no_cuda(monkeypatch, count)
    out = tmp_path / "out.bvh"
    assert main(_argv(command, bvh, out) + ["--device", device]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"satagraph: error: {says}") and err.count("\n") == 1
    assert not out.exists()


class _Loaded(Exception):
    """Raised by the spies once they saw where the model goes."""


@pytest.mark.parametrize("command", ["reconstruct", "retarget", "generate"])
def test_the_model_is_loaded_onto_the_device(bvh, tmp_path, monkeypatch, command):
    _no_cuda(monkeypatch, 2)
    seen = []

    def load_module(name, map_location="cpu"):
        seen.append(map_location)
        raise _Loaded

    class Generator:
        def to(self, device):
            seen.append(device)
            raise _Loaded

    import satagraph.experiment.train as train
    import satagraph.pipelines.generate as generate
    monkeypatch.setattr(train, "load_module", load_module)
    monkeypatch.setattr(generate, "load_generator", lambda ckpt: Generator())
    with pytest.raises(_Loaded):
        main(_argv(command, bvh, tmp_path / "out.bvh") + ["--device", "cuda:1",
                                                           "--ckpt", "builtin"])
    assert seen == ["cuda:1"]
