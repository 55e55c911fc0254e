"""Limb ends found by their semantic descriptions, on any skeleton.

The four limbs of a tetrapod (``left front``, ``right front``, ``left
hind``, ``right hind``) end in a hand/front paw or a foot/hind paw. Their
terminal joints are what unpaired retargeting across species compares
(:func:`satagraph.losses.limb_velocity_loss`) and what the dog -> human
sanity check correlates (``benchmarks/retarget_sanity.py``): a human's hand
and a dog's front paw share the description "left front limb terminal
segment", whatever their names.
"""
from __future__ import annotations

import re
from typing import Callable, Dict, List

import numpy as np

from satagraph.semantics.evidence import EvidenceLike
from satagraph.skeleton import Skeleton

#: The limbs, in the order of :func:`limb_end_index`.
LIMBS: List[str] = ["left front", "right front", "left hind", "right hind"]


def limb_ends(skeleton: Skeleton, evidence: EvidenceLike = None) -> Dict[str, int]:
    """Terminal joint of each limb the skeleton has: the first joint that
    :func:`~satagraph.semantics.describe_joints` (with the optional
    geometry / motion :obj:`evidence`) describes as ``"<limb> limb terminal
    segment"`` (an arthropod's first and last leg pairs are its front and
    hind limbs)."""
    from satagraph.semantics import describe_joints  # the package imports this module
    found: Dict[str, int] = {}
    for j, text in enumerate(describe_joints(skeleton, evidence=evidence)):
        if _helper(text):  # Unreal's ik_foot_l: a target, not the foot
            continue
        for limb in LIMBS:
            if text.startswith(f"{limb} limb terminal segment") and limb not in found:
                found[limb] = j
    return found


def helper_joints(skeleton: Skeleton, evidence: EvidenceLike = None) -> np.ndarray:
    """Which joints are helpers: twist, share and inverse-kinematics bones
    that ride along a segment and lead to no real joint (CC_Base's
    ``CC_Base_L_CalfTwist01`` and ``CC_Base_L_KneeShareBone``, Unreal's
    ``calf_twist_01_l``), and their tips, as
    :func:`~satagraph.semantics.describe_joints` (with the optional
    geometry / motion :obj:`evidence`) reads them.

    Shapes:
        - **output**: :math:`(J,)` bool
    """
    return _marked(skeleton, evidence, _helper)


def _helper(description: str) -> bool:
    """Whether a joint's description is a helper's (twist, share, IK)."""
    return " helper" in description


def hip_bones(skeleton: Skeleton, evidence: EvidenceLike = None) -> np.ndarray:
    """Which joints are hip bones: a tetrapod's pelvic girdle, which is
    fused to its trunk (CMU's ``LHipJoint``, the bone from the pelvis to
    the hip socket), as :func:`~satagraph.semantics.describe_joints` reads
    them. The shoulder blade and an arthropod's coxa move; they are not.

    Shapes:
        - **output**: :math:`(J,)` bool
    """
    return _marked(skeleton, evidence, lambda text: "limb girdle segment (hip bone)" in text)


def _marked(skeleton: Skeleton, evidence: EvidenceLike,
            test: Callable[[str], bool]) -> np.ndarray:
    """Which joints' descriptions pass :obj:`test`, :math:`(J,)` bool."""
    from satagraph.semantics import describe_joints  # the package imports this module
    return np.array([test(text) for text in describe_joints(skeleton, evidence=evidence)],
                    dtype=bool)


def limb_end_index(skeleton: Skeleton, evidence: EvidenceLike = None) -> List[int]:
    """:func:`limb_ends` as a list in the order of :data:`LIMBS` (``-1``
    for a limb the skeleton lacks)."""
    found = limb_ends(skeleton, evidence)
    return [found.get(limb, -1) for limb in LIMBS]


#: A leg's terminal segment in a description of an arthropod's leg pairs.
_PAIRED_LEG_END = re.compile(r"^(left|right) \w+ limb terminal segment, \w+ leg pair")


def paired_legs(skeleton: Skeleton, evidence: EvidenceLike = None) -> int:
    """Number of legs numbered in leg pairs (six or more legs: an arthropod),
    ``0`` for a body with four legs or fewer, as
    :func:`~satagraph.semantics.describe_joints` (with the optional
    geometry / motion :obj:`evidence`) reads them."""
    from satagraph.semantics import describe_joints  # the package imports this module
    return sum(bool(_PAIRED_LEG_END.match(text))
               for text in describe_joints(skeleton, evidence=evidence))
