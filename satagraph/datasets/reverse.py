r"""Reversing captions: the text of a motion played backwards in time.

A walk played backwards is a backward walk: the body travels the other way
while it keeps facing the same way, and the legs' swing reverses. Human
backward walking is close to forward walking time-reversed in its limb
kinematics (Grasso et al. 1998, "Motor patterns for human gait: backward
versus forward locomotion"), which is what lets
:func:`~satagraph.transforms.augment.reverse_time` give captioned backward
walks on rigs whose data holds only forward ones (``experiments/T2M.md``
section 65).

Few captions say what their motion is backwards: a jump, a start, a turn
or a stop does not read the same. :func:`reverse_text` therefore knows only
walks in the words of the templated motion-capture captions
(:mod:`.mocap_captions`: subjects, styles, ``walks forward`` /
``backward``) and gives ``None`` for any other text, which leaves such a
window unreversed.
"""
from __future__ import annotations

import re
from typing import FrozenSet, Optional

from satagraph.datasets.mocap_captions import BANDAI_STYLES, SUBJECTS, XIA_STYLES

#: Direction word -> the direction of the reversed walk.
REVERSED_DIRECTIONS = {"forward": "backward", "forwards": "backward",
                       "backward": "forward", "backwards": "forward"}
#: The verbs a reversible caption walks with.
WALK_VERBS = ("walks",)
_WORD = re.compile(r"[a-z]+")


def _words(text: str) -> FrozenSet[str]:
    return frozenset(_WORD.findall(text.lower()))


def _style_words() -> FrozenSet[str]:
    words = set()
    for adverbs, adjective in (*BANDAI_STYLES.values(), *XIA_STYLES.values()):
        for phrase in (*adverbs, adjective):
            words |= _words(phrase)
    return frozenset(words)


#: Every word a reversible caption may hold: the walk verbs, directions,
#: subjects and style phrases of the templated captions, and ``person``.
REVERSIBLE_WORDS: FrozenSet[str] = (
    _style_words() | _words(" ".join(SUBJECTS)) | _words(" ".join(REVERSED_DIRECTIONS))
    | frozenset(WALK_VERBS) | {"a", "an", "person"})


def reverse_text(text: str) -> Optional[str]:
    """The caption of the motion played backwards in time, where it is known.

    Args:
        text: A caption.

    Returns:
        str, optional: A walk's caption with its direction reversed
        (``forward`` <-> ``backward``; a walk that names no direction walks
        ``backward``), or ``None`` where :obj:`text` holds a word outside
        :data:`REVERSIBLE_WORDS` or no walk verb.

    Example::

        reverse_text("a person walks forward sadly")   # 'a person walks backward sadly'
        reverse_text("someone walks")                  # 'someone walks backward'
        reverse_text("a person jumps forward")         # None
    """
    tokens = _WORD.findall(text.lower())
    if not tokens or not set(tokens) <= REVERSIBLE_WORDS \
            or not set(tokens) & set(WALK_VERBS):
        return None
    if set(tokens) & set(REVERSED_DIRECTIONS):
        pattern = r"\b(" + "|".join(REVERSED_DIRECTIONS) + r")\b"
        return re.sub(pattern, lambda m: REVERSED_DIRECTIONS[m.group(1).lower()], text,
                      flags=re.IGNORECASE)
    verbs = r"\b(" + "|".join(WALK_VERBS) + r")\b"
    return re.sub(verbs, r"\1 backward", text, count=1, flags=re.IGNORECASE)


__all__ = ["REVERSED_DIRECTIONS", "REVERSIBLE_WORDS", "WALK_VERBS", "reverse_text"]
