"""A sentence-transformers model (e.g. all-MiniLM-L6-v2) from a local
folder, through ``transformers`` alone: mean pooling and L2 norm, nothing
downloaded."""
from __future__ import annotations

import json
from pathlib import Path
from typing import Optional, Sequence, Union

import torch
import torch.nn.functional as F
from torch import Tensor

from satagraph.semantics.encoders import (PathLike, TextEncoder,
                                          _folder_fingerprint, default_device,
                                          encode_mean_pooled, load_frozen)

SENTENCE_HELP = (
    "satagraph never downloads models. Get a sentence-transformers folder "
    "(config.json, weights, tokenizer files; e.g. all-MiniLM-L6-v2) on a "
    "machine with network access, copy it here and pass it: "
    "SentenceEncoder('./all-MiniLM-L6-v2') or 'sentence:./all-MiniLM-L6-v2'.")


def _transformer_folder(path: Path) -> Path:
    """The folder of the transformer module: ``path`` itself, or the
    ``Transformer`` module's folder named in ``modules.json``."""
    modules = path / "modules.json"
    if not modules.is_file():
        return path
    try:
        entries = json.loads(modules.read_text())
    except (OSError, ValueError) as err:
        raise FileNotFoundError(f"SentenceEncoder: unreadable {modules}: {err}") from None
    for entry in entries if isinstance(entries, list) else []:
        if str(entry.get("type", "")).endswith("Transformer"):
            return path / str(entry.get("path", ""))
    return path


def _check_pooling(path: Path) -> None:
    """Refuse a folder whose pooling is not the mean of the tokens."""
    for config in sorted(path.glob("*Pooling/config.json")):
        try:
            modes = json.loads(config.read_text())
        except (OSError, ValueError) as err:
            raise ValueError(f"SentenceEncoder: unreadable {config}: {err}") from None
        if not modes.get("pooling_mode_mean_tokens", True):
            used = [k for k, v in modes.items() if k.startswith("pooling_mode") and v]
            raise ValueError(f"SentenceEncoder: {config} pools with {used}; only mean "
                             "pooling (pooling_mode_mean_tokens) is supported")


class SentenceEncoder(TextEncoder):
    r"""Frozen sentence-transformers encoder loaded from a local folder.

    Loaded lazily on the first :meth:`encode` with
    ``AutoModel.from_pretrained(path, local_files_only=True)`` and
    ``AutoTokenizer.from_pretrained(path, local_files_only=True)`` (the
    ``sentence-transformers`` package is not needed); eval mode, gradients
    off. Embeddings are the mean of the last hidden states over non-padding
    tokens, L2-normalised, as ``all-MiniLM-L6-v2`` is used. A folder laid
    out by sentence-transformers (``modules.json``, ``1_Pooling``) is read
    for where the transformer lies and checked for mean pooling.

    Args:
        path (str or PathLike): The model folder.
        device (str or torch.device, optional): Where to run; CUDA when
            available, else CPU.
        batch_size (int): Texts per forward pass (default 64).
        max_length (int): Token limit per text (default 256).

    Raises:
        FileNotFoundError: No folder or no ``config.json`` at :obj:`path`
            (one line naming the path).
        ValueError: The folder pools otherwise than by the mean.
    """

    def __init__(self, path: PathLike,
                 device: Union[str, torch.device, None] = None,
                 batch_size: int = 64, max_length: int = 256) -> None:
        self.path = Path(path).expanduser().resolve()
        if not self.path.is_dir():
            raise FileNotFoundError(f"SentenceEncoder: no model folder at {self.path}. "
                                    f"{SENTENCE_HELP}")
        self.model_path = _transformer_folder(self.path)
        config = self.model_path / "config.json"
        if not config.is_file():
            raise FileNotFoundError(f"SentenceEncoder: {self.path} is not a model folder "
                                    f"({config} missing). {SENTENCE_HELP}")
        _check_pooling(self.path)
        self._dim = int(json.loads(config.read_text()).get("hidden_size", 0))
        self._id = f"sentence:{self.path.name}:{_folder_fingerprint(self.model_path)}"
        self.device = default_device(device)
        self.batch_size, self.max_length = int(batch_size), int(max_length)
        self._model: Optional[torch.nn.Module] = None
        self._tokenizer = None

    def load(self) -> "SentenceEncoder":
        """Load tokenizer and model now (otherwise on first use).

        Returns:
            SentenceEncoder: self.
        """
        if self._model is not None:
            return self
        from transformers import AutoModel
        self._model, self._tokenizer = load_frozen(
            AutoModel, self.model_path, self.device, self._load_error)
        self._dim = int(self._model.config.hidden_size)
        return self

    def _load_error(self, said: str) -> FileNotFoundError:
        return FileNotFoundError(f"SentenceEncoder: cannot load a model and tokenizer "
                                 f"from {self.model_path}: {said}. {SENTENCE_HELP}")

    @torch.inference_mode()
    def encode(self, texts: Sequence[str]) -> Tensor:
        self.load()
        pooled = encode_mean_pooled(self._model, self._tokenizer, texts, self._dim,
                                    self.device, self.batch_size, self.max_length)
        return F.normalize(pooled, dim=-1)


__all__ = ["SentenceEncoder", "SENTENCE_HELP"]
