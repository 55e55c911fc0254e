r"""Joint names written in other scripts, read as English words.

The lexicon (:mod:`.lexicon`) and the rig reader know English words only.
Some exporters name their joints otherwise: a MikuMikuDance (MMD) model
names its bones in Japanese (``センター``, ``上半身2``, ``左ひざ``,
``右足ＩＫ``, ``左人指１``), and some rigs come with Chinese names
(``左大腿``, ``头``). :func:`english_name` rewrites such a name with
English words in place of the known ones, so every rule that reads joint
names reads these rigs too (``左ひざ`` -> ``Left Knee``).

The rewrite:

1. Unicode compatibility forms become plain ones (NFKC): full-width
   letters and digits (``ＩＫ``, ``１``) are ASCII.
2. Known words (:data:`FOREIGN_WORDS`: MMD's standard bone names and
   common Chinese joint names), the longest first, become English words
   between spaces.
3. Latin letters lose their accents (``Épaule`` -> ``Epaule``); what is
   still not ASCII is left for the lexicon, which reads it as a separator.

ASCII names come back unchanged. Where Japanese and Chinese read a
character differently, MMD's reading is kept (``足``: a leg, the thigh
bone of an MMD model; ``腕``: an arm).

Example::

    english_name("左ひざ")      # "Left Knee"
    english_name("右足ＩＫ")    # "Right Leg IK"
    english_name("上半身2")     # "Chest"
    english_name("LeftUpLeg")   # "LeftUpLeg"
"""
from __future__ import annotations

import re
import unicodedata
from functools import lru_cache
from typing import Dict

from satagraph.sides import SIDE_CHARACTERS

#: Known non-English joint words (NFKC forms) and their English words.
FOREIGN_WORDS: Dict[str, str] = {
    **{c: side.capitalize() for c, side in SIDE_CHARACTERS.items()},
    # MikuMikuDance: trunk and head
    "全ての親": "Master", "操作中心": "Root", "センター": "Hips",
    "グルーブ": "Groove Helper", "腰": "Waist", "股関節": "Hip", "下半身": "Pelvis",
    "上半身": "Spine", "上半身2": "Chest", "上半身3": "Upper Chest", "首": "Neck",
    "頭": "Head", "両目": "Eyes", "目": "Eye", "舌": "Tongue", "歯": "Teeth",
    "あご": "Jaw", "顎": "Jaw",
    "髪": "Hair", "眉": "Brow", "まぶた": "Eyelid", "耳": "Ear",
    "鼻": "Nose", "口": "Mouth", "胸": "Breast", "乳": "Breast",
    "尻尾": "Tail", "しっぽ": "Tail", "尾": "Tail",
    # MikuMikuDance: arms, hands and helpers
    "肩P": "Shoulder Helper", "肩C": "Shoulder Helper", "肩": "Shoulder",
    "腕捩れ": "Arm Twist", "腕捩": "Arm Twist", "腕": "Arm",
    "手捩れ": "Forearm Twist", "手捩": "Forearm Twist", "捩": "Twist",
    "ひじ": "Elbow", "肘": "Elbow", "手首": "Wrist", "手のひら": "Palm",
    "手": "Hand", "親指": "Thumb", "人差し指": "Index Finger",
    "人差指": "Index Finger", "人指": "Index Finger", "中指": "Middle Finger",
    "薬指": "Ring Finger", "小指": "Little Finger", "指": "Finger",
    "キャンセル": "Helper", "補助": "Helper", "親": "Parent",
    # MikuMikuDance: legs
    "前足": "Front Leg", "後ろ足": "Hind Leg", "後足": "Hind Leg",
    "足首": "Ankle", "足先": "Toe", "足": "Leg", "ひざ": "Knee", "膝": "Knee",
    "つま先": "Toe", "かかと": "Heel", "踵": "Heel",
    # Chinese
    "头": "Head", "胸部": "Chest", "颈": "Neck", "脖子": "Neck", "脊椎": "Spine",
    "脊柱": "Spine", "骨盆": "Pelvis", "髋": "Hip", "盆骨": "Pelvis", "锁骨": "Clavicle",
    "鎖骨": "Clavicle", "上臂": "Upper Arm", "大臂": "Upper Arm",
    "前臂": "Forearm", "小臂": "Forearm", "手腕": "Wrist", "手臂": "Arm",
    "手指": "Finger", "拇指": "Thumb", "食指": "Index Finger",
    "无名指": "Ring Finger", "大腿": "Thigh", "小腿": "Calf",
    "脚踝": "Ankle", "脚趾": "Toe", "脚": "Foot", "前腿": "Front Leg",
    "后腿": "Hind Leg", "腿": "Leg", "尾巴": "Tail", "翅膀": "Wing",
    "翼": "Wing",
}

_WORDS = re.compile("|".join(
    re.escape(word) for word in sorted(FOREIGN_WORDS, key=len, reverse=True)))
_SPACES = re.compile(r"\s+")


@lru_cache(maxsize=16384)
def english_name(name: str) -> str:
    """A joint name with its known foreign words in English (see the
    module); ASCII names come back unchanged.

    Args:
        name: A raw joint name.

    Returns:
        str: The name to read.
    """
    if name.isascii():
        return name
    name = unicodedata.normalize("NFKC", name)
    name = _WORDS.sub(lambda m: f" {FOREIGN_WORDS[m.group()]} ", name)
    return _SPACES.sub(" ", "".join(map(_plain_letter, name))).strip()


def _plain_letter(char: str) -> str:
    """A Latin letter without its accents (``É`` -> ``E``); any other
    character as it is (a kana keeps its voicing mark: ``ダ`` is not ``タ``)."""
    base = unicodedata.normalize("NFKD", char)
    return base[0] if base[:1].isascii() and base[:1].isalpha() else char
