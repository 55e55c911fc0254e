"""Disk cache of description embeddings, keyed by (encoder id, text).

One file per encoder id, ``<cache_dir>/<id>-<hash>.pt``, holding the texts
and a ``[N, D]`` float32 tensor. The directory is the ``cache_dir``
argument, else the ``SATAGRAPH_CACHE`` environment variable, else
``~/.cache/satagraph/embeddings``. Files are written atomically (temporary
file + :func:`os.replace`), merged with whatever another process wrote in the
meantime under a lock file (:func:`lock_path`); an unreadable or malformed
file is ignored with a warning and rebuilt; an unwritable directory only costs a warning. Loaded tables are kept
in memory and reused while the file on disk is unchanged.
"""
from __future__ import annotations

import hashlib
import os
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple, Union

import torch
from torch import Tensor

from satagraph.io.checkpoint import save_checkpoint
from satagraph.semantics.encoders import TextEncoder
from satagraph.utils.cache import cache_moved, cache_root
from satagraph.utils.files import file_lock

PathLike = Union[str, "os.PathLike[str]"]
FORMAT = "satagraph-embeddings"


def default_cache_dir() -> Path:
    """``$SATAGRAPH_CACHE`` or ``~/.cache/satagraph/embeddings``.

    Returns:
        Path: The cache directory (not created).
    """
    return cache_root() if cache_moved() else cache_root() / "embeddings"


def cache_file(cache_dir: PathLike, encoder_id: str) -> Path:
    """File that stores the embeddings of one encoder.

    Args:
        cache_dir: The cache directory.
        encoder_id: :attr:`TextEncoder.id`.

    Returns:
        Path: ``<cache_dir>/<readable id>-<12 hex>.pt``.
    """
    safe = re.sub(r"[^A-Za-z0-9._-]+", "_", encoder_id)[:60]
    digest = hashlib.blake2b(encoder_id.encode(), digest_size=6).hexdigest()
    return Path(cache_dir) / f"{safe}-{digest}.pt"


def lock_path(path: Path) -> Path:
    """The lock file a writer of the cache file :obj:`path` holds while it
    merges and writes (``.<name>.lock``, removed after)."""
    return path.with_name(f".{path.name}.lock")


@dataclass
class _Table:
    texts: List[str] = field(default_factory=list)
    rows: Dict[str, int] = field(default_factory=dict)
    emb: Optional[Tensor] = None
    stamp: Optional[Tuple[int, int]] = None

    def add(self, texts: Sequence[str], emb: Tensor) -> None:
        for text in texts:
            self.rows[text] = len(self.texts)
            self.texts.append(text)
        self.emb = emb if self.emb is None else torch.cat([self.emb, emb])


_MEMORY: Dict[Path, _Table] = {}


def _stamp(path: Path) -> Optional[Tuple[int, int]]:
    try:
        st = path.stat()
    except OSError:
        return None
    return (st.st_mtime_ns, st.st_size)


def _read_table(path: Path, encoder_id: str, dim: int) -> _Table:
    """Read a cache file; an absent file is empty, a bad one warns."""
    stamp = _stamp(path)
    if stamp is None:
        return _Table()
    try:
        data = torch.load(path, map_location="cpu", weights_only=True)
        texts, emb = data["texts"], data["embeddings"]
        ok = (data.get("format") == FORMAT and data.get("encoder_id")
              == encoder_id and isinstance(texts, list)
              and all(isinstance(t, str) for t in texts)
              and isinstance(emb, Tensor) and emb.dtype == torch.float32
              and tuple(emb.shape) == (len(texts), dim))
        if not ok:
            raise ValueError("unexpected content")
    except Exception as err:  # noqa: BLE001 - any corruption is non-fatal
        warnings.warn(f"ignoring unreadable embedding cache {path}"
                      f" ({type(err).__name__}: {err}); it will be rebuilt",
                      RuntimeWarning, stacklevel=3)
        return _Table()
    table = _Table(stamp=stamp)
    table.add(texts, emb)
    return table


class EmbeddingCache:
    r"""Embeddings of texts per encoder, on disk and in memory.

    Args:
        cache_dir (str or PathLike, optional): Directory; see
            :func:`default_cache_dir`.
    """

    def __init__(self, cache_dir: Optional[PathLike] = None) -> None:
        self.cache_dir = Path(cache_dir).expanduser() if cache_dir is not None \
            else default_cache_dir()

    def _table(self, encoder: TextEncoder) -> Tuple[Path, _Table]:
        path = cache_file(self.cache_dir, encoder.id)
        table = _MEMORY.get(path)
        if table is None or table.stamp != _stamp(path):
            table = _read_table(path, encoder.id, encoder.out_channels)
            _MEMORY[path] = table
        return path, table

    def embed(self, encoder: TextEncoder, texts: Sequence[str]) -> Tensor:
        """Embeddings of :obj:`texts`, encoding only the ones not cached.

        Args:
            encoder: The text encoder.
            texts: N texts (duplicates allowed).

        Returns:
            Tensor: float32 ``[N, D]``.
        """
        path, table = self._table(encoder)
        missing = [t for t in dict.fromkeys(texts) if t not in table.rows]
        if missing:
            emb = encoder.encode(missing).detach().float().cpu()
            if emb.shape != (len(missing), encoder.out_channels):
                raise ValueError(f"{encoder!r} returned shape "
                                 f"{tuple(emb.shape)} for {len(missing)} "
                                 f"texts, expected D={encoder.out_channels}")
            table = self._store(path, encoder, table, missing, emb)
        if not texts:
            return torch.zeros(0, encoder.out_channels)
        index = torch.tensor([table.rows[t] for t in texts])
        return table.emb.index_select(0, index)

    def _store(self, path: Path, encoder: TextEncoder, table: _Table,
               texts: List[str], emb: Tensor) -> _Table:
        """Merge new rows with the file on disk and write it atomically,
        holding its lock file (:func:`lock_path`): a write of another process
        between a merge and its write was replaced, its new rows lost."""
        try:  # a full disk is an OSError there, costing the cache alone
            with file_lock(lock_path(path), create_parent=True):
                if _stamp(path) != table.stamp:  # someone else wrote meanwhile
                    table = _read_table(path, encoder.id, encoder.out_channels)
                _add_new(table, texts, emb)
                save_checkpoint({"format": FORMAT, "encoder_id": encoder.id,
                                 "texts": table.texts, "embeddings": table.emb}, path)
                table.stamp = _stamp(path)
        except OSError as err:
            warnings.warn(f"cannot write embedding cache {path} "
                          f"({err}); continuing without it", RuntimeWarning,
                          stacklevel=3)
            _add_new(table, texts, emb)
            table.stamp = None
        _MEMORY[path] = table
        return table


def _add_new(table: _Table, texts: List[str], emb: Tensor) -> None:
    """Add the rows of :obj:`texts` that :obj:`table` lacks."""
    new = [i for i, t in enumerate(texts) if t not in table.rows]
    if new:
        table.add([texts[i] for i in new], emb[new])


def clear_memory() -> None:
    """Forget the in-memory copies of cache files (the files stay)."""
    _MEMORY.clear()
