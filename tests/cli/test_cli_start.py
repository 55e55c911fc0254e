"""The command line starts without torch, PyG or Lightning: ``--help`` and
``inspect`` need argparse and numpy only (behaviour, not timing)."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
HEAVY = ("torch", "torch_geometric", "lightning", "roma", "transformers")

# Runs the CLI in-process, then prints the heavy top-level modules loaded.
PROBE = """
import sys
from satagraph.cli import main
try:
    code = main(sys.argv[1:])
except SystemExit as exit:
    code = exit.code
heavy = sorted({{m.split('.')[0] for m in sys.modules}} & set({heavy!r}))
print('HEAVY=' + ','.join(heavy))
sys.exit(code or 0)
"""


def _heavy_modules(*args: str) -> list:
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1"}
    proc = subprocess.run([sys.executable, "-c", PROBE.format(heavy=HEAVY), *args],
                          cwd=ROOT, env=env, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    line = proc.stdout.strip().splitlines()[-1]
    return [m for m in line.removeprefix("HEAVY=").split(",") if m]


def test_import_cli_is_light():
    assert _heavy_modules("--version") == []


@pytest.mark.parametrize("command", ["inspect", "convert", "demo", "tags",
                                     "train", "zoo", "render", "sweep"])
def test_command_help_is_light(command):
    assert _heavy_modules(command, "--help") == []


def test_inspect_is_light(tmp_path):
    from satagraph.data.examples import example_motion
    from satagraph.io import write_bvh
    path = tmp_path / "walk.bvh"
    write_bvh(example_motion(), path)
    assert _heavy_modules("inspect", str(path), "--json") == []


def test_lazy_exports_still_work():
    import satagraph
    from satagraph.io import BVHError, read_bvh, write_bvh  # noqa: F401
    from satagraph.ops import euler_to_matrix, forward_kinematics  # noqa: F401
    assert satagraph.Motion.__name__ == "Motion"
    assert "read_bvh" in dir(satagraph.io)
    with pytest.raises(AttributeError):
        satagraph.io.no_such_name  # noqa: B018
