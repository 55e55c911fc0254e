"""Small file helpers: atomic writes and JSON reading with clear errors."""
from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Union

from satagraph.utils.files import InputFileError, atomic_write, check_input_file

PathLike = Union[str, "os.PathLike[str]"]


class SemanticsError(ValueError):
    """A bad user input to the semantic-tag pipeline (dictionary, anchor,
    reference vocabulary, language-model answer). The message is one line
    and names the file or the offending key."""


def write_json_atomic(path: PathLike, obj: Any) -> None:
    """Write :obj:`obj` as indented UTF-8 JSON, atomically.

    Args:
        path: Destination file.
        obj: A JSON-serialisable object.
    """
    text = json.dumps(obj, indent=2, ensure_ascii=False) + "\n"
    atomic_write(path, lambda f: f.write(text), create_parent=True)


def read_json(path: PathLike, what: str) -> Any:
    """Read a JSON file, turning every failure into a one-line
    :class:`SemanticsError` that names the file.

    Args:
        path: The file.
        what: What the file should be, for messages (``"dictionary"``).

    Returns:
        The decoded JSON value.

    Raises:
        SemanticsError: The file is missing, unreadable or not JSON.
    """
    try:
        check_input_file(path, f"{what} file")
        text = Path(path).read_text(encoding="utf-8")
    except InputFileError as err:
        if Path(path).is_symlink() or Path(path).exists():
            raise SemanticsError(str(err)) from None
        raise SemanticsError(f"{path}: {what} file not found") from None
    except FileNotFoundError:
        raise SemanticsError(f"{path}: {what} file not found") from None
    except (OSError, UnicodeDecodeError) as err:
        raise SemanticsError(f"{path}: cannot read {what}: {err}") from None
    return loads_json(text, str(path))


def loads_json(text: str, source: str) -> Any:
    """Decode JSON text with a one-line error naming :obj:`source`.

    Args:
        text: The JSON text.
        source: Where it came from (file name), for messages.

    Returns:
        The decoded value.

    Raises:
        SemanticsError: Not valid JSON.
    """
    try:
        return json.loads(text)
    except json.JSONDecodeError as err:
        raise SemanticsError(f"{source}: not valid JSON: {err.msg} (line "
                             f"{err.lineno}, column {err.colno})") from None
