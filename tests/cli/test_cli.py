"""The ``satagraph`` command: inspect, convert, demo, errors, plugins."""
from __future__ import annotations

import importlib.util
import io
import json
import os
import re
import runpy
import sys
import types
from pathlib import Path

import numpy as np
import pytest
import torch

import satagraph.cli as cli
from satagraph.cli import main
from satagraph.io import BVHError, read_bvh, write_bvh
from satagraph.motion import Motion
from satagraph.ops.rotation import axis_angle_matrix

BANDAI = "bandai/dataset-1_bow_active_001.bvh"


def run(capsys, *argv: str):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def rest_motion(skeleton, up: str = "+Y", frames: int = 3) -> Motion:
    """The rest pose for a few frames, turned so that +Y goes to :obj:`up`."""
    rot = np.broadcast_to(np.eye(3), (frames, skeleton.num_joints, 3, 3)).copy()
    if up == "+Z":  # +90 degrees about X takes +Y to +Z
        quarter = torch.tensor(np.pi / 2, dtype=torch.float64)
        rot[:, 0] = axis_angle_matrix(quarter, "X").numpy()
    trans = np.broadcast_to(skeleton.offsets, (frames, skeleton.num_joints, 3))
    return Motion(skeleton, rot, trans.copy(), fps=25.0)


@pytest.fixture
def tiny_file(tiny_skeleton, tmp_path) -> Path:
    path = tmp_path / "tiny.bvh"
    write_bvh(rest_motion(tiny_skeleton), path)
    return path


# ------------------------------------------------------------------ inspect
def test_inspect_table_real_file(capsys, shared_data, manifest):
    code, out, err = run(capsys, "inspect", str(shared_data / BANDAI))
    assert code == 0 and err == ""
    row = next(r for r in manifest if r["path"] == BANDAI)
    rows = dict(re.split(r"\s{2,}", line, maxsplit=1)
                for line in out.strip().splitlines())
    assert rows["joints"] == f"27 ({row['joints']} without end sites)"
    assert rows["end sites"] == "5"
    assert rows["frames"] == row["frames"]
    assert rows["fps"] == "30"
    assert rows["up axis"].startswith("+Y (detected, confidence")
    assert rows["rotation orders"] == "ZXY x22"
    assert "22 joints with 6" in rows["channels"]
    assert rows["root"] == "joint_Root"
    assert rows["height"].endswith(" m") and "file units, 1." in rows["height"]  # cm
    assert rows["units"].startswith("cm (human, confidence 0.90")
    assert rows["frame 0"] == "motion"
    code, out, _ = run(capsys, "inspect", str(shared_data / "ccbase" / "007_05.bvh"))
    rows = dict(re.split(r"\s{2,}", line, maxsplit=1) for line in out.strip().splitlines())
    assert rows["frame 0"] == "the rig's bind pose, not motion: read as frame 1's pose"


def test_inspect_json_real_file(capsys, shared_data, manifest):
    for row in manifest:
        if row["path"] in (BANDAI, "cmu/01_01.bvh", "ccbase/007_01.bvh",
                           "dog/D1_010_KAN01_002.bvh", "fixtures/test3.bvh"):
            code, out, _ = run(capsys, "inspect", "--json",
                               str(shared_data / row["path"]))
            assert code == 0
            info = json.loads(out)
            assert info["frames"] == int(row["frames"])
            assert info["joints_without_end_sites"] == int(row["joints"])
            assert info["joints"] == info["joints_without_end_sites"] + info["end_sites"]
            assert info["fps"] == pytest.approx(float(row["fps"]), rel=1e-4)
            assert info["duration"] == pytest.approx(info["frames"] / info["fps"])
            assert info["up_axis"] == "+Y"  # frame 0 of all of these stands on Y
            assert info["height"] > 0
            assert sum(info["channel_layout"].values()) == info["joints"]
            assert info["bind_frame"] == (row["path"] == "cmu/01_01.bvh")  # CMU's T first


def test_inspect_json_synthetic(capsys, tiny_file):
    code, out, _ = run(capsys, "inspect", str(tiny_file), "--json")
    assert code == 0
    info = json.loads(out)
    rig = info.pop("rig")
    # no hands, not metres-sized, no known exporter: the units are undecided
    assert rig["units_how"] == "kept" and rig["units"] == "file"
    assert rig["up_axis_how"] == "detected" and 0.0 <= rig["up_axis_confidence"] <= 1.0
    assert set(rig["up_axis_evidence"]) >= {"rest"}
    assert any("units unknown" in w for w in rig["warnings"])
    assert info.pop("height_m") == pytest.approx(150.0)  # file units kept
    assert info == {
        "file": str(tiny_file), "root": "Hips", "joints": 10,
        "joints_without_end_sites": 7, "end_sites": 3, "frames": 3,
        "fps": 25.0, "duration": pytest.approx(0.12), "up_axis": "+Y",
        "height": pytest.approx(150.0), "max_depth": 3,
        "rotation_orders": {"XYZ": 1, "XZY": 1, "YXZ": 1, "YZX": 1, "ZXY": 2,
                            "ZYX": 1},
        "channel_layout": {"0": 3, "3": 5, "6": 2},
        "position_channel_joints": 2, "channels_per_frame": 27, "bind_frame": False,
    }


def test_inspect_detects_z_up(capsys, tiny_skeleton, tmp_path):
    # Toes straight down: a body this thin with toes pointing forward is
    # ambiguous (the toes would be "below" along the forward axis too).
    offsets = tiny_skeleton.offsets.copy()
    offsets[[6, 9]] = [0.0, -5.0, 0.0]
    path = tmp_path / "zup.bvh"
    write_bvh(rest_motion(tiny_skeleton.replace(offsets=offsets), up="+Z"), path)
    code, out, _ = run(capsys, "inspect", "--json", str(path))
    info = json.loads(out)
    assert info["up_axis"] == "+Z"
    assert info["height"] == pytest.approx(150.0)


def test_inspect_table_synthetic(capsys, tiny_file):
    code, out, _ = run(capsys, "inspect", str(tiny_file))
    assert code == 0
    assert "10 (7 without end sites)" in out
    assert "XYZ x1" in out and "ZXY x2" in out
    assert "0.120 s" in out
    assert out.splitlines()[0].split() == ["file", str(tiny_file)]


def test_inspect_zero_frames(capsys, tiny_skeleton, tmp_path):
    path = tmp_path / "empty.bvh"
    write_bvh(rest_motion(tiny_skeleton, frames=0), path)
    code, out, _ = run(capsys, "inspect", "--json", str(path))
    info = json.loads(out)
    assert code == 0 and info["frames"] == 0 and info["duration"] == 0
    assert info["up_axis"] == "+Y"


# ------------------------------------------------------------------ convert
def test_convert_roundtrip(capsys, shared_data, tmp_path, assert_same_hierarchy):
    src = shared_data / "fixtures/test_mocapbank.bvh"
    out = tmp_path / "out.bvh"
    code, text, err = run(capsys, "convert", str(src), str(out))
    assert code == 0 and err == ""
    assert str(out) in text and "455 frames" in text
    a, b = read_bvh(src), read_bvh(out)
    assert_same_hierarchy(a.skeleton, b.skeleton)
    assert np.allclose(a.raw_channels, b.raw_channels, rtol=1e-5, atol=1e-6)
    assert b.fps == a.fps


def test_convert_in_place(capsys, tiny_file):
    before = read_bvh(tiny_file)
    assert main(["convert", str(tiny_file), str(tiny_file)]) == 0
    np.testing.assert_allclose(read_bvh(tiny_file).raw_channels, before.raw_channels)
    assert sorted(p.name for p in tiny_file.parent.iterdir()) == ["tiny.bvh"]


def test_convert_fps(capsys, shared_data, tmp_path):
    pytest.importorskip("satagraph.transforms.canonical")
    out = tmp_path / "30.bvh"
    code, text, _ = run(capsys, "convert", str(shared_data / "cmu/angry_13_000.bvh"),
                        str(out), "--fps", "30")
    assert code == 0
    motion = read_bvh(out)
    assert motion.fps == 30.0
    assert motion.num_frames == pytest.approx(140 / 4, abs=1)
    assert "30 fps" in text


def test_convert_canonical(capsys, shared_data, tmp_path):
    pytest.importorskip("satagraph.transforms.canonical")
    out = tmp_path / "canon.bvh"
    code, text, _ = run(capsys, "convert", str(shared_data / BANDAI), str(out),
                        "--canonical", "--fps", "15")
    assert code == 0 and "canonical" in text
    motion = read_bvh(out)
    assert motion.fps == 15.0
    assert "joint_Root" not in motion.skeleton.names  # motionless root removed
    pos = motion.global_positions()
    assert 1.0 < np.ptp(pos[0, :, 1]) < 2.2  # metres, Y up
    code, out_json, _ = run(capsys, "inspect", "--json", str(out))
    assert json.loads(out_json)["up_axis"] == "+Y"


def test_convert_canonical_up_axis_flag(capsys, tiny_skeleton, tmp_path):
    pytest.importorskip("satagraph.transforms.canonical")
    src = tmp_path / "zup.bvh"
    write_bvh(rest_motion(tiny_skeleton, up="+Z"), src)
    out = tmp_path / "yup.bvh"
    assert main(["convert", str(src), str(out), "--canonical", "--up-axis", "z",
                 "--units", "m"]) == 0
    pos = read_bvh(out).global_positions()[0]
    assert np.argmax(np.ptp(pos, axis=0)) == 1  # now Y up


def test_convert_up_axis_needs_canonical(capsys, tiny_file, tmp_path):
    code, _, err = run(capsys, "convert", str(tiny_file), str(tmp_path / "o.bvh"),
                       "--up-axis", "+Z")
    assert code == 2
    assert err.strip() == "satagraph: error: --up-axis and --units need --canonical"
    assert not (tmp_path / "o.bvh").exists()


@pytest.mark.parametrize("argv", [["--fps", "0"], ["--fps", "abc"],
                                  ["--canonical", "--up-axis", "W"]])
def test_convert_bad_options(capsys, tiny_file, tmp_path, argv):
    with pytest.raises(SystemExit) as info:
        main(["convert", str(tiny_file), str(tmp_path / "o.bvh"), *argv])
    assert info.value.code == 2
    assert "error" in capsys.readouterr().err


@pytest.mark.parametrize("fps", ["0.5", "2000"])
def test_convert_refuses_a_rate_the_other_commands_refuse(capsys, tiny_file, tmp_path, fps):
    out = tmp_path / "o.bvh"
    code, _, err = run(capsys, "convert", str(tiny_file), str(out), "--fps", fps)
    assert code == 2 and not out.exists()
    assert_one_line_error(err, f"--fps {fps}", "1 to 1000 fps")
    assert main(["convert", str(tiny_file), str(out), "--fps", "1000"]) == 0
    assert read_bvh(out).fps == 1000.0


# ------------------------------------------------------------------- errors
def assert_one_line_error(err: str, *words: str) -> None:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("satagraph: error: ")
    assert "Traceback" not in err
    for word in words:
        assert word in lines[0], lines[0]


def allocate_too_much(args):
    torch.empty(2 ** 58, dtype=torch.uint8)  # torch's CPU allocator refuses it at once


def test_out_of_memory_is_one_line(capsys, monkeypatch, tiny_file, tmp_path):
    import satagraph.cli.train as train
    monkeypatch.setattr(train, "run_reconstruct", allocate_too_much)
    code, out, err = run(capsys, "reconstruct", str(tiny_file), str(tmp_path / "o.bvh"),
                         "--window", "100000")
    assert code == 2 and out == ""
    assert_one_line_error(err, "out of memory: 268435456.0 GiB asked for at once",
                          "--window")
    from satagraph.cli.folders import failure_line
    with pytest.raises(RuntimeError) as info:
        allocate_too_much(None)
    assert failure_line("a.bvh", info.value) == (
        "a.bvh: out of memory: 268435456.0 GiB asked for at once")
    monkeypatch.setattr(train, "run_reconstruct",
                        lambda args: torch.zeros(2, 3) @ torch.zeros(2, 3))
    with pytest.raises(RuntimeError, match="cannot be multiplied"):  # not memory: raised
        main(["reconstruct", str(tiny_file), str(tmp_path / "o.bvh")])


@pytest.mark.parametrize("said, asked", [
    ("CUDA out of memory. Tried to allocate 20.00 GiB. GPU 0 has a total capacity of 139.81 "
     "GiB of which 3.06 GiB is free. Including non-PyTorch memory, this process has 136.74 GiB "
     "memory in use.", "20.00 GiB"),
    ("MPS backend out of memory (MPS allocated: 17.60 GB, other allocations: 1.20 GB, max "
     "allowed: 18.13 GB). Tried to allocate 256.00 MB on private pool.", "256.00 MB")],
    ids=["cuda", "mps"])
def test_out_of_memory_on_a_gpu_says_what_was_asked_for(capsys, monkeypatch, tiny_file,
                                                        tmp_path, said, asked):
    """torch's GPU allocators say the size in a paragraph about the
    device's memory: the line was its first twelve words, cut mid-sentence
    ('... GPU 0 has')."""
    import satagraph.cli.train as train

    def fail(args):
        raise torch.OutOfMemoryError(said)

    monkeypatch.setattr(train, "run_reconstruct", fail)
    code, out, err = run(capsys, "reconstruct", str(tiny_file), str(tmp_path / "o.bvh"))
    assert code == 2 and out == ""
    assert err == (f"satagraph: error: out of memory on the GPU: {asked} asked for at once "
                   "(a shorter --window needs less)\n")


@pytest.mark.parametrize("said", [
    "CUDA error: out of memory\nCUDA kernel errors might be asynchronously reported at some "
    "other API call, so the stacktrace below might be incorrect.",
    "CUDA error: CUBLAS_STATUS_ALLOC_FAILED when calling `cublasCreate(handle)`"],
    ids=["kernel", "cublas"])
def test_out_of_memory_in_a_cuda_library_is_one_line(capsys, monkeypatch, tiny_file, tmp_path,
                                                     said):
    """A CUDA library out of memory raises a plain RuntimeError, without
    the size: it was a traceback; another CUDA error still is one."""
    import satagraph.cli.train as train

    def failing(message: str):
        def fail(args):
            raise RuntimeError(message)
        return fail

    monkeypatch.setattr(train, "run_reconstruct", failing(said))
    code, out, err = run(capsys, "reconstruct", str(tiny_file), str(tmp_path / "o.bvh"))
    assert code == 2 and out == ""
    assert err == ("satagraph: error: out of memory on the GPU (in a CUDA library, which says "
                   "no size) (a shorter --window needs less)\n")
    monkeypatch.setattr(train, "run_reconstruct",
                        failing("CUDA error: device-side assert triggered"))
    with pytest.raises(RuntimeError, match="device-side assert"):
        main(["reconstruct", str(tiny_file), str(tmp_path / "o.bvh")])


def test_error_missing_file(capsys, tmp_path):
    missing = tmp_path / "missing.bvh"
    for argv in (["inspect", str(missing)],
                 ["convert", str(missing), str(tmp_path / "o.bvh")]):
        code, out, err = run(capsys, *argv)
        assert code == 2 and out == ""
        assert_one_line_error(err, str(missing), "No such file")


def test_error_malformed_file(capsys, tmp_path):
    bad = tmp_path / "bad.bvh"
    bad.write_text("HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n"
                   "  CHANNELS 3 Xposition Yposition Zrotation\n}\n")
    code, _, err = run(capsys, "inspect", str(bad))
    assert code == 2
    assert_one_line_error(err, f"{bad}:5:", "not supported")


def test_error_unwritable_output(capsys, tiny_file, tmp_path):
    target = tmp_path / "no" / "such" / "dir.bvh"
    code, _, err = run(capsys, "convert", str(tiny_file), str(target))
    assert code == 2
    assert_one_line_error(err, f"cannot write {target}")
    (tmp_path / "afile").write_text("x")
    code, _, err = run(capsys, "convert", str(tiny_file),
                       str(tmp_path / "afile" / "o.bvh"))
    assert code == 2
    assert_one_line_error(err, "cannot write")


@pytest.mark.parametrize("command", [["retarget", "--target", "t.bvh", "s.bvh"],
                                     ["generate", "--text", "a walk", "--skeleton", "t.bvh"]])
def test_a_carriage_no_mode_names_is_refused_before_any_file_is_read(capsys, tmp_path,
                                                                       command):
    with pytest.raises(SystemExit) as info:
        main([*command, "--carriage", "sometimes", str(tmp_path / "o.bvh")])
    assert info.value.code == 2
    assert capsys.readouterr().err.strip().splitlines()[-1] == (
        f"satagraph {command[0]}: error: argument --carriage: invalid choice: 'sometimes' "
        "(choose from 'auto', 'always', 'never')")
    assert not (tmp_path / "o.bvh").exists()


@pytest.mark.parametrize("frames", [0, 1])
def test_retarget_refuses_a_line_rest_that_shows_no_body(capsys, shared_data, tmp_path, frames):
    """The dog's rig without frames, or in one frame at rest, shows no
    body (``check_shown_body``): ``retarget`` refuses both in one line
    naming the file, as ``generate`` does, and writes nothing."""
    dog = read_bvh(shared_data / "dog" / "D1_001_KAN01_001.bvh").slice(0, frames)
    rig, out = tmp_path / "rig.bvh", tmp_path / "out.bvh"
    write_bvh(dog.with_(rotations=np.broadcast_to(np.eye(3), dog.rotations.shape).copy()), rig)
    code, _, err = run(capsys, "retarget", str(shared_data / BANDAI), "--target", str(rig),
                       "--target-units", "cm", str(out))
    assert code == 2 and not out.exists()
    assert_one_line_error(err.strip().splitlines()[-1], f"{rig}: a rig ", "shows no body")


def test_traceback_flag_reraises(tmp_path):
    with pytest.raises(BVHError):
        main(["--traceback", "inspect", str(tmp_path / "missing.bvh")])


def test_no_command_is_usage_error(capsys):
    with pytest.raises(SystemExit) as info:
        main([])
    assert info.value.code == 2
    assert "COMMAND" in capsys.readouterr().err


# --------------------------------------------------------------------- demo
def test_demo(capsys):
    code, out, err = run(capsys, "demo", "--quick")
    assert code == 0 and err == ""
    assert "built-in example walk" in out
    assert "$ satagraph inspect" in out
    assert "10 (7 without end sites)" in out
    assert "+Y" in out


def test_demo_quick_says_its_file_is_gone_unless_kept(capsys):
    """Without --output the example lives in a temporary folder: the path it
    prints is gone when the command returns, and the line says so (and
    counts the joints as --help and the other commands do)."""
    out = run(capsys, "demo", "--quick")[1]
    wrote = next(line for line in out.splitlines() if " wrote " in line)
    assert "60 frames at 30 fps on a 7-joint skeleton (and 3 end sites)" in wrote
    path = Path(re.search(r" to (\S+\.bvh)", wrote).group(1))
    assert not path.exists()
    assert wrote.endswith(f"{path} (removed when the demo ends: --output PATH keeps it)")


def test_demo_keeps_output(capsys, tmp_path):
    path = tmp_path / "walk.bvh"
    code, out, _ = run(capsys, "demo", "--quick", "--output", str(path), "--json")
    assert code == 0
    info = json.loads(out[out.index("{"):])
    motion = read_bvh(path)
    assert info["frames"] == motion.num_frames == 60
    # the median vertical extent over the frames: a 1.75 m rest pose walking
    assert info["height"] == pytest.approx(1.72, abs=0.01)
    assert info["rig"]["units"] == "m"


def test_inspect_says_a_rig_has_no_motion(capsys, tmp_path):
    """A file of no frames is a rig: ``inspect`` says so instead of calling
    frame 0 motion."""
    path = tmp_path / "rig.bvh"
    path.write_text("HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 3 Zrotation "
                    "Xrotation Yrotation\n End Site\n {\n  OFFSET 0 1 0\n }\n}\n"
                    "MOTION\nFrames: 0\nFrame Time: 0.04\n")
    code, out, _ = run(capsys, "inspect", str(path))
    assert code == 0
    assert "0 frame(s): a rig without motion" in out
    assert re.search(r"^frame 0\s+none$", out, re.M)


def test_demo_quick_spares_a_users_file(capsys, tmp_path):
    """``demo --quick --output FILE.bvh`` rewrites its own walk, never another
    motion."""
    path = tmp_path / "capture.bvh"
    capture = ("HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 3 Zrotation Xrotation "
               "Yrotation\n End Site\n {\n  OFFSET 0 1 0\n }\n}\nMOTION\nFrames: 1\n"
               "Frame Time: 0.04\n0 0 0\n")
    path.write_text(capture)
    code, _, err = run(capsys, "demo", "--quick", "--output", str(path))
    assert code == 2 and "is not the example walk" in err
    assert path.read_text() == capture
    fresh = tmp_path / "walk.bvh"
    assert run(capsys, "demo", "--quick", "--output", str(fresh))[0] == 0
    assert run(capsys, "demo", "--quick", "--output", str(fresh))[0] == 0


def test_example_motion_is_plausible():
    from satagraph.data.examples import example_motion

    motion = example_motion(num_frames=45, fps=30)
    pos = motion.global_positions()
    assert pos.shape == (45, 10, 3)
    feet = pos[:, motion.skeleton.end_site & (pos[0, :, 1] < 0.5)]
    np.testing.assert_allclose(feet[..., 1].min(axis=1), 0.0, atol=1e-9)
    assert pos[-1, 0, 2] > pos[0, 0, 2] + 1.0  # walks forward along +Z
    assert example_motion(num_frames=45).rotations.tobytes() == motion.rotations.tobytes()


# --------------------------------------------------------------- help, plugins
@pytest.mark.parametrize("command, words", [
    ("inspect", ["up axis", "--json"]),
    ("convert", ["--fps", "(1 to 1000)", "--canonical", "atomically"]),
    ("demo", ["built-in", "--output"]),
])
def test_subcommand_help(capsys, command, words):
    with pytest.raises(SystemExit) as info:
        main([command, "--help"])
    assert info.value.code == 0
    out = capsys.readouterr().out
    assert out.startswith(f"usage: satagraph {command}")
    for word in words:
        assert word in out


def test_top_level_help_and_version(capsys):
    with pytest.raises(SystemExit):
        main(["--help"])
    out = capsys.readouterr().out
    for command in ("inspect", "convert", "demo"):
        assert command in out
    with pytest.raises(SystemExit):
        main(["--version"])
    assert capsys.readouterr().out.startswith("satagraph ")


def test_tags_registered_when_available():
    choices = cli.build_parser()._subparsers._group_actions[0].choices
    has_tags = importlib.util.find_spec("satagraph.cli.tags") is not None
    assert ("tags" in choices) == has_tags


#: Paths of the repository that an installed satagraph (a wheel) does not have.
CHECKOUT_ONLY = ("README", "experiments/", "benchmarks/", "tests/", "../shared", "Makefile",
                 ".venv")


def test_no_help_sends_a_user_where_only_a_source_checkout_goes():
    """``satagraph --help`` and every command's: what they cite, a user of
    the installed package has (a command, a named config, the fact itself)."""
    for module, _ in cli.OPTIONAL_COMMANDS:  # one that fails to import has no --help
        importlib.import_module(module)
    parser = cli.build_parser()
    commands = parser._subparsers._group_actions[0].choices
    for name, command in [("satagraph", parser), *commands.items()]:
        text = " ".join(command.format_help().split())
        cited = [path for path in CHECKOUT_ONLY if path in text]
        assert not cited, f"{name} --help cites {cited}"


def test_a_named_config_s_missing_data_says_where_it_looked_and_what_to_give(
        capsys, monkeypatch, tmp_path):
    """Installed, ``satagraph train tiny`` runs where the config's
    ``../shared/data`` is not: the error says where that was looked for
    and that ``--data`` names one's own."""
    monkeypatch.chdir(tmp_path)
    code, _, err = run(capsys, "train", "tiny", "logger.name=none")
    assert code == 2
    assert f"motion source not found: ../shared/data (looked for in {tmp_path})" in err
    assert "--data path/to/bvh_folder" in err


def test_optional_commands(capsys, monkeypatch, tmp_path):
    calls = []
    plugin = types.ModuleType("fake_satagraph_plugin")

    def add_fake_parser(subparsers):
        subparsers.add_parser("fake", help="a fake command")  # no func

    plugin.add_fake_parser = add_fake_parser
    plugin.run_fake = lambda args: calls.append(args.command) or 3
    monkeypatch.setitem(sys.modules, "fake_satagraph_plugin", plugin)
    (tmp_path / "broken_satagraph_plugin.py").write_text("raise RuntimeError('boom')\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(cli, "OPTIONAL_COMMANDS", (
        ("fake_satagraph_plugin", "add_fake_parser"),
        ("satagraph.no_such_module", "add_x_parser"),
        ("broken_satagraph_plugin", "add_y_parser"),
    ))
    assert main(["fake"]) == 3 and calls == ["fake"]
    err = capsys.readouterr().err
    assert "no_such_module" not in err  # missing modules are skipped silently
    assert "broken_satagraph_plugin failed to import" in err and "boom" in err


def test_python_dash_m(capsys, monkeypatch):
    """``python -m satagraph`` runs the same command (in-process here)."""
    monkeypatch.setattr(sys, "argv", ["satagraph", "--version"])
    with pytest.raises(SystemExit) as info:
        runpy.run_module("satagraph", run_name="__main__")
    assert info.value.code == 0
    assert capsys.readouterr().out.startswith("satagraph ")
    monkeypatch.setattr(sys, "argv", ["satagraph", "inspect", "/no/such.bvh"])
    with pytest.raises(SystemExit) as info:
        runpy.run_module("satagraph", run_name="__main__")
    assert info.value.code == 2


def test_overrides_may_follow_options():
    """``satagraph train CONFIG --init-from CKPT key=value`` keeps the
    overrides (argparse alone rejects them after the option); anything else
    left over is still a usage error."""
    from satagraph.cli import build_parser, parse_args
    parser = build_parser()
    args = parse_args(parser, ["train", "tiny", "a.b=1", "--init-from", "x.ckpt", "c=2"])
    assert args.config == "tiny" and args.init_from == "x.ckpt"
    assert args.overrides == ["a.b=1", "c=2"]
    with pytest.raises(SystemExit):
        parse_args(parser, ["train", "tiny", "--init-from", "x.ckpt", "stray"])
    with pytest.raises(SystemExit):
        parse_args(parser, ["inspect", "f.bvh", "a=1"])


def test_sweep_items_may_follow_options():
    """``satagraph sweep tiny gnn_gat --steps 2 data.batch_size=4`` was
    'unrecognized arguments: data.batch_size=4' (a config after an option
    likewise), where ``train`` takes overrides wherever they stand."""
    from satagraph.cli import build_parser, parse_args
    parser = build_parser()
    args = parse_args(parser, ["sweep", "tiny", "--steps", "2", "gnn_gat", "--output", "o",
                               "data.batch_size=4"])
    assert args.items == ["tiny", "gnn_gat", "data.batch_size=4"] and args.steps == 2
    assert args.output == "o"
    with pytest.raises(SystemExit):
        parse_args(parser, ["sweep", "tiny", "--steps", "2", "--stray"])


def test_each_warning_line_is_shown_once_per_command():
    """A file's rig is read again at every step that canonicalises it; the
    command shows each of its warnings once (other lines still pass)."""
    shown = []
    once = cli._once(lambda message, *rest: shown.append(str(message)))
    for text in ("a.bvh: units unknown", "a.bvh: units unknown", "b.bvh: up axis guessed",
                 "a.bvh: units unknown"):
        once(UserWarning(text), UserWarning, "f.py", 1)
    assert shown == ["a.bvh: units unknown", "b.bvh: up axis guessed"]


def test_sigterm_stops_a_command_as_ctrl_c_does(tmp_path, monkeypatch, capsys) -> None:
    """SIGTERM (a cluster's, ``kill``'s) during a folder's writes: the write
    under way is taken back, one line, exit 130, the handler before put
    back. It ended the process at once (here: the test's own handler's
    exception, which no command catches), without a line, the temporary
    file of that write left behind."""
    import signal

    from satagraph.utils.files import is_temp_file

    class Killed(BaseException):
        pass

    def killed(signum, frame):
        raise Killed

    real_fsync, synced = os.fsync, []

    def fsync_then_term(fd: int) -> None:
        synced.append(fd)
        if len(synced) == 3:  # the third file's write
            os.kill(os.getpid(), signal.SIGTERM)
        real_fsync(fd)

    monkeypatch.setattr(os, "fsync", fsync_then_term)
    before = signal.signal(signal.SIGTERM, killed)
    try:
        code = main(["zoo", str(tmp_path / "zoo"), "--species", "biped", "--clips", "4",
                     "--frames", "8"])
    finally:
        assert signal.signal(signal.SIGTERM, before) is killed
    assert code == 130
    assert capsys.readouterr().err.strip().splitlines() == [
        "satagraph: interrupted (outputs are written whole or not at all)"]
    written = [p for p in (tmp_path / "zoo").rglob("*") if p.is_file()]
    assert len(written) == 2 and not any(is_temp_file(p.name) for p in written)


def test_an_interrupt_is_one_line_and_exit_130(monkeypatch, capsys) -> None:
    """Ctrl-C in any command: one line, exit code 130, no traceback."""
    def interrupted(args):
        raise KeyboardInterrupt
    real = cli.build_parser
    def patched():
        parser = real()
        for action in parser._subparsers._group_actions[0].choices.values():
            action.set_defaults(func=interrupted)
        return parser
    monkeypatch.setattr(cli, "build_parser", patched)
    assert cli.main(["inspect", "anything.bvh"]) == 130
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "interrupted" in err[0]


@pytest.mark.parametrize("argv, said", [
    (["zoo", "{tmp}/z", "--fps", "0"], "--fps must be between 1 and 1000"),
    (["zoo", "{tmp}/z", "--fps", "nan"], "--fps must be between 1 and 1000"),
    (["zoo", "{tmp}/z", "--frames", "1"], "--frames must be at least 2"),
    (["code-bank", "t2m_tiny", "{tmp}/b.safetensors", "--windows", "4", "--device", "gpu0"],
     "--device gpu0: not a device"),
    (["generate", "--ckpt", "builtin-wide", "--text", "walk", "--skeleton", "{zoo}",
      "{tmp}/g.bvh"], "builtin-wide: a built-in retargeting model, not a text-to-motion"),
    (["generate", "--ckpt", "{tmp}", "--text", "walk", "--skeleton", "{zoo}", "{tmp}/g.bvh"],
     "a folder without checkpoints/last.ckpt"),
    (["reconstruct", "{zoo}", "{tmp}/r.bvh", "--ckpt", "{t2m}"],
     "a text-to-motion model; this command needs a motion autoencoder"),
    (["eval", "--ckpt", "{t2m}", "--data", "{tmp}/clips"],
     "padded model); the repository's benchmarks/t2m.py --ckpt C --data FOLDER scores"),
    (["eval", "--ckpt", "builtin", "--data", "{tmp}/clips"], "no windows in the 'test' split"),
    (["eval", "--ckpt", "builtin", "--data", "{zoo}"], "not one .bvh file: put it in a folder"),
])
def test_wrong_arguments_are_one_line(argv, said, tmp_path, capsys) -> None:
    """Mistakes a new user makes: one line each, exit 2, nothing written."""
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    from satagraph.io.weights import builtin_path
    (tmp_path / "clips").mkdir()
    zoo = tmp_path / "clips" / "walk.bvh"
    write_bvh(generate_clip(zoo_rigs(["biped"])[0], "walk", frames=40, seed=1), zoo)
    t2m = builtin_path(kind="text-to-motion")
    argv = [a.format(tmp=tmp_path, zoo=zoo, t2m=t2m) for a in argv]
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and said in err[0], err
    assert not [p for p in tmp_path.iterdir() if p.name not in ("clips",)]


NO_ROOT_CHANNELS = ("HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n JOINT Spine\n {\n  OFFSET 0 0.5 0"
                    "\n  CHANNELS 3 Zrotation Xrotation Yrotation\n  JOINT Head\n  {\n   OFFSET 0 "
                    "0.5 0\n   CHANNELS 3 Zrotation Xrotation Yrotation\n   End Site\n   {\n"
                    "    OFFSET 0 0.2 0\n   }\n  }\n }\n}\nMOTION\nFrames: 3\nFrame Time: 0.04\n"
                    + "0 0 0 0 0 0\n0 5 0 0 5 0\n0 9 0 0 9 0\n")


@pytest.mark.parametrize("command", ["reconstruct", "retarget", "convert"])
def test_a_rig_whose_root_has_no_channels_is_refused_before_any_work(command, tmp_path,
                                                                     capsys) -> None:
    """Nothing can be written onto a root without CHANNELS: one line naming
    the input whose rig would be written, before the model runs."""
    rig = tmp_path / "rig.bvh"
    rig.write_text(NO_ROOT_CHANNELS)
    out = tmp_path / "out.bvh"
    argv = {"reconstruct": ["reconstruct", str(rig), str(out)],
            "convert": ["convert", str(rig), str(out)],
            "retarget": ["retarget", str(rig), "--target", str(rig), str(out)]}[command]
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert f"{rig}: its root joint 'Hips' has no CHANNELS" in err[-1]
    assert not out.exists()


def test_a_body_of_one_joint_is_refused_as_training_refuses_it(tmp_path, capsys) -> None:
    """A root and its End Site: training says "degenerate"; reconstruct
    wrote it with the moving root frozen in place."""
    rig = tmp_path / "one.bvh"
    rig.write_text("HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition "
                   "Zposition Zrotation Xrotation Yrotation\n End Site\n {\n  OFFSET 0 10 0\n"
                   " }\n}\nMOTION\nFrames: 3\nFrame Time: 0.04\n"
                   + "".join(f"{i} 0 0 0 {9 * i} 0\n" for i in range(3)))
    out = tmp_path / "out.bvh"
    assert cli.main(["reconstruct", str(rig), str(out)]) == 2
    assert "the skeleton is degenerate" in capsys.readouterr().err
    assert not out.exists()


def test_render_raw_says_a_rig_of_another_up_axis_will_lie(tmp_path, capsys) -> None:
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    from satagraph.datasets.zoo.dialects import Dialect, apply_dialect
    clip = generate_clip(zoo_rigs(["biped"])[0], "walk", frames=30, seed=3)
    write_bvh(apply_dialect(clip, Dialect(up_axis="+Z"))[0], tmp_path / "z.bvh")
    args = ["render", str(tmp_path / "z.bvh"), str(tmp_path / "z.gif"), "--max-frames", "2"]
    assert cli.main(args + ["--raw"]) == 0
    assert "reads +Z up (detected): it will lie on its side" in capsys.readouterr().err
    assert cli.main(args) == 0 and "lie on its side" not in capsys.readouterr().err


def test_a_negative_up_axis_needs_no_equals_sign(capsys, tiny_file) -> None:
    """``--up-axis -Y`` (argparse alone took ``-Y`` for an option)."""
    assert cli.main(["inspect", str(tiny_file), "--up-axis", "-Y"]) == 0
    assert "-Y (given)" in capsys.readouterr().out


@pytest.mark.parametrize("png, said", [("nodir/s.png", "nodir does not exist"),
                                       ("s.jpg", "the contact sheet is a .png file")])
def test_render_checks_the_sheet_before_drawing(tiny_file, tmp_path, capsys, png, said):
    """A sheet that cannot be written is refused before the GIF is drawn."""
    gif = tmp_path / "o.gif"
    assert cli.main(["render", str(tiny_file), str(gif), "--png", str(tmp_path / png)]) == 2
    assert said in capsys.readouterr().err and not gif.exists()


def test_traceback_may_follow_the_command(tmp_path) -> None:
    """``satagraph inspect missing.bvh --traceback`` raises instead of one line."""
    with pytest.raises(BVHError):
        cli.main(["inspect", str(tmp_path / "missing.bvh"), "--traceback"])


def test_inspect_prints_on_a_cp1252_output(tiny_file, monkeypatch):
    """A joint name that cp1252 lacks (a Windows console's or file's
    encoding) failed ``inspect``: "satagraph: error: 'charmap' codec can't
    encode characters in position 41-44"; it is printed as escapes."""
    text = tiny_file.read_text()
    root = re.search(r"ROOT (\S+)", text)[1]
    tiny_file.write_text(text.replace(f"ROOT {root}", "ROOT センター"), encoding="utf-8")
    out = io.TextIOWrapper(io.BytesIO(), encoding="cp1252")
    monkeypatch.setattr(sys, "stdout", out)
    assert main(["inspect", str(tiny_file)]) == 0
    out.flush()
    assert "\\u30bb\\u30f3\\u30bf\\u30fc" in out.buffer.getvalue().decode("cp1252")
    assert out.errors == "strict"  # as it was after the command


@pytest.mark.parametrize("command, seed", [("zoo", "-1"), ("demo", "-1"),
                                           ("generate", "99999999999999999999")])
def test_a_seed_out_of_range_is_refused_as_an_argument(capsys, tiny_file, tmp_path,
                                                      command, seed):
    """``zoo --seed -1`` and ``demo --seed -1`` failed as ``expected
    non-negative integer`` (naming no option), ``generate --seed 1e20``'s
    digits as ``Overflow when unpacking long long`` after the model loaded:
    each is refused up front, with a config's seed range."""
    out = str(tmp_path / "out")
    argv = {"zoo": ["zoo", out], "demo": ["demo", "--output", out],
            "generate": ["generate", "--text", "a walk", "--skeleton", str(tiny_file),
                         out + ".bvh"]}[command]
    with pytest.raises(SystemExit) as info:
        main([*argv, "--seed", seed])
    assert info.value.code == 2
    assert f"argument --seed: a seed from 0 to 4294967295 is expected: '{seed}'" in \
        capsys.readouterr().err
    assert not list(tmp_path.glob("out*"))
