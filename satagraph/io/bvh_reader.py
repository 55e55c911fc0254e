"""BVH reader for any dialect: channel layouts, rotation orders, line endings."""
from __future__ import annotations

import io
import math
import os
import re
import warnings
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from satagraph.io._floats import parse_decimal_table
from satagraph.io.errors import BVHError
from satagraph.utils.files import InputFileError, check_input_file
from satagraph.motion import Motion, RigSettings
from satagraph.skeleton import Skeleton

PathLike = Union[str, "os.PathLike[str]"]

#: Joint-frames per step of the Euler angle conversion (small temporaries).
EULER_CHUNK_JOINT_FRAMES = 1 << 15

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
    """The numbers of a line, or an error naming the first token that is not
    one (a BVH number: no digit separators, which Python's ``float`` takes)."""
    values = []
    for i, token in enumerate(tokens):
        try:
            if "_" in token:
                raise ValueError(token)
            values.append(float(token))
        except ValueError:
            raise BVHError(path, lineno, f"non-numeric value {token[:40]!r} in {what} "
                           f"(value {i + 1} of {len(tokens)})") from None
    if not all(map(math.isfinite, values)):
        raise BVHError(path, lineno, f"non-finite value in {what}")
    return np.array(values)


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
        #: Names made up for End Sites (``<parent>_end``): joint index by name.
        self.made_up: Dict[str, int] = {}

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
            if not rest.lower().startswith("site") or rest[4:5].strip().strip("{"):
                raise self.error(lineno, f"expected 'End Site', found {line!r}")
            self._open_joint(lineno, None, "END", tail=_end_site_tail(rest[4:]))
        elif upper == "OFFSET":
            self._offset(lineno, line.split()[1:])
        elif upper == "CHANNELS":
            self._channels(lineno, line.split()[1:])
        elif not line.strip("{} \t"):  # only braces
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
            self.made_up[name] = len(joints)
        else:
            if name.endswith("{"):
                name, tail = name[:-1].strip(), "{"
            if not name:
                raise self.error(lineno, f"{kind} without a name")
            if name in self.made_up:  # the file's own name wins over one made up
                self._rename_end_site(name)
            elif name in self.names:
                raise self.error(lineno, f"duplicate joint name {name!r}")
        joints.append(_Joint(name, parent, lineno, end_site=kind == "END"))
        self.names.add(name)
        self.pending = len(joints) - 1
        if tail == "{":
            self._open_brace(lineno)
        elif tail:
            raise self.error(lineno, f"unexpected {tail!r}")

    def _rename_end_site(self, name: str) -> None:
        """Give the End Site called :obj:`name` another made-up name."""
        index = self.made_up.pop(name)
        new = _unique(name, self.names)
        self.header.joints[index].name = new
        self.names.add(new)
        self.made_up[new] = index

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


def _end_site_tail(tail: str) -> str:
    """What follows ``End Site`` on its line without the name some
    exporters give it there (``End Site Head_end``), which Blender's
    importer ignores too: the End Site keeps its made-up name."""
    tail = tail.strip()
    return "{" if tail.endswith("{") else ""


def _unique(name: str, names: set) -> str:
    out, k = name, 1
    while out in names:
        k += 1
        out = f"{name}{k}"
    return out


_SAYS = (r"#[ \t]*satagraph:[ \t]*(?:canonical[ \t]+)?"
         r"up_axis=([+-][XYZ])(?:[ \t]+scale=(\S+))?[ \t]*")
#: A trailing ``# satagraph: [canonical] up_axis=AXIS [scale=S]`` line: the
#: file declares how it is to be read (written by ``satagraph convert
#: --canonical``, and by retarget / reconstruct in the target's own frame;
#: no ``scale`` where the units are the file's own, undecided). Files of
#: this version say it on the ``HIERARCHY`` line (:data:`_HEAD_DECLARATION`).
_DECLARATION = re.compile(r"(?:\r?\n|\r)[ \t]*" + _SAYS + r"(?:\r?\n|\r)?\s*\Z")
#: The declaration as written now, after ``HIERARCHY`` on its line: Blender's
#: importer reads every line after ``Frame Time`` as a frame (a trailing
#: comment failed its import), and readers skip the rest of that line.
_HEAD_DECLARATION = re.compile(r"\A\s*HIERARCHY[ \t]+" + _SAYS + r"(?:\r?\n|\r)", re.I)
_MOTION = re.compile(r"^[ \t]*MOTION[ \t]*\r?$", re.M | re.I)


def written_by_satagraph(path: str) -> bool:
    """Whether a file holds the declaration satagraph writes
    (:data:`_HEAD_DECLARATION`, or :data:`_DECLARATION` at its end): a
    result of ``retarget``, ``reconstruct``, ``generate`` or ``convert
    --canonical``, not someone's capture."""
    try:
        with open(path, "rb") as handle:
            head = handle.read(4096).decode("utf-8", errors="replace")
            handle.seek(0, os.SEEK_END)
            handle.seek(max(handle.tell() - 4096, 0))
            tail = handle.read().decode("utf-8", errors="replace")
    except OSError:
        return False
    return (_HEAD_DECLARATION.match(head.lstrip("\ufeff")) is not None
            or _DECLARATION.search(tail) is not None)


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


def _parse_frames(path: str, text: str, pos: int, raw: Optional[bytes], lineno: int,
                  frames: int, width: int) -> np.ndarray:
    """Parse the frame lines, from offset :obj:`pos` of :obj:`text` (and of
    :obj:`raw`, the file's bytes, when given: they align with the text):
    the vectorised fast path for plain decimals, else the C parser of numpy;
    on any problem, find and name the offending line."""
    if width == 0:  # a skeleton without channels: frame lines are empty
        present = text.count("\n", pos) + bool(text[pos:] and not text.endswith("\n"))
        if frames > present:
            raise BVHError(path, lineno, f"'Frames: {frames}' but only {present} lines "
                           "follow (a skeleton without channels has an empty line a frame)")
        return np.zeros((frames, 0))
    if frames == 0:
        if text[pos:].strip():
            raise _locate_bad_frame(path, text[pos:], lineno, frames, width)
        return np.zeros((0, width))
    data = parse_decimal_table(raw[pos:] if raw is not None else text[pos:].encode(),
                               frames, width)
    if data is not None:
        return data
    body = text[pos:]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            data = np.loadtxt(io.StringIO(body), dtype=np.float64, ndmin=2,
                              comments=None)
        except ValueError:
            raise _locate_bad_frame(path, body, lineno, frames, width) from None
    if data.shape != (frames, width) or not np.isfinite(data).all():
        raise _locate_bad_frame(path, body, lineno, frames, width)
    return data


def _euler_components(angles: np.ndarray, order: str) -> np.ndarray:
    r"""Rotation matrices of intrinsic Euler angles (radians, BVH order of
    three distinct axes), component-major, in closed form.

    ``R_i(a) R_j(b) R_k(c)`` is :math:`P R_x R_y R_z P^T` for the permutation
    :math:`P` taking ``XYZ`` to ``ijk``, with the angles negated when
    :math:`P` is odd (a reflection reverses the sense of rotation).

    Shapes:
        - **angles**: :math:`(3, *)`
        - **output**: :math:`(3, 3, *)`
    """
    idx = ["XYZ".index(a) for a in order]
    shape, angles = angles.shape[1:], angles.reshape(3, -1)
    ca, cb, cc = np.cos(angles)
    sin = np.sin(angles)
    if order not in ("XYZ", "YZX", "ZXY"):
        np.negative(sin, out=sin)
    sa, sb, sc = sin
    out = np.empty((3, 3, angles.shape[1]))
    e = [[out[idx[r], idx[c]] for c in range(3)] for r in range(3)]
    tmp, sa_sb, ca_sb = np.empty_like(ca), sa * sb, ca * sb
    np.multiply(cb, cc, out=e[0][0])
    np.negative(np.multiply(cb, sc, out=e[0][1]), out=e[0][1])
    e[0][2][...] = sb
    np.add(np.multiply(ca, sc, out=e[1][0]), np.multiply(sa_sb, cc, out=tmp), out=e[1][0])
    np.subtract(np.multiply(ca, cc, out=e[1][1]), np.multiply(sa_sb, sc, out=tmp),
                out=e[1][1])
    np.negative(np.multiply(sa, cb, out=e[1][2]), out=e[1][2])
    np.subtract(np.multiply(sa, sc, out=e[2][0]), np.multiply(ca_sb, cc, out=tmp),
                out=e[2][0])
    np.add(np.multiply(sa, cc, out=e[2][1]), np.multiply(ca_sb, sc, out=tmp), out=e[2][1])
    np.multiply(ca, cb, out=e[2][2])
    return out.reshape((3, 3) + shape)


def _euler_to_matrix(angles: np.ndarray, order: str) -> np.ndarray:
    r"""Numpy twin of :func:`~satagraph.ops.euler_to_matrix` (radians, BVH
    order of three distinct axes), in closed form.

    Shapes:
        - **angles**: :math:`(*, 3)`
        - **output**: :math:`(*, 3, 3)`
    """
    out = _euler_components(np.moveaxis(angles, -1, 0), order)
    return np.moveaxis(out, (0, 1), (-2, -1))


@dataclass
class _ChannelMap:
    """Where the channels of the frame lines go: position channels as
    (joint, axis, column) triples, rotation channels as column triples
    grouped by rotation order."""
    pos_joint: List[int] = field(default_factory=list)
    pos_axis: List[int] = field(default_factory=list)
    pos_column: List[int] = field(default_factory=list)
    rotations: Dict[str, Tuple[List[int], List[List[int]]]] = field(default_factory=dict)

    @classmethod
    def of(cls, channels: Sequence[Sequence[str]]) -> "_ChannelMap":
        """The map of each joint's channel names, in file order."""
        out, column = cls(), 0
        for j, names in enumerate(channels):
            order, cols = "", []
            for name in names:
                if name.endswith("position"):
                    out.pos_joint.append(j)
                    out.pos_axis.append("XYZ".index(name[0]))
                    out.pos_column.append(column)
                else:
                    order, cols = order + name[0], cols + [column]
                column += 1
            if cols:
                idx, all_cols = out.rotations.setdefault(order, ([], []))
                idx.append(j)
                all_cols.append(cols)
        return out


def _local_rotations(data: np.ndarray, channels: _ChannelMap,
                     num_joints: int) -> np.ndarray:
    """Local rotation matrices ``[T, J, 3, 3]`` (identity for joints without
    rotation channels), built for all the joints of one rotation order at
    once, a block of frames at a time (small temporaries)."""
    num_frames = data.shape[0]
    out = np.empty((num_frames, num_joints, 3, 3))
    still = np.ones(num_joints, dtype=bool)
    for order, (idx, cols) in channels.rotations.items():
        cols = np.array(cols).T  # [3, n]
        step = max(1, EULER_CHUNK_JOINT_FRAMES // len(idx))
        for start in range(0, num_frames, step):
            part = slice(start, start + step)
            angles = data[part].T[cols]  # [3, n, frames]
            np.radians(angles, out=angles)
            out[part, idx] = _euler_components(angles, order).transpose(3, 2, 0, 1)
        still[idx] = False
    out[:, still] = np.eye(3)
    return out


def channel_transforms(skeleton: Skeleton, data: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    r"""Local rotations and translations of BVH channel values in the
    skeleton's channel layout (what :func:`read_bvh` makes of a file's
    frame lines): joints without position channels stand at their offsets,
    joints without rotation channels keep the identity.

    Shapes:
        - **data**: :math:`(T, C)`
        - **output**: :math:`(T, J, 3, 3)` and :math:`(T, J, 3)`
    """
    channels = _ChannelMap.of(skeleton.channels)
    trans = np.empty((data.shape[0], skeleton.num_joints, 3))
    trans[...] = skeleton.offsets
    trans[:, channels.pos_joint, channels.pos_axis] = data[:, channels.pos_column]
    return _local_rotations(data, channels, skeleton.num_joints), trans


def _to_motion(path: str, header: _Header, data: np.ndarray, frame_time: float) -> Motion:
    joints = header.joints
    skeleton = Skeleton(
        names=[j.name for j in joints],
        parents=np.array([j.parent for j in joints]),
        offsets=np.stack([j.offset for j in joints]),
        channels=[j.channels for j in joints],
        end_site=np.array([j.end_site for j in joints]),
    )
    rot, trans = channel_transforms(skeleton, data)
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

    Text is UTF-8 (a byte order mark is skipped) or UTF-16 with its byte
    order mark; a file that is not UTF-8 is read as Latin-1 with a
    :class:`BVHWarning`; a binary file (a NUL byte: a checkpoint, an image,
    a compressed file) is refused in one line saying what it looks like.
    Lines may end with ``\n``, ``\r\n`` or ``\r``.

    Raises:
        BVHError: naming the file, the line and the problem, for any
            malformed input, and for a path that is not a regular file (a
            FIFO, a device, a directory).
    """
    path = os.fspath(path)
    raw = _read_bytes(path)
    text = _decode(path, raw)
    if not text.strip():
        raise BVHError(path, 1, "empty file")
    aligned = raw if len(raw) == len(text) else None  # one byte per character
    text, rig = _declaration(path, text)
    if aligned is not None and len(aligned) != len(text):  # cut at the declaration
        aligned = aligned[:len(text) - 1] + b"\n"
    match = _MOTION.search(text)
    head_end = match.end() + 1 if match else len(text)
    header = _HeaderParser(path, text[:head_end].splitlines()).run()
    frames, frame_time, pos, lineno = _frame_header(
        path, text, head_end, header.motion_line)
    width = sum(len(j.channels) for j in header.joints)
    data = _parse_frames(path, text, pos, aligned, lineno, frames, width)
    motion = _to_motion(path, header, data, frame_time)
    motion.rig = rig
    return motion


def _declaration(path: str, text: str) -> Tuple[str, Optional[RigSettings]]:
    """The text without a trailing satagraph declaration, and the settings
    declared on the ``HIERARCHY`` line or on that trailing line (``None``
    without either). Only the last non-blank line can be a trailing one:
    the search starts at the line break before it (a whole-text search
    costs more than parsing the frames)."""
    head = _HEAD_DECLARATION.match(text)
    if head is not None:  # the header parser reads no further than HIERARCHY on it
        return text, _declared(path, head, text[:head.start(1)].count("\n") + 1)
    end = len(text.rstrip())
    start = max(text.rfind("\n", 0, end), text.rfind("\r", 0, end))
    match = _DECLARATION.search(text, max(start - 1, 0)) if start >= 0 else None
    if match is None:
        return text, None
    line = text[:match.start()].count("\n") + 2
    return text[:match.start()] + "\n", _declared(path, match, line)


def _declared(path: str, match: "re.Match[str]", line: int) -> RigSettings:
    """The settings of a declaration :obj:`match` (on line :obj:`line`):
    its up axis and scale, if it gives one."""
    if match.group(2) is None:
        return RigSettings(match.group(1), None, declared=True)
    try:
        scale = float(match.group(2))
    except ValueError:
        scale = float("nan")
    if not (math.isfinite(scale) and scale > 0):
        raise BVHError(path, line, f"bad scale in the satagraph declaration: "
                       f"{match.group(2)!r}")
    return RigSettings(match.group(1), scale, declared=True)


_BOM = b"\xef\xbb\xbf"
_LONE_CR = re.compile(rb"\r(?!\n)")


def _read_bytes(path: str) -> bytes:
    r"""The bytes of a regular file (FIFOs, devices and directories are
    refused before opening: reading them hangs or never ends), without a
    UTF-8 byte order mark, with old Mac line endings (``\r`` alone) turned
    into ``\n``."""
    try:
        check_input_file(path, "BVH file")
        with open(path, "rb") as f:
            raw = f.read()
    except InputFileError as err:
        message = str(err).split(": ", 1)[1]
        if not message.startswith("cannot read"):
            message = f"cannot read: it {message}"
        raise BVHError(path, 0, message) from None
    except OSError as err:
        raise BVHError(path, 0, f"cannot read file: {err.strerror or err}") from None
    raw = _from_utf16(path, raw)
    if raw.startswith(_BOM):
        raw = raw[len(_BOM):]
    _refuse_binary(path, raw)
    if b"\r" in raw and _LONE_CR.search(raw):
        raw = _LONE_CR.sub(b"\n", raw)
    return raw


_UTF16_BOMS = (b"\xff\xfe", b"\xfe\xff")

#: What a binary file's first bytes say it is (:func:`_refuse_binary`).
_MAGIC = ((b"PK\x03\x04", "a zip archive (a PyTorch checkpoint? it goes to --ckpt)"),
          (b"\x1f\x8b", "gzip-compressed (decompress it first)"),
          (b"\x80", "a Python pickle"),
          (b"\x89PNG", "a PNG image"), (b"GIF8", "a GIF image"), (b"\xff\xd8\xff", "a JPEG image"))


def _from_utf16(path: str, raw: bytes) -> bytes:
    """UTF-16 text with a byte order mark (as some Windows tools save
    text) as UTF-8 bytes; other bytes as they are."""
    if not raw.startswith(_UTF16_BOMS):
        return raw
    try:
        return raw.decode("utf-16").encode("utf-8")
    except UnicodeDecodeError as err:
        raise BVHError(path, 0, f"a UTF-16 byte order mark, but not UTF-16 text "
                       f"(byte {err.start})") from None


def _refuse_binary(path: str, raw: bytes) -> None:
    """Refuse bytes with a NUL, which no BVH text holds, saying what they
    look like (:data:`_MAGIC`): a checkpoint given as a motion read as
    Latin-1 and failed on a line of escaped bytes."""
    nul = raw.find(b"\x00")
    if nul < 0:
        return
    kind = next((what for magic, what in _MAGIC if raw.startswith(magic)), None)
    head = raw[:64]
    if kind is None and len(head) >= 8 and (not any(head[1::2]) or not any(head[0::2])):
        kind = "UTF-16 text without a byte order mark (save it as UTF-8)"
    what = f"{kind}, not BVH text" if kind else "binary data (a NUL byte), not BVH text"
    raise BVHError(path, 0 if kind else raw.count(b"\n", 0, nul) + 1, what)


def _decode(path: str, raw: bytes) -> str:
    """UTF-8 text; a file that is not UTF-8 is read as Shift-JIS (cp932)
    where that gives Japanese kana (MikuMikuDance's own encoding: its
    ``センター`` read as Latin-1 was ``ƒZƒ“ƒ^[``), else as Latin-1 (every
    byte one character, so no joint name is lost or merged), with a
    warning naming the first offending line and the encoding read."""
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as err:
        line = raw.count(b"\n", 0, err.start) + 1
        text, encoding = _japanese(raw), "Shift-JIS (cp932)"
        if text is None:
            text, encoding = raw.decode("latin-1"), "Latin-1 (ISO 8859-1)"
        warnings.warn(f"{path}:{line}: not UTF-8; the file is read as {encoding}",
                      BVHWarning, stacklevel=3)
        return text


_KANA = re.compile("[\u3040-\u30ff]")


def _japanese(raw: bytes) -> Optional[str]:
    """:obj:`raw` as Shift-JIS text if it is that and holds kana (the C1
    bytes that begin a kana in it are no Latin-1 text's), else ``None``."""
    try:
        text = raw.decode("cp932")
    except UnicodeDecodeError:
        return None
    return text if _KANA.search(text) else None


class BVHWarning(UserWarning):
    """A BVH file was read with a fallback (e.g. Latin-1 text)."""
