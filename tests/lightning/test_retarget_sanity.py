"""benchmarks/retarget_sanity.py end to end on a tiny model and real clips
(the trained checkpoints' tables are in benchmarks/results/)."""
from __future__ import annotations

import sys
from pathlib import Path
from typing import Callable

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

import retarget_sanity as rs  # noqa: E402


def test_run_scores_every_case_and_control(build_tiny_module: Callable, shared_data: Path,
                                           monkeypatch: pytest.MonkeyPatch) -> None:
    """Two dog clips onto a human rig: one row per clip for the trained
    model, the re-initialised control and the reconstruction; a summary
    row per (model, target) with the shuffled control; every correlation a
    finite number in [-1, 1]."""
    module = build_tiny_module("vae")
    monkeypatch.setattr(rs, "load_module", lambda ckpt: module)
    dogs = [shared_data / "dog" / name for name in ("D1_001_KAN01_001.bvh",
                                                    "D1_004_KAN01_001.bvh")]
    human = shared_data / "bandai" / "dataset-1_walk_normal_001.bvh"
    text = rs.run("tiny.ckpt", dogs, [human], frames=48)
    rows = [line for line in text.splitlines() if line.startswith("| ") and ".bvh |" in line]
    per_clip = [r for r in rows if r.count(".bvh") >= 2]
    assert len(per_clip) == 2 * 3
    summary = {tuple(c.strip() for c in line.split("|")[1:3])
               for line in text.split("| model | target |")[1].splitlines()[2:] if line}
    target = "bandai/dataset-1_walk_normal_001.bvh"
    assert summary == {(rs.TRAINED, target), ("re-initialised (chance)", target),
                       (rs.RECONSTRUCTION, "dog"), (rs.SHUFFLED, target)}
    for line in per_clip:
        values = [float(c) for c in line.split("|")[4:-1]]
        assert len(values) == len(rs.LIMBS) + 3
        assert all(-1.0 <= v <= 1.0 for v in values)
