r"""Templated captions of the motion-capture clips in ``../shared/data``,
from what their file names say.

* Bandai (``dataset-1_<action>_<style>_<take>``): :data:`BANDAI_ACTIONS`
  x :data:`BANDAI_STYLES` (16 action and 15 style tokens in the manifest).
  The phrases were checked against the clips where the token alone is
  ambiguous: ``walk-left``/``walk-right`` walk forward and diagonally to
  that side without turning (about 10-25 degrees off straight, facing
  kept), ``walk-back`` walks backwards, ``bye`` waves one hand and
  ``byebye`` both.
* CMU ``01_01``: "playground: forward jumps, turn around" (the CMU index).
* Xia et al. (``<style>_<content>_<take>``): content 01 walk, 13 run,
  16 jump, 18 punch; styles :data:`XIA_STYLES`.
* ccbase (CMU subjects 6 and 7 on the CC_Base rig, ``00S_TT``): what each
  trial does is not known here, so captions say what the whole subject
  does: dribbling a basketball (6), walking (7).

Every clip gets several phrasings: a subject (``"a person"``,
``"someone"``) x a verb phrase x a style phrase (an adverbial, or an
adjective before ``"person"``). A token that is not in the tables gives no
caption rather than a guess.
"""
from __future__ import annotations

import re
from typing import Dict, List, Optional, Sequence, Tuple

#: Bandai action token -> verb phrases (third person).
BANDAI_ACTIONS: Dict[str, Tuple[str, ...]] = {
    "bow": ("bows", "bends forward in a bow"),
    "bye": ("waves goodbye with one hand", "waves a hand to say goodbye"),
    "byebye": ("waves goodbye with both hands", "waves both hands to say goodbye"),
    "call": ("calls to someone", "calls someone over"),
    "dance-short": ("dances", "does a short dance"),
    "dash": ("dashes forward", "sprints forward"),
    "guide": ("gestures to show the way", "guides someone with a hand gesture"),
    "kick": ("kicks", "throws a kick"),
    "punch": ("punches", "throws a punch"),
    "respond": ("raises a hand to respond", "answers by raising a hand"),
    "run": ("runs forward", "runs"),
    "slash": ("slashes", "makes a slashing motion"),
    "walk": ("walks forward", "walks"),
    "walk-back": ("walks backward", "walks backwards"),
    "walk-left": ("walks forward and to the left", "walks diagonally to the left"),
    "walk-right": ("walks forward and to the right", "walks diagonally to the right"),
}

#: Style token -> (adverbial phrases, adjective). ``normal`` has neither.
BANDAI_STYLES: Dict[str, Tuple[Tuple[str, ...], str]] = {
    "active": (("energetically", "in an active way"), "energetic"),
    "angry": (("angrily", "in an angry manner"), "angry"),
    "childish": (("childishly", "like a child"), "childish"),
    "chimpira": (("like a thug", "like a street punk"), "thuggish"),
    "feminine": (("in a feminine way", "in a feminine manner"), "feminine"),
    "giant": (("like a giant", "like a huge, heavy giant"), "huge"),
    "happy": (("happily", "in a happy mood"), "happy"),
    "masculinity": (("in a masculine way", "in a manly manner"), "masculine"),
    "musical": (("theatrically, as in a musical", "like a musical performer"),
                "theatrical"),
    "normal": ((), ""),
    "not-confident": (("timidly", "without confidence"), "timid"),
    "old": (("like an old person", "like an elderly person"), "elderly"),
    "proud": (("proudly", "with pride"), "proud"),
    "sad": (("sadly", "in a sad mood"), "sad"),
    "tired": (("wearily", "in a tired way"), "tired"),
}

#: Xia et al. content number -> verb phrases.
XIA_CONTENTS: Dict[str, Tuple[str, ...]] = {
    "01": ("walks forward", "walks"),
    "13": ("runs forward", "runs"),
    "16": ("jumps", "makes a jump"),
    "18": ("punches", "throws a punch"),
}

#: Xia et al. style -> (adverbial phrases, adjective).
XIA_STYLES: Dict[str, Tuple[Tuple[str, ...], str]] = {
    "neutral": ((), ""),
    "angry": BANDAI_STYLES["angry"],
    "childlike": (("like a child", "childishly"), "childlike"),
    "depressed": (("dejectedly", "in a depressed mood"), "depressed"),
    "old": BANDAI_STYLES["old"],
    "proud": BANDAI_STYLES["proud"],
    "sexy": (("seductively", "in a sexy way"), "sexy"),
    "strutting": (("with a strut", "in a strutting, swaggering way"), "swaggering"),
}

#: CMU trials on their own (the CMU motion index).
CMU_TRIALS: Dict[str, Tuple[str, ...]] = {
    "01_01": ("a person jumps forward several times and turns around",
              "someone does a series of forward jumps, then turns around",
              "on a playground, a person hops forward repeatedly and turns around"),
}

#: CMU subjects whose trials are not told apart (ccbase): what every trial
#: of the subject does.
CMU_SUBJECTS: Dict[str, Tuple[str, ...]] = {
    "06": ("a person dribbles a basketball",
           "someone dribbles a basketball while moving around",
           "a basketball player dribbles the ball"),
    "07": ("a person walks", "someone walks", "a person takes a walk"),
}

SUBJECTS = ("a person", "someone")
_BANDAI = re.compile(r"^dataset-1_(?P<action>[a-z-]+)_(?P<style>[a-z-]+)_(?P<take>\d+)$")
_XIA = re.compile(r"^(?P<style>[a-z]+)_(?P<content>\d\d)_(?P<take>\d+)$")
_CCBASE = re.compile(r"^(?P<subject>\d{2,3})_(?P<trial>\d\d)$")


def _article(word: str) -> str:
    return "an" if word[:1] in "aeiou" else "a"


def styled(verbs: Sequence[str], style: Tuple[Tuple[str, ...], str]) -> List[str]:
    """Every phrasing of verb phrases in a style.

    Args:
        verbs: Verb phrases (``"walks forward"``).
        style: (adverbial phrases, adjective); both empty for no style.

    Returns:
        list[str]: ``subject verb adverbial`` for every subject, verb and
        adverbial, then ``a(n) adjective person verb``; plain ``subject
        verb`` without a style.
    """
    adverbs, adjective = style
    out = []
    for verb in verbs:
        if not adverbs:
            out += [f"{subject} {verb}" for subject in SUBJECTS]
            continue
        out += [f"{subject} {verb} {adverb}" for adverb in adverbs for subject in SUBJECTS]
        out.append(f"{_article(adjective)} {adjective} person {verb}")
    return out


def bandai_phrasings(stem: str) -> Optional[List[str]]:
    """Phrasings of a Bandai clip (``dataset-1_walk_angry_001``), or
    ``None`` when its name or tokens are unknown."""
    match = _BANDAI.match(stem)
    if not match or match["action"] not in BANDAI_ACTIONS \
            or match["style"] not in BANDAI_STYLES:
        return None
    return styled(BANDAI_ACTIONS[match["action"]], BANDAI_STYLES[match["style"]])


def cmu_phrasings(stem: str) -> Optional[List[str]]:
    """Phrasings of a CMU clip (``01_01``) or a Xia style clip
    (``angry_13_000``), or ``None``."""
    if stem in CMU_TRIALS:
        return list(CMU_TRIALS[stem])
    match = _XIA.match(stem)
    if not match or match["content"] not in XIA_CONTENTS \
            or match["style"] not in XIA_STYLES:
        return None
    return styled(XIA_CONTENTS[match["content"]], XIA_STYLES[match["style"]])


def ccbase_phrasings(stem: str) -> Optional[List[str]]:
    """Phrasings of a ccbase clip (``006_04``): its CMU subject's activity,
    or ``None`` for another subject."""
    match = _CCBASE.match(stem)
    if not match:
        return None
    subject = f"{int(match['subject']):02d}"
    return list(CMU_SUBJECTS[subject]) if subject in CMU_SUBJECTS else None


__all__ = ["BANDAI_ACTIONS", "BANDAI_STYLES", "XIA_CONTENTS", "XIA_STYLES",
           "CMU_TRIALS", "CMU_SUBJECTS", "SUBJECTS", "styled", "bandai_phrasings",
           "cmu_phrasings", "ccbase_phrasings"]
