r"""Mirroring captions: the text of a left/right mirrored motion.

:func:`~satagraph.transforms.augment.mirror` swaps the left and right joints of a
motion; a caption of that motion must swap its side words too (``"turns
left"`` -> ``"turns right"``, ``"clockwise"`` -> ``"counterclockwise"``).
The side words are those of the joint-name rule
(:data:`satagraph.sides.MIRROR_WORDS`: ``left`` and ``right``), plus the words of turning
directions. Whole words only (``"leftover"`` stays), case kept
(``"Left"`` -> ``"Right"``, ``"LEFT"`` -> ``"RIGHT"``).

:func:`mirror_text` is an involution on texts written with the canonical
spellings; the spellings ``anticlockwise``, ``anti-clockwise``,
``counter-clockwise`` and ``counter clockwise`` (a space, as HumanML3D
writes it) become ``clockwise``, whose mirror image is
``counterclockwise``. ``right`` in the sense of "correct" or "just"
(``"right after"``) is swapped as well: telling it apart would break the
involution.
"""
from __future__ import annotations

import re
from typing import Dict

from satagraph.sides import MIRROR_WORDS as _SIDE_MIRROR

#: Lower-case word -> its mirror image.
MIRROR_WORDS: Dict[str, str] = {
    **{w: _SIDE_MIRROR[w] for w in ("left", "right")},
    "leftward": "rightward", "rightward": "leftward",
    "leftwards": "rightwards", "rightwards": "leftwards",
    "leftmost": "rightmost", "rightmost": "leftmost",
    "clockwise": "counterclockwise", "counterclockwise": "clockwise",
    "counter-clockwise": "clockwise", "anticlockwise": "clockwise",
    "anti-clockwise": "clockwise", "counter clockwise": "clockwise",
    "anti clockwise": "clockwise",
}
# Longest first, so that "counter clockwise" wins over its "clockwise". A
# word ends at anything but a letter or digit: an underscore, as in a
# sidecar's "left_hand", separates words as a hyphen does.
_PATTERN = re.compile(
    r"(?<![^\W_])(" + "|".join(re.escape(w) for w in sorted(
        MIRROR_WORDS, key=len, reverse=True)) + r")(?![^\W_])",
    re.IGNORECASE)


def _same_case(word: str, like: str) -> str:
    """:obj:`word` in the case of :obj:`like` (lower, Title or UPPER)."""
    if like.isupper() and len(like) > 1:
        return word.upper()
    if like[0].isupper():
        return word[0].upper() + word[1:]
    return word


def mirror_text(text: str) -> str:
    """The caption of the left/right mirrored motion.

    Args:
        text: A caption.

    Returns:
        str: :obj:`text` with its side words swapped (whole words, case
        kept).

    Example::

        mirror_text("A person turns Left, then spins clockwise")
        # 'A person turns Right, then spins counterclockwise'
    """
    def swap(match: re.Match) -> str:
        word = match.group(0)
        return _same_case(MIRROR_WORDS[word.lower()], word)
    return _PATTERN.sub(swap, text)


__all__ = ["MIRROR_WORDS", "mirror_text"]
