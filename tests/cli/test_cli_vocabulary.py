"""One concept, one spelling: options that several commands share read
the same way in each."""
from __future__ import annotations

import pytest

from satagraph.cli import build_parser, parse_args


@pytest.fixture(scope="module")
def parser():
    return build_parser()


@pytest.mark.parametrize("command", [
    ["train", "tiny"],
    ["code-bank", "t2m_tiny", "bank.safetensors", "--windows", "4"],
    ["eval", "--ckpt", "builtin"],
    ["demo"],
])
def test_repeated_data_keeps_every_source(parser, command):
    """``--data A --data B`` names two sources on every command that takes
    ``--data`` (eval and demo kept only B: train's spelling silently scored
    or trained on one folder of two)."""
    args = parse_args(parser, [*command, "--data", "mocap/a", "--data", "mocap/b"])
    assert args.data == ["mocap/a", "mocap/b"]


@pytest.mark.parametrize("command", [["eval", "--ckpt", "builtin"], ["demo"]])
def test_listed_data_still_reads(parser, command):
    """The list form those two commands had (``--data A B``) is kept."""
    assert parse_args(parser, [*command, "--data", "a", "b"]).data == ["a", "b"]
    assert parse_args(parser, command).data is None


class _Stop(Exception):
    """Raised by a stand-in once the command's config is known."""


@pytest.mark.parametrize("command", [
    ["train", "t2m_tiny"],
    ["code-bank", "t2m_tiny", "bank.safetensors", "--windows", "4"],
])
def test_data_rig_options_reach_the_config(monkeypatch, command):
    """``--up-axis`` / ``--units`` of the data read the same on every
    command whose ``--data`` reads BVH folders: code-bank, told to draw
    from ``train --data``'s folders, had no way to say their units
    (``unrecognized arguments: --units cm``)."""
    import satagraph.experiment.config as config
    from satagraph.cli import main

    seen = {}
    load = config.load_config

    def capture(name, overrides=()):
        seen.update(load(name, overrides)["data"]["preprocessing"])
        raise _Stop

    monkeypatch.setattr(config, "load_config", capture)
    with pytest.raises(_Stop):
        main([*command, "--data", "mocap", "--up-axis", "z", "--units", "cm"])
    assert seen["up_axis"] == "+Z"
    assert seen["scale"] == pytest.approx(0.01)


def test_demo_data_read_in_the_units_given(monkeypatch, tmp_path):
    """``demo --data FOLDER --units cm --up-axis z`` trains on the folder
    read as ``train --data FOLDER --units cm --up-axis z`` reads it (demo
    had neither option: ``unrecognized arguments``)."""
    import satagraph.experiment.demo as demo
    from satagraph.cli import main

    seen = []
    monkeypatch.setattr(demo, "run_demo", lambda options: seen.append(options) or _stop())
    with pytest.raises(_Stop):
        main(["demo", "--data", "mocap", "--units", "cm", "--up-axis", "z", "data.batch_size=2"])
    cfg = demo.demo_config(seen[0], ["mocap"], tmp_path / "run")
    prep = cfg["data"]["preprocessing"]
    assert (prep["up_axis"], prep["scale"], cfg["data"]["batch_size"]) == ("+Z", 0.01, 2)


def _stop():
    raise _Stop


@pytest.mark.parametrize("axes", [["-Z"], ["+Y", "-Z"], ["-Z", "negX", "+y"], ["-Z,+X"]])
def test_zoo_up_axes_take_a_minus_as_up_axis_does(parser, axes):
    """``zoo --up-axes -Z`` reads as ``inspect --up-axis -Z`` does (it was
    ``argument --up-axes: expected at least one argument``, and ``--up-axes
    +Y -Z`` ``unrecognized arguments: -Z``), the folder after it kept."""
    from satagraph.cli.zoo import _axes, _flat
    args = parse_args(parser, ["zoo", "--up-axes", *axes, "out", "--units", "cm"])
    assert _flat(args.up_axes) == _axes(",".join(axes))
    assert (args.out_dir, args.units) == ("out", ["cm"])


@pytest.mark.parametrize("argv, axes, units", [
    (["--up-axes", "-Z", "--units", "cm", "out"], ["-Z"], ["cm"]),
    (["--units", "cm", "28", "out"], ["+Y"], ["cm", "28"]),
    (["--up-axes", "+Y", "Z", "out"], ["+Y", "+Z"], ["m"])])
def test_zoo_axes_and_units_leave_the_folder_after_them(parser, argv, axes, units):
    """``zoo --up-axes -Z --units cm out`` took ``out`` for a unit (``argument
    --units: unit must be one of [...], got 'out'``), as ``--species`` no
    longer takes a folder after it for a species."""
    from satagraph.cli.zoo import _flat
    args = parse_args(parser, ["zoo", *argv])
    assert (args.out_dir, _flat(args.up_axes), args.units) == ("out", axes, units)


def test_axis_lists_without_a_minus_left_to_argparse(parser):
    args = parse_args(parser, ["zoo", "out", "--up-axes", "+Y", "Z"])
    assert args.up_axes == [["+Y"], ["+Z"]] and args.out_dir == "out"
