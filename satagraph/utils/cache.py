"""The one cache root of satagraph: preprocessed features and text
embeddings live under it."""
from __future__ import annotations

import os
from pathlib import Path

#: Environment variable that moves the cache root.
ENV_VAR = "SATAGRAPH_CACHE"


def cache_root() -> Path:
    """``$SATAGRAPH_CACHE`` (when set and not empty), else ``~/.cache/satagraph``.

    Returns:
        Path: The cache root, user expanded (not created).
    """
    return Path(os.environ.get(ENV_VAR) or "~/.cache/satagraph").expanduser()


def cache_moved() -> bool:
    """Whether ``$SATAGRAPH_CACHE`` moves the cache root."""
    return bool(os.environ.get(ENV_VAR))


__all__ = ["ENV_VAR", "cache_root", "cache_moved"]
