"""Rig machinery of the zoo: rotation helpers, naming styles, the joint
builder (:class:`_Builder`), legs (:class:`Leg`), sways (:class:`Sway`)
and :class:`ZooRig`."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, List, Optional, Sequence

import numpy as np

from satagraph.ops.rotation_numpy import axis_angle_matrix_numpy
from satagraph.skeleton import Skeleton

_POS = ("Xposition", "Yposition", "Zposition")


# ------------------------------------------------------------------ math
def _rot(axis: int, angle: np.ndarray) -> np.ndarray:
    """Rotations about coordinate axis :obj:`axis` (0, 1, 2), :math:`(*, 3, 3)`."""
    return axis_angle_matrix_numpy(angle, axis)


def _euler(angles: np.ndarray) -> np.ndarray:
    """``Rx @ Ry @ Rz`` from angles :math:`(*, 3)` (radians)."""
    return _rot(0, angles[..., 0]) @ _rot(1, angles[..., 1]) @ _rot(2, angles[..., 2])


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)


def _frame(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Orthonormal frames (columns) from a direction and a second vector."""
    a = _unit(a)
    b = _unit(b - np.sum(a * b, axis=-1, keepdims=True) * a)
    return np.stack([a, b, np.cross(a, b)], axis=-1)


def _align(a_loc: np.ndarray, b_loc: np.ndarray, a_world: np.ndarray,
           b_world: np.ndarray) -> np.ndarray:
    """Rotations taking ``a_loc`` to ``a_world`` (exactly) and ``b_loc``
    towards ``b_world``."""
    return _frame(a_world, b_world) @ np.swapaxes(_frame(a_loc, b_loc), -1, -2)


def _smoothstep(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


# ---------------------------------------------------------------- naming
#: Naming conventions: joint key -> template. ``{S}`` is the side word,
#: ``{i}`` 1-based, ``{i0}`` empty for the first, ``{i2}``/``{i3}``
#: zero-padded; a tuple lists explicit names per index.
STYLES: Dict[str, Dict[str, object]] = {
    "mixamo": dict(
        sides=("Left", "Right"), root="Hips", spine="Spine{i0}",
        neck="Neck{i0}", head="Head", tail="Tail{i0}",
        girdle_h=None, upper_h="{S}UpLeg", lower_h="{S}Leg",
        foot_h="{S}Foot", toe_h="{S}ToeBase", girdle_f="{S}Shoulder",
        upper_f="{S}Arm", lower_f="{S}ForeArm", hand_f="{S}Hand",
        wing_prefix="{S}Wing", jaw="Jaw"),
    "blender": dict(
        sides=("L", "R"), root="hips", spine="spine.{i3}", neck="neck.{i3}",
        head="head", tail="tail.{i3}", girdle_h=None, upper_h="thigh.{S}",
        lower_h="shin.{S}", foot_h="foot.{S}", toe_h="toe.{S}",
        girdle_f="shoulder.{S}", upper_f="upper_arm.{S}",
        lower_f="forearm.{S}", hand_f="hand.{S}", jaw="jaw"),
    "cmu": dict(
        sides=("Left", "Right"), root="Hips",
        spine=("LowerBack", "Spine", "Spine1", "Spine2"), neck="Neck{i0}",
        head="Head", tail="Tail{i0}", girdle_h="{s}HipJoint",
        upper_h="{S}UpLeg", lower_h="{S}Leg", foot_h="{S}Foot",
        toe_h="{S}ToeBase", girdle_f="{S}Shoulder", upper_f="{S}Arm",
        lower_f="{S}ForeArm", hand_f="{S}Hand", jaw="Jaw"),
    "smpl": dict(
        sides=("l", "r"), root="pelvis", spine="spine{i}", neck="neck{i0}",
        head="head", tail="tail{i}", girdle_h=None, upper_h="{S}_hip",
        lower_h="{S}_knee", foot_h="{S}_ankle", toe_h="{S}_foot",
        girdle_f="{S}_collar", upper_f="{S}_shoulder", lower_f="{S}_elbow",
        hand_f="{S}_wrist", jaw="jaw"),
    # Quadrupeds: legs named as front / hind legs.
    "frontleg": dict(
        sides=("Left", "Right"), root="Pelvis", spine="Spine{i2}",
        neck="Neck{i2}", head="Head", tail="Tail{i2}",
        girdle_h="{S}HindHip", upper_h="{S}HindThigh",
        lower_h="{S}HindShin", foot_h="{S}HindFoot", toe_h="{S}HindToe",
        girdle_f="{S}FrontScapula", upper_f="{S}FrontUpperLeg",
        lower_f="{S}FrontLowerLeg", hand_f="{S}FrontPaw", toe_f=None,
        jaw="Jaw"),
    "abbrev": dict(
        sides=("L", "R"), root="root_pelvis", spine="spine_{i2}",
        neck="neck_{i2}", head="head", tail="tail_{i2}", girdle_h=None,
        upper_h="{S}_Bk_UpLeg", lower_h="{S}_Bk_Leg", foot_h="{S}_Bk_Foot",
        toe_h="{S}_Bk_Toe", girdle_f=None, upper_f="{S}_Fr_UpLeg",
        lower_f="{S}_Fr_Leg", hand_f="{S}_Fr_Foot", toe_f="{S}_Fr_Toe",
        jaw="jaw"),
}


def _name(style: str, key: str, index: int = 0, side: int = 0) -> Optional[str]:
    """The joint name for :obj:`key` in :obj:`style` (``None``: no joint)."""
    template = STYLES[style].get(key)
    if template is None:
        return None
    if isinstance(template, tuple):
        template = template[index]
    words = STYLES[style]["sides"]
    return str(template).format(
        S=words[side], s=words[side][0], i=index + 1,
        i0="" if index == 0 else index, i2=f"{index + 1:02d}",
        i3=f"{index + 1:03d}")


# -------------------------------------------------------------- the rigs
@dataclass
class Leg:
    r"""One leg driven by two-bone IK.

    Args:
        key (str): Gait key, e.g. ``"L"``, ``"RF"`` (right front), ``"L2"``.
        upper (int): Joint at the hip / shoulder (rotates the upper bone).
        lower (int): Joint at the knee / elbow.
        foot (int): Joint at the ankle / wrist (kept level, facing forward).
        pole (np.ndarray): Direction the knee points to, in the rest frame.
        tips (list[int]): Leaves below :obj:`foot` (they touch the ground).
    """

    key: str
    upper: int
    lower: int
    foot: int
    pole: np.ndarray
    tips: List[int] = field(default_factory=list)


@dataclass
class Sway:
    r"""Local rotation of one joint: ``static + amplitude * sin(2 pi (k u +
    phase))`` as ``Rx @ Ry @ Rz`` angles, ``u`` the gait (or idle) phase."""

    static: np.ndarray
    amplitude: np.ndarray
    k: float = 1.0
    phase: float = 0.0


@dataclass
class ZooRig:
    r"""A zoo skeleton with what its motion generator needs.

    Args:
        name (str): Skeleton id, e.g. ``"zoo_quadruped_frontleg"``.
        species (str): One of :data:`SPECIES`.
        skeleton (Skeleton): The skeleton, metres, +Y up, facing +Z.
        legs (list[Leg]): IK legs (empty for snakes).
        sway (dict): Joint index -> :class:`Sway` for the other joints.
        leg_length (float): Typical leg (or body) length in metres.
        arms (list[int]): Upper-arm joints that can reach (left first).
        stance (float): How far the legs stretch when the body stands: the
            hip-to-ankle distance over the leg's two bones (``0.95``, the
            default, bends a knee of equal bones by 36 degrees; a standing
            human's 5-15 degrees is 0.99-0.999); walking may stretch them
            a little further (:func:`stance_of_bend`).
    """

    name: str
    species: str
    skeleton: Skeleton
    legs: List[Leg] = field(default_factory=list)
    sway: Dict[int, Sway] = field(default_factory=dict)
    leg_length: float = 1.0
    arms: List[int] = field(default_factory=list)
    stance: float = 0.95


def stance_of_bend(degrees: float) -> float:
    r"""The :attr:`ZooRig.stance` at which a leg of two equal bones bends
    its knee by :obj:`degrees` (0: straight)."""
    return float(np.cos(np.radians(degrees) / 2.0))


class _Builder:
    """Accumulates joints (parents first) and records their sway."""

    def __init__(self, style: str, order: str, rng: np.random.Generator) -> None:
        self.style, self.order, self.rng = style, order, rng
        self.names: List[str] = []
        self.parents: List[int] = []
        self.offsets: List[np.ndarray] = []
        self.ends: List[bool] = []
        self.sway: Dict[int, Sway] = {}
        self.legs: List[Leg] = []
        self.arms: List[int] = []

    def add(self, name: str, parent: int, offset: Sequence[float],
            end: bool = False) -> int:
        self.names.append(name)
        self.parents.append(parent)
        self.offsets.append(np.asarray(offset, dtype=np.float64))
        self.ends.append(end)
        return len(self.names) - 1

    def key(self, key: str, parent: int, offset: Sequence[float],
            index: int = 0, side: int = 0) -> int:
        """Add the joint named by :obj:`key` in the style (skipped, returning
        :obj:`parent`, when the style has no such joint)."""
        name = _name(self.style, key, index, side)
        return parent if name is None else self.add(name, parent, offset)

    def end(self, parent: int, offset: Sequence[float]) -> int:
        return self.add(f"{self.names[parent]}_end", parent, offset, end=True)

    def swing(self, j: int, static=(0.0, 0.0, 0.0), amplitude=(0.0, 0.0, 0.0),
              k: float = 1.0, phase: float = 0.0) -> None:
        self.sway[j] = Sway(np.radians(static), np.radians(amplitude), k, phase)

    def jitter(self, value: float, spread: float = 0.1) -> float:
        return float(value * self.rng.uniform(1.0 - spread, 1.0 + spread))

    def skeleton(self) -> Skeleton:
        rot = tuple(f"{a}rotation" for a in self.order)
        channels = [() if e else (_POS + rot if p < 0 else rot)
                    for p, e in zip(self.parents, self.ends)]
        return Skeleton(names=list(self.names), parents=np.array(self.parents),
                        offsets=np.stack(self.offsets), channels=channels,
                        end_site=np.array(self.ends))

    def depth_first(self) -> None:
        """Reorder the joints as a BVH file lists them (depth first), so
        that a written and re-read skeleton has the same joint order."""
        children: List[List[int]] = [[] for _ in self.names]
        for j, p in enumerate(self.parents[1:], start=1):
            children[p].append(j)
        order, stack = [], [0]
        while stack:
            j = stack.pop()
            order.append(j)
            stack.extend(reversed(children[j]))
        new = {old: i for i, old in enumerate(order)}
        self.names = [self.names[j] for j in order]
        self.parents = [-1 if j == 0 else new[self.parents[j]] for j in order]
        self.offsets = [self.offsets[j] for j in order]
        self.ends = [self.ends[j] for j in order]
        self.sway = {new[j]: s for j, s in self.sway.items()}
        for leg in self.legs:
            leg.upper, leg.lower, leg.foot = (new[leg.upper], new[leg.lower],
                                              new[leg.foot])
        self.arms = [new[j] for j in self.arms]

    def rig(self, name: str, species: str, leg_length: float) -> ZooRig:
        self.depth_first()
        skel = self.skeleton()
        for leg in self.legs:
            leg.tips = [j for j in range(skel.num_joints)
                        if skel.is_leaf[j] and _is_below(skel, j, leg.foot)]
        return ZooRig(name, species, skel, self.legs, self.sway, leg_length, self.arms)


def _is_below(skel: Skeleton, j: int, ancestor: int) -> bool:
    while j >= 0:
        if j == ancestor:
            return True
        j = int(skel.parents[j])
    return False


def _chain(b: _Builder, key: str, parent: int, count: int,
           step: Sequence[float]) -> List[int]:
    """``count`` joints named by :obj:`key`, each :obj:`step` from the last."""
    out = []
    for i in range(count):
        parent = b.key(key, parent, step, index=i)
        out.append(parent)
    return out


def _leg(b: _Builder, parent: int, side: int, lengths: Sequence[float],
         attach: Sequence[float], front: bool, key: str,
         pole: Sequence[float], girdle: Sequence[float] = (0.0, 0.0, 0.0),
         foot: Sequence[float] = (0.0, -0.3, 1.0)) -> None:
    """A leg: [girdle], upper, lower, foot, [toe], tip. ``lengths`` are the
    upper, lower and foot segment lengths; ``foot`` the direction of the
    foot segment."""
    sx = 1.0 if side == 0 else -1.0
    tag = "f" if front else "h"
    g = b.key(f"girdle_{tag}", parent, np.array(attach) * [sx, 1, 1], side=side)
    hip = (np.array(girdle) * [sx, 1, 1] if g != parent
           else np.array(attach) * [sx, 1, 1])
    up = b.key("upper_f" if front else "upper_h", g, hip, side=side)
    lo = b.key("lower_f" if front else "lower_h", up, (0, -lengths[0], 0.01), side=side)
    ft = b.key("hand_f" if front else "foot_h", lo, (0, -lengths[1], -0.01), side=side)
    seg = lengths[2] * _unit(np.array(foot, dtype=np.float64))
    toe_key = "toe_f" if front else "toe_h"
    toe = b.key(toe_key, ft, seg, side=side)
    if toe == ft:
        b.end(ft, seg)
    else:
        b.end(toe, (0.0, 0.0, 0.4 * lengths[2]))
    b.legs.append(Leg(key, up, lo, ft, np.asarray(pole, dtype=np.float64)))

