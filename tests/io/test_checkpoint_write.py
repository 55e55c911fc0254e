"""A checkpoint that cannot be written (a full disk) is one OSError naming
it, and the previous checkpoint is kept."""
from __future__ import annotations

from pathlib import Path

import pytest
import torch

from satagraph.io.checkpoint import load_checkpoint, save_checkpoint


def test_a_failed_checkpoint_write_names_the_file_and_keeps_the_previous(
        tmp_path: Path, file_size_limit) -> None:
    gen = torch.Generator().manual_seed(0)
    path = tmp_path / "checkpoints" / "last.ckpt"
    small = {"state_dict": {"w": torch.randn(8, generator=gen)}}
    save_checkpoint(small, path)
    big = {"state_dict": {"w": torch.randn(200_000, generator=gen)}}  # 800 kB
    with file_size_limit(200_000), pytest.raises(OSError) as err:
        save_checkpoint(big, path)
    text = str(err.value)
    assert str(path) in text and "too large" in text  # not "enforce fail ... unexpected pos"
    kept = load_checkpoint(path)["state_dict"]["w"]
    assert torch.equal(kept, small["state_dict"]["w"])
    assert sorted(p.name for p in path.parent.iterdir()) == ["last.ckpt"]  # no temporary file
