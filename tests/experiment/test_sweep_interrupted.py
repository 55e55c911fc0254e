"""A sweep stopped part way (Ctrl-C in its third hour) keeps the rows of
the configs it finished, and running it again says what to do (train's
``--resume`` is no sweep option)."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from satagraph.experiment import sweep as sweep_mod
from satagraph.experiment.sweep import SweepRow


def test_an_interrupted_sweep_keeps_its_finished_rows(tmp_path: Path, monkeypatch) -> None:
    def run_config(run, **kw):
        if run.cfg["name"] == "tiny_3":
            raise KeyboardInterrupt
        folder = Path(run.cfg["output_dir"]) / "checkpoints"
        folder.mkdir(parents=True)
        (folder / "last.ckpt").write_bytes(b"trained")
        return SweepRow(run.cfg["name"], run.source, params=5, steps=3, train_loss=1.0,
                        metrics={"all": {n: 0.1 for n in ("JR", "RT", "JP", "FS", "GP")}})
    monkeypatch.setattr(sweep_mod, "run_config", run_config)
    with pytest.raises(KeyboardInterrupt):
        sweep_mod.run_sweep(["tiny", "tiny", "tiny"], 0.01, str(tmp_path), log=lambda *a: None)
    table = (tmp_path / "sweep.md").read_text()
    assert table.startswith("# Sweep: 2 of 3 configs so far")
    assert "| tiny | 5e-06 |" in table and "| tiny_2 | 5e-06 |" in table
    assert "tiny_3" not in table
    rows = json.loads((tmp_path / "sweep.json").read_text())["rows"]
    assert [r["name"] for r in rows] == ["tiny", "tiny_2"]

    with pytest.raises(ValueError) as err:
        sweep_mod.run_sweep(["tiny", "tiny", "tiny"], 0.01, str(tmp_path), log=lambda *a: None)
    text = str(err.value)
    assert "holds a trained run" in text and "--output" in text and "--resume" not in text
