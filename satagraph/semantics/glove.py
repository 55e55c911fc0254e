"""Word vectors (GloVe and the like) from a local text file, averaged over
the words of a text."""
from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Dict, List, Optional, Sequence

import numpy as np
import torch
from torch import Tensor

from satagraph.semantics.encoders import _WORD, PathLike, TextEncoder

GLOVE_HELP = ("satagraph never downloads word vectors: pass a local text file of "
              "'word v1 v2 ...' lines (e.g. glove.6B.50d.txt) as "
              "GloVeEncoder('glove.6B.50d.txt') or 'glove:glove.6B.50d.txt'.")


def _file_digest(path: Path) -> str:
    h = hashlib.blake2b(digest_size=8)
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _is_header(fields: List[str]) -> bool:
    """A word2vec-style ``count dim`` first line."""
    return len(fields) == 2 and all(f.isdigit() for f in fields)


class GloVeEncoder(TextEncoder):
    r"""Mean of the word vectors of a text, from a local ``word v1 ... vD``
    text file (GloVe's format; a word2vec ``count dim`` header line is
    skipped).

    Words are the lower-cased whitespace-separated tokens without their
    surrounding punctuation. A token missing from the file falls back on
    its alphanumeric parts (``"not-confident"`` -> ``"not"``,
    ``"confident"``); parts still unknown are skipped. A text without any
    known word gets the zero vector. Vectors are L2-normalised unless
    :obj:`normalize` is false. The file is read on the first
    :meth:`encode`; :attr:`id` holds a hash of its bytes.

    Args:
        path (str or PathLike): The word-vector file.
        normalize (bool): L2-normalise the embeddings (default ``True``).

    Raises:
        FileNotFoundError: No file at :obj:`path`.
        ValueError: A malformed line (file and line number in the message).
    """

    def __init__(self, path: PathLike, normalize: bool = True) -> None:
        self.path = Path(path).expanduser().resolve()
        if not self.path.is_file():
            raise FileNotFoundError(f"GloVeEncoder: no word-vector file at {self.path}. "
                                    f"{GLOVE_HELP}")
        self.normalize = bool(normalize)
        self._dim = self._read_dim()
        self._id = (f"glove:{self.path.name}:{_file_digest(self.path)}:d{self._dim}"
                    f"{'' if self.normalize else ':raw'}")
        self._index: Optional[Dict[str, int]] = None
        self._vectors: Optional[np.ndarray] = None

    def _read_dim(self) -> int:
        with open(self.path, encoding="utf-8") as f:
            for number, line in enumerate(f, start=1):
                fields = line.split()
                if not fields or (number == 1 and _is_header(fields)):
                    continue
                if len(fields) < 2:
                    raise ValueError(f"{self.path}:{number}: expected 'word v1 v2 ...'")
                return len(fields) - 1
        raise ValueError(f"{self.path}: no word vectors in the file")

    @property
    def vocabulary_size(self) -> int:
        """Words in the file (reads it)."""
        return len(self.load()._index)

    def load(self) -> "GloVeEncoder":
        """Read the file now (otherwise on first use).

        Returns:
            GloVeEncoder: self.
        """
        if self._index is not None:
            return self
        index: Dict[str, int] = {}
        rows: List[np.ndarray] = []
        with open(self.path, encoding="utf-8") as f:
            for number, line in enumerate(f, start=1):
                fields = line.split()
                if not fields or (number == 1 and _is_header(fields)):
                    continue
                rows.append(self._parse(fields, number))
                index.setdefault(fields[0], len(rows) - 1)
        self._vectors = np.stack(rows).astype(np.float32)
        self._index = index
        return self

    def _parse(self, fields: List[str], number: int) -> np.ndarray:
        if len(fields) != self._dim + 1:
            raise ValueError(f"{self.path}:{number}: expected a word and {self._dim} "
                             f"numbers, found {len(fields)} fields")
        try:
            return np.array(fields[1:], dtype=np.float64)
        except ValueError:
            raise ValueError(f"{self.path}:{number}: the values of {fields[0]!r} are not "
                             "all numbers") from None

    def words(self, text: str) -> List[str]:
        """The known words of a text that its vector averages.

        Args:
            text: A text.

        Returns:
            list[str]: Known words, in order (repeats kept).
        """
        self.load()
        out = []
        for token in text.lower().split():
            token = token.strip(".,;:!?\"'()[]{}")
            if token in self._index:
                out.append(token)
            else:
                out += [w for w in _WORD.findall(token) if w in self._index]
        return out

    def encode(self, texts: Sequence[str]) -> Tensor:
        self.load()
        out = np.zeros((len(texts), self._dim), dtype=np.float32)
        for i, text in enumerate(texts):
            rows = [self._index[w] for w in self.words(text)]
            if not rows:
                continue
            vec = self._vectors[rows].mean(axis=0)
            norm = float(np.linalg.norm(vec))
            out[i] = vec / norm if self.normalize and norm > 0 else vec
        return torch.from_numpy(out)


__all__ = ["GloVeEncoder", "GLOVE_HELP"]
