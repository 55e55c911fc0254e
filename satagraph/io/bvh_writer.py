"""BVH writer: standard HIERARCHY/MOTION layout, atomic replacement."""
from __future__ import annotations

import os
import stat
import tempfile
from typing import List, Union

import numpy as np
import torch

from satagraph.motion import Motion
from satagraph.ops.rotation import matrix_to_euler

PathLike = Union[str, "os.PathLike[str]"]


def _fmt(values: np.ndarray) -> str:
    return " ".join(f"{v:.6f}" for v in values)


def _hierarchy(motion: Motion) -> List[str]:
    skel = motion.skeleton
    lines = ["HIERARCHY"]

    def visit(j: int, depth: int) -> None:
        pad = "  " * depth
        if skel.end_site[j] and not skel.children[j] and not skel.channels[j]:
            lines.extend([f"{pad}End Site", f"{pad}{{",
                          f"{pad}  OFFSET {_fmt(skel.offsets[j])}", f"{pad}}}"])
            return
        kind = "ROOT" if j == 0 else "JOINT"
        lines.extend([f"{pad}{kind} {skel.names[j]}", f"{pad}{{",
                      f"{pad}  OFFSET {_fmt(skel.offsets[j])}"])
        if skel.channels[j]:
            lines.append(f"{pad}  CHANNELS {len(skel.channels[j])} "
                         + " ".join(skel.channels[j]))
        for c in skel.children[j]:
            visit(c, depth + 1)
        lines.append(f"{pad}}}")

    visit(0, 0)
    return lines


def channel_values(motion: Motion) -> np.ndarray:
    r"""The motion as BVH channel values (Euler angles in degrees, unwrapped
    over time, and positions), in the skeleton's channel layout.

    Shapes:
        - **output**: :math:`(T, C)`
    """
    skel = motion.skeleton
    if motion.raw_channels is not None and motion.raw_channels.shape == (
            motion.num_frames, skel.num_channels):
        return motion.raw_channels
    columns = []
    for j, chans in enumerate(skel.channels):
        order = skel.rotation_orders[j]
        euler = None
        if order:
            rot = np.array(motion.rotations[:, j])  # writable copy for torch
            rad = matrix_to_euler(torch.from_numpy(rot), order)
            euler = np.degrees(np.unwrap(rad.numpy(), axis=0))
        for c in chans:
            if c.endswith("position"):
                columns.append(motion.translations[:, j, "XYZ".index(c[0])])
            else:
                columns.append(euler[:, order.index(c[0])])
    if not columns:
        return np.zeros((motion.num_frames, 0))
    return np.stack(columns, axis=1)


def _file_mode(path: str) -> int:
    """Permissions for the output: those of the file being replaced, else
    the default for new files (0666 less the umask)."""
    try:
        return stat.S_IMODE(os.stat(path).st_mode)
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def declaration(motion: Motion) -> str:
    """The trailing line by which a canonical file declares its up axis and
    units (empty for other motions): readers of this package then never
    re-guess them; other readers stop after the declared frames."""
    rig = motion.rig
    if rig is None or not rig.declared or rig.up_axis is None or rig.scale is None:
        return ""
    return f"# satagraph: canonical up_axis={rig.up_axis} scale={float(rig.scale):g}\n"


def write_bvh(motion: Motion, path: PathLike, precision: int = 6) -> None:
    r"""Write a motion as a BVH file.

    The file is written to a temporary file beside :obj:`path` and moved into
    place only when complete, so a failure never leaves a partial file.

    Args:
        motion (Motion): The motion; joints flagged as end sites with no
            children and no channels are written as ``End Site`` blocks.
        path (str or PathLike): Output path.
        precision (int, optional): Decimals per channel value (at least 6).
    """
    path = os.fspath(path)
    if motion.skeleton.num_joints and not motion.skeleton.channels[0]:
        raise ValueError(f"{path}: the root joint needs channels to be written")
    values = channel_values(motion)
    header = _hierarchy(motion)
    header += ["MOTION", f"Frames: {motion.num_frames}",
               f"Frame Time: {1.0 / motion.fps:.8f}"]
    directory = os.path.dirname(os.path.abspath(path))
    mode = _file_mode(path)
    fd, tmp = tempfile.mkstemp(prefix=".tmp-", suffix=".bvh", dir=directory)
    try:
        with os.fdopen(fd, "w", newline="\n") as f:
            os.fchmod(f.fileno(), mode)  # mkstemp makes 0600 files
            f.write("\n".join(header) + "\n")
            if values.size:
                np.savetxt(f, values, fmt=f"%.{max(precision, 6)}f")
            f.write(declaration(motion))
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
