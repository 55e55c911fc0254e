"""A folder job (``retarget SRC_DIR --target T OUT_DIR``, ``reconstruct``)
whose output folder cannot be written says so once, before any file is
read or the model loaded, not as a failure of every input file (one line
each, then "N failed: <the inputs>")."""
from __future__ import annotations

import os
from pathlib import Path

import pytest

from satagraph.cli import main
from satagraph.datasets.zoo import write_zoo


@pytest.fixture(scope="module")
def walks(tmp_path_factory: pytest.TempPathFactory) -> Path:
    zoo = tmp_path_factory.mktemp("zoo")
    write_zoo(zoo, species=["biped"], clips=1, frames=40, seed=4)
    return zoo / "biped"


def _said_once(out: Path, code: int, printed) -> None:
    assert code == 2 and printed.out == ""
    lines = printed.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"satagraph: error: cannot write into {out}: ")
    assert "using the built-in model" not in printed.err


def test_an_output_folder_that_cannot_be_made_is_one_line(walks: Path, tmp_path: Path,
                                                          capsys) -> None:
    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    out = blocker / "out"
    _said_once(out, main(["reconstruct", str(walks), str(out)]), capsys.readouterr())
    target = sorted(walks.glob("*.bvh"))[0]
    code = main(["retarget", str(walks), "--target", str(target), str(out)])
    _said_once(out, code, capsys.readouterr())


def test_an_output_folder_that_is_not_writable_is_one_line(walks: Path, tmp_path: Path,
                                                           capsys, monkeypatch) -> None:
    out = tmp_path / "ro"
    out.mkdir()
    access = os.access  # root writes into a read-only folder: the folder says no instead
    monkeypatch.setattr(os, "access", lambda path, mode, **kw: (
        False if Path(path) == out else access(path, mode, **kw)))
    _said_once(out, main(["reconstruct", str(walks), str(out)]), capsys.readouterr())
