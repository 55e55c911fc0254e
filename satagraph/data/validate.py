r"""Checks that a motion is fit for training and inference.

A BVH file can be well-formed and still poison a model: ``Frames: 0``, a
frame rate typed into ``Frame Time`` (``Frame Time: 30``: one frame every
30 s, whose resampling to 30 fps asks for terabytes), a skeleton whose
offsets are all zero, one frame with the root at ``1e30``. :func:`check_motion`
refuses such files with one line saying what is wrong, before any
resampling; :func:`check_features` is the last check on the features.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Tuple

import numpy as np

from satagraph.motion import Motion


class MotionValidationError(ValueError):
    """A motion unfit for training or inference; the message names the
    file and the reason in one line."""


@dataclass(frozen=True)
class MotionLimits:
    r"""What :func:`check_motion` accepts.

    Args:
        min_frames (int): Fewest frames (velocities need two).
        min_fps (float): Lowest frame rate.
        max_fps (float): Highest frame rate.
        max_duration (float): Longest clip (seconds).
        max_joint_frames (float): Most joints x frames after resampling
            (bounds the memory of resampling and features).
        max_bone_ratio (float): Longest bone over the median bone length.
        max_travel (float): Farthest a joint with position channels may be
            from its offset, in skeleton sizes.
        max_angle (float): Largest Euler angle (degrees; unwrapped angles
            of long spinning clips stay far below).
    """

    min_frames: int = 2
    min_fps: float = 1.0
    max_fps: float = 1000.0
    max_duration: float = 2 * 3600.0
    max_joint_frames: float = 3e7
    max_bone_ratio: float = 1e4
    max_travel: float = 1e4
    max_angle: float = 1e7


DEFAULT_LIMITS = MotionLimits()


def default_windows(module, window: Optional[int] = None,
                    overlap: Optional[int] = None) -> Tuple[int, int]:
    """The window the module was trained on (``meta["window"]``, else 64)
    and a quarter of it as overlap, unless given (:obj:`module` is not read
    where :obj:`window` is given)."""
    if window is None:
        window = int((getattr(module, "meta", None) or {}).get("window", 64))
    return window, window // 4 if overlap is None else overlap


def check_windows(window: int, overlap: int) -> None:
    """Refuse windows of :obj:`window` frames sharing :obj:`overlap` that
    plan nothing (one line): a window needs at least 1 frame and its overlap
    0 to ``window - 1``."""
    if window < 1 or not 0 <= overlap < window:
        raise ValueError(f"windows of {window} frames sharing {overlap}: a window needs at "
                         f"least 1 frame and its overlap 0 to window - 1 frames")


def skeleton_size(motion: Motion) -> float:
    """The largest extent of the rest pose along any axis (file units)."""
    rest = motion.skeleton.rest_positions()
    return float(np.ptp(rest, axis=0).max()) if len(rest) else 0.0


def _error(path: str, message: str) -> MotionValidationError:
    return MotionValidationError(f"{path}: {message}")


def check_timing(motion: Motion, path: str, fps: Optional[float] = None,
                 limits: MotionLimits = DEFAULT_LIMITS) -> None:
    """Frame count, frame rate and duration; with :obj:`fps`, the size of
    the motion resampled to it.

    Raises:
        MotionValidationError: One line naming :obj:`path`.
    """
    if motion.num_frames < limits.min_frames:
        raise _error(path, f"{motion.num_frames} frame(s): at least "
                     f"{limits.min_frames} are needed")
    check_resample(motion, path, fps, limits)


def check_resample(motion: Motion, path: str, fps: Optional[float] = None,
                   limits: MotionLimits = DEFAULT_LIMITS) -> None:
    """Frame rate range, duration, and the size of the motion resampled to
    :obj:`fps` (the memory resampling needs), whatever the frame count.

    Raises:
        MotionValidationError: One line naming :obj:`path`.
    """
    rate = float(motion.fps)
    if not (limits.min_fps <= rate <= limits.max_fps):
        raise _error(path, f"frame rate {rate:.4g} fps (Frame Time: {1 / rate:.6g} s) "
                     f"is outside {limits.min_fps:g}-{limits.max_fps:g} fps; 'Frame "
                     "Time' is the seconds per frame (0.0333333 for 30 fps), not "
                     "the frame rate")
    duration = motion.num_frames / rate
    if duration > limits.max_duration:
        raise _error(path, f"{duration:.3g} s long (Frame Time: {1 / rate:.6g} s); at "
                     f"most {limits.max_duration:.0f} s are accepted")
    frames = duration * (fps or rate)
    if frames * motion.num_joints > limits.max_joint_frames:
        raise _error(path, f"{motion.num_joints} joints x {frames:.0f} frames "
                     f"{'at ' + format(fps, 'g') + ' fps ' if fps else ''}is more "
                     f"than the {limits.max_joint_frames:.0e} joint-frames accepted")


def check_skeleton(motion: Motion, path: str,
                   limits: MotionLimits = DEFAULT_LIMITS) -> float:
    """A skeleton that is not degenerate and has no absurd bone; returns
    its size (:func:`skeleton_size`).

    Raises:
        MotionValidationError: One line naming :obj:`path`.
    """
    skel = motion.skeleton
    size = skeleton_size(motion)
    if skel.num_joints < 2 or not size > 0:
        raise _error(path, "degenerate skeleton: every joint has the same rest "
                     "position (all OFFSETs are zero)" if skel.num_joints > 1
                     else "a skeleton needs at least two joints")
    lengths = np.linalg.norm(skel.offsets[1:], axis=1)
    median = float(np.median(lengths[lengths > 0]))
    worst = int(np.argmax(lengths))
    if lengths[worst] > limits.max_bone_ratio * median:
        raise _error(path, f"implausible OFFSET of joint {skel.names[worst + 1]!r}: "
                     f"length {lengths[worst]:.3g} is {lengths[worst] / median:.2g} "
                     "times the median bone")
    return size


def check_values(motion: Motion, path: str, size: float,
                 limits: MotionLimits = DEFAULT_LIMITS) -> None:
    """Finite channel values of plausible magnitude: positions within
    ``max_travel`` skeleton sizes, angles below ``max_angle``.

    Raises:
        MotionValidationError: One line naming :obj:`path`.
    """
    skel = motion.skeleton
    moving = np.flatnonzero(skel.has_position_channels)
    if moving.size:
        trans = motion.translations[:, moving]
        if not np.isfinite(trans).all():
            raise _error(path, "non-finite joint positions")
        dist = np.abs(trans - skel.offsets[moving]).max(axis=(1, 2))
        frame = int(np.argmax(dist))
        if dist[frame] > limits.max_travel * size:
            raise _error(path, f"implausible position at frame {frame}: "
                         f"{dist[frame]:.3g} from the rest offset, "
                         f"{dist[frame] / size:.2g} times the skeleton's size "
                         f"({size:.3g})")
    if not np.isfinite(motion.rotations).all():
        raise _error(path, "non-finite rotations")
    raw = motion.raw_channels
    if raw is not None and raw.size:
        columns = [c.endswith("rotation") for chans in skel.channels for c in chans]
        angles = raw[:, np.asarray(columns, dtype=bool)] if len(columns) == raw.shape[1] \
            else raw[:, :0]
        if angles.size and np.abs(angles).max() > limits.max_angle:
            frame = int(np.argmax(np.abs(angles).max(axis=1)))
            raise _error(path, f"implausible rotation angle at frame {frame}: "
                         f"{np.abs(angles[frame]).max():.3g} degrees")


def check_motion(motion: Motion, path: Optional[str] = None, fps: Optional[float] = None,
                 limits: MotionLimits = DEFAULT_LIMITS) -> None:
    """Every check of this module: timing (and the size once resampled to
    :obj:`fps`), skeleton, values.

    Args:
        motion (Motion): The motion as read.
        path (str, optional): The file (default: the motion's source).
        fps (float, optional): The rate it will be resampled to.
        limits (MotionLimits): What is accepted.

    Raises:
        MotionValidationError: One line naming the file and the reason.
    """
    path = path or motion.source or "<motion>"
    check_timing(motion, path, fps, limits)
    size = check_skeleton(motion, path, limits)
    check_values(motion, path, size, limits)


def check_writable(motion: Motion, path: Optional[str] = None) -> None:
    """A rig that motion can be written onto: a root with channels (the
    root's motion goes into them), checked before any work is done on it.

    Raises:
        MotionValidationError: One line naming the file.
    """
    skel = motion.skeleton
    if skel.num_joints and not skel.channels[0]:
        built = "" if path or motion.source else (
            " (a Skeleton built in code: give it channels, e.g. ('Xposition', 'Yposition', "
            "'Zposition', 'Zrotation', 'Xrotation', 'Yrotation') for the root and the "
            "three rotations for every other joint)")
        raise _error(path or motion.source or "<motion>",
                     f"its root joint {skel.names[0]!r} has no CHANNELS, so no motion can be "
                     f"written onto this rig{built}")


def check_features(feats, path: str) -> None:
    """Finite features and a positive height (the last check before a
    file's features are cached or trained on).

    Raises:
        MotionValidationError: One line naming :obj:`path`.
    """
    if not (np.isfinite(feats.height) and feats.height > 0):
        raise _error(path, f"character height {feats.height:.3g} after "
                     "canonicalisation: the skeleton is degenerate, or read with the "
                     "wrong up axis (--up-axis sets it)")
    for name in ("q", "x", "x_rel", "v_q", "v_x", "r", "c", "x_local", "x_global"):
        if not np.isfinite(getattr(feats, name)).all():
            raise _error(path, f"non-finite features ({name}) after preprocessing")


def check_shown_body(target: Motion) -> None:
    """A target without frames, or whose every frame is its rest pose (a
    rig exported at rest), whose rest is a line
    (:func:`~satagraph.transforms.rest.is_line_rest`) shows the model no
    body: no pose to stand it in, no up axis to read (Bandai's rig without
    its frames came out 77 cm tall for 131, hovering 24 cm, or lying along
    -Z and 34 cm under the floor; a Bandai walk onto
    the dog's rig in one frame at rest walked on its hind legs, steps
    +0.45, and carried as that frame lay flat, steps +0.06).

    Raises:
        MotionValidationError: One line naming the target.
    """
    from satagraph.transforms.rest import is_line_rest
    if is_line_rest(target.skeleton) and np.allclose(target.rotations, np.eye(3)):
        shown = "shown only at rest" if target.num_frames else "without frames"
        raise MotionValidationError(
            f"{target.source or '<target>'}: a rig {shown} whose rest pose is a line "
            "(every bone along one axis, as Bandai's and the dog's files write it) shows no "
            "body to put a motion on: give a clip of it (a file with frames that pose it)")


__all__ = ["MotionValidationError", "MotionLimits", "DEFAULT_LIMITS", "check_motion",
           "check_writable", "check_shown_body",
           "check_timing", "check_resample", "check_skeleton", "check_values", "check_features",
           "skeleton_size", "default_windows", "check_windows"]
