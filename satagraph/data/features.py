r"""Lossless motion features in the character's facing frame (SAME layout).

Per joint and frame (``dynamic``, :data:`DYNAMIC_LAYOUT`): 6D local rotation
``q`` (the root's relative to the facing frame :math:`F_t`), position ``x``
in :math:`F_t`, position relative to the parent ``x_rel`` in :math:`F_t`,
rotation velocity ``v_q`` (6D of :math:`R_{t-1}^\top R_t`), velocity ``v_x``
in :math:`F_t` (units per second) and contact ``c``. Per frame: root
features ``r`` = (yaw velocity, x velocity, z velocity in :math:`F_{t-1}`,
root height), velocities per second. Static per joint: ``X_l`` (rest offset
from the parent; zero for the root, whose file offset is where its
translation starts, not a bone: a rig whose root offset is the hips' world
position at frame 0, as Bandai's and the dog's files give it, would
otherwise look like no other) and ``X_g`` (rest position relative to the root); per bone:
(depth, reverse depth) of its child joint.

:math:`F_t` is the rotation about +Y by the yaw of the root's facing axis
(the root-local axis that points to +Z at frame 0 of a canonical motion),
placed at the root's ground projection. The first frame's ``r`` is taken
relative to the world origin, so integration restores the trajectory.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property, partial
from typing import Callable, Dict, Optional, Tuple

import numpy as np
import torch

from satagraph.data.clip import MotionClip
from satagraph.motion import (CONTACT_HEIGHT, CONTACT_SPEED, CanonicalTransform, Motion,
                              character_height, ground_contacts, leg_length)
from satagraph.ops.fk import forward_kinematics
from satagraph.ops.rotation import matrix_to_rotation_6d, rotation_6d_to_matrix
from satagraph.ops.rotation_numpy import yaw_matrix_numpy, yaw_of
from satagraph.skeleton import Skeleton
from satagraph.typing import (DYNAMIC_CHANNELS, DYNAMIC_LAYOUT, ROOT_CHANNELS,  # noqa: F401
                              STATIC_CHANNELS)


@dataclass
class MotionFeatures:
    r"""Features of one motion (numpy, float64). See the module docstring.

    Shapes:
        - **x_local**, **x_global**: :math:`(J, 3)`
        - **edge_attr**: :math:`(2(J-1), 2)`
        - **q**, **v_q**: :math:`(T, J, 6)`
        - **x**, **x_rel**, **v_x**: :math:`(T, J, 3)`
        - **r**: :math:`(T, 4)`
        - **c**: :math:`(T, J)`
        - **facing_axis**: :math:`(3,)`

    :attr:`rig_warnings`: what reading the file's rig doubted, as
    ``(kind, line)`` with kind ``"up_axis"`` or ``"units"``, kept with the
    features so that a run served from the cache says it again.
    """

    skeleton: Skeleton
    fps: float
    height: float
    x_local: np.ndarray
    x_global: np.ndarray
    edge_attr: np.ndarray
    q: np.ndarray
    x: np.ndarray
    x_rel: np.ndarray
    v_q: np.ndarray
    v_x: np.ndarray
    r: np.ndarray
    c: np.ndarray
    facing_axis: np.ndarray
    transform: Optional[CanonicalTransform] = None
    rig_warnings: Tuple[Tuple[str, str], ...] = ()

    @property
    def num_frames(self) -> int:
        return self.q.shape[0]

    @cached_property
    def leg_length(self) -> float:
        """:func:`satagraph.motion.leg_length` over every frame (computed
        once: every window of a clip and every decoding target reads it)."""
        return leg_length(self.x, self.height)

    @property
    def dynamic(self) -> np.ndarray:
        """Per-joint features in :data:`DYNAMIC_LAYOUT` order,
        :math:`(T, J, 22)`."""
        return self.dynamic_slice(slice(None))

    def dynamic_slice(self, frames: slice) -> np.ndarray:
        """:attr:`dynamic` for some frames only."""
        parts = [self.q, self.x, self.x_rel, self.v_q, self.v_x, self.c[..., None]]
        return np.concatenate([p[frames] for p in parts], axis=-1)

    @property
    def static(self) -> np.ndarray:
        """``[X_l, X_g]`` per joint, :math:`(J, 6)`."""
        return np.concatenate([self.x_local, self.x_global], axis=-1)

    def to_clip(self, start: int = 0, stop: Optional[int] = None,
                semantic: Optional[torch.Tensor] = None,
                meta: Optional[dict] = None) -> MotionClip:
        """Frames ``start:stop`` as a float32 :class:`MotionClip`.

        Args:
            start (int): First frame.
            stop (int, optional): One past the last frame (default: the end).
            semantic (Tensor, optional): The skeleton's semantic embedding
                :math:`(J, D_t)` (``model.embed(skeleton)``), which a model
                trained with one needs; default: none, :math:`(J, 0)`.
            meta (dict, optional): Extra metadata (dataset, file, ...).

        Returns:
            MotionClip: Dynamic, root, static and semantic features, the
            bones and the metadata (height, leg length, fps).
        """
        sl = slice(start, stop)
        num = self.skeleton.num_joints
        return MotionClip(
            dynamic=torch.from_numpy(self.dynamic_slice(sl)).float(),
            root=torch.from_numpy(self.r[sl]).float(),
            static=torch.from_numpy(self.static).float(),
            semantic=(semantic.float() if semantic is not None
                      else torch.zeros(num, 0)),
            parents=torch.from_numpy(self.skeleton.parents),
            edge_attr=torch.from_numpy(self.edge_attr).float(),
            meta=dict(meta or {}, height=self.height, leg=self.leg_length, fps=self.fps,
                      start=start),
        )


def _wrap(angle: np.ndarray) -> np.ndarray:
    return (angle + np.pi) % (2 * np.pi) - np.pi


def _facing(root_rot: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Yaw angle per frame of the root's facing axis."""
    return yaw_of(root_rot @ axis)


def smooth_yaw(theta: np.ndarray, sigma: float) -> np.ndarray:
    r"""A yaw track (radians) smoothed over time by a Gaussian of
    :obj:`sigma` frames (unwrapped first, edges reflected), shifted to keep
    its first value; unchanged for :obj:`sigma` :math:`\le 0`.

    Shapes:
        - **theta**, **output**: :math:`(T,)`
    """
    if sigma <= 0 or len(theta) < 2:
        return theta
    unwrapped = np.unwrap(theta)
    reach = int(np.ceil(3 * sigma))
    kernel = np.exp(-0.5 * (np.arange(-reach, reach + 1) / sigma) ** 2)
    padded = np.pad(unwrapped, reach, mode="reflect" if len(theta) > reach else "edge")
    smooth = np.convolve(padded, kernel / kernel.sum(), mode="valid")
    return smooth - smooth[0] + theta[0]


def _to_6d(rot: np.ndarray) -> np.ndarray:
    return matrix_to_rotation_6d(torch.from_numpy(rot)).numpy()


def _root_features(theta: np.ndarray, origin: np.ndarray, height: np.ndarray,
                   fps: float) -> np.ndarray:
    prev_theta = np.concatenate([[0.0], theta[:-1]])
    prev_origin = np.concatenate([np.zeros((1, 3)), origin[:-1]])
    delta = np.einsum("tji,tj->ti", yaw_matrix_numpy(prev_theta), origin - prev_origin)
    return np.stack([_wrap(theta - prev_theta) * fps, delta[:, 0] * fps,
                     delta[:, 2] * fps, height], axis=1)


def bone_offsets(skeleton: Skeleton) -> np.ndarray:
    r"""``X_l``: each joint's rest offset from its parent, zero for the root
    (it has no bone; its offset only places the character).

    Shapes:
        - **output**: :math:`(J, 3)`
    """
    out = skeleton.offsets.copy()
    out[skeleton.parents < 0] = 0.0
    return out


#: Frames :func:`motion_to_features` computes at once: its temporaries
#: (rotations, their products, velocities) are those of this many frames.
FEATURE_CHUNK = 2048


def motion_to_features(
    motion: Motion,
    contact_height: float = CONTACT_HEIGHT,
    contact_speed: float = CONTACT_SPEED,
    facing_axis: Optional[np.ndarray] = None,
    facing_smooth: float = 0.0,
    chunk: int = FEATURE_CHUNK,
    height: Optional[float] = None,
) -> MotionFeatures:
    r"""Compute the features of a (canonical) motion.

    Args:
        motion (Motion): A motion, +Y up; canonicalise it first
            (:func:`satagraph.transforms.canonicalize`) so that frame 0 faces +Z.
        contact_height (float, optional): Contact height threshold as a
            fraction of the character height.
        contact_speed (float, optional): Contact speed threshold in character
            heights per second.
        facing_axis (np.ndarray, optional): Root-local facing axis; by default
            the one pointing to +Z at frame 0.
        facing_smooth (float, optional): Standard deviation in seconds of a
            Gaussian over time applied to the facing yaw (:func:`smooth_yaw`):
            the facing frame then turns with the body's heading, not with
            every sway of the root (a trotting dog's pelvis swings its yaw
            by hundreds of degrees a clip), and the sway goes to the root's
            rotation, which is not integrated. 0 (default): the root's own
            yaw in every frame. Lossless either way.
        chunk (int, optional): Frames whose per-frame features are computed
            at once (:data:`FEATURE_CHUNK`): the temporaries are those of a
            chunk, not of the whole take; the features are the same to the
            bit for any chunk.
        height (float, optional): The character height the contacts are
            measured in and the features carry (default: the motion's,
            :func:`~satagraph.motion.character_height`); a window of a
            clip passes the clip's (see
            :func:`~satagraph.data.dataset.window_height`).
    """
    if chunk < 1:
        raise ValueError(f"chunk must be at least 1 frame, got {chunk}")
    skel, fps = motion.skeleton, motion.fps
    pos = motion.global_positions()
    root_rot = motion.rotations[:, 0]
    if facing_axis is None:
        facing_axis = (root_rot[0].T @ np.array([0.0, 0.0, 1.0])
                       if motion.num_frames else np.array([0.0, 0.0, 1.0]))
    theta = smooth_yaw(_facing(root_rot, facing_axis), facing_smooth * fps)
    origin = pos[:, 0] * np.array([1.0, 0.0, 1.0])
    height = character_height(skel, pos) if height is None else float(height)
    contacts = partial(ground_contacts, fps=fps, size=height, height=contact_height,
                       speed=contact_speed)
    frames = _empty_frame_features(motion.num_frames, motion.num_joints)
    for start in range(0, motion.num_frames, chunk):
        stop = min(start + chunk, motion.num_frames)
        part = _frame_features(motion, pos, theta, origin, slice(start, stop), contacts)
        for key, value in part.items():
            frames[key][start:stop] = value
    return MotionFeatures(
        skeleton=skel, fps=fps, height=height,
        x_local=bone_offsets(skel), x_global=skel.rest_positions(),
        edge_attr=skel.edge_attr.astype(np.float64),
        r=_root_features(theta, origin, pos[:, 0, 1], fps),
        facing_axis=np.asarray(facing_axis, dtype=np.float64),
        transform=motion.transform, **frames,
    )


def _empty_frame_features(num_frames: int, num_joints: int) -> Dict[str, np.ndarray]:
    """The per-joint, per-frame feature arrays of a motion, to be filled.

    Shapes:
        - **q**, **v_q**: :math:`(T, J, 6)`
        - **x**, **x_rel**, **v_x**: :math:`(T, J, 3)`
        - **c**: :math:`(T, J)`
    """
    width = {"q": (6,), "x": (3,), "x_rel": (3,), "v_q": (6,), "v_x": (3,), "c": ()}
    return {key: np.empty((num_frames, num_joints) + shape) for key, shape in width.items()}


def _frame_features(motion: Motion, pos: np.ndarray, theta: np.ndarray,
                    origin: np.ndarray, frames: slice,
                    contacts: Callable[[np.ndarray], np.ndarray]) -> Dict[str, np.ndarray]:
    r""":func:`motion_to_features`' per-frame features of :obj:`frames`
    (``q``, ``x``, ``x_rel``, ``v_q``, ``v_x``, and ``c`` by
    :obj:`contacts` of positions) from the whole motion's positions,
    facing yaw and ground origin; the velocities and contacts read the
    frame before (none before frame 0: zero and the identity).

    Shapes:
        - **pos**: :math:`(T, J, 3)`; **theta**: :math:`(T,)`; **origin**: :math:`(T, 3)`
        - **output**: :math:`(F, J, C)` each, :math:`F` the frames of the slice
    """
    start, stop = frames.start, frames.stop
    lead = 1 if start else 0  # frames before the chunk read: one, for velocities
    inv = yaw_matrix_numpy(theta[start - lead:stop]).transpose(0, 2, 1)
    p = pos[start - lead:stop]
    local = motion.rotations[start - lead:stop].copy()
    local[:, 0] = inv @ motion.rotations[start - lead:stop, 0]
    prev = local[:-1] if lead else np.concatenate([local[:1], local[:-1]])
    disp = (p[1:] - p[:-1] if lead else
            np.concatenate([np.zeros_like(p[:1]), p[1:] - p[:-1]])) * motion.fps
    c = contacts(p)[lead:]
    inv, p, local = inv[lead:], p[lead:], local[lead:]
    x = np.einsum("tij,tkj->tki", inv, p - origin[frames, None])
    x_rel = np.einsum("tij,tkj->tki", inv,
                      p - p[:, np.maximum(motion.skeleton.parents, 0)])
    x_rel[:, 0] = x[:, 0]
    return {"q": _to_6d(local), "x": x, "x_rel": x_rel,
            "v_q": _to_6d(prev.transpose(0, 1, 3, 2) @ local),
            "v_x": np.einsum("tij,tkj->tki", inv, disp), "c": c}


def integrate_root(r: np.ndarray, fps: float) -> tuple:
    r"""Facing yaw :math:`(T,)` and ground origin :math:`(T, 3)` per frame
    from root features, starting from the world origin."""
    theta = np.cumsum(r[:, 0] / fps)
    prev_theta = np.concatenate([[0.0], theta[:-1]])
    local = np.stack([r[:, 1], np.zeros(len(r)), r[:, 2]], axis=1) / fps
    origin = np.cumsum(np.einsum("tij,tj->ti", yaw_matrix_numpy(prev_theta), local), axis=0)
    return theta, origin


def features_to_motion(
    features: MotionFeatures,
    q: Optional[np.ndarray] = None,
    r: Optional[np.ndarray] = None,
    skeleton: Optional[Skeleton] = None,
    use_positions: bool = True,
) -> Motion:
    r"""Rebuild a :class:`Motion` from features.

    Rotations come from ``q`` and the root trajectory from ``r`` (either may
    be given separately, e.g. a decoder's predictions); the other joints use
    their rest offsets, except joints with position channels, whose
    per-frame translations are recovered from ``x`` when
    :obj:`use_positions` is set (this makes the round trip lossless).

    Args:
        features (MotionFeatures): The features (and their skeleton, frame
            rate and canonical transform).
        q (np.ndarray, optional): 6D local rotations (default: the
            features' own).
        r (np.ndarray, optional): Root features (default: the features' own).
        skeleton (Skeleton, optional): The skeleton to rebuild on (default:
            the features').
        use_positions (bool, optional): Recover the translations of joints
            with position channels from ``x`` (only where :obj:`q` is the
            features' own).

    Returns:
        Motion: The motion, in the canonical frame the features were
        computed in.

    Shapes:
        - **q**: :math:`(T, J, 6)`, optional
        - **r**: :math:`(T, 4)`, optional
    """
    skel = skeleton or features.skeleton
    q = features.q if q is None else q
    r = features.r if r is None else r
    theta, origin = integrate_root(r, features.fps)
    face = yaw_matrix_numpy(theta)
    rot = rotation_6d_to_matrix(torch.from_numpy(np.asarray(q, np.float64))).numpy()
    rot[:, 0] = face @ rot[:, 0]
    trans = np.broadcast_to(skel.offsets, rot.shape[:2] + (3,)).copy()
    trans[:, 0] = origin + np.array([0.0, 1.0, 0.0]) * r[:, 3:4]
    motion = Motion(skel, rot, trans, fps=features.fps, transform=features.transform)
    moving = np.flatnonzero(skel.has_position_channels[1:]) + 1
    if use_positions and len(moving) and q is features.q:
        motion = _restore_translations(motion, features.x, face, origin, moving)
    return motion


def _restore_translations(motion: Motion, x: np.ndarray, face: np.ndarray,
                          origin: np.ndarray, joints: np.ndarray) -> Motion:
    """Local translations of :obj:`joints` from their positions ``x``."""
    glob_rot, _ = forward_kinematics(torch.from_numpy(motion.rotations),
                                     torch.from_numpy(motion.translations),
                                     torch.from_numpy(motion.skeleton.parents))
    glob_rot = glob_rot.numpy()
    pos = np.einsum("tij,tkj->tki", face, x) + origin[:, None]
    par = motion.skeleton.parents[joints]
    trans = motion.translations.copy()
    trans[:, joints] = np.einsum("tkji,tkj->tki", glob_rot[:, par],
                                 pos[:, joints] - pos[:, par])
    return motion.with_(translations=trans)
