r"""Geometry and motion evidence for the semantic rules.

Names do not always say what a chain is: a bird's legs may hang off the same
spine joint as its wings, a crab's legs are numbered, exporters write joints
``Bone.017``. What the body does does: a chain whose end carries weight and
touches the ground is a leg wherever it hangs, a laterally spread chain that
never bears weight is a wing or an arm, and the legs of an arthropod are
ordered front to back by where they join the body, then by their feet.

:class:`JointEvidence` summarises a motion per joint (mean height above the
ground, fraction of frames in ground contact, mean lateral and forward
position, all in body heights) and is quantised to 0.01, so it is hashable
and part of the rule cache key: descriptions are a deterministic function of
(skeleton, evidence). Positions must be in the canonical body frame: +Y up,
facing +Z, left at +X -- the features' ``x`` (see
:func:`evidence_from_features`), or :func:`evidence_from_motion` of any
motion as read from a file. Rest offsets of a skeleton read from a file are
*not* in that frame (only the root is turned by canonicalisation).
"""
from __future__ import annotations

import inspect
from dataclasses import dataclass
from typing import Any, Callable, Optional, Sequence, Tuple, Union

import numpy as np

#: A joint is in contact when it is this close to the ground (body heights)
#: and no contact flags are given.
GROUND_HEIGHT = 0.04


def _quantise(values: np.ndarray) -> Tuple[float, ...]:
    return tuple(float(v) + 0.0 for v in np.round(np.asarray(values, dtype=np.float64), 2))


@dataclass(frozen=True)
class JointEvidence:
    r"""Per-joint facts of a motion, in body heights, quantised to 0.01.

    Attributes:
        height (tuple[float, ...]): Mean height above the ground.
        contact (tuple[float, ...]): Fraction of frames in ground contact.
        lateral (tuple[float, ...]): Mean sideways position relative to the
            root (left is positive).
        forward (tuple[float, ...]): Mean position along the facing axis
            relative to the root (front is positive).
    """

    height: Tuple[float, ...]
    contact: Tuple[float, ...]
    lateral: Tuple[float, ...]
    forward: Tuple[float, ...]

    def __post_init__(self) -> None:
        sizes = {len(self.height), len(self.contact), len(self.lateral),
                 len(self.forward)}
        if len(sizes) != 1:
            raise ValueError(f"JointEvidence: fields of different lengths {sorted(sizes)}")

    @property
    def num_joints(self) -> int:
        """Number of joints."""
        return len(self.height)

    def subset(self, index: Sequence[int]) -> "JointEvidence":
        """The evidence of some joints, in the order of :obj:`index`."""
        return JointEvidence(*(tuple(field[i] for i in index) for field in (
            self.height, self.contact, self.lateral, self.forward)))


EvidenceLike = Union[None, JointEvidence, np.ndarray, Any]


def joint_evidence(positions, contacts=None, height: Optional[float] = None
                   ) -> JointEvidence:
    r"""Evidence from joint positions in the canonical body frame.

    Args:
        positions: ``[T, J, 3]`` or ``[J, 3]`` (one pose, e.g. a rest pose
            built in metres +Y up), +Y up, facing +Z, left at +X. The root's
            horizontal position is taken out per frame; the ground is the
            lowest height.
        contacts: Optional ``[T, J]`` contact flags (the features' ``c``);
            by default a joint is in contact within
            :data:`GROUND_HEIGHT` body heights of the ground.
        height: Body height (default: the median vertical extent per frame).

    Returns:
        JointEvidence: The evidence.
    """
    pos = np.asarray(positions, dtype=np.float64)
    if pos.ndim == 2:
        pos = pos[None]
    if pos.ndim != 3 or pos.shape[-1] != 3 or pos.shape[0] == 0:
        raise ValueError(f"positions must be [T, J, 3] or [J, 3], got {pos.shape}")
    up = pos[..., 1] - pos[..., 1].min()
    scale = height or float(np.median(up.max(axis=1) - up.min(axis=1)))
    scale = max(scale, 1e-6)
    if contacts is None:
        touch = up <= GROUND_HEIGHT * scale
    else:
        touch = np.asarray(contacts, dtype=np.float64).reshape(up.shape) > 0.5
    rel = pos - pos[:, :1]
    return JointEvidence(
        height=_quantise(up.mean(axis=0) / scale),
        contact=_quantise(touch.mean(axis=0)),
        lateral=_quantise(rel[..., 0].mean(axis=0) / scale),
        forward=_quantise(rel[..., 2].mean(axis=0) / scale))


def evidence_from_features(features) -> JointEvidence:
    """Evidence of a :class:`~satagraph.data.MotionFeatures` (positions in
    the facing frame, contact flags and character height).

    Args:
        features: The motion features.

    Returns:
        JointEvidence: The evidence.
    """
    return joint_evidence(features.x, features.c, features.height)


def evidence_from_motion(motion, canonical: bool = False,
                         up_axis: Optional[str] = None) -> JointEvidence:
    """Evidence of a motion: canonicalised (unless :obj:`canonical`), then
    featurised, so that any up axis and unit gives the same facts. A
    motionless root that canonicalisation removes gets its child's facts.

    Args:
        motion: A :class:`~satagraph.Motion` (a zero-frame motion gives the
            evidence of its rest pose).
        canonical: The motion is canonical already.
        up_axis: The motion's up axis (``"Y"``, ``"-Z"`` ...; default
            detected -- give it for flat bodies such as crabs, which the
            detection may misjudge).

    Returns:
        JointEvidence: The evidence, one entry per joint of
        ``motion.skeleton``.
    """
    from satagraph.transforms.canonical import canonicalize
    from satagraph.pipelines.inference import static_features
    source = motion if motion.num_frames else _rest(motion)
    if not canonical:  # evidence is in body heights: the units do not matter
        known = source.rig is not None and source.rig.scale is not None
        source = canonicalize(source, up_axis=up_axis,
                              unit_scale=None if known else 1.0)
    feats = static_features(source)
    return remap_evidence(evidence_from_features(feats), feats.skeleton.names,
                          motion.skeleton)


def _rest(motion):
    """A one-frame motion in the rest pose."""
    skel = motion.skeleton
    return motion.with_(rotations=np.broadcast_to(np.eye(3), (1, skel.num_joints, 3, 3)).copy(),
                        translations=skel.offsets[None].copy())


def as_evidence(evidence: EvidenceLike, num_joints: int) -> Optional[JointEvidence]:
    """Normalise the ``evidence`` argument of the public functions: ``None``,
    a :class:`JointEvidence`, motion features, or canonical positions.

    Args:
        evidence: The evidence or what it is computed from.
        num_joints: Joints of the skeleton it belongs to.

    Returns:
        JointEvidence or None.

    Raises:
        ValueError: The evidence has another number of joints.
    """
    if evidence is None:
        return None
    if not isinstance(evidence, JointEvidence):
        evidence = (evidence_from_features(evidence) if hasattr(evidence, "c")
                    and hasattr(evidence, "x") else joint_evidence(
                        _numpy(evidence)))
    if evidence.num_joints != num_joints:
        raise ValueError(f"evidence for {evidence.num_joints} joints given for a "
                         f"skeleton of {num_joints}")
    return evidence


def _numpy(value) -> np.ndarray:
    return value.detach().cpu().numpy() if hasattr(value, "detach") else np.asarray(value)


def remap_evidence(evidence: Optional[JointEvidence], source_names: Sequence[str],
                   skeleton) -> Optional[JointEvidence]:
    """Carry a file's evidence over to an augmented copy of its skeleton by
    joint name (augmentation keeps names: a mirrored ``LeftFoot`` carries
    the reflected data of ``RightFoot`` and keeps ``LeftFoot``'s evidence,
    which describes the same kind of joint on the side it now lies). An
    inserted joint takes the facts of its nearest named child (or parent).

    Args:
        evidence: Evidence of the source skeleton (``None``: none).
        source_names: The source skeleton's joint names.
        skeleton: The augmented :class:`~satagraph.Skeleton`.

    Returns:
        JointEvidence or None.
    """
    if evidence is None:
        return None
    index = {n: i for i, n in enumerate(source_names)}
    found = [index.get(n, -1) for n in skeleton.names]
    children = skeleton.children
    for j in range(skeleton.num_joints - 1, -1, -1):  # children first
        if found[j] < 0:
            kids = [found[c] for c in children[j] if found[c] >= 0]
            found[j] = kids[0] if kids else -1
    for j in range(skeleton.num_joints):  # then parents
        if found[j] < 0:
            p = int(skeleton.parents[j])
            found[j] = found[p] if p >= 0 else 0
    return evidence.subset(found)


def accepts_evidence(fn: Callable) -> bool:
    """Whether a semantic embedder takes an ``evidence`` keyword (embedders
    written as ``skeleton -> [J, D]`` are called without it)."""
    try:
        params = inspect.signature(fn).parameters.values()
    except (TypeError, ValueError):
        return False
    return any(p.name == "evidence" or p.kind is p.VAR_KEYWORD for p in params)


def call_semantic(fn: Callable, skeleton, evidence: Optional[JointEvidence] = None):
    """``fn(skeleton, evidence=evidence)`` where :obj:`fn` accepts evidence,
    else ``fn(skeleton)``.

    Args:
        fn: A semantic embedder.
        skeleton: The skeleton.
        evidence: Its evidence.

    Returns:
        What :obj:`fn` returns.
    """
    if evidence is not None and accepts_evidence(fn):
        return fn(skeleton, evidence=evidence)
    return fn(skeleton)
