r"""Safe file handling shared by every reader and writer.

- :func:`atomic_write` is the ONE way satagraph writes a file: into a
  temporary file beside the destination (``.<name>.<host>-<pid>.<random>.tmp``),
  flushed and fsynced, then moved into place with :func:`os.replace`.
  Readers never see a half-written file, a failed write leaves the previous
  file untouched and removes its temporary file, errors name the
  destination (never the temporary file), and temporary files left by a
  killed process (``kill -9``) are swept by the first write of a process in
  that folder (:func:`sweep_stale_temps`; those of this machine and
  process-id namespace only).
- :func:`append_whole` appends a record to a log whole or not at all.
- :func:`lock_fd` and :func:`file_lock` keep another process out (of a
  run's folder, of a cache's read-merge-write).
- :func:`check_output_path` checks an output path before any work is done.
- :func:`check_input_file` refuses what is not a regular file (FIFOs,
  devices, sockets, directories: reading them hangs or never ends) and
  files too large to read into memory.
"""
from __future__ import annotations

import contextlib
import errno
import hashlib
import os
import re
import secrets
import shutil
import socket
import stat
import time
from pathlib import Path
from typing import IO, Any, Callable, Iterator, Optional, Union

PathLike = Union[str, "os.PathLike[str]"]

#: Largest input file read into memory (bytes).
MAX_INPUT_BYTES = 4 << 30

#: Temporary files: ``.<destination name>.<host>-<pid>.<8 hex>.tmp[.<extension>]``
#: (``<host>``: :data:`HOST`; files of versions before it have none).
_TEMP = re.compile(r"^\.(?P<name>.+)\.(?:(?P<host>[0-9a-f]{6})-)?(?P<pid>\d+)\.[0-9a-f]{8}"
                   r"\.tmp(?:\.[^.]+)?$")


def _machine() -> str:
    """This machine's host name and, on Linux, its process-id namespace: a
    container that shares the host name (``docker run --network host``,
    the containers of one pod) numbers its processes afresh."""
    try:
        space = os.readlink("/proc/self/ns/pid")
    except OSError:  # no /proc: not Linux
        space = ""
    return f"{socket.gethostname()} {space}".rstrip()


#: This machine (or container) in temporary file names: a process id means
#: something only where it was given, so a folder shared between machines
#: or containers (a cache in a network home, a volume mounted in two) is
#: swept of this machine's leftovers alone.
HOST = hashlib.sha1(_machine().encode()).hexdigest()[:6]


class InputFileError(ValueError):
    """An input path that cannot be read as a file; the message names it."""


class OutputPathError(ValueError):
    """An output path that cannot be written; the message names it."""


def _kind(mode: int) -> str:
    for test, name in ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
                       (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                       (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return name
    return "not a regular file"


def check_input_file(path: PathLike, what: str = "file",
                     max_bytes: int = MAX_INPUT_BYTES) -> os.stat_result:
    """The :func:`os.stat` of a readable regular file.

    Args:
        path: The file.
        what: What it should be, for messages (``"BVH file"``).
        max_bytes: Largest accepted size.

    Raises:
        InputFileError: Missing, unreadable, not a regular file (a FIFO, a
            device such as ``/dev/zero``, a directory) or too large; one
            line naming :obj:`path`.
    """
    try:
        st = os.stat(path)
    except OSError as err:
        raise InputFileError(f"{os.fspath(path)}: cannot read {what}: "
                             f"{err.strerror or err}") from None
    if not stat.S_ISREG(st.st_mode):
        raise InputFileError(f"{os.fspath(path)}: is {_kind(st.st_mode)}, "
                             f"not a {what}")
    if st.st_size > max_bytes:
        raise InputFileError(f"{os.fspath(path)}: {st.st_size / 2**30:.1f} GiB is "
                             f"larger than the {max_bytes / 2**30:.0f} GiB a {what} "
                             "may have")
    if not os.access(path, os.R_OK):
        raise InputFileError(f"{os.fspath(path)}: cannot read {what}: permission denied")
    return st


def check_output_path(path: PathLike, create_parent: bool = False) -> Path:
    """Check, before any work, that :obj:`path` can be written.

    Args:
        path: The output file.
        create_parent: A missing parent folder will be created by the write
            (else it must exist): the nearest folder above it must be
            writable. Nothing is created here, so that a command refused
            after this check leaves no empty folder behind.

    Returns:
        Path: The path.

    Raises:
        OutputPathError: The path is a directory or another non-regular
            file, its folder is missing or not writable; one line naming it.
    """
    path = Path(path)
    if path.name in ("", ".", ".."):
        raise OutputPathError(f"cannot write {path}: an output file needs a file name")
    try:
        st = os.stat(path)
    except FileNotFoundError:
        st = None
    except OSError as err:
        raise OutputPathError(f"cannot write {path}: {err.strerror or err}") from None
    if st is not None and not stat.S_ISREG(st.st_mode):
        raise OutputPathError(f"cannot write {path}: it is {_kind(st.st_mode)}; give a "
                              "file path")
    parent = path.parent if str(path.parent) else Path(".")
    while create_parent and not parent.exists() and parent != parent.parent:
        parent = parent.parent  # the folder the write creates the missing ones in
    if not parent.is_dir():
        raise OutputPathError(f"cannot write {path}: folder {parent} does not exist")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise OutputPathError(f"cannot write {path}: folder {parent} is not writable")
    return path


def _file_mode(path: str) -> int:
    """Permissions of the file being replaced, else the default for new
    files (0666 less the umask)."""
    try:
        return stat.S_IMODE(os.stat(path).st_mode)
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def is_temp_file(name: str) -> bool:
    """Whether a file name is one of :func:`atomic_write`'s temporary files
    (``.<name>.<host>-<pid>.<random>.tmp.<ext>``): a write in progress or
    one a killed process left half done, never a file to read."""
    return _TEMP.match(os.path.basename(name)) is not None


#: Windows, where ``os.kill(pid, 0)`` ends the process (``TerminateProcess``)
#: instead of asking whether it runs.
_WINDOWS = os.name == "nt"
#: ``OpenProcess`` access, its error for a process that is gone, and the
#: exit code of one that runs.
_QUERY_LIMITED_INFORMATION, _ERROR_INVALID_PARAMETER, _STILL_ACTIVE = 0x1000, 87, 259


def _windows_pid_alive(pid: int) -> bool:
    """Whether process :obj:`pid` runs, asked of Windows; a process it
    will not tell about (access denied) counts as alive."""
    import ctypes
    kernel32 = ctypes.WinDLL("kernel32", use_last_error=True)
    handle = kernel32.OpenProcess(_QUERY_LIMITED_INFORMATION, False, pid)
    if not handle:
        return ctypes.get_last_error() != _ERROR_INVALID_PARAMETER
    try:
        code = ctypes.c_ulong()
        return (not kernel32.GetExitCodeProcess(handle, ctypes.byref(code))
                or code.value == _STILL_ACTIVE)
    finally:
        kernel32.CloseHandle(handle)


def _pid_alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    if _WINDOWS:
        return _windows_pid_alive(pid)
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def sweep_stale_temps(directory: PathLike, name: Optional[str] = None) -> int:
    """Remove temporary files of :func:`atomic_write` left in
    :obj:`directory` by processes that no longer run (``kill -9``).

    Args:
        directory: The folder.
        name: Only those of this destination file name (default: all).

    Returns:
        int: How many were removed.
    """
    removed = 0
    try:
        entries = list(os.scandir(directory))
    except OSError:
        return 0
    for entry in entries:
        match = _TEMP.match(entry.name)
        if match is None or (name is not None and match["name"] != name):
            continue
        if match["host"] not in (None, HOST) or _pid_alive(int(match["pid"])):
            continue
        with contextlib.suppress(OSError):
            os.unlink(entry.path)
            removed += 1
    return removed


_SWEPT: set = set()


def _renamed(err: OSError, path: str) -> OSError:
    """:obj:`err` naming the destination instead of a temporary file."""
    if err.errno:
        return type(err)(err.errno, err.strerror or str(err), path)
    return OSError(f"{path}: {err}")


@contextlib.contextmanager
def atomic_path(path: PathLike, create_parent: bool = False,
                durable: bool = True) -> Iterator[str]:
    """Context manager yielding a temporary path beside :obj:`path`, which
    replaces :obj:`path` when the block ends without error (for writers
    that want a path, such as image or video libraries); on error the
    temporary file is removed and :obj:`path` is left as it was.

    The temporary path ends with :obj:`path`'s extension, for writers that
    pick a format by extension. With :obj:`durable`, the data reach the
    disk (fsync) before the rename.
    """
    path = os.fspath(path)
    directory = os.path.dirname(os.path.abspath(path))
    if create_parent:
        os.makedirs(directory, exist_ok=True)
    name = os.path.basename(path)
    if directory not in _SWEPT:  # once per folder and process: cheap in big caches
        sweep_stale_temps(directory)
        _SWEPT.add(directory)
    ext = os.path.splitext(name)[1]
    tmp = os.path.join(directory,
                       f".{name}.{HOST}-{os.getpid()}.{secrets.token_hex(4)}.tmp{ext}")
    mode = _file_mode(path)
    try:
        yield tmp
        if durable:
            with open(tmp, "rb+") as f:
                os.fsync(f.fileno())
        os.chmod(tmp, mode)
        os.replace(tmp, path)
    except OSError as err:
        raise _renamed(err, path) from None
    finally:
        with contextlib.suppress(OSError):
            os.unlink(tmp)


def atomic_write(path: PathLike, write: Callable[[IO[Any]], Any], binary: bool = False,
                 encoding: str = "utf-8", newline: Optional[str] = None,
                 create_parent: bool = False, durable: bool = True) -> None:
    """Write a file atomically: ``write(f)`` fills an open temporary file
    beside :obj:`path`, which then replaces :obj:`path`.

    Args:
        path: Destination file.
        write: Called with the open temporary file.
        binary: Open the temporary file in binary mode.
        encoding: Text encoding (text mode).
        newline: ``newline`` of :func:`open` (text mode).
        create_parent: Create a missing parent folder.
        durable: fsync before the rename (caches that can be rebuilt may
            skip it).

    Raises:
        OSError: naming :obj:`path` (never the temporary file); the previous
            file is left as it was and the temporary file is removed.
    """
    kwargs = {} if binary else {"encoding": encoding, "newline": newline}
    with atomic_path(path, create_parent, durable) as tmp:
        try:
            with open(tmp, "wb" if binary else "w", **kwargs) as f:
                write(f)
                f.flush()
        except OSError as err:
            raise _renamed(err, os.fspath(path)) from None


def keep_copy(path: PathLike, copy: PathLike) -> None:
    """Make :obj:`copy` an atomic hard link (a copy where links are not
    supported) of the file :obj:`path`, replacing :obj:`copy`."""
    with atomic_path(copy, durable=False) as tmp:
        try:
            os.link(path, tmp)
        except OSError:
            shutil.copyfile(path, tmp)


def atomic_write_text(path: PathLike, text: str, create_parent: bool = False) -> None:
    """Write UTF-8 text atomically (see :func:`atomic_write`)."""
    atomic_write(path, lambda f: f.write(text), create_parent=create_parent)


def atomic_write_bytes(path: PathLike, data: bytes, create_parent: bool = False) -> None:
    """Write bytes atomically (see :func:`atomic_write`): a file serialised
    in memory first (a checkpoint, a code bank), so that a failed write (a
    full disk) is an :class:`OSError` naming :obj:`path`, not the
    serialiser's own error."""
    atomic_write(path, lambda f: f.write(data), binary=True, create_parent=create_parent)


def append_whole(path: PathLike, data: bytes, create_parent: bool = False) -> None:
    """Append :obj:`data` (a record of a log) to :obj:`path` whole or not at
    all: an append that fails part way (a full disk) is cut back off, so
    that the next one does not run on from half a record.

    Raises:
        OSError: naming :obj:`path`; the file is left as it was.
    """
    path = os.fspath(path)
    if create_parent:
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    try:
        fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o666)
    except OSError as err:
        raise _renamed(err, path) from None
    try:
        size, view = os.fstat(fd).st_size, memoryview(data)
        while view:
            view = view[os.write(fd, view):]
    except OSError as err:
        with contextlib.suppress(OSError):
            os.ftruncate(fd, size)
        raise _renamed(err, path) from None
    finally:
        os.close(fd)


#: The byte of a lock file that Windows locks: past the holder's line that
#: a run lock writes, which another process reads to name it (Windows locks
#: are not advisory).
_LOCKED_BYTE = 1 << 20


def lock_fd(fd: int, take: bool = True) -> bool:
    """Take (without waiting) or release an exclusive lock on :obj:`fd`: an
    advisory ``flock`` on POSIX, a one-byte ``msvcrt`` lock on Windows (no
    ``fcntl`` there); the system releases either when the process ends,
    even by ``kill -9``. Returns ``False`` where another holds it."""
    try:
        import fcntl
    except ImportError:  # Windows
        import msvcrt
        os.lseek(fd, _LOCKED_BYTE, os.SEEK_SET)
        try:
            msvcrt.locking(fd, msvcrt.LK_NBLCK if take else msvcrt.LK_UNLCK, 1)
        except OSError as err:
            if err.errno not in (errno.EACCES, errno.EDEADLOCK):
                raise
            return False
        finally:
            os.lseek(fd, 0, os.SEEK_SET)
        return True
    try:
        fcntl.flock(fd, (fcntl.LOCK_EX | fcntl.LOCK_NB) if take else fcntl.LOCK_UN)
    except BlockingIOError:
        return False
    return True


def names_fd(path: PathLike, fd: int) -> bool:
    """Whether :obj:`path` still names the file open as :obj:`fd`: a lock
    taken on a file that another process removed (or replaced) since it
    was opened keeps no one out, since the next process opens a new one."""
    try:
        return os.path.samestat(os.fstat(fd), os.stat(path))
    except FileNotFoundError:
        return False


@contextlib.contextmanager
def file_lock(path: PathLike, create_parent: bool = False,
              timeout: float = 60.0) -> Iterator[None]:
    """Hold an exclusive lock on the file :obj:`path` (made for it, removed
    after it) for the block, waiting while another process holds it: for a
    read-merge-write that two processes must not interleave.

    Args:
        path: The lock file.
        create_parent: Create a missing parent folder.
        timeout: Seconds to wait for another holder.

    Raises:
        OSError: The lock file cannot be made; :class:`TimeoutError` where
            another process held it :obj:`timeout` seconds; naming :obj:`path`.
    """
    path, deadline = os.fspath(path), time.monotonic() + timeout
    if create_parent:
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        while not lock_fd(fd):
            if time.monotonic() > deadline:
                os.close(fd)
                raise TimeoutError(errno.ETIMEDOUT, f"held by another process for "
                                   f"{timeout:g} s", path)
            time.sleep(0.005)
        if names_fd(path, fd):
            break
        lock_fd(fd, take=False)  # another holder removed it meanwhile: a new one
        os.close(fd)
    try:
        yield
    finally:
        with contextlib.suppress(OSError):  # while held: a waiter then tries anew
            os.unlink(path)
        lock_fd(fd, take=False)
        os.close(fd)


__all__ = ["InputFileError", "OutputPathError", "MAX_INPUT_BYTES", "check_input_file",
           "check_output_path", "atomic_write", "atomic_write_text", "atomic_write_bytes",
           "atomic_path", "keep_copy", "append_whole", "sweep_stale_temps", "is_temp_file",
           "lock_fd", "names_fd", "file_lock"]
