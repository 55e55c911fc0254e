"""Commands over a folder of BVH files (``satagraph retarget SRC_DIR
--target T.bvh OUT_DIR``, ``satagraph reconstruct IN_DIR OUT_DIR``): every
``.bvh`` below the folder, written to the same relative path below the
output folder; a file that fails gets one line on stderr and the run goes
on, and no output file is left for it (BVH writes are atomic). With
``--skip-existing``, the files whose result is already there, whole, are
left out (:func:`complete_output`): a folder run that was stopped goes on;
each file is claimed while it is made (:func:`claimed_output`), so that
two runs into one folder share the files rather than each making all."""
from __future__ import annotations

import contextlib
import os
import sys
import time
from pathlib import Path
from typing import Callable, Iterable, List, Optional, Sequence, Tuple, TypeVar, Union

from satagraph.datasets.sources import bvh_files
from satagraph.utils.files import file_lock, sweep_stale_temps

PathLike = Union[str, Path]
Item, Result = TypeVar("Item"), TypeVar("Result")


def input_files(source: PathLike, output: Optional[PathLike] = None) -> List[Path]:
    """:func:`bvh_files` below :obj:`source`, but those below
    :obj:`output` (results are never read as inputs).

    Raises:
        ValueError: None is left (one line, naming :obj:`output` where every
            file is below it: ``satagraph reconstruct takes takes``).
    """
    inside = None if output is None else Path(output).resolve()
    found = bvh_files(source)
    files = [p for p in found if inside is None or inside not in p.resolve().parents]
    if found and not files:
        raise ValueError(f"{source}: its {len(found)} .bvh file(s) are all below the output "
                         f"folder {output}, whose files are never read as inputs: write the "
                         "results to another folder")
    if not files:
        raise ValueError(f"{source}: no .bvh files in this folder or below it")
    return files


def failure_line(path: PathLike, err: BaseException) -> str:
    """One line for a file that failed, naming it (once)."""
    from satagraph.cli import _message
    text = " ".join((_message(err) or type(err).__name__).split())
    return text if str(path) in text else f"{path}: {text}"


def each_kept(items: Sequence[Item], work: Callable[[Item], Result],
              failure: Callable[[Item, BaseException], str], traceback: bool = False
              ) -> Tuple[List[Result], List[Item]]:
    """:obj:`work` on every item, one that fails said in one line on
    stderr (``satagraph: error:`` and :obj:`failure`'s text) while the
    others go on (:obj:`traceback`: raise instead): the results, and the
    items that failed."""
    results, failed = [], []
    for item in items:
        try:
            results.append(work(item))
        except Exception as err:  # one bad item never stops the rest
            if traceback:
                raise
            failed.append(item)
            print(f"satagraph: error: {failure(item, err)}", file=sys.stderr)
    return results, failed


def complete_output(path: PathLike) -> bool:
    """Whether :obj:`path` is a whole result of an earlier run: a file that
    satagraph wrote (its declaration is there) and that reads whole. BVH
    writes are atomic, so a write that a kill cut short left its temporary
    file (:func:`~satagraph.utils.files.is_temp_file`) beside this path,
    never a part of it; a file cut short otherwise (a copy) lacks frames.
    How it was made (checkpoint, options) is not checked."""
    from satagraph.io import BVHError, read_bvh
    from satagraph.io.bvh_reader import written_by_satagraph
    if not (Path(path).is_file() and written_by_satagraph(str(path))):
        return False
    try:
        read_bvh(path)
    except BVHError:
        return False
    return True


def claimed_output(path: PathLike, make: Callable[[], str]) -> Optional[str]:
    """:obj:`make` the output :obj:`path` while holding its claim
    (``.<name>.claim`` beside it, locked, removed after; the system releases
    the lock of a killed run), and its summary line; ``None``, with nothing
    made, where another live run holds the claim (it is making that output)
    or the output is whole by now (another run made it since this one
    began). Two ``--skip-existing`` runs into one folder decided at their
    start what to leave out, so each made every file."""
    path = Path(path)
    with contextlib.ExitStack() as held:
        try:
            held.enter_context(file_lock(_claim(path), timeout=0))
        except TimeoutError:
            return None
        return None if complete_output(path) else make()


def _claim(path: Path) -> Path:
    """The claim file of the output :obj:`path`: ``.<name>.claim`` beside it."""
    return path.parent / f".{path.name}.claim"


def sweep_stale_claims(outputs: Iterable[Path]) -> None:
    """Remove the claims (:func:`claimed_output`) of :obj:`outputs` that no
    live run holds: a killed run's, which no later run removes where it
    leaves that output out or makes it without ``--skip-existing``. Only
    these outputs' claims: another file named ``.*.claim`` is not one."""
    for claim in map(_claim, outputs):
        if not claim.is_file():  # none: none made by the lock either
            continue
        with contextlib.suppress(TimeoutError, OSError):  # a live run's: kept
            with file_lock(claim, timeout=0):
                pass  # taken: removed on release


def run_over_folder(source: PathLike, output: PathLike, one: Callable[[str, str], str],
                    verb: str, traceback: bool = False, skip_existing: bool = False) -> int:
    """Run :obj:`one` (input path, output path -> a one-line summary) on
    every BVH file below :obj:`source`, writing below :obj:`output`; with
    :obj:`skip_existing`, not on those whose output is already whole
    (:func:`complete_output`), nor on those another live run makes or has
    made since (:func:`claimed_output`), which the summary counts as they
    are at its end: whole, or not (that run is still making them, or
    failed on them).

    Returns:
        int: 0 when every file went through, 2 when any failed (each said
        on stderr as it failed, and listed at the end). A Ctrl-C says on
        stderr how many files went through before it, and is raised on.

    Raises:
        ValueError: :obj:`output` is a file or named as one (``.bvh``), or
            :obj:`source` holds no BVH file (outside :obj:`output`, whose
            files are never read as inputs).
    """
    source, output = Path(source), Path(output)
    if (output.exists() and not output.is_dir()) or output.suffix.lower() == ".bvh":
        raise ValueError(f"{output}: not a folder: with an input folder, OUT is the folder "
                         "the results go to")
    files = input_files(source, output)
    _check_output_folder(output)  # once: not as a failure of every input file
    start = time.perf_counter()
    todo = files
    if skip_existing:
        todo = [p for p in files if not complete_output(output / p.relative_to(source))]
    sweep_stale_claims(output / p.relative_to(source) for p in files)  # a killed run's
    if skip_existing:
        for folder in {(output / p.relative_to(source)).parent for p in files}:
            sweep_stale_temps(folder)  # what the stopped run's killed writes left

    def write(path: Path) -> Optional[Path]:
        """Make one output; the output left to another run, or ``None``."""
        out = output / path.relative_to(source)
        out.parent.mkdir(parents=True, exist_ok=True)
        if not skip_existing:
            print(one(str(path), str(out)))
            return None
        line = claimed_output(out, lambda: one(str(path), str(out)))
        print(line or f"{out}: skipped, another run makes it or has made it (--skip-existing)")
        return None if line is not None else out

    done: List[Path] = []

    def counted(path: Path) -> Optional[Path]:
        kept = write(path)
        done.append(path)
        return kept

    try:
        made, failed = each_kept(todo, counted, failure_line, traceback)
    except KeyboardInterrupt:  # said, then the command's own interrupted line
        print(f"{verb} {len(done)} of {len(files)} files into {output} before the interrupt "
              "(--skip-existing goes on with the rest)", file=sys.stderr)
        raise
    left = [out for out in made if out is not None]
    whole = sum(map(complete_output, left))  # at the end: that run may fail on one
    print(f"{verb} {len(made) - len(left)} of {len(files)} files into {output} in "
          f"{time.perf_counter() - start:.1f} s"
          + _skipped(len(files) - len(todo), whole, len(left) - whole) + _failed(failed))
    return 2 if failed else 0


def _skipped(count: int, elsewhere: int = 0, missing: int = 0) -> str:
    """The part of the summary line for the files ``--skip-existing`` left
    out: :obj:`count` there at the start, :obj:`elsewhere` made by another run
    (whole at the end), :obj:`missing` left to another run and not whole at
    the end."""
    parts = [f"{count} skipped, their results already there"] if count else []
    parts += [f"{elsewhere} made by another run"] if elsewhere else []
    parts += [f"{missing} left to another run, not whole at the end (it failed on them "
              "or is still making them)"] if missing else []
    return f"; {', '.join(parts)} (--skip-existing)" if parts else ""


def _check_output_folder(output: Path) -> None:
    """Create :obj:`output` and check that it can be written, before any
    file is read or model loaded.

    Raises:
        OutputPathError: One line naming the folder.
    """
    from satagraph.utils.files import OutputPathError
    try:
        output.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise OutputPathError(f"cannot write into {output}: cannot create the folder: "
                              f"{err.strerror or err}") from None
    if not os.access(output, os.W_OK | os.X_OK):
        raise OutputPathError(f"cannot write into {output}: the folder is not writable")


def _failed(failed: List[Path], shown: int = 10) -> str:
    """The end of the summary line: the files that failed, the first
    :obj:`shown` named."""
    if not failed:
        return ""
    names = ", ".join(str(p) for p in failed[:shown])
    more = f" and {len(failed) - shown} more (each said above)" if len(failed) > shown else ""
    return f"; {len(failed)} failed: {names}{more}"


__all__ = ["input_files", "failure_line", "each_kept", "complete_output",
           "claimed_output", "sweep_stale_claims", "run_over_folder"]
