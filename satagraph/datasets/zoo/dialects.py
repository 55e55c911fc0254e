r"""Exporter dialects: the same zoo motion as other tools would write it.

A zoo motion is canonical: metres, +Y up, facing +Z, with the rest pose the
rig was built in. Real files differ in three independent ways, each a
composable step that keeps the motion itself exactly:

- :func:`export_dialect`: another up axis (a proper rotation of the whole
  motion, rest pose included) and another unit (a uniform scale);
- :func:`change_rest_pose`: another rest pose (A-pose, lying flat,
  crouched, arbitrary, every bone along its parent's +X as the Bandai and
  dog files have it), the local rotations re-solved so every frame keeps
  its global joint positions;
- :func:`add_name_noise`: exporter suffixes on every joint name
  (``Tail_01__x7Q``, ``Tail_01_v2``, ``Tail_01_a1b2c3``).

:class:`Dialect` bundles one choice of each, :func:`apply_dialect` applies
it, and :func:`dialect_variants` enumerates a benchmark's worth of them.

Example::

    motion = generate_clip(rig, "walk")
    zup_cm = export_dialect(motion, up_axis="+Z", scale=0.01)  # cm, Z up
    odd, scale = apply_dialect(motion, Dialect("-X", "in", "crouched", "tag"), seed=3)
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Dict, Iterator, Optional, Sequence, Tuple, Union

import numpy as np

from satagraph.transforms.augment import axis_rest_rotations, rebase_rest, set_rest_rotations
from satagraph.transforms.rig_reading import UNITS as READ_UNITS
from satagraph.transforms.rig_reading import UP_AXES
from satagraph.datasets.zoo.rigs import ZooRig, _rot, _unit
from satagraph.datasets.zoo.species import CLIP_KINDS, zoo_rigs
from satagraph.motion import Motion
from satagraph.ops.fk import forward_kinematics_numpy
from satagraph.ops.rotation_numpy import rotation_about_numpy

#: The standard units a zoo file may be written in (metres per unit).
UNITS: Dict[str, float] = {k: v for k, v in READ_UNITS.items()
                           if k in ("m", "cm", "mm", "in", "ft")}
#: Rest poses of :func:`change_rest_pose`.
REST_POSES = ("native", "apose", "flat", "crouched", "random", "frame", "axis")
#: Name-noise styles of :func:`add_name_noise`.
NOISE_STYLES = ("tag", "version", "hash")

Unit = Union[str, float]

# Rotation taking +Y (canonical up) to each up axis, handedness preserved:
# X-up and Z-up keep the character's left-right axis or forward axis.
_UP_ROTATIONS = {
    "+Y": np.eye(3),
    "-Y": _rot(0, np.pi),
    "+Z": _rot(0, np.pi / 2),
    "-Z": _rot(0, -np.pi / 2),
    "+X": _rot(2, -np.pi / 2),
    "-X": _rot(2, np.pi / 2),
}


def up_rotation(up_axis: str) -> np.ndarray:
    """The proper rotation taking canonical +Y up to :obj:`up_axis`
    (``"+X"``, ``"-Z"`` ...), :math:`(3, 3)`."""
    if up_axis not in _UP_ROTATIONS:
        raise ValueError(f"up_axis must be one of {list(UP_AXES)}, got {up_axis!r}")
    return np.rint(_UP_ROTATIONS[up_axis])


def unit_scale(unit: Unit, height_m: float) -> float:
    r"""Metres per file unit of :obj:`unit`: a name in :data:`UNITS`, or a
    number (or numeric string) giving the character's height in file
    units (an arbitrary unit: ``28`` makes a character 28 units tall).

    Args:
        unit (str or float): The unit.
        height_m (float): The character's height in metres.
    """
    if isinstance(unit, str) and unit in UNITS:
        return UNITS[unit]
    try:
        tall = float(unit)
    except ValueError:
        raise ValueError(f"unit must be one of {list(UNITS)} or a height in "
                         f"file units, got {unit!r}") from None
    if not tall > 0:
        raise ValueError(f"unit: a height in file units must be positive, got {unit!r}")
    return height_m / tall


def export_dialect(motion: Motion, up_axis: str = "+Y", scale: float = 1.0) -> Motion:
    r"""The same motion written with another up axis and unit.

    Every global joint position :math:`p` becomes :math:`R p / s` with
    :math:`R` = :func:`up_rotation` and :math:`s` = :obj:`scale`, and every
    global rotation :math:`G` becomes :math:`R G R^\top`: offsets and all
    translations are rotated and scaled, local rotations conjugated by
    :math:`R`, so the rest pose stands along the new up axis too.

    Args:
        motion (Motion): A canonical motion (metres, +Y up).
        up_axis (str): One of :data:`UP_AXES`.
        scale (float): Metres per file unit (``0.01``: centimetres), the
            manifest's ``scale`` column.
    """
    if not scale > 0:
        raise ValueError(f"export_dialect: scale must be positive, got {scale}")
    rot = up_rotation(up_axis)
    skel = motion.skeleton
    offsets = skel.offsets @ rot.T / scale
    rotations = rot @ motion.rotations @ rot.T
    translations = motion.translations @ rot.T / scale
    return motion.with_(skeleton=skel.replace(offsets=offsets),
                        rotations=rotations, translations=translations,
                        transform=None)


# ------------------------------------------------------------ rest poses
def rest_pose_rotations(motion: Motion, pose: str, seed: int = 0) -> np.ndarray:
    r"""Global rotations :math:`(J, 3, 3)` of a rest pose, relative to the
    motion's current (canonical: +Y up, facing +Z) rest pose.

    ``"apose"`` lowers every limb that sticks out sideways by 40 degrees
    (at the first joint of a run of sideways bones),
    ``"flat"`` lays the whole rest pose on its back, ``"crouched"`` bends
    every chain of downward bones (hip +30, knee -60, ankle +30 degrees),
    ``"random"`` turns every joint by up to 35 degrees about a random axis.
    ``"axis"`` turns every joint so that its first child's offset lies along
    its +X, with one roll convention (:func:`~satagraph.transforms.augment.axis_rest_rotations`;
    the rest pose is a line, as in files exported with joint orients baked
    in: Bandai, the dog).
    ``"native"`` is the identity.
    """
    skel = motion.skeleton
    if pose == "axis":
        return axis_rest_rotations(skel)
    rest = skel.rest_positions()
    local = np.broadcast_to(np.eye(3), (skel.num_joints, 3, 3)).copy()
    rng = np.random.default_rng(seed)
    if pose == "flat":
        local[0] = _rot(0, -np.pi / 2)
    bones = np.array([_unit(rest[kids[0]] - rest[j]) if len(kids) == 1 else np.zeros(3)
                      for j, kids in enumerate(skel.children)])
    sideways = np.abs(bones[:, 0]) > 0.55
    for j in range(skel.num_joints):
        if pose == "random" and skel.children[j]:
            axis = _unit(rng.normal(size=3))
            local[j] = rotation_about_numpy(axis, rng.uniform(0, np.radians(35)))
        elif pose == "apose" and sideways[j] and not (j and sideways[skel.parents[j]]):
            local[j] = _rot(2, -np.sign(bones[j, 0]) * np.radians(40))
        elif pose == "crouched" and bones[j, 1] < -0.7:
            local[j] = _rot(0, np.radians(_crouch_angle(skel, rest, j)))
    positions = np.zeros((1, skel.num_joints, 3))
    return forward_kinematics_numpy(local[None], positions, skel.parents)[0][0]


def _crouch_angle(skel, rest: np.ndarray, j: int) -> float:
    """Bend (degrees) at the ``k``-th joint of a chain of downward bones:
    +30, -60, +30, then straight."""
    k, p = 0, int(skel.parents[j])
    while p >= 0 and len(skel.children[p]) == 1 and _unit(rest[j] - rest[p])[1] < -0.7:
        k, j, p = k + 1, p, int(skel.parents[p])
    return (30.0, -60.0, 30.0, 0.0)[min(k, 3)]


def change_rest_pose(motion: Motion, pose: str = "apose", seed: int = 0) -> Motion:
    r"""The same motion on a skeleton with another rest pose (offsets
    changed, local rotations re-solved): every frame keeps its global joint
    positions exactly.

    Args:
        motion (Motion): A canonical motion (+Y up, facing +Z).
        pose (str): One of :data:`REST_POSES`; ``"frame"`` takes a random
            frame's pose (:func:`~satagraph.transforms.augment.rebase_rest`).
        seed (int): Random seed (``"random"`` and ``"frame"``).
    """
    if pose not in REST_POSES:
        raise ValueError(f"rest pose must be one of {list(REST_POSES)}, got {pose!r}")
    if pose == "native":
        return motion
    if pose == "frame":
        frame = int(np.random.default_rng(seed).integers(max(motion.num_frames, 1)))
        return rebase_rest(motion, frame)
    return set_rest_rotations(motion, rest_pose_rotations(motion, pose, seed))


# ------------------------------------------------------------ name noise
_LOWER, _UPPER = "abcdefghijklmnopqrstuvwxyz", "ABCDEFGHIJKLMNOPQRSTUVWXYZ"
_DIGITS = "0123456789"


def _pick(rng: np.random.Generator, chars: str) -> str:
    return chars[int(rng.integers(len(chars)))]


def _suffix(rng: np.random.Generator, style: str, version: int) -> str:
    """One exporter suffix; never a word (it always mixes in digits)."""
    if style == "tag":  # __x7Q: lower, digit, upper
        return f"__{_pick(rng, _LOWER)}{_pick(rng, _DIGITS)}{_pick(rng, _UPPER)}"
    if style == "version":
        return f"_v{version}"
    if style == "hash":  # _a1b2c3: hex letters and digits alternating
        return "_" + "".join(_pick(rng, "abcdef" if k % 2 == 0 else _DIGITS)
                             for k in range(6))
    raise ValueError(f"name noise must be one of {list(NOISE_STYLES)}, got {style!r}")


def add_name_noise(motion: Motion, style: str = "tag", seed: int = 0) -> Motion:
    r"""The same motion with an exporter suffix on every joint name:
    ``"tag"`` (``Tail_01__x7Q``, two underscores and three random
    alphanumerics), ``"version"`` (``Tail_01_v2``, one version per file) or
    ``"hash"`` (``Tail_01_a1b2c3``). End sites are renamed
    ``<parent>_end``, as a BVH reader names them. Deterministic in
    :obj:`seed`.

    Args:
        motion (Motion): The motion.
        style (str): One of :data:`NOISE_STYLES`.
        seed (int): Random seed.
    """
    rng = np.random.default_rng(seed)
    version = int(rng.integers(2, 10))
    skel = motion.skeleton
    names = []
    for j, name in enumerate(skel.names):
        if skel.end_site[j] and not skel.children[j] and j:
            names.append(f"{names[skel.parents[j]]}_end")
        else:
            names.append(name + _suffix(rng, style, version))
    if len(set(names)) != len(names):
        raise ValueError("add_name_noise: the new names are not unique")
    return motion.with_(skeleton=skel.replace(names=names))


# --------------------------------------------------------------- dialects
@dataclass(frozen=True)
class Dialect:
    r"""How one file is exported.

    Args:
        up_axis (str): One of :data:`UP_AXES`.
        unit (str or float): A name in :data:`UNITS` or the character's
            height in file units (see :func:`unit_scale`).
        rest (str): One of :data:`REST_POSES`.
        noise (str, optional): One of :data:`NOISE_STYLES`, or ``None``.
    """

    up_axis: str = "+Y"
    unit: Unit = "m"
    rest: str = "native"
    noise: Optional[str] = None

    def __post_init__(self) -> None:
        up_rotation(self.up_axis)
        unit_scale(self.unit, 1.0)
        if self.rest not in REST_POSES:
            raise ValueError(f"rest pose must be one of {list(REST_POSES)}, got {self.rest!r}")
        if self.noise is not None and self.noise not in NOISE_STYLES:
            raise ValueError(f"name noise must be one of {list(NOISE_STYLES)} "
                             f"or None, got {self.noise!r}")

    @property
    def canonical(self) -> bool:
        """Whether this is the zoo's own dialect (+Y up, metres, native
        rest pose, clean names)."""
        return self.tag == ""

    @property
    def tag(self) -> str:
        """File-name tag, e.g. ``"Zup-cm-apose-tag"`` (``""`` when
        canonical); a numeric unit reads ``u28``."""
        parts = []
        if self.up_axis != "+Y":
            parts.append(f"{'neg' if self.up_axis[0] == '-' else ''}{self.up_axis[1]}up")
        if str(self.unit) != "m":
            parts.append(self.unit if self.unit in UNITS else f"u{float(self.unit):g}")
        if self.rest != "native":
            parts.append(self.rest)
        if self.noise:
            parts.append(self.noise)
        return "-".join(parts)


def apply_dialect(motion: Motion, dialect: Dialect, seed: int = 0) -> Tuple[Motion, float]:
    r"""A canonical motion in a :class:`Dialect`: rest pose first, then up
    axis and unit, then name noise.

    Args:
        motion (Motion): A canonical zoo motion (metres, +Y up).
        dialect (Dialect): The dialect.
        seed (int): Random seed (random rest pose and name noise).

    Returns:
        (Motion, float): The motion and its scale (metres per file unit).
    """
    scale = unit_scale(dialect.unit, motion.height())
    out = change_rest_pose(motion, dialect.rest, seed)
    out = export_dialect(out, dialect.up_axis, scale)
    if dialect.noise:
        out = add_name_noise(out, dialect.noise, seed)
    return out, scale


@dataclass(frozen=True)
class DialectVariant:
    """One file of a dialect benchmark: a zoo rig, a clip kind and a
    :class:`Dialect`."""

    rig: ZooRig
    kind: str
    dialect: Dialect


def dialect_variants(seed: int = 0, species: Optional[Sequence[str]] = None,
                     up_axes: Sequence[str] = UP_AXES,
                     units: Sequence[Unit] = ("m", "cm", "in", "tall"),
                     rests: Sequence[str] = REST_POSES,
                     noises: Sequence[Optional[str]] = (None,) + NOISE_STYLES
                     ) -> Iterator[DialectVariant]:
    r"""Every zoo rig in every up axis of :obj:`up_axes`, the units, rest
    poses and name noises cycling over rigs and axes so that each rig gets
    several units and every combination of options appears.

    ``"tall"`` in :obj:`units` stands for an arbitrary unit: the character
    is drawn to be 10 to 200 file units tall. The clip kind is drawn from
    the species' kinds. Deterministic in :obj:`seed`.

    Args:
        seed (int): Random seed (rigs, kinds, arbitrary units).
        species (list[str], optional): Species (default: all).
        up_axes (list[str]): Up axes, each used for every rig.
        units (list): Units (names, heights in file units, or ``"tall"``).
        rests (list[str]): Rest poses.
        noises (list): Name-noise styles (``None``: clean names).

    Yields:
        DialectVariant: (rig, clip kind, dialect).
    """
    rng = np.random.default_rng([seed, 15])
    for r, rig in enumerate(zoo_rigs(species, seed)):
        kinds = CLIP_KINDS[rig.species]
        for a, axis in enumerate(up_axes):
            unit = units[(r + a) % len(units)]
            if unit == "tall":
                unit = float(np.round(rng.uniform(10, 200), 1))
            kind = kinds[int(rng.integers(len(kinds)))]
            yield DialectVariant(rig, kind, Dialect(
                axis, unit, rests[(r + 2 * a) % len(rests)],
                noises[(2 * r + a) % len(noises)]))
