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


def test_a_bare_state_dict_is_named_as_one(tmp_path) -> None:
    """``torch.save(model.state_dict(), path)`` given as a checkpoint was
    refused as having "no state_dict"."""
    from satagraph.io.checkpoint import CheckpointError, load_checkpoint
    path = tmp_path / "weights.pt"
    torch.save({"encoder.weight": torch.zeros(2, 2), "encoder.bias": torch.zeros(2)}, path)
    with pytest.raises(CheckpointError, match=r"weights.pt: a bare state dict \(2 tensors, "
                       r"e.g. 'encoder.weight'\), not a satagraph checkpoint: it holds no "
                       r"settings"):
        load_checkpoint(path)


def test_a_long_reason_is_cut_at_a_word(tmp_path) -> None:
    """The reason of an unreadable checkpoint was cut at 120 characters
    mid-word ("... If yo")."""
    from satagraph.io.checkpoint import _clipped
    text = "word " * 40
    assert _clipped(text) == ("word " * 24).rstrip() + " ..."
    assert _clipped("short reason") == "short reason"
