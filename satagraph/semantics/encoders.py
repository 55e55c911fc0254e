"""Text encoders that turn joint descriptions into the semantic features X_t.

* :class:`OfflineTextEncoder` (the default) needs no weights: a hashed,
  weighted bag of words, word bigrams and character 4-grams, L2-normalised.
  It is deterministic across runs and machines (BLAKE2b hashing, never
  Python's salted :func:`hash`), depends only on the text, and gives close
  vectors to texts that share words. Functional words weigh most: side
  (left/right), front/hind and the segment roles (girdle, upper, lower,
  terminal, digit, tip).
* :class:`T5TextEncoder` loads a local T5 checkpoint with ``transformers``
  (no download, ever), frozen and in eval mode, and mean-pools the last
  hidden states over non-padding tokens, as SATA does with its frozen T5.
"""
from __future__ import annotations

import abc
import hashlib
import json
import os
import re
from functools import lru_cache
from pathlib import Path
from typing import Callable, Dict, List, Sequence, Tuple, Union

import numpy as np
import torch
from torch import Tensor

PathLike = Union[str, "os.PathLike[str]"]


class TextEncoder(abc.ABC):
    """Interface of the description encoders.

    Subclasses provide :meth:`encode` and set ``self._id`` and ``self._dim``
    (or override :attr:`id` / :attr:`out_channels`); :attr:`id` must change
    whenever the vectors would (it keys the disk cache).
    """

    _id: str
    _dim: int

    @property
    def id(self) -> str:
        """Stable identifier of the encoder and its weights."""
        return self._id

    @property
    def out_channels(self) -> int:
        """Embedding width D."""
        return self._dim

    @abc.abstractmethod
    def encode(self, texts: Sequence[str]) -> Tensor:
        """Embed texts.

        Args:
            texts: N strings.

        Returns:
            Tensor: float32 ``[N, D]`` on the CPU.
        """

    def __call__(self, texts: Sequence[str]) -> Tensor:
        return self.encode(texts)

    def __repr__(self) -> str:
        return f"{type(self).__name__}(id={self.id!r})"


# --------------------------------------------------------------- offline
STOPWORDS = frozenset({"the", "of", "a", "an", "and", "or", "to", "from",
                       "for", "in", "on", "at", "where", "with", "by", "is",
                       "its", "this", "that"})
WORD_WEIGHTS: Dict[str, float] = {
    **dict.fromkeys(("left", "right"), 1.5),
    **dict.fromkeys(("front", "hind"), 1.5),
    **dict.fromkeys(("girdle", "upper", "lower", "terminal", "digit", "tip"),
                    1.25),
    **dict.fromkeys(("first", "second", "third", "fourth", "fifth"), 1.0),
    **dict.fromkeys(("limb", "segment", "joint", "chain"), 0.5),
    **dict.fromkeys(("helper", "twist"), 1.0),
}
BIGRAM_SCALE = 0.5
CHAR_SCALE = 0.35
_WORD = re.compile(r"[a-z0-9]+")


def _hash(feature: str) -> Tuple[int, int]:
    digest = hashlib.blake2b(feature.encode("utf-8"), digest_size=8).digest()
    value = int.from_bytes(digest, "little")
    return value, 1 if (value >> 63) & 1 else -1


# Words of the canonical descriptions (and their common paraphrases) get an
# axis of their own, so that they never collide with each other; every other
# feature (other words, bigrams, character n-grams) is hashed into the
# remaining axes. Part of the encoder's version: changing it changes the id.
CORE_WORDS = tuple("""
left right front hind limb girdle upper lower terminal digit segment tip
helper twist first second third fourth fifth pelvis hips hip root center
motion skeleton ground reference body spine back chest waist neck head top
face jaw teeth tongue eye eyelid eyebrow ear snout nose lip mouth cheek beak
horn antler hair breast ribs tail clavicle shoulder blade arm forearm hand paw
finger fingers fingertip thumb index middle ring little palm wrist elbow thigh
shin calf foot toe toes knee ankle heel bone joint leg inverse kinematics
chain unnamed digits soft tissue big
""".split())
_CORE_INDEX = {w: i for i, w in enumerate(CORE_WORDS)}


@lru_cache(maxsize=65536)
def _feature_slot(feature: str, dim: int) -> Tuple[int, int]:
    reserved = len(CORE_WORDS) if dim >= 2 * len(CORE_WORDS) else 0
    if reserved and feature.startswith("w:") and feature[2:] in _CORE_INDEX:
        return _CORE_INDEX[feature[2:]], 1
    value, sign = _hash(feature)
    return reserved + value % (dim - reserved), sign


def _char_ngrams(word: str, n: int = 4) -> List[str]:
    padded = f"<{word}>"
    return [padded[i:i + n] for i in range(max(1, len(padded) - n + 1))]


def text_features(text: str) -> Dict[str, float]:
    """Weighted features of a text (before hashing).

    A word repeated ``c`` times counts ``sqrt(c)`` times, so that long
    descriptions do not drown in their own repetitions.

    Args:
        text: A description.

    Returns:
        dict[str, float]: feature -> weight. Words (``w:``), ordered word
        bigrams (``b:``) and character 4-grams of each word (``c:``).
    """
    words = [w for w in _WORD.findall(text.lower()) if w not in STOPWORDS]
    feats: Dict[str, float] = {}
    for word in words:
        weight = WORD_WEIGHTS.get(word, 1.0)
        feats[f"w:{word}"] = feats.get(f"w:{word}", 0.0) + weight ** 2
        grams = _char_ngrams(word)
        share = (CHAR_SCALE * weight) ** 2 / len(grams)
        for gram in grams:
            feats[f"c:{gram}"] = feats.get(f"c:{gram}", 0.0) + share
    for a, b in zip(words, words[1:]):
        weight = BIGRAM_SCALE * (WORD_WEIGHTS.get(a, 1.0)
                                 + WORD_WEIGHTS.get(b, 1.0)) / 2
        feats[f"b:{a} {b}"] = feats.get(f"b:{a} {b}", 0.0) + weight ** 2
    return {k: float(np.sqrt(v)) for k, v in feats.items()}


class OfflineTextEncoder(TextEncoder):
    r"""Weight-free, deterministic hashed text encoder (the default).

    Features: words, word bigrams and character 4-grams, weighted so that
    side, front/hind and segment-role words dominate incidental words. The
    words of the canonical descriptions (:data:`CORE_WORDS`) have one axis
    each (when ``out_channels >= 2 * len(CORE_WORDS)``); all other features
    are hashed with BLAKE2b to signed buckets in the remaining axes. The
    vector is L2-normalised. Identical texts give identical vectors on every machine;
    texts sharing words have a high cosine similarity.

    Args:
        out_channels (int): Embedding width D (default 256).
    """

    VERSION = 1

    def __init__(self, out_channels: int = 256) -> None:
        if out_channels < 1:
            raise ValueError("OfflineTextEncoder: out_channels must be >= 1")
        self._dim = int(out_channels)

    @property
    def id(self) -> str:
        return f"offline-hash-v{self.VERSION}-d{self._dim}"

    def encode_one(self, text: str) -> np.ndarray:
        """Embed one text.

        Args:
            text: The text.

        Returns:
            np.ndarray: float64 ``[D]``, unit norm (zero for empty text).
        """
        vec = np.zeros(self._dim)
        for feature, weight in text_features(text).items():
            slot, sign = _feature_slot(feature, self._dim)
            vec[slot] += sign * weight
        norm = np.linalg.norm(vec)
        return vec / norm if norm > 0 else vec

    def encode(self, texts: Sequence[str]) -> Tensor:
        out = np.zeros((len(texts), self._dim), dtype=np.float32)
        for i, text in enumerate(texts):
            out[i] = self.encode_one(text)
        return torch.from_numpy(out)


# -------------------------------------------------------------------- T5
T5_HELP = (
    "satagraph never downloads models. Download a T5 checkpoint yourself on "
    "a machine with network access, for example `huggingface-cli download "
    "google-t5/t5-base --local-dir ./t5-base` (it needs config.json, the "
    "weights and the tokenizer files), copy the folder here and pass it: "
    "T5TextEncoder('./t5-base') or `--t5 ./t5-base`.")


def _folder_fingerprint(path: Path) -> str:
    """Hash of config.json and the names and sizes of the folder's files."""
    h = hashlib.blake2b(digest_size=8)
    h.update((path / "config.json").read_bytes())
    for item in sorted(path.iterdir()):
        if item.is_file():
            h.update(f"{item.name}:{item.stat().st_size};".encode())
    return h.hexdigest()


class T5TextEncoder(TextEncoder):
    r"""Frozen T5 encoder loaded from a local folder.

    The model is loaded lazily on the first :meth:`encode` (a warm embedding
    cache never loads it) with ``T5EncoderModel.from_pretrained(path,
    local_files_only=True)`` and ``AutoTokenizer.from_pretrained(path,
    local_files_only=True)``; it is put in eval mode with gradients off.
    Embeddings are the mean of the last hidden states over non-padding
    tokens.

    Args:
        path (str or PathLike): Folder with ``config.json``, weights and
            tokenizer files.
        device (str or torch.device, optional): Where to run; CUDA when
            available, else CPU.
        batch_size (int): Texts per forward pass (default 64).
        max_length (int): Token limit per text (default 128).

    Raises:
        FileNotFoundError: The folder or its ``config.json`` is missing; the
            message says how to provide a model.
    """

    def __init__(self, path: PathLike, device: Union[str, torch.device,
                                                     None] = None,
                 batch_size: int = 64, max_length: int = 128) -> None:
        self.path = Path(path).expanduser().resolve()
        if not (self.path / "config.json").is_file():
            what = "folder" if not self.path.is_dir() else "config.json in"
            raise FileNotFoundError(
                f"T5TextEncoder: no T5 model at {self.path} ({what} missing)."
                f" {T5_HELP}")
        config = json.loads((self.path / "config.json").read_text())
        self._dim = int(config.get("d_model", 0))
        self._id = f"t5:{self.path.name}:{_folder_fingerprint(self.path)}"
        self.device = default_device(device)
        self.batch_size, self.max_length = int(batch_size), int(max_length)
        self._model = self._tokenizer = None

    def load(self) -> "T5TextEncoder":
        """Load tokenizer and model now (otherwise on first use).

        Returns:
            T5TextEncoder: self.
        """
        if self._model is not None:
            return self
        from transformers import T5EncoderModel
        self._model, self._tokenizer = load_frozen(
            T5EncoderModel, self.path, self.device, lambda said: FileNotFoundError(
                f"T5TextEncoder: cannot load a T5 model and tokenizer from "
                f"{self.path}: {said}. {T5_HELP}"))
        self._dim = int(self._model.config.d_model)
        return self

    @torch.inference_mode()
    def encode(self, texts: Sequence[str]) -> Tensor:
        self.load()
        return encode_mean_pooled(self._model, self._tokenizer, texts, self._dim,
                                  self.device, self.batch_size, self.max_length)


def default_device(device: Union[str, torch.device, None]) -> torch.device:
    """Where a ``transformers`` encoder runs: :obj:`device`, else CUDA when
    available, else the CPU."""
    return torch.device(device) if device is not None else \
        torch.device("cuda" if torch.cuda.is_available() else "cpu")


def load_frozen(model_class: type, path: Path, device: torch.device,
                error: Callable[[str], Exception]) -> Tuple[torch.nn.Module, object]:
    r"""``(model, tokenizer)`` of a ``transformers`` folder, read from local
    files only; the model in eval mode, gradients off, on :obj:`device`.

    Args:
        model_class: The ``transformers`` class (``from_pretrained``).
        path: The folder.
        device: Where the model runs.
        error: The encoder's own error, given the first line of what
            ``from_pretrained`` raised (``OSError`` or ``ValueError``; its
            messages run over several lines), without its closing period.
    """
    from transformers import AutoTokenizer
    try:
        tokenizer = AutoTokenizer.from_pretrained(str(path), local_files_only=True)
        model = model_class.from_pretrained(str(path), local_files_only=True)
    except (OSError, ValueError) as err:
        first = (str(err).strip() or type(err).__name__).splitlines()[0]
        raise error(first.rstrip(".")) from err
    model.requires_grad_(False)
    return model.eval().to(device), tokenizer


def mean_pool(hidden: Tensor, mask: Tensor) -> Tensor:
    r"""Mean of hidden states over the non-padding tokens.

    Args:
        hidden: Last hidden states.
        mask: Attention mask (1 for tokens, 0 for padding).

    Returns:
        Tensor: The pooled states.

    Shapes:
        - **hidden**: :math:`(N, L, D)`
        - **mask**: :math:`(N, L)`
        - **output**: :math:`(N, D)`
    """
    weights = mask.unsqueeze(-1).to(hidden.dtype)
    return (hidden * weights).sum(1) / weights.sum(1).clamp_min(1.0)


def encode_mean_pooled(model: torch.nn.Module, tokenizer, texts: Sequence[str],
                       dim: int, device: torch.device, batch_size: int,
                       max_length: int) -> Tensor:
    r"""Mean-pooled last hidden states of a ``transformers`` encoder, in
    batches (call under :func:`torch.inference_mode`).

    Args:
        model: The encoder (returns ``last_hidden_state``).
        tokenizer: Its tokenizer.
        texts: N texts.
        dim: Hidden width D (the shape of an empty result).
        device: Where the model runs.
        batch_size: Texts per forward pass.
        max_length: Token limit per text.

    Returns:
        Tensor: float32 ``[N, D]`` on the CPU.
    """
    chunks = []
    for i in range(0, len(texts), batch_size):
        tokens = tokenizer(list(texts[i:i + batch_size]), padding=True,
                           truncation=True, max_length=max_length,
                           return_tensors="pt")
        ids = tokens["input_ids"].to(device)
        mask = tokens["attention_mask"].to(device)
        hidden = model(input_ids=ids, attention_mask=mask).last_hidden_state
        chunks.append(mean_pool(hidden, mask).float().cpu())
    return torch.cat(chunks) if chunks else torch.zeros(0, dim)
