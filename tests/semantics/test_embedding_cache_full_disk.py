"""An embedding cache on a full disk costs a warning, as an unwritable one
does: the command goes on (a full ~/.cache ended retarget, reconstruct and
training with a 26-frame RuntimeError traceback)."""
from __future__ import annotations

from pathlib import Path

import pytest
import torch

from satagraph.semantics import EmbeddingCache, OfflineTextEncoder
from satagraph.semantics.cache import cache_file, clear_memory


def test_a_full_disk_under_the_embedding_cache_only_warns(tmp_path: Path, file_size_limit) -> None:
    encoder = OfflineTextEncoder()
    texts = [f"left hind limb segment {i}" for i in range(64)]  # 64 x 256 floats: 64 kB
    clear_memory()
    expected = EmbeddingCache(tmp_path / "fresh").embed(encoder, texts)
    clear_memory()
    with file_size_limit(8_000), pytest.warns(RuntimeWarning, match="cannot write"):
        got = EmbeddingCache(tmp_path / "full").embed(encoder, texts)
    torch.testing.assert_close(got, expected)
    folder = tmp_path / "full"
    assert not cache_file(folder, encoder.id).exists()
    assert [p.name for p in folder.iterdir()] == []  # no temporary file left
    clear_memory()
