"""The command line starts without torch, PyG or Lightning: ``--help`` and
``inspect`` need argparse and numpy only (behaviour, not timing)."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Dict, List, Sequence, Tuple

import pytest

ROOT = Path(__file__).resolve().parents[2]
HEAVY = ("torch", "torch_geometric", "lightning", "roma", "transformers")
HELP_COMMANDS = ("inspect", "convert", "demo", "tags", "train", "zoo", "render", "sweep",
                 "retarget", "reconstruct", "eval", "export-weights", "code-bank", "generate")

# Imports the CLI, then runs each command line of argv[1] (JSON) in-process
# and prints the heavy top-level modules loaded. Each runs in a child forked
# right after the import, so it starts from the state a fresh interpreter
# that ran ``from satagraph.cli import main`` has (one interpreter start for
# all); without fork, one command line a process.
PROBE = """
import json, os, sys, traceback
from satagraph.cli import main
argvs = json.loads(sys.argv[1])
fork = hasattr(os, 'fork')
assert fork or len(argvs) == 1
for i, argv in enumerate(argvs):
    sys.stdout.flush(); sys.stderr.flush()
    pid = os.fork() if fork else 0
    if pid:
        _, status = os.waitpid(pid, 0)
        if status:
            print(f'RESULT{{i}}=' + json.dumps(['child status ' + str(status), []]))
        continue
    try:
        try:
            code = main(argv)
        except SystemExit as exit:
            code = exit.code
    except BaseException:
        traceback.print_exc()
        code = 'raised'
    heavy = sorted({{m.split('.')[0] for m in sys.modules}} & set({heavy!r}))
    print(f'RESULT{{i}}=' + json.dumps([code or 0, heavy]))
    sys.stdout.flush(); sys.stderr.flush()
    if fork:
        os._exit(0)
"""


def _heavy_modules_of(argvs: Sequence[Sequence[str]]) -> List[List[str]]:
    """The heavy modules each command line loads (each must exit with 0)."""
    return _probe(argvs)[0]


def _probe(argvs: Sequence[Sequence[str]], code: int = 0) -> Tuple[List[List[str]], str]:
    """:func:`_heavy_modules_of` and what the command lines wrote to stderr."""
    if len(argvs) > 1 and not hasattr(os, "fork"):
        runs = [_probe([argv], code) for argv in argvs]
        return [heavy[0] for heavy, _ in runs], "".join(err for _, err in runs)
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1"}
    proc = subprocess.run([sys.executable, "-c", PROBE.format(heavy=HEAVY),
                           json.dumps([list(argv) for argv in argvs])],
                          cwd=ROOT, env=env, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    results: Dict[int, Tuple[object, List[str]]] = {}
    for line in proc.stdout.splitlines():
        key, _, value = line.partition("=")
        if key.startswith("RESULT") and key[len("RESULT"):].isdigit():
            results[int(key[len("RESULT"):])] = json.loads(value)
    assert sorted(results) == list(range(len(argvs))), proc.stdout + proc.stderr
    for i, argv in enumerate(argvs):
        assert results[i][0] == code, (argv, results[i][0], proc.stderr)
    return [results[i][1] for i in range(len(argvs))], proc.stderr


def _heavy_modules(*args: str) -> list:
    return _heavy_modules_of([args])[0]


@pytest.fixture(scope="module")
def help_heavy() -> Dict[str, List[str]]:
    """The heavy modules ``COMMAND --help`` loads, for every command of
    :data:`HELP_COMMANDS` (one probe for all)."""
    argvs = [(command, "--help") for command in HELP_COMMANDS]
    return dict(zip(HELP_COMMANDS, _heavy_modules_of(argvs)))


def test_import_cli_is_light():
    assert _heavy_modules("--version") == []


@pytest.mark.parametrize("command", HELP_COMMANDS)
def test_command_help_is_light(command, help_heavy):
    assert help_heavy[command] == []


def test_inspect_is_light(tmp_path):
    from satagraph.data.examples import example_motion
    from satagraph.io import write_bvh
    path = tmp_path / "walk.bvh"
    write_bvh(example_motion(), path)
    assert _heavy_modules("inspect", str(path), "--json") == []


def test_model_commands_refuse_bad_input_before_loading_the_model(tmp_path):
    """A missing input, an unwritable output or a bad window or duration is
    said (exit code 2) before torch, PyG or Lightning load; a missing
    ``--ckpt`` before PyG and Lightning."""
    from satagraph.data.examples import example_motion
    from satagraph.io import write_bvh
    rig, out, gone = tmp_path / "walk.bvh", str(tmp_path / "out.bvh"), str(tmp_path / "no.bvh")
    pose = tmp_path / "pose.bvh"  # one frame: a target, never a source
    write_bvh(example_motion(), rig)
    write_bvh(example_motion(num_frames=1), pose)
    rig, unwritable, pose = str(rig), str(tmp_path / "no_folder" / "out.bvh"), str(pose)
    argvs = [("retarget", gone, "--target", rig, out),
             ("retarget", pose, "--target", rig, out),
             ("reconstruct", pose, out),
             ("retarget", rig, "--target", rig, unwritable),
             ("retarget", rig, "--target", rig, out, "--window", "-3"),
             ("reconstruct", gone, out),
             ("reconstruct", rig, out, "--window", "8", "--overlap", "8"),
             ("generate", "--text", "a walk", "--skeleton", gone, out, "--seconds", "2"),
             ("generate", "--text", "a walk", "--skeleton", rig, unwritable),
             ("generate", "--text", "a walk", "--skeleton", rig, out, "--seconds", "100"),
             ("retarget", rig, "--target", rig, out, "--overlap", "-1"),
             ("reconstruct", rig, out, "--refine", "-1"),
             ("retarget", rig, "--target", rig, out, "--ckpt", gone),
             ("generate", "--text", "a walk", "--skeleton", rig, out, "--ckpt", gone)]
    heavy, stderr = _probe(argvs, code=2)
    assert heavy[:-2] == [[]] * (len(argvs) - 2)
    assert "pose.bvh: 1 frame(s): at least 2 are needed" in stderr
    assert heavy[-2:] == [["torch"]] * 2  # the weights file's reader, not the model's code
    said = [line for line in stderr.splitlines() if "error:" in line]
    assert [line.split("error: ")[1].split(":")[0] for line in said] == [
        gone, pose, pose, f"cannot write {unwritable}", "--window -3", gone,
        "--window 8 --overlap 8", gone, f"cannot write {unwritable}",
        "argument --seconds", "--overlap -1", "argument --refine", gone, gone]
    assert not Path(out).exists()


def test_lazy_exports_still_work():
    import satagraph
    from satagraph.io import BVHError, read_bvh, write_bvh  # noqa: F401
    from satagraph.ops import euler_to_matrix, forward_kinematics  # noqa: F401
    assert satagraph.Motion.__name__ == "Motion"
    assert "read_bvh" in dir(satagraph.io)
    with pytest.raises(AttributeError):
        satagraph.io.no_such_name  # noqa: B018


def test_console_command_exits_with_main_code_and_runs_exit_handlers(tmp_path):
    """``satagraph`` (``satagraph.cli:run``) exits with :func:`main`'s code,
    its output flushed and ``atexit`` handlers run, though the final
    collection is skipped."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    script = ("import atexit, sys; atexit.register(lambda: print('handler ran')); "
              "sys.argv = ['satagraph'] + sys.argv[1:]; from satagraph.cli import run; run()")
    done = subprocess.run([sys.executable, "-c", script, "--version"], cwd=ROOT, env=env,
                          capture_output=True, text=True)
    assert done.returncode == 0
    assert done.stdout.startswith("satagraph ") and done.stdout.endswith("handler ran\n")
    gone = str(tmp_path / "gone.bvh")
    failed = subprocess.run([sys.executable, "-m", "satagraph", "inspect", gone], cwd=ROOT,
                            env=env, capture_output=True, text=True)
    assert failed.returncode == 2 and gone in failed.stderr
    assert "satagraph = satagraph.cli:run" in (ROOT / "setup.cfg").read_text()
