r"""Safe loading and atomic saving of checkpoints.

Every checkpoint a user passes or a run left behind is loaded with
``torch.load(..., weights_only=True)`` (tensors and plain containers only:
a planted pickle cannot run code, whatever ``TORCH_FORCE_NO_WEIGHTS_ONLY_LOAD``
says). A file that is not a checkpoint, is truncated or holds other objects
gives one :class:`CheckpointError` line naming the file and what it is not,
never advice to turn safe loading off.
"""
from __future__ import annotations

import io
import os
import pickle
import re
import warnings
import zipfile
from typing import Any, Dict, Sequence, Union

import torch

from satagraph.utils.files import InputFileError, atomic_write_bytes, check_input_file

PathLike = Union[str, "os.PathLike[str]"]

_GLOBAL = re.compile(r"(?:Unsupported global|GLOBAL)[: ]+(?:GLOBAL )?([\w.]+)")


class CheckpointError(ValueError):
    """A file that cannot be used as a checkpoint; one line naming it."""


def _refused(path: str, err: Exception) -> CheckpointError:
    """The error for a file torch cannot load safely (no advice to load it
    unsafely)."""
    text = str(err)
    found = _GLOBAL.search(text)
    if found:
        return CheckpointError(
            f"{path}: not a satagraph checkpoint: it holds Python objects "
            f"({found.group(1)}) that safe loading refuses (only tensors and plain "
            "containers are loaded)")
    detail = text.split("WeightsUnpickler error:")[-1] if "WeightsUnpickler" in text \
        else text
    lines = [x.strip() for x in detail.strip().splitlines() if x.strip()]
    first = lines[0] if lines else type(err).__name__
    if "weights_only" in first:
        first = type(err).__name__
    return CheckpointError(f"{path}: not a readable checkpoint (truncated or another "
                           f"format: {_clipped(first)})")


def _clipped(text: str, limit: int = 120) -> str:
    """:obj:`text` cut to about :obj:`limit` characters at a word's end,
    with an ellipsis where it was cut (a cut mid-word read "If yo")."""
    if len(text) <= limit:
        return text
    cut = text[:limit].rsplit(" ", 1)[0] if " " in text[:limit] else text[:limit]
    return cut.rstrip(" ,;:") + " ..."


def _looks_like_torch_file(path: str) -> bool:
    """A zip archive (torch.save) or a pickle (legacy torch.save)."""
    with open(path, "rb") as f:
        head = f.read(2)
    return head == b"PK" or head[:1] == b"\x80"


def load_checkpoint(path: PathLike, map_location: Any = "cpu",
                    require: Sequence[str] = ("state_dict",),
                    what: str = "satagraph checkpoint") -> Dict[str, Any]:
    """Load a checkpoint safely (``weights_only=True``).

    Args:
        path: The file.
        map_location: Where tensors go (see :func:`torch.load`).
        require: Keys the checkpoint must have.
        what: What the file should be, for messages.

    Returns:
        dict: The checkpoint.

    Raises:
        CheckpointError: Not a regular file, not a torch file, truncated,
            holding objects other than tensors and plain containers, or
            lacking a key of :obj:`require`; one line naming :obj:`path`.
    """
    path = os.fspath(path)
    try:
        check_input_file(path, "checkpoint")
    except InputFileError as err:
        raise CheckpointError(str(err)) from None
    if not _looks_like_torch_file(path):
        raise CheckpointError(f"{path}: not a readable checkpoint (not a file written "
                              "by torch.save)")
    try:
        with warnings.catch_warnings():  # torch's note on old pickle protocols
            warnings.filterwarnings("ignore", message="Detected pickle protocol")
            ckpt = torch.load(path, map_location=map_location, weights_only=True)
    except (pickle.UnpicklingError, RuntimeError, EOFError, ValueError, TypeError,
            AttributeError, ImportError, IndexError, KeyError, OSError,
            zipfile.BadZipFile, UnicodeDecodeError, MemoryError) as err:
        raise _refused(path, err) from None
    if not isinstance(ckpt, dict):
        raise CheckpointError(f"{path}: not a {what} (it holds a "
                              f"{type(ckpt).__name__}, not a dictionary)")
    missing = [k for k in require if k not in ckpt]
    if missing and ckpt and all(isinstance(v, torch.Tensor) for v in ckpt.values()):
        raise CheckpointError(
            f"{path}: a bare state dict ({len(ckpt)} tensors, e.g. {next(iter(ckpt))!r}), not "
            f"a {what}: it holds no settings to build a model from (save the run's Lightning "
            "checkpoint, or satagraph export-weights RUN OUT.safetensors)")
    if missing:
        raise CheckpointError(f"{path}: not a {what} (no {', '.join(missing)})")
    return ckpt


def check_finite_weights(ckpt: Dict[str, Any], path: PathLike) -> None:
    """Refuse a checkpoint whose weights hold NaN or infinity (a diverged run).

    Raises:
        CheckpointError: Naming :obj:`path` and how many tensors are bad.
    """
    state = ckpt.get("state_dict") or {}
    floats = {k: v for k, v in state.items()
              if isinstance(v, torch.Tensor) and v.is_floating_point()}
    bad = [k for k, v in floats.items() if not torch.isfinite(v).all()]
    if bad:
        raise CheckpointError(f"{os.fspath(path)}: {len(bad)} of {len(floats)} weight "
                              f"tensors are non-finite (e.g. {bad[0]}): the run that "
                              "wrote it diverged; use an earlier checkpoint")


def save_checkpoint(checkpoint: Dict[str, Any], path: PathLike) -> None:
    """Save atomically (fsynced temporary file, then rename).

    The checkpoint is serialised in memory first and then written as
    bytes: torch's zip writer, given a path or a file, turns a failed write
    (a full disk) into ``RuntimeError: [enforce fail at
    inline_container.cc] unexpected pos``, which names neither the file nor
    the cause.

    Args:
        checkpoint: The checkpoint dictionary.
        path: Destination.

    Raises:
        OSError: The file cannot be written (``No space left on device``),
            naming :obj:`path`; the previous file is left as it was.
    """
    buffer = io.BytesIO()
    torch.save(checkpoint, buffer)
    atomic_write_bytes(path, buffer.getbuffer(), create_parent=True)


__all__ = ["CheckpointError", "load_checkpoint", "check_finite_weights", "save_checkpoint"]
