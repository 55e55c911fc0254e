"""A code bank that cannot be written (a full disk) is one OSError naming
the file, after minutes of drawing: no traceback, no file left."""
from __future__ import annotations

from pathlib import Path

import pytest
import torch

from satagraph.data.code_bank import CodeBank


def _bank(windows: int, nodes: int = 20) -> CodeBank:
    gen = torch.Generator().manual_seed(0)
    frames = torch.full((windows,), 8, dtype=torch.long)
    codes = torch.randint(0, 256, (int(frames.sum()), 6), generator=gen)
    x = torch.randn(windows * nodes, 16, generator=gen)
    parent = torch.arange(-1, nodes - 1).repeat(windows)
    return CodeBank(codes, frames, x, parent, torch.full((windows,), nodes),
                    torch.ones(windows), ["a person walks"] * windows, "f")


def test_a_bank_that_cannot_be_written_names_its_file(tmp_path: Path, file_size_limit) -> None:
    path = tmp_path / "bank.safetensors"
    _bank(2).save(path)
    before = path.read_bytes()
    with file_size_limit(100_000), pytest.raises(OSError) as err:
        _bank(2000).save(path)  # about 1.4 MB
    assert str(path) in str(err.value) and "too large" in str(err.value)
    assert path.read_bytes() == before  # the previous bank is kept
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bank.safetensors"]
    assert len(CodeBank.load(path)) == 2


def test_a_bank_is_the_same_bytes_every_time(tmp_path: Path) -> None:
    """The metadata (format, fingerprint, texts, data) was written in a hash
    map's order, new at every save: two banks of one seed differed."""
    paths = [tmp_path / f"bank{i}.safetensors" for i in range(5)]
    bank = _bank(3)
    bank.data = {"sources": ["zoo"], "window": 8}
    for path in paths:
        bank.save(path)
    assert len({path.read_bytes() for path in paths}) == 1
    loaded = CodeBank.load(paths[0])
    assert torch.equal(loaded.codes, bank.codes) and loaded.texts == bank.texts
