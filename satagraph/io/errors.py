"""Errors raised by the file readers and writers."""
from __future__ import annotations


class BVHError(ValueError):
    r"""A malformed or unreadable BVH file.

    The message names the file, the line (1-based; :attr:`line` is 0 and the
    message gives none when no line applies: a missing file) and what is
    wrong: ``"walk.bvh:12: frame 3 has 68 values, expected 69"``.

    Args:
        path (str): The file.
        line (int): The 1-based line number.
        message (str): What is wrong.
    """

    def __init__(self, path: str, line: int, message: str) -> None:
        self.path, self.line, self.message = path, line, message
        super().__init__(f"{path}:{line}: {message}" if line > 0 else f"{path}: {message}")

    def __reduce__(self):
        """Pickled with its three arguments (an error raised in a worker
        process reaches the parent whole)."""
        return type(self), (self.path, self.line, self.message)
