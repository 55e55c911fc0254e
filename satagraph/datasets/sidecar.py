r"""User captions from a sidecar file next to a clip.

A clip ``walk.bvh`` may have ``walk.txt`` and/or ``walk.json`` beside it:

* ``.txt``: HumanML3D lines ``caption#tokens#from#to`` (``from`` and ``to``
  in seconds; ``0.0#0.0`` is the whole clip, as in HumanML3D; the tokens
  are ignored), or a bare caption per line (the whole clip). Blank lines
  are skipped.
* ``.json``: a list of objects ``{"text": str, "start": float, "end":
  float or null}`` (``start`` defaults to 0, ``end`` to the clip's end),
  or ``{"captions": [...]}`` with such a list. No other keys.

Every malformation raises :class:`~satagraph.datasets.caption.CaptionError`
with a one-line message naming the file and the line (or list item).
"""
from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import List, Optional, Union

from satagraph.datasets.caption import Caption, CaptionError

PathLike = Union[str, "os.PathLike[str]"]
#: Sidecar suffixes, in the order they are read.
SIDECAR_SUFFIXES = (".txt", ".json")
_JSON_KEYS = {"text", "start", "end"}


def sidecar_paths(clip: PathLike) -> List[Path]:
    """The sidecar files that exist for a clip (``.txt`` first).

    Args:
        clip: Path of the clip (``.bvh``).

    Returns:
        list[Path]: Existing sidecars.
    """
    path = Path(clip)
    return [p for p in (path.with_suffix(s) for s in SIDECAR_SUFFIXES) if p.is_file()]


def read_sidecars(clip: PathLike) -> List[Caption]:
    """User captions of a clip from its sidecars (none when it has none).

    Args:
        clip: Path of the clip.

    Returns:
        list[Caption]: Captions with ``source="user"``, file order.

    Raises:
        CaptionError: A malformed sidecar (file and line in the message).
    """
    return [c for p in sidecar_paths(clip) for c in read_sidecar(p)]


def read_sidecar(path: PathLike) -> List[Caption]:
    """Captions of one sidecar file (``.txt`` or ``.json``).

    Args:
        path: The sidecar.

    Returns:
        list[Caption]: Its captions (``source="user"``).

    Raises:
        CaptionError: A malformed file, an unknown suffix or an unreadable
            file.
    """
    path = Path(path)
    try:
        content = _utf8(path, path.read_bytes())
    except OSError as err:
        raise CaptionError(f"{path}: cannot read captions: {err}") from None
    if path.suffix.lower() == ".txt":
        return parse_humanml3d(content, str(path))
    if path.suffix.lower() == ".json":
        return parse_caption_json(content, str(path))
    raise CaptionError(f"{path}: captions must be in a .txt (HumanML3D) or .json "
                       "file")


def _utf8(path: Path, raw: bytes) -> str:
    """The text of a sidecar's bytes (UTF-8, with or without a byte order
    mark); another encoding is refused naming the line of its first bad
    byte (a Latin-1 "fatiguée" said only "position 44")."""
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        line = raw.count(b"\n", 0, err.start) + 1
        raise CaptionError(f"{path}:{line}: not UTF-8 text ({err.reason} at byte "
                           f"{err.start}); save the captions as UTF-8") from None


def _seconds(text: str, where: str, what: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise CaptionError(f"{where}: {what} {text.strip()!r} is not a number of "
                           "seconds") from None
    if not math.isfinite(value) or value < 0:
        raise CaptionError(f"{where}: {what} must be a finite number >= 0, not {text.strip()}")
    return value


def _caption(text: str, start: float, end: Optional[float], where: str) -> Caption:
    text = " ".join(text.split())
    if not text:
        raise CaptionError(f"{where}: empty caption")
    if end is not None and end <= start:
        raise CaptionError(f"{where}: end ({end:g} s) must be after start ({start:g} s)")
    return Caption(text, start, end, "user")


def parse_humanml3d(content: str, name: str = "<captions>") -> List[Caption]:
    """Captions of HumanML3D text lines ``caption#tokens#from#to``.

    ``0.0#0.0`` (or a bare caption without ``#``) is the whole clip;
    otherwise ``to`` must be after ``from``.

    Args:
        content: The file's text.
        name: File name for error messages.

    Returns:
        list[Caption]: One caption per non-blank line.
    """
    out = []
    for number, line in enumerate(content.splitlines(), start=1):
        if not line.strip():
            continue
        where = f"{name}:{number}"
        fields = line.split("#")
        if len(fields) == 1:
            out.append(_caption(fields[0], 0.0, None, where))
            continue
        if len(fields) != 4:
            raise CaptionError(f"{where}: expected 'caption#tokens#from#to' (4 fields "
                               f"separated by '#'), found {len(fields)} fields")
        start = _seconds(fields[2], where, "from")
        end = _seconds(fields[3], where, "to")
        whole = start == 0.0 and end == 0.0
        out.append(_caption(fields[0], start, None if whole else end, where))
    return out


def parse_caption_json(content: str, name: str = "<captions>") -> List[Caption]:
    """Captions of a JSON sidecar (see the module's schema).

    Args:
        content: The file's text.
        name: File name for error messages.

    Returns:
        list[Caption]: One caption per list item.
    """
    try:
        data = json.loads(content)
    except json.JSONDecodeError as err:
        raise CaptionError(f"{name}:{err.lineno}: invalid JSON: {err.msg}") from None
    if isinstance(data, dict) and set(data) == {"captions"}:
        data = data["captions"]
    if not isinstance(data, list):
        raise CaptionError(f"{name}: expected a list of {{text, start, end}} objects "
                           "(or {\"captions\": [...]})")
    return [_json_item(item, f"{name}: captions[{i}]") for i, item in enumerate(data)]


def _json_item(item: object, where: str) -> Caption:
    if isinstance(item, str):
        item = {"text": item}
    if not isinstance(item, dict):
        raise CaptionError(f"{where}: expected an object {{text, start, end}}")
    unknown = sorted(set(item) - _JSON_KEYS)
    if unknown:
        raise CaptionError(f"{where}: unknown keys {unknown}; known: text, start, end")
    text = item.get("text")
    if not isinstance(text, str):
        raise CaptionError(f"{where}: 'text' must be a string")
    start, end = item.get("start", 0.0), item.get("end")
    for key, value in (("start", start), ("end", end)):
        if value is not None and (isinstance(value, bool)
                                  or not isinstance(value, (int, float))):
            raise CaptionError(f"{where}: '{key}' must be a number of seconds")
    start = _seconds(str(start if start is not None else 0.0), where, "start")
    end = None if end is None else _seconds(str(end), where, "end")
    return _caption(text, start, end, where)


__all__ = ["SIDECAR_SUFFIXES", "sidecar_paths", "read_sidecars", "read_sidecar",
           "parse_humanml3d", "parse_caption_json"]
