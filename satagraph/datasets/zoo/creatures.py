r"""The zoo's body plans with fixed real-world naming dialects (see the
issue-15 rig spec): birds in the 3ds Max biped dialect (``Bip01_*``, legs
and wings off the same spine joint) and with finger-named wings, crabs
(three walking-leg pairs, claws, eye stalks), spiders (four leg pairs
numbered over both sides) and long-tailed quadrupeds (about 100 joints).

Every walking leg is an IK :class:`~satagraph.datasets.zoo.rigs.Leg`: an upper
and a lower bone solved by two-bone IK, then a rigid foot whose tips rest
flat on the ground in the rest pose.
"""
from __future__ import annotations

from typing import List, Optional, Sequence

import numpy as np

from satagraph.datasets.zoo.rigs import Leg, ZooRig, _Builder, _rot, _unit

Vec = Sequence[float]


def _limb(b: _Builder, parent: int, names: Sequence[str],
          offsets: Sequence[Vec], end: Optional[Vec] = None,
          key: Optional[str] = None, pole: Vec = (0.0, 0.0, 1.0),
          ik: int = 0) -> List[int]:
    """A chain of explicitly named joints, each at its offset from the
    last, with an optional end site; with :obj:`key`, joints ``ik``,
    ``ik + 1`` and ``ik + 2`` become an IK leg (upper, lower, foot)."""
    joints, j = [], parent
    for name, offset in zip(names, offsets):
        j = b.add(name, j, offset)
        joints.append(j)
    if end is not None:
        b.end(j, end)
    if key is not None:
        b.legs.append(Leg(key, joints[ik], joints[ik + 1], joints[ik + 2],
                          np.asarray(pole, dtype=np.float64)))
    return joints


def _spread(sx: float, yaw: float, out: float, up: float) -> np.ndarray:
    """Direction ``(out, up)`` in the vertical plane of a leg that points
    sideways (``sx``) turned by :obj:`yaw` degrees towards the front."""
    return _rot(1, np.radians(-sx * yaw)) @ np.array([sx * out, up, 0.0])


def _fold_wing(b: _Builder, joints: Sequence[int], sx: float) -> None:
    """Fold a wing (upper, lower, hand joints) along the body, flapping
    slightly."""
    b.swing(joints[0], static=(0, sx * 70, -sx * 15), amplitude=(0, 0, sx * 4), k=2.0)
    b.swing(joints[1], static=(0, -sx * 150, 0))
    b.swing(joints[2], static=(0, sx * 140, 0))


# ----------------------------------------------------------------- birds
def _bird_legs(b: _Builder, parent: int, names: Sequence[Sequence[str]],
               size: float, attach: Vec) -> float:
    """Digitigrade bird legs (thigh, shank, tarsometatarsus standing on
    flat toes); ``names[side]`` lists upper, lower, ankle, toe joints (and
    more toe joints). Returns the leg length."""
    thigh, shin, tarsus = (b.jitter(0.3 * size), b.jitter(0.45 * size),
                           b.jitter(0.35 * size))
    for side, chain in enumerate(names):
        sx = 1.0 if side == 0 else -1.0
        offsets = [np.array(attach) * [sx, 1, 1], (0, -thigh, 0.3 * thigh),
                   (0, -shin, -0.3 * shin), tarsus * _unit(np.array([0, -1, 0.15]))]
        offsets += [(0, 0, 0.1 * size)] * (len(chain) - 4)
        _limb(b, parent, chain, offsets, end=(0, 0, 0.08 * size), key="LR"[side])
    return thigh + shin


def _bip01(label: str, rng: np.random.Generator, name: str) -> ZooRig:
    """A bird in the 3ds Max biped dialect: legs and wings both hang off
    ``Bip01_Spine``; ``HorseLink`` is the tarsometatarsus."""
    b = _Builder(label, rng.choice(["ZXY", "YXZ"]), rng)
    s = rng.uniform(0.15, 0.8)
    root = b.add("Bip01", -1, (0, 0, 0))
    b.swing(root, static=(-10, 0, 0), amplitude=(2, 4, 3))
    pelvis = b.add("Bip01_Pelvis", root, (0, 0.01 * s, 0))
    spine = _limb(b, pelvis, ("Bip01_Spine", "Bip01_Spine1"),
                  ((0, 0.02 * s, 0.05 * s), (0, 0.04 * s, 0.18 * s)))
    neck = _limb(b, spine[1], ("Bip01_Neck", "Bip01_Neck1", "Bip01_Head", "Bip01_Beak"),
                 ((0, 0.12 * s, 0.06 * s), (0, 0.14 * s, 0.02 * s),
                  (0, 0.06 * s, 0.02 * s), (0, -0.01 * s, 0.06 * s)),
                 end=(0, -0.01 * s, 0.06 * s))
    for i, j in enumerate(neck[:2]):
        b.swing(j, amplitude=(6, 2, 0), phase=0.05 * i)
    b.swing(neck[2], static=(10, 0, 0), amplitude=(-8, 0, 0))
    tail = _limb(b, pelvis, ("Bip01_Tail", "Bip01_Tail1"),
                 ((0, 0.02 * s, -0.12 * s), (0, 0.01 * s, -0.1 * s)), end=(0, 0, -0.1 * s))
    for j in tail:
        b.swing(j, amplitude=(3, 5, 0))
    legs = [[f"Bip01_{S}_{part}" for part in ("Thigh", "Calf", "HorseLink", "Foot", "Toe0")]
            for S in "LR"]
    length = _bird_legs(b, spine[0], legs, s, (0.07 * s, -0.08 * s, -0.04 * s))
    for side, S in enumerate("LR"):
        sx = 1.0 if side == 0 else -1.0
        wing = _limb(b, spine[0], [f"Bip01_{S}_{p}" for p in
                                   ("Clavicle", "UpperArm", "Forearm", "Hand", "Finger0")],
                     [(sx * 0.03 * s, 0.08 * s, 0.1 * s)] + [
                         (sx * b.jitter(x * s), 0, 0) for x in (0.04, 0.25, 0.3, 0.25)],
                     end=(sx * 0.1 * s, 0, 0))
        _fold_wing(b, wing[1:4], sx)
    return b.rig(name, "fowl", length)


def _fingerwing(label: str, rng: np.random.Generator, name: str) -> ZooRig:
    """A bird whose wings are finger-named chains straight off the spine."""
    b = _Builder(label, rng.choice(["ZXY", "XYZ"]), rng)
    s = rng.uniform(0.15, 0.8)
    root = b.add("root", -1, (0, 0, 0))
    b.swing(root, static=(-10, 0, 0), amplitude=(2, 4, 3))
    pelvis = b.add("pelvis", root, (0, 0.01 * s, 0))
    body = _limb(b, pelvis, ("spine_01", "spine_02", "neck_01", "neck_02", "head", "beak"),
                 ((0, 0.03 * s, 0.1 * s), (0, 0.03 * s, 0.12 * s),
                  (0, 0.12 * s, 0.06 * s), (0, 0.12 * s, 0.02 * s),
                  (0, 0.06 * s, 0.02 * s), (0, -0.01 * s, 0.07 * s)),
                 end=(0, -0.01 * s, 0.06 * s))
    b.swing(body[2], amplitude=(6, 2, 0))
    b.swing(body[3], amplitude=(6, 2, 0), phase=0.05)
    b.swing(body[4], static=(10, 0, 0), amplitude=(-8, 0, 0))
    legs = [[f"{part}_{S}" for part in ("thigh", "shin", "tarsus", "toe")] for S in "LR"]
    length = _bird_legs(b, pelvis, legs, s, (0.06 * s, -0.05 * s, 0.02 * s))
    for side, S in enumerate("LR"):
        sx = 1.0 if side == 0 else -1.0
        wing = _limb(b, body[1], [f"{S}_Finger_{k:02d}" for k in (1, 2, 3)],
                     [(sx * 0.05 * s, 0.03 * s, 0)] + [
                         (sx * b.jitter(x * s), 0, 0) for x in (0.25, 0.3)],
                     end=(sx * 0.3 * s, 0, 0))
        _fold_wing(b, wing, sx)
    return b.rig(name, "fowl", length)


# ---------------------------------------------------------- arthropods
def _arthropod_leg(b: _Builder, parent: int, names: Sequence[str], sx: float,
                   attach: Vec, yaw: float, lengths: Vec, key: str) -> None:
    """An arthropod walking leg: upper bone up and out (knee up), lower
    bone down and out, a rigid terminal segment down to the tip."""
    l1, l2, l3 = lengths
    offsets = [attach, l1 * _spread(sx, yaw, 0.6, 0.8),
               l2 * _spread(sx, yaw, 0.4, -0.92), l3 * _spread(sx, yaw, 0.25, -0.97)]
    _limb(b, parent, names, offsets, end=0.15 * l3 * _spread(sx, yaw, 0.25, -0.97),
          key=key, pole=(0.0, 1.0, 0.0))


def _crab(label: str, rng: np.random.Generator, name: str,
          abdomen: bool = False) -> ZooRig:
    """A crab: three walking-leg pairs ``leg_S_0n`` (front to back), two
    claws ``Claw_S_*`` in front of them and eye stalks."""
    b = _Builder(label, rng.choice(["ZXY", "XYZ"]), rng)
    s = rng.uniform(0.05, 0.4)
    root = b.add("Root", -1, (0, 0, 0))
    b.swing(root, amplitude=(1, 2, 2), k=2.0)
    body = b.add("Body", root, (0, 0.04 * s, 0))
    lengths = (b.jitter(0.5 * s), b.jitter(0.55 * s), b.jitter(0.25 * s))
    for side, S in enumerate("LR"):
        sx = 1.0 if side == 0 else -1.0
        for n, (z, yaw) in enumerate(((0.12, 30.0), (0.0, 0.0), (-0.12, -30.0)), start=1):
            leg = f"leg_{S}_{n:02d}"
            _arthropod_leg(b, body, [leg, f"{leg}_02", f"{leg}_03", f"{leg}_04"], sx,
                           (sx * 0.3 * s, -0.04 * s, z * s), yaw, lengths, f"{S}{n}")
        claw = _limb(b, body, [f"Claw_{S}_01", f"Claw_{S}_02", f"Claw_{S}_Pincer"],
                     ((sx * 0.2 * s, -0.02 * s, 0.25 * s), (sx * 0.12 * s, 0, 0.25 * s),
                      (-sx * 0.06 * s, 0.02 * s, 0.28 * s)), end=(-sx * 0.04 * s, 0, 0.15 * s))
        b.swing(claw[0], static=(0, -sx * 10, 0), amplitude=(6, sx * 5, 0), phase=0.5 * side)
        b.swing(claw[1], amplitude=(0, sx * 8, 0), phase=0.5 * side + 0.1)
        b.swing(claw[2], amplitude=(0, sx * 10, 0), k=2.0, phase=0.3 * side)
        eye = b.add(f"EyeStalk_{S}", body, (sx * 0.07 * s, 0.06 * s, 0.3 * s))
        b.swing(eye, amplitude=(8, 8, 0), phase=0.25 * side)
        b.end(eye, (0, 0.08 * s, 0.02 * s))
    if abdomen:
        tail = b.add("Abdomen", body, (0, -0.06 * s, -0.2 * s))
        b.end(tail, (0, -0.02 * s, 0.12 * s))
    return b.rig(name, "crab", lengths[0] + lengths[1])


def _spider(label: str, rng: np.random.Generator, name: str,
            palps: bool = False) -> ZooRig:
    """A spider: legs ``Leg_L_01``..``Leg_L_04`` and ``Leg_R_05``..
    ``Leg_R_08`` (front to back), fangs and a two-joint abdomen."""
    b = _Builder(label, rng.choice(["ZXY", "YXZ"]), rng)
    s = rng.uniform(0.03, 0.2)
    root = b.add("Cephalothorax", -1, (0, 0, 0))
    b.swing(root, amplitude=(1, 1, 1), k=2.0)
    abdomen = _limb(b, root, ("Abdomen_01", "Abdomen_02"),
                    ((0, 0.03 * s, -0.15 * s), (0, 0.02 * s, -0.3 * s)),
                    end=(0, -0.02 * s, -0.2 * s))
    b.swing(abdomen[0], amplitude=(2, 3, 0))
    base = (b.jitter(0.55 * s), b.jitter(0.65 * s), b.jitter(0.35 * s))
    pairs = ((0.08, 55.0, 1.15), (0.03, 20.0, 1.0), (-0.02, -20.0, 0.9), (-0.07, -50.0, 1.05))
    for side, S in enumerate("LR"):
        sx = 1.0 if side == 0 else -1.0
        for n, (z, yaw, scale) in enumerate(pairs, start=1):
            leg = f"Leg_{S}_{n + 4 * side:02d}"
            _arthropod_leg(b, root, [leg, f"{leg}_1", f"{leg}_2", f"{leg}_3"], sx,
                           (sx * 0.1 * s, -0.02 * s, z * s), yaw,
                           [scale * x for x in base], f"{S}{n}")
        fang = b.add(f"Fang_{S}", root, (sx * 0.03 * s, -0.03 * s, 0.13 * s))
        b.swing(fang, amplitude=(5, 0, 0), k=2.0)
        b.end(fang, (0, -0.04 * s, 0.01 * s))
        if palps:
            palp = _limb(b, root, [f"Pedipalp_{S}", f"Pedipalp_{S}_1"],
                         ((sx * 0.05 * s, 0, 0.12 * s), (sx * 0.03 * s, 0.05 * s, 0.12 * s)),
                         end=(0, -0.06 * s, 0.1 * s))
            b.swing(palp[0], amplitude=(8, sx * 4, 0), phase=0.5 * side)
    return b.rig(name, "spider", base[0] + base[1])


# ----------------------------------------------------- long-tailed quadruped
_DIGITS = ("Index1", "Middle1", "Ring1", "Pinky1")


def _paw_leg(b: _Builder, parent: int, sx: float, names: Sequence[str],
             offsets: Sequence[Vec], paw: float, front: bool, key: str,
             digits: str) -> None:
    """A leg of [girdle], upper, lower, ankle / wrist joints; four flat
    digits (``<digits>Index1`` ...) spread at the end of the paw."""
    ik = len(names) - 3
    pole = (0.0, 0.0, -1.0 if front else 1.0)
    joints = _limb(b, parent, names, offsets, key=key, pole=pole, ik=ik)
    step = paw * _unit(np.array([0.0, -1.0, 0.25 if front else 0.08]))
    if not front:
        joints.append(b.add(names[-1].replace("Foot", "ToeBase"), joints[-1], step))
        step = np.zeros(3)
    for k, digit in enumerate(_DIGITS):
        spread = sx * (0.6 - 0.4 * k) * 0.1 * paw
        j = b.add(f"{digits}{digit}", joints[-1], step + (spread, 0, 0.15 * paw))
        b.end(j, (0.2 * spread, 0, 0.2 * paw))


def _longtail(label: str, rng: np.random.Generator, name: str,
              tail_joints: int = 32) -> ZooRig:
    """A long-tailed quadruped with Mixamo-like names, ``Tail_01``.., ears,
    jaw, tongue, snout and four digits per paw (about 100 joints)."""
    b = _Builder(label, rng.choice(["ZXY", "XYZ", "YXZ"]), rng)
    size = rng.uniform(0.35, 1.0)
    thigh, shin, hock = b.jitter(0.38 * size), b.jitter(0.4 * size), b.jitter(0.25 * size)
    arm, fore, paw = b.jitter(0.4 * size), b.jitter(0.42 * size), b.jitter(0.15 * size)
    body, width = b.jitter(1.0 * size, 0.15), 0.12 * size
    root = b.add("Hips", -1, (0, 0, 0))
    b.swing(root, amplitude=(1, 3, 2))
    spine = _limb(b, root, ("Spine", "Spine1", "Spine2"), [(0, 0.02 * size, body / 3)] * 3)
    for i, j in enumerate(spine):
        b.swing(j, amplitude=(0.5, -2, -1), phase=0.05 * i)
    head = _limb(b, spine[-1], ("Neck", "Neck1", "Head"),
                 ((0, 0.15 * size, 0.08 * size), (0, 0.15 * size, 0.07 * size),
                  (0, 0.08 * size, 0.06 * size)))
    for j in head[:2]:
        b.swing(j, static=(4, 0, 0), amplitude=(2, 3, 0), k=2.0)
    b.swing(head[2], static=(25, 0, 0), amplitude=(3, 0, 0), k=2.0, phase=0.1)
    _limb(b, head[2], ("Snout",), ((0, -0.03 * size, 0.2 * size),),
          end=(0, -0.02 * size, 0.1 * size))
    jaw = b.add("Jaw", head[2], (0, -0.06 * size, 0.05 * size))
    b.swing(jaw, amplitude=(4, 0, 0), k=2.0)
    b.end(jaw, (0, -0.02 * size, 0.2 * size))
    _limb(b, jaw, ("Tongue_01", "Tongue_02"), ((0, 0.01 * size, 0.06 * size),
                                               (0, 0, 0.06 * size)), end=(0, 0, 0.04 * size))
    for side, S in enumerate("LR"):
        sx = 1.0 if side == 0 else -1.0
        ear = b.add(f"Ear_{S}", head[2], (sx * 0.06 * size, 0.06 * size, -0.02 * size))
        b.swing(ear, amplitude=(6, 0, sx * 6), phase=0.3 * side)
        b.end(ear, (sx * 0.02 * size, 0.1 * size, -0.03 * size))
    step = 1.3 * size / tail_joints
    tail = _limb(b, root, [f"Tail_{i + 1:02d}" for i in range(tail_joints)],
                 [(0, 0.01 * size, -step)] + [(0, 0, -step)] * (tail_joints - 1),
                 end=(0, 0, -step))
    for i, j in enumerate(tail):
        b.swing(j, static=(-1.5 if i < tail_joints // 3 else 0.5, 0, 0),
                amplitude=(0.5, 2.5, 0), phase=-0.03 * i)
    for side, S in enumerate(("Left", "Right")):
        sx = 1.0 if side == 0 else -1.0
        _paw_leg(b, root, sx, [f"{S}UpLeg", f"{S}Leg", f"{S}Foot"],
                 [(sx * width, -0.08 * size, -0.05 * size), (0, -thigh, 0.01), (0, -shin, -0.01)],
                 hock, False, S[0] + "H", f"{S}Foot")
        _paw_leg(b, spine[-1], sx, [f"{S}Shoulder", f"{S}Arm", f"{S}ForeArm", f"{S}Hand"],
                 [(sx * width, -0.08 * size, 0.05 * size), (sx * 0.2 * width, -0.12 * size, 0),
                  (0, -arm, 0.01), (0, -fore, -0.01)], paw, True, S[0] + "F", f"{S}Hand")
    return b.rig(name, "longtail", thigh + shin)
