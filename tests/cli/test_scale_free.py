"""Commands that read bodies in their own heights (`retarget`,
`reconstruct`, `generate`) give the same output in any units, so they do
not warn about units they cannot decide; `convert`, whose output is in
metres, still does."""
from __future__ import annotations

import warnings
from pathlib import Path
from typing import List

import numpy as np
import pytest

from satagraph.cli import main
from satagraph.transforms.rig_reading import UnitsWarning
from satagraph.datasets.zoo import Dialect, apply_dialect, generate_clip, zoo_rigs
from satagraph.io import read_bvh, write_bvh


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """A zoo biped walk in metres and a fowl 28 units tall: a chicken in
    centimetres or a larger bird in another unit, undecidable."""
    folder = tmp_path_factory.mktemp("rigs")
    biped = generate_clip(zoo_rigs(["biped"], seed=4)[0], "walk", frames=40, seed=1)
    fowl = generate_clip(zoo_rigs(["fowl"], seed=3)[0], "walk", frames=40, seed=5)
    out = {"source": folder / "walk.bvh", "fowl": folder / "fowl.bvh"}
    write_bvh(apply_dialect(biped, Dialect())[0], out["source"])
    write_bvh(apply_dialect(fowl, Dialect(unit=28.0))[0], out["fowl"])
    return out


def _positions(path: Path) -> np.ndarray:
    return read_bvh(path).global_positions()


def _units_warnings(argv: List[str], code: int = 0) -> List[str]:
    """The units warnings that running :obj:`argv` raises (it must exit with :obj:`code`)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert main(argv) == code
    return [str(w.message) for w in caught if issubclass(w.category, UnitsWarning)]


def test_retarget_is_the_same_in_any_units_and_does_not_warn(files, tmp_path, capsys) -> None:
    outs = []
    for units in (None, "cm", "m"):
        out = tmp_path / f"{units}.bvh"
        extra = [] if units is None else ["--target-units", units]
        assert _units_warnings(["retarget", str(files["source"]), "--target",
                                str(files["fowl"]), str(out), *extra]) == []
        outs.append(_positions(out))
    scale = np.abs(outs[0]).max()
    for other in outs[1:]:  # written in the file's units either way
        np.testing.assert_allclose(other, outs[0], atol=1e-4 * scale)
    assert "the model reads a body in its own heights" in _help(["retarget"], capsys)


def test_reconstruct_does_not_warn_where_convert_does(files, tmp_path) -> None:
    assert _units_warnings(["reconstruct", str(files["fowl"]), str(tmp_path / "r.bvh"),
                            "--no-mirror"]) == []
    said = _units_warnings(["convert", str(files["fowl"]), str(tmp_path / "c.bvh"),
                            "--canonical"], code=2)  # a canonical file declares metres
    assert said and said[0].startswith(f"{files['fowl']}: units unknown: 28 units tall")
    assert not (tmp_path / "c.bvh").exists()


def _help(command, capsys) -> str:
    with pytest.raises(SystemExit):
        main([*command, "--help"])
    return " ".join(capsys.readouterr().out.split())


def test_generate_is_the_same_in_any_units_and_does_not_warn(files, tmp_path, capsys) -> None:
    outs = []
    for units in ("cm", "in", None):
        out = tmp_path / f"{units}.bvh"
        extra = [] if units is None else ["--units", units]
        assert _units_warnings(["generate", "--text", "a bird walks forward", "--skeleton",
                                str(files["fowl"]), "--seconds", "1", "--seed", "2",
                                str(out), *extra]) == []
        outs.append(_positions(out))
    scale = np.abs(outs[0]).max()
    for other in outs[1:]:
        np.testing.assert_allclose(other, outs[0], atol=1e-4 * scale)
    assert "the model reads a body in its own heights" in _help(["generate"], capsys)
