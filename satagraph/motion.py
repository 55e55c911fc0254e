"""A motion clip: a skeleton plus per-frame local rotations and translations."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from satagraph.ops.fk import forward_kinematics_numpy
from satagraph.ops.rotation_numpy import yaw_matrix_numpy
from satagraph.skeleton import Skeleton

#: Contact thresholds as fractions of the character height: SAME's 5 cm and
#: 0.4 m/s for a 1.75 m human (see :func:`ground_contacts`).
CONTACT_HEIGHT = 0.05 / 1.75
CONTACT_SPEED = 0.4 / 1.75
#: Foot-sliding height threshold as a fraction of the height: SAME's 3 cm
#: for a 1.75 m character (FS, :func:`~satagraph.metrics.foot_sliding`, and
#: the motion descriptor's sliding channel).
SLIDE_HEIGHT = 0.03 / 1.75


@dataclass
class CanonicalTransform:
    r"""What canonicalisation did to a motion, so that results can be written
    back in the source's own frame and units.

    A canonical point ``p_c`` relates to the source point ``p_s`` by
    ``p_c = scale * (R @ p_s) + t``, with ``R = yaw @ up``.

    Args:
        up_axis (str): Up axis detected (or given) in the source, e.g. ``"+Y"``.
        up_rotation (np.ndarray): Rotation taking the source up axis to +Y.
        yaw (float): Rotation about +Y (radians) applied after :obj:`up_rotation`
            so that the character faces +Z at frame 0.
        translation (np.ndarray): Translation (canonical units) applied last.
        scale (float): Source units to metres.
        source_fps (float): Frame rate of the source.
        removed_root (dict, optional): A root above the hips that
            canonicalisation folded into them
            (:func:`~satagraph.transforms.canonical.fold_root`: name,
            channels, offset, frame 0's rotation and translation, the hips'
            offset and whether it carried them), for writing back.
        source_rig (RigSettings, optional): How the source was read (up
            axis and units, as given, declared or detected), given back by
            decanonicalisation so that results on the source's rig are read
            the same way.
    """

    up_axis: str = "+Y"
    up_rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    yaw: float = 0.0
    translation: np.ndarray = field(default_factory=lambda: np.zeros(3))
    scale: float = 1.0
    source_fps: float = 30.0
    removed_root: Optional[dict] = None
    source_rig: Optional["RigSettings"] = None

    @property
    def rotation(self) -> np.ndarray:
        """The full rotation ``yaw @ up`` from source to canonical axes."""
        return yaw_matrix_numpy(self.yaw) @ self.up_rotation

    def to_dict(self) -> dict:
        """Plain-Python summary (for reports, JSON and checkpoints)."""
        return {
            "up_axis": self.up_axis,
            "yaw_degrees": float(np.degrees(self.yaw)),
            "translation": [float(v) for v in self.translation],
            "scale": float(self.scale),
            "source_fps": float(self.source_fps),
            "removed_root": (self.removed_root or {}).get("name"),
        }


@dataclass(frozen=True)
class RigSettings:
    r"""How to read a rig, where it is known rather than guessed: its up axis
    and its units (file units to metres).

    Set from the command line (``--up-axis``, ``--units``), a manifest row
    or ``data.sources`` entry (``up_axis``, ``scale`` / ``units``), or a
    file's own declaration (files written by ``satagraph convert
    --canonical`` declare ``+Y`` and metres). Canonicalisation uses what is
    set and detects only the rest.

    Args:
        up_axis (str, optional): ``"+Y"``, ``"-Z"``, ...
        scale (float or str, optional): File units to metres, or a unit
            name (``"cm"``, ``"in"``, ...; see
            :data:`satagraph.transforms.rig_reading.UNITS`).
        declared (bool): Whether the file itself declared these (a
            canonical file), rather than a user.
    """

    up_axis: Optional[str] = None
    scale: Optional[object] = None
    declared: bool = False

    def merged(self, base: Optional["RigSettings"]) -> "RigSettings":
        """These settings over :obj:`base`: what is unset here comes from
        :obj:`base` (a user's override over a file's declaration)."""
        if base is None:
            return self
        mine = self.up_axis is not None or self.scale is not None
        return RigSettings(self.up_axis or base.up_axis,
                           self.scale if self.scale is not None else base.scale,
                           self.declared if mine else base.declared)


@dataclass
class Motion:
    r"""Local joint transforms over time for one :class:`Skeleton`.

    Args:
        skeleton (Skeleton): The skeleton.
        rotations (np.ndarray): Local rotation matrices per frame and joint.
        translations (np.ndarray): Local translation per frame and joint: the
            rest offset, or the value of the joint's position channels; the
            root's is its position in the world.
        fps (float): Frames per second.
        transform (CanonicalTransform, optional): Set by canonicalisation.
        raw_channels (np.ndarray, optional): Channel values exactly as read
            from a BVH file; the writer uses them verbatim while they are
            present. Anything that changes the motion drops them.
        source (str, optional): Path of the file the motion came from.
        rig (RigSettings, optional): Known up axis and units of the rig
            (given by a user or declared by the file); canonicalisation
            guesses only what is not set here.

    Shapes:
        - **rotations**: :math:`(T, J, 3, 3)`
        - **translations**: :math:`(T, J, 3)`
    """

    skeleton: Skeleton
    rotations: np.ndarray
    translations: np.ndarray
    fps: float = 30.0
    transform: Optional[CanonicalTransform] = None
    raw_channels: Optional[np.ndarray] = None
    source: Optional[str] = None
    rig: Optional[RigSettings] = None

    def __post_init__(self) -> None:
        num = self.skeleton.num_joints
        self.rotations = np.asarray(self.rotations, dtype=np.float64)
        self.translations = np.asarray(self.translations, dtype=np.float64)
        if self.rotations.ndim != 4 or self.rotations.shape[1:] != (num, 3, 3):
            raise ValueError(f"Motion: rotations must be [T, {num}, 3, 3], "
                             f"got {list(self.rotations.shape)}")
        if self.translations.shape != (self.num_frames, num, 3):
            raise ValueError(f"Motion: translations must be "
                             f"[{self.num_frames}, {num}, 3], got "
                             f"{list(self.translations.shape)}")
        if not self.fps > 0:
            raise ValueError(f"Motion: fps must be positive, got {self.fps}")

    @property
    def num_frames(self) -> int:
        """Number of frames :math:`T`."""
        return self.rotations.shape[0]

    @property
    def num_joints(self) -> int:
        """Number of joints :math:`J` (end sites included)."""
        return self.skeleton.num_joints

    @property
    def duration(self) -> float:
        """Length in seconds."""
        return self.num_frames / self.fps

    @property
    def root_translation(self) -> np.ndarray:
        """Root position per frame, :math:`(T, 3)`."""
        return self.translations[:, 0]

    def __repr__(self) -> str:
        return (f"Motion(frames={self.num_frames}, joints={self.num_joints}, "
                f"fps={self.fps:g})")

    def global_transforms(self) -> tuple:
        """Global rotations :math:`(T, J, 3, 3)` and positions
        :math:`(T, J, 3)` by forward kinematics, vectorised over frames."""
        return forward_kinematics_numpy(self.rotations, self.translations,
                                        self.skeleton.parents)

    def global_positions(self) -> np.ndarray:
        """Global joint positions :math:`(T, J, 3)` by forward kinematics."""
        return forward_kinematics_numpy(self.rotations, self.translations,
                                        self.skeleton.parents,
                                        rotations=False)[1]

    def first_pose(self) -> np.ndarray:
        r"""Global joint positions of frame 0; the rest pose for a motion
        without frames.

        Shapes:
            - **output**: :math:`(J, 3)`
        """
        if self.num_frames == 0:
            return self.skeleton.rest_positions()
        return self.slice(0, 1).global_positions()[0]

    def height(self) -> float:
        """Character height: the larger of the rest pose's vertical (+Y)
        extent and the median extent over the frames. Rest poses are not
        always upright (a line along +X for Bandai and the dog), and a clip
        can start lying down (a dog's 0.30 m first frame in a clip it
        mostly stands at 0.47 m)."""
        return character_height(self.skeleton, self.global_positions()
                                if self.num_frames else None)

    def with_(self, **changes) -> "Motion":
        """A copy with some fields replaced; drops :obj:`raw_channels` unless
        given."""
        fields = dict(skeleton=self.skeleton, rotations=self.rotations,
                      translations=self.translations, fps=self.fps,
                      transform=self.transform, raw_channels=None,
                      source=self.source, rig=self.rig)
        fields.update(changes)
        return Motion(**fields)

    def slice(self, start: int, stop: int) -> "Motion":
        """Frames ``start:stop``."""
        raw = None if self.raw_channels is None else self.raw_channels[start:stop]
        return self.with_(rotations=self.rotations[start:stop],
                          translations=self.translations[start:stop],
                          raw_channels=raw)


def require_motion(value: object, name: str = "motion") -> Motion:
    """:obj:`value` if it is a :class:`Motion`, else a one-line
    :class:`TypeError` saying how to get one (a path is read with
    :func:`satagraph.io.read_bvh`)."""
    if not isinstance(value, Motion):
        hint = (f"; read it first: satagraph.io.read_bvh({str(value)!r})"
                if isinstance(value, (str, bytes)) or hasattr(value, "__fspath__") else "")
        raise TypeError(f"{name}: expected a satagraph Motion, got "
                        f"{type(value).__name__}{hint}")
    return value


def ground_contacts(positions: np.ndarray, fps: float, size: float,
                    height: float = CONTACT_HEIGHT,
                    speed: float = CONTACT_SPEED) -> np.ndarray:
    r"""Joints in ground contact (+Y up, floor at 0): lower than
    ``height * size`` and slower than ``speed * size`` per second; frame 0
    has no velocity, so the height test alone decides it.

    Args:
        positions (np.ndarray): Global joint positions.
        fps (float): Frame rate.
        size (float): The character height (:meth:`Motion.height`).
        height (float): Height threshold, a fraction of :obj:`size`.
        speed (float): Speed threshold, :obj:`size` per second.

    Shapes:
        - **positions**: :math:`(T, J, 3)`
        - **output**: :math:`(T, J)` bool
    """
    vel = np.diff(positions, axis=0, prepend=positions[:1]) * fps
    slow = np.linalg.norm(vel, axis=-1) < speed * size
    slow[:1] = True
    return (positions[..., 1] < height * size) & slow


def character_height(skeleton: Skeleton, positions: Optional[np.ndarray] = None) -> float:
    r""":meth:`Motion.height` of a skeleton and its global joint positions
    (``None``: the rest pose only), for callers that have the positions.

    Shapes:
        - **positions**: :math:`(T, J, 3)`
    """
    extent = float(np.ptp(skeleton.rest_positions()[:, 1]))
    if positions is None or len(positions) == 0:
        return extent
    return max(extent, float(np.median(np.ptp(positions[..., 1], axis=1))))


def leg_length(positions: np.ndarray, size: float) -> float:
    r"""The character's leg length: the root's median height above the
    lowest joint (the hip height of a legged character), at least 5 % of
    :obj:`size`. The unit of travel and ground speed across body plans (a
    biped's legs are half its height, a quadruped's two thirds).

    Args:
        positions (np.ndarray): Joint positions, +Y up, the root first (any
            horizontal frame: global or facing).
        size (float): The character height (:meth:`Motion.height`).

    Shapes:
        - **positions**: :math:`(T, J, 3)`
    """
    if len(positions) == 0:
        return 0.5 * size
    hip = np.median(positions[:, 0, 1] - positions[:, :, 1].min(axis=1))
    return float(max(hip, 0.05 * max(size, 1e-9)))
