r"""The endless zoo as a data source: windows generated on the fly.

A ``data.sources`` entry ``{zoo: endless, ...}`` (see :func:`zoo_entry`)
gives, per split, an :class:`EndlessZooDataset`: training windows are new
rigs and clips drawn from ``(seed, epoch, index)``
(:class:`~satagraph.datasets.zoo.endless.EndlessZoo`), featurised like real
files; validation and test windows come from held-out seeds (fixed across
epochs), together with the held-out body plans (dataset
``<name>-holdout``). :class:`MixedDataset` puts file and zoo windows in one
training set.
"""
from __future__ import annotations

import bisect
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple

import numpy as np
import torch
from torch.utils.data import Dataset

from satagraph.transforms.canonical import canonicalize
from satagraph.data.clip import MotionClip
from satagraph.data.dataset import (DEFAULT_PREPROCESSING, WindowKey, _per_skeleton,
                                    _semantic_once, shown_as, feature_options)
from satagraph.data.features import MotionFeatures, motion_to_features
from satagraph.semantics.evidence import evidence_from_features
from satagraph.semantics.limbs import limb_end_index
from satagraph.data.validate import check_features
from satagraph.datasets.zoo.endless import EndlessZoo, ZooSample

#: Keys of a ``{zoo: endless}`` source entry and their defaults.
ZOO_ENTRY_DEFAULTS: Dict[str, Any] = {
    "zoo": "endless", "dataset": "zoo-endless", "species": None,
    "holdout_species": [], "windows_per_epoch": 1024, "val_windows": 64,
    "test_windows": 64, "fit_windows": 128, "rests": None, "noise": 0.3, "seed": None,
    "kinds": None, "stance_bend": None}


def endless_zoo(spec: Mapping[str, Any], fps: float, seed: int) -> EndlessZoo:
    """The :class:`~satagraph.datasets.zoo.endless.EndlessZoo` of a zoo
    entry (:func:`zoo_entry`; its ``seed`` when set, else :obj:`seed`)."""
    options = {"rests": spec["rests"]} if spec.get("rests") else {}
    return EndlessZoo(spec["species"], spec["holdout_species"], noise=spec["noise"], fps=fps,
                      seed=seed if spec["seed"] is None else spec["seed"],
                      kinds=spec["kinds"], stance_bend=spec["stance_bend"], **options)


def is_zoo_entry(source: Any) -> bool:
    """Whether a ``data.sources`` entry is a zoo source (``{zoo: ...}``)."""
    return isinstance(source, Mapping) and "zoo" in source


def zoo_entry(source: Mapping[str, Any]) -> Dict[str, Any]:
    """A zoo source entry with its defaults, checked. Its keys
    (:data:`ZOO_ENTRY_DEFAULTS`) are :class:`~satagraph.datasets.zoo.endless.EndlessZoo`'s
    (``species``, ``holdout_species``, ``rests``, ``noise``, ``seed``,
    ``kinds``, ``stance_bend``: e.g. ``{biped: [0, 36]}``) and the
    dataset's (``dataset``, ``windows_per_epoch``, ``val_windows``,
    ``test_windows``, ``fit_windows``).

    Raises:
        ValueError: Unknown keys or an unknown ``zoo`` kind.
    """
    spec = dict(source)
    unknown = sorted(set(spec) - set(ZOO_ENTRY_DEFAULTS))
    if unknown:
        raise ValueError(f"data.sources zoo entry: unknown keys {unknown}; known: "
                         f"{sorted(ZOO_ENTRY_DEFAULTS)}")
    if spec.get("zoo") != "endless":
        raise ValueError(f"data.sources: unknown zoo {spec.get('zoo')!r} (use endless)")
    return dict(ZOO_ENTRY_DEFAULTS, **spec)


class EndlessZooDataset(Dataset):
    r"""Windows of an :class:`~satagraph.datasets.zoo.endless.EndlessZoo`.

    The key ``(epoch, index)`` (what a keyed
    :class:`~satagraph.data.sampler.ResumableSampler` yields) draws a new
    sample every epoch; a plain index is epoch 0 (evaluation: a fixed set).
    Each window is generated with one frame before it, so that the
    velocities of its first frame are those of the motion.

    Args:
        zoo (EndlessZoo): The sampler of rigs and clips.
        windows (int): Windows per epoch (the dataset's length).
        window (int): Frames per window.
        semantic (Callable, optional): The semantic embedder (see
            :class:`~satagraph.data.dataset.MotionDataset`).
        stream (str): ``"train"``, ``"val"`` or ``"test"`` seeds.
        holdout (bool): Draw the held-out body plans.
        preprocessing (dict, optional): Contact thresholds and fps (see
            :data:`~satagraph.data.dataset.DEFAULT_PREPROCESSING`).
        dataset (str): Dataset name of the windows (``meta["dataset"]``).
    """

    #: Keyed by ``(epoch, index)`` in training.
    keyed = True
    augment = None

    def __init__(self, zoo: EndlessZoo, windows: int, window: int = 64,
                 semantic: Optional[Callable] = None, stream: str = "train",
                 holdout: bool = False, preprocessing: Optional[Mapping] = None,
                 dataset: str = "zoo-endless") -> None:
        self.zoo, self.windows, self.window = zoo, int(windows), int(window)
        self.semantic_fn, self.stream, self.holdout = semantic, stream, holdout
        self.config = dict(DEFAULT_PREPROCESSING, **(preprocessing or {}))
        self.dataset = dataset
        self.files: List[Any] = []
        self._semantic: Dict[Tuple, torch.Tensor] = {}
        self._limbs: Dict[Tuple, Tuple[int, ...]] = {}

    def __len__(self) -> int:
        return self.windows

    def group(self, idx: int) -> str:
        """``dataset/species`` of a window (known without drawing it)."""
        return f"{self.dataset}/{self.zoo.species_of(idx, self.holdout)}"

    def features(self, epoch: int, index: int) -> Tuple[MotionFeatures, ZooSample]:
        """Features (``window + 1`` frames) and sample of a key.

        Shapes:
            features: ``window + 1`` frames of the sample's skeleton.
        """
        sample = self.zoo.sample(epoch, index, self.window + 1, self.stream, self.holdout)
        motion = canonicalize(sample.motion, fps=self.config["fps"], up_axis="+Y",
                              unit_scale=1.0, floor=self.config["floor"],
                              replace_bind=False)  # procedural: no bind frame
        feats = motion_to_features(shown_as(motion, self.config), **feature_options(self.config))
        check_features(feats, f"<endless zoo {self.stream} {epoch} {index}>")
        return feats, sample

    def fit_features(self, count: int) -> List[MotionFeatures]:
        """Features of the first :obj:`count` windows of epoch 0 (for the
        normaliser)."""
        return [self.features(0, i)[0] for i in range(min(count, max(self.windows, 1)))]

    def __getitem__(self, key: WindowKey) -> MotionClip:
        epoch, idx = key if isinstance(key, tuple) else (0, key)
        feats, sample = self.features(int(epoch), int(idx))
        evidence = evidence_from_features(feats)
        limbs = _per_skeleton(self._limbs, feats.skeleton,
                              lambda skeleton: tuple(limb_end_index(skeleton, evidence)),
                              evidence)
        meta = {"path": f"<endless zoo {self.stream} {epoch} {idx}: {sample.plan} "
                        f"{sample.kind}>",
                "dataset": self.dataset, "skeleton": sample.plan,
                "species": sample.species, "limb_ends": limbs}
        semantic = _semantic_once(self._semantic, self.semantic_fn, feats.skeleton, evidence)
        return feats.to_clip(1, None, semantic, meta)


class MixedDataset(Dataset):
    r"""Several window datasets as one; a key ``(epoch, index)`` goes to
    the part holding :obj:`index`, keyed for keyed parts (augmented files,
    endless zoo) and as a plain index for the others.

    Args:
        parts (list[Dataset]): Datasets with ``group(i)``.
    """

    def __init__(self, parts: Sequence[Dataset]) -> None:
        self.parts = [p for p in parts if len(p)]
        self.offsets = list(np.cumsum([0] + [len(p) for p in self.parts]).tolist())
        self.keyed = any(_keyed(p) for p in self.parts)
        self.augment = None

    @property
    def files(self) -> List[Any]:
        """The files of the file parts."""
        return [f for p in self.parts for f in getattr(p, "files", [])]

    def __len__(self) -> int:
        return self.offsets[-1]

    def _locate(self, idx: int) -> Tuple[Dataset, int]:
        if not 0 <= idx < len(self):
            raise IndexError(f"window {idx} of {len(self)}")
        k = bisect.bisect_right(self.offsets, idx) - 1
        return self.parts[k], idx - self.offsets[k]

    def group(self, idx: int) -> str:
        part, local = self._locate(idx)
        return part.group(local)

    def __getitem__(self, key: WindowKey) -> MotionClip:
        epoch, idx = key if isinstance(key, tuple) else (None, key)
        part, local = self._locate(int(idx))
        if epoch is not None and _keyed(part):
            return part[(epoch, local)]
        return part[local]


def _keyed(ds: Dataset) -> bool:
    """Whether a dataset wants ``(epoch, index)`` keys."""
    return bool(getattr(ds, "keyed", getattr(ds, "augment", None) is not None))


def zoo_datasets(spec: Mapping[str, Any], split: str, window: int,
                 semantic: Optional[Callable], preprocessing: Optional[Mapping],
                 seed: int) -> List[EndlessZooDataset]:
    """The zoo datasets of one split of a zoo entry (:func:`zoo_entry`):
    training windows of the training plans; validation and test windows of
    held-out seeds, of the training plans and of the held-out plans
    (dataset ``<name>-holdout``)."""
    config = dict(DEFAULT_PREPROCESSING, **(preprocessing or {}))
    zoo = endless_zoo(spec, config["fps"], seed)
    name = spec["dataset"]
    if split == "train":
        return [EndlessZooDataset(zoo, spec["windows_per_epoch"], window, semantic,
                                  "train", False, config, name)]
    count = spec[f"{split}_windows"]
    out = [EndlessZooDataset(zoo, count, window, semantic, split, False, config, name)]
    if zoo.holdout_plans:
        out.append(EndlessZooDataset(zoo, count, window, semantic, split, True, config,
                                     f"{name}-holdout"))
    return out


__all__ = ["ZOO_ENTRY_DEFAULTS", "endless_zoo", "is_zoo_entry", "zoo_entry", "EndlessZooDataset",
           "MixedDataset", "zoo_datasets"]
