"""Where motion files come from: folders and manifests, with splits."""
from __future__ import annotations

import csv
import fnmatch
import hashlib
import os
import re
import warnings
from collections import Counter
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Dict, Iterable, List, Optional, Sequence, Tuple, Union

from satagraph.utils.files import is_temp_file

SPLITS = ("train", "val", "test")
#: Encoding of manifest TSVs whatever the system's (Windows reads cp1252
#: otherwise); a byte order mark (Excel, Notepad) is skipped.
MANIFEST_ENCODING = "utf-8-sig"
#: Splits a manifest may hold that no run reads (the shared data's reader tests).
UNUSED_SPLITS = ("parser_test",)
#: How to give a run its data, said when its ``data.sources`` has none to read
#: (a named config's may be the project's data folder, which an installed
#: package does not have).
SOURCES_HINT = ("name your BVH folders or manifests, e.g. --data path/to/bvh_folder "
                "(train) or data.sources=[path/to/bvh_folder]")


@dataclass(frozen=True)
class MotionFile:
    r"""One BVH file with its dataset, skeleton id and split, and how to read
    its rig where that is known (a manifest's ``up_axis`` and ``scale``
    columns, or a ``data.sources`` entry's ``up_axis`` and ``units`` /
    ``scale`` keys): these override detection (see
    :class:`~satagraph.motion.RigSettings`). :attr:`skeleton_named` says
    whether the source names the skeleton id (a manifest's ``skeleton``
    column); where it does not, the id is the dataset's name, and the
    windows of every rig it holds are told apart by their rig
    (:func:`~satagraph.data.dataset.skeleton_id`). :attr:`dataset_named`
    says whether the source names the dataset (a ``data.sources`` entry's
    ``dataset`` key or a manifest's ``dataset`` column); where it does not,
    the dataset is named after a folder (:func:`refuse_shared_names`)."""

    path: str
    dataset: str
    skeleton: str
    split: str
    up_axis: Optional[str] = None
    scale: Optional[float] = None
    skeleton_named: bool = True
    dataset_named: bool = True

    def read(self):
        """The motion, with this file's rig settings attached."""
        from satagraph.transforms.rig_reading import with_rig
        from satagraph.io import read_bvh
        return with_rig(read_bvh(self.path), self.up_axis, self.scale)


def _row_settings(row: dict, where: str) -> dict:
    """``up_axis`` and ``scale`` of a manifest row or source entry (empty
    cells and missing keys: not set), validated."""
    from satagraph.transforms.rig_reading import normalize_up_axis, parse_units
    out = {}
    try:
        if row.get("up_axis") not in (None, ""):
            out["up_axis"] = normalize_up_axis(row["up_axis"])
        units = row.get("scale", row.get("units"))
        if units not in (None, ""):
            out["scale"] = parse_units(units)
    except ValueError as err:
        raise ValueError(f"{where}: {err}") from None
    return out


def _hash_split(name: str, val: float = 0.1, test: float = 0.1) -> str:
    """Deterministic split from the file name (for folders without one)."""
    u = int(hashlib.sha1(name.encode()).hexdigest()[:8], 16) / 0xFFFFFFFF
    return "test" if u < test else "val" if u < test + val else "train"


def bvh_files(folder: Union[str, os.PathLike]) -> List[Path]:
    """Every ``.bvh`` entry (any case: ``.BVH``, ``.Bvh``) below :obj:`folder`
    but folders, sorted: special files and broken links too, which the reader
    refuses in one line rather than the listing leaving them out unsaid.
    Linked folders are followed (a folder of links to datasets kept
    elsewhere), but not one that links back to a folder above it or to one
    the walk came through (a loop, also across two folders).
    Temporary files of satagraph's atomic writes (``.walk.bvh.<host>-<pid>.
    <random>.tmp.bvh``: a write in progress, or the start of one that
    ``kill -9`` cut short) are no motion files and are left out."""
    found: List[Path] = []
    came = {os.fspath(folder): frozenset({Path(folder).resolve()})}  # resolved, per folder
    for root, folders, names in os.walk(folder, followlinks=True):
        here, through = Path(root).resolve(), came.pop(root)
        kept = []
        for name in folders:
            target = Path(root, name).resolve()
            if not (here.is_relative_to(target) or target in through):  # no loop
                kept.append(name)
                came[os.path.join(root, name)] = through | {target}
        folders[:] = kept
        found += [Path(root, n) for n in names
                  if Path(n).suffix.lower() == ".bvh" and not is_temp_file(n)]
    return sorted(found)


def read_manifest(path: Union[str, os.PathLike], dataset: Optional[str] = None) -> List[MotionFile]:
    r"""Rows of a manifest TSV with at least the columns ``path`` (relative
    to the manifest's folder) and ``split``; ``dataset`` and ``skeleton``
    are used when present."""
    path = Path(path)
    with open(path, newline="", encoding=MANIFEST_ENCODING) as f:
        rows = list(csv.DictReader(f, delimiter="\t"))
    if not rows or "path" not in rows[0] or "split" not in rows[0]:
        raise ValueError(f"{path}: a manifest needs 'path' and 'split' columns")
    out, odd = [], Counter()
    for line, row in enumerate(rows, start=2):
        name = row.get("dataset") or dataset or path.parent.name
        if dataset and name != dataset:
            continue
        if row["split"] not in SPLITS + UNUSED_SPLITS:
            odd[row["split"]] += 1
        out.append(MotionFile(str(path.parent / row["path"]), name,
                              row.get("skeleton") or name, row["split"],
                              **_row_settings(row, f"{path}:{line}"),
                              skeleton_named=bool(row.get("skeleton")),
                              dataset_named=bool(row.get("dataset") or dataset)))
    if odd:
        warnings.warn(f"{path}: rows of splits other than {', '.join(SPLITS)} are not used: "
                      + ", ".join(f"{k!r} ({n})" for k, n in odd.most_common()), stacklevel=2)
    return out


def scan_folder(path: Union[str, os.PathLike], dataset: Optional[str] = None) -> List[MotionFile]:
    r"""BVH files under a folder. The nearest ``manifest.tsv`` in the folder
    or above it gives the splits of the files it lists below the folder
    (``satagraph zoo``'s is two folders above its files:
    ``zoo/biped/Zup-in``); otherwise files are split 80/10/10 by a hash of
    their name. Said in a warning: files a manifest leaves out (not read),
    a manifest above that lists none of the folder's files, and manifests
    in folders below that are not read (each such folder is a source of
    its own)."""
    path = Path(path)
    manifest = next((d / "manifest.tsv" for d in (path, *path.parents)
                     if (d / "manifest.tsv").is_file()), None)
    files = bvh_files(path)
    if manifest is not None:
        top, real = os.path.abspath(path), path.resolve()  # once, not per row
        rows = [r for r in read_manifest(manifest) if _listed_below(r.path, top, real)]
        if rows:
            _warn_unlisted(files, rows, manifest)
            return [replace(r, dataset=dataset or r.dataset,
                            dataset_named=r.dataset_named or dataset is not None)
                    for r in rows]
    if not files:
        raise FileNotFoundError(f"{path}: no .bvh files found")
    if manifest is not None:  # one above that lists none of these files
        warnings.warn(f"{path}: {manifest} above it lists none of its {len(files)} .bvh "
                      "file(s): they are split by name (80/10/10), with no rig settings of "
                      "that manifest", stacklevel=2)
    _warn_manifests_below(files, path)
    name = dataset or path.name
    return [MotionFile(str(f), name, name, _hash_split(f.name), skeleton_named=False,
                       dataset_named=dataset is not None) for f in files]


def _some(paths: Sequence[Path], shown: int = 3) -> str:
    """The first :obj:`shown` of :obj:`paths`, and how many more."""
    more = f", ... ({len(paths) - shown} more)" if len(paths) > shown else ""
    return ", ".join(str(p) for p in paths[:shown]) + more


def _warn_unlisted(files: Sequence[Path], rows: Sequence[MotionFile], manifest: Path) -> None:
    """Warn of the .bvh files below a folder that its manifest does not list
    (added after it was written): they are not read."""
    listed = {os.path.abspath(r.path) for r in rows} | {os.path.realpath(r.path) for r in rows}
    left = [f for f in files if os.path.abspath(f) not in listed
            and os.path.realpath(f) not in listed]
    if left:
        warnings.warn(f"{manifest}: {len(left)} .bvh file(s) below it are not in it and are "
                      f"not read: {_some(left)} (add rows for them, or remove the manifest "
                      "to split every file by name)", stacklevel=3)


def _warn_manifests_below(files: Sequence[Path], folder: Path) -> None:
    """Warn of the ``manifest.tsv`` files in folders below :obj:`folder`
    that hold its files: a folder is read with the nearest manifest at or
    above it, so theirs (splits, up axes, units) are not read."""
    top = Path(os.path.abspath(folder))
    dirs = {d for f in files for d in Path(os.path.abspath(f)).parents
            if d != top and d.is_relative_to(top)}
    below = sorted(d / "manifest.tsv" for d in dirs if (d / "manifest.tsv").is_file())
    if below:
        warnings.warn(f"{folder}: its files are split by name, and the {len(below)} "
                      f"manifest(s) below it are not read: {_some(below)}; pass each "
                      "manifest's folder as a source of its own (--data FOLDER once per "
                      "folder) for their splits and rig settings", stacklevel=3)


def _listed_below(file: str, folder: str, resolved: Path) -> bool:
    """Whether a manifest's :obj:`file` lies below the folder (absolute
    :obj:`folder`, :obj:`resolved` with its links resolved), by its path
    as listed (a link to a file kept elsewhere is the folder's file: checked
    resolved alone, a folder of links never read its own manifest) or with
    every link resolved."""
    return (Path(os.path.abspath(file)).is_relative_to(folder)
            or Path(file).resolve().is_relative_to(resolved))


def resolve_sources(sources: Union[str, Sequence]) -> List[MotionFile]:
    r"""Files from one or several sources: a folder, a manifest path,
    ``NAME=PATH`` (:func:`source_spec`: the dataset named), or a dict
    ``{"path": ..., "dataset": ..., "exclude": [...], "include": [...],
    "up_axis": ..., "units": ...}``. A manifest with a ``dataset`` key keeps
    only that dataset; ``include`` keeps only files whose name matches one of
    its shell patterns (e.g. ``["[0-9][0-9]_[0-9][0-9].bvh"]``: only the
    clips whose licence allows a use); ``up_axis`` and ``units`` (or
    ``scale``) apply to every file of the entry that has no setting of its
    own in its manifest. Two sources whose files a folder's name names
    alike are refused (:func:`refuse_shared_names`)."""
    if isinstance(sources, (str, os.PathLike)) or isinstance(sources, dict):
        sources = [sources]
    files: List[MotionFile] = []
    homes: Dict[str, Tuple[Path, str]] = {}
    for src in sources:
        spec = dict(src) if isinstance(src, dict) else source_spec(str(src))
        path = Path(os.path.expanduser(str(spec["path"])))
        if not path.exists():
            raise FileNotFoundError(_missing_source(path))
        if path.suffix.lower() == ".bvh":
            raise ValueError(f"{path}: a motion source is a folder of .bvh files or a "
                             "manifest (.tsv), not one .bvh file: put it in a folder")
        found = (read_manifest(path, spec.get("dataset")) if path.is_file()
                 else scan_folder(path, spec.get("dataset")))
        exclude = set(spec.get("exclude") or ())
        include = _patterns(spec.get("include"))
        settings = _row_settings(spec, f"data.sources entry {spec['path']}")
        kept = [_with_defaults(f, settings) for f in found
                if f.dataset not in exclude and f.split not in UNUSED_SPLITS
                and (include is None or _included(f.path, include))]
        refuse_shared_names(kept, path, homes)
        files += kept
    return files


_NAMED = re.compile(r"([A-Za-z0-9_.-]+)=(.+)")


def source_spec(text: str) -> Dict[str, str]:
    """A source given as text: ``NAME=PATH`` names its dataset
    (``--data dogs=path/to/bvh``, as ``{path: ..., dataset: dogs}`` in
    ``data.sources``), unless a file or folder of that whole name exists;
    any other text is a path."""
    named = _NAMED.fullmatch(text)
    if named is None or os.path.exists(os.path.expanduser(text)):
        return {"path": text}
    return {"path": named.group(2), "dataset": named.group(1)}


def refuse_shared_names(files: Sequence[MotionFile], path: Path,
                        homes: Dict[str, Tuple[Path, str]]) -> None:
    r"""Refuse a source whose dataset shares its name with another
    folder's, where either name is a folder's (two folders ``a/mocap`` and
    ``b/mocap``): their per-dataset figures, balanced-sampling groups and
    skeleton ids would merge unsaid. A name that both sources give
    (``dataset`` keys or manifest columns) merges them, as asked.

    Args:
        files (list[MotionFile]): The files of the source at :obj:`path`.
        path (Path): The source as given.
        homes (dict): ``{dataset: (folder, source)}`` of the sources before,
            updated: the folder a name was taken from (``None`` where a
            source gives it).

    Raises:
        ValueError: One line naming both sources and how to name them.
    """
    for name, named in {(f.dataset, f.dataset_named): None for f in files}:
        folder = None if named else _named_after(path, name)
        other = homes.setdefault(name, (folder, str(path)))
        if other[1] == str(path) or folder == other[0]:
            continue
        raise ValueError(f"data.sources: {other[1]} and {path} are both dataset {name!r} "
                         "(named after their folder), so their per-dataset figures, "
                         "balanced groups and skeleton ids would merge: name them, e.g. "
                         f"--data {name}_2={path} or {{path: {path}, dataset: {name}_2}} in "
                         "data.sources (the same dataset on both merges them)")


def _named_after(path: Path, name: str) -> Path:
    """The folder at or above :obj:`path` whose name a dataset took."""
    path = path.resolve()
    return next((p for p in (path, *path.parents) if p.name == name), path)


def _missing_source(path: Path) -> str:
    """The one line for a source that does not exist: where a relative one
    was looked for, and how to name one's own (:data:`SOURCES_HINT`)."""
    where = "" if path.is_absolute() else f" (looked for in {Path.cwd()})"
    return f"motion source not found: {path}{where}; {SOURCES_HINT}"


def _patterns(include) -> Optional[List[str]]:
    """``include`` of a source entry as a list of patterns (``None``: all)."""
    if include is None:
        return None
    return [include] if isinstance(include, str) else [str(p) for p in include]


def _included(path: str, patterns: Sequence[str]) -> bool:
    name = Path(path).name
    return any(fnmatch.fnmatchcase(name, p) for p in patterns)


def _with_defaults(f: MotionFile, settings: dict) -> MotionFile:
    """:obj:`f` with the entry's settings where it has none of its own."""
    missing = {k: v for k, v in settings.items() if getattr(f, k) is None}
    return replace(f, **missing) if missing else f


def select(files: Iterable[MotionFile], split: str) -> List[MotionFile]:
    """Files of one split."""
    return [f for f in files if f.split == split]


def spread_files(files: Sequence[MotionFile], limit: Optional[int]) -> List[MotionFile]:
    """At most :obj:`limit` of :obj:`files` (all for ``None``), taken
    in turn from each (dataset, skeleton) group, in the order the groups
    first appear and each group's own order: a limit keeps every source
    and body plan it has room for (the first ``limit`` files of a folder
    listed by name were one rig's, and of two sources the first's only).
    The files keep their order."""
    if limit is not None and limit < 1:
        raise ValueError(f"max_files={limit}: at least 1 is expected (None reads every file)")
    if limit is None or len(files) <= limit:
        return list(files)
    groups: Dict[Tuple[str, str], List[int]] = {}
    for i, f in enumerate(files):
        groups.setdefault((f.dataset, f.skeleton), []).append(i)
    taken: List[int] = []
    for rank in range(max(len(g) for g in groups.values())):
        taken += [g[rank] for g in groups.values() if rank < len(g)]
    return [files[i] for i in sorted(taken[:limit])]


def limit_note(split: str, chosen: Sequence[MotionFile], files: Sequence[MotionFile]) -> str:
    """``"train 4 of 18 (cmu 2 of 6, zoo 2 of 12)"``: what a file limit
    kept of one split, per dataset."""
    count = lambda fs, name: sum(1 for f in fs if f.dataset == name)  # noqa: E731
    names = list(dict.fromkeys(f.dataset for f in files))
    parts = ", ".join(f"{n} {count(chosen, n)} of {count(files, n)}" for n in names)
    return f"{split} {len(chosen)} of {len(files)} ({parts})"


def limit_files(files: Sequence[MotionFile], split: str, limit: Optional[int]
                ) -> Tuple[List[MotionFile], List[str]]:
    """One split's files under a file limit (:func:`spread_files`), and
    what the limit kept (:func:`limit_note`; no line when it kept them
    all)."""
    every = select(files, split)
    chosen = spread_files(every, limit)
    return chosen, [limit_note(split, chosen, every)] if len(chosen) < len(every) else []


def limit_warning(limit: Optional[int], notes: Sequence[str]) -> str:
    """The warning a data module gives when ``data.max_files`` left files
    out (:func:`limit_files`' notes)."""
    return (f"data.max_files={limit} reads " + "; ".join(notes)
            + " files (data.max_files=null reads them all)")
