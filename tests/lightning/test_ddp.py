"""Distributed data-parallel training on CPU (two processes, gloo)."""
from __future__ import annotations

import pickle
from typing import Any, Dict

import lightning as L
import pytest
import torch

from satagraph.experiment import train as train_mod
from satagraph.experiment.train import train

pytestmark = pytest.mark.skipif(not torch.distributed.is_available()
                                or not torch.distributed.is_gloo_available(),
                                reason="torch.distributed with gloo is not available")


def _ddp_overrides(strategy: str) -> Dict[str, Any]:
    return dict(strategy=strategy, devices=2, accelerator="cpu", max_epochs=1,
                limit_train_batches=1, limit_val_batches=0, num_sanity_val_steps=0,
                enable_model_summary=False)


@pytest.mark.parametrize("strategy", [
    "ddp_fork",
    # fresh interpreters import torch, PyG and satagraph again (10-25 s)
    pytest.param("ddp_spawn", marks=pytest.mark.slow),
])
def test_one_ddp_step_on_two_cpu_processes(strategy: str, tiny_config: Dict[str, Any]) -> None:
    cfg = dict(tiny_config, logger={"name": "none"})
    cfg["data"] = dict(cfg["data"], batch_size=2)
    module, _, trainer, run_dir = train(cfg, **_ddp_overrides(strategy))

    assert trainer.world_size == 2 and trainer.num_devices == 2
    assert trainer.strategy._get_process_group_backend() == "gloo"
    assert trainer.state.finished
    ckpt = torch.load(run_dir / "checkpoints" / "last.ckpt", map_location="cpu",
                      weights_only=True)
    assert ckpt["global_step"] == 1
    # Rank 0's trained weights come back to the main process.
    for key, value in ckpt["state_dict"].items():
        torch.testing.assert_close(module.state_dict()[key], value, msg=key)
    assert torch.isfinite(trainer.callback_metrics["train_loss"])


def test_spawned_workers_get_a_picklable_datamodule(tiny_config: Dict[str, Any],
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    """``ddp_spawn`` pickles the data module; the set-up one holds the
    semantic embedder (a closure), so :func:`train` must hand over a fresh
    one."""
    seen = {}

    def fake_fit(self: L.Trainer, module: L.LightningModule, datamodule=None,
                 ckpt_path=None) -> None:
        seen["spawns"] = train_mod._spawns_workers(self)
        seen["datamodule"] = datamodule
        seen["normalizer_fitted"] = bool(module.normalizer.fitted)

    monkeypatch.setattr(L.Trainer, "fit", fake_fit)
    cfg = dict(tiny_config, logger={"name": "none"})
    train(cfg, **_ddp_overrides("ddp_spawn"))
    assert seen["spawns"] and seen["normalizer_fitted"]
    assert pickle.loads(pickle.dumps(seen["datamodule"])).sources == cfg["data"]["sources"]
    # Forked workers share memory: the set-up data module is kept.
    train(cfg, **_ddp_overrides("ddp_fork"))
    assert not seen["spawns"] and seen["datamodule"].datasets


@pytest.mark.slow
def test_ddp_validation_logs_per_dataset_figures_of_both_processes(
        tiny_config: Dict[str, Any]) -> None:
    """Each process validates its own share of the batches; the per-dataset
    figures are summed over both before they are logged, and every process
    logs the same keys (no hang where one saw a dataset the other did not)."""
    cfg = dict(tiny_config, logger={"name": "none"})
    cfg["data"] = dict(cfg["data"], batch_size=2)
    overrides = dict(_ddp_overrides("ddp_fork"), limit_val_batches=2)
    _, _, trainer, _ = train(cfg, **overrides)
    per_dataset = [k for k in trainer.callback_metrics if k.startswith("val/") and k.count("/") == 2]
    assert per_dataset and all(torch.isfinite(trainer.callback_metrics[k]) for k in per_dataset)
