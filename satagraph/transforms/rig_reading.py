r"""Reading a rig right: its up axis and its units, from evidence that holds
for any body plan, with a confidence and the evidence itself.

The up axis is decided from the motion first (:func:`guess_up_axis`):

* **ground**: along the true up axis the lowest joints of every frame sit
  at one common level (the floor), and the joints touching it are planted
  (slow) while the body moves; contacts recur over the clip;
* **level**: the per-frame lowest level barely varies over the clip;
* **root**: the root travels across the ground plane and varies little
  along the up axis;
* **rest**: the pose itself: joints named like feet below the body, joints
  named like heads above it, many chain ends at the bottom.

Units (:func:`guess_units`) come from what the file says: a declaration
written by ``satagraph convert --canonical``, exporter dialects with known
units (CMU, Mixamo, Reallusion CC), a human body plan (whose height is
known), and magnitudes that can only be metres (a vertebrate 0.02 to 3.5
units across; never an arthropod, which may be a millimetre or a metre
across). Anything else keeps the file's own units and says so: a 45-unit
quadruped may be a dog in centimetres or a horse in inches, a 3-unit spider
a tarantula in inches or a giant in metres. A human in an arbitrary unit
that makes it a human height in a standard unit cannot be told from one:
it is read in that unit.

Overrides always win: :class:`RigSettings` on a motion (from the command
line, a manifest row, a ``data.sources`` entry or the file's own
declaration) is used as given and never re-guessed.
"""
from __future__ import annotations

import re
import warnings
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Tuple

import numpy as np

from satagraph.motion import Motion, RigSettings
from satagraph.sides import side_of
from satagraph.skeleton import Skeleton

UP_AXES = ("+X", "-X", "+Y", "-Y", "+Z", "-Z")

#: File units to metres, by name (``file`` keeps the file's own units).
UNITS: Dict[str, float] = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254,
                           "ft": 0.3048, "cmu": 0.056444, "mmd": 0.08, "file": 1.0}
_UNIT_ALIASES = {"metre": "m", "metres": "m", "meter": "m", "meters": "m",
                 "centimetre": "cm", "centimetres": "cm", "centimeter": "cm",
                 "centimeters": "cm", "millimetre": "mm", "millimetres": "mm",
                 "millimeter": "mm", "millimeters": "mm", "inch": "in",
                 "inches": "in", "feet": "ft", "foot": "ft", "native": "file"}

#: Confidence under which a guess is flagged (warned about).
LOW_CONFIDENCE = 0.5

#: Weights of the up-axis cues in the total score.
CUE_WEIGHTS = {"ground": 1.0, "level": 0.5, "root": 0.5, "rest": 0.75}
_Y_PRIOR = 0.05  # most BVH files are +Y up: a tie-breaker only
_PAIRS = 96  # frame pairs sampled for positions and velocities
_CONTACT_HEIGHT = 0.04  # of the body size
_CONTACT_SPEED = 0.25  # body sizes per second
_TOP = re.compile(r"head|skull", re.I)
_BOTTOM = re.compile(r"foot|toe|paw|hoof|ankle|heel|tars", re.I)


def normalize_up_axis(text: str) -> str:
    """``"z"`` -> ``"+Z"``, ``"-y"`` -> ``"-Y"``; raises ValueError on others."""
    axis = str(text).strip().upper()
    axis = axis if axis[:1] in ("+", "-") else "+" + axis
    if axis not in UP_AXES:
        raise ValueError(f"up_axis must be one of {', '.join(UP_AXES)}, got {text!r}")
    return axis


def parse_units(value) -> float:
    r"""Factor from file units to metres: a positive number, or a unit name
    (``m``, ``cm``, ``mm``, ``in``, ``ft``, ``cmu``, ``file``)."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        scale = float(value)
    else:
        text = str(value).strip().lower()
        text = _UNIT_ALIASES.get(text, text)
        if text in UNITS:
            return UNITS[text]
        try:
            scale = float(text)
        except ValueError:
            raise ValueError(f"units must be a positive number or one of "
                             f"{', '.join(UNITS)}, got {value!r}") from None
    if not (np.isfinite(scale) and scale > 0):
        raise ValueError(f"units must be a positive number, got {value!r}")
    return scale


def unit_name(scale: float) -> str:
    """The name of a unit factor (``"cm"``), or the factor itself."""
    for name, value in UNITS.items():
        if name != "file" and abs(scale - value) <= 1e-9 * value:
            return name
    return f"{scale:g} m"


# ------------------------------------------------------------------ up axis
@dataclass
class UpAxisGuess:
    r"""The up axis of a motion with its confidence and evidence.

    Args:
        axis (str): ``"+Y"``, ``"-Z"``, ...
        confidence (float): 0 (a coin flip) to 1 (no doubt).
        how (str): ``"given"``, ``"declared"`` (by the file) or ``"detected"``.
        scores (dict): Total score per candidate axis.
        evidence (dict): Cue -> score per candidate axis (detected only).
        moving (bool): Whether the clip moved enough for the motion cues.
    """

    axis: str
    confidence: float = 1.0
    how: str = "detected"
    scores: Dict[str, float] = field(default_factory=dict)
    evidence: Dict[str, Dict[str, float]] = field(default_factory=dict)
    moving: bool = True

    @property
    def low_confidence(self) -> bool:
        return self.how == "detected" and self.confidence < LOW_CONFIDENCE

    def summary(self) -> str:
        """One line: the axis, how it was decided and the runner-up."""
        if self.how != "detected":
            return f"{self.axis} ({self.how})"
        ranked = sorted(self.scores, key=self.scores.get, reverse=True)
        runner = ranked[1] if len(ranked) > 1 else None
        cues = ", ".join(f"{k} {v[self.axis]:.2f}" for k, v in self.evidence.items())
        text = (f"{self.axis} (detected, confidence {self.confidence:.2f}; {cues}"
                + (f"; runner-up {runner} {self.scores[runner]:.2f} against "
                   f"{self.scores[self.axis]:.2f}" if runner else "") + ")")
        return text + ("" if self.moving else "; the clip barely moves: mostly its pose")


def axis_vector(axis: str) -> np.ndarray:
    """The unit vector of a signed axis (``"-Z"`` -> ``[0, 0, -1]``)."""
    vec = np.zeros(3)
    vec["XYZ".index(axis[1])] = 1.0 if axis[0] == "+" else -1.0
    return vec


def _sample(motion: Motion) -> Tuple[np.ndarray, Optional[np.ndarray]]:
    """Global positions of up to :data:`_PAIRS` frames spread over the clip
    and the joint velocities there (per second; ``None`` without motion).

    Shapes:
        - **output**: :math:`(T', J, 3)`, :math:`(T', J, 3)`
    """
    frames = motion.num_frames
    if frames < 2:
        return motion.first_pose()[None], None
    gap = max(1, min(int(round(motion.fps / 20.0)), frames - 1))
    starts = np.unique(np.linspace(0, frames - 1 - gap, min(_PAIRS, frames - gap))
                       .astype(np.int64))
    idx = np.concatenate([starts, starts + gap])
    pos = motion.with_(rotations=motion.rotations[idx],
                       translations=motion.translations[idx]).global_positions()
    first, second = pos[: len(starts)], pos[len(starts):]
    return first, (second - first) * (motion.fps / gap)


def body_size(positions: np.ndarray) -> float:
    r"""Median over frames of the diagonal of the pose's bounding box.

    Shapes:
        - **positions**: :math:`(T, J, 3)`
    """
    diag = np.linalg.norm(np.ptp(positions, axis=1), axis=-1)
    return max(float(np.median(diag)), 1e-9)


def _ground_cues(pos: np.ndarray, vel: np.ndarray, size: float,
                 up: np.ndarray) -> Tuple[float, float]:
    """(ground, level): the fraction of frames with a planted joint on the
    common lowest level, and how steady that level is."""
    height = pos @ up
    if height.shape[1] > 2:  # a helper root on the floor moves with the body
        height, vel = height[:, 1:], vel[:, 1:]
    low = height.min(axis=1)
    floor = float(np.median(low))
    near = (height - floor) < _CONTACT_HEIGHT * size
    slow = np.linalg.norm(vel, axis=-1) < _CONTACT_SPEED * size
    contact = near & slow
    recurring = min(1.0, len(np.flatnonzero(contact.any(axis=0))) / 2.0)
    ground = float(contact.any(axis=1).mean()) * (0.5 + 0.5 * recurring)
    level = float(np.clip(1.0 - np.std(low) / (0.05 * size), 0.0, 1.0))
    return ground, level


def _root_cue(pos: np.ndarray, size: float) -> Optional[np.ndarray]:
    """Per axis (X, Y, Z): 1 - the root's range along it over its largest
    range along another axis; ``None`` when the root barely travels."""
    extent = np.ptp(pos[:, 0], axis=0)
    if extent.max() < 0.3 * size:
        return None
    out = np.empty(3)
    for i in range(3):
        other = max(extent[k] for k in range(3) if k != i)
        out[i] = np.clip(1.0 - extent[i] / max(other, 1e-12), 0.0, 1.0)
    return out


def _rest_cue(pose: np.ndarray, names: List[str], leaves: np.ndarray) -> np.ndarray:
    r"""Per signed axis (order of :data:`UP_AXES`), in [-1, 1]: joints
    named like feet below the body and like heads above it, and more chain
    ends on the bottom of the pose than on its top.

    Shapes:
        - **pose**: :math:`(J, 3)`
    """
    extent = max(float(np.linalg.norm(np.ptp(pose, axis=0))), 1e-9)
    middle = np.median(pose, axis=0)
    score = np.zeros(3)
    bottom = [i for i, n in enumerate(names) if _BOTTOM.search(n)]
    top = [i for i, n in enumerate(names) if _TOP.search(n)]
    if bottom:
        score += 2.0 * (middle - pose[bottom].mean(0)) / extent
    if top:  # weak: heads are in front of most animals, above only some
        score += 0.5 * (pose[top].mean(0) - middle) / extent
    ends = pose[leaves] if leaves.any() else pose
    low = (ends - pose.min(0)) < 0.03 * extent
    high = (pose.max(0) - ends) < 0.03 * extent
    score = score + 0.5 * (low.mean(0) - high.mean(0))
    score = np.clip(score, -1.0, 1.0)
    signed = np.array([s * v for v in score for s in (1.0, -1.0)])
    # joints resting on a plane: the ground under a lying or crouching body
    lying = np.concatenate([[((pose - pose.min(0)) < 0.03 * extent).mean(0)[i],
                             ((pose.max(0) - pose) < 0.03 * extent).mean(0)[i]]
                            for i in range(3)])
    return signed + lying


def guess_up_axis(motion: Motion) -> UpAxisGuess:
    r"""Detect the up axis of a motion of any body plan, with a confidence.

    The cues (see the module docstring) are scored for each of the six
    signed axes and summed with :data:`CUE_WEIGHTS`; the confidence is the
    margin of the best total over the runner-up (a margin of 0.5 or more is
    certain). A clip that barely moves is decided on its pose alone, with a
    lower confidence; a rig without frames on its rest pose alone, with half
    of that (always low: exporters need not write a rest upright, and
    CC_Base's lies along +Z, its motion standing it up), and as +Y, the
    convention of most files, at confidence 0 where that rest is a line
    (:func:`~satagraph.transforms.rest.is_line_rest`: Bandai's and the
    dog's lie along X, no pose to read an axis from).
    """
    pos, vel = _sample(motion)
    size = body_size(pos)
    moving = 0.0
    if vel is not None:
        speed = np.linalg.norm(vel, axis=-1).max(axis=1)
        moving = float((speed > _CONTACT_SPEED * size).mean())
    evidence: Dict[str, Dict[str, float]] = {k: {} for k in CUE_WEIGHTS}
    root = _root_cue(pos, size) if vel is not None else None
    names = english_names(motion)
    rest = np.median([_rest_cue(p, names, motion.skeleton.is_leaf)
                      for p in pos[:: max(1, len(pos) // 8)]], axis=0)
    busy = (slice(None) if vel is None or (speed > _CONTACT_SPEED * size).sum() < 8
            else speed > _CONTACT_SPEED * size)  # motion cues where it moves
    for k, axis in enumerate(UP_AXES):
        if vel is not None:
            ground, level = _ground_cues(pos[busy], vel[busy], size,
                                         axis_vector(axis))
            evidence["ground"][axis], evidence["level"][axis] = ground, level
        if root is not None:
            evidence["root"][axis] = float(root["XYZ".index(axis[1])])
        evidence["rest"][axis] = float(rest[k])
    evidence = {k: v for k, v in evidence.items() if v}
    scores = {a: sum(CUE_WEIGHTS[k] * v[a] for k, v in evidence.items())
              + (_Y_PRIOR if a == "+Y" else 0.0) for a in UP_AXES}
    ranked = sorted(UP_AXES, key=scores.get, reverse=True)
    margin = scores[ranked[0]] - scores[ranked[1]]
    confidence = float(np.clip(margin / 0.5, 0.0, 1.0)) * (0.6 + 0.4 * min(1.0, 4 * moving))
    if motion.num_frames == 0:
        confidence *= 0.5
        from satagraph.transforms.rest import is_line_rest
        if is_line_rest(motion.skeleton):  # no pose to read: the convention
            return UpAxisGuess("+Y", 0.0, "detected", scores, evidence, False)
    return UpAxisGuess(ranked[0], confidence, "detected", scores, evidence, moving > 0.05)


# -------------------------------------------------------------------- units
@dataclass
class UnitGuess:
    r"""Units of a rig: the factor to metres, how sure, and why.

    Args:
        scale (float): File units to metres (1.0 also where the file's own
            units are kept).
        confidence (float): 0 to 1.
        how (str): ``"given"``, ``"declared"``, ``"dialect"``, ``"human"``,
            ``"magnitude"`` or ``"kept"`` (undecidable: file units kept).
        reason (str): The evidence in words.
        height (float): Character height in file units.
    """

    scale: float
    confidence: float
    how: str
    reason: str
    height: float = 0.0

    @property
    def low_confidence(self) -> bool:
        return self.how not in ("given", "declared") and self.confidence < LOW_CONFIDENCE

    @property
    def kept(self) -> bool:
        return self.how == "kept"

    def summary(self) -> str:
        if self.kept:
            return f"file units kept ({self.reason})"
        return (f"{unit_name(self.scale)} ({self.how}, confidence "
                f"{self.confidence:.2f}: {self.reason})")


#: Exporter dialects whose units are known: (name, joint-name test, fps
#: test or None, units).
_DIALECTS = (
    ("CMU mocap", re.compile(r"^(LHipJoint|RHipJoint|LowerBack)$"), 120.0, "cmu"),
    ("Mixamo", re.compile(r"^mixamorig\d*:", re.I), None, "cm"),
    ("Reallusion CC", re.compile(r"^CC_Base_"), None, "cm"),
    ("MikuMikuDance", re.compile(r"^(センター|上半身|下半身|全ての親)$"), None, "mmd"),
)
#: Heights (metres) a human body plan allows.
HUMAN_HEIGHT = (1.0, 2.3)
#: A human rig of a known exporter is read in the exporter's units unless
#: that makes it shorter or taller than this (metres): then by its height,
#: as any human (Mixamo's names re-exported from Blender in metres).
DIALECT_HUMAN_HEIGHT = (0.8, 3.0)
#: The units a human body plan may be read in: a file in an arbitrary unit
#: that makes it :data:`HUMAN_HEIGHT` tall in one of them reads as that unit.
STANDARD_UNITS = ("m", "cm", "mm", "in", "cmu")
#: Names no human has (a ponytail is hair: 3ds Max biped's ``Bip01 Ponytail1``).
_NOT_HUMAN = re.compile(r"(?<!pony)tail|wing|beak|snout|muzzle|paw|hoof|antenn|claw|"
                        r"pincer|fin(?![a-z])|horn|mane|feather|tentacle", re.I)


def english_names(motion: Motion) -> List[str]:
    """The joint names of :obj:`motion` with foreign words in English
    (:func:`~satagraph.semantics.foreign.english_name`), as the name cues
    read them."""
    from satagraph.semantics.foreign import english_name
    return [english_name(name) for name in motion.skeleton.names]


def _dialect(motion: Motion) -> Optional[Tuple[str, str]]:
    names = motion.skeleton.names
    for label, pattern, fps, units in _DIALECTS:
        hits = sum(1 for n in names if pattern.search(n))
        if hits and (fps is None or abs(motion.fps - fps) < 1.0):
            return label, units
    return None


def _limb_sides(names: List[str], word: re.Pattern) -> int:
    """How many sides (0, 1, 2) have a joint named by :obj:`word`."""
    return len({side_of(n) for n in names if word.search(n)} - {None})


def looks_human(motion: Motion, pose_up: np.ndarray) -> bool:
    r"""A human body plan: a head, hands and feet on both sides, nothing a
    human lacks (tail, wings, beak, paws, ...), and an upright pose (the
    hips between 30% and 75% of the height).

    The head and the hips are read as :func:`~satagraph.semantics.describe_joints`
    reads them (names and hierarchy only): the head is a joint named so or
    the top of the spine (Rigify's ``DEF-spine.006``), the hips the joint
    where the legs meet (Daz Genesis's ``pelvis`` beside ``abdomenLower``).

    Shapes:
        - **pose_up**: :math:`(J,)` heights of the joints in a pose.
    """
    names = english_names(motion)
    if any(_NOT_HUMAN.search(n) for n in names):
        return False
    if not (any(_TOP.search(n) for n in names) or _has_head(motion.skeleton)):
        return False
    hands = _limb_sides(names, re.compile(r"hand|wrist", re.I))
    feet = _limb_sides(names, re.compile(r"foot|ankle|toe", re.I))
    if hands < 2 or feet < 2:
        return False
    low, high = float(pose_up.min()), float(pose_up.max())
    frac = (pose_up - low) / max(high - low, 1e-12)
    hands = [j for j, n in enumerate(names) if re.search(r"hand|wrist", n, re.I)]
    # hips half way up, hands off the ground (a quadruped's front paws are on it)
    return 0.3 <= frac[_hips(motion.skeleton)] <= 0.75 and frac[hands].min() > 0.2


def _has_head(skeleton: Skeleton) -> bool:
    """Whether :func:`~satagraph.semantics.describe_joints` (names and
    hierarchy) finds a head: the top of a spine without a head name."""
    from satagraph.semantics import describe_joints
    from satagraph.semantics.rules import TRUNK_TEXT
    return TRUNK_TEXT["head"] in describe_joints(skeleton)


def _hips(skeleton: Skeleton) -> int:
    """Where the legs meet: the deepest joint above both hind limb ends
    (:func:`~satagraph.semantics.limb_ends`), else the root."""
    from satagraph.semantics import limb_ends
    ends = limb_ends(skeleton)
    if "left hind" not in ends or "right hind" not in ends:
        return 0
    above = set()
    j = ends["left hind"]
    while j >= 0:
        above.add(j)
        j = int(skeleton.parents[j])
    j = ends["right hind"]
    while j not in above:
        j = int(skeleton.parents[j])
    return j


def _height(motion: Motion, up: np.ndarray) -> Tuple[float, np.ndarray]:
    """Height (file units) along :obj:`up`: the median over frames of the
    pose's extent (rest poses are arbitrary: the rest pose only for a motion
    without frames), and the joint heights of a pose (frame 0)."""
    if motion.num_frames == 0:
        pose = motion.skeleton.rest_positions() @ up
        return float(np.ptp(pose)), pose
    poses = _sample(motion)[0] @ up
    return float(np.median(np.ptp(poses, axis=1))), poses[0]


def _size(motion: Motion) -> float:
    """Body size (file units): the median bounding-box diagonal."""
    return body_size(_sample(motion)[0])


def _paired_legs(motion: Motion, up_axis: str) -> int:
    """Legs numbered in leg pairs (an arthropod's six or more), read from
    names, geometry and motion; ``0`` for any other body plan. A skeleton
    with fewer than six chain ends has no three leg pairs: it is told so
    without the motion evidence (which needs torch)."""
    if int(np.count_nonzero(motion.skeleton.is_leaf)) < 6:
        return 0
    from satagraph.semantics import evidence_from_motion, paired_legs
    evidence = evidence_from_motion(motion, up_axis=up_axis)
    return paired_legs(motion.skeleton, evidence)


def guess_units(motion: Motion, up_axis: str) -> UnitGuess:
    r"""Guess the units of a rig from what its file says (see the module
    docstring), never from a human prior unless the rig is human."""
    height, pose = _height(motion, axis_vector(up_axis))
    dialect, human = _dialect(motion), looks_human(motion, pose)
    if dialect is not None:
        label, units = dialect
        tall = height * UNITS[units]
        if not human or DIALECT_HUMAN_HEIGHT[0] <= tall <= DIALECT_HUMAN_HEIGHT[1]:
            return UnitGuess(UNITS[units], 0.9, "dialect", f"{label} rig", height)
        # a Mixamo rig re-exported in metres is no 1.5 cm human: read the body
    if human:
        fits = [u for u in STANDARD_UNITS
                if HUMAN_HEIGHT[0] <= height * UNITS[u] <= HUMAN_HEIGHT[1]]
        if fits:
            best = min(fits, key=lambda u: abs(np.log(height * UNITS[u] / 1.7)))
            conf = 0.9 if len(fits) == 1 else 0.5
            return UnitGuess(UNITS[best], conf, "human", f"a human body plan "
                             f"{height:.4g} units tall ({height * UNITS[best]:.3g} m "
                             f"in {best})", height)
    legs = _paired_legs(motion, up_axis)
    if legs:
        return UnitGuess(1.0, 0.0, "kept", f"{height:.4g} units tall, {legs} legs: "
                         "an arthropod may be a millimetre or a metre across, so "
                         "no size tells its units; " + SET_UNITS, height)
    size = _size(motion)
    if 0.02 <= size <= 3.5:
        return UnitGuess(1.0, 0.7, "magnitude", f"{size:.3g} units across: "
                         "only metres make such a size for a body of four "
                         "legs or fewer", height)
    return UnitGuess(1.0, 0.0, "kept", f"{height:.4g} units tall, not a human "
                     "and no known exporter: cm, inches or another unit all "
                     "fit; " + SET_UNITS, height)


# ------------------------------------------------------------------- reading
#: How a user sets what was guessed, on the command line and in Python
#: (:func:`with_rig`; training: a manifest's ``up_axis`` / ``scale`` columns).
SET_UP_AXIS = "pass --up-axis (Python: with_rig(motion, up_axis=...)) to set it"
SET_UNITS = "pass --units (Python: with_rig(motion, scale=...)) to set them"


class RigReadingWarning(UserWarning):
    """A rig's up axis or units were guessed with low confidence, or its
    units could not be decided (the file's own are kept)."""


class UnitsWarning(RigReadingWarning):
    """The units part of a :class:`RigReadingWarning`. Whatever reads bodies
    in their own heights (the models' features, contacts, grounding and
    planting) gives the same output in any units, so the commands built on
    that alone (``retarget``, ``reconstruct``, ``generate``) do not show
    it."""


def warn_reading(reading: "RigReading", source: Optional[str] = None) -> None:
    """Warn about each doubtful part of a reading: the up axis as a
    :class:`RigReadingWarning`, the units as a :class:`UnitsWarning`."""
    for line in reading.up_warnings:
        warnings.warn(f"{source or 'motion'}: {line}", RigReadingWarning, stacklevel=3)
    for line in reading.unit_warnings:
        warnings.warn(f"{source or 'motion'}: {line}", UnitsWarning, stacklevel=3)


@dataclass
class RigReading:
    r"""How a motion's rig is read: up axis and units, each given, declared
    or guessed."""

    up: UpAxisGuess
    units: UnitGuess

    @property
    def warnings(self) -> List[str]:
        """Lines to show a user: low-confidence or undecided readings
        (:attr:`up_warnings`, then :attr:`unit_warnings`)."""
        return self.up_warnings + self.unit_warnings

    @property
    def up_warnings(self) -> List[str]:
        """The line of a low-confidence up axis, if any."""
        if not self.up.low_confidence:
            return []
        return [f"up axis {self.up.axis} is a low-confidence guess "
                f"({self.up.confidence:.2f}); {SET_UP_AXIS}"]

    @property
    def unit_warnings(self) -> List[str]:
        """The line of undecided or low-confidence units, if any."""
        if self.units.kept:
            return [f"units unknown: {self.units.reason}"]
        if self.units.low_confidence:
            return [f"units {unit_name(self.units.scale)} are a "
                    f"low-confidence guess; {SET_UNITS}"]
        return []

    def to_dict(self) -> dict:
        return {"up_axis": self.up.axis, "up_axis_how": self.up.how,
                "up_axis_confidence": round(self.up.confidence, 3),
                "up_axis_evidence": {k: {a: round(x, 3) for a, x in v.items()}
                                     for k, v in self.up.evidence.items()},
                "scale": self.units.scale,
                "units": "file" if self.units.kept else unit_name(self.units.scale),
                "units_how": self.units.how,
                "units_confidence": round(self.units.confidence, 3),
                "units_reason": self.units.reason,
                "height_file_units": self.units.height,
                "warnings": self.warnings}


def with_rig(motion: Motion, up_axis: Optional[str] = None,
             scale=None) -> Motion:
    r""":obj:`motion` with the given up axis and units (either may be
    ``None``) set over what it already knows (a file's declaration), so that
    every later canonicalisation uses them. Validates both."""
    if up_axis is None and scale is None:
        return motion
    settings = RigSettings(None if up_axis is None else normalize_up_axis(up_axis),
                           None if scale is None else parse_units(scale))
    return motion.with_(rig=settings.merged(motion.rig),
                        raw_channels=motion.raw_channels)


def read_rig(motion: Motion, up_axis: Optional[str] = None,
             scale: Optional[float] = None) -> RigReading:
    r"""Up axis and units of a motion: :obj:`up_axis` / :obj:`scale` when
    given, else the motion's :class:`~satagraph.motion.RigSettings` (a
    declaration in its file, or overrides attached by a manifest or the
    command line), else detection, on the body: a root above the hips is
    folded into them first (:func:`~satagraph.transforms.canonical.fold_root`),
    as canonicalisation does."""
    from satagraph.transforms.canonical import fold_root
    return read_body(fold_root(motion)[0], up_axis, scale)


def read_body(motion: Motion, up_axis: Optional[str] = None,
              scale: Optional[float] = None) -> RigReading:
    r""":func:`read_rig` of a motion whose root is already the body's
    (:func:`~satagraph.transforms.canonical.fold_root` done)."""
    rig = motion.rig or RigSettings()
    how = "declared" if rig.declared else "given"
    if up_axis is not None:
        up = UpAxisGuess(normalize_up_axis(up_axis), how="given")
    elif rig.up_axis is not None:
        up = UpAxisGuess(normalize_up_axis(rig.up_axis), how=how)
    else:
        up = guess_up_axis(motion)
    if scale is not None or rig.scale is not None:
        value = parse_units(scale if scale is not None else rig.scale)
        height = _height(motion, axis_vector(up.axis))[0]
        units = UnitGuess(value, 1.0, "given" if scale is not None else how,
                          "as given" if scale is not None or not rig.declared
                          else "declared by the file", height)
    else:
        units = guess_units(motion, up.axis)
    return RigReading(up, units)
