"""Writing the zoo: BVH files and a manifest (:func:`write_zoo`)."""
from __future__ import annotations

import csv
import hashlib
import os
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Union

import numpy as np

from satagraph.data.zoo.motions import generate_clip
from satagraph.data.zoo.rigs import ZooRig
from satagraph.data.zoo.species import CLIP_KINDS, zoo_rigs
from satagraph.io import write_bvh

PathLike = Union[str, "os.PathLike[str]"]

MANIFEST_COLUMNS = ("path", "dataset", "skeleton", "species", "split", "fps",
                    "frames", "joints", "licence", "sha1")
LICENCE = "CC0 1.0"


# ---------------------------------------------------------------- writing
def _split(rig_index: int, rig_count: int, clip: int, clips: int) -> str:
    """The last skeleton of a species with 3+ variants is held out for
    testing; the last clip of the others (3+ clips) is for validation."""
    if rig_count >= 3 and rig_index == rig_count - 1:
        return "test"
    return "val" if clips >= 3 and clip == clips - 1 else "train"


def write_zoo(out_dir: PathLike, species: Optional[Sequence[str]] = None,
              clips: int = 4, seed: int = 0, fps: float = 30.0,
              frames: int = 120) -> List[Dict[str, str]]:
    r"""Write the zoo as BVH files under ``out_dir/<species>/`` and a
    ``manifest.tsv`` (columns :data:`MANIFEST_COLUMNS`, the layout of the
    shared data manifest) in :obj:`out_dir`.

    Clip kinds cycle through ``CLIP_KINDS[species]``; every file has its own
    seed derived from :obj:`seed`, so the zoo is deterministic.

    Args:
        out_dir (str or PathLike): Output folder (created).
        species (list[str], optional): Species (default: all).
        clips (int): Clips per skeleton.
        seed (int): Random seed.
        fps (float): Frames per second.
        frames (int): Frames per clip.

    Returns:
        list[dict]: The manifest rows.
    """
    if clips < 1 or frames < 2:
        raise ValueError("write_zoo: clips must be >= 1 and frames >= 2")
    out = Path(out_dir)
    rigs = zoo_rigs(species, seed)
    counts = {r.species: sum(q.species == r.species for q in rigs) for r in rigs}
    seen: Dict[str, int] = {}
    rows = []
    for r, rig in enumerate(rigs):
        index = seen.setdefault(rig.species, 0)
        seen[rig.species] += 1
        for c in range(clips):
            rows.append(_write_clip(out, rig, c, seed, fps, frames,
                                    _split(index, counts[rig.species], c, clips),
                                    r))
    _write_manifest(out / "manifest.tsv", rows)
    return rows


def _write_clip(out: Path, rig: ZooRig, c: int, seed: int, fps: float,
                frames: int, split: str, r: int) -> Dict[str, str]:
    kinds = CLIP_KINDS[rig.species]
    kind, repeat = kinds[c % len(kinds)], c // len(kinds)
    clip_seed = int(np.random.default_rng([seed, r, c]).integers(2 ** 31))
    motion = generate_clip(rig, kind, frames, fps, clip_seed)
    rel = f"{rig.species}/{rig.name}_{kind}{f'_{repeat + 1}' if repeat else ''}.bvh"
    path = out / rel
    path.parent.mkdir(parents=True, exist_ok=True)
    write_bvh(motion, path)
    return {"path": rel, "dataset": "zoo", "skeleton": rig.name,
            "species": rig.species, "split": split, "fps": f"{fps:.1f}",
            "frames": str(frames), "joints": str(rig.skeleton.num_joints),
            "licence": LICENCE,
            "sha1": hashlib.sha1(path.read_bytes()).hexdigest()}


def _write_manifest(path: Path, rows: List[Dict[str, str]]) -> None:
    """Write the manifest atomically."""
    tmp = path.with_name(f".{path.name}.tmp")
    with open(tmp, "w", newline="") as f:
        writer = csv.DictWriter(f, MANIFEST_COLUMNS, delimiter="\t",
                                lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
    os.replace(tmp, path)
