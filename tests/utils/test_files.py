"""The one atomic-write helper, stale temporary files, path checks."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from satagraph.utils.files import (InputFileError, OutputPathError, atomic_path,
                                   atomic_write, atomic_write_text, check_input_file,
                                   check_output_path, sweep_stale_temps)


def _temps(folder: Path):
    return sorted(p.name for p in folder.iterdir() if ".tmp" in p.name)


def test_atomic_write_replaces_and_keeps_mode(tmp_path: Path) -> None:
    path = tmp_path / "a.txt"
    path.write_text("old")
    path.chmod(0o640)
    atomic_write_text(path, "new")
    assert path.read_text() == "new"
    assert (path.stat().st_mode & 0o777) == 0o640
    assert _temps(tmp_path) == []


def test_failed_write_keeps_the_old_file_and_no_temp(tmp_path: Path) -> None:
    path = tmp_path / "a.json"
    path.write_text("previous")

    def fail(f) -> None:
        f.write("partial")
        raise RuntimeError("boom")

    with pytest.raises(RuntimeError):
        atomic_write(path, fail)
    assert path.read_text() == "previous"
    assert _temps(tmp_path) == []


def test_errors_name_the_destination_not_the_temp(tmp_path: Path) -> None:
    def fail(f) -> None:
        raise OSError(28, "No space left on device")

    with pytest.raises(OSError) as info:
        atomic_write(tmp_path / "out.bvh", fail)
    assert info.value.filename == str(tmp_path / "out.bvh")
    assert ".tmp" not in str(info.value)


def test_atomic_path_keeps_the_extension(tmp_path: Path) -> None:
    with atomic_path(tmp_path / "x.gif") as tmp:
        assert tmp.endswith(".gif") and Path(tmp).parent == tmp_path
        Path(tmp).write_bytes(b"GIF89a")
    assert (tmp_path / "x.gif").read_bytes() == b"GIF89a"


def test_stale_temps_of_dead_processes_are_swept(tmp_path: Path) -> None:
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True).stdout.strip()
    from satagraph.utils.files import HOST
    stale = tmp_path / f".out.bvh.{HOST}-{dead}.0123abcd.tmp.bvh"
    old_style = tmp_path / f".walk.bvh.{dead}.0123abcd.tmp.bvh"  # before host tags
    live = tmp_path / f".out.bvh.{HOST}-{os.getpid()}.0123abcd.tmp.bvh"
    # another machine's write into a shared folder: its pid means nothing here
    elsewhere = tmp_path / f".out.bvh.{'0' * 6 if HOST != '0' * 6 else '1' * 6}-{dead}.0123abcd.tmp"
    other = tmp_path / ".notes.tmp"
    for p in (stale, old_style, live, elsewhere, other):
        p.write_text("x")
    atomic_write_text(tmp_path / "out.bvh", "data")  # first write in the folder
    assert not stale.exists() and not old_style.exists()
    assert live.exists() and elsewhere.exists() and other.exists()
    live.unlink()
    elsewhere.unlink()
    assert sweep_stale_temps(tmp_path) == 0


def _in_new_pid_namespace(code: str) -> subprocess.CompletedProcess:
    """Run Python :obj:`code` as a container that shares this machine's
    host name does: in a process-id namespace of its own."""
    return subprocess.run(["unshare", "--user", "--map-root-user", "--pid", "--fork",
                           "--mount-proc", sys.executable, "-c", code],
                          capture_output=True, text=True, timeout=60,
                          cwd=Path(__file__).resolve().parents[2])


def test_a_container_of_the_same_host_name_leaves_live_writes(tmp_path: Path) -> None:
    """A write in progress here is no leftover to a process of another
    process-id namespace (``docker run --network host`` on a shared
    volume, ``satagraph cache --clear`` there): this pid is dead there,
    and its sweep deleted the temporary file, failing the write."""
    probe = _in_new_pid_namespace("import os; print(os.getpid())")
    if probe.returncode != 0 or probe.stdout.strip() == str(os.getpid()):
        pytest.skip(f"no process-id namespace can be made here: {probe.stderr.strip()}")
    with atomic_path(tmp_path / "out.bvh") as tmp:
        Path(tmp).write_text("half")
        swept = _in_new_pid_namespace("from satagraph.utils.files import sweep_stale_temps; "
                                      f"print(sweep_stale_temps({str(tmp_path)!r}))")
        assert swept.stdout.strip() == "0", swept.stderr
        Path(tmp).write_text("whole")
    assert (tmp_path / "out.bvh").read_text() == "whole"


def test_sweeping_on_windows_never_signals(tmp_path: Path,
                                           monkeypatch: pytest.MonkeyPatch) -> None:
    """``os.kill(pid, 0)`` on Windows ends a live process and raises
    ``OSError`` (EINVAL) for a gone one: the sweep of a folder ended
    another writer there, or failed the write."""
    from satagraph.utils import files
    killed = []

    def windows_kill(pid: int, sig: int) -> None:  # what os.kill does there
        if pid != 4242:
            raise OSError(22, "Invalid argument")
        killed.append(pid)
    monkeypatch.setattr(files, "_WINDOWS", True, raising=False)
    monkeypatch.setattr(files.os, "kill", windows_kill)
    monkeypatch.setattr(files, "_windows_pid_alive", lambda pid: pid == 4242,
                        raising=False)
    alive = tmp_path / f".a.bvh.{files.HOST}-4242.0123abcd.tmp.bvh"
    gone = tmp_path / f".b.bvh.{files.HOST}-4343.0123abcd.tmp.bvh"
    for p in (alive, gone):
        p.write_text("x")
    assert sweep_stale_temps(tmp_path) == 1
    assert alive.exists() and not gone.exists() and not killed


def test_check_input_file_refuses_special_files(tmp_path: Path) -> None:
    fifo = tmp_path / "pipe.bvh"
    os.mkfifo(fifo)
    for path, word in ((fifo, "FIFO"), (tmp_path, "directory"),
                       (Path("/dev/zero"), "device"), (tmp_path / "no.bvh", "No such")):
        with pytest.raises(InputFileError, match=word):
            check_input_file(path, "BVH file")
    regular = tmp_path / "a.bvh"
    regular.write_text("x")
    with pytest.raises(InputFileError, match="larger"):
        check_input_file(regular, max_bytes=0)
    assert check_input_file(regular).st_size == 1


def test_check_output_path(tmp_path: Path) -> None:
    assert check_output_path(tmp_path / "out.bvh") == tmp_path / "out.bvh"
    with pytest.raises(OutputPathError, match="directory"):
        check_output_path(tmp_path)
    with pytest.raises(OutputPathError, match="does not exist"):
        check_output_path(tmp_path / "missing" / "out.bvh")
    assert check_output_path(tmp_path / "new" / "deeper" / "out.bvh", create_parent=True)
    assert not (tmp_path / "new").exists()  # made by the write: a refused command made none
    (tmp_path / "file").write_text("")
    with pytest.raises(OutputPathError, match="Not a directory"):
        check_output_path(tmp_path / "file" / "new" / "out.bvh", create_parent=True)
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        if not os.access(ro, os.W_OK):  # root may write anyway
            with pytest.raises(OutputPathError, match="not writable"):
                check_output_path(ro / "out.bvh")
    finally:
        ro.chmod(0o700)


def test_one_atomic_helper_in_the_package() -> None:
    """Every other module writes through satagraph.utils.files."""
    root = Path(__file__).resolve().parents[2] / "satagraph"
    offenders = [str(p.relative_to(root)) for p in root.rglob("*.py")
                 if p.name != "files.py" and ("mkstemp" in p.read_text()
                                              or "os.replace(" in p.read_text())]
    assert offenders == []
