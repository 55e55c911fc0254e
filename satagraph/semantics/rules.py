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
* **Body plans beyond mammals**: leg words (``Thigh``, ``Calf``,
  ``HorseLink``, ``Foot``, ``Toe``) make a hind limb even where the chain
  hangs off the same joint as the arms or wings (3ds Max biped birds); a
  digitigrade segment (tarsometatarsus, horse link) lies between the lower
  and the terminal segment; a chain of identically named joints that makes a
  whole limb (``leg_L_01`` -> ``leg_L_01_02`` ..., or wing chains named
  ``Finger_01`` .. ``03`` off the spine) is ranked by position; six or more
  legs are *leg pairs* numbered front to back (``"left front limb upper
  segment, first leg pair"``, then ``middle`` ..., the last pair ``hind``);
  claws / pincers, antennae, eye stalks, fangs, fins, beaks are named;
  limbs named as wings beside other front limbs (a dragon's) are ``"wing
  limb"`` segments, a bird's wings its front limbs.
* **Evidence** (optional, :mod:`.evidence`): a chain whose end bears weight
  is a leg wherever it hangs, hind unless the weight-bearing chains form a
  front and a back group; a laterally spread chain that never bears weight
  is a front limb (arm or wing); leg pairs are ordered by where they join
  the body, then by their feet; unnamed paired chains off the trunk become legs or wings. Without
  evidence, names and hierarchy decide.
* Unknown names fall back to their cleaned words plus a structural role:
  ``"unnamed joint, second segment of a chain from the spine"``.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache
from typing import Dict, List, Optional, Sequence, Tuple

from satagraph.semantics.evidence import JointEvidence
from satagraph.semantics.lexicon import NameInfo, parse_name, shared_prefix

SEGMENTS = ("girdle segment", "upper segment", "lower segment",
            "terminal segment", "digit segment")
TIP_SEGMENTS = ("girdle", "upper segment", "lower segment", "terminal",
                "digit")
GLOSSES = {
    "front": ("clavicle / shoulder blade", "upper arm", "forearm",
              "hand / front paw", "fingers / front paw digits"),
    "hind": ("hip bone", "thigh", "shin / calf", "foot / hind paw", "toes"),
    "wing": ("wing shoulder blade", "wing upper arm", "wing forearm",
             "wing hand", "wing fingers"),
}
TIP_GLOSSES = {
    "front": ("shoulder", "elbow", "wrist", "hand / front paw tip",
              "fingertip"),
    "hind": ("hip joint", "knee", "ankle", "foot / hind paw tip", "toe tip"),
    "wing": ("wing shoulder", "wing elbow", "wing wrist", "wing hand tip",
             "wing fingertip"),
}
DIGIT_GLOSSES = {
    "front": {"first": "thumb", "second": "index finger",
              "third": "middle finger", "fourth": "ring finger",
              "fifth": "little finger"},
    "hind": {"first": "big toe", "second": "second toe",
             "third": "middle toe", "fourth": "fourth toe",
             "fifth": "little toe"},
}
DIGIT_GLOSSES["wing"] = {k: f"wing {v}" for k, v in DIGIT_GLOSSES["front"].items()}
TRUNK_TEXT = {
    "root": "skeleton root (ground reference of the whole body)",
    "pelvis": "pelvis, hips root (center of motion)",
    "pelvis_girdle": "pelvis segment (hips)",
    "spine": "spine segment (back)",
    "spine_lower": "spine segment (lower back / waist)",
    "spine_upper": "spine segment (chest)",
    "neck": "neck segment", "head": "head", "headtop": "head top tip",
    "face": "face", "body": "main body segment (trunk)",
    "body_root": "main body, skeleton root (center of motion)",
}
TRUNK_LABEL = {"root": "skeleton root", "pelvis": "pelvis",
               "pelvis_girdle": "pelvis", "spine": "spine",
               "spine_lower": "spine", "spine_upper": "spine",
               "neck": "neck", "head": "head", "headtop": "head",
               "face": "face", "body": "main body",
               "body_root": "main body"}
TRUNK_TIP = {"root": "skeleton root tip", "pelvis": "pelvis tip",
             "pelvis_girdle": "pelvis tip", "spine": "spine tip",
             "spine_lower": "spine tip", "spine_upper": "spine tip",
             "neck": "neck tip", "head": "head top tip",
             "headtop": "head top tip", "face": "head top tip",
             "body": "main body tip", "body_root": "main body tip"}
PART_TEXT = {"jaw": "lower jaw", "tongue": "tongue segment",
             "snout": "snout (nose)", "breast": "breast (soft tissue)",
             "beak": "beak (bill)", "antenna": "antenna (feeler)",
             "eye stalk": "eye stalk (stalked eye)",
             "fang": "fang (chelicera)", "fin": "fin",
             "tentacle": "tentacle segment"}
HELPER_TEXT = {"twist": "twist helper", "ik": "inverse kinematics helper",
               "helper": "helper"}
DIGITIGRADE_GLOSS = {"hind": "tarsometatarsus / hock / horse link",
                     "front": "metacarpus / cannon", "wing": "wing metacarpus"}
DIGITIGRADE_TIP = "ankle / fetlock"
#: Glosses of arthropod legs and claws, per rank (girdle .. digit).
PAIR_GLOSSES = ("coxa / hip", "femur / thigh", "tibia / shin",
                "tarsus / foot", "claw tip / toes")
PAIR_TIP_GLOSSES = ("hip joint", "knee", "ankle", "foot tip", "toe tip")
CLAW_GLOSSES = ("claw base", "claw / pincer", "claw / pincer",
                "pincer", "pincer finger")
#: Weight-bearing (evidence): contact fraction, or mean height in body
#: heights, of some joint of the chain.
BEARS_WEIGHT_CONTACT = 0.2
BEARS_WEIGHT_HEIGHT = 0.05
#: A non-weight-bearing chain reaching this far sideways is an arm or wing.
SPREAD = 0.1
#: Weight-bearing chains this far apart along the body (body heights) are
#: front and hind limbs.
FRONT_HIND_GAP = 0.2
#: Legs of an arthropod (or more): leg pairs.
MIN_LEGS_FOR_PAIRS = 6
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
    family: Optional[str] = None  # arm | leg | claw (limbs)
    digitigrade: bool = False
    pair: Optional[int] = None  # leg pair, 1 = front (arthropods)


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
                         (("spine", "spine_lower", "spine_upper", "body"), max)):
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


@dataclass
class _Chain:
    """A limb chain hanging off the trunk, with its evidence facts."""

    root: int
    family: str  # arm | leg | claw
    attach: Optional[int]
    real: bool  # not a helper, attached to the trunk
    weight: Optional[bool] = None  # bears weight (None: no evidence)
    spread: float = 0.0  # sideways reach beyond the attachment
    forward: float = 0.0  # where its lowest joint (the foot) is
    attach_forward: float = 0.0  # where its first joint (on the body) is
    lateral: float = 0.0  # sideways position of its farthest joint
    low_height: float = 0.0  # height of its lowest joint
    root_height: float = 0.0  # height of its first joint


def _subtree(j: int, tree: _Tree) -> List[int]:
    out, stack = [], [j]
    while stack:
        k = stack.pop()
        out.append(k)
        stack.extend(tree.children[k])
    return out


def _chain_facts(chain: _Chain, tree: _Tree, ev: JointEvidence) -> None:
    """Weight bearing, spread and position of a chain from the evidence."""
    joints = _subtree(chain.root, tree)
    low = min(joints, key=lambda k: (ev.height[k], -tree.depth[k], k))
    far = max(joints, key=lambda k: (abs(ev.lateral[k]), tree.depth[k], -k))
    base = tree.parents[chain.root]
    chain.weight = (max(ev.contact[k] for k in joints) >= BEARS_WEIGHT_CONTACT
                    or ev.height[low] <= BEARS_WEIGHT_HEIGHT)
    chain.spread = abs(ev.lateral[far]) - (abs(ev.lateral[base]) if base >= 0 else 0.0)
    chain.forward, chain.lateral = ev.forward[low], ev.lateral[far]
    chain.attach_forward = ev.forward[chain.root]
    chain.low_height, chain.root_height = ev.height[low], ev.height[chain.root]


def _limb_chains(states: List[_State], tree: _Tree, trunk: List[int],
                 evidence: Optional[JointEvidence]) -> List[_Chain]:
    """Every limb chain's first joint, family, attachment and facts."""
    trunk_pos = {j: i for i, j in enumerate(trunk)}
    chains = []
    for j, s in enumerate(states):
        if s.kind != "limb" or (j > 0 and states[tree.parents[j]].kind == "limb"):
            continue
        attach = _attach_index(j, trunk_pos, tree)
        chain = _Chain(j, (s.info.limb or ("leg",))[0], attach,
                       not s.helper and attach is not None)
        if evidence is not None and j > 0:
            _chain_facts(chain, tree, evidence)
        chains.append(chain)
    return chains


def _unnamed_run(j: int, states: List[_State], tree: _Tree) -> List[int]:
    """An unbranched chain of unknown joints from :obj:`j` (tips aside)."""
    run = [j]
    while True:
        kids = [c for c in tree.children[run[-1]] if states[c].kind != "tip"]
        if not kids:
            return run
        if len(kids) != 1 or states[kids[0]].kind != "unknown":
            return []
        run.append(kids[0])


def _promote_unnamed_chains(states: List[_State], tree: _Tree,
                            trunk: List[int], ev: JointEvidence) -> None:
    """An unnamed chain of two or more joints hanging off the trunk to one
    side is a leg when it bears weight and an arm / wing when it spreads
    sideways without bearing weight; ranked by position."""
    for j, s in enumerate(states):
        p = tree.parents[j]
        if s.kind != "unknown" or p < 0 or states[p].kind != "trunk":
            continue
        run = _unnamed_run(j, states, tree)
        if len(run) < 2:
            continue
        chain = _Chain(j, "leg", None, True)
        _chain_facts(chain, tree, ev)
        side = s.info.side or ("left" if chain.lateral >= 0.03 else
                               "right" if chain.lateral <= -0.03 else None)
        family = ("leg" if chain.weight else
                  "arm" if chain.spread >= SPREAD else None)
        if side is None or family is None:
            continue
        first = 0 if len(run) >= 5 else 1
        for i, k in enumerate(run):
            rank = min(first + i, 4)
            states[k].kind, states[k].side = "limb", side
            states[k].info = replace(states[k].info, side=side, limb=(
                family, frozenset((rank,)), rank))


def _plausible(states: List[_State], chains: List[_Chain]) -> bool:
    """Evidence in a wrong frame (a flat body whose up axis was misjudged)
    is ignored: every limb chain with a named side must lie on that side,
    and a weight-bearing chain must hang below where it starts."""
    for c in chains:
        side = states[c.root].side
        if c.real and side and abs(c.lateral) >= 0.02 and \
                side != ("left" if c.lateral > 0 else "right"):
            return False
    return all(c.low_height < c.root_height for c in chains
               if c.real and c.weight)


def _weight_groups(chains: List[_Chain]) -> Dict[int, str]:
    """Front / hind of the weight-bearing chains: split at the largest gap
    along the body when it is wide enough (a quadruped), else all hind."""
    bearing = sorted((c for c in chains if c.real and c.weight
                      and c.family != "claw"), key=lambda c: (c.forward, c.root))
    gaps = [(b.forward - a.forward, i) for i, (a, b) in
            enumerate(zip(bearing, bearing[1:]))]
    split = max(gaps)[1] + 1 if gaps and max(gaps)[0] >= FRONT_HIND_GAP \
        else len(bearing)
    return {c.root: ("hind" if i < split else "front")
            for i, c in enumerate(bearing)}


def _by_names(chain: _Chain, arm_idx: List[int], leg_idx: List[int],
              neck: int) -> str:
    """Front / hind of a leg-word chain from where it hangs: above the arms
    is front, beside or below them hind (a biped bird's legs hang off the
    wings' spine joint); without arms, see the module doc."""
    if arm_idx:
        return "front" if chain.attach > max(arm_idx) else "hind"
    upper = neck > 0 and chain.attach / neck >= 0.5
    return "front" if upper and chain.attach > min(leg_idx) else "hind"


def _limb_roots_front_hind(states: List[_State], tree: _Tree,
                           trunk: List[int], chains: List[_Chain]) -> dict:
    """Front/hind of each limb chain's first joint (see module doc)."""
    neck = next((i for i, j in enumerate(trunk)
                 if states[j].trunk in ("neck", "head", "headtop")),
                len(trunk) - 1)
    arm_idx = [c.attach for c in chains if c.real and c.family == "arm"]
    leg_idx = [c.attach for c in chains if c.real and c.family == "leg"]
    groups = _weight_groups(chains)
    any_weight = bool(groups)
    out = {}
    for c in chains:
        explicit = _explicit_front_hind(c.root, states, tree)
        if explicit or c.family in ("arm", "claw"):
            out[c.root] = explicit or "front"
        elif not c.real:
            out[c.root] = "hind"
        elif c.root in groups:
            out[c.root] = groups[c.root]  # bears weight: a leg
        elif any_weight and c.weight is False and c.spread >= SPREAD:
            out[c.root] = "front"  # spread, never bears weight: arm / wing
        else:
            out[c.root] = _by_names(c, arm_idx, leg_idx, neck)
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
             if states[j].kind == "trunk" and states[j].trunk.startswith("spine")
             and "spine" in states[j].info.words]  # not an abdomen
    for j in above:
        states[j].trunk = "head" if j == trunk[-1] else "neck"


def _wings_beside_front_limbs(states: List[_State], tree: _Tree,
                              chains: List[_Chain]) -> None:
    """Limbs named as wings on a body that has other front limbs too (a
    dragon's wings beside its forelegs) are *wing* limbs, not a second pair
    of front limbs; a bird's wings are its front limbs and stay so."""
    limbs = {c.root: [j for j in _subtree(c.root, tree) if states[j].kind == "limb"]
             for c in chains if c.real and c.family != "claw"}
    wings = {r for r, joints in limbs.items() if any(states[j].info.wing for j in joints)}
    if not any(states[r].front_hind == "front" for r in set(limbs) - wings):
        return
    for r in wings:
        for j in limbs[r]:
            states[j].front_hind = "wing"


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
        s.family = (s.info.limb or ("leg",))[0]
        if s.family == "claw" and lp is not None and states[lp].family != "claw":
            s.rank, s.digit, s.family = 4, s.info.digit or "", states[lp].family
        elif s.info.mid_only:
            if lp is None or states[lp].rank < 3:
                s.kind = "unknown"
                continue
            s.rank, s.digit = 4, "third"
        else:
            lower = 0 if lp is None else states[lp].rank + (
                0 if states[lp].digitigrade else 1)
            s.rank = _resolve_rank(s.info, lower, below[j] - 1)
            s.digit = s.info.digit
            s.digitigrade = s.info.digitigrade and s.rank == 3
        if s.rank == 4 and not s.digit:
            parent_digit = states[lp].digit if lp is not None else None
            s.digit = parent_digit or ""
        s.front_hind = s.info.front_hind or (
            states[p].front_hind if in_limb else roots.get(j, "hind"))
        s.side = s.info.side or (states[p].side if in_limb else None)


def _same_name_run(r: int, states: List[_State], tree: _Tree) -> List[int]:
    """``r`` and the joints below it that repeat its words (numbers aside)."""
    run, j = [r], r
    while True:
        kids = [c for c in tree.children[j]
                if states[c].kind == "limb" and not states[c].helper]
        if len(kids) != 1 or states[kids[0]].info.words != states[r].info.words:
            return run
        j = kids[0]
        run.append(j)


def _positional_ranks(states: List[_State], tree: _Tree) -> None:
    """A whole limb named by one repeated word (``leg_L_01`` ..
    ``leg_L_01_04``, ``Wing_01`` .., ``Finger_01`` .. off the spine) is
    ranked by position: upper, lower, terminal, digit (girdle first from
    five joints on)."""
    below = _definite_below(states, tree)
    for r, s in enumerate(states):
        if s.kind != "limb" or s.helper or s.info.limb is None or (
                r > 0 and states[tree.parents[r]].kind == "limb"):
            continue
        ranks = s.info.limb[1]
        run = _same_name_run(r, states, tree)
        digits = ranks == frozenset((4,))
        if len(run) < 2 or not (len(ranks) > 1 or digits):
            continue
        first = 0 if len(run) >= 5 else (1 if digits else s.rank)
        cap = min(4, below[run[-1]] - 1)
        for i, j in enumerate(run):
            states[j].rank = int(min(first + i, cap))
            states[j].digit = "" if states[j].rank == 4 else None


def _pair_order_key(chain: _Chain, states: List[_State], geometry: bool
                    ) -> tuple:
    """Front-to-back sort key: where the leg joins the body, then where
    its foot is (legs may splay across each other: the body keeps their
    order), else the name's number, else front / middle / hind words, else
    the joint order."""
    info = states[chain.root].info
    word = {"front": 0, "hind": 2}.get(info.front_hind or "", 1)
    number = info.number if info.number is not None else 1 << 30
    where = (-chain.attach_forward, -chain.forward) if geometry else (0.0, 0.0)
    return (*where, number, word, chain.root)


def _number_leg_pairs(states: List[_State], tree: _Tree,
                      chains: List[_Chain]) -> None:
    """Six or more legs are leg pairs, numbered front to back per side; the
    first pair is the front limb, the last the hind limb, others middle."""
    legs = [c for c in chains if c.real and c.family == "leg"]
    if len(legs) < MIN_LEGS_FOR_PAIRS:
        return
    geometry = all(c.weight is not None for c in legs) and \
        2 * sum(bool(c.weight) for c in legs) >= len(legs)
    sides: Dict[Optional[str], List[_Chain]] = {}
    for c in legs:
        sides.setdefault(states[c.root].side, []).append(c)
    count = max(len(v) for v in sides.values())
    for side_legs in sides.values():
        side_legs.sort(key=lambda c: _pair_order_key(c, states, geometry))
        for k, c in enumerate(side_legs, start=1):
            label = "front" if k == 1 else "hind" if k == count else "middle"
            for j in _subtree(c.root, tree):
                if states[j].kind == "limb":
                    states[j].pair, states[j].front_hind = k, label


def _segment_word(s: _State, tip: bool = False) -> str:
    if s.digitigrade:
        return "digitigrade" if tip else "digitigrade segment"
    segment = (TIP_SEGMENTS if tip else SEGMENTS)[s.rank]
    return f"{s.digit} {segment}" if s.rank == 4 and s.digit else segment


def _core(s: _State, segment: str) -> str:
    if s.family == "claw":
        return _join(s.side, "claw limb", segment)
    core = _join(s.side, s.front_hind, "limb", segment)
    return f"{core}, {ordinal(s.pair)} leg pair" if s.pair else core


def _limb_core(s: _State) -> str:
    return _core(s, _segment_word(s))


def _gloss(s: _State, tip: bool = False) -> str:
    fh = s.front_hind if s.front_hind in GLOSSES else "hind"
    if s.family == "claw":
        return CLAW_GLOSSES[s.rank] + (" tip" if tip else "")
    if s.digitigrade:
        return DIGITIGRADE_TIP if tip else DIGITIGRADE_GLOSS[fh]
    if s.pair:
        return (PAIR_TIP_GLOSSES if tip else PAIR_GLOSSES)[s.rank]
    if s.rank == 4 and s.digit:
        return DIGIT_GLOSSES[fh][s.digit] + (" tip" if tip else "")
    return (TIP_GLOSSES if tip else GLOSSES)[fh][s.rank]


def _limb_text(s: _State) -> str:
    if s.helper:
        return _join(_limb_core(s), HELPER_TEXT[s.helper])
    if s.info.tip:
        return _limb_tip(s)
    return f"{_limb_core(s)} ({_gloss(s)})"


def _limb_tip(s: _State) -> str:
    if s.helper:
        return _join(_core(s, _segment_word(s, tip=True)), HELPER_TEXT[s.helper],
                     "tip")
    if s.pair:  # "left front limb terminal tip, first leg pair (foot tip)"
        core = _join(s.side, s.front_hind, "limb", _segment_word(s, True))
        return f"{core} tip, {ordinal(s.pair)} leg pair ({_gloss(s, True)})"
    return f"{_core(s, _segment_word(s, tip=True))} tip ({_gloss(s, True)})"


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
        if s.trunk == "body" and j == 0:
            return "body_root"
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
                       end_site: Tuple[bool, ...],
                       evidence: Optional[JointEvidence] = None) -> RuleResult:
    """Rule descriptions of a joint list (cached on the exact structure and
    evidence).

    Args:
        names: Raw joint names.
        parents: Parent index per joint (``-1`` for the root, parents first).
        end_site: End-site flags.
        evidence: Optional geometry / motion facts per joint (see
            :mod:`satagraph.semantics.evidence`).

    Returns:
        RuleResult: descriptions and fallback flags.
    """
    tree = _Tree(parents)
    cut = len(shared_prefix(names))
    states = [_initial_kind(parse_name(n[cut:]), j, bool(e))
              for j, (n, e) in enumerate(zip(names, end_site))]
    _mark_helpers(states, tree)
    trunk = _trunk_path(states, tree)
    if evidence is not None and not _plausible(
            states, _limb_chains(states, tree, trunk, evidence)):
        evidence = None
    if evidence is not None:
        _promote_unnamed_chains(states, tree, trunk, evidence)
    chains = _limb_chains(states, tree, trunk, evidence)
    _resolve_limbs(states, tree,
                   _limb_roots_front_hind(states, tree, trunk, chains))
    _positional_ranks(states, tree)
    _number_leg_pairs(states, tree, chains)
    _upper_trunk_roles(states, tree, trunk)
    _wings_beside_front_limbs(states, tree, chains)
    return _Describer(states, tree).run()
