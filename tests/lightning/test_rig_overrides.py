"""Overrides survive convert -> inspect -> render -> retarget: once given
(or declared by a canonical file), an up axis or unit is never re-guessed."""
from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np

import satagraph.transforms.rig_reading as rr
from satagraph.cli import main
from satagraph.transforms.rig_reading import with_rig
from satagraph.datasets.zoo import Dialect, apply_dialect, generate_clip, zoo_rigs
from satagraph.pipelines.inference import retarget_motion
from satagraph.io import read_bvh, write_bvh


def _write(path: Path, species: str, dialect: Dialect) -> Path:
    clip = generate_clip(zoo_rigs([species], seed=3)[0], "walk", frames=40, seed=2)
    write_bvh(apply_dialect(clip, dialect)[0], path)
    return path


def test_override_survives_convert_inspect_render_retarget(
        tmp_path: Path, build_tiny_module: Callable, embed: Callable, monkeypatch,
        capsys) -> None:
    source = _write(tmp_path / "biped.bvh", "biped", Dialect(up_axis="+Z", unit="cm"))
    crab = _write(tmp_path / "crab.bvh", "crab", Dialect(up_axis="-X", unit="in"))
    canon = tmp_path / "crab_canon.bvh"
    assert main(["convert", str(crab), str(canon), "--canonical", "--up-axis=-X",
                 "--units", "in"]) == 0

    def never(_motion, *_args):
        raise AssertionError("re-guessed")
    monkeypatch.setattr(rr, "guess_up_axis", never)
    monkeypatch.setattr(rr, "guess_units", never)
    assert main(["inspect", str(canon)]) == 0
    assert "+Y (declared)" in capsys.readouterr().out
    assert main(["render", str(canon), str(source), str(tmp_path / "o.gif"),
                 "--max-frames", "3", "--up-axis=+Z", "--units", "cm"]) == 0

    target = read_bvh(canon)
    out = retarget_motion(build_tiny_module(), with_rig(read_bvh(source), "+Z", "cm"),
                          target, embed, window=16, overlap=4)
    assert out.rig == target.rig  # in the target's declared frame, declared again
    # on the target's own rig: its offsets (metres, +Y up), the source's frames
    np.testing.assert_allclose(out.skeleton.offsets[1:], target.skeleton.offsets[1:])
    assert out.num_frames == 40
    write_bvh(out, tmp_path / "out.bvh")
    assert read_bvh(tmp_path / "out.bvh").rig.declared


def test_results_on_a_rig_are_read_as_that_rig_was(
        tmp_path: Path, build_tiny_module: Callable, embed: Callable, monkeypatch) -> None:
    """A retarget onto a -X-up rig in inches says so in its file; one onto a
    rig of undecided units declares the up axis only."""
    from satagraph.motion import RigSettings
    source = read_bvh(_write(tmp_path / "biped.bvh", "biped", Dialect()))
    module = build_tiny_module()
    crab = read_bvh(_write(tmp_path / "crab.bvh", "crab", Dialect(up_axis="-X", unit="in")))
    out = retarget_motion(module, source, with_rig(crab, "-X", "in"), embed, window=16)
    assert out.rig == RigSettings("-X", 0.0254, declared=True)
    write_bvh(out, tmp_path / "out.bvh")
    assert (tmp_path / "out.bvh").read_text().splitlines()[0] == \
        "HIERARCHY # satagraph: up_axis=-X scale=0.0254"
    bird = read_bvh(_write(tmp_path / "bird.bvh", "fowl", Dialect(unit=28.0)))
    out = retarget_motion(module, source, with_rig(bird, "+Y"), embed, window=16)
    assert out.rig == RigSettings("+Y", None, declared=True)  # units stay undecided
    write_bvh(out, tmp_path / "out2.bvh")
    again = read_bvh(tmp_path / "out2.bvh")
    assert again.rig == out.rig

    def never(_motion, *_args):
        raise AssertionError("re-guessed")
    monkeypatch.setattr(rr, "guess_up_axis", never)
    from satagraph.transforms.canonical import canonicalize
    assert canonicalize(again, fps=None).transform.up_axis == "+Y"
