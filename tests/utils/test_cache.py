"""The one cache root: features under it, text embeddings in its
``embeddings/`` folder unless ``$SATAGRAPH_CACHE`` moves it."""
from __future__ import annotations

from pathlib import Path

from satagraph.utils.cache import ENV_VAR, cache_moved, cache_root


def test_cache_root_default_and_moved(tmp_path, monkeypatch):
    from satagraph.data.cache import default_cache_dir as feature_cache
    from satagraph.semantics.cache import default_cache_dir as embedding_cache
    monkeypatch.delenv(ENV_VAR, raising=False)
    home = Path("~/.cache/satagraph").expanduser()
    assert cache_root() == home and not cache_moved()
    assert feature_cache() == home and embedding_cache() == home / "embeddings"
    monkeypatch.setenv(ENV_VAR, str(tmp_path))
    assert cache_root() == tmp_path and cache_moved()
    assert feature_cache() == tmp_path and embedding_cache() == tmp_path
    monkeypatch.setenv(ENV_VAR, "")
    assert cache_root() == home
