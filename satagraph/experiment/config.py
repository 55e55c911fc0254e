"""Experiment configs: omegaconf YAML with dotted command-line overrides
(one merger, :func:`merge_overrides`), checked against the schema
(:mod:`satagraph.experiment.schema`) and turned into plain containers
before they reach the modules."""
from __future__ import annotations

import copy
import os
import site
import sys
import sysconfig
from pathlib import Path
from typing import Any, Dict, List, Mapping, Sequence, Tuple

from omegaconf import ListConfig, OmegaConf

from satagraph.experiment.schema import resolve_config

ROOT = Path(__file__).resolve().parents[2]
_SHARED = Path("share") / "satagraph" / "experiments"


def config_dirs(root: Path = ROOT) -> Tuple[Path, ...]:
    """Where named configs are looked up, first existing folder wins: the
    source checkout's ``experiments/`` (editable installs, the repository:
    a folder beside ``setup.cfg``, not any ``experiments`` an installed
    package puts into site-packages), then the copy a non-editable install
    ships as data files (``<data>/share/satagraph/experiments``, see
    ``setup.cfg``) under this environment's data path, its prefix, or the
    user base of a ``pip install --user``."""
    checkout = [root / "experiments"] if (root / "setup.cfg").is_file() else []
    bases = (sysconfig.get_paths()["data"], sys.prefix, site.USER_BASE or "")
    return tuple(dict.fromkeys(checkout + [Path(b) / _SHARED for b in bases if b]))


#: :func:`config_dirs` of this installation.
CONFIG_DIRS = config_dirs()


def experiments_dir() -> Path:
    """The folder of the named configs (see :data:`CONFIG_DIRS`).

    Raises:
        FileNotFoundError: None of them exists (one line naming them).
    """
    found = next((d for d in CONFIG_DIRS if d.is_dir()), None)
    if found is None:
        raise FileNotFoundError("the named configs are not installed: looked in "
                                + ", ".join(map(str, CONFIG_DIRS))
                                + "; give a config's path, or reinstall satagraph")
    return found


def config_path(name: str) -> Path:
    """A config file by path, or by name in ``experiments/`` (``tiny``,
    ``sata_vae.yaml``)."""
    path = Path(name)
    if path.is_file():
        return path
    folder = experiments_dir()
    for candidate in (folder / name, folder / f"{name}.yaml"):
        if candidate.is_file():
            return candidate
    known = ", ".join(sorted(p.stem for p in folder.glob("*.yaml")))
    raise FileNotFoundError(f"config {name!r} not found (a path, or one of: {known})")


def _load(path: Path, files: List[Path], chain: Tuple[Path, ...] = ()):
    """The config of :obj:`path` merged onto its ``defaults``; every file
    read is appended to :obj:`files`; :obj:`chain` holds the files that
    include it.

    Raises:
        ValueError: A file includes itself, is no mapping of sections, or
            ``defaults`` is not a list (one line naming the file).
    """
    chain = chain + (path,)
    if any(path.resolve() == p.resolve() for p in chain[:-1]):
        raise ValueError(f"{chain[0]}: defaults include themselves: "
                         + " -> ".join(map(str, chain)))
    files.append(path)
    try:
        cfg = OmegaConf.load(path)
    except Exception as err:  # yaml or omegaconf errors: one line naming the file
        detail = " ".join(str(err).split())[:200]
        raise ValueError(f"{path}: not a valid YAML config ({detail})") from None
    if isinstance(cfg, ListConfig):
        raise ValueError(f"{path}: a config is a mapping of sections (model:, data:, "
                         "trainer:, ...), not a list")
    bases = cfg.pop("defaults", []) or []
    if not isinstance(bases, (list, ListConfig)):
        raise ValueError(f"{path}: defaults: a list of configs is expected, e.g. "
                         f"defaults: [{bases}] (got {bases!r})")
    return OmegaConf.merge(*[_load(_base(path, str(b)), files, chain) for b in bases], cfg)


def _base(path: Path, name: str) -> Path:
    """A ``defaults`` entry of :obj:`path`: the file of that name, or of
    that name and ``.yaml``, relative to :obj:`path`'s folder
    (``[base]``, ``[base.yaml]``, ``[../common/base.yaml]``), else the named
    config (``defaults: [tiny]`` or ``[tiny.yaml]`` in one's own folder).

    Raises:
        FileNotFoundError: None of them (one line naming :obj:`path`).
    """
    for beside in (path.parent / name, path.parent / f"{name}.yaml"):
        if beside.is_file():
            return beside
    try:
        return config_path(name)
    except FileNotFoundError as err:
        raise FileNotFoundError(f"{path}: defaults: {err}") from None


def _stamp(path: Path) -> Tuple[str, int, int]:
    stat = path.stat()
    return str(path.resolve()), stat.st_mtime_ns, stat.st_size


#: Configs read so far: path -> (stamps of every file read, plain container).
_LOADED: Dict[str, Tuple[Tuple, Dict[str, Any]]] = {}


def _read(path: Path) -> Dict[str, Any]:
    """The config of :obj:`path` with its ``defaults`` merged in, as plain
    containers; read again only when one of its files changed (merging
    costs tens of milliseconds, and a test suite or sweep loads the same
    configs hundreds of times)."""
    key = str(path.resolve())
    hit = _LOADED.get(key)
    if hit is not None:
        try:
            if tuple(_stamp(Path(f[0])) for f in hit[0]) == hit[0]:
                return copy.deepcopy(hit[1])
        except OSError:
            pass
    files: List[Path] = []
    cfg = OmegaConf.to_container(_load(path, files))
    _LOADED[key] = (tuple(_stamp(f) for f in files), cfg)
    return copy.deepcopy(cfg)


def merge_overrides(cfg: Mapping[str, Any], overrides: Sequence[str] = (),
                    where: str = "the config") -> Dict[str, Any]:
    r"""The one override merger: :obj:`cfg` with ``key.sub=value``
    overrides applied in order (omegaconf's dot-list: nested keys, an item
    of a list by its index as in ``data.sources.0.scale=0.01``, YAML values
    such as ``[a, b]``, ``{k: v}``, ``null``, numbers), as plain containers
    with interpolations resolved.

    Raises:
        ValueError: An item is not ``key=value``, or omegaconf cannot apply
            it (one line naming :obj:`where` and the override).
    """
    for item in overrides:
        if "=" not in item:
            raise ValueError(f"override {item!r} is not of the form key=value")
    merged = OmegaConf.create(dict(cfg))
    for item in overrides:
        try:
            merged.merge_with_dotlist([item])
        except Exception as err:  # omegaconf: an index out of range, a key into a number
            raise ValueError(f"{where}: override {item}: cannot be applied "
                             f"({_one_line(err)})") from None
    try:
        out = OmegaConf.to_container(merged, resolve=True)
    except Exception as err:  # omegaconf: an interpolation
        raise ValueError(f"{where}: cannot apply the config and its overrides "
                         f"({_one_line(err)})") from None
    for item in overrides:
        _check_number(cfg, out, item.split("=", 1)[0].strip(), where)
    return out


def _one_line(err: Exception) -> str:
    """An omegaconf error's text on one line, cut at 200 characters."""
    return " ".join(str(err).split())[:200]


#: Config sections whose numbers take no text (:func:`_check_number`).
NUMBER_SECTIONS = ("optim", "loss", "model")


def _check_number(before: Mapping[str, Any], after: Mapping[str, Any], key: str,
                  where: str) -> None:
    """Refuse an override that puts text where the config has a number in
    a section of numbers (:data:`NUMBER_SECTIONS`: ``optim.lr=abc``),
    before anything fails on it far from the cause (``data`` takes units
    such as ``cm`` where a factor stood, ``trainer`` times as text)."""
    if key.split(".", 1)[0] not in NUMBER_SECTIONS:
        return
    old, new = before, after
    for part in key.split("."):
        if not isinstance(old, Mapping) or not isinstance(new, Mapping) or part not in old:
            return
        old, new = old[part], new.get(part)
    number = isinstance(old, (int, float)) and not isinstance(old, bool)
    if number and isinstance(new, str):
        raise ValueError(f"{where}: {key}={new}: a number is expected (the config has "
                         f"{old!r})")


def dotted_settings(value: Any, key: str = "") -> Dict[str, Any]:
    """A config section's settings by dotted name, as an override names them
    (``{"masked": {"heads": 4}}`` under ``"model"``: ``model.masked.heads``)."""
    if not isinstance(value, dict):
        return {key: value}
    flat: Dict[str, Any] = {}
    for k, v in value.items():
        flat.update(dotted_settings(v, f"{key}.{k}" if key else str(k)))
    return flat


def load_config(name: str, overrides: Sequence[str] = ()) -> Dict[str, Any]:
    r"""Load a YAML config (with ``defaults: [base, ...]`` inheritance: a
    file relative to the config's folder, else a named config of
    ``experiments/``), apply ``key.sub=value`` overrides
    (:func:`merge_overrides`) and check it against the schema, every default
    filled (:func:`~satagraph.experiment.schema.resolve_config`); ``name``
    defaults to the file's stem.

    Args:
        name (str): A config of ``experiments/`` by its stem (``"tiny"``) or
            the path of a YAML file.
        overrides (Sequence[str]): Dotted ``key.sub=value`` overrides, applied
            in order (``["data.batch_size=8", "optim.lr=1e-4"]``).

    Returns:
        dict: The whole config as plain Python values.

    Raises:
        FileNotFoundError: No such config (the message lists the known ones).
        ValueError: An override or a value the schema refuses, in one line.
    """
    path = config_path(name)
    cfg = merge_overrides(_read(path), overrides, str(path))
    if not cfg.get("name"):
        cfg["name"] = path.stem
    return resolve_config(cfg)


def expand_path(value: Any) -> str:
    """User and environment variables expanded."""
    return os.path.expandvars(os.path.expanduser(str(value)))  # output_dir=2024 reads as a number
