"""A run says only what its user can act on: no "not empty" warning for the
folder a resume goes on in, no advertised cloud logger."""
from __future__ import annotations

import logging
import warnings
from pathlib import Path

import pytest
from lightning.pytorch.callbacks import ModelCheckpoint

from satagraph.datasets.zoo import write_zoo
from satagraph.experiment.config import load_config
from satagraph.experiment.train import LIGHTNING_INFO, train


def _config(root: Path, epochs: int) -> dict:
    return load_config("tiny", [
        f"data.sources=[{root / 'zoo' / 'manifest.tsv'}]", f"data.cache_dir={root / 'cache'}",
        "data.window=16", "data.stride=16", "data.batch_size=4", "data.max_files=null",
        "logger.name=none", "trainer.progress=false", "trainer.enable_model_summary=false",
        f"trainer.max_epochs={epochs}", "trainer.limit_train_batches=1",
        "trainer.limit_val_batches=1", "trainer.num_sanity_val_steps=0", "threads=1",
        f"output_dir={root / 'run'}"])


@pytest.mark.slow
def test_a_resume_is_not_warned_of_its_own_checkpoints(tmp_path: Path,
                                                       caplog: pytest.LogCaptureFixture) -> None:
    write_zoo(tmp_path / "zoo", species=["biped"], clips=3, frames=32)
    with caplog.at_level(logging.INFO, logger=LIGHTNING_INFO):
        train(_config(tmp_path, 1))
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            mine = tmp_path / "mine"  # a checkpoint folder of one's own, not empty: said
            mine.mkdir()
            (mine / "other.ckpt").write_bytes(b"")
            _, _, trainer, _ = train(_config(tmp_path, 2), resume=True,
                                     callbacks=[ModelCheckpoint(dirpath=str(mine))])
    assert trainer.global_step == 2  # it did go on, from the first run's step
    said = [str(w.message) for w in seen]
    assert [m for m in said if "exists and is not empty" in m] == [
        f"Checkpoint directory {mine.resolve()} exists and is not empty."], said
    infos = [r.getMessage() for r in caplog.records if r.name == LIGHTNING_INFO]
    assert any("GPU available" in m for m in infos)  # Lightning's own lines stay
    assert not [m for m in infos if "litlogger" in m], infos
