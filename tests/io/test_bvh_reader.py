"""BVH reader: every real file, dialect quirks and malformed input."""
from __future__ import annotations

import random
from collections import Counter
from pathlib import Path
from typing import List

import numpy as np
import pytest

from satagraph.io import BVHError, read_bvh

BASE = """\
HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Spine
  {
    OFFSET 0 10 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 0 5 0
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.033333
0 90 0 0 0 0 10 0 0
1 90 0 0 0 0 20 0 0
""".splitlines()
# 1-based line numbers of BASE used below.
L_SPINE, L_SPINE_OFFSET, L_SPINE_CHANNELS, L_ROOT_CLOSE = 6, 8, 9, 15
L_MOTION, L_FRAMES, L_FRAME_TIME, L_FRAME0, L_FRAME1 = 16, 17, 18, 19, 20


def write(tmp_path: Path, lines: List[str], name: str = "clip.bvh",
          newline: str = "\n") -> Path:
    path = tmp_path / name
    path.write_bytes((newline.join(lines) + newline).encode())
    return path


def replace(line: int, text: str) -> List[str]:
    """BASE with 1-based line :obj:`line` replaced."""
    out = list(BASE)
    out[line - 1] = text
    return out


def expect_error(path: Path, line: int, *words: str) -> BVHError:
    with pytest.raises(BVHError) as info:
        read_bvh(path)
    err = info.value
    msg = str(err)
    assert msg.startswith(f"{path}:{line}: " if line else f"{path}: "), msg
    assert err.path == str(path) and err.line == line
    for word in words:
        assert word.lower() in msg.lower(), msg
    return err


# ---------------------------------------------------------------- real files
def test_manifest_file_reads(manifest_row, read_real):
    motion = read_real(manifest_row["path"])
    skel = motion.skeleton
    assert motion.num_frames == int(manifest_row["frames"])
    assert motion.fps == pytest.approx(float(manifest_row["fps"]), rel=1e-4)
    assert int((~skel.end_site).sum()) == int(manifest_row["joints"])
    assert motion.raw_channels.shape == (motion.num_frames, skel.num_channels)
    assert np.isfinite(motion.rotations).all()
    assert np.isfinite(motion.translations).all()
    # Local rotations are proper rotations.
    rot = motion.rotations[:: max(1, motion.num_frames // 20)]
    eye = np.broadcast_to(np.eye(3), rot.shape)
    np.testing.assert_allclose(rot @ rot.swapaxes(-1, -2), eye, atol=1e-9)
    np.testing.assert_allclose(np.linalg.det(rot), 1.0, atol=1e-9)
    # End sites are leaves without channels.
    assert skel.is_leaf[skel.end_site].all()
    assert all(not skel.channels[j] for j in np.flatnonzero(skel.end_site))


def test_manifest_lists_every_file(shared_data, manifest):
    listed = {row["path"] for row in manifest}
    on_disk = {p.relative_to(shared_data).as_posix()
               for p in shared_data.rglob("*.bvh")}
    assert on_disk == listed
    assert len(manifest) == 247


def test_bandai_dialect(read_real):
    skel = read_real("bandai/dataset-1_bow_active_001.bvh").skeleton
    assert skel.names[:2] == ["joint_Root", "Hips"]
    joints = ~skel.end_site
    assert all(len(c) == 6 for c, j in zip(skel.channels, joints) if j)
    assert set(o for o in skel.rotation_orders if o) == {"ZXY"}
    assert skel.has_position_channels[joints].all()


def test_cmu_120_fps(read_real):
    assert read_real("cmu/01_01.bvh").fps == 120.0  # Frame Time: .0083333
    assert read_real("cmu/neutral_01_000.bvh").fps == 120.0  # 0.008333


def test_ccbase_zup_extra_root(read_real):
    zup = read_real("ccbase/007_01.bvh").skeleton
    yup = read_real("ccbase/006_01.bvh").skeleton
    assert zup.names[0] == "RL_BoneRoot"
    assert int((~zup.end_site).sum()) == 101
    assert int((~yup.end_site).sum()) == 100
    assert zup.names[1:] == yup.names


def test_dog_crlf(shared_data, read_real):
    path = "dog/D1_010_KAN01_002.bvh"
    assert b"\r\n" in (shared_data / path).read_bytes()[:200]
    motion = read_real(path)
    assert all("\r" not in n for n in motion.skeleton.names)
    assert "Tail" in " ".join(motion.skeleton.names)


def test_fixture_dialects(read_real):
    mixamo = read_real("fixtures/test_freebvh.bvh").skeleton
    assert mixamo.names[0] == "mixamorig:Hips"
    blender = read_real("fixtures/test3.bvh")
    skel = blender.skeleton
    assert blender.fps == 24.0
    assert {"spine.001", "shoulder.L"} <= set(skel.names)
    assert Counter(len(c) for c in skel.channels)[3] >= 1
    assert Counter(len(c) for c in skel.channels)[6] >= 1
    assert {"XYZ", "YXZ"} <= set(skel.rotation_orders)


# ------------------------------------------------------------ small dialects
def test_base_file(tmp_path):
    motion = read_bvh(write(tmp_path, BASE))
    skel = motion.skeleton
    assert skel.names == ["Hips", "Spine", "Spine_end"]
    assert skel.parents.tolist() == [-1, 0, 1]
    assert skel.end_site.tolist() == [False, False, True]
    assert skel.rotation_orders == ["ZXY", "ZXY", ""]
    assert motion.num_frames == 2 and motion.fps == 30.0
    assert motion.source == str(tmp_path / "clip.bvh")
    np.testing.assert_allclose(motion.translations[1, 0], [1, 90, 0])
    np.testing.assert_allclose(motion.translations[:, 1], [[0, 10, 0]] * 2)
    # Spine: Zrotation 10 then 20 degrees.
    angle = np.radians(20)
    rz = np.array([[np.cos(angle), -np.sin(angle), 0],
                   [np.sin(angle), np.cos(angle), 0], [0, 0, 1]])
    np.testing.assert_allclose(motion.rotations[1, 1], rz, atol=1e-12)
    np.testing.assert_allclose(motion.raw_channels[1], [1, 90, 0, 0, 0, 0, 20, 0, 0])


def test_crlf_and_tabs(tmp_path):
    tabbed = [line.replace("  ", "\t") for line in BASE]
    tabbed[L_SPINE_OFFSET - 1] = "\tOFFSET\t0\t10\t0  "
    tabbed[L_FRAME0 - 1] = "0\t90\t0 0 0 0\t10 0 0\t"
    ref = read_bvh(write(tmp_path, BASE, "ref.bvh"))
    for newline in ("\r\n", "\n", "\r\n\r\n"):
        motion = read_bvh(write(tmp_path, tabbed, "crlf.bvh", newline))
        assert motion.skeleton.names == ref.skeleton.names
        np.testing.assert_array_equal(motion.raw_channels, ref.raw_channels)
        np.testing.assert_array_equal(motion.skeleton.offsets, ref.skeleton.offsets)


def test_odd_joint_names(tmp_path):
    lines = list(BASE)
    lines[1] = "ROOT mixamorig:Hips"
    lines[L_SPINE - 1] = "  JOINT Left Upper Arm.001"
    motion = read_bvh(write(tmp_path, lines, newline="\r\n"))
    assert motion.skeleton.names == ["mixamorig:Hips", "Left Upper Arm.001",
                                     "Left Upper Arm.001_end"]


def test_braces_on_declaration_line(tmp_path):
    lines = list(BASE)
    lines[1:3] = ["ROOT Hips {"]
    lines[L_SPINE - 2:L_SPINE] = ["  JOINT Spine{"]
    lines = [line if line.strip() != "End Site" else line + " {" for line in lines]
    lines.remove("    {")
    motion = read_bvh(write(tmp_path, lines))
    assert motion.skeleton.names == ["Hips", "Spine", "Spine_end"]


def test_case_insensitive_channel_names(tmp_path):
    path = write(tmp_path, replace(L_SPINE_CHANNELS,
                                   "    CHANNELS 3 zrotation XROTATION Yrotation"))
    skel = read_bvh(path).skeleton
    assert skel.channels[1] == ("Zrotation", "Xrotation", "Yrotation")


def test_zero_frames(tmp_path):
    path = write(tmp_path, BASE[:L_FRAMES - 1] + ["Frames: 0", BASE[L_FRAME_TIME - 1]])
    motion = read_bvh(path)
    assert motion.num_frames == 0 and motion.num_joints == 3
    assert motion.rotations.shape == (0, 3, 3, 3)
    assert motion.raw_channels.shape == (0, 9)
    assert motion.global_positions().shape == (0, 3, 3)


def test_non_integer_fps_kept(tmp_path):
    motion = read_bvh(write(tmp_path, replace(L_FRAME_TIME, "Frame Time: 0.04")))
    assert motion.fps == 25.0
    motion = read_bvh(write(tmp_path, replace(L_FRAME_TIME, "Frame Time: 0.0125333")))
    assert motion.fps == pytest.approx(1 / 0.0125333)


# ------------------------------------------------------------------- errors
def test_error_truncated_frames(tmp_path):
    expect_error(write(tmp_path, BASE[:L_FRAME0]), L_FRAME0, "truncated",
                 "Frames: 2")


def test_error_truncated_mid_line(tmp_path):
    path = write(tmp_path, BASE[:L_FRAME0] + ["1 90 0 0"])
    expect_error(path, L_FRAME1, "frame 1", "4 values", "expected 9")


def test_error_truncated_frame_header(tmp_path):
    expect_error(write(tmp_path, BASE[:L_FRAMES]), L_FRAMES, "truncated")
    expect_error(write(tmp_path, BASE[:L_MOTION]), L_MOTION, "truncated")


def test_error_missing_motion(tmp_path):
    expect_error(write(tmp_path, BASE[:L_ROOT_CLOSE]), L_ROOT_CLOSE,
                 "missing MOTION")


def test_error_wrong_value_count(tmp_path):
    path = write(tmp_path, replace(L_FRAME0, "0 90 0 0 0 0 10 0"))
    expect_error(path, L_FRAME0, "frame 0", "8 values", "expected 9")
    path = write(tmp_path, replace(L_FRAME1, "1 90 0 0 0 0 20 0 0 7"))
    expect_error(path, L_FRAME1, "frame 1", "10 values")


def test_error_too_many_frames(tmp_path):
    path = write(tmp_path, BASE + ["2 90 0 0 0 0 30 0 0"])
    expect_error(path, L_FRAME1 + 1, "more frame lines")


@pytest.mark.parametrize("token", ["abc", "1,5", "0x10", "--1", "1_1"])
def test_error_non_numeric_frame(tmp_path, token):
    """The error names the token and its place, not the whole line (Python's
    ``float`` takes ``1_1``; BVH does not)."""
    path = write(tmp_path, replace(L_FRAME1, f"1 90 0 {token} 0 0 20 0 0"))
    expect_error(path, L_FRAME1, "non-numeric", "frame 1", repr(token), "value 4 of 9")


def test_a_skeleton_without_channels_names_missing_frame_lines(tmp_path):
    """``Frames: 100000000000`` over no channels: one error line, not the
    allocation of terabytes."""
    path = tmp_path / "nochan.bvh"
    path.write_text("HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n JOINT Spine\n {\n  OFFSET 0 1 0"
                    "\n  End Site\n  {\n   OFFSET 0 1 0\n  }\n }\n}\nMOTION\n"
                    "Frames: 100000000000\nFrame Time: 0.04\n\n\n")
    with pytest.raises(BVHError, match="'Frames: 100000000000' but only 2 lines follow"):
        read_bvh(path)


@pytest.mark.parametrize("token", ["nan", "NaN", "inf", "-inf", "1e999"])
def test_error_non_finite_frame(tmp_path, token):
    path = write(tmp_path, replace(L_FRAME0, f"0 90 0 {token} 0 0 10 0 0"))
    expect_error(path, L_FRAME0, "non-finite", "frame 0")


def test_error_bad_offset(tmp_path):
    expect_error(write(tmp_path, replace(L_SPINE_OFFSET, "    OFFSET 0 x 0")),
                 L_SPINE_OFFSET, "non-numeric", "OFFSET")
    expect_error(write(tmp_path, replace(L_SPINE_OFFSET, "    OFFSET 0 nan 0")),
                 L_SPINE_OFFSET, "non-finite", "OFFSET")
    expect_error(write(tmp_path, replace(L_SPINE_OFFSET, "    OFFSET 0 1")),
                 L_SPINE_OFFSET, "3 values")


def test_error_unknown_channel(tmp_path):
    path = write(tmp_path, replace(L_SPINE_CHANNELS,
                                   "    CHANNELS 3 Zrotation Wrotation Yrotation"))
    expect_error(path, L_SPINE_CHANNELS, "unknown channel", "Wrotation")


def test_error_channel_count(tmp_path):
    path = write(tmp_path, replace(L_SPINE_CHANNELS,
                                   "    CHANNELS 4 Zrotation Xrotation Yrotation"))
    expect_error(path, L_SPINE_CHANNELS, "CHANNELS says 4")


def test_error_duplicate_joint(tmp_path):
    expect_error(write(tmp_path, replace(L_SPINE, "  JOINT Hips")), L_SPINE,
                 "duplicate joint name", "Hips")


def test_error_extra_closing_brace(tmp_path):
    lines = BASE[:L_ROOT_CLOSE - 1] + ["  }"] + BASE[L_ROOT_CLOSE - 1:]
    expect_error(write(tmp_path, lines), L_ROOT_CLOSE + 1, "unbalanced braces")


def test_error_missing_closing_brace(tmp_path):
    lines = BASE[:L_ROOT_CLOSE - 1] + BASE[L_ROOT_CLOSE:]
    # MOTION moves up to the removed line's number.
    expect_error(write(tmp_path, lines), L_ROOT_CLOSE, "unbalanced braces",
                 "not closed")


def test_error_brace_without_joint(tmp_path):
    lines = BASE[:1] + ["{"] + BASE[1:]
    expect_error(write(tmp_path, lines), 2, "unbalanced braces")


@pytest.mark.parametrize("line", ["OFFSET 0 0 0", "CHANNELS 3 Zrotation Xrotation Yrotation"])
def test_error_outside_any_joint(tmp_path, line):
    lines = BASE[:1] + [line] + BASE[1:]  # before the ROOT
    expect_error(write(tmp_path, lines), 2, f"{line.split()[0]} outside of any joint")


@pytest.mark.parametrize("scale", ["0", "-1", "nan", "x"])
def test_error_bad_declared_scale(tmp_path, scale):
    says = f"# satagraph: up_axis=+Y scale={scale}"
    expect_error(write(tmp_path, replace(1, f"HIERARCHY {says}")), 1, "bad scale", scale)
    expect_error(write(tmp_path, BASE + [says]), len(BASE) + 1, "bad scale", scale)


@pytest.mark.parametrize("content", [b"", b"   \n\t\n", b"\r\n"])
def test_error_empty_file(tmp_path, content):
    path = tmp_path / "empty.bvh"
    path.write_bytes(content)
    expect_error(path, 1, "empty file")


def test_error_missing_file(tmp_path):
    err = expect_error(tmp_path / "nope.bvh", 0, "cannot read", "no such file")
    assert "nope.bvh" in str(err)


def test_error_directory(tmp_path):
    expect_error(tmp_path, 0, "cannot read")


def test_error_no_hierarchy(tmp_path):
    expect_error(write(tmp_path, BASE[1:]), 1, "expected HIERARCHY")


def test_error_bad_frame_time(tmp_path):
    for text in ("Frame Time: 0", "Frame Time: -0.1", "Frame Time: nan"):
        expect_error(write(tmp_path, replace(L_FRAME_TIME, text)), L_FRAME_TIME,
                     "Frame Time")
    expect_error(write(tmp_path, replace(L_FRAMES, "Frames: two")), L_FRAMES,
                 "Frames: two")


def test_extreme_frame_time_is_bvh_error_or_valid(tmp_path):
    # A huge Frame Time must not be snapped to 0 fps, a subnormal one must
    # not overflow.
    motion = read_bvh(write(tmp_path, replace(L_FRAME_TIME, "Frame Time: 33333")))
    assert 0 < motion.fps < 1e-4
    expect_error(write(tmp_path, replace(L_FRAME_TIME, "Frame Time: 1e-320")),
                 L_FRAME_TIME, "Frame Time")


def test_only_bvh_errors_on_corrupted_input(tmp_path):
    """Random edits of a valid file either read or raise BVHError."""
    rng = random.Random(0)
    text = "\n".join(BASE) + "\n"
    alphabet = "{}x.-:\n\r \t0eE+#"
    path = tmp_path / "fuzz.bvh"
    failures = 0
    for _ in range(400):
        chars = list(text)
        i = rng.randrange(len(chars))
        op = rng.randrange(4)
        if op == 0:
            chars = chars[:i]
        elif op == 1:
            del chars[i]
        elif op == 2:
            chars[i] = rng.choice(alphabet)
        else:
            chars.insert(i, rng.choice(alphabet))
        path.write_text("".join(chars), newline="")
        try:
            read_bvh(path)
        except BVHError as err:
            failures += 1
            assert str(err).startswith(f"{path}:")
    assert failures > 50


@pytest.mark.parametrize("text, found", [
    ("a\n# satagraph: up_axis=+Z scale=0.01\n", ("+Z", 0.01)),
    ("a\r\n# satagraph: canonical up_axis=+Y\r\n\r\n  \n", ("+Y", None)),
    ("a\n  # satagraph: up_axis=-X \n", ("-X", None)),
    ("# satagraph: up_axis=+Z\n", None),  # no line before it: not a declaration
    ("a\n# satagraph: up_axis=+Z\nb\n", None),  # not the last line
])
def test_declaration_is_read_on_the_last_line_only(text, found):
    from satagraph.io.bvh_reader import _DECLARATION, _declaration
    rest, rig = _declaration("x.bvh", text)
    assert (rig and (rig.up_axis, rig.scale)) == (found or None)
    whole = _DECLARATION.search(text)  # what a whole-text search finds
    assert rest == (text if whole is None else text[:whole.start()] + "\n")


def test_a_joint_named_like_a_made_up_end_site_name_is_read(tmp_path):
    """End Sites are named ``<parent>_end``; a later joint of the file called
    that keeps its name and the End Site takes another."""
    path = tmp_path / "named.bvh"
    path.write_text("HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 3 Zrotation Xrotation "
                    "Yrotation\n JOINT Spine\n {\n  OFFSET 0 1 0\n  CHANNELS 3 Zrotation "
                    "Xrotation Yrotation\n  End Site\n  {\n   OFFSET 0 1 0\n  }\n }\n"
                    " JOINT Spine_end\n {\n  OFFSET 1 0 0\n  CHANNELS 3 Zrotation Xrotation "
                    "Yrotation\n  End Site\n  {\n   OFFSET 1 0 0\n  }\n }\n}\nMOTION\n"
                    "Frames: 1\nFrame Time: 0.04\n0 0 0 0 0 0 0 0 0\n")
    skeleton = read_bvh(path).skeleton
    assert skeleton.names == ["Hips", "Spine", "Spine_end2", "Spine_end", "Spine_end_end"]
    assert list(skeleton.end_site) == [False, False, True, False, True]


def test_the_error_crosses_process_boundaries_whole():
    """An error raised in a worker process reaches its parent pickled: it
    failed to unpickle, and a benchmark's pool broke without the reason."""
    import pickle
    err = pickle.loads(pickle.dumps(BVHError("x.bvh", 3, "bad frame")))
    assert (err.path, err.line, err.message, str(err)) == ("x.bvh", 3, "bad frame",
                                                           "x.bvh:3: bad frame")
