"""Rule-based canonical functional descriptions of joints.

The rules follow the SATA prompt (paper Figure 6) without a language model:

* **Taxonomic neutrality**: limbs are "front" / "hind" limbs with girdle,
  upper, lower, terminal and digit segments, so a human thigh and a dog's
  hind thigh are both ``"... hind limb upper segment (thigh)"`` and a human
  upper arm and a dog's front upper leg are both ``"... front limb upper
  segment (upper arm)"``. Digits are numbered first (thumb, big toe) to
  fifth (little finger / toe).
* **Hierarchy-aware reading**: ambiguous words take the rank their place in
  the chain allows (``Leg`` under ``UpLeg`` is the lower segment, ``Shoulder``
  under ``Collar`` the upper segment, ``Foot`` under ``Ankle`` the toes,
  ``LHipJoint`` above ``LeftUpLeg`` the hip bone). A limb named only with leg
  words is a front limb when it hangs off the trunk at or above the arms (or,
  without arms, above the lowest leg attachment and in the upper half of the
  spine); otherwise it is a hind limb. Arm words always mean a front limb.
* **Abbreviations** and rig prefixes are expanded or dropped (see
  :mod:`.lexicon`); **numbers are ignored**; end sites and ``End`` / ``Nub``
  / ``Tip`` joints become ``"... tip"``.
* **Helpers** (twist, share, IK bones) that lead to no real joint are the
  described segment plus ``"twist helper"`` / ``"helper"``; a "twist" joint
  on the main chain (CC_Base ``NeckTwist01`` above the head) is the segment
  itself.
* Unknown names fall back to their cleaned words plus a structural role:
  ``"unnamed joint, second segment of a chain from the spine"``.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import List, Optional, Sequence, Tuple

from satagraph.data.semantics.lexicon import NameInfo, parse_name

SEGMENTS = ("girdle segment", "upper segment", "lower segment",
            "terminal segment", "digit segment")
TIP_SEGMENTS = ("girdle", "upper segment", "lower segment", "terminal",
                "digit")
GLOSSES = {
    "front": ("clavicle / shoulder blade", "upper arm", "forearm",
              "hand / front paw", "fingers / front paw digits"),
    "hind": ("hip bone", "thigh", "shin / calf", "foot / hind paw", "toes"),
}
TIP_GLOSSES = {
    "front": ("shoulder", "elbow", "wrist", "hand / front paw tip",
              "fingertip"),
    "hind": ("hip joint", "knee", "ankle", "foot / hind paw tip", "toe tip"),
}
DIGIT_GLOSSES = {
    "front": {"first": "thumb", "second": "index finger",
              "third": "middle finger", "fourth": "ring finger",
              "fifth": "little finger"},
    "hind": {"first": "big toe", "second": "second toe",
             "third": "middle toe", "fourth": "fourth toe",
             "fifth": "little toe"},
}
TRUNK_TEXT = {
    "root": "skeleton root (ground reference of the whole body)",
    "pelvis": "pelvis, hips root (center of motion)",
    "pelvis_girdle": "pelvis segment (hips)",
    "spine": "spine segment (back)",
    "spine_lower": "spine segment (lower back / waist)",
    "spine_upper": "spine segment (chest)",
    "neck": "neck segment", "head": "head", "headtop": "head top tip",
    "face": "face",
}
TRUNK_LABEL = {"root": "skeleton root", "pelvis": "pelvis",
               "pelvis_girdle": "pelvis", "spine": "spine",
               "spine_lower": "spine", "spine_upper": "spine",
               "neck": "neck", "head": "head", "headtop": "head",
               "face": "face"}
TRUNK_TIP = {"root": "skeleton root tip", "pelvis": "pelvis tip",
             "pelvis_girdle": "pelvis tip", "spine": "spine tip",
             "spine_lower": "spine tip", "spine_upper": "spine tip",
             "neck": "neck tip", "head": "head top tip",
             "headtop": "head top tip", "face": "head top tip"}
PART_TEXT = {"jaw": "lower jaw", "tongue": "tongue segment",
             "snout": "snout (nose)", "breast": "breast (soft tissue)"}
HELPER_TEXT = {"twist": "twist helper", "ik": "inverse kinematics helper",
               "helper": "helper"}
ORDINALS = ("zeroth", "first", "second", "third", "fourth", "fifth", "sixth",
            "seventh", "eighth", "ninth", "tenth")


def ordinal(k: int) -> str:
    """English ordinal word for small :obj:`k`, ``"11th"`` style beyond.

    Args:
        k: A non-negative integer.

    Returns:
        The ordinal.
    """
    if k < len(ORDINALS):
        return ORDINALS[k]
    suffix = "th" if 10 <= k % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(
        k % 10, "th")
    return f"{k}{suffix}"


def _join(*parts: Optional[str]) -> str:
    return " ".join(p for p in parts if p)


@dataclass
class _State:
    """Per-joint working state of the structural pass."""

    kind: str  # limb | trunk | part | tail | tip | unknown
    info: NameInfo
    side: Optional[str] = None
    front_hind: Optional[str] = None
    rank: int = -1
    digit: Optional[str] = None
    trunk: Optional[str] = None
    helper: Optional[str] = None


@dataclass(frozen=True)
class RuleResult:
    r"""Rule output for one skeleton.

    Attributes:
        descriptions (tuple[str, ...]): One description per joint.
        fallback (tuple[bool, ...]): ``True`` where the name was not
            understood and the description is a structural fallback.
    """

    descriptions: Tuple[str, ...]
    fallback: Tuple[bool, ...]


class _Tree:
    """Parent/children/depth of a joint list."""

    def __init__(self, parents: Sequence[int]) -> None:
        self.parents = list(parents)
        self.children: List[List[int]] = [[] for _ in self.parents]
        self.depth = [0] * len(self.parents)
        for j, p in enumerate(self.parents):
            if p >= 0:
                self.children[p].append(j)
                self.depth[j] = self.depth[p] + 1

    def path_to(self, j: int) -> List[int]:
        """Joints from the root down to :obj:`j`."""
        path = []
        while j >= 0:
            path.append(j)
            j = self.parents[j]
        return path[::-1]

    def subtree_size(self) -> List[int]:
        """Number of joints in each joint's subtree."""
        size = [1] * len(self.parents)
        for j in range(len(self.parents) - 1, 0, -1):
            size[self.parents[j]] += size[j]
        return size


def _initial_kind(info: NameInfo, j: int, end_site: bool) -> _State:
    if end_site or (info.tip and not info.has_content):
        kind = "tip"
    elif info.part:
        kind = "part"
    elif info.limb or info.mid_only:
        kind = "limb"
    elif info.tail:
        kind = "tail"
    elif info.trunk:
        kind = "trunk"
    elif j == 0 and not info.words:
        return _State("trunk", info, trunk="root")  # "Bip01", "mixamorig:"
    else:
        kind = "unknown"
    return _State(kind, info, side=info.side, trunk=info.trunk)


def _mark_helpers(states: List[_State], tree: _Tree) -> None:
    """A helper-named joint is a helper only if no real joint lies below."""
    core = [s.kind in ("limb", "trunk", "part", "tail") and not s.info.helper
            for s in states]
    below = [False] * len(states)
    for j in range(len(states) - 1, 0, -1):
        p = tree.parents[j]
        below[p] = below[p] or core[j] or below[j]
    for j, state in enumerate(states):
        if state.info.helper and state.kind != "tip" and not below[j]:
            state.helper = state.info.helper


def _trunk_path(states: List[_State], tree: _Tree) -> List[int]:
    """Root-to-head path (or to the neck / deepest spine joint), else the
    structural trunk."""
    for wanted, pick in ((("head",), min), (("neck",), min),
                         (("spine", "spine_lower", "spine_upper"), max)):
        found = [j for j, s in enumerate(states)
                 if s.kind == "trunk" and s.trunk in wanted]
        if found:
            return tree.path_to(pick(found, key=lambda j: (tree.depth[j], j)))
    return _structural_trunk(tree)


def _structural_trunk(tree: _Tree) -> List[int]:
    """Follow the largest child that has no mirror-image sibling."""
    size, path, j = tree.subtree_size(), [0], 0
    while tree.children[j]:
        kids = tree.children[j]
        single = [c for c in kids
                  if sum(size[o] == size[c] for o in kids) == 1]
        if not single:
            break
        j = max(single, key=lambda c: (size[c], -c))
        path.append(j)
    return path


def _attach_index(j: int, trunk_pos: dict, tree: _Tree) -> Optional[int]:
    p = tree.parents[j]
    while p >= 0 and p not in trunk_pos:
        p = tree.parents[p]
    return trunk_pos.get(p)


def _explicit_front_hind(root: int, states: List[_State],
                         tree: _Tree) -> Optional[str]:
    stack = [root]
    while stack:
        j = stack.pop()
        if states[j].info.front_hind:
            return states[j].info.front_hind
        stack.extend(c for c in tree.children[j] if states[c].kind == "limb")
    return None


def _limb_roots_front_hind(states: List[_State], tree: _Tree,
                           trunk: List[int]) -> dict:
    """Front/hind of each limb chain's first joint (see module doc)."""
    trunk_pos = {j: i for i, j in enumerate(trunk)}
    roots = [j for j, s in enumerate(states) if s.kind == "limb"
             and (j == 0 or states[tree.parents[j]].kind != "limb")]
    neck = next((i for i, j in enumerate(trunk)
                 if states[j].trunk in ("neck", "head", "headtop")),
                len(trunk) - 1)
    attach = {r: _attach_index(r, trunk_pos, tree) for r in roots}
    family = {r: (states[r].info.limb or ("leg",))[0] for r in roots}
    real = [r for r in roots if not states[r].helper and attach[r] is not None]
    arm_idx = [attach[r] for r in real if family[r] == "arm"]
    leg_idx = [attach[r] for r in real if family[r] != "arm"]
    out = {}
    for r in roots:
        explicit = _explicit_front_hind(r, states, tree)
        if explicit or family[r] == "arm":
            out[r] = explicit or "front"
        elif attach[r] is None or r not in real:
            out[r] = "hind"
        elif arm_idx:
            out[r] = "front" if attach[r] >= min(arm_idx) else "hind"
        else:
            upper = neck > 0 and attach[r] / neck >= 0.5
            out[r] = ("front" if upper and attach[r] > min(leg_idx)
                      else "hind")
    return out


def _upper_trunk_roles(states: List[_State], tree: _Tree,
                       trunk: List[int]) -> None:
    """Without any neck or head name, spine joints beyond the front-limb
    attachment are the neck, the last one the head (rigify ``spine.004``
    to ``spine.006``)."""
    if any(s.kind == "trunk" and s.trunk in ("neck", "head", "headtop", "face")
           for s in states):
        return
    trunk_pos = {j: i for i, j in enumerate(trunk)}
    attach = [_attach_index(j, trunk_pos, tree) for j, s in enumerate(states)
              if s.kind == "limb" and s.front_hind == "front" and not s.helper
              and j > 0 and states[tree.parents[j]].kind != "limb"]
    attach = [a for a in attach if a is not None]
    if not attach:
        return
    above = [j for j in trunk[max(attach) + 1:]
             if states[j].kind == "trunk" and states[j].trunk.startswith("spine")]
    for j in above:
        states[j].trunk = "head" if j == trunk[-1] else "neck"


def _definite_below(states: List[_State], tree: _Tree) -> List[float]:
    """Smallest definite limb rank strictly below each joint, in its limb."""
    inf = float("inf")
    below = [inf] * len(states)
    for j in range(len(states) - 1, 0, -1):
        s, p = states[j], tree.parents[j]
        if s.kind != "limb" or s.helper:
            continue
        own = inf
        if s.info.limb and len(s.info.limb[1]) == 1:
            own = min(s.info.limb[1])
        below[p] = min(below[p], own, below[j])
    return below


def _resolve_rank(info: NameInfo, lower: int, upper: float) -> int:
    ranks, default = info.limb[1], info.limb[2]
    if len(ranks) == 1:
        return default
    feasible = [r for r in sorted(ranks) if lower <= r <= upper]
    if default in feasible:
        return default
    if feasible:
        return feasible[0]
    return max(ranks) if lower > max(ranks) else default


def _limb_parent(j: int, states: List[_State], tree: _Tree) -> Optional[int]:
    """Nearest ancestor in the same limb that is not a helper."""
    p = tree.parents[j]
    while p >= 0 and states[p].kind == "limb":
        if not states[p].helper:
            return p
        p = tree.parents[p]
    return None


def _resolve_limbs(states: List[_State], tree: _Tree, roots: dict) -> None:
    below = _definite_below(states, tree)
    for j, s in enumerate(states):
        if s.kind != "limb":
            continue
        p = tree.parents[j]
        in_limb = p >= 0 and states[p].kind == "limb"
        lp = _limb_parent(j, states, tree)
        if s.info.mid_only:
            if lp is None or states[lp].rank < 3:
                s.kind = "unknown"
                continue
            s.rank, s.digit = 4, "third"
        else:
            lower = states[lp].rank + 1 if lp is not None else 0
            s.rank = _resolve_rank(s.info, lower, below[j] - 1)
            s.digit = s.info.digit
        if s.rank == 4 and not s.digit:
            parent_digit = states[lp].digit if lp is not None else None
            s.digit = parent_digit or ""
        s.front_hind = s.info.front_hind or (
            states[p].front_hind if in_limb else roots.get(j, "hind"))
        s.side = s.info.side or (states[p].side if in_limb else None)


def _limb_core(s: _State) -> str:
    segment = SEGMENTS[s.rank]
    if s.rank == 4 and s.digit:
        segment = f"{s.digit} {segment}"
    return _join(s.side, s.front_hind, "limb", segment)


def _limb_text(s: _State) -> str:
    if s.helper:
        return _join(_limb_core(s), HELPER_TEXT[s.helper])
    if s.info.tip:
        return _limb_tip(s)
    fh = s.front_hind or "hind"
    gloss = GLOSSES[fh][s.rank]
    if s.rank == 4 and s.digit:
        gloss = DIGIT_GLOSSES[fh][s.digit]
    return f"{_limb_core(s)} ({gloss})"


def _limb_tip(s: _State) -> str:
    segment = TIP_SEGMENTS[s.rank]
    if s.rank == 4 and s.digit:
        segment = f"{s.digit} {segment}"
    core = _join(s.side, s.front_hind, "limb", segment)
    if s.helper:
        return _join(core, HELPER_TEXT[s.helper], "tip")
    fh = s.front_hind or "hind"
    gloss = TIP_GLOSSES[fh][s.rank]
    if s.rank == 4 and s.digit:
        gloss = f"{DIGIT_GLOSSES[fh][s.digit]} tip"
    return f"{core} tip ({gloss})"


class _Describer:
    """Turns resolved joint states into text."""

    def __init__(self, states: List[_State], tree: _Tree) -> None:
        self.states, self.tree = states, tree
        self.text: List[str] = [""] * len(states)
        self.fallback = [False] * len(states)

    def run(self) -> RuleResult:
        for j in range(len(self.states)):
            self.text[j] = self.describe(j)
        return RuleResult(tuple(self.text), tuple(self.fallback))

    def describe(self, j: int) -> str:
        s = self.states[j]
        if s.kind == "tip":
            return self.tip_of(self.tree.parents[j]) if j else "skeleton tip"
        if s.kind == "limb":
            return _limb_text(s)
        if s.kind == "unknown":
            self.fallback[j] = True
            return self.unknown(j)
        base = self.base_text(j)
        if s.info.tip and s.kind != "trunk":
            return f"{self.label(j)} tip"
        return _join(base, HELPER_TEXT.get(s.helper or ""))

    def base_text(self, j: int) -> str:
        s = self.states[j]
        if s.kind == "trunk":
            if s.info.tip:
                return TRUNK_TIP[self.trunk_kind(j)]
            return TRUNK_TEXT[self.trunk_kind(j)]
        if s.kind == "part":
            return _join(s.side, PART_TEXT.get(s.info.part, s.info.part))
        return "tail segment"

    def trunk_kind(self, j: int) -> str:
        """Hierarchy-aware trunk role: root vs pelvis, face vs head."""
        s, tree = self.states[j], self.tree
        ancestors = tree.path_to(j)[:-1]
        kinds = [self.states[a].trunk for a in ancestors
                 if self.states[a].kind == "trunk"]
        if s.trunk == "pelvis" and "pelvis" in kinds:
            return "pelvis_girdle"
        if s.trunk == "face" and "head" not in kinds:
            return "head"
        if j == 0 and s.trunk in ("root", "spine", "spine_lower") \
                and self._legs_on_root(j):
            return "pelvis"  # rigify "spine", a root that carries the legs
        return s.trunk

    def _legs_on_root(self, j: int) -> bool:
        has_pelvis = any(s.kind == "trunk" and s.trunk == "pelvis"
                         for s in self.states)
        return not has_pelvis and any(
            self.states[c].kind == "limb"
            and self.states[c].front_hind == "hind"
            for c in self.tree.children[j])

    def label(self, j: int) -> str:
        """Short name of a joint, used in tips and fallback roles."""
        s = self.states[j]
        if s.kind == "limb":
            return _limb_core(s)
        if s.kind == "trunk":
            return TRUNK_LABEL[self.trunk_kind(j)]
        if s.kind == "part":
            return _join(s.side, s.info.part)
        if s.kind == "tail":
            return "tail"
        if s.kind == "tip" and j > 0:
            return self.label(self.tree.parents[j])
        return s.info.cleaned() or "unnamed joint"

    def tip_of(self, p: int) -> str:
        s = self.states[p]
        if s.kind == "tip" or s.info.tip:
            return self.text[p]
        if s.kind == "limb":
            return _limb_tip(s)
        if s.kind == "trunk":
            return TRUNK_TIP[self.trunk_kind(p)]
        if s.kind == "unknown":
            return f"tip of {self.text[p]}"
        return f"{self.label(p)} tip"

    def unknown(self, j: int) -> str:
        info = self.states[j].info
        name = info.cleaned() or "unnamed"
        name = name if name.endswith("joint") else f"{name} joint"
        if j == 0:
            return f"{name}, root of the skeleton"
        a = self.tree.parents[j]
        while a > 0 and self.states[a].kind in ("unknown", "tip"):
            a = self.tree.parents[a]
        known = self.states[a].kind not in ("unknown", "tip")
        where = self.label(a) if known else "skeleton root"
        hops = self.tree.depth[j] - self.tree.depth[a]
        return f"{name}, {ordinal(hops)} segment of a chain from the {where}"


@lru_cache(maxsize=256)
def describe_structure(names: Tuple[str, ...], parents: Tuple[int, ...],
                       end_site: Tuple[bool, ...]) -> RuleResult:
    """Rule descriptions of a joint list (cached on the exact structure).

    Args:
        names: Raw joint names.
        parents: Parent index per joint (``-1`` for the root, parents first).
        end_site: End-site flags.

    Returns:
        RuleResult: descriptions and fallback flags.
    """
    tree = _Tree(parents)
    states = [_initial_kind(parse_name(n), j, bool(e))
              for j, (n, e) in enumerate(zip(names, end_site))]
    _mark_helpers(states, tree)
    trunk = _trunk_path(states, tree)
    _resolve_limbs(states, tree, _limb_roots_front_hind(states, tree, trunk))
    _upper_trunk_roles(states, tree, trunk)
    return _Describer(states, tree).run()
