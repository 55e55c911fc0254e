"""Experiment configs: omegaconf YAML with dotted command-line overrides,
turned into plain containers before they reach the modules."""
from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Any, Dict, Sequence

from omegaconf import OmegaConf

ROOT = Path(__file__).resolve().parents[2]
#: Where named configs are looked up, first existing folder wins: the
#: source checkout's ``experiments/`` (editable installs, the repository),
#: then the copy a non-editable install ships as data files
#: (``<prefix>/share/satagraph/experiments``, see ``setup.cfg``).
CONFIG_DIRS = (ROOT / "experiments",
               Path(sys.prefix) / "share" / "satagraph" / "experiments")


def experiments_dir() -> Path:
    """The folder of the named configs (see :data:`CONFIG_DIRS`)."""
    return next((d for d in CONFIG_DIRS if d.is_dir()), CONFIG_DIRS[0])


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


def _load(path: Path):
    try:
        cfg = OmegaConf.load(path)
    except Exception as err:  # yaml or omegaconf errors: one line naming the file
        detail = " ".join(str(err).split())[:200]
        raise ValueError(f"{path}: not a valid YAML config ({detail})") from None
    bases = cfg.pop("defaults", []) or []
    return OmegaConf.merge(*[_load(path.parent / f"{b}.yaml") for b in bases], cfg)


def load_config(name: str, overrides: Sequence[str] = ()) -> Dict[str, Any]:
    r"""Load a YAML config (with ``defaults: [base, ...]`` inheritance from
    the same folder) and apply ``key.sub=value`` overrides."""
    path = config_path(name)
    for item in overrides:
        if "=" not in item:
            raise ValueError(f"override {item!r} is not of the form key=value")
    try:
        merged = OmegaConf.merge(_load(path), OmegaConf.from_dotlist(list(overrides)))
        out = OmegaConf.to_container(merged, resolve=True)
    except ValueError:
        raise
    except Exception as err:  # omegaconf: bad override or interpolation
        detail = " ".join(str(err).split())[:200]
        raise ValueError(f"{path}: cannot apply the config and its overrides "
                         f"({detail})") from None
    if not out.get("name"):
        out["name"] = path.stem
    return out


def expand_path(value: str) -> str:
    """User and environment variables expanded."""
    return os.path.expandvars(os.path.expanduser(value))
