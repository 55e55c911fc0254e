"""BVH writer: standard HIERARCHY/MOTION layout, atomic replacement."""
from __future__ import annotations

import os
from typing import Dict, List, Tuple, Union

import numpy as np
import torch

from satagraph.utils.files import atomic_write
from satagraph.motion import Motion
from satagraph.ops.rotation import unit_quaternion_to_euler
from satagraph.ops.rotation_numpy import matrix_to_quaternion_numpy

PathLike = Union[str, "os.PathLike[str]"]


#: How values read from a file are written back: every decimal of up to 15
#: significant digits (any exporter's) comes back digit for digit.
EXACT = "%.15g"


def _fmt(values: np.ndarray, tiny: float = 0.0) -> str:
    """An OFFSET's numbers without exponents, six decimals at least (a
    tenth of a micron is not rounded to a bone of length zero), to 15
    significant digits (any file's value comes back digit for digit, and
    the last bits of arithmetic go: ``-17.822200000000006`` is
    ``-17.8222``); below :obj:`tiny` a value is zero (``-6.3e-23`` from
    turning a zero)."""
    return " ".join(np.format_float_positional(0.0 if abs(v) < tiny else float(EXACT % v),
                                               unique=True, min_digits=6) for v in values)


def _hierarchy(motion: Motion) -> Tuple[List[str], List[int]]:
    """The HIERARCHY lines, by an explicit depth-first walk (no recursion:
    any depth), and the joints in the order they are written: a skeleton's
    own order need only list parents first (a joint inserted after its
    siblings' subtrees), and the MOTION columns follow this one."""
    skel = motion.skeleton
    tiny = 1e-12 * float(np.abs(skel.offsets).max(initial=0.0))  # arithmetic's zero
    lines, order = ["HIERARCHY"], []
    children = skel.children
    stack = [(0, 0, False)]  # (joint, depth, closing)
    while stack:
        j, depth, closing = stack.pop()
        pad = "  " * depth
        if closing:
            lines.append(f"{pad}}}")
            continue
        order.append(j)
        if skel.end_site[j] and not children[j] and not skel.channels[j]:
            lines.extend([f"{pad}End Site", f"{pad}{{",
                          f"{pad}  OFFSET {_fmt(skel.offsets[j], tiny)}", f"{pad}}}"])
            continue
        kind = "ROOT" if j == 0 else "JOINT"
        lines.extend([f"{pad}{kind} {skel.names[j]}", f"{pad}{{",
                      f"{pad}  OFFSET {_fmt(skel.offsets[j], tiny)}"])
        if skel.channels[j]:
            lines.append(f"{pad}  CHANNELS {len(skel.channels[j])} "
                         + " ".join(skel.channels[j]))
        stack.append((j, depth, True))
        stack.extend((c, depth + 1, False) for c in reversed(children[j]))
    return lines, order


def _check_finite(motion: Motion, values: np.ndarray, path: str) -> None:
    """Refuse non-finite offsets, channel values or frame rate (a diverged
    model's output): one line naming the file and the first bad value."""
    skel = motion.skeleton
    if not (np.isfinite(motion.fps) and motion.fps > 0):
        raise ValueError(f"{path}: refusing to write a frame rate of {motion.fps}")
    bad = ~np.isfinite(skel.offsets)
    if bad.any():
        j = int(np.argwhere(bad)[0, 0])
        raise ValueError(f"{path}: refusing to write non-finite values: OFFSET of "
                         f"joint {skel.names[j]!r}")
    bad = ~np.isfinite(values)
    if bad.any():
        frame, column = (int(v) for v in np.argwhere(bad)[0])
        joint = int(np.searchsorted(np.cumsum([len(c) for c in skel.channels]),
                                    column, side="right"))
        raise ValueError(f"{path}: refusing to write non-finite values: "
                         f"{int(bad.sum())} of {values.size} channel values (first: "
                         f"frame {frame}, joint {skel.names[joint]!r}); the motion "
                         "is broken (a diverged model?)")


#: Frames whose Euler angles :func:`_euler_radians` computes at once (a
#: multiple of 64: every chunk a whole number of SIMD lanes).
EULER_FRAMES = 4096
#: Joint tracks :func:`_euler_degrees` unwraps at once.
EULER_JOINTS = 8


def _euler_degrees(motion: Motion) -> Dict[int, np.ndarray]:
    r"""Each rotating joint's Euler angles in degrees, in its own rotation
    order and unwrapped over time; the joints of one order are converted
    together.

    Shapes:
        - **output**: joint index -> :math:`(T, 3)`
    """
    orders = motion.skeleton.rotation_orders
    out: Dict[int, np.ndarray] = {}
    for order in sorted({o for o in orders if o}):
        joints = [j for j, o in enumerate(orders) if o == order]
        rad = _euler_radians(motion.rotations, joints, order)
        for start in range(0, len(joints), EULER_JOINTS):  # unwrapped a few tracks at a time
            group = slice(start, start + EULER_JOINTS)
            deg = np.degrees(np.unwrap(rad[:, group], axis=0))
            out.update({j: deg[:, k] for k, j in enumerate(joints[group])})
    return out


def _euler_radians(rotations: np.ndarray, joints: List[int], order: str) -> np.ndarray:
    r"""Euler angles (radians, not unwrapped) of :obj:`joints`' rotations in
    one rotation order, :data:`EULER_FRAMES` frames at a time: the
    conversion's temporaries are those of a chunk of frames (a whole
    number of SIMD lanes per chunk: the same values as all at once).

    Shapes:
        - **rotations**: :math:`(T, J, 3, 3)`
        - **output**: :math:`(T, J', 3)`, :math:`J'` the joints given
    """
    out = np.empty((len(rotations), len(joints), 3))
    for start in range(0, len(rotations), EULER_FRAMES):
        part = slice(start, start + EULER_FRAMES)
        quat = matrix_to_quaternion_numpy(rotations[part][:, joints])  # matrix_to_euler's
        out[part] = unit_quaternion_to_euler(torch.from_numpy(quat), order).numpy()
    return out


def raw_channels_hold(motion: Motion, atol: float = 1e-9) -> bool:
    """Whether the motion's channel values as read (:attr:`Motion.raw_channels`)
    still say what it holds: rotations and translations unchanged since
    (an edit in place, or a :func:`dataclasses.replace`, leaves the values
    of the file behind)."""
    raw = motion.raw_channels
    if raw is None or raw.shape != (motion.num_frames, motion.skeleton.num_channels):
        return False
    from satagraph.io.bvh_reader import channel_transforms
    rot, trans = channel_transforms(motion.skeleton, raw)
    return (np.allclose(rot, motion.rotations, rtol=0.0, atol=atol)
            and np.allclose(trans, motion.translations, rtol=1e-12, atol=atol))


def channel_values(motion: Motion) -> np.ndarray:
    r"""The motion as BVH channel values (Euler angles in degrees, unwrapped
    over time, and positions), in the skeleton's channel layout: the values
    as read where they still hold (:func:`raw_channels_hold`).

    Args:
        motion (Motion): The motion.

    Returns:
        np.ndarray: One row of channel values per frame.

    Shapes:
        - **output**: :math:`(T, C)`
    """
    skel = motion.skeleton
    if raw_channels_hold(motion):
        return motion.raw_channels
    euler, columns = _euler_degrees(motion), []
    for j, chans in enumerate(skel.channels):
        order = skel.rotation_orders[j]
        for c in chans:
            if c.endswith("position"):
                columns.append(motion.translations[:, j, "XYZ".index(c[0])])
            else:
                columns.append(euler[j][:, order.index(c[0])])
    if not columns:
        return np.zeros((motion.num_frames, 0))
    return np.stack(columns, axis=1)


def declaration(motion: Motion) -> str:
    """The comment by which a file declares how it is to be read, written
    after ``HIERARCHY`` on its line (empty where nothing is declared):
    ``canonical up_axis=+Y scale=1`` for a canonical motion, the up axis
    and units of the rig it was put on for a retargeted or reconstructed
    one (no scale where the units are the file's own). Readers of this
    package then never re-guess them; other readers (Blender's, bvhio)
    look no further than ``HIERARCHY`` on that line, where a line after
    the frames failed Blender's import, which reads every line to the end
    as a frame."""
    rig = motion.rig
    if rig is None or not rig.declared or rig.up_axis is None:
        return ""
    scale = "" if rig.scale is None else f" scale={float(rig.scale):g}"
    canonical = "canonical " if rig.up_axis == "+Y" and scale == " scale=1" else ""
    return f"# satagraph: {canonical}up_axis={rig.up_axis}{scale}"


def write_bvh(motion: Motion, path: PathLike, precision: int = 6) -> None:
    r"""Write a motion as a BVH file.

    The file is written to a temporary file beside :obj:`path` and moved into
    place only when complete (:func:`~satagraph.utils.files.atomic_write`), so
    a failure never leaves a partial file. Non-finite values are refused.

    Args:
        motion (Motion): The motion; joints flagged as end sites with no
            children and no channels are written as ``End Site`` blocks.
        path (str or PathLike): Output path.
        precision (int, optional): Decimals per computed channel value (at
            least 6); values as read from a file that still hold are written
            back exactly (:func:`raw_channels_hold`).

    Raises:
        ValueError: A non-finite offset, channel value or frame rate, or a
            root without channels (the message names :obj:`path`).
        OSError: The file cannot be written (names :obj:`path`).
    """
    path = os.fspath(path)
    if motion.skeleton.num_joints and not motion.skeleton.channels[0]:
        raise ValueError(f"{path}: the root joint needs channels to be written")
    values = channel_values(motion)
    exact = values is motion.raw_channels
    _check_finite(motion, values, path)
    header, order = _hierarchy(motion)
    if order != sorted(order):  # the columns in the order the joints are written
        channels = motion.skeleton.channels
        spans = np.split(np.arange(values.shape[1]), np.cumsum([len(c) for c in channels]))
        values = values[:, np.concatenate([spans[j] for j in order])]
    header[0] = f"{header[0]} {declaration(motion)}".rstrip()
    header += ["MOTION", f"Frames: {motion.num_frames}",
               f"Frame Time: {1.0 / motion.fps:.10g}"]

    def write(f) -> None:
        f.write("\n".join(header) + "\n")
        if values.size:
            np.savetxt(f, values, fmt=EXACT if exact else f"%.{max(precision, 6)}f")

    atomic_write(path, write, newline="\n")
