r"""A procedural zoo: skeletons of several body plans and physically sensible
motions for them, written as BVH files with a manifest (no data needed).

Body plans (:data:`SPECIES`): ``biped`` (humans), ``quadruped`` (with and
without tail), ``bird`` (two legs, two wings), ``hexapod`` (insects) and
``snake`` (one long chain). Each has several skeleton variants
(:data:`VARIANTS`) that differ in proportions, joint counts, rotation orders
and naming conventions (``LeftUpLeg`` / ``thigh.L`` / ``l_hip``), all chosen
so that :func:`satagraph.data.semantics.describe_joints` reads them well.

Legged motions are built from a gait: per-leg phases and a duty factor give
stance and swing intervals; a stance foot stays planted where it landed
(height 0, zero velocity), a swing foot travels on an arc to the next
landing spot beside the moving body; two-bone IK with a knee pole poses the
legs, and the body height is lowered wherever a planted foot would be out
of reach. Clip kinds (:data:`CLIP_KINDS`): ``walk``, ``turn``, ``speed``
(speed change), ``idle`` and ``trot`` (quadrupeds). Snakes slither: every
joint follows the path of the head.

Example::

    from satagraph.data.zoo import write_zoo
    rows = write_zoo("zoo", species=["quadruped", "snake"], clips=3, seed=1)
"""
from __future__ import annotations

import csv
import hashlib
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from satagraph.io import write_bvh
from satagraph.io.files import atomic_write
from satagraph.motion import Motion
from satagraph.skeleton import Skeleton

PathLike = Union[str, "os.PathLike[str]"]

SPECIES = ("biped", "quadruped", "bird", "hexapod", "snake")
CLIP_KINDS = {
    "biped": ("walk", "turn", "speed", "idle"),
    "quadruped": ("walk", "trot", "turn", "speed", "idle"),
    "bird": ("walk", "turn", "speed", "idle"),
    "hexapod": ("walk", "turn", "speed", "idle"),
    "snake": ("walk", "turn", "speed", "idle"),
}
MANIFEST_COLUMNS = ("path", "dataset", "skeleton", "species", "split", "fps",
                    "frames", "joints", "licence", "sha1")
LICENCE = "CC0 1.0"
_POS = ("Xposition", "Yposition", "Zposition")


# ------------------------------------------------------------------ math
def _rot(axis: int, angle: np.ndarray) -> np.ndarray:
    """Rotations about coordinate axis :obj:`axis` (0, 1, 2), :math:`(*, 3, 3)`."""
    angle = np.asarray(angle, dtype=np.float64)
    out = np.zeros(angle.shape + (3, 3))
    a, b = (axis + 1) % 3, (axis + 2) % 3
    c, s = np.cos(angle), np.sin(angle)
    out[..., axis, axis] = 1.0
    out[..., a, a], out[..., a, b] = c, -s
    out[..., b, a], out[..., b, b] = s, c
    return out


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
    """

    name: str
    species: str
    skeleton: Skeleton
    legs: List[Leg] = field(default_factory=list)
    sway: Dict[int, Sway] = field(default_factory=dict)
    leg_length: float = 1.0


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

    def rig(self, name: str, species: str, leg_length: float) -> ZooRig:
        self.depth_first()
        skel = self.skeleton()
        for leg in self.legs:
            leg.tips = [j for j in range(skel.num_joints)
                        if skel.is_leaf[j] and _is_below(skel, j, leg.foot)]
        return ZooRig(name, species, skel, self.legs, self.sway, leg_length)


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


# ---------------------------------------------------------------- biped
def _biped(style: str, rng: np.random.Generator, name: str) -> ZooRig:
    b = _Builder(style, rng.choice(["ZXY", "ZYX", "XYZ"]), rng)
    h = rng.uniform(1.5, 1.95)
    thigh, shin, width = b.jitter(0.245 * h), b.jitter(0.245 * h), b.jitter(0.055 * h)
    ankle = 0.045 * h
    root = b.add(_name(style, "root"), -1, (0, 0, 0))
    b.swing(root, amplitude=(2, 4, 3), k=1.0)
    nspine = len(STYLES[style]["spine"]) if style == "cmu" else int(rng.integers(2, 4))
    spine = _chain(b, "spine", root, nspine, (0, b.jitter(0.3 * h) / nspine, 0))
    for i, j in enumerate(spine):
        b.swing(j, static=(2, 0, 0), amplitude=(1, -3, -1), k=1.0, phase=0.02 * i)
    nneck = int(rng.integers(1, 3))
    neck = _chain(b, "neck", spine[-1], nneck, (0, 0.06 * h / nneck, 0.01))
    head = b.key("head", neck[-1], (0, 0.05 * h, 0.01))
    b.swing(head, amplitude=(1.5, 3, 0), k=2.0)
    b.end(head, (0, 0.1 * h, 0.02))
    tpose = style in ("mixamo", "cmu")
    for side in (0, 1):
        sx = 1.0 if side == 0 else -1.0
        _leg(b, root, side, (thigh, shin, ankle * 2.4), (width, -0.05 * h, 0),
             False, "LR"[side], (0, 0, 1), girdle=(0.3 * width, -0.03 * h, 0),
             foot=(0, -ankle, 0.1 * h))
        _arm(b, spine[-1], side, sx, h, tpose)
    return b.rig(name, "biped", thigh + shin)


def _arm(b: _Builder, parent: int, side: int, sx: float, h: float,
         tpose: bool) -> None:
    """Clavicle, upper arm, forearm, hand and tip, hanging and swinging."""
    down = 0.0 if tpose else 40.0
    direction = np.array([sx * np.cos(np.radians(down)), -np.sin(np.radians(down)), 0])
    c = b.key("girdle_f", parent, (sx * 0.02 * h, 0.05 * h, 0), side=side)
    u = b.key("upper_f", c, (sx * 0.09 * h, 0, 0), side=side)
    f = b.key("lower_f", u, direction * b.jitter(0.17 * h), side=side)
    hd = b.key("hand_f", f, direction * b.jitter(0.15 * h), side=side)
    b.end(hd, direction * 0.1 * h)
    hang = -sx * (82.0 - down)
    b.swing(u, static=(0, 0, hang), amplitude=(-22, 0, 0), k=1.0,
            phase=0.5 * side - 0.19)
    b.swing(f, static=(0, -sx * 20, 0), amplitude=(0, -sx * 10, 0), k=1.0,
            phase=0.5 * side - 0.19)


# ------------------------------------------------------------ quadruped
def _quadruped(style: str, rng: np.random.Generator, name: str,
               tail: bool) -> ZooRig:
    b = _Builder(style, rng.choice(["ZXY", "XYZ", "YXZ"]), rng)
    size = rng.uniform(0.35, 1.4)  # leg length scale (m)
    thigh, shin, hock = (b.jitter(0.38 * size), b.jitter(0.4 * size),
                         b.jitter(0.25 * size))
    arm, fore, paw = b.jitter(0.4 * size), b.jitter(0.42 * size), b.jitter(0.15 * size)
    body = b.jitter(1.1 * size, 0.2)
    width = 0.12 * size
    root = b.add(_name(style, "root"), -1, (0, 0, 0))
    b.swing(root, amplitude=(1, 3, 2), k=1.0)
    nspine = int(rng.integers(2, 5))
    spine = _chain(b, "spine", root, nspine, (0, 0.02 * size, body / nspine))
    for i, j in enumerate(spine):
        b.swing(j, amplitude=(0.5, -2, -1), k=1.0, phase=0.05 * i)
    nneck = int(rng.integers(1, 4))
    neck = _chain(b, "neck", spine[-1], nneck, (0, 0.3 * size / nneck, 0.15 * size / nneck))
    for j in neck:
        b.swing(j, static=(8 / nneck, 0, 0), amplitude=(2, 3, 0), k=2.0)
    head = b.key("head", neck[-1], (0, 0.08 * size, 0.06 * size))
    b.swing(head, static=(25, 0, 0), amplitude=(3, 0, 0), k=2.0, phase=0.1)
    b.end(head, (0, -0.05 * size, 0.3 * size))
    if rng.random() < 0.5:
        jaw = b.key("jaw", head, (0, -0.04 * size, 0.05 * size))
        b.end(jaw, (0, -0.02 * size, 0.2 * size))
    if tail:
        ntail = int(rng.integers(2, 7))
        joints = _chain(b, "tail", root, ntail, (0, 0.02 * size, -0.7 * size / ntail))
        for i, j in enumerate(joints):
            b.swing(j, static=(-6, 0, 0), amplitude=(2, 6 + 3 * i, 0), k=1.0,
                    phase=-0.08 * i)
        b.end(joints[-1], (0, 0, -0.1 * size))
    for side in (0, 1):
        s = "LR"[side]
        _leg(b, root, side, (thigh, shin, hock), (width, -0.05 * size, -0.05 * size),
             False, s + "H", (0, 0, 1), girdle=(0.3 * width, -0.05 * size, 0),
             foot=(0, -1, 0.08))
        _leg(b, spine[-1], side, (arm, fore, paw), (width, -0.08 * size, 0.05 * size),
             True, s + "F", (0, 0, -1), girdle=(0.2 * width, -0.12 * size, 0),
             foot=(0, -1, 0.25))
    return b.rig(name, "quadruped", thigh + shin)


# ----------------------------------------------------------------- bird
def _bird(style: str, rng: np.random.Generator, name: str) -> ZooRig:
    b = _Builder(style, rng.choice(["ZXY", "YXZ"]), rng)
    size = rng.uniform(0.15, 0.8)
    thigh, shin, tarsus = b.jitter(0.3 * size), b.jitter(0.45 * size), b.jitter(0.35 * size)
    root = b.add(_name(style, "root"), -1, (0, 0, 0))
    b.swing(root, static=(-10, 0, 0), amplitude=(2, 4, 3), k=1.0)
    nspine = int(rng.integers(1, 3))
    spine = _chain(b, "spine", root, nspine, (0, 0.08 * size / nspine, 0.25 * size / nspine))
    nneck = int(rng.integers(2, 6))
    neck = _chain(b, "neck", spine[-1], nneck, (0, 0.3 * size / nneck, 0.05 * size / nneck))
    for i, j in enumerate(neck):
        b.swing(j, amplitude=(6, 2, 0), k=1.0, phase=0.05 * i)
    head = b.key("head", neck[-1], (0, 0.05 * size, 0.02 * size))
    b.swing(head, static=(10, 0, 0), amplitude=(-8, 0, 0), k=1.0)
    b.end(head, (0, 0, 0.12 * size))
    ntail = int(rng.integers(1, 3))
    tail = _chain(b, "tail", root, ntail, (0, 0.03 * size, -0.2 * size / ntail))
    for j in tail:
        b.swing(j, amplitude=(3, 5, 0), k=1.0)
    b.end(tail[-1], (0, 0.02 * size, -0.15 * size))
    for side in (0, 1):
        sx = 1.0 if side == 0 else -1.0
        _leg(b, root, side, (thigh, shin, tarsus), (0.08 * size, -0.05 * size, 0.02 * size),
             False, "LR"[side], (0, 0, 1), girdle=(0.02 * size, -0.02 * size, 0),
             foot=(0, -1, 0.15))
        _wing(b, spine[-1], side, sx, size)
    return b.rig(name, "bird", thigh + shin)


def _wing(b: _Builder, parent: int, side: int, sx: float, size: float) -> None:
    """A wing as an arm (humerus, forearm, hand), folded and flapping."""
    prefix = _name(b.style, "wing_prefix", side=side)
    keys = ("girdle_f", "upper_f", "lower_f", "hand_f")
    lengths = (0.06, 0.25, 0.3, 0.3)
    j = parent
    joints = []
    for key, length in zip(keys, lengths):
        name = _name(b.style, key, side=side)
        if prefix is not None:  # "LeftWingArm" instead of "LeftArm"
            name = prefix + name[len(STYLES[b.style]["sides"][side]):]
        j = b.add(name, j, (sx * b.jitter(length * size), 0.02 * size if j == parent else 0, 0))
        joints.append(j)
    b.end(j, (sx * 0.25 * size, 0, 0))
    b.swing(joints[1], static=(0, sx * 70, -sx * 15), amplitude=(0, 0, sx * 4), k=2.0)
    b.swing(joints[2], static=(0, -sx * 150, 0), amplitude=(0, 0, 0))
    b.swing(joints[3], static=(0, sx * 140, 0), amplitude=(0, 0, 0))


# -------------------------------------------------------------- hexapod
def _hexapod(style: str, rng: np.random.Generator, name: str) -> ZooRig:
    b = _Builder(style, rng.choice(["ZXY", "XYZ"]), rng)
    size = rng.uniform(0.02, 0.3)
    femur, tibia, tarsus = b.jitter(0.5 * size), b.jitter(0.6 * size), b.jitter(0.3 * size)
    root = b.add(_name(style, "root"), -1, (0, 0, 0))
    b.swing(root, amplitude=(1, 2, 1), k=2.0)
    front = b.key("spine", root, (0, 0.02 * size, 0.35 * size), index=0)
    head = b.key("head", front, (0, 0.02 * size, 0.25 * size))
    b.swing(head, amplitude=(3, 4, 0), k=1.0)
    b.end(head, (0, 0, 0.2 * size))
    for side in (0, 1):
        sx = 1.0 if side == 0 else -1.0
        ant = b.add(_name(style, "antenna", side=side), head,
                    (sx * 0.05 * size, 0.08 * size, 0.1 * size))
        b.swing(ant, amplitude=(10, 10, 0), k=1.0, phase=0.3 * side)
        b.end(ant, (sx * 0.15 * size, 0.1 * size, 0.4 * size))
    nabd = int(rng.integers(2, 5))
    abd = _chain(b, "tail", root, nabd, (0, 0.0, -0.7 * size / nabd))
    for j in abd:
        b.swing(j, amplitude=(2, 2, 0), k=1.0)
    b.end(abd[-1], (0, 0, -0.1 * size))
    for side in (0, 1):
        for pair, (parent, z, yaw) in enumerate(((front, 0.05, 35), (root, 0, 0),
                                                 (root, -0.15, -35))):
            _insect_leg(b, parent, side, pair, z * size, yaw, (femur, tibia, tarsus))
    return b.rig(name, "hexapod", femur + tibia)


def _insect_leg(b: _Builder, parent: int, side: int, pair: int, z: float,
                yaw: float, lengths: Sequence[float]) -> None:
    """Coxa, femur (up and out), tibia (down and out), tarsus, tip."""
    sx = 1.0 if side == 0 else -1.0
    turn = _rot(1, np.radians(sx * yaw))

    def out(x: float, y: float) -> np.ndarray:
        return turn @ np.array([sx * x, y, 0.0])

    names = [_name(b.style, k, pair, side) for k in ("coxa", "femur", "tibia", "tarsus")]
    coxa = b.add(names[0], parent, (sx * 0.06 * lengths[0], -0.02 * lengths[0], z))
    fem = b.add(names[1], coxa, out(0.25 * lengths[0], 0.0))
    tib = b.add(names[2], fem, lengths[0] * out(0.75, 0.66))
    tar = b.add(names[3], tib, lengths[1] * out(0.35, -0.94))
    b.end(tar, lengths[2] * out(0.7, -0.7))
    b.legs.append(Leg("LR"[side] + str(pair + 1), fem, tib, tar,
                      np.array([0.0, 1.0, 0.0])))


# Insect leg and antenna names (per style): front / middle / hind pairs.
STYLES["insect"] = dict(
    sides=("Left", "Right"), root="Thorax", spine=("ThoraxFront",), head="Head",
    tail="Abdomen{i2}", antenna="{S}Antenna",
    coxa=("{S}FrontCoxaHipJoint", "{S}CenterCoxaHipJoint",
          "{S}HindCoxaHipJoint"),
    femur=("{S}FrontFemur", "{S}CenterFemur", "{S}HindFemur"),
    tibia=("{S}FrontTibia", "{S}CenterTibia", "{S}HindTibia"),
    tarsus=("{S}FrontTarsus", "{S}CenterTarsus", "{S}HindTarsus"))
STYLES["insect_snake"] = dict(
    sides=("l", "r"), root="thorax", spine=("thorax_front",), head="head",
    tail="abdomen_{i}", antenna="antenna_{S}",
    coxa=("coxa_hip_joint_front_{S}", "coxa_hip_joint_mid_{S}",
          "coxa_hip_joint_rear_{S}"),
    femur=("femur_front_{S}", "femur_mid_{S}", "femur_rear_{S}"),
    tibia=("tibia_front_{S}", "tibia_mid_{S}", "tibia_rear_{S}"),
    tarsus=("tarsus_front_{S}", "tarsus_mid_{S}", "tarsus_rear_{S}"))


# ---------------------------------------------------------------- snake
def _snake(style: str, rng: np.random.Generator, name: str) -> ZooRig:
    b = _Builder(style, rng.choice(["ZXY", "ZYX"]), rng)
    length = rng.uniform(0.8, 3.0)
    nbody = int(rng.integers(8, 21))
    ntail = int(rng.integers(3, 8))
    step = 0.7 * length / (nbody + 1)
    root = b.add(_name(style, "root"), -1, (0, 0, 0))
    body = _chain(b, "spine", root, nbody, (0, 0, step))
    neck = b.key("neck", body[-1], (0, 0, step))
    head = b.key("head", neck, (0, 0, step))
    b.end(head, (0, 0, 0.6 * step))
    if rng.random() < 0.5:
        jaw = b.key("jaw", head, (0, -0.2 * step, 0.1 * step))
        b.end(jaw, (0, 0, 0.5 * step))
    tail = _chain(b, "tail", root, ntail, (0, 0, -0.3 * length / ntail))
    b.end(tail[-1], (0, 0, -0.3 * length / ntail))
    return b.rig(name, "snake", length)


STYLES["snake"] = dict(sides=("L", "R"), root="Pelvis", spine="Spine{i2}",
                       neck="Neck", head="Head", tail="Tail{i2}", jaw="Jaw")
STYLES["snake_blender"] = dict(sides=("L", "R"), root="root", spine="spine.{i3}",
                               neck="neck", head="head", tail="tail.{i3}",
                               jaw="jaw")
STYLES["snake_vertebra"] = dict(sides=("L", "R"), root="cloaca_root",
                                spine="vertebra_{i2}", neck="neck_01",
                                head="skull", tail="tail_{i2}", jaw="mandible")

#: Skeleton variants per species: (style, options).
VARIANTS: Dict[str, Tuple[Tuple[str, dict], ...]] = {
    "biped": (("mixamo", {}), ("blender", {}), ("smpl", {}), ("cmu", {})),
    "quadruped": (("frontleg", {"tail": True}), ("abbrev", {"tail": False}),
                  ("blender", {"tail": True}), ("mixamo", {"tail": False})),
    "bird": (("mixamo", {}), ("blender", {}), ("smpl", {})),
    "hexapod": (("insect", {}), ("insect_snake", {})),
    "snake": (("snake", {}), ("snake_blender", {}), ("snake_vertebra", {})),
}
_BUILDERS = {"biped": _biped, "quadruped": _quadruped, "bird": _bird,
             "hexapod": _hexapod, "snake": _snake}


def zoo_rigs(species: Optional[Sequence[str]] = None, seed: int = 0) -> List[ZooRig]:
    r"""The zoo's skeletons: every variant of every requested species.

    Proportions are drawn from a generator seeded by ``(seed, species,
    variant)``, so a subset of species gives the same skeletons as the full
    zoo.

    Args:
        species (list[str], optional): Species from :data:`SPECIES`
            (default: all).
        seed (int): Random seed.
    """
    out = []
    for name in _check_species(species):
        s = SPECIES.index(name)
        for v, (style, options) in enumerate(VARIANTS[name]):
            rng = np.random.default_rng([seed, s, v])
            tag = "" if "tail" not in options else (
                "-tail" if options["tail"] else "-notail")
            rig_name = f"zoo{seed}-{name}-{style}{tag}"
            out.append(_BUILDERS[name](style, rng, rig_name, **options))
    return out


def _check_species(species: Optional[Sequence[str]]) -> List[str]:
    species = list(SPECIES if species is None else species)
    unknown = [s for s in species if s not in SPECIES]
    if unknown:
        raise ValueError(f"unknown species {unknown}: choose from {list(SPECIES)}")
    return species


# ----------------------------------------------------------------- gaits
#: Gaits: leg phases, duty factor, stride (leg lengths), speed (leg lengths
#: per second), swing height (leg lengths).
GAITS: Dict[str, Tuple[Dict[str, float], float, float, float, float]] = {
    "biped": ({"L": 0.0, "R": 0.5}, 0.62, 1.25, 1.5, 0.1),
    "bird": ({"L": 0.0, "R": 0.5}, 0.6, 1.1, 1.3, 0.15),
    "quadruped": ({"LH": 0.0, "LF": 0.25, "RH": 0.5, "RF": 0.75}, 0.7, 1.1, 1.0, 0.12),
    "trot": ({"LH": 0.0, "RF": 0.0, "RH": 0.5, "LF": 0.5}, 0.55, 1.3, 2.4, 0.15),
    "hexapod": ({"L1": 0.0, "R2": 0.0, "L3": 0.0, "R1": 0.5, "L2": 0.5,
                 "R3": 0.5}, 0.55, 0.8, 1.5, 0.2),
    "snake": ({}, 1.0, 1.0, 0.25, 0.0),
}
_IDLE_HZ = 0.3
_PAD_SECONDS = 3.0


@dataclass
class _Clip:
    """Speed and yaw rate over an extended frame grid (``pad`` frames on
    either side of the clip), and the resulting root path."""

    fps: float
    pad: int
    speed: np.ndarray
    yaw_rate: np.ndarray
    heading: Optional[np.ndarray] = None
    position: Optional[np.ndarray] = None

    @property
    def time(self) -> np.ndarray:
        return (np.arange(len(self.speed)) - self.pad) / self.fps


def _profile(kind: str, frames: int, fps: float, speed: float,
             rng: np.random.Generator) -> _Clip:
    """Speed and yaw-rate profiles of one clip kind."""
    pad = int(_PAD_SECONDS * fps)
    t = (np.arange(frames + 2 * pad) - pad) / fps
    mid = 0.5 * frames / fps
    ramp = _smoothstep((t - mid + 0.75) / 1.5)
    v = speed * rng.uniform(0.85, 1.15) * np.ones_like(t)
    yaw = np.radians(rng.uniform(-4, 4)) * np.ones_like(t)
    if kind == "idle":
        v[:], yaw[:] = 0.0, 0.0
    elif kind == "turn":
        rate = np.radians(rng.uniform(35, 70)) * rng.choice([-1.0, 1.0])
        yaw = rate * _smoothstep((t - 0.3 * mid) / 0.8)
        v *= 0.85
    elif kind == "speed":
        lo, hi = speed * rng.uniform(0.5, 0.65), speed * rng.uniform(1.15, 1.3)
        a, b = (lo, hi) if rng.random() < 0.5 else (hi, lo)
        v = a + (b - a) * ramp
    return _Clip(fps, pad, v, yaw)


# ------------------------------------------------------------ feet, IK
@dataclass
class _Feet:
    """Ankle targets and foot yaw per leg over the extended grid."""

    targets: np.ndarray  # (legs, N, 3)
    yaw: np.ndarray  # (legs, N)


def _leg_geometry(rig: ZooRig, leg: Leg) -> Tuple[np.ndarray, float, float, float]:
    """Neutral foot position (rest, relative to the root), ankle height
    above the ground, upper and lower bone lengths."""
    rest = rig.skeleton.rest_positions()
    below = [j for j in range(rig.skeleton.num_joints)
             if _is_below(rig.skeleton, j, leg.foot)]
    ankle = float(rest[leg.foot, 1] - rest[below, 1].min())
    off = rig.skeleton.offsets
    return (rest[leg.foot], ankle, float(np.linalg.norm(off[leg.lower])),
            float(np.linalg.norm(off[leg.foot])))


def _plan_feet(rig: ZooRig, clip: _Clip, phase: np.ndarray, gait: tuple,
               idle: bool) -> _Feet:
    """Planted / swinging ankle targets for every leg."""
    offsets, duty, _, _, lift = gait
    index = np.arange(len(phase), dtype=np.float64)
    targets, yaws = [], []
    for leg in rig.legs:
        neutral, ankle, l1, l2 = _leg_geometry(rig, leg)
        lift_h = lift * (l1 + l2)

        def plant(tau: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
            psi = np.interp(tau, index, clip.heading)
            root = np.stack([np.interp(tau, index, clip.position[:, k])
                             for k in range(3)], axis=-1)
            c, s = np.cos(psi), np.sin(psi)
            x = root[..., 0] + c * neutral[0] + s * neutral[2]
            z = root[..., 2] - s * neutral[0] + c * neutral[2]
            return np.stack([x, np.full_like(x, ankle), z], axis=-1), psi

        if idle:
            pos, psi = plant(np.full(len(phase), float(clip.pad)))
            targets.append(pos)
            yaws.append(psi)
            continue
        u = phase + offsets[leg.key]
        n = np.floor(u)
        f = u - n
        start = np.interp(n + duty / 2 - offsets[leg.key], phase, index)
        stop = np.interp(n + 1 + duty / 2 - offsets[leg.key], phase, index)
        (p0, y0), (p1, y1) = plant(start), plant(stop)
        s = np.clip((f - duty) / (1.0 - duty), 0.0, 1.0)
        w = _smoothstep(s)[:, None]
        pos = (1 - w) * p0 + w * p1
        pos[:, 1] += lift_h * np.sin(np.pi * s)
        targets.append(pos)
        yaws.append((1 - w[:, 0]) * y0 + w[:, 0] * y1)
    return _Feet(np.array(targets), np.array(yaws))


def _two_bone(hip: np.ndarray, target: np.ndarray, l1: float, l2: float,
              pole: np.ndarray) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Knee position, upper and lower bone directions reaching ``target``
    (clamped to the reachable range), the knee bent towards ``pole``.

    Shapes:
        - **hip**, **target**, **pole**: :math:`(T, 3)`
        - **output**: three :math:`(T, 3)` arrays
    """
    e = target - hip
    dist = np.clip(np.linalg.norm(e, axis=-1), abs(l1 - l2) + 1e-6,
                   (l1 + l2) * (1 - 1e-6))
    e = _unit(e)
    side = _unit(pole - np.sum(pole * e, axis=-1, keepdims=True) * e)
    x = (l1 ** 2 - l2 ** 2 + dist ** 2) / (2 * dist)
    y = np.sqrt(np.maximum(l1 ** 2 - x ** 2, 0.0))
    knee = hip + x[:, None] * e + y[:, None] * side
    end = hip + dist[:, None] * e
    return knee, _unit(knee - hip), _unit(end - knee)


def _sway_rotation(sway: Optional[Sway], phase: np.ndarray) -> np.ndarray:
    """Local rotations :math:`(T, 3, 3)` of a joint's sway."""
    if sway is None:
        return np.broadcast_to(np.eye(3), (len(phase), 3, 3))
    wave = np.sin(2 * np.pi * (sway.k * phase + sway.phase))[:, None]
    return _euler(sway.static[None] + sway.amplitude[None] * wave)


def _pose(rig: ZooRig, root_pos: np.ndarray, root_rot: np.ndarray,
          phase: np.ndarray, heading: np.ndarray,
          feet: Optional[_Feet] = None) -> Tuple[np.ndarray, np.ndarray]:
    """Global rotations and positions by forward kinematics, legs by IK
    when :obj:`feet` is given."""
    skel = rig.skeleton
    frames, num = len(phase), skel.num_joints
    rot, pos = np.zeros((frames, num, 3, 3)), np.zeros((frames, num, 3))
    rot[:, 0], pos[:, 0] = root_rot, root_pos
    fixed: Dict[int, np.ndarray] = {}
    roles = {leg.upper: i for i, leg in enumerate(rig.legs)}
    for j in range(1, num):
        p = skel.parents[j]
        pos[:, j] = pos[:, p] + rot[:, p] @ skel.offsets[j]
        if feet is not None and j in roles:
            fixed.update(_solve_leg(rig, roles[j], pos[:, j], heading, feet))
        rot[:, j] = fixed[j] if j in fixed else rot[:, p] @ _sway_rotation(
            rig.sway.get(j), phase)
    return rot, pos


def _solve_leg(rig: ZooRig, i: int, hip: np.ndarray, heading: np.ndarray,
               feet: _Feet) -> Dict[int, np.ndarray]:
    """Global rotations of a leg's upper, lower and foot joints."""
    leg, off = rig.legs[i], rig.skeleton.offsets
    l1, l2 = np.linalg.norm(off[leg.lower]), np.linalg.norm(off[leg.foot])
    pole = _rot(1, heading) @ leg.pole
    _, d1, d2 = _two_bone(hip, feet.targets[i], l1, l2, pole)
    hinge_w = _unit(np.cross(d1, pole))
    u, lo = off[leg.lower] / l1, off[leg.foot] / l2
    hinge = _unit(np.cross(_unit(u + lo), leg.pole))
    return {leg.upper: _align(u, hinge, d1, hinge_w),
            leg.lower: _align(lo, hinge, d2, hinge_w),
            leg.foot: _rot(1, feet.yaw[i])}


def _body_height(rig: ZooRig, clip: _Clip, root_rot: np.ndarray,
                 phase: np.ndarray, feet: _Feet, reach: float = 0.97,
                 crouch: float = 0.95) -> np.ndarray:
    """Root height per frame: the rest stance (legs at most ``crouch``
    extended), lowered wherever a leg would need more than ``reach`` of its
    length to touch its target."""
    rest = rig.skeleton.rest_positions()
    flat = clip.position * np.array([1.0, 0.0, 1.0])
    _, pos = _pose(rig, flat, root_rot, phase, clip.heading)
    base = -rest[:, 1].min()
    bounds = []
    for i, leg in enumerate(rig.legs):
        _, ankle, l1, l2 = _leg_geometry(rig, leg)
        base = min(base, ankle + crouch * (l1 + l2) - rest[leg.upper, 1])
        d = pos[:, leg.upper] - feet.targets[i]
        flat2 = d[:, 0] ** 2 + d[:, 2] ** 2
        vertical = np.sqrt(np.maximum((reach * (l1 + l2)) ** 2 - flat2, 0.0))
        bounds.append(feet.targets[i][:, 1] - pos[:, leg.upper, 1] + vertical)
    height = np.minimum(base, np.min(bounds, axis=0)) if bounds else np.full(
        len(phase), base)
    return _smooth_min(height, int(round(0.1 * clip.fps)))


def _smooth_min(x: np.ndarray, width: int) -> np.ndarray:
    """A moving minimum followed by a moving average (stays at or below
    the original almost everywhere)."""
    if width < 1:
        return x
    padded = np.pad(x, width, mode="edge")
    windows = np.lib.stride_tricks.sliding_window_view(padded, 2 * width + 1)
    low = np.pad(windows.min(axis=1), width, mode="edge")
    kernel = np.ones(2 * width + 1) / (2 * width + 1)
    return np.convolve(low, kernel, mode="valid")


def _legged(rig: ZooRig, kind: str, frames: int, fps: float,
            rng: np.random.Generator) -> Tuple[np.ndarray, np.ndarray, int]:
    """Global rotations and positions of a legged clip (extended grid)."""
    gait = GAITS["trot" if kind == "trot" else rig.species]
    _, _, stride, speed, _ = gait
    length = rig.leg_length
    clip = _profile(kind, frames, fps, speed * length, rng)
    idle = kind == "idle"
    _trace(clip, rng.uniform(-np.pi, np.pi), idle, length, rng)
    if idle:
        freq = np.full_like(clip.speed, _IDLE_HZ)
    else:
        freq = np.sqrt(clip.speed * speed * length) / (stride * length)
    phase = np.cumsum(freq) / fps
    phase = phase - phase[clip.pad] + rng.uniform(0, 1)
    feet = _plan_feet(rig, clip, phase, gait, idle)
    root_rot = _rot(1, clip.heading) @ _sway_rotation(rig.sway.get(0), phase)
    height = _body_height(rig, clip, root_rot, phase, feet)
    root = clip.position * np.array([1.0, 0.0, 1.0])
    root[:, 1] = height
    if idle:
        root[:, 1] -= 0.01 * length * (1 + np.sin(2 * np.pi * phase))
    rot, pos = _pose(rig, root, root_rot, phase, clip.heading, feet)
    return rot, pos, clip.pad


def _trace(clip: _Clip, heading: float, idle: bool, length: float,
           rng: np.random.Generator) -> None:
    """The root's heading and ground path from the speed and yaw rate,
    starting at the origin with :obj:`heading`; idles sway sideways."""
    psi = np.cumsum(clip.yaw_rate) / clip.fps
    clip.heading = psi - psi[clip.pad] + heading
    fwd = np.stack([np.sin(clip.heading), np.zeros_like(clip.heading),
                    np.cos(clip.heading)], axis=1)
    pos = np.cumsum(clip.speed[:, None] * fwd, axis=0) / clip.fps
    clip.position = pos - pos[clip.pad]
    if idle:
        t = clip.time
        side = np.stack([np.cos(clip.heading), 0 * t, -np.sin(clip.heading)], 1)
        amp = 0.03 * length * rng.uniform(0.5, 1.0)
        clip.position += amp * np.sin(2 * np.pi * 0.25 * t)[:, None] * side


# ----------------------------------------------------------- snake motion
def _snake_path(length: float, kind: str, rng: np.random.Generator,
                extent: Tuple[float, float]) -> Tuple[np.ndarray, np.ndarray]:
    """Arc-length grid and points (x, z) of a serpentine path."""
    step = length / 400
    s = np.arange(extent[0] - length, extent[1] + length, step)
    wave = length * rng.uniform(0.4, 0.6)
    theta = np.radians(rng.uniform(25, 40)) * np.sin(2 * np.pi * s / wave)
    if kind == "turn":
        theta += rng.choice([-1.0, 1.0]) * s / (length * rng.uniform(1.0, 2.0))
    theta += rng.uniform(-np.pi, np.pi)
    xz = np.cumsum(np.stack([np.sin(theta), np.cos(theta)], 1), axis=0) * step
    return s, xz - xz[np.searchsorted(s, 0.0)]


def _slither(rig: ZooRig, kind: str, frames: int, fps: float,
             rng: np.random.Generator) -> Tuple[np.ndarray, np.ndarray, int]:
    """Global rotations and positions of a slithering snake."""
    skel, length = rig.skeleton, rig.leg_length
    clip = _profile(kind, frames, fps, GAITS["snake"][3] * length, rng)
    s_root = np.cumsum(clip.speed) / fps
    s_root = (s_root - s_root[clip.pad])[clip.pad:clip.pad + frames]
    z = skel.rest_positions()[:, 2]
    s, xz = _snake_path(length, kind, rng, (s_root.min() + z.min(), s_root.max() + z.max()))
    arc = s_root[:, None] + z[None]
    target = np.zeros((frames, skel.num_joints, 3))
    target[..., 0], target[..., 2] = np.interp(arc, s, xz[:, 0]), np.interp(arc, s, xz[:, 1])
    radius = 0.02 * length
    lift = np.clip((z - 0.55 * z.max()) / (0.45 * z.max()), 0, 1) ** 2
    target[..., 1] = radius + 0.08 * length * lift
    if kind == "idle":
        t = np.arange(frames) / fps
        sway = 0.05 * length * np.sin(2 * np.pi * _IDLE_HZ * t)[:, None] * lift
        target[..., 0] += sway
        target[..., 1] += 0.02 * length * lift * np.sin(np.pi * _IDLE_HZ * t)[:, None]
    return (*_follow(skel, target), 0)


def _follow(skel: Skeleton, target: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """Rotations pointing every joint's first child at its target (Y kept
    up), and the positions they give by forward kinematics."""
    frames, num = target.shape[:2]
    rot, pos = np.zeros((frames, num, 3, 3)), np.zeros((frames, num, 3))
    up = np.array([0.0, 1.0, 0.0])
    pos[:, 0] = target[:, 0]
    for j in range(num):
        p = skel.parents[j]
        if j:
            pos[:, j] = pos[:, p] + rot[:, p] @ skel.offsets[j]
        kids = skel.children[j]
        if not kids:
            rot[:, j] = rot[:, p]
            continue
        c = kids[0]
        rot[:, j] = _align(_unit(skel.offsets[c]), up, target[:, c] - target[:, j],
                           np.broadcast_to(up, (frames, 3)))
    return rot, pos


# -------------------------------------------------------------- clips
def generate_clip(rig: ZooRig, kind: str = "walk", frames: int = 120,
                  fps: float = 30.0, seed: int = 0) -> Motion:
    r"""A procedural motion of a zoo skeleton.

    Args:
        rig (ZooRig): A skeleton from :func:`zoo_rigs`.
        kind (str): One of ``CLIP_KINDS[rig.species]``.
        frames (int): Number of frames.
        fps (float): Frames per second.
        seed (int): Random seed (speed, turn rate, heading, phase).

    Returns:
        Motion: Local rotations and translations (metres, +Y up, ground at
        y = 0); no raw channels.
    """
    if kind not in CLIP_KINDS[rig.species]:
        raise ValueError(f"{rig.species} has no clip kind {kind!r}: choose "
                         f"from {list(CLIP_KINDS[rig.species])}")
    rng = np.random.default_rng(seed)
    make = _slither if rig.species == "snake" else _legged
    rot, pos, pad = make(rig, kind, frames, fps, rng)
    rot, pos = rot[pad:pad + frames], pos[pad:pad + frames]
    return _to_motion(rig, rot, pos, fps, kind)


def _to_motion(rig: ZooRig, rot: np.ndarray, pos: np.ndarray, fps: float,
               kind: str) -> Motion:
    """Local rotations from global ones; translations are the offsets and
    the root position."""
    skel = rig.skeleton
    parents = np.maximum(skel.parents, 0)
    local = np.swapaxes(rot[:, parents], -1, -2) @ rot
    local[:, 0] = rot[:, 0]
    local[:, skel.end_site] = np.eye(3)
    trans = np.broadcast_to(skel.offsets, pos.shape).copy()
    trans[:, 0] = pos[:, 0]
    return Motion(skel, local, trans, fps=fps,
                  source=f"<satagraph zoo {rig.name} {kind}>")


# ---------------------------------------------------------------- writing
def _split(rig_index: int, rig_count: int, clip: int, clips: int) -> str:
    """The last skeleton of a species with 3+ variants is held out for
    testing; the last clip of the others (3+ clips) is for validation."""
    if rig_count >= 3 and rig_index == rig_count - 1:
        return "test"
    return "val" if clips >= 3 and clip == clips - 1 else "train"


def write_zoo(out_dir: PathLike, species: Optional[Sequence[str]] = None,
              clips: int = 4, seed: int = 0, fps: float = 30.0,
              frames: int = 120) -> List[Dict[str, str]]:
    r"""Write the zoo as BVH files under ``out_dir/<species>/`` and a
    ``manifest.tsv`` (columns :data:`MANIFEST_COLUMNS`, the layout of the
    shared data manifest) in :obj:`out_dir`.

    Clip kinds cycle through ``CLIP_KINDS[species]``; every file has its own
    seed derived from :obj:`seed`, so the zoo is deterministic.

    Args:
        out_dir (str or PathLike): Output folder (created).
        species (list[str], optional): Species (default: all).
        clips (int): Clips per skeleton.
        seed (int): Random seed.
        fps (float): Frames per second.
        frames (int): Frames per clip.

    Returns:
        list[dict]: The manifest rows.
    """
    if clips < 1 or frames < 2:
        raise ValueError("write_zoo: clips must be >= 1 and frames >= 2")
    out = Path(out_dir)
    rigs = zoo_rigs(species, seed)
    counts = {r.species: sum(q.species == r.species for q in rigs) for r in rigs}
    seen: Dict[str, int] = {}
    rows = []
    for r, rig in enumerate(rigs):
        index = seen.setdefault(rig.species, 0)
        seen[rig.species] += 1
        for c in range(clips):
            rows.append(_write_clip(out, rig, c, seed, fps, frames,
                                    _split(index, counts[rig.species], c, clips),
                                    r))
    _write_manifest(out / "manifest.tsv", rows)
    return rows


def _write_clip(out: Path, rig: ZooRig, c: int, seed: int, fps: float,
                frames: int, split: str, r: int) -> Dict[str, str]:
    kinds = CLIP_KINDS[rig.species]
    kind, repeat = kinds[c % len(kinds)], c // len(kinds)
    clip_seed = int(np.random.default_rng([seed, r, c]).integers(2 ** 31))
    motion = generate_clip(rig, kind, frames, fps, clip_seed)
    rel = f"{rig.species}/{rig.name}_{kind}{f'_{repeat + 1}' if repeat else ''}.bvh"
    path = out / rel
    path.parent.mkdir(parents=True, exist_ok=True)
    write_bvh(motion, path)
    return {"path": rel, "dataset": "zoo", "skeleton": rig.name,
            "species": rig.species, "split": split, "fps": f"{fps:.1f}",
            "frames": str(frames), "joints": str(rig.skeleton.num_joints),
            "licence": LICENCE,
            "sha1": hashlib.sha1(path.read_bytes()).hexdigest()}


def _write_manifest(path: Path, rows: List[Dict[str, str]]) -> None:
    """Write the manifest atomically."""
    def write(f) -> None:
        writer = csv.DictWriter(f, MANIFEST_COLUMNS, delimiter="\t",
                                lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)

    atomic_write(path, write, newline="")
