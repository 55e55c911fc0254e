"""BVH reader for any dialect: channel layouts, rotation orders, line endings."""
from __future__ import annotations

import io
import os
import re
import warnings
from dataclasses import dataclass, field
from typing import List, Optional, Tuple, Union

import numpy as np

from satagraph.io.errors import BVHError
from satagraph.motion import Motion
from satagraph.skeleton import Skeleton

PathLike = Union[str, "os.PathLike[str]"]

_CHANNELS = {f"{a}{k}".lower(): f"{a}{k}" for a in "XYZ"
             for k in ("position", "rotation")}


@dataclass
class _Joint:
    name: str
    parent: int
    line: int
    offset: Optional[np.ndarray] = None
    channels: Tuple[str, ...] = ()
    end_site: bool = False


@dataclass
class _Header:
    path: str
    joints: List[_Joint] = field(default_factory=list)
    motion_line: int = 0


def _floats(path: str, lineno: int, tokens: List[str], what: str) -> np.ndarray:
    try:
        values = np.array([float(t) for t in tokens])
    except ValueError:
        raise BVHError(path, lineno, f"non-numeric value in {what}: "
                       f"{' '.join(tokens)!r}") from None
    if not np.isfinite(values).all():
        raise BVHError(path, lineno, f"non-finite value in {what}")
    return values


def _parse_channels(path: str, lineno: int, tokens: List[str]) -> Tuple[str, ...]:
    if not tokens or not tokens[0].isdigit():
        raise BVHError(path, lineno, "CHANNELS needs a count and channel names")
    count, names = int(tokens[0]), tokens[1:]
    if count != len(names):
        raise BVHError(path, lineno, f"CHANNELS says {count} but lists "
                       f"{len(names)} names")
    out = []
    for name in names:
        if name.lower() not in _CHANNELS:
            raise BVHError(path, lineno, f"unknown channel name {name!r}")
        out.append(_CHANNELS[name.lower()])
    rot = [c for c in out if c.endswith("rotation")]
    pos = [c for c in out if c.endswith("position")]
    if len(set(out)) != len(out) or len(rot) not in (0, 3) or len(pos) not in (0, 3):
        raise BVHError(path, lineno, f"channel layout {' '.join(names)!r} is "
                       "not supported: expected 0 or 3 distinct rotation and "
                       "0 or 3 distinct position channels")
    return tuple(out)


class _HeaderParser:
    """Line-based parser of the HIERARCHY section (names may hold spaces)."""

    def __init__(self, path: str, lines: List[str]) -> None:
        self.path, self.lines = path, lines
        self.header = _Header(path)
        self.stack: List[int] = []  # open joint indices
        self.pending: Optional[int] = None  # joint waiting for its '{'
        self.names: set = set()

    def error(self, lineno: int, msg: str) -> BVHError:
        return BVHError(self.path, lineno, msg)

    def run(self) -> _Header:
        seen_hierarchy = False
        for i, raw in enumerate(self.lines):
            lineno = i + 1
            line = raw.strip()
            if not line:
                continue
            keyword = line.split(None, 1)[0]
            if not seen_hierarchy:
                if keyword.upper() != "HIERARCHY":
                    raise self.error(lineno, f"expected HIERARCHY, found {keyword!r}")
                seen_hierarchy = True
                continue
            if keyword.upper() == "MOTION":
                self._finish(lineno)
                self.header.motion_line = lineno
                return self.header
            self._line(lineno, line, keyword)
        if not seen_hierarchy:
            raise self.error(len(self.lines), "empty file")
        raise self.error(len(self.lines), "missing MOTION section (file ends "
                         "inside or after the hierarchy)")

    def _finish(self, lineno: int) -> None:
        if self.stack or self.pending is not None:
            raise self.error(lineno, "unbalanced braces: "
                             f"{len(self.stack)} joint(s) not closed before MOTION")
        if not self.header.joints:
            raise self.error(lineno, "no ROOT joint before MOTION")

    def _line(self, lineno: int, line: str, keyword: str) -> None:
        upper = keyword.upper()
        if upper in ("ROOT", "JOINT"):
            self._open_joint(lineno, line[len(keyword):].strip(), upper)
        elif upper == "END":
            rest = line[len(keyword):].strip()
            if not rest.lower().startswith("site"):
                raise self.error(lineno, f"expected 'End Site', found {line!r}")
            self._open_joint(lineno, None, "END", tail=rest[4:].strip())
        elif upper == "OFFSET":
            self._offset(lineno, line.split()[1:])
        elif upper == "CHANNELS":
            self._channels(lineno, line.split()[1:])
        elif set(line) <= set("{} \t"):
            for ch in line:
                if ch == "{":
                    self._open_brace(lineno)
                elif ch == "}":
                    self._close_brace(lineno)
        else:
            raise self.error(lineno, f"unexpected {keyword!r} in HIERARCHY")

    def _open_joint(self, lineno: int, name: Optional[str], kind: str,
                    tail: str = "") -> None:
        if self.pending is not None:
            raise self.error(lineno, "expected '{' after joint declaration")
        joints = self.header.joints
        if kind == "ROOT" and (joints or self.stack):
            raise self.error(lineno, "only one ROOT is supported")
        if kind != "ROOT" and not self.stack:
            raise self.error(lineno, f"{kind.title()} outside of any joint "
                             "(unbalanced braces?)")
        parent = self.stack[-1] if self.stack else -1
        if kind == "END":
            name = _unique(f"{joints[parent].name}_end", self.names)
        else:
            if name.endswith("{"):
                name, tail = name[:-1].strip(), "{"
            if not name:
                raise self.error(lineno, f"{kind} without a name")
            if name in self.names:
                raise self.error(lineno, f"duplicate joint name {name!r}")
        joints.append(_Joint(name, parent, lineno, end_site=kind == "END"))
        self.names.add(name)
        self.pending = len(joints) - 1
        if tail == "{":
            self._open_brace(lineno)
        elif tail:
            raise self.error(lineno, f"unexpected {tail!r}")

    def _open_brace(self, lineno: int) -> None:
        if self.pending is None:
            raise self.error(lineno, "unbalanced braces: '{' without a joint")
        self.stack.append(self.pending)
        self.pending = None

    def _close_brace(self, lineno: int) -> None:
        if not self.stack:
            raise self.error(lineno, "unbalanced braces: '}' without a joint")
        joint = self.header.joints[self.stack.pop()]
        if joint.offset is None:
            raise self.error(joint.line, f"joint {joint.name!r} has no OFFSET")

    def _current(self, lineno: int, what: str) -> _Joint:
        if not self.stack:
            raise self.error(lineno, f"{what} outside of any joint")
        return self.header.joints[self.stack[-1]]

    def _offset(self, lineno: int, tokens: List[str]) -> None:
        joint = self._current(lineno, "OFFSET")
        if len(tokens) != 3:
            raise self.error(lineno, f"OFFSET needs 3 values, got {len(tokens)}")
        joint.offset = _floats(self.path, lineno, tokens, "OFFSET")

    def _channels(self, lineno: int, tokens: List[str]) -> None:
        joint = self._current(lineno, "CHANNELS")
        if joint.end_site:
            raise self.error(lineno, "an End Site cannot have CHANNELS")
        joint.channels = _parse_channels(self.path, lineno, tokens)


def _unique(name: str, names: set) -> str:
    out, k = name, 1
    while out in names:
        k += 1
        out = f"{name}{k}"
    return out


_MOTION = re.compile(r"^[ \t]*MOTION[ \t]*\r?$", re.M | re.I)


def _next_line(text: str, pos: int) -> Tuple[str, int]:
    end = text.find("\n", pos)
    end = len(text) if end < 0 else end
    return text[pos:end], end + 1


def _frame_header(path: str, text: str, pos: int, lineno: int) -> Tuple[int, float, int, int]:
    """Parse 'Frames:' and 'Frame Time:' after MOTION, starting at offset
    :obj:`pos` (line :obj:`lineno`); returns (frames, frame time, offset and
    line number of the first data line)."""
    found = {}
    while len(found) < 2:
        if pos >= len(text):
            raise BVHError(path, lineno, "truncated MOTION section: missing "
                           "'Frames:' or 'Frame Time:'")
        raw, pos = _next_line(text, pos)
        lineno += 1
        line = raw.strip()
        if not line:
            continue
        key, sep, value = line.partition(":")
        key = " ".join(key.split()).lower()
        if not sep or key not in ("frames", "frame time"):
            raise BVHError(path, lineno, f"expected 'Frames:' and 'Frame Time:', "
                           f"found {line[:40]!r}")
        try:
            found[key] = float(value) if key == "frame time" else int(value)
        except ValueError:
            raise BVHError(path, lineno, f"bad value in {line!r}") from None
        if key == "frames" and found[key] < 0:
            raise BVHError(path, lineno, "negative frame count")
        if key == "frame time" and not (np.isfinite(found[key]) and found[key] > 0
                                        and np.isfinite(1.0 / found[key])):
            raise BVHError(path, lineno, "Frame Time must be positive")
    return found["frames"], found["frame time"], pos, lineno


def _locate_bad_frame(path: str, text: str, lineno: int, frames: int,
                      width: int) -> BVHError:
    """Slow path used only to name the line of a malformed frame."""
    count = 0
    lines = text.splitlines()
    for i, line in enumerate(lines):
        tokens = line.split()
        if not tokens:
            continue
        if count == frames:
            return BVHError(path, lineno + i + 1,
                            f"more frame lines than 'Frames: {frames}'")
        if len(tokens) != width:
            return BVHError(path, lineno + i + 1, f"frame {count} has "
                            f"{len(tokens)} values, expected {width}")
        _floats(path, lineno + i + 1, tokens, f"frame {count}")
        count += 1
    return BVHError(path, lineno + len(lines), f"truncated MOTION section: "
                    f"'Frames: {frames}' but only {count} frame lines")


def _parse_frames(path: str, text: str, lineno: int, frames: int,
                  width: int) -> np.ndarray:
    """Parse the frame lines (C parser of numpy); on any problem, find and
    name the offending line."""
    if width == 0:  # a skeleton without channels: frame lines are empty
        return np.zeros((frames, 0))
    if frames == 0:
        if text.strip():
            raise _locate_bad_frame(path, text, lineno, frames, width)
        return np.zeros((0, width))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            data = np.loadtxt(io.StringIO(text), dtype=np.float64, ndmin=2,
                              comments=None)
        except ValueError:
            raise _locate_bad_frame(path, text, lineno, frames, width) from None
    if data.shape != (frames, width) or not np.isfinite(data).all():
        raise _locate_bad_frame(path, text, lineno, frames, width)
    return data


def _euler_to_matrix(angles: np.ndarray, order: str) -> np.ndarray:
    r"""Numpy twin of :func:`~satagraph.ops.euler_to_matrix` (radians, BVH
    order of three distinct axes), in closed form.

    ``R_i(a) R_j(b) R_k(c)`` is :math:`P R_x R_y R_z P^T` for the permutation
    :math:`P` taking ``XYZ`` to ``ijk``, with the angles negated when
    :math:`P` is odd (a reflection reverses the sense of rotation).

    Shapes:
        - **angles**: :math:`(*, 3)`
        - **output**: :math:`(*, 3, 3)`
    """
    idx = ["XYZ".index(a) for a in order]
    sign = 1.0 if order in ("XYZ", "YZX", "ZXY") else -1.0
    ca, cb, cc = np.moveaxis(np.cos(angles), -1, 0)
    sa, sb, sc = np.moveaxis(np.sin(angles) * sign, -1, 0)
    sa_sb, ca_sb = sa * sb, ca * sb
    entries = (
        (cb * cc, -cb * sc, sb),
        (ca * sc + sa_sb * cc, ca * cc - sa_sb * sc, -sa * cb),
        (sa * sc - ca_sb * cc, sa * cc + ca_sb * sc, ca * cb),
    )
    out = np.empty(angles.shape[:-1] + (3, 3))
    for r, row in enumerate(entries):
        for c, value in enumerate(row):
            out[..., idx[r], idx[c]] = value
    return out


def _to_motion(path: str, header: _Header, data: np.ndarray, frame_time: float) -> Motion:
    joints = header.joints
    skeleton = Skeleton(
        names=[j.name for j in joints],
        parents=np.array([j.parent for j in joints]),
        offsets=np.stack([j.offset for j in joints]),
        channels=[j.channels for j in joints],
        end_site=np.array([j.end_site for j in joints]),
    )
    num_frames, num = data.shape[0], len(joints)
    trans = np.broadcast_to(skeleton.offsets, (num_frames, num, 3)).copy()
    rot = np.empty((num_frames, num, 3, 3))
    by_order: dict = {}
    starts = np.cumsum([0] + [len(j.channels) for j in joints])
    for j, joint in enumerate(joints):
        rot_cols, order = [], ""
        for k, c in enumerate(joint.channels, start=starts[j]):
            if c.endswith("position"):
                trans[:, j, "XYZ".index(c[0])] = data[:, k]
            else:
                rot_cols.append(k)
                order += c[0]
        if rot_cols:
            idx, cols = by_order.setdefault(order, ([], []))
            idx.append(j)
            cols.append(rot_cols)
    still = np.ones(num, dtype=bool)  # joints without rotation channels
    for order, (idx, cols) in by_order.items():
        angles = np.radians(data[:, np.array(cols)])  # [T, n, 3]
        rot[:, idx] = _euler_to_matrix(angles, order)
        still[idx] = False
    rot[:, still] = np.eye(3)
    fps = 1.0 / frame_time
    if round(fps) >= 1 and abs(fps - round(fps)) < 1e-2 * max(1.0, fps / 100):
        fps = float(round(fps))
    return Motion(skeleton, rot, trans, fps=fps, raw_channels=data, source=path)


def read_bvh(path: PathLike) -> Motion:
    r"""Read a BVH file of any skeleton and channel layout.

    End sites become leaf joints named ``<parent>_end``. Position channels on
    any joint replace that joint's offset component for each frame.

    Args:
        path (str or PathLike): The ``.bvh`` file.

    Returns:
        Motion: skeleton, local rotations and translations, frame rate, and
        the raw channel values (so that writing it back is exact).

    Raises:
        BVHError: naming the file, the line and the problem, for any
            malformed input.
    """
    path = os.fspath(path)
    try:
        with open(path, "rb") as f:
            text = f.read().decode("utf-8", errors="replace")
    except OSError as err:
        raise BVHError(path, 0, f"cannot read file: {err.strerror}") from None
    if not text.strip():
        raise BVHError(path, 1, "empty file")
    match = _MOTION.search(text)
    head_end = match.end() + 1 if match else len(text)
    header = _HeaderParser(path, text[:head_end].splitlines()).run()
    frames, frame_time, pos, lineno = _frame_header(
        path, text, head_end, header.motion_line)
    width = sum(len(j.channels) for j in header.joints)
    data = _parse_frames(path, text[pos:], lineno, frames, width)
    return _to_motion(path, header, data, frame_time)
