"""Commands over a folder of BVH files (``satagraph retarget SRC_DIR
--target T.bvh OUT_DIR``, ``satagraph reconstruct IN_DIR OUT_DIR``): every
``.bvh`` below the folder, written to the same relative path below the
output folder; a file that fails gets one line on stderr and the run goes
on, and no output file is left for it (BVH writes are atomic)."""
from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import Callable, List, Union

PathLike = Union[str, Path]


def bvh_files(folder: PathLike) -> List[Path]:
    """Every ``.bvh`` entry (any case) below :obj:`folder` but folders,
    sorted: special files and broken links too, which the reader refuses
    in one line rather than the listing leaving them out unsaid."""
    return sorted(p for p in Path(folder).rglob("*") if p.suffix.lower() == ".bvh"
                  and not p.is_dir())


def failure_line(path: PathLike, err: BaseException) -> str:
    """One line for a file that failed, naming it (once)."""
    if isinstance(err, OSError) and err.filename is not None:
        text = f"{err.filename}: {err.strerror or err}"
    else:
        text = str(err) or type(err).__name__
    text = " ".join(text.split())
    return text if str(path) in text else f"{path}: {text}"


def run_over_folder(source: PathLike, output: PathLike, one: Callable[[str, str], str],
                    verb: str, traceback: bool = False) -> int:
    """Run :obj:`one` (input path, output path -> a one-line summary) on
    every BVH file below :obj:`source`, writing below :obj:`output`.

    Returns:
        int: 0 when every file went through, 2 when any failed (each said
        on stderr as it failed, and listed at the end).

    Raises:
        ValueError: :obj:`output` is a file or named as one (``.bvh``), or
            :obj:`source` holds no BVH file (outside :obj:`output`, whose
            files are never read as inputs).
    """
    source, output = Path(source), Path(output)
    if (output.exists() and not output.is_dir()) or output.suffix.lower() == ".bvh":
        raise ValueError(f"{output}: not a folder: with an input folder, OUT is the folder "
                         "the results go to")
    inside = output.resolve()
    files = [p for p in bvh_files(source) if inside not in p.resolve().parents]
    if not files:
        raise ValueError(f"{source}: no .bvh files in this folder or below it")
    start, failed = time.perf_counter(), []
    for path in files:
        out = output / path.relative_to(source)
        try:
            out.parent.mkdir(parents=True, exist_ok=True)
            print(one(str(path), str(out)))
        except Exception as err:  # one bad file never stops the folder
            if traceback:
                raise
            failed.append(path)
            print(f"satagraph: error: {failure_line(path, err)}", file=sys.stderr)
    done = len(files) - len(failed)
    print(f"{verb} {done} of {len(files)} files into {output} in "
          f"{time.perf_counter() - start:.1f} s" + _failed(failed))
    return 2 if failed else 0


def _failed(failed: List[Path], shown: int = 10) -> str:
    """The end of the summary line: the files that failed, the first
    :obj:`shown` named."""
    if not failed:
        return ""
    names = ", ".join(str(p) for p in failed[:shown])
    more = f" and {len(failed) - shown} more (each said above)" if len(failed) > shown else ""
    return f"; {len(failed)} failed: {names}{more}"


__all__ = ["bvh_files", "failure_line", "run_over_folder"]
