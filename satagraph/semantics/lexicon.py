"""Joint-name lexicon: split raw joint names into canonical tokens.

A raw name such as ``"mixamorig:LeftUpLeg"``, ``"CC_Base_L_Thigh"``,
``"DEF-upper_arm.L.001"`` or ``"Bip01 L Finger0Nub"`` is parsed into a
:class:`NameInfo`: side, explicit front/hind, limb keyword (with the segment
ranks it may stand for), trunk/part/tail words, helper and tip flags, and the
words that were not understood. Parsing depends only on the name; the
hierarchy is taken into account later, in :mod:`.rules`.

Limb segment ranks: 0 girdle (clavicle, shoulder blade, hip bone), 1 upper
(upper arm, thigh), 2 lower (forearm, shin), 3 terminal (hand, foot, paw),
4 digit (fingers, toes). A digitigrade segment (``HorseLink``,
tarsometatarsus, cannon bone) has rank 3 without using it up: the foot below
it is still the terminal segment.

Tokens that are not words -- exporter suffixes such as ``Tail_01__x7Q``,
version tags ``_v2`` and hashes ``_a1b2c3`` -- are dropped before parsing
(:func:`drop_noise_tokens`).
"""
from __future__ import annotations

import os
import re
from dataclasses import dataclass
from functools import lru_cache
from typing import Dict, FrozenSet, List, Optional, Sequence, Tuple

from satagraph.semantics.foreign import english_name
from satagraph.sides import LEG_CODES, SIDE_WORDS, side_of_words

# (family, candidate ranks, default rank). Family "arm" is a strong hint of a
# front limb, "leg" a weak hint of a hind limb (the hierarchy may override it).
LimbWord = Tuple[str, FrozenSet[int], int]

#: Words of a digitigrade segment (bird tarsometatarsus, horse cannon bone).
DIGITIGRADE_WORDS = frozenset({"horselink", "tarsometatarsus", "metatarsus",
                               "cannon", "tmt"})


def _limb(family: str, ranks: Tuple[int, ...], default: int) -> LimbWord:
    return (family, frozenset(ranks), default)


LIMB_WORDS: Dict[str, LimbWord] = {
    **{w: _limb("arm", (0,), 0) for w in (
        "clavicle", "clav", "collar", "collarbone", "scapula", "shoulderblade")},
    **{w: _limb("arm", (0, 1), 0) for w in ("shoulder", "shldr")},
    **{w: _limb("arm", (1,), 1) for w in (
        "upperarm", "uparm", "arm", "humerus", "bicep", "biceps")},
    **{w: _limb("arm", (2,), 2) for w in (
        "elbow", "forearm", "lowerarm", "loarm", "radius", "ulna",
        "foretwist")},  # 3ds Max biped's "Bip01 L ForeTwist"
    "wrist": _limb("arm", (3,), 3),
    "hand": _limb("arm", (3, 4), 3),
    "palm": _limb("arm", (3, 4), 3),
    **{w: _limb("arm", (3, 4), 3) for w in ("metacarpal", "carpal")},  # Daz "lCarpal1"
    **{w: _limb("arm", (4,), 4) for w in (
        "finger", "fingers", "fingerbase", "thumb", "index", "ring", "pinky",
        "pinkie", "little")},
    "hip": _limb("leg", (0, 1), 1),
    "hipjoint": _limb("leg", (0, 1), 0),
    "pelvis": _limb("leg", (0,), 0),
    "coxa": _limb("leg", (0,), 0),  # an arthropod leg's first segment
    **{w: _limb("leg", (1,), 1) for w in (
        "thigh", "upleg", "upperleg", "femur")},
    "leg": _limb("leg", (1, 2), 1),
    **{w: _limb("leg", (2,), 2) for w in (
        "knee", "stifle", "shin", "calf", "lowerleg", "loleg", "tibia",
        "crus", "gaskin")},
    **{w: _limb("leg", (3,), 3) for w in ("ankle", "hock", "tarsus", "heel")},
    **{w: _limb("leg", (3,), 3) for w in DIGITIGRADE_WORDS},
    **{w: _limb("leg", (3, 4), 3) for w in ("foot", "metatarsal")},  # Daz "lMetatarsals"
    "feet": _limb("leg", (3, 4), 3),
    "paw": _limb("leg", (3,), 3),
    "hoof": _limb("leg", (3,), 3),
    **{w: _limb("leg", (4,), 4) for w in (
        "toe", "toes", "toebase", "ball", "bigtoe")},
    # claws / pincers of arthropods: a limb of their own off the body (a
    # claw inside a hand or foot is a digit, see :mod:`.rules`)
    **{w: _limb("claw", (1, 2, 3), 1) for w in ("claw", "claws", "cheliped")},
    **{w: _limb("claw", (3,), 3) for w in ("pincer", "pincers", "chela",
                                           "nipper", "nippers")},
}

#: Limb words that also name a whole limb: in a name with another limb word
#: (``HindLeg_Hip_L``, ``Arm_L_Clavicle``) they say which limb, not which
#: segment.
WHOLE_LIMB_WORDS = frozenset({"leg", "arm"})

# Digit words -> ordinal, neutral across hands, feet and paws.
DIGIT_WORDS: Dict[str, str] = {
    "thumb": "first", "bigtoe": "first", "index": "second",
    "middle": "third", "mid": "third", "ring": "fourth", "pinky": "fifth",
    "pinkie": "fifth", "little": "fifth",
}

TRUNK_WORDS: Dict[str, str] = {
    **{w: "root" for w in (
        "root", "reference", "armature", "world", "origin", "master", "cog",
        "com", "trajectory")},
    **{w: "pelvis" for w in ("hips", "pelvic", "sacrum")},
    **{w: "spine" for w in (
        "spine", "torso", "abdomen", "abdomin", "belly", "stomach", "lumbar",
        "thoracic", "vertebra")},
    **{w: "spine_lower" for w in ("waist", "lowerback")},
    **{w: "spine_upper" for w in (
        "chest", "upperchest", "ribcage", "thorax", "upperback", "sternum")},
    **{w: "neck" for w in ("neck", "cervical")},
    **{w: "head" for w in ("head", "skull", "cranium")},
    "headtop": "headtop",
    **{w: "face" for w in ("face", "facial")},
    **{w: "body" for w in ("body", "carapace", "cephalothorax", "prosoma")},
}

PART_WORDS: Dict[str, str] = {
    **{w: "jaw" for w in ("jaw", "jawroot", "mandible", "chin")},
    "upperjaw": "upper jaw",
    **{w: "teeth" for w in ("teeth", "tooth")},
    "tongue": "tongue",
    **{w: "eye" for w in ("eye", "eyes", "eyeball")},
    **{w: "eyelid" for w in ("eyelid", "lid")},
    **{w: "eyebrow" for w in ("brow", "eyebrow")},
    **{w: "ear" for w in ("ear", "ears")},
    **{w: "snout" for w in ("nose", "snout", "muzzle")},
    **{w: "lip" for w in ("lip", "lips")},
    "mouth": "mouth", "cheek": "cheek", "beak": "beak", "horn": "horn",
    "antler": "antler",
    **{w: "hair" for w in ("hair", "ponytail", "mane")},
    **{w: "breast" for w in ("breast", "boob")},
    **{w: "ribs" for w in ("rib", "ribs")},
    **{w: "antenna" for w in ("antenna", "antennae", "antennas", "feeler")},
    **{w: "eye stalk" for w in ("eyestalk", "ommatophore")},
    **{w: "fang" for w in ("fang", "fangs", "chelicera", "chelicerae")},
    **{w: "fin" for w in ("fin", "fins", "flipper")},
    **{w: "tentacle" for w in ("tentacle", "tentacles")},
    "whisker": "whisker",
}

TAIL_WORDS = frozenset({"tail", "tailbone"})
HELPER_WORDS: Dict[str, str] = {
    **{w: "twist" for w in ("twist", "roll", "foretwist")},
    **{w: "ik" for w in ("ik", "pole", "target")},
    **{w: "helper" for w in (
        "share", "sharebone", "helper", "help", "corrective", "corr", "adjust",
        "fk", "ctrl", "control", "mch", "dummy", "socket", "attach", "prop",
        "weapon", "gun", "footsteps", "bend", "volume", "bulge")},
}
TIP_WORDS = frozenset({"end", "nub", "tip", "site", "effector", "ee"})
FILLER_WORDS = frozenset({
    "joint", "jnt", "jt", "bone", "bind", "def", "org", "grp", "node", "base",
    "mixamorig", "cc", "rl", "bip", "biped", "jnts", "skin", "bn", "b", "j",
})
FRONT_HIND_WORDS = {"front": "front", "fr": "front", "frnt": "front",
                    "fore": "front", "anterior": "front", "hind": "hind",
                    "bk": "hind", "rear": "hind", "hnd": "hind",
                    "posterior": "hind"}
POSITION_WORDS = {"up": "upper", "upper": "upper", "upr": "upper",
                  "uppr": "upper", "top": "upper", "lo": "lower",
                  "low": "lower", "lower": "lower", "lwr": "lower",
                  "bottom": "lower"}

# Adjacent-word compounds (after lower-casing), checked left to right.
COMPOUNDS: Dict[Tuple[str, str], str] = {
    ("fore", "arm"): "forearm", ("upper", "arm"): "upperarm",
    ("up", "arm"): "upperarm", ("lower", "arm"): "forearm",
    ("lo", "arm"): "forearm", ("low", "arm"): "forearm",
    ("up", "leg"): "upleg", ("upper", "leg"): "upleg",
    ("lower", "leg"): "lowerleg", ("lo", "leg"): "lowerleg",
    ("low", "leg"): "lowerleg", ("lower", "back"): "lowerback",
    ("upper", "back"): "upperback", ("upper", "chest"): "upperchest",
    ("upper", "jaw"): "upperjaw", ("lower", "jaw"): "jaw",
    ("head", "top"): "headtop", ("toe", "base"): "toebase",
    ("finger", "base"): "fingerbase", ("hip", "joint"): "hipjoint",
    ("share", "bone"): "sharebone", ("big", "toe"): "bigtoe",
    ("shoulder", "blade"): "shoulderblade", ("collar", "bone"): "collarbone",
    ("eye", "lid"): "eyelid", ("eye", "brow"): "eyebrow",
    ("jaw", "root"): "jawroot", ("tail", "bone"): "tailbone",
    ("center", "of"): "center", ("of", "mass"): "com",
    ("horse", "link"): "horselink", ("eye", "stalk"): "eyestalk",
    ("tarso", "metatarsus"): "tarsometatarsus", ("fore", "twist"): "foretwist",
}

_PREFIX = re.compile(
    r"^(?:cc_base_|cc_|rl_|def[-_]|org[-_]|mch[-_]|bip0*\d+[ _]*|"
    r"joint_|jnt_)", re.IGNORECASE)
_CAMEL = (re.compile(r"([a-z])([A-Z])"), re.compile(r"([A-Z]+)([A-Z][a-z])"),
          re.compile(r"([A-Za-z])(\d)"), re.compile(r"(\d)([A-Za-z])"))
_SEPARATORS = re.compile(r"[^A-Za-z0-9]+")
_TOKEN = re.compile(r"[A-Za-z0-9]+")
_LETTER = re.compile(r"[A-Za-z]")
_VERSION = re.compile(r"v(?:er|ersion)?\d+")
_MIXED = re.compile(r"[A-Za-z]\d+[A-Za-z]")
_HEX = re.compile(r"[0-9a-f]{5,}")
_ODD_CASE = re.compile(r"[a-z][A-Z][a-z]|[A-Z]{2}[a-z]$|\d[A-Z][a-z]")
_NUMBER = re.compile(r"\d+")

KNOWN_WORDS = frozenset(
    set(LIMB_WORDS) | set(DIGIT_WORDS) | set(TRUNK_WORDS) | set(PART_WORDS)
    | TAIL_WORDS | set(HELPER_WORDS) | TIP_WORDS | FILLER_WORDS
    | set(SIDE_WORDS) | set(FRONT_HIND_WORDS) | set(POSITION_WORDS)
    | {"back", "hips", "center", "centre", "big", "blade", "fl", "hl", "hr",
       "bl", "br", "wing", "wings", "mid", "middle"}
    | {w for pair in COMPOUNDS for w in pair} | set(COMPOUNDS.values()))


@dataclass(frozen=True)
class NameInfo:
    r"""What the rules understood from one raw joint name.

    Attributes:
        raw (str): The raw name.
        words (tuple[str, ...]): Canonical lower-case words, numbers dropped.
        side (str or None): ``"left"``, ``"right"`` or ``None``.
        front_hind (str or None): Explicit ``"front"`` / ``"hind"``.
        limb (tuple or None): ``(family, candidate ranks, default rank)``.
        digit (str or None): Digit ordinal (``"first"`` ... ``"fifth"``), or
            ``""`` for a digit without a known ordinal, ``None`` otherwise.
        mid_only (bool): The name's only body word is ``mid``/``middle``,
            which means a middle digit only inside a hand or foot.
        trunk (str or None): ``root``, ``pelvis``, ``spine``,
            ``spine_lower``, ``spine_upper``, ``neck``, ``head``, ``headtop``
            or ``face``.
        part (str or None): Head or soft-tissue part (``eye``, ``jaw`` ...).
        position (str or None): ``upper`` / ``lower`` adjective.
        tail (bool): A tail word is present.
        helper (str or None): ``twist``, ``ik`` or ``helper``.
        tip (bool): An end/nub/tip word is present.
        unknown (tuple[str, ...]): Words the lexicon does not know.
        digitigrade (bool): The limb word is a digitigrade segment
            (``HorseLink``, tarsometatarsus).
        wing (bool): A wing word is present (a wing is a front limb).
        number (int or None): The first number in the name (``leg_L_03``:
            3), used to order otherwise identical chains.
    """

    raw: str
    words: Tuple[str, ...]
    side: Optional[str]
    front_hind: Optional[str]
    limb: Optional[LimbWord]
    digit: Optional[str]
    mid_only: bool
    trunk: Optional[str]
    part: Optional[str]
    position: Optional[str]
    tail: bool
    helper: Optional[str]
    tip: bool
    unknown: Tuple[str, ...]
    digitigrade: bool = False
    wing: bool = False
    number: Optional[int] = None

    @property
    def has_content(self) -> bool:
        """``True`` when a body word (limb, trunk, part, tail) was found."""
        return bool(self.limb or self.trunk or self.part or self.tail
                    or self.mid_only)

    def cleaned(self) -> str:
        """Expanded, number-free form of the name (may be empty)."""
        out: List[str] = [w for w in (self.side, self.front_hind) if w]
        for word in self.words:
            if word in FILLER_WORDS or word in TIP_WORDS or \
                    word in SIDE_WORDS or word in FRONT_HIND_WORDS:
                continue
            word = POSITION_WORDS.get(word, word)
            if word not in out:
                out.append(word)
        return " ".join(out)


def strip_prefixes(name: str) -> str:
    """Remove namespaces and rig prefixes (``mixamorig:``, ``CC_Base_``,
    ``RL_``, ``DEF-``, ``ORG-``, ``Bip01``/``Bip001``, ``joint_``).

    Args:
        name: A raw joint name.

    Returns:
        The name without namespace and known prefixes.
    """
    name = name.strip().rsplit(":", 1)[-1].rsplit("|", 1)[-1]
    previous = None
    while previous != name:
        previous, name = name, _PREFIX.sub("", name, count=1)
    return name


def shared_prefix(names: Sequence[str]) -> str:
    """The longest prefix every name of a rig begins with, up to a
    separator, that leaves every name some letters (``Character1_Ctrl_``
    of MotionBuilder's HumanIK control rig: read per name, its ``Ctrl``
    would make every joint a helper), exporter noise
    (:func:`drop_noise_tokens`) aside. ``""`` for a rig of one joint.

    Args:
        names: The raw joint names of one rig.
    """
    if len(names) < 2:
        return ""
    clean = [drop_noise_tokens(name) for name in names]  # "Bip01__lg2" is "Bip01"
    common = os.path.commonprefix(clean)
    cut = max((i + 1 for i, c in enumerate(common) if _SEPARATORS.fullmatch(c)), default=0)
    prefix = common[:cut]
    keeps = all(_LETTER.search(c[cut:]) and n.startswith(prefix) for c, n in zip(clean, names))
    return prefix if keeps else ""


def split_words(name: str) -> List[str]:
    """Split a name into lower-case words at separators, camelCase humps
    and letter/digit boundaries.

    Args:
        name: A name without prefixes.

    Returns:
        The words, lower-cased, digits kept as their own words.
    """
    for pattern in _CAMEL:
        name = pattern.sub(r"\1 \2", name)
    return [w.lower() for w in _SEPARATORS.split(name) if w]


def _segment(word: str) -> List[str]:
    """Split a glued word (``"lefthand"``) into known words, or keep it."""
    if word in KNOWN_WORDS or word.isdigit() or len(word) < 4:
        return [word]
    if word.endswith("s") and word[:-1] in KNOWN_WORDS:
        return [word[:-1]]
    best: List[Optional[List[str]]] = [None] * (len(word) + 1)
    best[0] = []
    for end in range(1, len(word) + 1):
        for start in range(end):
            piece, head = word[start:end], best[start]
            if head is None:
                continue
            edge = start == 0 or end == len(word)
            if piece in KNOWN_WORDS and (len(piece) > 1 or edge):
                if best[end] is None or len(head) + 1 < len(best[end]):
                    best[end] = head + [piece]
    found = best[len(word)]
    return found if found and len(found) <= 4 else [word]


def _merge_compounds(words: List[str]) -> List[str]:
    out: List[str] = []
    for word in words:
        if out and (out[-1], word) in COMPOUNDS:
            out[-1] = COMPOUNDS[(out[-1], word)]
        else:
            out.append(word)
    return out


def _letter_runs(token: str) -> List[str]:
    """Lower-case letter runs of a token, split at camelCase humps."""
    for pattern in _CAMEL[:2]:
        token = pattern.sub(r"\1 \2", token)
    return [w.lower() for w in re.findall(r"[A-Za-z]+", token)]


def _is_word(run: str) -> bool:
    """A known word of three letters or more, or a glue of known words."""
    if len(run) < 3:
        return False
    return run in KNOWN_WORDS or all(w in KNOWN_WORDS for w in _segment(run))


def is_noise_token(token: str, suffix: bool = False) -> bool:
    """Whether a raw name token is not a word: a random ID (``x7Q``), a hash
    (``a1b2c3``) or a version tag (``v2``). :obj:`suffix` marks the last
    token after a double separator (``Tail_01__k3Z``), where any token
    without a real word is an exporter suffix.

    Args:
        token: An alphanumeric token of a raw name, case kept.
        suffix: The token ends the name after ``__`` (or ``--``, ``..``).

    Returns:
        bool: ``True`` when the token should be dropped.
    """
    low = token.lower()
    if _VERSION.fullmatch(low):
        return True
    if low.isdigit() or (low in KNOWN_WORDS and not suffix):
        return False
    real = any(_is_word(run) for run in _letter_runs(token))
    if _MIXED.search(token) or _HEX.fullmatch(low):
        return not real
    if suffix:  # "LeftHand" after "Model::" is camel case of words, "wnH" is not
        camel = all(w in KNOWN_WORDS for w in split_words(token))
        return not (real or low in SIDE_WORDS or low in TIP_WORDS) \
            or (bool(_ODD_CASE.search(token)) and not camel)
    return len(token) <= 4 and bool(_ODD_CASE.search(token)) and not real


@lru_cache(maxsize=16384)
def drop_noise_tokens(name: str) -> str:
    """Remove the tokens of a raw name that are not words (see
    :func:`is_noise_token`), each with the separator before it; namespaces
    and rig prefixes are kept for :func:`strip_prefixes` (cached; depends
    only on the name).

    Args:
        name: A raw joint name.

    Returns:
        str: The name with its word tokens only.
    """
    tokens = list(_TOKEN.finditer(name))
    last = len(tokens) - 1  # the last token before tip words (``_end``)
    while last > 0 and tokens[last].group().lower() in TIP_WORDS:
        last -= 1
    out, pos = [], 0
    for i, match in enumerate(tokens):
        gap = name[tokens[i - 1].end():match.start()] if i > 0 else ""
        suffix = i == last and i > 0 and len(gap) >= 2
        if is_noise_token(match.group(), suffix):
            out.append(name[pos:match.start() - len(gap)])
            pos = match.end()
    if not out:
        return name
    return "".join(out) + name[pos:]


@lru_cache(maxsize=16384)
def parse_name(raw: str) -> NameInfo:
    """Parse one raw joint name (cached; depends only on the name).

    Args:
        raw: The raw joint name.

    Returns:
        NameInfo: The understood words.
    """
    words: List[str] = []
    clean = strip_prefixes(drop_noise_tokens(english_name(raw)))
    for word in split_words(clean):
        words.extend(_segment(word))
    words = _merge_compounds([w for w in words if not w.isdigit()])
    words = _expand_combined_sides(words)
    words = [w for w in words if len(w) > 1 or w in SIDE_WORDS]
    number = _NUMBER.search(clean)
    return _classify(raw, tuple(words), int(number.group()) if number else None)


def _expand_combined_sides(words: List[str]) -> List[str]:
    """Quadruped leg codes: ``FL``/``FR``/``HL``/``HR``/``BL``/``BR`` mean
    front/hind + left/right when the name has no other side word (``Fr``
    alone next to a side word is just *front*)."""
    if any(w in SIDE_WORDS for w in words):
        return words
    out: List[str] = []
    for word in words:
        out.extend(LEG_CODES.get(word, (word,)))
    return out


def _pick_limb(words: Tuple[str, ...]) -> Optional[LimbWord]:
    """The most distal limb word (highest smallest rank) of the name; a
    word that names the whole limb (:data:`WHOLE_LIMB_WORDS`) only where no
    other limb word says which segment (``FrontLeg_Scapula_L``: the
    shoulder blade, not the leg's upper segment)."""
    named = [w for w in words if w in LIMB_WORDS]
    named = [w for w in named if w not in WHOLE_LIMB_WORDS] or named
    found = [LIMB_WORDS[w] for w in named]
    return max(found, key=lambda lw: (min(lw[1]), lw[2])) if found else None


def _classify(raw: str, words: Tuple[str, ...],
              number: Optional[int] = None) -> NameInfo:
    side = side_of_words(words)
    position = next((POSITION_WORDS[w] for w in words if w in POSITION_WORDS),
                    None)
    limb_words = [w for w in words if w in LIMB_WORDS or w == "back"]
    front_hind = next((FRONT_HIND_WORDS[w] for w in words
                       if w in FRONT_HIND_WORDS), None)
    has_limb = any(w in LIMB_WORDS for w in limb_words)
    if front_hind is None and has_limb and "back" in words:
        front_hind = "hind"  # "BackLeg", "Back_Left_Foot"
    limb, trunk = _pick_limb(words), _trunk(words, side, has_limb, position)
    if limb is not None and limb[0] == "leg" and words.count("pelvis") \
            and side is None:
        limb = _pick_limb(tuple(w for w in words if w != "pelvis"))
    if limb is not None and set(words) & {"hip", "hipjoint"} and side is None \
            and not any(w in LIMB_WORDS for w in words
                        if w not in ("hip", "hipjoint")):
        limb = None  # "CC_Base_Hip": the pelvis, not a limb
    limb = _adjust_limb_for_position(limb, words, position)
    wing = bool(set(words) & {"wing", "wings"})
    if wing and limb is None:
        limb = ("arm", frozenset((1, 2, 3)), 1)  # "Wing_L_01": a whole limb
    digit = _digit(words, limb)
    if digit is not None and limb is not None:
        limb = (_digit_family(words, limb), frozenset((4,)), 4)
    mid_only = (limb is None and digit is None
                and any(w in ("mid", "middle") for w in words)
                and not (trunk or _part(words) or set(words) & TAIL_WORDS))
    return NameInfo(
        raw=raw, words=words, side=side, front_hind=front_hind, limb=limb,
        digit=digit, mid_only=mid_only, trunk=None if limb else trunk,
        part=_part(words), position=position,
        tail=bool(set(words) & TAIL_WORDS),
        helper=next((HELPER_WORDS[w] for w in words if w in HELPER_WORDS),
                    None),
        tip=bool(set(words) & TIP_WORDS),
        unknown=tuple(w for w in words if w not in KNOWN_WORDS),
        digitigrade=bool(limb and limb[1] == frozenset((3,))
                         and set(words) & DIGITIGRADE_WORDS
                         and not set(words) & {"foot", "feet", "paw", "hoof"}),
        wing=wing, number=number)


def _trunk(words: Tuple[str, ...], side: Optional[str], has_limb: bool,
           position: Optional[str]) -> Optional[str]:
    for word in words:
        if word in TRUNK_WORDS:
            kind = TRUNK_WORDS[word]
            if kind == "spine" and position == "upper":
                return "spine_upper"
            if kind == "spine" and position == "lower":
                return "spine_lower"
            return kind
        if word in ("hip", "hipjoint", "pelvis") and side is None \
                and not _has_limb_besides(words, word):
            return "pelvis"
        if word == "back" and not has_limb and side is None:
            return "spine"  # "LowerBack"; a sided "back" is no spine (VRoid's "J_Sec_L_SkirtBack")
    return None


def _has_limb_besides(words: Tuple[str, ...], word: str) -> bool:
    """``True`` if a limb word other than :obj:`word` is among :obj:`words`."""
    return any(w in LIMB_WORDS and w != word for w in words)


def _adjust_limb_for_position(limb: Optional[LimbWord], words: Tuple[str, ...],
                              position: Optional[str]) -> Optional[LimbWord]:
    """``Leg`` + ``Upper`` in any order is a thigh, ``Arm`` + ``Lower`` a
    forearm (``"Leg_Upper"``, ``"Arm_Lo"``)."""
    if limb is None or position is None:
        return limb
    if "leg" in words:
        return LIMB_WORDS["upleg" if position == "upper" else "lowerleg"]
    if "arm" in words:
        return LIMB_WORDS["upperarm" if position == "upper" else "forearm"]
    return limb


def _digit(words: Tuple[str, ...], limb: Optional[LimbWord]) -> Optional[str]:
    if limb is None or 4 not in limb[1]:
        return None
    for word in words:
        if word in DIGIT_WORDS and (word not in ("mid", "middle", "little")
                                    or 4 in limb[1]):
            return DIGIT_WORDS[word]
    if min(limb[1]) == 4:
        return ""
    return "third" if any(w in ("mid", "middle") for w in words) else None


_FOOT_DIGIT_WORDS = frozenset({"toe", "toes", "toebase", "bigtoe", "foot", "feet",
                               "ball", "hoof", "metatarsal"})
_HAND_DIGIT_WORDS = frozenset({"hand", "finger", "fingers", "fingerbase",
                               "thumb", "palm", "metacarpal", "carpal"})


def _digit_family(words: Tuple[str, ...], limb: LimbWord) -> str:
    """Toes belong to the leg family, fingers to the arm family."""
    if set(words) & _FOOT_DIGIT_WORDS:
        return "leg"
    if set(words) & _HAND_DIGIT_WORDS:
        return "arm"
    return limb[0]


def _part(words: Tuple[str, ...]) -> Optional[str]:
    for word in words:
        if word in PART_WORDS:
            return PART_WORDS[word]
    return None
