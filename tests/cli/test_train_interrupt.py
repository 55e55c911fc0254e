"""Ctrl-C in ``satagraph train`` says what ``--resume`` will find: a run
stopped before its first checkpoint has nothing to resume (``--resume``
then said ``no checkpoint at .../last.ckpt``), one after it goes on."""
from __future__ import annotations

from pathlib import Path

import pytest

from satagraph.cli import main


def test_ctrl_c_says_whether_there_is_a_checkpoint_to_resume(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path, capsys) -> None:
    import satagraph.experiment.train as train_mod

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(train_mod, "train", interrupted)
    run = tmp_path / "run"
    assert main(["train", "tiny", f"output_dir={run}"]) == 130
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "interrupted before" in err[0]
    assert "nothing to resume" in err[0] and "without --resume" in err[0]

    (run / "checkpoints").mkdir(parents=True)
    (run / "checkpoints" / "last.ckpt").write_bytes(b"a checkpoint")
    assert main(["train", "tiny", f"output_dir={run}", "--resume"]) == 130
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"--resume goes on from {run / 'checkpoints' / 'last.ckpt'}" in err[0]


def test_ctrl_c_names_the_checkpoint_it_saved(monkeypatch: pytest.MonkeyPatch,
                                              tmp_path: Path, capsys) -> None:
    """An interrupt that wrote ``last.ckpt`` (its step the interrupt's
    argument, :meth:`ResumeCheckpoint.on_exception`) says so."""
    import satagraph.experiment.train as train_mod

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt(6)

    monkeypatch.setattr(train_mod, "train", interrupted)
    run = tmp_path / "run"
    assert main(["train", "tiny", f"output_dir={run}"]) == 130
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"satagraph: interrupted at step 6, saved as "
                   f"{run / 'checkpoints' / 'last.ckpt'}: train --resume goes on from there"]
