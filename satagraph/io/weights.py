r"""Trained weights as a safetensors file: the format of the built-in model.

A weights file holds tensors only (the module's ``state_dict``: the network,
optionally in half precision, and the normaliser statistics, always in
float32) and, in the safetensors metadata (JSON strings), everything needed
to rebuild the module offline:

- ``format``: :data:`FORMAT`, ``format_version``: :data:`FORMAT_VERSION`,
- ``hyper_parameters``: ``{model, loss, optim, fps, meta}`` and a
  subclass's own constructor arguments (plain containers; what
  :func:`satagraph.experiment.train.load_module` rebuilds from),
- ``module``, ``semantic_encoder``, ``fps``, ``window``, ``dtype``,
- ``training_data``: what the model was trained on (free text or a
  description), ``provenance``: how (command, minutes, machine, ...).

The file format cannot carry code (no pickle anywhere): reading it parses a
JSON header and raw tensor bytes. Every failure is one
:class:`~satagraph.io.checkpoint.CheckpointError` line naming the file.
"""
from __future__ import annotations

import json
import os
import re
import warnings
from pathlib import Path
from typing import Any, Dict, List, Mapping, Optional, Tuple, Union

import torch
from torch import Tensor

from satagraph.io.checkpoint import CheckpointError
from satagraph.utils.files import InputFileError, atomic_write, check_input_file

PathLike = Union[str, "os.PathLike[str]"]

#: Prefix of the feature normaliser's tensors in a model's state dict: what
#: the features mean, kept in float32 by ``half``, refitted or kept by a
#: fine-tune, never blended.
NORMALIZER_PREFIX = "normalizer."
#: ``format`` of a satagraph weights file's metadata.
FORMAT = "satagraph.weights"
#: Version of the metadata layout.
FORMAT_VERSION = "1"
#: Largest file :func:`save_weights` writes without ``force`` (the built-in
#: model is committed to the repository).
MAX_WEIGHTS_BYTES = 8 * 1024 * 1024
#: Name that resolves to the package's built-in weights.
BUILTIN = "builtin"
#: The package's built-in weights files (``satagraph/weights/``) by kind.
BUILTIN_FILES = {"autoencoder": "builtin.safetensors",
                 "text-to-motion": "t2m_builtin.safetensors"}
#: Other built-in autoencoders, by the name that loads them (``--ckpt
#: builtin-wide``): the same network trained on every body plan of the zoo.
BUILTIN_VARIANTS = {"builtin-wide": "builtin_wide.safetensors"}
#: How to make each kind (or named variant) when none ships.
_BUILTIN_RECIPES = {"autoencoder": "`satagraph train pretrain_zoo`",
                    "text-to-motion": "`satagraph train t2m_rvq_builtin` then "
                                      "`satagraph train t2m_builtin`",
                    "builtin-wide": "`satagraph train pretrain_zoo_wide`"}


def _no_builtin(kind: str, name: str = BUILTIN) -> str:
    """The one line shown when the built-in weights :obj:`name` of
    :obj:`kind` do not ship."""
    if name != BUILTIN:
        return (f"no {name} weights are shipped in this version: train one with "
                f"{_BUILTIN_RECIPES[name]} or pass another --ckpt")
    what = "" if kind == "autoencoder" else f" {kind}"
    return (f"no built-in{what} weights are shipped in this version: train one with "
            f"{_BUILTIN_RECIPES[kind]} or pass --ckpt")


#: The one line shown when no built-in autoencoder weights ship.
NO_BUILTIN = _no_builtin("autoencoder")
#: Largest weights file read.
_MAX_READ_BYTES = 1 << 30
_HPARAM_KEYS = ("model", "loss", "optim", "fps", "meta")


class WeightsSizeError(ValueError):
    """A weights file over the size limit (pass ``force`` to write it)."""


def builtin_path(kind: str = "autoencoder", name: str = BUILTIN) -> Path:
    """Where the package's built-in weights of a kind live (package data:
    ``satagraph/weights/``, see :data:`BUILTIN_FILES`); :obj:`name` picks
    an autoencoder of :data:`BUILTIN_VARIANTS`."""
    from importlib import resources
    if kind not in BUILTIN_FILES:
        raise ValueError(f"built-in weights kind must be one of {list(BUILTIN_FILES)}, "
                         f"got {kind!r}")
    if name != BUILTIN and (kind != "autoencoder" or name not in BUILTIN_VARIANTS):
        raise ValueError(f"built-in {kind} weights are named {builtin_names(kind)}, "
                         f"got {name!r}")
    file = BUILTIN_FILES[kind] if name == BUILTIN else BUILTIN_VARIANTS[name]
    return Path(str(resources.files("satagraph.weights") / file))


def builtin_names(kind: str = "autoencoder") -> List[str]:
    """The names that load built-in weights of a kind."""
    return [BUILTIN] + (list(BUILTIN_VARIANTS) if kind == "autoencoder" else [])


def is_builtin(name: PathLike, kind: str = "autoencoder") -> bool:
    """Whether :obj:`name` names built-in weights (:func:`builtin_names`)."""
    return os.fspath(name) in builtin_names(kind)


def resolve_weights(name: PathLike, kind: str = "autoencoder") -> str:
    """A path for :obj:`name`: ``"builtin"`` gives the package's weights of
    :obj:`kind` (:data:`BUILTIN_FILES`), ``"builtin-wide"`` its other
    autoencoder (:data:`BUILTIN_VARIANTS`), a run folder its
    ``checkpoints/last.ckpt`` (as ``satagraph train`` leaves it).

    Raises:
        CheckpointError: a built-in name whose weights do not ship, or a
            folder without ``checkpoints/last.ckpt`` (one line saying how
            on).
    """
    name = os.fspath(name)
    if os.path.isdir(name):
        last = os.path.join(name, "checkpoints", "last.ckpt")
        if not os.path.isfile(last):
            raise CheckpointError(f"{name}: a folder without checkpoints/last.ckpt (give a "
                                  "run folder of satagraph train, or a checkpoint file)")
        return last
    if name == "auto" and kind == "autoencoder" and not os.path.exists(name):
        raise CheckpointError("auto picks a built-in model by the rigs a command reads "
                              "(satagraph.pipelines.builtin_choice.choose_builtin); name "
                              "builtin or builtin-wide here")
    if not is_builtin(name, kind):
        return name
    path = builtin_path(kind, name)
    if not path.is_file():
        raise CheckpointError(_no_builtin(kind, name))
    return str(path)


#: Longest provenance part (command, machine, note) that :func:`builtin_notice`
#: shows whole; a longer command or machine is cut at its first clause, a
#: longer note is pointed to.
NOTICE_PART_CHARS = 120


def _first_clause(text: str) -> str:
    """:obj:`text` up to its first bracket, semicolon or comma, when it is
    longer than :data:`NOTICE_PART_CHARS`."""
    if len(text) <= NOTICE_PART_CHARS:
        return text
    return re.split(r" \(|;|,", text, maxsplit=1)[0][:NOTICE_PART_CHARS]


def _earlier(provenance: dict) -> Optional[dict]:
    """The provenance one step back: of the file re-exported (``previous``)
    or, for a blend, of its base (``blend.previous``)."""
    blend = provenance.get("blend")
    for earlier in (provenance.get("previous"),
                    blend.get("previous") if isinstance(blend, dict) else None):
        if isinstance(earlier, dict) and earlier:
            return earlier
    return None


def provenance_chain(provenance: dict) -> List[dict]:
    """A weights file's provenance, then that of each file it was re-exported
    from (``previous``: a part swapped in, ``export-weights --decoder`` or
    ``--length``) or blended back into (``blend.previous``: the base of
    ``export-weights --blend``), the first training last."""
    chain = [provenance]
    while (earlier := _earlier(chain[-1])) is not None:
        chain.append(earlier)
    return chain


def _builtin_path_call(kind: str, name: str) -> str:
    """The call of :func:`builtin_path` that gives the built-in weights
    :obj:`name` of :obj:`kind`, its default arguments left out."""
    args = [kind, name] if name != BUILTIN else [kind] if kind != "autoencoder" else []
    return f"builtin_path({', '.join(map(repr, args))})"


def builtin_notice(kind: str = "autoencoder", name: str = BUILTIN) -> str:
    """One short line on a built-in model, from its own metadata: what made
    it (the first training's command and machine, cut to their first
    clause, and the minutes of every step of :func:`provenance_chain`) and
    its provenance note when that is short (a long one is pointed to: the
    call of :func:`read_weights_metadata` that gives it whole, which an
    installed package has, unlike a source checkout's README); shown by the
    commands that fall back on it."""
    meta = read_weights_metadata(resolve_weights(name, kind))
    chain = provenance_chain(meta.get("provenance") or {})
    prov, minutes = chain[-1], sum(float(p.get("minutes") or 0.0) for p in chain)
    parts = (prov.get("command") and _first_clause(str(prov["command"])),
             minutes and f"{minutes:.0f} min",
             prov.get("machine") and _first_clause(str(prov["machine"])))
    made = ", ".join(str(part) for part in parts if part)
    note = str(prov.get("note") or "")
    if len(note) > NOTICE_PART_CHARS:
        note = ("what it can and cannot do: the provenance notes of satagraph.io."
                f"weights.read_weights_metadata({_builtin_path_call(kind, name)})")
    what = "model" if kind == "autoencoder" else f"{kind} model"
    which = "" if name == BUILTIN else f" {name}"
    return f"using the built-in {what}{which} ({made})" + (f": {note}" if note else "")


def is_weights_file(path: PathLike) -> bool:
    """Whether :obj:`path` looks like a safetensors file (an 8-byte header
    length followed by ``{``), whatever its name."""
    try:
        with open(path, "rb") as f:
            head = f.read(9)
    except OSError:
        return False
    return len(head) == 9 and head[8:9] == b"{" and int.from_bytes(head[:8], "little") > 1


def _plain(value: Any, where: str) -> Any:
    """:obj:`value` as JSON-ready plain containers."""
    if isinstance(value, Mapping):
        return {str(k): _plain(v, f"{where}.{k}") for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v, where) for v in value]
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    if hasattr(value, "item") and getattr(value, "ndim", 1) == 0:  # numpy / torch scalar
        return value.item()
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    raise TypeError(f"{where}: {type(value).__name__} is not a plain value")


def module_hyper_parameters(module: torch.nn.Module) -> Dict[str, Any]:
    """The ``{model, loss, optim, fps, meta}`` hyperparameters a module was
    built from, and a subclass's own constructor arguments (what
    :func:`~satagraph.experiment.train.load_module` passes back to it), as
    plain containers; an argument that is no plain value is left out with a
    warning."""
    hparams = dict(getattr(module, "hparams", {}) or {})
    out = _plain({k: hparams[k] for k in _HPARAM_KEYS if k in hparams}, "hyper_parameters")
    for key in sorted(set(hparams) - set(_HPARAM_KEYS)):
        try:
            out[key] = _plain(hparams[key], f"hyper_parameters.{key}")
        except TypeError as err:
            warnings.warn(f"{err}: left out (loaded back, the module takes its default)",
                          stacklevel=2)
    return out


def weights_payload(module: torch.nn.Module, half: bool = False,
                    training_data: Any = None,
                    provenance: Optional[Mapping[str, Any]] = None,
                    ) -> Tuple[Dict[str, Tensor], Dict[str, str]]:
    """The tensors and metadata of a module's weights file.

    Args:
        module: A trained satagraph module (its ``hparams`` hold
            ``model``, ``fps`` and ``meta``).
        half: Store the network's floating-point weights as float16 (the
            normaliser statistics stay float32).
        training_data: What it was trained on (default: the sources named
            in its ``meta.data``).
        provenance: How it was trained (command, minutes, machine, ...).

    Returns:
        ``(tensors, metadata)``: contiguous CPU tensors and JSON strings.
    """
    hparams = module_hyper_parameters(module)
    if not isinstance(hparams.get("model"), dict):
        raise ValueError("not a satagraph model: no model hyperparameters")
    meta = dict(hparams.get("meta") or {})
    if training_data is None:
        training_data = (meta.get("data") or {}).get("sources")
    dtype = torch.float16 if half else torch.float32
    tensors = {}
    for key, value in module.state_dict().items():
        value = value.detach().to("cpu")
        if value.is_floating_point() and not key.startswith(NORMALIZER_PREFIX):
            value = value.to(dtype)
        tensors[key] = value.contiguous().clone()
    metadata = {"format": FORMAT, "format_version": FORMAT_VERSION,
                "hyper_parameters": hparams,
                "module": meta.get("module", "vae"),
                "semantic_encoder": meta.get("semantic_encoder", "offline"),
                "fps": hparams.get("fps", 30.0), "window": meta.get("window"),
                "dtype": "float16" if half else "float32",
                "training_data": _plain(training_data, "training_data"),
                "provenance": _plain(dict(provenance or {}), "provenance")}
    return tensors, {k: json.dumps(v, sort_keys=True) for k, v in metadata.items()}


def safetensors_bytes(tensors: Mapping[str, Tensor], metadata: Mapping[str, str]) -> bytes:
    """The bytes of a safetensors file of :obj:`tensors` and
    :obj:`metadata`, its header's keys in sorted order: the same tensors
    and metadata give the same bytes (``safetensors.torch.save`` writes the
    metadata in a hash map's order, which changes from one call to the next:
    two exports of one checkpoint, or two code banks of one seed, differed)."""
    from safetensors.torch import save
    data = save(dict(tensors), metadata=dict(metadata))
    size = int.from_bytes(data[:8], "little")
    header = json.loads(data[8:8 + size])
    text = json.dumps(header, sort_keys=True, ensure_ascii=False,
                      separators=(",", ":")).encode("utf-8")
    text += b" " * (-len(text) % 8)  # safetensors' own alignment of the data
    return len(text).to_bytes(8, "little") + text + data[8 + size:]


def save_weights(module: torch.nn.Module, path: PathLike, half: bool = False,
                 training_data: Any = None, provenance: Optional[Mapping[str, Any]] = None,
                 force: bool = False, max_bytes: int = MAX_WEIGHTS_BYTES) -> int:
    """Write a module's weights file atomically (see :func:`weights_payload`).

    Args:
        module: A trained satagraph module.
        path (str or PathLike): The ``.safetensors`` file to write.
        half, training_data, provenance: See :func:`weights_payload`.
        force (bool, optional): Write a file over :obj:`max_bytes` too.
        max_bytes (int, optional): The size limit (:data:`MAX_WEIGHTS_BYTES`).

    Returns:
        int: The file's size in bytes.

    Raises:
        WeightsSizeError: Larger than :obj:`max_bytes` and not :obj:`force`
            (nothing is written).
    """
    tensors, metadata = weights_payload(module, half, training_data, provenance)
    data = safetensors_bytes(tensors, metadata)
    if len(data) > max_bytes and not force:
        raise WeightsSizeError(
            f"{os.fspath(path)}: the weights take {len(data) / 2**20:.2f} MB, over the "
            f"{max_bytes / 2**20:.0f} MB limit: try --half, or --force to write it")
    atomic_write(path, lambda f: f.write(data), binary=True)
    return len(data)


def _header(data: bytes, path: str) -> Dict[str, Any]:
    """The JSON header of safetensors bytes."""
    size = int.from_bytes(data[:8], "little") if len(data) >= 8 else 0
    if size < 2 or 8 + size > len(data):
        raise CheckpointError(f"{path}: not a readable weights file (truncated or "
                              "another format)")
    try:
        header = json.loads(data[8:8 + size].decode("utf-8"))
    except (UnicodeDecodeError, ValueError):
        raise CheckpointError(f"{path}: not a readable weights file (its header is "
                              "not JSON)") from None
    if not isinstance(header, dict):
        raise CheckpointError(f"{path}: not a readable weights file (bad header)")
    return header


def _metadata(header: Dict[str, Any], path: str) -> Dict[str, Any]:
    """The decoded satagraph metadata of a header."""
    raw = header.get("__metadata__") or {}
    if not isinstance(raw, dict) or raw.get("format") != json.dumps(FORMAT):
        raise CheckpointError(f"{path}: not satagraph weights (a safetensors file "
                              "without satagraph metadata)")
    try:
        meta = {k: json.loads(v) for k, v in raw.items()}
    except (TypeError, ValueError):
        raise CheckpointError(f"{path}: not readable satagraph weights (metadata "
                              "that is not JSON)") from None
    if meta.get("format_version") != FORMAT_VERSION:
        raise CheckpointError(f"{path}: satagraph weights of format version "
                              f"{meta.get('format_version')!r}; this version reads "
                              f"{FORMAT_VERSION!r}")
    if not isinstance(meta.get("hyper_parameters"), dict) or \
            not isinstance(meta["hyper_parameters"].get("model"), dict):
        raise CheckpointError(f"{path}: not satagraph weights (no model "
                              "hyperparameters)")
    return meta


def read_weights_metadata(path: PathLike) -> Dict[str, Any]:
    """The decoded metadata of a satagraph weights file (no tensors read).

    Args:
        path (str or PathLike): The ``.safetensors`` file.

    Raises:
        CheckpointError: Not a satagraph weights file (one line naming it).
    """
    path = os.fspath(path)
    with open(_checked(path), "rb") as f:
        head = f.read(8)
        size = int.from_bytes(head, "little") if len(head) == 8 else 0
        body = f.read(size) if 1 < size < _MAX_READ_BYTES else b""
    return _metadata(_header(head + body, path), path)


def check_weights(name: PathLike, kind: str = "autoencoder") -> str:
    """The path :obj:`name` gives (:func:`resolve_weights`), refused where
    it is not a readable file: what a command checks before it loads the
    model's code.

    Raises:
        CheckpointError: Missing, unreadable or too large (one line naming it).
    """
    return _checked(resolve_weights(name, kind))


def _checked(path: str) -> str:
    try:
        check_input_file(path, "checkpoint or weights file", max_bytes=_MAX_READ_BYTES)
    except InputFileError as err:
        raise CheckpointError(str(err)) from None
    return path


def load_weights(path: PathLike) -> Dict[str, Any]:
    """A weights file as a checkpoint-like dictionary.

    Returns:
        dict: ``state_dict`` (float32 for every floating-point tensor),
        ``hyper_parameters`` and ``weights_metadata`` (the decoded metadata).

    Raises:
        CheckpointError: Missing, truncated, not safetensors, or a
            safetensors file that is not satagraph weights (one line
            naming it).
    """
    from safetensors import SafetensorError
    from safetensors.torch import load
    path = os.fspath(path)
    with open(_checked(path), "rb") as f:
        data = f.read()
    meta = _metadata(_header(data, path), path)
    try:
        state = load(data)
    except (SafetensorError, ValueError, RuntimeError) as err:
        first = (str(err).strip().splitlines() or [type(err).__name__])[0]
        raise CheckpointError(f"{path}: not a readable weights file (truncated or "
                              f"damaged: {first[:120]})") from None
    state = {k: v.float() if v.is_floating_point() else v for k, v in state.items()}
    return {"state_dict": state, "hyper_parameters": meta["hyper_parameters"],
            "weights_metadata": meta}


def load_weights_or_checkpoint(path: PathLike, require=("state_dict",),
                               kind: str = "autoencoder") -> Dict[str, Any]:
    """A checkpoint (``torch.save``, loaded with ``weights_only=True``) or a
    weights file, by content; ``"builtin"`` names the package's weights of
    :obj:`kind` (:data:`BUILTIN_FILES`)."""
    from satagraph.io.checkpoint import load_checkpoint
    path = check_weights(path, kind)
    if is_weights_file(path):
        return load_weights(path)
    return load_checkpoint(path, require=require)


__all__ = ["FORMAT", "FORMAT_VERSION", "MAX_WEIGHTS_BYTES", "BUILTIN", "BUILTIN_FILES",
           "BUILTIN_VARIANTS", "NO_BUILTIN", "WeightsSizeError", "builtin_path",
           "builtin_names", "is_builtin", "builtin_notice", "resolve_weights", "is_weights_file",
           "module_hyper_parameters", "weights_payload", "safetensors_bytes", "save_weights",
           "read_weights_metadata", "load_weights", "load_weights_or_checkpoint",
           "check_weights"]
