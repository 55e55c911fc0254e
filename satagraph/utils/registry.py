"""The one rule of satagraph's name registries (window transforms, text
encoders, local convolutions): a name is registered once."""
from __future__ import annotations

from typing import Dict, Iterable, TypeVar

T = TypeVar("T")


def register_name(table: Dict[str, T], key: str, value: T, what: str,
                  reserved: Iterable[str] = ()) -> None:
    """Add :obj:`key` -> :obj:`value` to a registry :obj:`table`.

    Args:
        table (dict): The registry.
        key (str): The name, as the registry keeps it (stripped, lower case).
        value: What the name stands for.
        what (str): The registry's kind, for the error (``"local conv"``).
        reserved (iterable of str): Names taken without being in
            :obj:`table` (``"offline"``, ``"none"``).

    Raises:
        ValueError: The name is taken (one line naming it).
    """
    if key in table or key in reserved:
        raise ValueError(f"{what} {key!r} is registered already; pick another name")
    table[key] = value


__all__ = ["register_name"]
