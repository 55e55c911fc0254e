"""``satagraph inspect FOLDER``: one line per BVH file below a folder and a
summary of how its rigs read, to check a dataset before training on it
(mixed up axes, units no file tells, files that do not read)."""
from __future__ import annotations

import argparse
import json
import os
from collections import Counter
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Tuple

from satagraph.cli.folders import each_kept, failure_line, input_files

#: The columns of a folder's table.
COLUMNS = ("file", "joints", "frames", "fps", "seconds", "up axis", "units", "height, m",
           "warnings")


def folder_row(info: Dict[str, Any], relative: str) -> List[str]:
    """One table row of a file's :func:`~satagraph.cli.describe`."""
    rig = info["rig"]
    up = rig["up_axis"] + (f" ({rig['up_axis_confidence']:.2f})"
                           if rig["up_axis_how"] == "detected" else f" ({rig['up_axis_how']})")
    units = "undecided" if rig["units_how"] == "kept" else f"{rig['units']} ({rig['units_how']})"
    height = "?" if rig["units_how"] == "kept" else f"{info['height_m']:.3g}"
    return [relative, str(info["joints"]), str(info["frames"]), f"{info['fps']:g}",
            f"{info['duration']:.1f}", up, units, height, str(len(rig["warnings"]))]


def folder_summary(infos: List[Dict[str, Any]], failed: int) -> str:
    """How the rigs of a folder read, in one line."""
    def counts(values) -> str:
        return ", ".join(f"{k} {n}" for k, n in Counter(values).most_common())
    ups = counts(i["rig"]["up_axis"] for i in infos)
    units = counts("undecided" if i["rig"]["units_how"] == "kept" else i["rig"]["units"]
                   for i in infos)
    warned = sum(bool(i["rig"]["warnings"]) for i in infos)
    bound = sum(bool(i.get("bind_frame")) for i in infos)
    return (f"{len(infos) + failed} files: up axis {ups or '-'}; units {units or '-'}; "
            f"{warned} with warnings; {bound} with a bind pose as frame 0; "
            f"{failed} unreadable")


def manifest_rigs(folder: str) -> Dict[str, Tuple[Optional[str], Optional[float]]]:
    """The up axis and units that the manifest of a folder (the nearest at
    or above it, :func:`~satagraph.datasets.sources.scan_folder`) sets, per
    file by its absolute path: what training reads the files with."""
    from satagraph.datasets.sources import scan_folder
    return {os.path.abspath(f.path): (f.up_axis, f.scale) for f in scan_folder(folder)
            if f.up_axis is not None or f.scale is not None}


def run_inspect_folder(args: argparse.Namespace,
                       describe_file: Callable[[str, Optional[str], Optional[float]], Dict]
                       ) -> int:
    """Describe every BVH file below ``args.file`` (:obj:`describe_file`:
    a path, with the up axis and units its folder's manifest sets, to
    :func:`~satagraph.cli.describe`'s summary; a manifest's ``up_axis`` and
    ``scale`` columns were not read, so the files whose units training reads
    from them showed as undecided) as a table or, with ``--json``, a list; a
    file that does not read is said in one line and the others go on (exit
    code 2 if any failed)."""
    files = input_files(args.file)
    rigs = manifest_rigs(args.file)
    infos, bad = each_kept(files, lambda path: describe_file(
        str(path), *rigs.get(os.path.abspath(path), (None, None))),
        failure_line, args.traceback)
    failed = len(bad)
    rows = [folder_row(info, Path(info["file"]).relative_to(args.file).as_posix())
            for info in infos]
    if args.json:
        print(json.dumps(infos, indent=2))
    else:
        print(_table(rows))
        print(folder_summary(infos, failed))
    return 2 if failed else 0


def _table(rows: List[List[str]]) -> str:
    """Aligned columns: text left, numbers right."""
    widths = [max([len(c)] + [len(r[i]) for r in rows]) for i, c in enumerate(COLUMNS)]
    left = {0, 5, 6}

    def line(cells) -> str:
        return "  ".join(c.ljust(w) if i in left else c.rjust(w)
                         for i, (c, w) in enumerate(zip(cells, widths))).rstrip()
    return "\n".join([line(COLUMNS)] + [line(r) for r in rows])


__all__ = ["COLUMNS", "folder_row", "folder_summary", "manifest_rigs", "run_inspect_folder"]
