"""Errors raised by the file readers and writers."""
from __future__ import annotations


class BVHError(ValueError):
    r"""A malformed or unreadable BVH file.

    The message always names the file and the line (1-based; 0 when no line
    applies) and what is wrong: ``"walk.bvh:12: frame 3 has 68 values,
    expected 69"``.

    Args:
        path (str): The file.
        line (int): The 1-based line number.
        message (str): What is wrong.
    """

    def __init__(self, path: str, line: int, message: str) -> None:
        self.path, self.line, self.message = path, line, message
        super().__init__(f"{path}:{line}: {message}")
