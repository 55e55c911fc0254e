"""Motions of the zoo: gaits with planted feet and two-bone IK for legged
rigs, slithering for snakes, and :func:`generate_clip`."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Dict, List, Optional, Tuple

import numpy as np

from satagraph.datasets.zoo.rigs import (Leg, Sway, ZooRig, _align, _euler,
                                         _is_below, _rot, _smoothstep, _unit)
from satagraph.datasets.zoo.species import ALL_KINDS
from satagraph.motion import Motion
from satagraph.ops.rotation_numpy import rotation_about_numpy
from satagraph.skeleton import Skeleton


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
    # Crabs: alternating tripods; spiders: alternating tetrapods.
    "crab": ({"L1": 0.0, "R2": 0.0, "L3": 0.0, "R1": 0.5, "L2": 0.5, "R3": 0.5},
             0.6, 0.7, 1.2, 0.2),
    "spider": ({"L1": 0.0, "R2": 0.0, "L3": 0.0, "R4": 0.0, "R1": 0.5, "L2": 0.5,
                "R3": 0.5, "L4": 0.5}, 0.6, 0.7, 1.4, 0.2),
}
#: A quadruped's ``run`` gallops (rotary: the hind feet land one after the
#: other, then the fore feet, with a moment of suspension): at the
#: ``run`` multiple of this speed, 4-6 leg lengths a second. The dog's
#: clips run at 3-10 (``../shared/data``, outside its test split); the
#: walking footfall at 2-3 was all the zoo's quadrupeds did fast.
GAITS["gallop"] = ({"LH": 0.0, "RH": 0.1, "LF": 0.5, "RF": 0.6}, 0.35, 1.6, 2.4, 0.15)
GAITS["fowl"] = GAITS["bird"]
GAITS["longtail"] = GAITS["quadruped"]
_IDLE_HZ = 0.3
_PAD_SECONDS = 3.0
#: Below this fraction of the gait's speed a step lifts its foot less
#: (none at standstill), so the feet of a ``start`` or ``stop`` clip stay
#: planted while the body stands; the gait phase never runs slower than
#: :data:`_MIN_CADENCE` of its cruising rate.
_LIFT_SPEED, _MIN_CADENCE = 0.35, 0.3
#: ``look`` clips: head, neck, tail and arm joints (every swaying joint)
#: turn by up to this many degrees, at 0.15-0.5 Hz.
_LOOK_DEGREES = 30.0
#: ``jump`` clips: height of the body's rise and forward hop (leg lengths;
#: a hop of 0 jumps in place), crouch before take-off and after landing
#: (leg lengths), gravity (m/s^2): the flight takes sqrt(8 rise / g).
_JUMP_RISE, _JUMP_HOP, _JUMP_CROUCH, _GRAVITY = (0.15, 0.4), (0.0, 0.6), 0.12, 9.81
#: ``reach`` clips: how far one arm swings up from hanging (degrees: 60
#: reaches forward and down, 90 straight ahead, 150 overhead), how long it
#: rises (s) and holds (s).
_REACH_DEGREES, _REACH_RISE, _REACH_HOLD = (60.0, 150.0), (0.5, 0.9), (0.3, 1.0)
#: ``bow`` clips: how far the upper body bends forward (degrees; the pelvis
#: takes :data:`_BOW_PELVIS` of it, the spine the rest), how long it goes
#: down (and comes up, s) and holds (s).
_BOW_DEGREES, _BOW_DOWN, _BOW_HOLD, _BOW_PELVIS = (30.0, 70.0), (0.7, 1.2), (0.3, 1.0), 0.6
#: ``wave`` clips: how far the upper arm rises from hanging (degrees, to the
#: side), how far the forearm bends up from it, the forearm's side-to-side
#: swing (degrees, Hz), how long the arm rises (s) and waves (s).
_WAVE_RAISE, _WAVE_ELBOW = (100.0, 150.0), (30.0, 70.0)
_WAVE_SWING, _WAVE_HZ, _WAVE_RISE, _WAVE_HOLD = (20.0, 35.0), (1.5, 2.8), (0.4, 0.7), (1.2, 2.2)
#: ``sit`` and ``lie`` clips of quadrupeds: the body pitches nose up until
#: its hips are :data:`_SIT_DROP` of their height lower (the shoulders
#: stay up on straight fore legs) or goes down by :data:`_LIE_DROP` of its
#: standing height; the feet of the folded legs turn flat on the ground.
#: The body goes down in :data:`_LOWER_MOVE` seconds, stays down
#: :data:`_LOWER_HOLD` and gets up again; where in that the clip starts is
#: drawn, so a short clip can show the body going down, staying down or
#: getting up.
_SIT_DROP, _LIE_DROP, _LOWER_MOVE, _LOWER_HOLD = (0.4, 0.6), (0.55, 0.8), (0.6, 1.2), (1.0, 4.0)
#: How far a lying quadruped's fore and hind feet move forward (leg
#: lengths).
_LIE_FORE, _LIE_HIND = (0.7, 0.95), (0.3, 0.6)
#: Lowest a lowered body's joints above its feet come to the ground (leg
#: lengths); how far a flat foot turns towards the ground (of the angle
#: that lays it flat).
_CLEARANCE, _FLAT = 0.03, 0.9
#: The most a leg stretches (hip to ankle over its bones): a knee stays
#: bent by at least 5 degrees, so that it knows which way to fold.
_STRAIGHT = 0.999
#: Kinds that lower the body (:func:`_lower`).
_LOWER_KINDS = ("sit", "lie")
#: Kinds whose body stays in place.
_STILL_KINDS = ("idle", "look", "reach", "bow", "wave") + _LOWER_KINDS
#: Walks that do not go where the body faces: ``back`` at this share of the
#: gait's speed, ``side`` at this share and this angle off the facing
#: direction (degrees, to a random side: below 60 diagonally forward, above
#: it sideways); ``run``: the gait at this multiple of its speed.
_BACK_SPEED, _SIDE_SPEED, _SIDE_DEGREES, _RUN_SPEED = (
    (0.45, 0.7), (0.4, 0.65), (30.0, 90.0), (1.8, 2.5))


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
    #: ``jump`` clips: take-off time (s, clip time) and flight time (s)
    jump: Optional[Tuple[float, float]] = None
    #: Direction of travel off the facing direction (radians, positive:
    #: to the character's left): pi for ``back``, drawn for ``side``
    travel: float = 0.0

    @property
    def time(self) -> np.ndarray:
        return (np.arange(len(self.speed)) - self.pad) / self.fps


def _profile(kind: str, frames: int, fps: float, speed: float,
             rng: np.random.Generator, length: float = 1.0) -> _Clip:
    """Speed and yaw-rate profiles of one clip kind (:obj:`length`: the
    leg length, the unit of a jump's hop)."""
    pad = int(_PAD_SECONDS * fps)
    t = (np.arange(frames + 2 * pad) - pad) / fps
    mid = 0.5 * frames / fps
    ramp = _smoothstep((t - mid + 0.75) / 1.5)
    v = speed * rng.uniform(0.85, 1.15) * np.ones_like(t)
    yaw = np.radians(rng.uniform(-4, 4)) * np.ones_like(t)
    if kind in _STILL_KINDS:
        v[:], yaw[:] = 0.0, 0.0
    elif kind == "turn":
        rate = np.radians(rng.uniform(35, 70)) * rng.choice([-1.0, 1.0])
        yaw = rate * _smoothstep((t - 0.3 * mid) / 0.8)
        v *= 0.85
    elif kind in ("start", "stop"):
        v *= ramp if kind == "start" else 1.0 - ramp
        yaw *= 0.0
    elif kind == "speed":
        lo, hi = speed * rng.uniform(0.5, 0.65), speed * rng.uniform(1.15, 1.3)
        a, b = (lo, hi) if rng.random() < 0.5 else (hi, lo)
        v = a + (b - a) * ramp
    elif kind == "jump":
        # still but for the flight, which carries the body forward at a
        # constant speed (the hop's length over the flight time)
        take_off = rng.uniform(0.3, 0.55) * 2 * mid
        flight = np.sqrt(8 * rng.uniform(*_JUMP_RISE) * length / _GRAVITY)
        hop = rng.uniform(*_JUMP_HOP) * length
        v = np.where((t >= take_off) & (t < take_off + flight), hop / flight, 0.0)
        return _Clip(fps, pad, v, np.zeros_like(yaw), jump=(take_off, flight))
    if kind == "back":
        return _Clip(fps, pad, v * rng.uniform(*_BACK_SPEED), yaw, travel=np.pi)
    if kind == "side":
        angle = np.radians(rng.uniform(*_SIDE_DEGREES)) * rng.choice([-1.0, 1.0])
        return _Clip(fps, pad, v * rng.uniform(*_SIDE_SPEED), yaw, travel=float(angle))
    if kind == "run":
        v *= rng.uniform(*_RUN_SPEED)
    return _Clip(fps, pad, v, yaw)


@dataclass(frozen=True)
class ClipFacts:
    r"""What a generated zoo clip does, as the generator drew it (the
    truth captions are written from).

    Attributes:
        species (str): Body plan.
        kind (str): Clip kind (:data:`ALL_KINDS`).
        duration (float): Seconds.
        speed_start (float): Forward speed at the first frame, in leg
            lengths per second (0 for idles).
        speed_end (float): Forward speed at the last frame.
        turn (float): Heading change over the clip in degrees; positive
            turns to the character's left (+X of the canonical frame,
            counterclockwise seen from above). Snakes: the bend of their
            path, without the serpentine wave.
        travel (float): Direction of travel off the facing direction in
            degrees, positive to the left: 0 but for ``back`` (180) and
            ``side`` (30-90 either way). Speeds are along it.
    """

    species: str
    kind: str
    duration: float
    speed_start: float
    speed_end: float
    turn: float
    travel: float = 0.0


def _legged_facts(rig: ZooRig, kind: str, clip: _Clip, frames: int) -> ClipFacts:
    """Facts of a legged clip from its traced profile."""
    first, last = clip.pad, clip.pad + frames - 1
    turn = np.degrees(clip.heading[last] - clip.heading[first])
    scale = 1.0 / rig.leg_length
    return ClipFacts(rig.species, kind, frames / clip.fps,
                     float(clip.speed[first] * scale), float(clip.speed[last] * scale),
                     float(turn), float(np.degrees(clip.travel)))


# ------------------------------------------------------------ feet, IK
@dataclass
class _Feet:
    """Ankle targets and foot yaw per leg over the extended grid."""

    targets: np.ndarray  # (legs, N, 3)
    yaw: np.ndarray  # (legs, N)
    #: Pitch of each foot (radians, (legs, N); negative lays it forward
    #: and flat), or ``None`` for feet kept as in the rest
    pitch: Optional[np.ndarray] = None
    #: How far each leg is folded under a lowered body, 0 to 1 (legs, N)
    fold: Optional[np.ndarray] = None


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
               idle: bool, lift_scale: np.ndarray) -> _Feet:
    """Planted / swinging ankle targets for every leg, each step's lift
    scaled per frame by :obj:`lift_scale`."""
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
        pos[:, 1] += lift_h * lift_scale * np.sin(np.pi * s)
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


def _sway_rotation(sway: Optional[Sway], phase: np.ndarray,
                   scale: Optional[np.ndarray] = None) -> np.ndarray:
    """Local rotations :math:`(T, 3, 3)` of a joint's sway, its amplitude
    times :obj:`scale` per frame (:math:`(T,)`) when given."""
    if sway is None:
        return np.broadcast_to(np.eye(3), (len(phase), 3, 3))
    wave = np.sin(2 * np.pi * (sway.k * phase + sway.phase))[:, None]
    if scale is not None:
        wave = wave * scale[:, None]
    return _euler(sway.static[None] + sway.amplitude[None] * wave)


def _pose(rig: ZooRig, root_pos: np.ndarray, root_rot: np.ndarray, heading: np.ndarray,
          local: Dict[int, np.ndarray], feet: Optional[_Feet] = None
          ) -> Tuple[np.ndarray, np.ndarray]:
    """Global rotations and positions by forward kinematics: legs by IK
    when :obj:`feet` is given, the other joints by their local rotations
    :math:`(T, 3, 3)` in :obj:`local` (:func:`_local_rotations`; identity
    where absent)."""
    skel = rig.skeleton
    frames, num = len(root_rot), skel.num_joints
    rot, pos = np.zeros((frames, num, 3, 3)), np.zeros((frames, num, 3))
    rot[:, 0], pos[:, 0] = root_rot, root_pos
    fixed: Dict[int, np.ndarray] = {}
    roles = {leg.upper: i for i, leg in enumerate(rig.legs)}
    for j in range(1, num):
        p = skel.parents[j]
        pos[:, j] = pos[:, p] + rot[:, p] @ skel.offsets[j]
        if feet is not None and j in roles:
            fixed.update(_solve_leg(rig, roles[j], pos[:, j], heading, feet))
        if j in fixed:
            rot[:, j] = fixed[j]
        else:
            rot[:, j] = rot[:, p] @ local[j] if j in local else rot[:, p]
    return rot, pos


def _local_rotations(rig: ZooRig, phase: np.ndarray, scale: np.ndarray,
                     extra: Optional[Dict[int, np.ndarray]] = None) -> Dict[int, np.ndarray]:
    """Local rotations :math:`(T, 3, 3)` of every swaying joint but the
    root: its sway (amplitude times :obj:`scale` per frame), then its
    :obj:`extra` rotation where there is one (``look`` clips)."""
    extra = extra or {}
    out = {}
    for j, sway in rig.sway.items():
        if j:
            out[j] = _sway_rotation(sway, phase, scale)
            if j in extra:
                out[j] = out[j] @ extra[j]
    return out


def _look(rig: ZooRig, time: np.ndarray, rng: np.random.Generator) -> Dict[int, np.ndarray]:
    """Slow free turns of every swaying joint (head, neck, tail, arms,
    spine): a sum of two sines about a random axis each, up to
    :data:`_LOOK_DEGREES`."""
    out = {}
    for j in sorted(rig.sway):
        if j == 0:
            continue
        axis = _unit(rng.normal(size=3))
        hz, shift = rng.uniform(0.15, 0.5, 2), rng.uniform(0, 2 * np.pi, 2)
        waves = np.sin(2 * np.pi * hz[:, None] * time[None] + shift[:, None])
        angle = np.radians(_LOOK_DEGREES) * rng.uniform(0.3, 1.0) * waves.mean(axis=0)
        out[j] = rotation_about_numpy(axis, angle)
    return out


def _reach(rig: ZooRig, clip: _Clip, local: Dict[int, np.ndarray],
           rng: np.random.Generator) -> None:
    """One arm (drawn) swings up from its hanging pose about the body's
    left-right axis, holds and comes back down, centred in the clip:
    updates the upper arm's local rotation in :obj:`local`."""
    arm = rig.arms[int(rng.integers(len(rig.arms)))]
    rise, hold = rng.uniform(*_REACH_RISE), rng.uniform(*_REACH_HOLD)
    angle = -np.radians(rng.uniform(*_REACH_DEGREES)) * _centred(clip, rise, hold)
    local[arm] = _rot(0, angle) @ local[arm]


def _centred(clip: _Clip, rise: float, hold: float, shift: float = 0.0) -> np.ndarray:
    """A 0 -> 1 -> 0 envelope over the clip's extended grid: rising for
    :obj:`rise` seconds, held for :obj:`hold`, falling for :obj:`rise`,
    centred in the clip (or :obj:`shift` seconds after its middle)."""
    mid = 0.5 * (len(clip.time) - 2 * clip.pad) / clip.fps + shift
    up = _smoothstep((clip.time - (mid - hold / 2 - rise)) / rise)
    down = _smoothstep((clip.time - (mid + hold / 2)) / rise)
    return up - down


def _bow(rig: ZooRig, clip: _Clip, local: Dict[int, np.ndarray],
         rng: np.random.Generator) -> np.ndarray:
    """The upper body bends forward at the hips and along the spine, holds
    and straightens, centred in the clip (the legs stay planted by IK, the
    arms keep hanging): updates the spine's and arms' local rotations in
    :obj:`local`; returns the pelvis's extra rotation :math:`(T, 3, 3)`."""
    angle = np.radians(rng.uniform(*_BOW_DEGREES)) * _centred(
        clip, rng.uniform(*_BOW_DOWN), rng.uniform(*_BOW_HOLD))
    spine = _spine(rig)
    for j in spine:
        local[j] = _rot(0, angle * (1.0 - _BOW_PELVIS) / len(spine)) @ local[j]
    for arm in rig.arms:  # the arms keep hanging down
        local[arm] = _rot(0, -angle) @ local[arm]
    return _rot(0, angle * _BOW_PELVIS)


def _spine(rig: ZooRig) -> List[int]:
    """The joints from the root's child to the joint the arms hang from."""
    parents = rig.skeleton.parents
    j, chain = int(parents[parents[rig.arms[0]]]), []
    while j > 0:
        chain.append(j)
        j = int(parents[j])
    return chain[::-1]


def _wave(rig: ZooRig, clip: _Clip, local: Dict[int, np.ndarray],
          rng: np.random.Generator) -> None:
    """One arm (drawn) rises to the side, its forearm bent up and swinging
    from side to side, then comes down, centred in the clip: updates the
    upper arm's and forearm's local rotations in :obj:`local`."""
    arm = rig.arms[int(rng.integers(len(rig.arms)))]
    forearm = int(np.flatnonzero(rig.skeleton.parents == arm)[0])
    rest = rig.skeleton.offsets[forearm]
    side = 1.0 if rest[0] >= 0 else -1.0  # the arm points to +X (left) or -X
    rise, hold = rng.uniform(*_WAVE_RISE), rng.uniform(*_WAVE_HOLD)
    up = _centred(clip, rise, hold)
    on = _centred(clip, 0.5 * rise, hold + rise)  # the swing fades in and out
    hz, start = rng.uniform(*_WAVE_HZ), rng.uniform(0, 2 * np.pi)
    swing = np.radians(rng.uniform(*_WAVE_SWING)) * np.sin(2 * np.pi * hz * clip.time + start)
    raise_ = np.radians(rng.uniform(*_WAVE_RAISE)) * up
    elbow = np.radians(rng.uniform(*_WAVE_ELBOW)) * up + swing * on
    local[arm] = _rot(2, side * raise_) @ local[arm]
    local[forearm] = _rot(2, side * elbow) @ local[forearm]


#: Kinds that move the body in place: kind -> a function updating the local
#: rotations (and returning the pelvis's extra rotation, or ``None``).
_GESTURES = {"reach": _reach, "bow": _bow, "wave": _wave}


@dataclass
class _Lowering:
    """A ``sit`` or ``lie`` over the extended grid: the pelvis's extra
    rotation :math:`(T, 3, 3)` (or ``None``), the share of its standing
    height the root goes down by :math:`(T,)`, and how flat each leg's
    foot lies, 0 standing to 1 flat :math:`(L, T)`."""

    pelvis: Optional[np.ndarray]
    drop: np.ndarray
    flat: np.ndarray
    #: How far each foot moves forward, in its leg's lengths :math:`(L, T)`
    ahead: np.ndarray


def _lower(rig: ZooRig, kind: str, clip: _Clip, local: Dict[int, np.ndarray],
           rng: np.random.Generator) -> _Lowering:
    """A quadruped sits (nose up, hind legs folded with their feet flat;
    the tail's base turns back so that the tail keeps its carriage) or
    lies down (every leg folded): updates the tail's local rotations in
    :obj:`local`."""
    move, hold = rng.uniform(*_LOWER_MOVE), rng.uniform(*_LOWER_HOLD)
    down = _centred(clip, move, hold, rng.uniform(-1.0, 1.0) * (0.5 * hold + move))
    hind = np.array([not leg.key.endswith("F") for leg in rig.legs], dtype=np.float64)
    if kind == "lie":  # the fore legs stretch out in front, the hind feet come forward
        fore = rng.uniform(*_LIE_FORE) * (1.0 - hind) + rng.uniform(*_LIE_HIND) * hind
        return _Lowering(None, rng.uniform(*_LIE_DROP) * down,
                         np.repeat(down[None], len(rig.legs), axis=0), fore[:, None] * down[None])
    # the nose-up pitch that takes the hips :data:`_SIT_DROP` of their
    # height down while the shoulders stay up
    rest = rig.skeleton.rest_positions()
    shoulders = [leg.upper for leg in rig.legs if leg.key.endswith("F")]
    body = float(np.mean(rest[shoulders, 2]) - rest[0, 2])
    hips = float(rest[0, 1] - rest[:, 1].min())
    pitch = np.arcsin(min(rng.uniform(*_SIT_DROP) * hips / body, 0.8)) * down
    for j in _tail_bases(rig):
        local[j] = _rot(0, pitch) @ local.get(j, np.eye(3))
    return _Lowering(_rot(0, -pitch), np.zeros_like(down), hind[:, None] * down[None],
                     np.zeros((len(rig.legs), len(down))))


def _tail_bases(rig: ZooRig) -> List[int]:
    """The root's children that point backwards (a tail's first joint)."""
    skel = rig.skeleton
    return [j for j in range(1, skel.num_joints)
            if skel.parents[j] == 0 and skel.offsets[j][2] < 0 and not skel.end_site[j]]


def _flatten(rig: ZooRig, feet: _Feet, flat: np.ndarray, ahead: np.ndarray) -> _Feet:
    """Feet that turn flat on the ground as :obj:`flat` goes to 1: each
    pitches until its ankle-to-tip line lies :data:`_FLAT` of the way to
    the ground, its lowest tip staying where it stood (in plan, moved
    :obj:`ahead` leg lengths forward) and its lowest joint on the
    ground."""
    skel = rig.skeleton
    rest = skel.rest_positions()
    targets, pitch = feet.targets.copy(), np.zeros_like(flat)
    for i, leg in enumerate(rig.legs):
        below = [j for j in range(skel.num_joints) if _is_below(skel, j, leg.foot)]
        w = rest[below] - rest[leg.foot]  # the foot's joints from its ankle
        v = w[np.argmin(w[:, 1])]  # ankle -> lowest tip
        pitch[i] = -_FLAT * np.arctan2(-v[1], v[2]) * flat[i]
        yaw = feet.yaw[i]
        turn, tilt = _rot(1, yaw), _rot(0, pitch[i])
        step = turn @ v - turn @ tilt @ v  # the tip stays in plan
        step[:, 1] = w[:, 1].min() - (tilt @ w.T)[:, 1].min(axis=-1)  # lowest joint down
        forward = np.stack([np.sin(yaw), np.zeros_like(yaw), np.cos(yaw)], axis=-1)
        length = sum(_leg_geometry(rig, leg)[2:])
        targets[i] += step + (ahead[i] * length)[:, None] * forward
    return _Feet(targets, feet.yaw, pitch, flat)


def _lowered(rig: ZooRig, clip: _Clip, root_rot: np.ndarray, local: Dict[int, np.ndarray],
             feet: _Feet, height: np.ndarray, drop: np.ndarray) -> np.ndarray:
    """Root height per frame of a body :obj:`drop` of its standing
    :obj:`height` down, kept so that no joint above the feet (knees
    included) comes nearer the ground than :data:`_CLEARANCE` (nor the
    root higher than :obj:`height`)."""
    skel = rig.skeleton
    root = clip.position * np.array([1.0, 0.0, 1.0])
    root[:, 1] = height * (1.0 - drop)
    _, pos = _pose(rig, root, root_rot, clip.heading, local, feet)
    body = [j for j in range(skel.num_joints)
            if not any(_is_below(skel, j, leg.foot) for leg in rig.legs)]
    under = _CLEARANCE * rig.leg_length - pos[:, body, 1].min(axis=1)
    return np.minimum(height, root[:, 1] + np.maximum(under, 0.0))


def _fold_pole(hip: np.ndarray, target: np.ndarray, l1: float, l2: float,
               pole: np.ndarray, fold: np.ndarray, clearance: float) -> np.ndarray:
    """The pole of a leg folded under a lowered body (:obj:`fold`, 0 to
    1): tipped up where the knee would otherwise come nearer the ground
    than :obj:`clearance` (a moving maximum and average over 9 frames).

    Shapes:
        - **hip**, **target**, **pole**: :math:`(T, 3)`
        - **fold**: :math:`(T,)`
        - **output**: :math:`(T, 3)`
    """
    up = np.array([0.0, 1.0, 0.0])
    lift = np.zeros_like(fold)
    for extra in (1.0, 3.0, 9.0, 27.0):
        knee, _, _ = _two_bone(hip, target, l1, l2, pole + np.outer(lift, up))
        low = (knee[:, 1] < clearance) & (fold > 0)
        if not low.any():
            break
        lift = np.where(low, lift + extra, lift)
    return pole + np.outer(-_smooth_min(-lift, 4), up)


def _solve_leg(rig: ZooRig, i: int, hip: np.ndarray, heading: np.ndarray,
               feet: _Feet) -> Dict[int, np.ndarray]:
    """Global rotations of a leg's upper, lower and foot joints."""
    leg, off = rig.legs[i], rig.skeleton.offsets
    l1, l2 = np.linalg.norm(off[leg.lower]), np.linalg.norm(off[leg.foot])
    pole = _rot(1, heading) @ leg.pole
    if feet.fold is not None:
        pole = _fold_pole(hip, feet.targets[i], l1, l2, pole, feet.fold[i],
                          _CLEARANCE * rig.leg_length)
    _, d1, d2 = _two_bone(hip, feet.targets[i], l1, l2, pole)
    hinge_w = _unit(np.cross(d1, pole))
    u, lo = off[leg.lower] / l1, off[leg.foot] / l2
    hinge = _unit(np.cross(_unit(u + lo), leg.pole))
    foot = _rot(1, feet.yaw[i])
    if feet.pitch is not None:
        foot = foot @ _rot(0, feet.pitch[i])
    return {leg.upper: _align(u, hinge, d1, hinge_w),
            leg.lower: _align(lo, hinge, d2, hinge_w),
            leg.foot: foot}


def _body_height(rig: ZooRig, clip: _Clip, root_rot: np.ndarray,
                 local: Dict[int, np.ndarray], feet: _Feet, reach: float = 0.97
                 ) -> np.ndarray:
    """Root height per frame: the rest stance (legs at most ``rig.stance``
    extended), lowered wherever a leg would need more than ``reach`` of its
    length (or a little more than its stance) to touch its target."""
    crouch = min(rig.stance, _STRAIGHT)
    reach = min(max(reach, rig.stance + 0.004), _STRAIGHT)
    rest = rig.skeleton.rest_positions()
    flat = clip.position * np.array([1.0, 0.0, 1.0])
    _, pos = _pose(rig, flat, root_rot, clip.heading, local)
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
        len(root_rot), base)
    return _smooth_min(height, int(round(0.1 * clip.fps * _slack(rig))))


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


def gait_of(species: str, kind: str) -> str:
    """The :data:`GAITS` entry a clip kind of a species moves in."""
    if kind == "trot":
        return "trot"
    if kind == "run" and species == "quadruped":
        return "gallop"
    return species


def _legged(rig: ZooRig, kind: str, frames: int, fps: float,
            rng: np.random.Generator
            ) -> Tuple[np.ndarray, np.ndarray, int, ClipFacts]:
    """Global rotations and positions of a legged clip (extended grid),
    and its facts."""
    gait = GAITS[gait_of(rig.species, kind)]
    _, _, stride, speed, _ = gait
    length = rig.leg_length
    clip = _profile(kind, frames, fps, speed * length, rng, length)
    idle = kind in _STILL_KINDS + ("jump",)
    _trace(clip, rng.uniform(-np.pi, np.pi), idle, length, rng)
    if idle:
        freq = np.full_like(clip.speed, _IDLE_HZ)
    else:
        cadence = np.maximum(clip.speed, _MIN_CADENCE * speed * length)
        freq = np.sqrt(cadence * speed * length) / (stride * length)
    phase = np.cumsum(freq) / fps
    phase = phase - phase[clip.pad] + rng.uniform(0, 1)
    # slower than _LIFT_SPEED of the gait: shorter lifts and sways (none
    # at standstill), so a start or stop stands still with planted feet
    scale = np.ones_like(clip.speed) if idle else np.clip(
        clip.speed / (_LIFT_SPEED * speed * length), 0.0, 1.0)
    feet = _plan_feet(rig, clip, phase, gait, idle, scale)
    if clip.jump is not None:
        scale = np.zeros_like(clip.speed)  # no sways: the body is tense
        lift = _jump_lift(clip, length)
        feet = _jump_feet(clip, feet, lift)
    root_rot = _rot(1, clip.heading) @ _sway_rotation(rig.sway.get(0), phase, scale)
    local = _local_rotations(rig, phase, scale,
                             _look(rig, clip.time, rng) if kind == "look" else None)
    pelvis, low = None, None
    if kind in _GESTURES:
        pelvis = _GESTURES[kind](rig, clip, local, rng)
    elif kind in _LOWER_KINDS:
        low = _lower(rig, kind, clip, local, rng)
        pelvis, feet = low.pelvis, _flatten(rig, feet, low.flat, low.ahead)
    if pelvis is not None:
        root_rot = root_rot @ pelvis
    height = _body_height(rig, clip, root_rot, local,
                          feet if clip.jump is None else _grounded(feet))
    if low is not None:
        height = _lowered(rig, clip, root_rot, local, feet, height, low.drop)
    root = clip.position * np.array([1.0, 0.0, 1.0])
    root[:, 1] = height
    if clip.jump is not None:
        root[:, 1] += lift[0] - lift[1]
    elif idle:
        root[:, 1] -= 0.01 * _slack(rig) * length * (1 + np.sin(2 * np.pi * phase))
    rot, pos = _pose(rig, root, root_rot, clip.heading, local, feet)
    return rot, pos, clip.pad, _legged_facts(rig, kind, clip, frames)


def _slack(rig: ZooRig) -> float:
    """How bent a rig's legs stand, from 1 (the zoo's stance, 0.95) to 0
    (straight). A standing body sinks by up to ``0.02 * slack`` leg
    lengths as it breathes (a body whose knees are nearly straight cannot
    sink without bending them: sinking 2 % of a leg bends a knee by 23
    degrees), and a walking body's height follows the moving
    minimum of what its legs reach over ``0.1 * slack`` seconds either
    side: a straighter-legged walker rises over each planted leg, as
    people do, instead of staying at its lowest."""
    return min(1.0, (1.0 - rig.stance) / 0.05)


def _jump_lift(clip: _Clip, length: float) -> Tuple[np.ndarray, np.ndarray]:
    """Per frame of a jump: the body's ballistic rise (zero on the ground)
    and its crouch (before take-off and after landing, feet planted)."""
    take_off, flight = clip.jump
    t = clip.time
    s = np.clip((t - take_off) / flight, 0.0, 1.0)
    rise = 0.5 * _GRAVITY * flight ** 2 * s * (1.0 - s)  # peak g T^2 / 8
    dip = np.exp(-0.5 * ((t - take_off + 0.18) / 0.1) ** 2) \
        + 0.8 * np.exp(-0.5 * ((t - take_off - flight - 0.12) / 0.1) ** 2)
    return rise, _JUMP_CROUCH * length * dip


def _grounded(feet: _Feet) -> _Feet:
    """Ankle targets kept at their first frame's height (a jump's stance
    height: as if the feet stayed down)."""
    targets = feet.targets.copy()
    targets[..., 1] = feet.targets[:, :1, 1]
    return _Feet(targets, feet.yaw)


def _jump_feet(clip: _Clip, feet: _Feet, lift: Tuple[np.ndarray, np.ndarray]) -> _Feet:
    """A jump's ankle targets: planted where they stood until take-off,
    carried through the air with the body (tucked up a little), planted
    where the hop lands them."""
    take_off, flight = clip.jump
    s = np.clip((clip.time - take_off) / flight, 0.0, 1.0)
    land = int(np.searchsorted(clip.time, take_off + flight))
    land = min(land, len(clip.time) - 1)
    shift = clip.position[land] - clip.position[clip.pad]
    w = _smoothstep(s)[:, None]
    targets = feet.targets + w[None] * shift[None, None] * np.array([1.0, 0.0, 1.0])
    tuck = 0.15 * lift[0].max(initial=0.0) * np.sin(np.pi * s)
    targets[..., 1] += (lift[0] + tuck)[None]
    return _Feet(targets, feet.yaw)


def _trace(clip: _Clip, heading: float, idle: bool, length: float,
           rng: np.random.Generator) -> None:
    """The root's heading and ground path from the speed and yaw rate (in
    the direction :attr:`_Clip.travel` off the heading), starting at the
    origin with :obj:`heading`; idles sway sideways."""
    psi = np.cumsum(clip.yaw_rate) / clip.fps
    clip.heading = psi - psi[clip.pad] + heading
    way = clip.heading + clip.travel
    fwd = np.stack([np.sin(way), np.zeros_like(way), np.cos(way)], axis=1)
    pos = np.cumsum(clip.speed[:, None] * fwd, axis=0) / clip.fps
    clip.position = pos - pos[clip.pad]
    if idle:
        t = clip.time
        side = np.stack([np.cos(clip.heading), 0 * t, -np.sin(clip.heading)], 1)
        amp = 0.03 * length * rng.uniform(0.5, 1.0)
        clip.position += amp * np.sin(2 * np.pi * 0.25 * t)[:, None] * side


# ----------------------------------------------------------- snake motion
def _snake_path(length: float, kind: str, rng: np.random.Generator,
                extent: Tuple[float, float]) -> Tuple[np.ndarray, np.ndarray, float]:
    """Arc-length grid and points (x, z) of a serpentine path, and its bend
    (radians per unit of arc length, positive to the left)."""
    step = length / 400
    s = np.arange(extent[0] - length, extent[1] + length, step)
    wave = length * rng.uniform(0.4, 0.6)
    theta = np.radians(rng.uniform(25, 40)) * np.sin(2 * np.pi * s / wave)
    bend = 0.0
    if kind == "turn":
        sign, radius = rng.choice([-1.0, 1.0]), length * rng.uniform(1.0, 2.0)
        theta += sign * s / radius
        bend = sign / radius
    theta += rng.uniform(-np.pi, np.pi)
    xz = np.cumsum(np.stack([np.sin(theta), np.cos(theta)], 1), axis=0) * step
    return s, xz - xz[np.searchsorted(s, 0.0)], float(bend)


def _slither(rig: ZooRig, kind: str, frames: int, fps: float,
             rng: np.random.Generator
             ) -> Tuple[np.ndarray, np.ndarray, int, ClipFacts]:
    """Global rotations and positions of a slithering snake, and its
    facts."""
    skel, length = rig.skeleton, rig.leg_length
    clip = _profile(kind, frames, fps, GAITS["snake"][3] * length, rng)
    s_root = np.cumsum(clip.speed) / fps
    s_root = (s_root - s_root[clip.pad])[clip.pad:clip.pad + frames]
    z = skel.rest_positions()[:, 2]
    s, xz, bend = _snake_path(length, kind, rng,
                              (s_root.min() + z.min(), s_root.max() + z.max()))
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
    first, last = clip.pad, clip.pad + frames - 1
    facts = ClipFacts(rig.species, kind, frames / fps, float(clip.speed[first] / length),
                      float(clip.speed[last] / length),
                      float(np.degrees(bend * (s_root[-1] - s_root[0]))))
    return (*_follow(skel, target), 0, facts)


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
        kind (str): One of ``ALL_KINDS[rig.species]``.
        frames (int): Number of frames.
        fps (float): Frames per second.
        seed (int): Random seed (speed, turn rate, heading, phase).

    Returns:
        Motion: Local rotations and translations (metres, +Y up, ground at
        y = 0); no raw channels.
    """
    return generate_clip_with_facts(rig, kind, frames, fps, seed)[0]


def generate_clip_with_facts(rig: ZooRig, kind: str = "walk", frames: int = 120,
                             fps: float = 30.0, seed: int = 0
                             ) -> Tuple[Motion, ClipFacts]:
    r""":func:`generate_clip` and what the clip does (:class:`ClipFacts`:
    speeds, turn), from the same random draws.

    Args:
        rig (ZooRig): A skeleton from :func:`zoo_rigs`.
        kind (str): One of ``ALL_KINDS[rig.species]``.
        frames (int): Number of frames.
        fps (float): Frames per second.
        seed (int): Random seed.

    Returns:
        tuple: The motion (see :func:`generate_clip`) and its facts.
    """
    if kind not in ALL_KINDS[rig.species]:
        raise ValueError(f"{rig.species} has no clip kind {kind!r}: choose "
                         f"from {list(ALL_KINDS[rig.species])}")
    rng = np.random.default_rng(seed)
    make = _slither if rig.species == "snake" else _legged
    rot, pos, pad, facts = make(rig, kind, frames, fps, rng)
    rot, pos = rot[pad:pad + frames], pos[pad:pad + frames]
    return _to_motion(rig, rot, pos, fps, kind), facts


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

