"""A sweep stopped part way (Ctrl-C in its third hour) keeps the rows of
the configs it finished, running it again says what to do, and
``--resume`` goes on with it."""
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
    assert "holds a trained run" in text and "--output" in text and "--resume goes on" in text


def test_a_resumed_sweep_keeps_its_rows_and_goes_on_where_it_stopped(tmp_path: Path,
                                                                      monkeypatch) -> None:
    """A stopped sweep could only be run again from its first config in
    another --output (hours of finished rows trained again); --resume keeps
    them, resumes the config it stopped in, and refuses other settings."""
    from satagraph.experiment.train import _record_config, check_config
    calls = []

    def run_config(run, resume=False, **kw):
        calls.append((run.cfg["name"], resume))
        folder = Path(run.cfg["output_dir"])
        _record_config(check_config(run.cfg), folder)
        (folder / "checkpoints").mkdir(exist_ok=True)
        (folder / "checkpoints" / "last.ckpt").write_bytes(b"trained")
        if run.cfg["name"] == "tiny_2" and not resume:
            raise KeyboardInterrupt
        return SweepRow(run.cfg["name"], run.source, params=5, steps=3, train_loss=1.0,
                        run_dir=run.cfg["output_dir"],
                        metrics={"all": {n: 0.1 for n in ("JR", "RT", "JP", "FS", "GP")}})
    monkeypatch.setattr(sweep_mod, "run_config", run_config)
    quiet = dict(log=lambda *a: None)
    with pytest.raises(KeyboardInterrupt):
        sweep_mod.run_sweep(["tiny", "tiny", "tiny"], 0.01, str(tmp_path), **quiet)
    with pytest.raises(ValueError, match=r"sweep --resume: config tiny \(tiny\): .* was "
                                         r"trained with trainer.max_time.seconds=0.6 \(here 1.2\)"):
        sweep_mod.run_sweep(["tiny", "tiny", "tiny"], 0.02, str(tmp_path), resume=True, **quiet)
    # where a run logs is no setting of its row: a folder recorded before
    # logger.group existed (or with another) goes on
    from omegaconf import OmegaConf
    recorded = tmp_path / "1_tiny_2" / "config.yaml"
    before = OmegaConf.load(recorded)
    before.logger.pop("group", None)
    before.logger.name = "csv"
    OmegaConf.save(before, recorded)
    calls.clear()
    rows = sweep_mod.run_sweep(["tiny", "tiny", "tiny"], 0.01, str(tmp_path), resume=True,
                               **quiet)
    assert calls == [("tiny_2", True), ("tiny_3", False)]  # tiny kept, tiny_2 goes on
    assert [r.name for r in rows] == ["tiny", "tiny_2", "tiny_3"]
    assert (tmp_path / "sweep.md").read_text().startswith("# Sweep: 3 configs")
    # a row whose run folder is gone trains again (its settings cannot be checked)
    import shutil
    shutil.rmtree(tmp_path / "0_tiny")
    calls.clear()
    sweep_mod.run_sweep(["tiny", "tiny", "tiny"], 0.01, str(tmp_path), resume=True, **quiet)
    assert calls == [("tiny", False)]
