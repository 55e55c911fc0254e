r"""Left and right in joint names: the one rule that canonicalisation
(facing from left/right pairs), augmentation (mirroring) and the semantic
lexicon share.

A name is cut into *pieces*: alphanumeric runs split at camelCase humps
and letter/digit boundaries (``mixamorig:LeftUpLeg`` -> ``mixamorig``,
``Left``, ``Up``, ``Leg``; ``HipL`` -> ``Hip``, ``L``; ``lShldr`` -> ``l``,
``Shldr``). Exporter tags such as ``__k8L`` or ``_a1b2c3`` (single letters
between digits) carry no side. A piece marks a side when

- it is a side word (:data:`SIDE_WORDS`: ``L``, ``Lt``, ``Left``, ``r``,
  ``rgt``, ...), or contains ``left`` / ``right`` (``lefthand``), or
  starts with a side word glued to body words, as the lexicon splits glued
  words (CMU ASF's ``lfemur``, ``rclavicle``; not ``label``, ``lower``,
  ``rib``);
- failing any such piece, it is a quadruped leg code (:data:`LEG_CODES`:
  ``FL``, ``HR``, ``BL``, ...; ``Fr`` next to a side word is *front* only).

The Japanese and Chinese side characters (:data:`SIDE_CHARACTERS`: ``左``,
``右``, as in an MMD model's ``左ひざ``) are side words wherever they stand.

The first marker gives the side; :func:`swap_side` mirrors every marker,
keeping its case, so ``swap_side(swap_side(name)) == name``.

Example::

    side_of("thigh.L")          # "left"
    side_of("Ladder")           # None
    swap_side("Bip01 L Thigh")  # "Bip01 R Thigh"
"""
from __future__ import annotations

import re
from functools import lru_cache
from typing import Callable, Dict, Iterable, Iterator, List, Optional, Tuple

#: Side words (lower case) and the side they name. Every word has its
#: mirror image in :data:`MIRROR_WORDS`.
SIDE_WORDS: Dict[str, str] = {
    "left": "left", "l": "left", "lt": "left", "lft": "left", "lf": "left",
    "lht": "left", "right": "right", "r": "right", "rt": "right",
    "rgt": "right", "rht": "right", "rf": "right"}
#: Side characters of Japanese and Chinese names (``左ひざ``: the left knee).
SIDE_CHARACTERS: Dict[str, str] = {"左": "left", "右": "right"}
SIDE_WORDS.update(SIDE_CHARACTERS)
#: Quadruped leg codes: front/hind and side, read as a side only in a name
#: without a side word.
LEG_CODES: Dict[str, Tuple[str, str]] = {
    "fl": ("front", "left"), "fr": ("front", "right"),
    "hl": ("hind", "left"), "hr": ("hind", "right"),
    "bl": ("hind", "left"), "br": ("hind", "right")}
_PAIRS = (("left", "right"), ("l", "r"), ("lt", "rt"), ("lft", "rgt"),
          ("lf", "rf"), ("lht", "rht"), ("fl", "fr"), ("hl", "hr"),
          ("bl", "br"), ("左", "右"))
#: Each side word or leg code and its mirror image (lower case).
MIRROR_WORDS: Dict[str, str] = {**dict(_PAIRS), **{b: a for a, b in _PAIRS}}

_TOKEN = re.compile(r"[A-Za-z0-9]+")
_PIECE = re.compile(r"[A-Z]+(?![a-z])|[A-Z]?[a-z]+|\d+")
_NOISE = re.compile(r"(?:[A-Za-z]?\d+)+[A-Za-z]?")  # k8L, a1b2c3, l9V
_GLUED = re.compile(r"left|right", re.IGNORECASE)
_CHARACTERS = re.compile("|".join(SIDE_CHARACTERS))

#: A side marker: start, end (character positions in the name) and word.
Marker = Tuple[int, int, str]


def _is_tag(token: str) -> bool:
    """An exporter tag: single letters and digits alternating, with a
    letter on both sides of a digit (``k8L``, ``a1b2c3``; not ``L1``)."""
    return bool(_NOISE.fullmatch(token)) and bool(re.search(r"[A-Za-z]\d+[A-Za-z]", token))


def _pieces(name: str) -> Iterator[Tuple[int, str]]:
    """Start position and text of each piece of :obj:`name` (see module)."""
    for token in _TOKEN.finditer(name):
        if _is_tag(token.group()):
            continue
        for piece in _PIECE.finditer(token.group()):
            yield token.start() + piece.start(), piece.group()


def side_markers(name: str) -> List[Marker]:
    r"""The side markers of :obj:`name`, in order: side words, ``left`` /
    ``right`` inside a piece, else leg codes.

    Returns:
        list[tuple[int, int, str]]: Start, end and lower-case side word
        (``"l"``, ``"left"``, ``"fr"``, ...) of each marker (a new list
        each call: the markers are cached per name).
    """
    return list(_side_markers(name))


@lru_cache(maxsize=16384)
def _side_markers(name: str) -> Tuple[Marker, ...]:
    """:func:`side_markers`, cached on the name (every rig read, mirror
    and canonicalisation asks again for the same names)."""
    words, codes = [], []
    for start, piece in _pieces(name):
        low = piece.lower()
        if low in SIDE_WORDS:
            words.append((start, start + len(piece), low))
        elif low in LEG_CODES:
            codes.append((start, start + len(piece), low))
        else:
            glued = [(start + m.start(), start + m.end(), m.group().lower())
                     for m in _GLUED.finditer(piece)]
            side = None if glued else _glued_side(low)
            words += glued or ([(start, start + len(side), side)] if side else [])
    words += [(m.start(), m.end(), m.group()) for m in _CHARACTERS.finditer(name)]
    return tuple(sorted(words) or codes)


@lru_cache(maxsize=4096)
def _glued_side(piece: str) -> Optional[str]:
    """The side word a lower-case piece starts with when the rest is body
    words, in the piece and in its mirror image, split as the lexicon
    splits glued words (``"lfemur"`` -> ``"l"``; ``"label"``, ``"lower"``,
    ``"lear"`` (``"rear"``) -> ``None``)."""
    from satagraph.semantics.lexicon import _segment  # the lexicon imports this module
    side = _segment(piece)[0]
    if side not in SIDE_WORDS or side == piece:
        return None
    other = MIRROR_WORDS[side]
    return side if _segment(other + piece[len(side):])[0] == other else None


def side_of_words(words: Iterable[str]) -> Optional[str]:
    """``"left"``, ``"right"`` or ``None`` for lower-case words already
    split from a name: the first side word, else the first leg code."""
    words = list(words)
    side = next((SIDE_WORDS[w] for w in words if w in SIDE_WORDS), None)
    if side is None:
        side = next((LEG_CODES[w][1] for w in words if w in LEG_CODES), None)
    return side


def side_of(name: str) -> Optional[str]:
    """``"left"``, ``"right"`` or ``None``: the side of a joint name
    (``"mixamorig:LeftUpLeg"``, ``"thigh.L"``, ``"HipL"`` -> ``"left"``;
    ``"Hips"``, ``"Ladder"`` -> ``None``)."""
    return side_of_words(word for _, _, word in _side_markers(name))


def _mirror_case(text: str) -> str:
    other = MIRROR_WORDS[text.lower()]
    if text.isupper():
        return other.upper()
    return other.capitalize() if text[0].isupper() else other


def swap_side(name: str) -> str:
    """The mirror image of a joint name: every side marker swapped, case
    kept (``"LeftUpLeg"`` -> ``"RightUpLeg"``, ``"thigh.L"`` ->
    ``"thigh.R"``, ``"FL_Foot"`` -> ``"FR_Foot"``); names without a side
    come back unchanged."""
    out, pos = [], 0
    for start, end, _ in _side_markers(name):
        out += [name[pos:start], _mirror_case(name[start:end])]
        pos = end
    return "".join(out) + name[pos:]


def side_pairs(names: List[str], key: Optional[Callable[[str], str]] = None
               ) -> Tuple[List[int], List[int]]:
    r"""Left joints and their right counterparts, matched by name:
    :obj:`names` ``[right[k]]`` is the mirror image of ``[left[k]]``
    (:func:`swap_side`, compared case-blind).

    Args:
        names (list[str]): Joint names.
        key (callable, optional): Normalises a name before matching (for
            example drops exporter noise).

    Returns:
        tuple[list[int], list[int]]: Indices of the left joints and of
        their right counterparts.
    """
    keys = [key(n) if key else n for n in names]
    index = {k.lower(): i for i, k in enumerate(keys)}
    left, right = [], []
    for i, k in enumerate(keys):
        other = index.get(swap_side(k).lower())
        if side_of(k) == "left" and other is not None and other != i:
            left.append(i)
            right.append(other)
    return left, right
