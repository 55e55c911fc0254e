"""Text and special files: encodings, BOM, line endings, FIFOs and devices;
the writer's deep hierarchies and non-finite values."""
from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np
import pytest

from satagraph.io import BVHError, read_bvh, write_bvh
from satagraph.io.bvh_reader import BVHWarning
from satagraph.motion import Motion
from satagraph.skeleton import Skeleton

TWO = ["HIERARCHY", "ROOT Hips", "{", "  OFFSET 0 0 0",
       "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation",
       "  JOINT {a}", "  {", "    OFFSET 0 1 0", "    CHANNELS 3 Zrotation Xrotation Yrotation",
       "  }", "  JOINT {b}", "  {", "    OFFSET 0 -1 0",
       "    CHANNELS 3 Zrotation Xrotation Yrotation", "  }", "}", "MOTION",
       "Frames: 2", "Frame Time: 0.0333333", "0 1 0 0 0 0 10 0 0 0 0 5",
       "0 1 1 0 0 0 20 0 0 0 0 6"]


def _text(a: str = "Spine", b: str = "Leg") -> str:
    return "\n".join(line.replace("{a}", a).replace("{b}", b) for line in TWO) + "\n"


def test_bom_and_cr_only_line_endings(tmp_path: Path) -> None:
    ref = read_bvh(_write(tmp_path / "ref.bvh", _text().encode()))
    for name, data in (("bom.bvh", b"\xef\xbb\xbf" + _text().encode()),
                       ("cr.bvh", _text().replace("\n", "\r").encode()),
                       ("mixed.bvh", _text().replace("\n", "\r", 5).encode())):
        motion = read_bvh(_write(tmp_path / name, data))
        assert motion.skeleton.names == ref.skeleton.names, name
        np.testing.assert_array_equal(motion.raw_channels, ref.raw_channels)


def test_utf16_text_with_its_byte_order_mark_is_read(tmp_path: Path) -> None:
    """A Windows tool's UTF-16 save read as Latin-1 and failed on line 1
    ('expected HIERARCHY, found ÿþH\\x00I...'); both byte orders read as the
    UTF-8 file, CRLF line endings too."""
    ref = read_bvh(_write(tmp_path / "ref.bvh", _text().encode()))
    for name, encoding in (("le.bvh", "utf-16"), ("be.bvh", "utf-16-be")):
        data = _text().replace("\n", "\r\n").encode(encoding)
        data = data if name == "le.bvh" else b"\xfe\xff" + data
        motion = read_bvh(_write(tmp_path / name, data))
        assert motion.skeleton.names == ref.skeleton.names, name
        np.testing.assert_array_equal(motion.raw_channels, ref.raw_channels)
    with pytest.raises(BVHError, match="bad.bvh: a UTF-16 byte order mark, but not UTF-16"):
        read_bvh(_write(tmp_path / "bad.bvh", b"\xff\xfeH\x00\x00\xdc"))


@pytest.mark.parametrize("data, said", [
    (b"PK\x03\x04" + b"\x00" * 32 + b"archive/data.pkl", r"x.bvh: a zip archive \(a PyTorch "
     r"checkpoint\? it goes to --ckpt\), not BVH text$"),
    (b"\x1f\x8b\x08\x00" + b"\x00" * 16, r"x.bvh: gzip-compressed \(decompress it first\)"),
    (b"\x89PNG\r\n\x1a\n\x00\x00", r"x.bvh: a PNG image, not BVH text$"),
    (b"HIERARCHY\nROOT Hips\n\x00\x00", r"x.bvh:3: binary data \(a NUL byte\), not BVH text$"),
    ("HIERARCHY\nROOT Hips\n".encode("utf-16-be"), r"x.bvh: UTF-16 text without a byte order "
     r"mark \(save it as UTF-8\), not BVH text$")])
def test_a_binary_file_is_said_to_be_one(tmp_path: Path, data: bytes, said: str) -> None:
    """A checkpoint given as a motion warned "read as Latin-1", then failed on
    a line of escaped bytes; now one line says what the file looks like."""
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no Latin-1 warning before the refusal
        with pytest.raises(BVHError, match=said):
            read_bvh(_write(tmp_path / "x.bvh", data))


def test_latin1_names_are_kept_distinct_with_a_warning(tmp_path: Path) -> None:
    data = _text("B\xedceps", "B\xecceps").encode("latin-1")
    with pytest.warns(BVHWarning, match=r"latin.bvh:6: not UTF-8"):
        motion = read_bvh(_write(tmp_path / "latin.bvh", data))
    assert motion.skeleton.names[1:] == ["B\xedceps", "B\xecceps"]


def test_shift_jis_names_are_read_as_japanese(tmp_path: Path) -> None:
    """MikuMikuDance writes Shift-JIS: read as Latin-1 its センター was
    mojibake and no Japanese name was understood. A Latin-1 file whose bytes
    also decode as Shift-JIS (``Tête``'s ``ê`` and ``t`` make a kanji) has
    no kana and stays Latin-1."""
    data = _text("\u5de6\u3072\u3056", "\u30bb\u30f3\u30bf\u30fc").encode("cp932")
    with pytest.warns(BVHWarning, match=r"sjis.bvh:6: not UTF-8; .* Shift-JIS"):
        motion = read_bvh(_write(tmp_path / "sjis.bvh", data))
    assert motion.skeleton.names[1:] == ["\u5de6\u3072\u3056", "\u30bb\u30f3\u30bf\u30fc"]
    data = _text("T\xeate", "Hanche").encode("latin-1")
    assert "\u30bb" not in data.decode("cp932", errors="replace")
    with pytest.warns(BVHWarning, match="Latin-1"):
        assert read_bvh(_write(tmp_path / "tete.bvh", data)).skeleton.names[1] == "T\xeate"


def test_utf8_names(tmp_path: Path) -> None:
    motion = read_bvh(_write(tmp_path / "u.bvh", _text("Wirbels\u00e4ule", "\u811a").encode()))
    assert motion.skeleton.names[1:] == ["Wirbels\u00e4ule", "\u811a"]


@pytest.mark.parametrize("kind", ["fifo", "dir", "dev"])
def test_special_files_are_refused_up_front(tmp_path: Path, kind: str) -> None:
    path = {"dir": tmp_path, "dev": Path("/dev/zero")}.get(kind, tmp_path / "p.bvh")
    if kind == "fifo":
        os.mkfifo(path)
    with pytest.raises(BVHError, match="cannot read") as info:
        read_bvh(path)
    assert str(info.value).startswith(f"{path}: cannot read")  # no line to name


def _chain(depth: int) -> Motion:
    names = [f"j{i}" for i in range(depth)]
    parents = np.arange(-1, depth - 1)
    offsets = np.tile([0.0, 1.0, 0.0], (depth, 1))
    channels = [("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation",
                 "Yrotation")] + [("Zrotation", "Xrotation", "Yrotation")] * (depth - 1)
    skel = Skeleton(names, parents, offsets, channels)
    rot = np.broadcast_to(np.eye(3), (2, depth, 3, 3)).copy()
    trans = np.broadcast_to(offsets, (2, depth, 3)).copy()
    return Motion(skel, rot, trans, fps=30.0)


def test_writer_has_no_depth_limit(tmp_path: Path) -> None:
    depth = sys.getrecursionlimit() + 100  # deeper than Python's recursion limit
    motion = _chain(depth)
    write_bvh(motion, tmp_path / "deep.bvh")
    back = read_bvh(tmp_path / "deep.bvh")
    assert back.skeleton.num_joints == depth
    np.testing.assert_array_equal(back.skeleton.parents, motion.skeleton.parents)


def test_writer_refuses_non_finite_values(tmp_path: Path) -> None:
    motion = _chain(3)
    motion.translations[1, 0, 0] = np.nan
    path = tmp_path / "nan.bvh"
    path.write_text("previous")
    with pytest.raises(ValueError, match=r"nan.bvh: refusing to write non-finite.*frame 1"):
        write_bvh(motion, path)
    assert path.read_text() == "previous"
    assert [p.name for p in tmp_path.iterdir()] == ["nan.bvh"]


def test_writer_refuses_a_non_finite_offset_or_frame_rate(tmp_path: Path) -> None:
    motion = _chain(4)
    offsets = motion.skeleton.offsets.copy()
    offsets[2, 1] = offsets[3, 0] = np.inf  # one axis of joint 2, then joint 3
    broken = Motion(motion.skeleton.replace(offsets=offsets), motion.rotations,
                    motion.translations, fps=30.0)
    with pytest.raises(ValueError, match=r"off.bvh: refusing to write non-finite values: "
                                         r"OFFSET of joint 'j2'$"):
        write_bvh(broken, tmp_path / "off.bvh")
    endless = Motion(motion.skeleton, motion.rotations, motion.translations, fps=np.inf)
    with pytest.raises(ValueError, match=r"fps.bvh: refusing to write a frame rate of inf$"):
        write_bvh(endless, tmp_path / "fps.bvh")
    assert list(tmp_path.iterdir()) == []


def _write(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    return path
