"""benchmarks/device_check.py refuses in one line where the device is
missing, running nothing (its checks need a GPU)."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest
import torch

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import device_check  # noqa: E402


@pytest.mark.parametrize("argv, says", [
    ([], "device_check: --device cuda: no CUDA device on this machine"),
    (["--device", "cuda:1"], "device_check: --device cuda:1: no CUDA device on this machine"),
    (["--device", "gpu0"], "device_check: --device gpu0: not a device"),
])
def test_without_a_gpu_it_refuses_in_one_line(monkeypatch, capsys, argv, says):
    monkeypatch.setattr(torch.cuda, "is_available", lambda: False)
    monkeypatch.setattr(device_check, "run_checks", lambda *a: pytest.fail("ran checks"))
    assert device_check.main(argv) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.startswith(says) and err.count("\n") == 1
