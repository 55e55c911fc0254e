"""Per-dataset figures: weighted epoch means per dataset, the same in one
process as summed over the processes of a distributed run whose processes
saw different datasets."""
from __future__ import annotations

from pathlib import Path

import pytest
import torch
import torch.distributed as dist
import torch.multiprocessing as mp

from satagraph.lightning.per_dataset import epoch_means, log_per_dataset

pytestmark = pytest.mark.skipif(not dist.is_available() or not dist.is_gloo_available(),
                                reason="torch.distributed with gloo is not available")


class _Module:
    """What the functions read of a LightningModule."""
    device = torch.device("cpu")


def test_epoch_means_are_weighted_over_batches_and_forgotten():
    module = _Module()
    log_per_dataset(module, "val", {"jp": torch.tensor([1.0, 2.0, 4.0])}, ["a", "b", "a"],
                    torch.tensor([1, 3, 0]))  # the third clip weighs nothing
    log_per_dataset(module, "val", {"jp": torch.tensor([3.0])}, ["a"], torch.tensor([3]))
    log_per_dataset(module, "test", {"jp": torch.tensor([7.0])}, ["a"])
    assert epoch_means(module, "val") == pytest.approx({"val/a/jp": (1 + 9) / 4,
                                                        "val/b/jp": 2.0})
    assert epoch_means(module, "val") == {}  # read once
    assert epoch_means(module, "test") == {"test/a/jp": 7.0}


def _worker(rank: int, path: str, out: str) -> None:
    dist.init_process_group("gloo", init_method=f"file://{path}", rank=rank, world_size=2)
    module = _Module()
    if rank == 0:  # dataset "a" twice, "b" never
        log_per_dataset(module, "val", {"jp": torch.tensor([1.0, 3.0])}, ["a", "a"])
    else:  # "a" once, "b" once
        log_per_dataset(module, "val", {"jp": torch.tensor([5.0, 10.0])}, ["a", "b"])
    torch.save(epoch_means(module, "val"), f"{out}.{rank}")
    dist.destroy_process_group()


def test_a_distributed_run_sums_over_processes_that_saw_other_datasets(tmp_path: Path):
    out = str(tmp_path / "means")
    # forked: the workers need no new interpreter (a spawn takes 10-25 s)
    mp.start_processes(_worker, args=(str(tmp_path / "rendezvous"), out), nprocs=2,
                       join=True, start_method="fork")
    want = {"val/a/jp": 3.0, "val/b/jp": 10.0}  # (1 + 3 + 5) / 3 and 10 / 1
    for rank in range(2):
        assert torch.load(f"{out}.{rank}") == pytest.approx(want)
