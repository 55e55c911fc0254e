"""BVH writer: round trips on real and synthetic motions, format, atomicity."""
from __future__ import annotations

import os
import re
import stat
from pathlib import Path

import numpy as np
import pytest

import satagraph.io.bvh_writer as bvh_writer
from satagraph.io import channel_values, read_bvh, write_bvh
from satagraph.motion import Motion
from satagraph.skeleton import Skeleton


def _extent(positions: np.ndarray) -> float:
    return float(np.ptp(positions.reshape(-1, 3), axis=0).max())


def assert_same_positions(a: Motion, b: Motion) -> None:
    """Global positions agree to 1e-6 of the motion's spatial extent."""
    pa, pb = a.global_positions(), b.global_positions()
    assert pa.shape == pb.shape
    tol = 1e-6 * max(1.0, _extent(pa))
    np.testing.assert_allclose(pb, pa, rtol=1e-5, atol=tol)


def listing(folder: Path) -> list:
    return sorted(p.name for p in folder.iterdir())


# --------------------------------------------------------------- real files
def test_roundtrip_raw_channels(skeleton_row, read_real, tmp_path,
                                assert_same_hierarchy):
    motion = read_real(skeleton_row["path"])
    out = tmp_path / "out.bvh"
    write_bvh(motion, out)
    again = read_bvh(out)
    assert_same_hierarchy(motion.skeleton, again.skeleton)
    assert again.num_frames == motion.num_frames == int(skeleton_row["frames"])
    assert again.fps == pytest.approx(motion.fps, rel=1e-6)
    assert np.allclose(again.raw_channels, motion.raw_channels, rtol=1e-5, atol=1e-6)


def test_roundtrip_without_raw_channels(skeleton_row, read_real, tmp_path,
                                        assert_same_hierarchy):
    """Channel values re-derived from the rotations (Euler angles may differ
    by multiples of 360 degrees): compare what they mean, by FK."""
    motion = read_real(skeleton_row["path"]).slice(0, 120).with_()
    assert motion.raw_channels is None
    out = tmp_path / "derived.bvh"
    write_bvh(motion, out)
    again = read_bvh(out)
    assert_same_hierarchy(motion.skeleton, again.skeleton)
    assert again.num_frames == motion.num_frames
    np.testing.assert_allclose(again.rotations, motion.rotations, atol=1e-6)
    np.testing.assert_allclose(again.translations, motion.translations,
                               rtol=1e-5, atol=1e-6)
    assert_same_positions(motion, again)


def test_roundtrip_every_file(every_file_row, read_real, tmp_path):
    """Every file of the manifest (one per skeleton id without --slow)."""
    motion = read_real(every_file_row["path"])
    write_bvh(motion, tmp_path / "a.bvh")
    assert np.allclose(read_bvh(tmp_path / "a.bvh").raw_channels,
                       motion.raw_channels, rtol=1e-5, atol=1e-6)
    write_bvh(motion.with_(), tmp_path / "b.bvh")
    assert_same_positions(motion, read_bvh(tmp_path / "b.bvh"))


def test_manifest_fps_survives_roundtrip(read_real, tmp_path):
    for path, fps in [("cmu/01_01.bvh", 120.0), ("fixtures/test3.bvh", 24.0),
                      ("ccbase/006_01.bvh", 60.0)]:
        motion = read_real(path).slice(0, 5)
        write_bvh(motion, tmp_path / "fps.bvh")
        assert read_bvh(tmp_path / "fps.bvh").fps == fps


# ---------------------------------------------------------------- synthetic
def test_roundtrip_synthetic(tiny_motion, tmp_path, assert_same_hierarchy):
    out = tmp_path / "tiny.bvh"
    write_bvh(tiny_motion, out)
    again = read_bvh(out)
    assert_same_hierarchy(tiny_motion.skeleton, again.skeleton)
    np.testing.assert_allclose(again.rotations, tiny_motion.rotations, atol=1e-6)
    np.testing.assert_allclose(again.translations, tiny_motion.translations,
                               atol=1e-6)
    # Written values read back and re-written are the same values, and the
    # same text from then on.
    write_bvh(again, tmp_path / "again.bvh")
    third = read_bvh(tmp_path / "again.bvh")
    np.testing.assert_array_equal(third.raw_channels, again.raw_channels)
    write_bvh(third, tmp_path / "third.bvh")
    assert (tmp_path / "third.bvh").read_text() == (tmp_path / "again.bvh").read_text()


def test_channel_values_layout(tiny_motion):
    values = channel_values(tiny_motion)
    skel = tiny_motion.skeleton
    assert values.shape == (tiny_motion.num_frames, skel.num_channels)
    # Root position channels come first, verbatim.
    np.testing.assert_allclose(values[:, :3], tiny_motion.translations[:, 0])
    # Raw channels, when present and still saying what the motion holds,
    # are used verbatim; values that say something else are not.
    raw = values.copy()
    assert channel_values(tiny_motion.with_(raw_channels=raw)) is raw
    other = np.arange(values.size, dtype=float).reshape(values.shape)
    np.testing.assert_allclose(channel_values(tiny_motion.with_(raw_channels=other)), values)


def test_position_channels_in_any_order(tmp_path, random_motion):
    skel = Skeleton(
        names=["root", "child", "child_end"], parents=np.array([-1, 0, 1]),
        offsets=np.array([[0, 0, 0], [1, 2, 3], [0, 1, 0]], dtype=float),
        channels=[("Zposition", "Xposition", "Yposition", "Yrotation",
                   "Xrotation", "Zrotation"),
                  ("Yrotation", "Zposition", "Xrotation", "Yposition",
                   "Zrotation", "Xposition"), ()],
        end_site=np.array([False, False, True]))
    motion = random_motion(skel, num_frames=5, seed=3)
    write_bvh(motion, tmp_path / "order.bvh")
    again = read_bvh(tmp_path / "order.bvh")
    assert again.skeleton.channels == skel.channels
    np.testing.assert_allclose(again.translations, motion.translations, atol=1e-6)
    np.testing.assert_allclose(again.rotations, motion.rotations, atol=1e-6)


def test_a_joint_listed_after_its_siblings_subtree_keeps_its_motion(tmp_path, random_motion):
    """A skeleton in topological but not depth-first order (a Daz ``pelvis``
    inserted under ``hip`` after ``abdomen``'s subtree): each joint's
    channels are written in its own block's place, not in joint order (the
    file's motion was scrambled: joints 134 cm off on a renamed Bandai clip)."""
    chans = ("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation")
    skel = Skeleton(names=["hip", "abdomen", "pelvis", "chest", "thigh"],
                    parents=np.array([-1, 0, 0, 1, 2]),
                    offsets=np.array([[0, 90, 0], [0, 10, 0], [0, 0, 0], [0, 20, 0],
                                      [10, -5, 0]], dtype=float),
                    channels=[chans, chans[3:], chans, chans[3:], chans[3:]],
                    end_site=np.zeros(5, dtype=bool))
    motion = random_motion(skel, num_frames=6, seed=4)
    write_bvh(motion, tmp_path / "daz.bvh")
    again = read_bvh(tmp_path / "daz.bvh")
    assert again.skeleton.names == ["hip", "abdomen", "chest", "pelvis", "thigh"]
    np.testing.assert_allclose(again.global_positions()[:, [0, 1, 3, 2, 4]],
                               motion.global_positions(), atol=1e-6)


def test_odd_names_roundtrip(tiny_skeleton, random_motion, tmp_path,
                             assert_same_hierarchy):
    names = list(tiny_skeleton.names)
    names[0], names[1], names[2] = "mixamorig:Hips", "spine.001", "Head Top"
    names[3] = "Head Top_end"
    skel = tiny_skeleton.replace(names=names)
    motion = random_motion(skel, num_frames=3)
    write_bvh(motion, tmp_path / "names.bvh")
    again = read_bvh(tmp_path / "names.bvh")
    assert_same_hierarchy(skel, again.skeleton)


def test_zero_frames_roundtrip(tiny_motion, tmp_path, assert_same_hierarchy):
    empty = tiny_motion.slice(0, 0)
    for motion in (empty, empty.with_(raw_channels=np.zeros((0, 0)))):
        write_bvh(motion, tmp_path / "empty.bvh")
        text = (tmp_path / "empty.bvh").read_text()
        assert "Frames: 0" in text
        again = read_bvh(tmp_path / "empty.bvh")
        assert again.num_frames == 0
        assert_same_hierarchy(tiny_motion.skeleton, again.skeleton)


def test_single_joint_roundtrip(tmp_path):
    skel = Skeleton(["only"], np.array([-1]), np.zeros((1, 3)),
                    [("Xposition", "Yposition", "Zposition")])
    trans = np.random.default_rng(0).normal(size=(4, 1, 3))
    motion = Motion(skel, np.broadcast_to(np.eye(3), (4, 1, 3, 3)), trans, fps=50)
    write_bvh(motion, tmp_path / "one.bvh")
    again = read_bvh(tmp_path / "one.bvh")
    np.testing.assert_allclose(again.translations, trans, atol=1e-6)
    assert again.fps == 50


def test_root_without_channels_rejected(tiny_skeleton, tmp_path):
    channels = [()] + list(tiny_skeleton.channels[1:])
    skel = tiny_skeleton.replace(channels=channels)
    motion = Motion(skel, np.broadcast_to(np.eye(3), (1, 10, 3, 3)),
                    skel.offsets[None], fps=30)
    with pytest.raises(ValueError, match="root joint needs channels"):
        write_bvh(motion, tmp_path / "x.bvh")
    assert listing(tmp_path) == []


# ------------------------------------------------------------------ format
def test_output_format(tiny_motion, tmp_path):
    out = tmp_path / "fmt.bvh"
    write_bvh(tiny_motion, out)
    raw = out.read_bytes()
    assert b"\r" not in raw
    lines = raw.decode().splitlines()
    assert lines[0] == "HIERARCHY"
    assert lines[1].startswith("ROOT Hips")
    motion_at = lines.index("MOTION")
    assert lines[motion_at + 1] == f"Frames: {tiny_motion.num_frames}"
    assert re.fullmatch(r"Frame Time: 0\.0333333\d*", lines[motion_at + 2])
    frames = lines[motion_at + 3:]
    assert len(frames) == tiny_motion.num_frames
    for line in frames:
        tokens = line.split()
        assert len(tokens) == tiny_motion.skeleton.num_channels
        assert all(re.fullmatch(r"-?\d+\.\d{6,}", t) for t in tokens), line
    for line in lines[:motion_at]:
        if line.strip().startswith("OFFSET"):
            assert all(re.fullmatch(r"-?\d+\.\d{6,}", t) for t in line.split()[1:])
    assert "End Site" in raw.decode()


def test_precision_argument(tiny_motion, tmp_path):
    write_bvh(tiny_motion, tmp_path / "p.bvh", precision=9)
    frame = (tmp_path / "p.bvh").read_text().splitlines()[-1].split()
    assert all(len(t.split(".")[1]) == 9 for t in frame)
    write_bvh(tiny_motion, tmp_path / "q.bvh", precision=2)  # floor of 6
    frame = (tmp_path / "q.bvh").read_text().splitlines()[-1].split()
    assert all(len(t.split(".")[1]) == 6 for t in frame)


def test_new_file_mode_follows_umask(tiny_motion, tmp_path):
    out = tmp_path / "mode.bvh"
    old = os.umask(0o022)
    try:
        write_bvh(tiny_motion, out)
    finally:
        os.umask(old)
    assert stat.S_IMODE(out.stat().st_mode) == 0o644
    out.chmod(0o600)
    write_bvh(tiny_motion, out)  # overwriting keeps the file's mode
    assert stat.S_IMODE(out.stat().st_mode) == 0o600


# --------------------------------------------------------------- atomicity
def test_failure_before_writing_leaves_nothing(tiny_motion, tmp_path, monkeypatch):
    def boom(motion):
        raise RuntimeError("no values")

    monkeypatch.setattr(bvh_writer, "channel_values", boom)
    with pytest.raises(RuntimeError, match="no values"):
        write_bvh(tiny_motion, tmp_path / "x.bvh")
    assert listing(tmp_path) == []


def test_failure_mid_write_keeps_old_file(tiny_motion, tmp_path, monkeypatch):
    out = tmp_path / "clip.bvh"
    out.write_text("old content\n")

    def partial_savetxt(f, values, fmt):
        f.write("0.000000 1.000000\n")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(bvh_writer.np, "savetxt", partial_savetxt)
    with pytest.raises(OSError, match="No space left"):
        write_bvh(tiny_motion, out)
    assert out.read_text() == "old content\n"
    assert listing(tmp_path) == ["clip.bvh"]


def test_failure_on_replace_removes_temp(tiny_motion, tmp_path, monkeypatch):
    def fail(src, dst):
        raise PermissionError(13, "Permission denied", dst)

    monkeypatch.setattr(bvh_writer.os, "replace", fail)
    with pytest.raises(PermissionError):
        write_bvh(tiny_motion, tmp_path / "clip.bvh")
    assert listing(tmp_path) == []


def test_parent_is_a_file(tiny_motion, tmp_path):
    (tmp_path / "afile").write_text("not a folder")
    with pytest.raises(OSError):
        write_bvh(tiny_motion, tmp_path / "afile" / "out.bvh")
    assert listing(tmp_path) == ["afile"]
    assert (tmp_path / "afile").read_text() == "not a folder"


def test_target_is_a_directory(tiny_motion, tmp_path):
    (tmp_path / "out.bvh").mkdir()
    with pytest.raises(OSError):
        write_bvh(tiny_motion, tmp_path / "out.bvh")
    assert listing(tmp_path) == ["out.bvh"]
    assert listing(tmp_path / "out.bvh") == []


def test_missing_parent_folder(tiny_motion, tmp_path):
    with pytest.raises(FileNotFoundError):
        write_bvh(tiny_motion, tmp_path / "nope" / "out.bvh")
    assert listing(tmp_path) == []


def test_overwrite_is_atomic_replace(tiny_motion, tmp_path, monkeypatch):
    out = tmp_path / "clip.bvh"
    write_bvh(tiny_motion.slice(0, 2), out)
    first = out.read_text()
    # A hard link to the old file keeps the old content: the new file was
    # moved into place, not written over the old one.
    os.link(out, tmp_path / "old_link.bvh")
    calls = []
    real_replace = os.replace

    def spy(src, dst):
        calls.append((os.fspath(src), os.fspath(dst)))
        assert Path(src).parent == out.parent and Path(src).stat().st_size > 0
        real_replace(src, dst)

    monkeypatch.setattr(bvh_writer.os, "replace", spy)
    write_bvh(tiny_motion, out)
    assert len(calls) == 1 and calls[0][1] == str(out)
    assert (tmp_path / "old_link.bvh").read_text() == first
    assert out.read_text() != first
    assert read_bvh(out).num_frames == tiny_motion.num_frames
    assert listing(tmp_path) == ["clip.bvh", "old_link.bvh"]


def test_accepts_str_and_pathlike(tiny_motion, tmp_path):
    write_bvh(tiny_motion, str(tmp_path / "a.bvh"))
    write_bvh(tiny_motion, tmp_path / "b.bvh")
    assert (tmp_path / "a.bvh").read_text() == (tmp_path / "b.bvh").read_text()


# ------------------------------------------------------- what is written back
TEXT = ("HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition "
        "Zrotation Xrotation Yrotation\n JOINT Spine\n {\n  OFFSET 1.2345e-07 1.1234567891 0\n"
        "  CHANNELS 3 Zrotation Xrotation Yrotation\n  End Site\n  {\n   OFFSET 0 0.5 0\n  }\n"
        " }\n}\nMOTION\nFrames: 2\nFrame Time: 0.0333333\n"
        "0 90 0 5.1072e-06 1.1234567891 -3 0.25 0 0\n1 91 0 0 0 0 0 12.3456789012 0\n")


def test_values_as_read_are_written_back_exactly(tmp_path):
    """Channel values and offsets read from a file come back value for value,
    tiny ones included (``%.6f`` made 5.1e-06 a zero and a 0.12 micron bone
    one of length zero)."""
    (tmp_path / "in.bvh").write_text(TEXT)
    motion = read_bvh(tmp_path / "in.bvh")
    write_bvh(motion, tmp_path / "out.bvh")
    again = read_bvh(tmp_path / "out.bvh")
    np.testing.assert_array_equal(again.raw_channels, motion.raw_channels)
    np.testing.assert_array_equal(again.skeleton.offsets, motion.skeleton.offsets)
    assert "e-" not in (tmp_path / "out.bvh").read_text().split("MOTION")[0]


def test_offsets_lose_the_last_bits_of_arithmetic(tmp_path):
    """A retarget onto a dog file wrote ``-17.822200000000006`` for its
    ``-17.8222`` and ``-0.0000...0006255933559731327`` for its ``0``: the
    unit and axis turns there and back leave the last bits."""
    (tmp_path / "in.bvh").write_text(TEXT)
    motion = read_bvh(tmp_path / "in.bvh")
    noisy = motion.skeleton.offsets.copy()
    noisy[1] = [-17.822200000000006, -6.255933559731327e-23, 1.2e-7]
    motion = motion.with_(skeleton=motion.skeleton.replace(offsets=noisy))
    write_bvh(motion, tmp_path / "out.bvh")
    assert "OFFSET -17.822200 0.000000 0.00000012" in (tmp_path / "out.bvh").read_text()


def test_a_motion_edited_after_reading_is_written_as_it_now_is(tmp_path):
    """An edit in place or a :func:`dataclasses.replace` is written, not the
    values the file held."""
    import dataclasses
    (tmp_path / "in.bvh").write_text(TEXT)
    motion = read_bvh(tmp_path / "in.bvh")
    assert bvh_writer.raw_channels_hold(motion)
    motion.translations[:, 0, 1] += 100.0
    assert not bvh_writer.raw_channels_hold(motion)
    write_bvh(motion, tmp_path / "moved.bvh")
    np.testing.assert_allclose(read_bvh(tmp_path / "moved.bvh").translations[:, 0, 1],
                               [190.0, 191.0], atol=1e-6)
    still = dataclasses.replace(motion, rotations=np.broadcast_to(
        np.eye(3), motion.rotations.shape).copy())
    write_bvh(still, tmp_path / "still.bvh")
    np.testing.assert_allclose(read_bvh(tmp_path / "still.bvh").rotations,
                               still.rotations, atol=1e-6)


def test_an_edit_under_a_radian_is_written(tmp_path):
    """A thousandth of a radian about +Y on the spine (a smoothing pass's
    size of change) is no longer the file's values: it is written."""
    (tmp_path / "in.bvh").write_text(TEXT)
    motion = read_bvh(tmp_path / "in.bvh")
    c, s = np.cos(1e-3), np.sin(1e-3)
    motion.rotations[:, 1] = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]) @ motion.rotations[:, 1]
    assert not bvh_writer.raw_channels_hold(motion)
    write_bvh(motion, tmp_path / "edited.bvh")
    np.testing.assert_allclose(read_bvh(tmp_path / "edited.bvh").rotations, motion.rotations,
                               atol=1e-7)


def test_joints_are_indented_by_depth_and_a_slow_frame_rate_is_kept(tmp_path):
    """Two spaces a level (ROOT, JOINT, End Site and their lines), and a
    motion of half a frame a second is written at that rate."""
    (tmp_path / "in.bvh").write_text(TEXT)
    motion = read_bvh(tmp_path / "in.bvh").with_(fps=0.5)
    write_bvh(motion, tmp_path / "out.bvh")
    head = (tmp_path / "out.bvh").read_text().split("MOTION")[0].splitlines()
    assert [len(line) - len(line.lstrip()) for line in head] == [
        0, 0, 0, 2, 2, 2, 2, 4, 4, 4, 4, 6, 4, 2, 0]
    assert read_bvh(tmp_path / "out.bvh").fps == 0.5


def test_a_tiny_frame_time_is_written_as_it_reads(tiny_motion, tmp_path):
    """``Frame Time`` keeps ten significant digits: 1e-10 s is not written as
    0, which no reader takes."""
    fast = tiny_motion.with_(fps=1e10)
    write_bvh(fast, tmp_path / "fast.bvh")
    assert read_bvh(tmp_path / "fast.bvh").fps == pytest.approx(1e10)


def test_euler_angles_in_chunks_are_the_whole_takes(read_real, monkeypatch) -> None:
    """Channel values computed 64 frames and 3 joint tracks at a time
    (temporaries of a chunk on a long take) are those computed all at once,
    to the bit, the unwrapping across chunk borders included."""
    motion = read_real("cmu/01_01.bvh").slice(0, 700).with_(raw_channels=None)
    rng = np.random.default_rng(0)
    turned = motion.rotations.copy()  # spins that wrap past 180 degrees
    turned[:, 0] = turned[:, 0] @ np.stack([_yaw(a) for a in
                                            np.cumsum(rng.uniform(0, 0.3, len(turned)))])
    motion = motion.with_(rotations=turned)
    monkeypatch.setattr(bvh_writer, "EULER_FRAMES", 10 ** 9)
    monkeypatch.setattr(bvh_writer, "EULER_JOINTS", 10 ** 9)
    whole = channel_values(motion)
    monkeypatch.setattr(bvh_writer, "EULER_FRAMES", 64)
    monkeypatch.setattr(bvh_writer, "EULER_JOINTS", 3)
    np.testing.assert_array_equal(channel_values(motion), whole)
    assert np.abs(np.diff(whole, axis=0)).max() < 180  # unwrapped across the borders
    assert np.ptp(whole, axis=0).max() > 360


def _yaw(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def test_euler_angles_are_matrix_to_euler_to_an_ulp(read_real) -> None:
    """The writer's angles (numpy quaternions, then roma's quaternion to
    Euler) are those of matrix_to_euler on the matrices, on two rigs and
    rotation orders (CMU's ZYX, the dog's ZXY)."""
    import torch
    from satagraph.ops.rotation import matrix_to_euler
    for path in ("cmu/01_01.bvh", "dog/D1_001_KAN01_001.bvh"):
        motion = read_real(path).slice(0, 300)
        orders = motion.skeleton.rotation_orders
        for order in sorted({o for o in orders if o}):
            joints = [j for j, o in enumerate(orders) if o == order]
            expected = matrix_to_euler(torch.from_numpy(motion.rotations[:, joints]), order)
            np.testing.assert_allclose(  # bit for bit on the VM; an ulp elsewhere
                bvh_writer._euler_radians(motion.rotations, joints, order), expected.numpy(),
                rtol=0, atol=1e-14)
