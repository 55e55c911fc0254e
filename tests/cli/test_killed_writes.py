"""What a killed writer leaves (``kill -9`` of ``retarget FOLDER OUT``:
half a BVH file in a hidden temporary file beside the output) is never
read as a motion file by the commands and trainings that list a folder."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from satagraph.cli import main
from satagraph.datasets.sources import bvh_files, scan_folder
from satagraph.datasets.zoo import write_zoo

REPO = Path(__file__).resolve().parents[2]

#: A process that dies (as by ``kill -9``: no cleanup runs) half way through
#: writing a BVH file atomically.
_KILLED = """
import os, sys
from satagraph.utils.files import atomic_write
text = open(sys.argv[1]).read()
def half(f):
    f.write(text[: len(text) // 2])
    f.flush()
    os._exit(9)
atomic_write(sys.argv[2], half)
"""


@pytest.fixture(scope="module")
def outputs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two whole zoo walks and the temporary file of a write killed half way."""
    zoo = tmp_path_factory.mktemp("zoo")
    write_zoo(zoo, species=["biped"], clips=1, frames=40, seed=3)
    walks = sorted((zoo / "biped").glob("*.bvh"))[:2]
    out = tmp_path_factory.mktemp("out")
    for walk in walks:
        (out / walk.name).write_bytes(walk.read_bytes())
    run = subprocess.run([sys.executable, "-c", _KILLED, str(walks[0]), str(out / "c.bvh")],
                         capture_output=True, text=True, cwd=REPO)
    assert run.returncode == 9, run.stderr
    left = [p.name for p in out.iterdir() if p.name.startswith(".")]
    assert len(left) == 1 and left[0].startswith(".c.bvh.") and left[0].endswith(".tmp.bvh")
    assert (out / left[0]).stat().st_size > 0 and not (out / "c.bvh").exists()
    return out


def test_a_killed_write_is_no_input_file(outputs: Path) -> None:
    names = [p.name for p in bvh_files(outputs)]
    assert len(names) == 2 and not any(n.startswith(".") for n in names)
    assert [Path(f.path).name for f in scan_folder(outputs)] == names  # training


def test_inspect_and_reconstruct_a_folder_with_a_killed_write(outputs: Path, tmp_path: Path,
                                                               capsys) -> None:
    assert main(["inspect", str(outputs)]) == 0
    printed = capsys.readouterr()
    assert printed.out.splitlines()[-1].startswith("2 files:") and "0 unreadable" in printed.out
    assert main(["reconstruct", str(outputs), str(tmp_path / "rec")]) == 0
    printed = capsys.readouterr()
    assert "reconstructed 2 of 2 files" in printed.out and "error" not in printed.err
