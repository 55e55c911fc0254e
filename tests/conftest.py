"""Shared fixtures: the real BVH data folder, its manifest, cached reads and
small hand-built skeletons and motions.

torch and satagraph are imported where they are used: under ``-n 2`` the
controlling process loads this file too, and runs no test (2 s saved)."""
from __future__ import annotations

import contextlib
import csv
import os
import signal
import socket
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, ContextManager, Dict, Iterator, List, Optional

import numpy as np
import pytest

if TYPE_CHECKING:
    from satagraph.motion import Motion
    from satagraph.skeleton import Skeleton

REPO_ROOT = Path(__file__).resolve().parents[1]
DATA_ENV = "SATAGRAPH_DATA"
SKIP_MESSAGE = ("../shared/data not found: real-data tests need the shared BVH "
                "files (set SATAGRAPH_DATA)")
ORDERS = ("XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX")


# ----------------------------------------------------------------- real data
def data_dir() -> Optional[Path]:
    """The shared data folder, or ``None`` when it is missing."""
    path = Path(os.environ.get(DATA_ENV) or REPO_ROOT.parent / "shared" / "data")
    return path if (path / "manifest.tsv").is_file() else None


def _read_manifest(root: Path) -> List[Dict[str, str]]:
    with open(root / "manifest.tsv", newline="") as f:
        return list(csv.DictReader(f, delimiter="\t"))


def _representatives(rows: List[Dict[str, str]]) -> List[Dict[str, str]]:
    """The shortest file of each skeleton id (keeps round trips fast)."""
    best: Dict[str, Dict[str, str]] = {}
    for row in rows:
        cur = best.get(row["skeleton"])
        if cur is None or int(row["frames"]) < int(cur["frames"]):
            best[row["skeleton"]] = row
    return list(best.values())


# ------------------------------------------------------------------ threads
THREAD_VARIABLES = ("OMP_NUM_THREADS", "MKL_NUM_THREADS")


def pytest_configure(config: pytest.Config) -> None:
    """One intra-op thread in the commands the tests spawn (a value the
    user exported is kept): the tiny models gain nothing from more, and two
    ``-n 2`` workers each running two threads on two cores slow every step
    (the suite took 64 s that way, 56 s this way)."""
    for name in THREAD_VARIABLES:
        os.environ.setdefault(name, "1")


@pytest.fixture(scope="session", autouse=True)
def _one_thread() -> None:
    """One intra-op thread in the test processes too (torch may be imported
    before :func:`pytest_configure` sets the variables). It also keeps
    ``ddp_fork`` from hanging: a child forked while a pool of threads
    runs waits on them forever."""
    import torch

    torch.set_num_threads(1)


# ------------------------------------------------------------------- fsync
@pytest.fixture(scope="session", autouse=True)
def _no_fsync() -> Iterator[None]:
    """``os.fsync`` in the test processes checks its descriptor and returns:
    no test can tell a file on the disk from one in the page cache, and the
    suite's 800 atomic writes each waited 3 ms or more for the disk. The
    writes still take the same path (temporary file, ``fsync`` call,
    rename), and the commands the tests spawn (``kill -9`` and resume)
    sync for real."""
    def fsync(fd: Any) -> None:
        os.fstat(fd if isinstance(fd, int) else fd.fileno())  # a bad one still fails

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(os, "fsync", fsync)
        yield


# ---------------------------------------------------------- end of session
@pytest.hookimpl(trylast=True)
def pytest_sessionfinish(session: pytest.Session) -> None:
    """Collect until nothing is left to collect, then freeze what lives:
    pytest's own five collections at exit (which look for unraisable
    exceptions in finalisers) then walk a few objects, not the half million
    that torch, PyG and Lightning keep alive (about 0.2 s each, in each
    worker, at the end of the run). Once a collection finds nothing, more
    would find nothing either; pytest's hook for unraisable exceptions is
    still in place for those before it."""
    import gc

    for _ in range(10):
        if not gc.collect():
            gc.freeze()
            return


# --------------------------------------------------------------- slow tests
SLOW_REASON = "slow: run with --slow (everything) or -m slow (only these)"


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--slow", action="store_true", default=False,
                     help="also run the tests marked slow (skipped by default)")


def pytest_collection_modifyitems(config: pytest.Config,
                                  items: List[pytest.Item]) -> None:
    """Tests marked ``slow`` are skipped unless ``--slow`` is given or the
    ``-m`` expression names the marker (``-m slow``)."""
    if config.getoption("--slow") or "slow" in (config.getoption("markexpr") or ""):
        return
    skip = pytest.mark.skip(reason=SLOW_REASON)
    for item in items:
        if item.get_closest_marker("slow") is not None:
            item.add_marker(skip)


# -------------------------------------------------------- real-data params
def _row_params(rows: List[Dict[str, str]], slow_beyond_representatives: bool
                ) -> List[Any]:
    """One param per row; with :obj:`slow_beyond_representatives`, all but
    the shortest file of each skeleton id are marked slow."""
    quick = {r["path"] for r in _representatives(rows)}
    return [pytest.param(r, id=r["path"], marks=(
        [pytest.mark.slow] if slow_beyond_representatives and r["path"] not in quick
        else [])) for r in rows]


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    """Parametrise ``manifest_row`` over every file of the manifest,
    ``skeleton_row`` over one file per skeleton id, and ``every_file_row``
    over every file with all but one file per skeleton id marked slow."""
    wanted = [n for n in ("manifest_row", "skeleton_row", "every_file_row")
              if n in metafunc.fixturenames]
    if not wanted:
        return
    root = data_dir()
    rows = _read_manifest(root) if root is not None else []
    for name in wanted:
        chosen = _representatives(rows) if name == "skeleton_row" else rows
        if not chosen:
            metafunc.parametrize(name, [pytest.param(
                None, marks=pytest.mark.skip(reason=SKIP_MESSAGE))])
        else:
            metafunc.parametrize(name, _row_params(chosen, name == "every_file_row"))


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """Path of the shared data folder (``../shared/data`` or
    ``$SATAGRAPH_DATA``); skips the test when it is missing."""
    root = data_dir()
    if root is None:
        pytest.skip(SKIP_MESSAGE)
    return root


@pytest.fixture(scope="session")
def manifest(shared_data: Path) -> List[Dict[str, str]]:
    """Rows of ``manifest.tsv`` as dicts (path, dataset, skeleton, fps, ...)."""
    return _read_manifest(shared_data)


@pytest.fixture(scope="session")
def read_real(shared_data: Path) -> Callable[[str], Motion]:
    """Read a file of the shared data folder by its manifest path, once per
    session. Callers must not modify the returned motion."""
    from satagraph.io import read_bvh
    cache: Dict[str, Motion] = {}

    def read(rel_path: str) -> Motion:
        if rel_path not in cache:
            cache[rel_path] = read_bvh(shared_data / rel_path)
        return cache[rel_path]

    return read


# -------------------------------------------------------------- synthetic
def _tiny_skeleton() -> Skeleton:
    r"""A 10-joint biped-like tree (3 end sites)::

        0 Hips
        +-- 1 Spine -- 2 Head -- 3 Head_end*
        +-- 4 LeftLeg -- 5 LeftFoot -- 6 LeftFoot_end*
        +-- 7 RightLeg -- 8 RightFoot -- 9 RightFoot_end*
    """
    from satagraph.skeleton import Skeleton
    names = ["Hips", "Spine", "Head", "Head_end", "LeftLeg", "LeftFoot",
             "LeftFoot_end", "RightLeg", "RightFoot", "RightFoot_end"]
    parents = np.array([-1, 0, 1, 2, 0, 4, 5, 0, 7, 8])
    offsets = np.array([
        [0.0, 90.0, 0.0], [0.0, 20.0, 0.0], [0.0, 30.0, 1.0], [0.0, 10.0, 0.0],
        [10.0, -5.0, 0.0], [0.0, -80.0, 0.0], [0.0, -5.0, 12.0],
        [-10.0, -5.0, 0.0], [0.0, -80.0, 0.0], [0.0, -5.0, 12.0]])
    pos = ("Xposition", "Yposition", "Zposition")
    rot = {o: tuple(f"{a}rotation" for a in o) for o in ORDERS}
    channels = [pos + rot["ZXY"], rot["XYZ"], rot["XZY"], (), pos + rot["YXZ"],
                rot["YZX"], (), rot["ZYX"], rot["ZXY"], ()]
    end_site = np.array([n.endswith("_end") for n in names])
    return Skeleton(names, parents, offsets, channels, end_site)


@pytest.fixture
def tiny_skeleton() -> Skeleton:
    """A hand-built 10-joint skeleton with every Euler order, 3- and
    6-channel joints and 3 end sites."""
    return _tiny_skeleton()


def _random_motion(skeleton: Skeleton, num_frames: int = 8, fps: float = 30.0,
                   seed: int = 0) -> Motion:
    """A motion with random rotations (Euler angles away from gimbal lock)
    and random values on every position channel; no raw channels."""
    import torch

    from satagraph.motion import Motion
    from satagraph.ops.rotation import euler_to_matrix
    gen = np.random.default_rng(seed)
    num = skeleton.num_joints
    angles = gen.uniform(-np.pi, np.pi, size=(num_frames, num, 3))
    angles[..., 1] = gen.uniform(-1.3, 1.3, size=(num_frames, num))
    rot = np.broadcast_to(np.eye(3), (num_frames, num, 3, 3)).copy()
    trans = np.broadcast_to(skeleton.offsets, (num_frames, num, 3)).copy()
    for j, order in enumerate(skeleton.rotation_orders):
        if order:
            rot[:, j] = euler_to_matrix(torch.from_numpy(angles[:, j]), order).numpy()
        if skeleton.has_position_channels[j]:
            trans[:, j] = skeleton.offsets[j] + gen.normal(0, 5, (num_frames, 3))
    return Motion(skeleton, rot, trans, fps=fps)


@pytest.fixture
def random_motion() -> Callable[..., Motion]:
    """Factory ``random_motion(skeleton, num_frames=8, fps=30.0, seed=0)``."""
    return _random_motion


@pytest.fixture
def tiny_motion(tiny_skeleton: Skeleton) -> Motion:
    """A seeded 8-frame random motion of :func:`tiny_skeleton`."""
    return _random_motion(tiny_skeleton, num_frames=8, seed=0)


def _assert_same_hierarchy(a: Skeleton, b: Skeleton, atol: float = 1e-6) -> None:
    assert a.names == b.names
    np.testing.assert_array_equal(a.parents, b.parents)
    np.testing.assert_allclose(a.offsets, b.offsets, rtol=1e-5, atol=atol)
    assert a.channels == b.channels
    np.testing.assert_array_equal(a.end_site, b.end_site)


@pytest.fixture
def assert_same_hierarchy() -> Callable[[Skeleton, Skeleton], None]:
    """Checker: same names, parents, offsets, channels and end sites."""
    return _assert_same_hierarchy


def _assert_grounded_pair(grounded_path: Path, raw_path: Path, lifted: bool = False) -> None:
    """Two outputs of one command with ``--ground`` and ``--no-ground``: the
    same rotations, root paths one constant apart, and the grounded one's
    median lowest joint within 2 % of its height of its file's floor. With
    :obj:`lifted` (a retarget), frames whose lowest joint would sink are
    raised onto the floor: their roots stand higher than the constant, and
    no frame is below the floor."""
    from satagraph.io import read_bvh
    from satagraph.transforms.canonical import canonicalize
    from satagraph.transforms.ground import lowest_heights
    grounded, raw = read_bvh(grounded_path), read_bvh(raw_path)
    np.testing.assert_allclose(grounded.rotations, raw.rotations, atol=1e-6)
    canon = canonicalize(grounded, fps=30.0, floor=False)  # the file's own floor
    shift = canon.translations[:, 0] - canonicalize(raw, fps=30.0, floor=False).translations[:, 0]
    low, tol = lowest_heights(canon), 1e-4 * canon.height()
    if lifted:
        raised = shift[:, 1] > shift[:, 1].min() + tol
        np.testing.assert_allclose(low[raised], 0.0, atol=tol)
        assert low.min() > -tol
        shift[:, 1] = shift[:, 1].min()
    np.testing.assert_allclose(shift, np.broadcast_to(shift[0], shift.shape), atol=tol)
    assert abs(np.median(low)) < 0.02 * canon.height()


@pytest.fixture
def assert_grounded_pair() -> Callable[..., None]:
    """Checker of a ``--ground`` / ``--no-ground`` pair of output files."""
    return _assert_grounded_pair


@contextlib.contextmanager
def _file_size_limit(limit: int) -> Iterator[None]:
    """Writes past :obj:`limit` bytes fail with ``EFBIG``, as a full disk
    fails them with ``ENOSPC`` (no mount needed; POSIX only: the test is
    skipped where the system has no file size limit, as on Windows)."""
    resource = pytest.importorskip("resource")
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    handler = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (limit, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))
        signal.signal(signal.SIGXFSZ, handler)


@pytest.fixture
def file_size_limit() -> Callable[[int], ContextManager[None]]:
    """``with file_size_limit(n):`` makes writes past ``n`` bytes fail, as
    on a full disk."""
    return _file_size_limit


@pytest.fixture
def no_internet(monkeypatch: pytest.MonkeyPatch) -> None:
    """No connection leaves the machine: a socket may reach a local one
    (``AF_UNIX``: W&B's own service process), no address of a network."""
    def refuse(*args: Any, **kwargs: Any) -> None:
        raise AssertionError(f"network access: {args[1:] or args}")

    def local_only(real: Callable) -> Callable:
        def connect(sock: socket.socket, address: Any) -> Any:
            if sock.family != socket.AF_UNIX:
                refuse(sock, address)
            return real(sock, address)
        return connect

    for name in ("connect", "connect_ex"):
        monkeypatch.setattr(socket.socket, name, local_only(getattr(socket.socket, name)))
    monkeypatch.setattr(socket, "create_connection", refuse)
    monkeypatch.setattr(socket, "getaddrinfo", refuse)


@pytest.fixture(autouse=True)
def _seed() -> None:
    """Every test starts from the same random state. The tests run on the
    CPU, so its generator is the one seeded: ``torch.manual_seed`` also queues
    a seed for each accelerator, formatting a stack trace each time (2 ms a
    test, 4 s a suite)."""
    import torch
    np.random.seed(0)
    torch.default_generator.manual_seed(0)


def save_module_checkpoint(module, path: Path) -> Path:
    """What a trainer stores of a module: weights, hyperparameters and the
    module's own :meth:`on_save_checkpoint` entries (a checkpoint without
    training one)."""
    import lightning as L
    import torch
    ckpt = {"state_dict": module.state_dict(), "hyper_parameters": dict(module.hparams),
            "pytorch-lightning_version": L.__version__}
    module.on_save_checkpoint(ckpt)
    torch.save(ckpt, path)
    return path

