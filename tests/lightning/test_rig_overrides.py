"""Overrides survive convert -> inspect -> render -> retarget: once given
(or declared by a canonical file), an up axis or unit is never re-guessed."""
from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np

import satagraph.data.rig_reading as rr
from satagraph.cli import main
from satagraph.data.rig_reading import with_rig
from satagraph.data.zoo import Dialect, apply_dialect, generate_clip, zoo_rigs
from satagraph.inference import retarget_motion
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
