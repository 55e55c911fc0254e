"""Writing the zoo: BVH files and a manifest (:func:`write_zoo`), in the
zoo's own dialect or in exporter dialects (:mod:`.dialects`)."""
from __future__ import annotations

import csv
import hashlib
import os
import zlib
from dataclasses import replace
from pathlib import Path
from typing import Dict, Iterable, List, Optional, Sequence, Union

import numpy as np

from satagraph.datasets.zoo.dialects import Dialect, DialectVariant, apply_dialect
from satagraph.datasets.zoo.motions import ClipFacts, generate_clip_with_facts
from satagraph.datasets.zoo.rigs import ZooRig, stance_of_bend
from satagraph.datasets.zoo.species import kinds_of, zoo_rigs
from satagraph.utils.files import atomic_write
from satagraph.motion import Motion

PathLike = Union[str, "os.PathLike[str]"]

MANIFEST_COLUMNS = ("path", "dataset", "skeleton", "species", "split", "fps",
                    "frames", "joints", "licence", "sha1", "up_axis", "scale",
                    "height_m", "rest_pose", "name_noise", "kind", "turn_deg",
                    "speed_start", "speed_end", "travel_deg")
LICENCE = "CC0 1.0"
#: What the manifest's dialect columns mean: ``up_axis`` the file's up axis,
#: ``scale`` metres per file unit, ``height_m`` the character's true height
#: in metres, ``rest_pose`` and ``name_noise`` the :class:`Dialect` options.
DIALECT_COLUMNS = ("up_axis", "scale", "height_m", "rest_pose", "name_noise")
#: What the clip does (:class:`~satagraph.datasets.zoo.motions.ClipFacts`, the
#: truth of its captions): ``kind``, ``turn_deg`` (positive: to the left),
#: ``speed_start`` and ``speed_end`` in leg lengths per second, ``travel_deg``
#: (direction of travel off the facing direction, positive: to the left).
MOTION_COLUMNS = ("kind", "turn_deg", "speed_start", "speed_end", "travel_deg")


# ---------------------------------------------------------------- writing
def _split(rig_index: int, rig_count: int, clip: int, clips: int) -> str:
    """The last skeleton of a species with 3+ variants is held out for
    testing; the last clip of the others (3+ clips) is for validation."""
    if rig_count >= 3 and rig_index == rig_count - 1:
        return "test"
    return "val" if clips >= 3 and clip == clips - 1 else "train"


def write_zoo(out_dir: PathLike, species: Optional[Sequence[str]] = None,
              clips: int = 4, seed: int = 0, fps: float = 30.0,
              frames: int = 120, dialects: Optional[Sequence[Dialect]] = None,
              kinds: Optional[Sequence[str]] = None,
              stance_bend: Optional[float] = None) -> List[Dict[str, str]]:
    r"""Write the zoo as BVH files under ``out_dir/<species>/`` and a
    ``manifest.tsv`` (columns :data:`MANIFEST_COLUMNS`, the layout of the
    shared data manifest plus the dialect truth :data:`DIALECT_COLUMNS`)
    in :obj:`out_dir`.

    Clip kinds cycle through ``CLIP_KINDS[species]`` (or the species' kinds
    among :obj:`kinds`); every file has its own
    seed derived from :obj:`seed`, so the zoo is deterministic. Each clip
    is written once per dialect, a non-canonical one under
    ``<species>/<dialect tag>/`` (e.g. ``crab/negZup-cm-apose/``).

    Args:
        out_dir (str or PathLike): Output folder (created).
        species (list[str], optional): Species (default: all).
        clips (int): Clips per skeleton.
        seed (int): Random seed.
        fps (float): Frames per second.
        frames (int): Frames per clip.
        dialects (list[Dialect], optional): Dialects every clip is written
            in (default: the zoo's own, +Y up in metres).
        kinds (list[str], optional): Clip kinds to write, of those each
            species can do (:data:`~satagraph.datasets.zoo.ALL_KINDS`: with
            the bipeds' gestures ``bow`` and ``wave``); every species must
            do one of them.
        stance_bend (float, optional): The knee bend (degrees) at which
            every rig stands (:attr:`~satagraph.datasets.zoo.rigs.ZooRig.stance`;
            default: the zoo's 36; a standing person's 3-15).

    Returns:
        list[dict]: The manifest rows.
    """
    if clips < 1 or frames < 2:
        raise ValueError("write_zoo: clips must be >= 1 and frames >= 2")
    dialects = list(dialects or [Dialect()])
    out = Path(out_dir)
    rigs = zoo_rigs(species, seed)
    if stance_bend is not None:
        if not 0.0 <= stance_bend < 90.0:  # also NaN
            raise ValueError(f"write_zoo: stance_bend is a knee bend in degrees, "
                             f"0 <= it < 90, got {stance_bend:g}")
        rigs = [replace(rig, stance=stance_of_bend(stance_bend)) for rig in rigs]
    drawn = kinds_of(dict.fromkeys(r.species for r in rigs), kinds, "write_zoo")
    counts = {r.species: sum(q.species == r.species for q in rigs) for r in rigs}
    seen: Dict[str, int] = {}
    rows = []
    for r, rig in enumerate(rigs):
        index = seen.setdefault(rig.species, 0)
        seen[rig.species] += 1
        for c in range(clips):
            split = _split(index, counts[rig.species], c, clips)
            rows += _write_clip(out, rig, drawn[rig.species], c, seed, fps, frames, split,
                                r, dialects)
    _write_manifest(out / "manifest.tsv", rows)
    return rows


def _write_clip(out: Path, rig: ZooRig, kinds: Sequence[str], c: int, seed: int,
                fps: float, frames: int, split: str, r: int,
                dialects: Sequence[Dialect]) -> List[Dict[str, str]]:
    kind, repeat = kinds[c % len(kinds)], c // len(kinds)
    clip_seed = int(np.random.default_rng([seed, r, c]).integers(2 ** 31))
    motion, facts = generate_clip_with_facts(rig, kind, frames, fps, clip_seed)
    stem = f"{rig.name}_{kind}{f'_{repeat + 1}' if repeat else ''}.bvh"
    return [_write_file(out, rig, motion, facts, stem, split, dialect, clip_seed + d)
            for d, dialect in enumerate(dialects)]


def _write_file(out: Path, rig: ZooRig, motion: Motion, facts: ClipFacts, stem: str,
                split: str, dialect: Dialect, seed: int) -> Dict[str, str]:
    """Write one clip in one dialect; its manifest row."""
    height = motion.height()
    if not dialect.canonical:
        motion, scale = apply_dialect(motion, dialect, seed)
    else:
        scale = 1.0
    rel = "/".join(p for p in (rig.species, dialect.tag, stem) if p)
    path = out / rel
    path.parent.mkdir(parents=True, exist_ok=True)
    from satagraph.io import write_bvh  # torch: loaded when writing

    write_bvh(motion, path)
    return {"path": rel, "dataset": "zoo", "skeleton": rig.name,
            "species": rig.species, "split": split, "fps": f"{motion.fps:.1f}",
            "frames": str(motion.num_frames), "joints": str(rig.skeleton.num_joints),
            "licence": LICENCE,
            "sha1": hashlib.sha1(path.read_bytes()).hexdigest(),
            "up_axis": dialect.up_axis, "scale": f"{scale:.10g}",
            "height_m": f"{height:.6f}", "rest_pose": dialect.rest,
            "name_noise": dialect.noise or "", "kind": facts.kind,
            "turn_deg": f"{facts.turn:+.1f}", "speed_start": f"{facts.speed_start:.3f}",
            "speed_end": f"{facts.speed_end:.3f}", "travel_deg": f"{facts.travel:+.1f}"}


def write_dialect_zoo(out_dir: PathLike, variants: Iterable[DialectVariant],
                      seed: int = 0, fps: float = 30.0, frames: int = 120
                      ) -> List[Dict[str, str]]:
    r"""Write one clip per :class:`DialectVariant` (e.g. from
    :func:`~satagraph.datasets.zoo.dialects.dialect_variants`) and a
    ``manifest.tsv``, laid out like :func:`write_zoo`. A rig's clip of one
    kind is the same motion in every dialect (its seed depends on
    :obj:`seed`, the rig and the kind only); every file is in the
    ``test`` split.

    Args:
        out_dir (str or PathLike): Output folder (created).
        variants (iterable of DialectVariant): What to write.
        seed (int): Random seed.
        fps (float): Frames per second.
        frames (int): Frames per clip.

    Returns:
        list[dict]: The manifest rows.
    """
    if frames < 2:
        raise ValueError("write_dialect_zoo: frames must be >= 2")
    out, rows = Path(out_dir), []
    for v, item in enumerate(variants):
        key = zlib.crc32(f"{item.rig.name}/{item.kind}".encode())
        clip_seed = int(np.random.default_rng([seed, key]).integers(2 ** 31))
        motion, facts = generate_clip_with_facts(item.rig, item.kind, frames, fps,
                                                 clip_seed)
        rows.append(_write_file(out, item.rig, motion, facts,
                                f"{item.rig.name}_{item.kind}.bvh", "test", item.dialect,
                                clip_seed + v))
    _write_manifest(out / "manifest.tsv", rows)
    return rows


def _write_manifest(path: Path, rows: List[Dict[str, str]]) -> None:
    """Write the manifest atomically."""
    path.parent.mkdir(parents=True, exist_ok=True)

    def write(f) -> None:
        writer = csv.DictWriter(f, MANIFEST_COLUMNS, delimiter="\t",
                                lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)

    atomic_write(path, write, newline="")
