"""A run stopped (``kill -9``, a full disk) after its first epoch's best
checkpoint was written and before its first ``last.ckpt`` was whole is
not a dead end: ``--resume`` goes on from that epoch checkpoint."""
from __future__ import annotations

import copy
from pathlib import Path
from typing import Any, Dict

import pytest

from satagraph.experiment.train import refuse_trained_folder, train
from satagraph.io.checkpoint import load_checkpoint
from satagraph.lightning.reliability import LAST, PREVIOUS, resume_checkpoint
from satagraph.utils.files import HOST


@pytest.mark.slow  # two training runs
def test_resume_from_the_epoch_checkpoint_when_no_last_was_written_whole(
        tiny_config: Dict[str, Any]) -> None:
    cfg = copy.deepcopy(tiny_config)
    cfg["trainer"]["max_epochs"] = 1
    train(cfg)
    folder = Path(cfg["output_dir"]) / "checkpoints"
    best = sorted(folder.glob("epoch=*.ckpt"))
    assert len(best) == 1
    step = load_checkpoint(best[0])["global_step"]
    assert step > 0
    # the state a kill -9 in the first last.ckpt write leaves: no last.ckpt, the
    # dead process's empty temporary file beside the epoch checkpoint
    (folder / LAST).unlink()
    (folder / PREVIOUS).unlink(missing_ok=True)
    (folder / f".{LAST}.{HOST}-999999999.0123abcd.tmp.ckpt").write_bytes(b"")

    with pytest.raises(ValueError, match="holds a trained run") as err:
        refuse_trained_folder(Path(cfg["output_dir"]))
    assert ".tmp" not in str(err.value) and best[0].name in str(err.value)
    with pytest.warns(UserWarning, match="newest epoch checkpoint"):
        assert resume_checkpoint(folder) == best[0]

    cfg["trainer"]["max_epochs"] = 2
    with pytest.warns(UserWarning, match="newest epoch checkpoint"):
        _, _, trainer, _ = train(cfg, resume=True)
    assert trainer.current_epoch == 2 and trainer.global_step == 2 * step
    assert load_checkpoint(folder / LAST)["global_step"] == 2 * step
