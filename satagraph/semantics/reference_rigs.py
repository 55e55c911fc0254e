r"""Hand-built skeletons of body plans beyond mammals, for the semantic rules.

The rigs follow the naming conventions of the zoo's body plans (issue 15
rig spec): a 3ds Max biped bird whose legs and wings hang off the same spine
joint (``bip01``), a bird whose wing chains are named like fingers
(``fingerwing``), a crab, a spider, a long-tailed quadruped, and any of them
with exporter noise in every name (:func:`with_exporter_noise`). Offsets are
metres, +Y up, facing +Z, left at +X, in a standing rest pose (feet on the
ground, wings spread), so :func:`rest_evidence` gives valid geometry
evidence. Tests and ``benchmarks/semantic_alignment.py`` share them.

Example::

    from satagraph.semantics import describe_joints
    from satagraph.semantics.reference_rigs import crab, rest_evidence

    skeleton = crab()
    describe_joints(skeleton, evidence=rest_evidence(skeleton))
"""
from __future__ import annotations

import hashlib
from typing import Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np

from satagraph.semantics.evidence import JointEvidence, joint_evidence
from satagraph.skeleton import Skeleton

#: ``(name, parent name or None, offset)``; a name ending in ``_end`` is an
#: end site.
Row = Tuple[str, Optional[str], Tuple[float, float, float]]
SIDES = (("L", 1.0), ("R", -1.0))


def build_skeleton(rows: Sequence[Row]) -> Skeleton:
    """A skeleton from rows listed parents first.

    Args:
        rows: ``(name, parent, (x, y, z))`` per joint, the root first with
            parent ``None``; names ending in ``_end`` are end sites.

    Returns:
        Skeleton: The skeleton (offsets in metres, +Y up, facing +Z).
    """
    index: Dict[str, int] = {}
    parents: List[int] = []
    for name, parent, _ in rows:
        if name in index:
            raise ValueError(f"duplicate joint {name!r}")
        parents.append(-1 if parent is None else index[parent])
        index[name] = len(parents) - 1
    return Skeleton(names=[r[0] for r in rows], parents=np.array(parents),
                    offsets=np.array([r[2] for r in rows], dtype=np.float64),
                    end_site=np.array([r[0].endswith("_end") for r in rows]))


def rest_evidence(skeleton: Skeleton) -> JointEvidence:
    """Evidence of a reference rig's rest pose (valid because its offsets
    are canonical: metres, +Y up, facing +Z)."""
    return joint_evidence(skeleton.rest_positions())


def bip01_bird() -> Skeleton:
    """Bird, 3ds Max biped style: legs (``Thigh`` .. ``HorseLink`` ..
    ``Toe0``) and wings (``Clavicle`` .. ``Finger0``) off ``Bip01_Spine``."""
    rows: List[Row] = [
        ("Bip01", None, (0.0, 0.35, 0.0)),
        ("Bip01_Pelvis", "Bip01", (0.0, 0.0, 0.0)),
        ("Bip01_Spine", "Bip01_Pelvis", (0.0, 0.02, 0.03)),
        ("Bip01_Spine1", "Bip01_Spine", (0.0, 0.03, 0.06)),
        ("Bip01_Neck", "Bip01_Spine1", (0.0, 0.05, 0.05)),
        ("Bip01_Neck1", "Bip01_Neck", (0.0, 0.07, 0.02)),
        ("Bip01_Head", "Bip01_Neck1", (0.0, 0.06, 0.02)),
        ("Bip01_Beak", "Bip01_Head", (0.0, 0.0, 0.05)),
        ("Bip01_Beak_end", "Bip01_Beak", (0.0, 0.0, 0.04)),
        ("Bip01_Tail", "Bip01_Pelvis", (0.0, 0.01, -0.08)),
        ("Bip01_Tail1", "Bip01_Tail", (0.0, 0.0, -0.07)),
        ("Bip01_Tail1_end", "Bip01_Tail1", (0.0, 0.0, -0.06)),
    ]
    for s, k in SIDES:
        p = f"Bip01_{s}_"
        rows += [(p + "Thigh", "Bip01_Spine", (0.06 * k, -0.03, 0.0)),
                 (p + "Calf", p + "Thigh", (0.0, -0.1, 0.04)),
                 (p + "HorseLink", p + "Calf", (0.0, -0.1, -0.05)),
                 (p + "Foot", p + "HorseLink", (0.0, -0.1, 0.02)),
                 (p + "Toe0", p + "Foot", (0.0, -0.04, 0.05)),
                 (p + "Toe0_end", p + "Toe0", (0.0, 0.0, 0.03))]
        rows += [(p + "Clavicle", "Bip01_Spine", (0.04 * k, 0.04, 0.02)),
                 (p + "UpperArm", p + "Clavicle", (0.08 * k, 0.0, 0.0)),
                 (p + "Forearm", p + "UpperArm", (0.1 * k, 0.0, 0.0)),
                 (p + "Hand", p + "Forearm", (0.08 * k, 0.0, 0.0)),
                 (p + "Finger0", p + "Hand", (0.05 * k, 0.0, 0.0)),
                 (p + "Finger0_end", p + "Finger0", (0.03 * k, 0.0, 0.0))]
    return build_skeleton(rows)


def fingerwing_bird() -> Skeleton:
    """Bird whose wings are chains ``L_Finger_01`` .. ``03`` off the spine."""
    rows: List[Row] = [
        ("root", None, (0.0, 0.35, 0.0)), ("pelvis", "root", (0.0, 0.0, 0.0)),
        ("spine_01", "pelvis", (0.0, 0.02, 0.04)),
        ("spine_02", "spine_01", (0.0, 0.02, 0.04)),
        ("neck_01", "spine_02", (0.0, 0.05, 0.03)),
        ("neck_02", "neck_01", (0.0, 0.05, 0.02)),
        ("head", "neck_02", (0.0, 0.05, 0.02)),
        ("beak", "head", (0.0, 0.0, 0.05)),
    ]
    for s, k in SIDES:
        rows += [(f"thigh_{s}", "pelvis", (0.05 * k, -0.02, 0.0)),
                 (f"shin_{s}", f"thigh_{s}", (0.0, -0.12, 0.03)),
                 (f"tarsus_{s}", f"shin_{s}", (0.0, -0.12, -0.03)),
                 (f"toe_{s}", f"tarsus_{s}", (0.0, -0.09, 0.04))]
        rows += [(f"{s}_Finger_01", "spine_02", (0.05 * k, 0.02, 0.0)),
                 (f"{s}_Finger_02", f"{s}_Finger_01", (0.12 * k, 0.0, 0.0)),
                 (f"{s}_Finger_03", f"{s}_Finger_02", (0.12 * k, 0.0, 0.0))]
    return build_skeleton(rows)


def crab(reverse_numbers: bool = False) -> Skeleton:
    """Crab: six walking legs ``leg_S_0n`` (numbered front to back, or back
    to front with :obj:`reverse_numbers`), two claws and two eye stalks."""
    rows: List[Row] = [("Root", None, (0.0, 0.08, 0.0)),
                       ("Body", "Root", (0.0, 0.0, 0.0))]
    for s, k in SIDES:
        rows += [(f"Claw_{s}_01", "Body", (0.04 * k, 0.0, 0.05)),
                 (f"Claw_{s}_02", f"Claw_{s}_01", (0.02 * k, 0.0, 0.04)),
                 (f"Claw_{s}_Pincer", f"Claw_{s}_02", (0.0, 0.0, 0.04)),
                 (f"EyeStalk_{s}", "Body", (0.015 * k, 0.02, 0.05))]
        for n in (1, 2, 3):
            label = 4 - n if reverse_numbers else n
            leg = f"leg_{s}_0{label}"
            rows += [(leg, "Body", (0.05 * k, 0.0, 0.03 - 0.03 * (n - 1))),
                     (f"{leg}_02", leg, (0.04 * k, 0.02, 0.0)),
                     (f"{leg}_03", f"{leg}_02", (0.04 * k, -0.04, 0.0)),
                     (f"{leg}_04", f"{leg}_03", (0.02 * k, -0.06, 0.0))]
    return build_skeleton(rows)


def spider() -> Skeleton:
    """Spider: legs ``Leg_L_01`` .. ``04`` and ``Leg_R_05`` .. ``08`` (front
    to back), abdomen and fangs off the cephalothorax."""
    rows: List[Row] = [
        ("Cephalothorax", None, (0.0, 0.05, 0.0)),
        ("Abdomen_01", "Cephalothorax", (0.0, 0.0, -0.03)),
        ("Abdomen_02", "Abdomen_01", (0.0, 0.0, -0.03)),
    ]
    for s, k in SIDES:
        rows.append((f"Fang_{s}", "Cephalothorax", (0.005 * k, -0.01, 0.02)))
        for i in range(4):
            leg = f"Leg_{s}_{i + 1 + (0 if s == 'L' else 4):02d}"
            rows += [(leg, "Cephalothorax", (0.01 * k, 0.0, 0.015 - 0.01 * i)),
                     (f"{leg}_1", leg, (0.03 * k, 0.02, 0.01 - 0.007 * i)),
                     (f"{leg}_2", f"{leg}_1", (0.03 * k, -0.03, 0.0)),
                     (f"{leg}_3", f"{leg}_2", (0.01 * k, -0.04, 0.0))]
    return build_skeleton(rows)


def long_tailed_quadruped(tail: int = 32) -> Skeleton:
    """Mixamo-like quadruped with a tail of :obj:`tail` joints ``Tail_01``
    .., ears, jaw, tongue, snout and four two-joint toes per paw."""
    rows: List[Row] = [
        ("Hips", None, (0.0, 0.6, 0.0)), ("Spine", "Hips", (0.0, 0.02, 0.15)),
        ("Spine1", "Spine", (0.0, 0.0, 0.15)), ("Spine2", "Spine1", (0.0, 0.0, 0.15)),
        ("Neck", "Spine2", (0.0, 0.08, 0.08)), ("Neck1", "Neck", (0.0, 0.08, 0.06)),
        ("Head", "Neck1", (0.0, 0.06, 0.06)), ("Jaw", "Head", (0.0, -0.04, 0.06)),
        ("Tongue", "Jaw", (0.0, 0.01, 0.05)), ("Snout", "Head", (0.0, 0.0, 0.12)),
        ("Ear_L", "Head", (0.04, 0.06, 0.0)), ("Ear_R", "Head", (-0.04, 0.06, 0.0)),
    ]
    rows += [(f"Tail_{i:02d}", "Hips" if i == 1 else f"Tail_{i - 1:02d}",
              (0.0, 0.0 if i > 1 else 0.02, -0.03)) for i in range(1, tail + 1)]
    for side, k in (("Left", 1.0), ("Right", -1.0)):
        rows += [(f"{side}Shoulder", "Spine2", (0.06 * k, -0.02, 0.02)),
                 (f"{side}Arm", f"{side}Shoulder", (0.04 * k, -0.1, 0.0)),
                 (f"{side}ForeArm", f"{side}Arm", (0.0, -0.22, 0.0)),
                 (f"{side}Hand", f"{side}ForeArm", (0.0, -0.22, 0.0))]
        rows += [(f"{side}UpLeg", "Hips", (0.08 * k, -0.04, 0.0)),
                 (f"{side}Leg", f"{side}UpLeg", (0.0, -0.24, 0.04)),
                 (f"{side}Foot", f"{side}Leg", (0.0, -0.28, -0.04))]
        for paw, top in (("Hand", 0.04), ("Foot", 0.04)):
            for t in range(1, 5):
                toe = f"{side}{paw}Toe{t}"
                rows += [(f"{toe}_1", f"{side}{paw}", ((t - 2.5) * 0.01, -top, 0.02)),
                         (f"{toe}_2", f"{toe}_1", (0.0, 0.0, 0.02)),
                         (f"{toe}_2_end", f"{toe}_2", (0.0, 0.0, 0.01))]
    rows += [(f"Tail_{tail:02d}_end", f"Tail_{tail:02d}", (0.0, 0.0, -0.03)),
             ("Snout_end", "Snout", (0.0, 0.0, 0.03))]
    return build_skeleton(rows)


#: Reference rig name -> builder.
REFERENCE_RIGS: Dict[str, Callable[[], Skeleton]] = {
    "bird_bip01": bip01_bird, "bird_fingerwing": fingerwing_bird,
    "crab": crab, "spider": spider, "quadruped_longtail": long_tailed_quadruped,
}

_ALNUM = "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789"


def exporter_suffix(name: str, seed: int = 0) -> str:
    """A deterministic non-word suffix for :obj:`name`: ``__`` and three
    random alphanumerics, a version tag ``_v2`` or a hash ``_a1b2c3``."""
    digest = hashlib.blake2b(f"{seed}:{name}".encode(), digest_size=8).digest()
    kind = digest[0] % 3
    if kind == 0:
        return "__" + "".join(_ALNUM[b % len(_ALNUM)] for b in digest[1:4])
    if kind == 1:
        return f"_v{1 + digest[1] % 9}"
    return "_" + digest[2:5].hex()


def with_exporter_noise(skeleton: Skeleton, seed: int = 0) -> Skeleton:
    """The skeleton with a random suffix on every joint name (end sites
    keep ``_end`` last: ``Toe0__x7Q_end``)."""
    names = []
    for name, end in zip(skeleton.names, skeleton.end_site.tolist()):
        base = name[:-4] if end and name.endswith("_end") else name
        names.append(base + exporter_suffix(base, seed) + ("_end" if end else ""))
    return skeleton.replace(names=names)
