"""Canonicalisation: +Y up, facing +Z and root xz at the origin at frame 0,
floor at y = 0, metres, one frame rate."""
from __future__ import annotations

import re
from typing import List, Optional, Tuple

import numpy as np
import torch

from satagraph.motion import CanonicalTransform, Motion
from satagraph.skeleton import Skeleton
from satagraph.ops.rotation import (matrix_to_quaternion, quaternion_slerp,
                                    quaternion_to_matrix)

_AXIS = {"+X": (0, 1.0), "-X": (0, -1.0), "+Y": (1, 1.0), "-Y": (1, -1.0),
         "+Z": (2, 1.0), "-Z": (2, -1.0)}
_Y_PRIOR = 1.5
_TOP = re.compile(r"head|neck|skull", re.I)
_BOTTOM = re.compile(r"foot|toe|paw|hoof|ankle|heel", re.I)
_SIDE = re.compile(r"(?i:left|right)|(?<![A-Za-z])[LRlr](?=[_.:\s]|$)"
                   r"|(?<![A-Za-z])[LR](?=[A-Z])")


def _axis_vector(axis: str) -> np.ndarray:
    i, sign = _AXIS[axis]
    vec = np.zeros(3)
    vec[i] = sign
    return vec


def _rotation_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rotation taking unit vector a onto unit vector b (Rodrigues)."""
    v, c = np.cross(a, b), float(np.dot(a, b))
    if c < -1 + 1e-9:  # opposite: half turn about any perpendicular axis
        axis = np.cross(a, [1.0, 0, 0])
        if np.linalg.norm(axis) < 1e-6:
            axis = np.cross(a, [0, 1.0, 0])
        axis /= np.linalg.norm(axis)
        return 2 * np.outer(axis, axis) - np.eye(3)
    k = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return np.eye(3) + k + k @ k / (1 + c)


def _first_pose(motion: Motion) -> np.ndarray:
    if motion.num_frames == 0:
        return motion.skeleton.rest_positions()
    return motion.slice(0, 1).global_positions()[0]


def _sample_poses(motion: Motion, count: int) -> np.ndarray:
    """Global positions of up to :obj:`count` evenly spaced frames."""
    if motion.num_frames == 0:
        return motion.skeleton.rest_positions()[None]
    idx = np.unique(np.linspace(0, motion.num_frames - 1, count).astype(int))
    sub = motion.with_(rotations=motion.rotations[idx],
                       translations=motion.translations[idx])
    return sub.global_positions()


def detect_up_axis(motion: Motion) -> str:
    r"""Guess the up axis of a motion (``"+Y"``, ``"-Z"``, ...).

    Uses up to 16 frames spread over the clip (or the rest pose for a
    skeleton without frames). With foot-like joints (foot, toe, paw, hoof, ankle, heel): the signed
    axis along which those joints lie furthest below the median joint,
    relative to the pose's extent (feet are at the bottom of a standing
    human or quadruped, but spread front to back). Without them: the axis of
    largest extent, signed towards the side of the head-like joints or the
    root. Y gets a 1.5x prior, as most BVH files are Y-up. Override it where the guess is wrong.
    """
    pos = _first_pose(motion)
    names = motion.skeleton.names
    bottom = [i for i, n in enumerate(names) if _BOTTOM.search(n)]
    extent = np.maximum(np.ptp(pos, axis=0), 1e-9)
    if bottom:
        poses = _sample_poses(motion, 16)
        med = np.median(poses, axis=1)
        spread = np.maximum(np.ptp(poses, axis=1), 1e-9)
        score = ((med - poses[:, bottom].mean(1)) / spread).mean(0)
        prior = np.array([1.0, _Y_PRIOR, 1.0])  # BVH files are mostly +Y up
        i = int(np.argmax(np.abs(score) * prior))
        return ("+" if score[i] >= 0 else "-") + "XYZ"[i]
    i = int(np.argmax(extent))
    top = [k for k, n in enumerate(names) if _TOP.search(n)] or [0]
    side = pos[top, i].mean() - 0.5 * (pos[:, i].max() + pos[:, i].min())
    return ("+" if side >= 0 else "-") + "XYZ"[i]


def _side(name: str) -> Optional[str]:
    """'L' or 'R' for names with a side marker, else None; the stem is the
    name with the marker removed."""
    match = _SIDE.search(name)
    if not match:
        return None
    return "L" if match.group(0).strip("_.").lower().startswith("l") else "R"


def _lateral_pairs(names: List[str]) -> Tuple[List[int], List[int]]:
    """Indices of left joints and their right counterparts (matched by the
    name with the side marker removed)."""
    stems = {}
    for i, name in enumerate(names):
        side = _side(name)
        if side:
            stem = _SIDE.sub("", name, count=1).lower()
            stems.setdefault(stem, {})[side] = i
    pairs = [(d["L"], d["R"]) for d in stems.values() if "L" in d and "R" in d]
    return [p[0] for p in pairs], [p[1] for p in pairs]


def lateral_forward(positions: np.ndarray, names: List[str],
                    up: np.ndarray) -> Optional[np.ndarray]:
    r"""Forward direction ``across x up`` with ``across`` the mean of
    left - right over the joint pairs found by name (not normalised);
    ``None`` for a skeleton without such pairs.

    Shapes:
        - **positions**: :math:`(..., J, 3)`
        - **output**: :math:`(..., 3)`
    """
    left, right = _lateral_pairs(names)
    if not left:
        return None
    across = (positions[..., left, :] - positions[..., right, :]).mean(-2)
    return np.cross(across, up)


def detect_forward(motion: Motion, up: np.ndarray) -> np.ndarray:
    r"""Horizontal facing direction at frame 0 (unit vector, world axes).

    From left/right joint pairs found by name (``Left*``/``Right*``, ``L_``,
    ``.L``, ``_r``, ...): forward = across x up with across = left - right.
    Falls back to the root's local +Z axis.
    """
    forward = lateral_forward(_first_pose(motion), motion.skeleton.names, up)
    if forward is None or np.linalg.norm(forward - up * forward.dot(up)) < 1e-8:
        root = motion.rotations[0, 0] if motion.num_frames else np.eye(3)
        forward = root[:, 2]
    forward = forward - up * forward.dot(up)
    norm = np.linalg.norm(forward)
    return forward / norm if norm > 1e-8 else _orthogonal(up)


def _orthogonal(up: np.ndarray) -> np.ndarray:
    other = np.array([0.0, 0, 1]) if abs(up[2]) < 0.9 else np.array([1.0, 0, 0])
    vec = other - up * other.dot(up)
    return vec / np.linalg.norm(vec)


def detect_unit_scale(height: float) -> float:
    r"""Factor from file units to metres, guessed from the character height
    in file units: centimetres above 30, CMU units (0.0564 m) from 5 to 30,
    metres below 5."""
    if height > 30:
        return 0.01
    if height > 5:
        return 0.056444
    return 1.0


def remove_static_root(motion: Motion) -> Tuple[Motion, Optional[dict]]:
    r"""Fold a motionless root with a single child into that child.

    Some rigs put a fixed helper joint (``joint_Root``, ``RL_BoneRoot``) above
    the moving hips. Global positions of the remaining joints are unchanged.

    Returns:
        The motion, and a description of the removed root (name, channels,
        offset, constant rotation and translation) or ``None``.
    """
    skel = motion.skeleton
    if motion.num_frames < 2 or skel.num_joints < 2 or len(skel.children[0]) != 1:
        return motion, None
    rot0, trans0 = motion.rotations[:, 0], motion.translations[:, 0]
    if np.ptp(rot0, axis=0).max() > 1e-9 or np.ptp(trans0, axis=0).max() > 1e-9:
        return motion, None
    child = skel.children[0][0]
    rot = motion.rotations[:, 1:].copy()
    trans = motion.translations[:, 1:].copy()
    rot[:, child - 1] = rot0 @ motion.rotations[:, child]
    trans[:, child - 1] = trans0 + np.einsum("tij,tj->ti", rot0,
                                             motion.translations[:, child])
    sub = skel.subset(range(1, skel.num_joints))
    offsets = sub.offsets.copy()
    offsets[0] = trans[0, 0]
    removed = {"name": skel.names[0], "channels": skel.channels[0],
               "offset": skel.offsets[0].copy(), "rotation": rot0[0].copy(),
               "translation": trans0[0].copy()}
    return motion.with_(skeleton=sub.replace(offsets=offsets), rotations=rot,
                        translations=trans), removed


def resample(motion: Motion, fps: float) -> Motion:
    r"""Resample to :obj:`fps` frames per second: slerp for rotations, linear
    interpolation for translations. The first frame is kept; the last new
    frame is at or before the last old frame."""
    if abs(motion.fps - fps) < 1e-9 or motion.num_frames < 2:
        return motion.with_(fps=fps)
    count = int(np.floor((motion.num_frames - 1) * fps / motion.fps + 1e-9)) + 1
    src = np.arange(count) * (motion.fps / fps)
    lo = np.minimum(np.floor(src).astype(np.int64), motion.num_frames - 2)
    w = src - lo
    quat = matrix_to_quaternion(torch.from_numpy(motion.rotations))
    wt = torch.from_numpy(w)[:, None].expand(count, motion.num_joints)
    q = quaternion_slerp(quat[lo], quat[lo + 1], wt)
    rot = quaternion_to_matrix(q).numpy()
    t0, t1 = motion.translations[lo], motion.translations[lo + 1]
    trans = t0 + w[:, None, None] * (t1 - t0)
    return motion.with_(rotations=rot, translations=trans, fps=float(fps))


def canonicalize(
    motion: Motion,
    fps: Optional[float] = 30.0,
    up_axis: Optional[str] = None,
    unit_scale: Optional[float] = None,
    floor: bool = True,
    remove_root: bool = True,
) -> Motion:
    r"""Bring a motion into the canonical frame used by the features.

    +Y up (detected unless :obj:`up_axis` is given), the character facing +Z
    and its root at x = z = 0 at frame 0, the floor (a low percentile of the
    per-frame lowest joint) at y = 0, metres (guessed from the height unless
    :obj:`unit_scale` is given), :obj:`fps` frames per second (``None``
    keeps the source rate). The returned motion's :attr:`~Motion.transform`
    records what was done; :func:`decanonicalize` undoes it.
    """
    motion, removed = (remove_static_root(motion) if remove_root
                       else (motion, None))
    up_name = (up_axis or detect_up_axis(motion)).upper()
    if up_name not in _AXIS:
        raise ValueError(f"up_axis must be one of {sorted(_AXIS)}, got {up_axis!r}")
    up_rot = _rotation_between(_axis_vector(up_name), np.array([0.0, 1.0, 0.0]))
    moved = _apply_rotation(motion, up_rot, 1.0, np.zeros(3))
    forward = detect_forward(moved, np.array([0.0, 1.0, 0.0]))
    yaw = float(np.arctan2(-forward[0], forward[2]))  # rotate forward onto +Z
    scale = unit_scale or detect_unit_scale(moved.height())
    transform = CanonicalTransform(up_axis=up_name, up_rotation=up_rot, yaw=yaw,
                                   scale=scale, source_fps=motion.fps,
                                   removed_root=removed)
    out = _apply_rotation(motion, transform.rotation, scale, np.zeros(3))
    shift = np.zeros(3)
    if out.num_frames:
        shift[[0, 2]] = -out.translations[0, 0, [0, 2]]
        if floor:
            lowest = out.global_positions()[:, :, 1].min(axis=1)
            shift[1] = -float(np.percentile(lowest, 2))
    transform.translation = shift
    out = out.with_(translations=_shift_root(out.translations, shift))
    out.transform = transform
    return resample(out, fps) if fps else out


def _shift_root(translations: np.ndarray, shift: np.ndarray) -> np.ndarray:
    out = translations.copy()
    out[:, 0] += shift
    return out


def _apply_rotation(motion: Motion, rot: np.ndarray, scale: float,
                    shift: np.ndarray) -> Motion:
    """p' = scale * rot @ p + shift applied to the whole motion."""
    rotations = motion.rotations.copy()
    rotations[:, 0] = rot @ rotations[:, 0]
    trans = motion.translations * scale
    trans[:, 0] = trans[:, 0] @ rot.T + shift
    skel = motion.skeleton
    offsets = skel.offsets * scale
    offsets[0] = offsets[0] @ rot.T
    return motion.with_(skeleton=skel.replace(offsets=offsets),
                        rotations=rotations, translations=trans)


def decanonicalize(motion: Motion, transform: Optional[CanonicalTransform] = None,
                   fps: Optional[float] = None) -> Motion:
    r"""Undo :func:`canonicalize`: back to the source's axes, units, frame
    rate (unless :obj:`fps` is given) and, where one was removed, the
    motionless root joint."""
    tf = transform or motion.transform
    if tf is None:
        return motion
    back = _apply_rotation(motion.with_(
        translations=_shift_root(motion.translations, -tf.translation)),
        tf.rotation.T, 1.0 / tf.scale, np.zeros(3))
    back.transform = None
    back = resample(back, fps or tf.source_fps)
    if tf.removed_root is not None:
        back = _restore_root(back, tf.removed_root)
    return back


def _restore_root(motion: Motion, removed: dict) -> Motion:
    """Put the motionless root removed by :func:`remove_static_root` back."""
    skel = motion.skeleton
    num_frames = motion.num_frames
    rot0, trans0 = removed["rotation"], removed["translation"]
    rotations = motion.rotations.copy()
    translations = motion.translations.copy()
    rotations[:, 0] = rot0.T @ rotations[:, 0]
    translations[:, 0] = (translations[:, 0] - trans0) @ rot0
    rot = np.concatenate([np.broadcast_to(rot0, (num_frames, 1, 3, 3)),
                          rotations], axis=1)
    trans = np.concatenate([np.broadcast_to(trans0, (num_frames, 1, 3)),
                            translations], axis=1)
    offsets = np.concatenate([removed["offset"][None], skel.offsets])
    new = Skeleton(names=[removed["name"]] + skel.names,
                   parents=np.concatenate([[-1, 0], skel.parents[1:] + 1]),
                   offsets=offsets, channels=[removed["channels"]] + skel.channels,
                   end_site=np.concatenate([[False], skel.end_site]))
    return motion.with_(skeleton=new, rotations=rot, translations=trans)
