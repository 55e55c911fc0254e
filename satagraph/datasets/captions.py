r"""Captions of clips: one entry point for every source of motion.

:func:`captions_for` gives the captions of a clip, named by its path, a
manifest row, a :class:`~satagraph.datasets.sources.MotionFile`, an
endless-zoo :class:`~satagraph.datasets.zoo.endless.ZooSample` or the zoo's
:class:`~satagraph.datasets.zoo.ClipFacts`:

1. user captions from the clip's sidecar files (``clip.txt`` in HumanML3D
   lines, ``clip.json``; see :mod:`.sidecar`), then
2. templated phrasings from what the dataset knows (:data:`CAPTIONERS`):
   the file name for ``bandai``, ``cmu`` and ``ccbase``
   (:mod:`.mocap_captions`), the generator's facts for ``zoo``
   (:mod:`.zoo_captions`). ``dog`` (and the parser ``fixtures``) have none,
   by design.

:func:`captioned_clips` lists the captioned clips of a manifest with their
splits (the manifest's splits, never re-split).

Example::

    captions_for("../shared/data/bandai/dataset-1_walk_not-confident_001.bvh",
                 count=3, seed=0)
    # [Caption(text='someone walks forward without confidence', ...), ...]
    clips = captioned_clips("../shared/data/manifest.tsv", split="train")
"""
from __future__ import annotations

import csv
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Dict, List, Mapping, Optional, Union

from satagraph.datasets.sources import MANIFEST_ENCODING, MotionFile
from satagraph.datasets.zoo import ClipFacts
from satagraph.datasets.zoo.endless import ZooSample
from satagraph.datasets.caption import Caption, CaptionError, choose
from satagraph.datasets.mocap_captions import (bandai_phrasings, ccbase_phrasings,
                                               cmu_phrasings)
from satagraph.datasets.sidecar import read_sidecars
from satagraph.datasets.zoo_captions import ZooClip, zoo_clip_of_row, zoo_phrasings

PathLike = Union[str, "os.PathLike[str]"]
ClipLike = Union[PathLike, Mapping[str, str], MotionFile, ZooSample, ClipFacts]

#: Dataset -> phrasings of a clip from its file stem (``None``: the dataset
#: has no captions, by design). ``zoo`` clips are captioned from their facts.
CAPTIONERS: Dict[str, Optional[Callable[[str], Optional[List[str]]]]] = {
    "bandai": bandai_phrasings,
    "cmu": cmu_phrasings,
    "ccbase": ccbase_phrasings,
    "dog": None,
    "fixtures": None,
}
#: File-name patterns that tell a clip's dataset when nothing else does.
DATASET_PATTERNS = (
    ("bandai", re.compile(r"^dataset-1_")),
    ("ccbase", re.compile(r"^\d{3}_\d\d$")),
    ("cmu", re.compile(r"^(\d\d_\d\d|[a-z]+_\d\d_\d+)$")),
    ("dog", re.compile(r"^D1_")),
    ("zoo", re.compile(r"^zoo\d+-")),
)


@dataclass(frozen=True)
class CaptionedClip:
    """A clip of a manifest with its split and captions."""

    path: str
    dataset: str
    split: str
    captions: List[Caption]


def infer_dataset(path: PathLike) -> Optional[str]:
    """The dataset of a clip from its folder (a known dataset name) or its
    file name (:data:`DATASET_PATTERNS`); ``None`` when unknown."""
    path = Path(path)
    if path.parent.name in CAPTIONERS or path.parent.name == "zoo":
        return path.parent.name
    return next((name for name, pattern in DATASET_PATTERNS
                 if pattern.search(path.stem)), None)


def _generated(clip: ClipLike, dataset: Optional[str]) -> List[str]:
    """Templated phrasings of a clip (none when nothing is known)."""
    if isinstance(clip, ClipFacts):
        return zoo_phrasings(ZooClip.of(clip))
    if isinstance(clip, ZooSample):
        facts = clip.facts
        return zoo_phrasings(ZooClip.of(facts) if facts is not None
                             else ZooClip(clip.species, clip.kind))
    if dataset == "zoo":
        zoo = zoo_clip_of_row(clip if isinstance(clip, Mapping) else {"path": _path_of(clip)})
        return zoo_phrasings(zoo) if zoo is not None else []
    captioner = CAPTIONERS.get(dataset or "")
    if captioner is None:
        return []
    return captioner(Path(_path_of(clip)).stem) or []


def _path_of(clip: ClipLike) -> str:
    if isinstance(clip, MotionFile):
        return clip.path
    if isinstance(clip, Mapping):
        return str(clip.get("path", ""))
    if isinstance(clip, (ZooSample, ClipFacts)):
        return ""
    return os.fspath(clip)


def _key_of(clip: ClipLike) -> str:
    """What seeds a clip's choice of phrasings."""
    if isinstance(clip, ZooSample):
        return f"{clip.plan}/{clip.kind}/{clip.motion.source}"
    if isinstance(clip, ClipFacts):
        return f"{clip.species}/{clip.kind}/{clip.turn:.3f}/{clip.speed_start:.3f}"
    return Path(_path_of(clip)).name


def _dataset_of(clip: ClipLike, dataset: Optional[str]) -> Optional[str]:
    if dataset is not None:
        return dataset
    if isinstance(clip, (ZooSample, ClipFacts)):
        return "zoo"
    if isinstance(clip, MotionFile) and clip.dataset in CAPTIONERS:
        return clip.dataset
    if isinstance(clip, Mapping) and clip.get("dataset"):
        return str(clip["dataset"])
    path = _path_of(clip)
    return infer_dataset(path) if path else None


def captions_for(clip: ClipLike, dataset: Optional[str] = None,
                 count: Optional[int] = None, seed: int = 0, user: bool = True,
                 generated: bool = True, root: Optional[PathLike] = None
                 ) -> List[Caption]:
    r"""The captions of a clip.

    Args:
        clip: A clip path, a manifest row (``path``, ``dataset``, ... as in
            ``manifest.tsv``; zoo rows with their ``species``/``kind``/
            ``turn_deg``/``speed_*`` columns), a
            :class:`~satagraph.datasets.sources.MotionFile`, an endless-zoo
            :class:`~satagraph.datasets.zoo.endless.ZooSample` or a
            :class:`~satagraph.datasets.zoo.ClipFacts`.
        dataset: The dataset (default: the row's or file's, else inferred
            from the path, see :func:`infer_dataset`).
        count: Templated phrasings to keep (a seeded choice, see
            :func:`~satagraph.datasets.caption.choose`); ``None`` for all.
            User captions are always all kept.
        seed: Seed of the choice.
        user: Read the sidecar files (``clip.txt``, ``clip.json``).
        generated: Add the templated phrasings.
        root: Folder a manifest row's relative path is relative to (for its
            sidecars).

    Returns:
        list[Caption]: User captions first, then templated ones
        (``source`` = dataset, whole clip). Empty for datasets without
        captions (``dog``) and clips nothing is known about.

    Raises:
        CaptionError: A malformed sidecar (file and line in the message).
    """
    dataset = _dataset_of(clip, dataset)
    out: List[Caption] = []
    path = _path_of(clip)
    if user and path:
        out += read_sidecars(Path(root) / path if root is not None else Path(path))
    if generated:
        source = "zoo" if isinstance(clip, (ZooSample, ClipFacts)) else dataset
        texts = choose(_generated(clip, dataset), _key_of(clip), seed, count)
        out += [Caption(text, 0.0, None, str(source)) for text in texts]
    return out


def read_manifest_rows(manifest: PathLike) -> List[Dict[str, str]]:
    """The rows of a manifest TSV (``path`` and ``split`` columns needed)."""
    path = Path(manifest)
    with open(path, newline="", encoding=MANIFEST_ENCODING) as f:
        rows = list(csv.DictReader(f, delimiter="\t"))
    if rows and ("path" not in rows[0] or "split" not in rows[0]):
        raise CaptionError(f"{path}: a manifest needs 'path' and 'split' columns")
    return rows


def captioned_clips(manifest: PathLike, split: Optional[str] = None,
                    count: Optional[int] = None, seed: int = 0,
                    user: bool = True) -> List[CaptionedClip]:
    """The clips of a manifest that have captions, with their split.

    Args:
        manifest: A ``manifest.tsv`` (the shared data's or a zoo's).
        split: Keep only this split (``"train"``, ``"val"``, ``"test"``).
        count: Templated phrasings per clip (see :func:`captions_for`).
        seed: Seed of the choice.
        user: Read sidecar files.

    Returns:
        list[CaptionedClip]: In manifest order; ``path`` is the clip's full
        path (the manifest's folder joined with its row's path).
    """
    root = Path(manifest).parent
    out = []
    for row in read_manifest_rows(manifest):
        if split is not None and row["split"] != split:
            continue
        dataset = row.get("dataset") or infer_dataset(row["path"]) or ""
        captions = captions_for(row, dataset, count, seed, user, root=root)
        if captions:
            out.append(CaptionedClip(str(root / row["path"]), dataset, row["split"],
                                     captions))
    return out


__all__ = ["CAPTIONERS", "DATASET_PATTERNS", "CaptionedClip", "infer_dataset",
           "captions_for", "captioned_clips", "read_manifest_rows"]
