"""Lightning data module: one or several motion datasets trained jointly."""
from __future__ import annotations

import warnings
from collections import Counter
from typing import (Any, Callable, Dict, List, Mapping, Optional, Sequence, Set, Tuple,
                    Union)

import lightning as L
import torch
from torch.utils.data import DataLoader

from satagraph.data.collate import collate_clips
from satagraph.data.dataset import (ON_ERROR, MotionDataset, WindowAugment, dataset_error,
                                    rig_warnings_capped, try_load_features)
from satagraph.data.endless import (MixedDataset, _keyed, is_zoo_entry, zoo_datasets,
                                    zoo_entry)
from satagraph.data.sampler import ResumableSampler
from satagraph.data.normalizer import ROOT_UNITS, FeatureNormalizer
from satagraph.data.pairing import PartnerCollate
from satagraph.data.window_transform import TransformedCollate, window_transform
from satagraph.datasets.sources import (SOURCES_HINT, SPLITS, limit_files, limit_warning,
                                        resolve_sources)


class SemanticEmbedder:
    r"""A picklable function ``(skeleton, evidence=None) -> [J, D_t]``: a
    dataset holds one, and DataLoader workers started by ``spawn`` (the
    default on macOS and Windows) receive it pickled, which a closure
    cannot be.

    Args:
        encoder (TextEncoder): The text encoder.
        cache_dir (str, optional): Embedding cache directory.
        dictionary (str, optional): Raw name -> description overrides.
    """

    def __init__(self, encoder: Any, cache_dir: Optional[str] = None,
                 dictionary: Optional[str] = None) -> None:
        self.encoder, self.cache_dir, self.dictionary = encoder, cache_dir, dictionary

    def __call__(self, skeleton: Any, evidence: Any = None) -> torch.Tensor:
        from satagraph.semantics import embed_skeleton
        kwargs = {"dictionary": self.dictionary} if self.dictionary else {}
        return embed_skeleton(skeleton, encoder=self.encoder, cache_dir=self.cache_dir,
                              evidence=evidence, **kwargs)


def semantic_embedder(encoder: Optional[str] = "offline",
                      cache_dir: Optional[str] = None,
                      dictionary: Optional[str] = None) -> Optional[SemanticEmbedder]:
    r"""A function ``(skeleton, evidence=None) -> [J, D_t]`` from the
    semantic tag pipeline: ``"offline"`` (default, no weights),
    ``"t5:/path/to/t5"`` for a local T5, any other spec of
    :func:`~satagraph.semantics.build_text_encoder`, or
    ``None``/``"none"`` for no semantic features. ``evidence`` (a
    :class:`~satagraph.semantics.JointEvidence` of the motion, see
    :func:`~satagraph.semantics.evidence_from_features`) lets the rules
    read legs, wings and leg pairs from what the body does."""
    if encoder in (None, "none", ""):
        return None
    from satagraph.semantics import build_text_encoder
    return SemanticEmbedder(build_text_encoder(encoder), cache_dir, dictionary)


def window_loader(ds, batch_size: int, seed: int, shuffle: bool, balanced: bool,
                  num_workers: int = 0, collate: Callable = collate_clips,
                  resume: Optional[Callable[[ResumableSampler], None]] = None) -> DataLoader:
    """A loader of windows: shuffled by a :class:`ResumableSampler` (every
    ``ds.group`` drawn equally often when :obj:`balanced`; :obj:`resume`
    may move it to where a resumed run stopped), else in order."""
    sampler = None
    if shuffle:
        weights = None
        if balanced:
            groups = [ds.group(i) for i in range(len(ds))]
            counts = Counter(groups)
            weights = [1.0 / counts[g] for g in groups]
        sampler = ResumableSampler(len(ds), weights, seed, keys=_keyed(ds))
        if resume is not None:
            resume(sampler)
    # a generator of its own: iterating never draws from the global state
    gen = torch.Generator().manual_seed(seed)
    return DataLoader(ds, batch_size=batch_size, sampler=sampler, collate_fn=collate,
                      num_workers=num_workers, persistent_workers=num_workers > 0,
                      generator=gen)


def dataset_names(ds) -> Optional[Set[str]]:
    """The datasets of a split's windows (their ``meta["dataset"]``): its
    files' and its endless zoos' (the parts of a
    :class:`~satagraph.data.endless.MixedDataset`); ``None`` where a part
    tells neither (a data module of one's own)."""
    names: Set[str] = set()
    for part in getattr(ds, "parts", [ds]):
        own = getattr(part, "dataset", None)
        if not isinstance(own, str) and not hasattr(part, "files"):
            return None
        names |= {own} if isinstance(own, str) else {f.dataset for f in part.files}
    return names


def _warn_unvalidated(train, val) -> None:
    """Say which datasets have training windows and no validation window:
    no ``val/<dataset>/...`` figure is logged for them."""
    names = dataset_names(train)
    if names is None:  # a data module of one's own: its datasets tell no names
        return
    missing = sorted(names - (dataset_names(val) or set()))
    if missing:
        warnings.warn(f"no validation windows of {', '.join(map(repr, missing))}: none of "
                      "its files is in the 'val' split, so no val/<dataset>/... figures are "
                      "logged for it", stacklevel=3)


class WindowDataModule(L.LightningDataModule):
    """The split loaders of a data module of windows: training shuffled,
    validation and test in order (``trainer.predict`` reads the test split,
    in order); subclasses build them in :meth:`_loader`."""

    def _loader(self, split: str, shuffle: bool) -> DataLoader:
        raise NotImplementedError

    def _resume(self, sampler: ResumableSampler) -> None:
        """Start the sampler where a resumed run stopped: the position a
        :class:`~satagraph.lightning.reliability.ResumeCheckpoint` of the
        trainer restored (epoch, batches done, whether the epoch was done)."""
        trainer = getattr(self, "trainer", None)
        for callback in getattr(trainer, "callbacks", None) or []:
            position = getattr(callback, "resume_position", None)
            if position is not None and not position["epoch_done"]:
                sampler.resume(position["epoch"], position["batches"] * self.batch_size)

    def train_dataloader(self) -> DataLoader:
        return self._loader("train", True)

    def val_dataloader(self) -> DataLoader:
        return self._loader("val", False)

    def test_dataloader(self) -> DataLoader:
        return self._loader("test", False)

    def predict_dataloader(self) -> DataLoader:
        return self._loader("test", False)


class MotionDataModule(WindowDataModule):
    r"""Windows of motion from one or several BVH folders or manifests.

    Clips of different skeletons share a batch without padding (see
    :func:`~satagraph.data.collate_clips`). Normalisation statistics come
    from the training split only and are handed to the model
    (:attr:`normalizer`), which keeps them in its checkpoint.

    Args:
        sources: A folder, a manifest TSV, a ``{"path", "dataset",
            "exclude", "include"}`` dict (see
            :func:`~satagraph.datasets.sources.resolve_sources`), an endless
            procedural zoo ``{"zoo": "endless", "species": [...],
            "holdout_species": [...], "windows_per_epoch": N}`` (windows
            generated on the fly, see :func:`~satagraph.data.endless.zoo_entry`),
            or a list of these (mixed in one training set).
        window (int): Frames per training window.
        stride (int): Frames between training window starts.
        eval_stride (int, optional): Stride for validation/test windows
            (defaults to :obj:`window`).
        batch_size (int): Windows per batch.
        balanced (bool): Sample training windows so that every (dataset,
            skeleton) group is drawn equally often.
        preprocessing (dict, optional): Overrides of
            :data:`~satagraph.data.dataset.DEFAULT_PREPROCESSING`.
        semantic_encoder (str, optional): See :func:`semantic_embedder`.
        cache_dir (str, optional): Cache folder (processed features and
            embeddings).
        num_workers (int): DataLoader workers.
        max_files (int, optional): Use at most this many files per split
            (quick experiments), taken in turn from each dataset and
            skeleton (:func:`~satagraph.datasets.sources.spread_files`); a
            warning says what was kept.
        seed (int): Seed of the training order (drawn per epoch from
            ``(seed, epoch)``, see
            :class:`~satagraph.data.sampler.ResumableSampler`) and of the
            augmentation.
        augment (dict or bool, optional): On-the-fly skeleton augmentation
            of the training windows (validation and test windows are never
            augmented): ``None``/``False`` (default, off), ``True`` (the
            defaults of :data:`~satagraph.data.dataset.AUGMENT_DEFAULTS`) or
            a dict of some of its keys, e.g. ``{"scale": 0.5, "mirror":
            0.5, "drop": 0.1, "low": 0.8, "high": 1.2}``. Every window is
            drawn on a new skeleton per epoch, deterministically given the
            seed (see :class:`~satagraph.data.dataset.WindowAugment`). It
            augments the windows of files: an endless zoo's are drawn on a
            new rig, proportions and rest pose already.
        on_error (str): What to do with files that cannot be processed
            (malformed, or failing :mod:`~satagraph.data.validate`): every
            bad file of every split is found first; ``"raise"`` (default)
            then fails with one error listing them all, ``"skip"`` warns,
            lists them in :attr:`skipped` and uses the others.
        body_relative (bool): Normalise lengths in character heights
            (default), see :class:`~satagraph.data.FeatureNormalizer`.
        root_unit (str): The unit of the root's ground speed and height
            when :obj:`body_relative`: ``"height"`` (default) or ``"leg"``
            (leg lengths, the unit in which travel compares across body
            plans), see :class:`~satagraph.data.FeatureNormalizer`.
        train_transform (str or callable, optional): A transform of one's
            own on every training window, after :obj:`augment`: a function
            ``MotionClip -> MotionClip`` or the name it was registered
            under (:mod:`~satagraph.data.window_transform`; a config's
            ``data.train_transform``).
    """

    def __init__(self, sources: Union[str, Sequence], window: int = 64, stride: int = 32,
                 eval_stride: Optional[int] = None, batch_size: int = 32,
                 balanced: bool = True, preprocessing: Optional[Dict] = None,
                 semantic_encoder: Optional[str] = "offline",
                 cache_dir: Optional[str] = None, num_workers: int = 0,
                 max_files: Optional[int] = None, seed: int = 0,
                 augment: Union[None, bool, Mapping[str, Any]] = None,
                 on_error: str = "raise", body_relative: bool = True,
                 root_unit: str = "height",
                 train_transform: Union[None, str, Callable] = None) -> None:
        super().__init__()
        if on_error not in ON_ERROR:
            raise ValueError(f"data.on_error must be one of {ON_ERROR}, got {on_error!r}")
        self.on_error = on_error
        self.train_transform = train_transform
        if root_unit not in ROOT_UNITS:
            raise ValueError(f"data.root_unit must be one of {ROOT_UNITS}, got {root_unit!r}")
        #: ``(split, error line)`` of every file left out (``on_error="skip"``).
        self.skipped: List[str] = []
        self.sources, self.window, self.stride = sources, window, stride
        self.eval_stride = eval_stride or window
        self.batch_size, self.balanced = batch_size, balanced
        self.preprocessing, self.cache_dir = dict(preprocessing or {}), cache_dir
        self.semantic_encoder, self.num_workers = semantic_encoder, num_workers
        self.max_files, self.seed = max_files, seed
        self.augment = WindowAugment.from_config(augment, seed, self.preprocessing)
        self.datasets: Dict[str, MotionDataset] = {}
        self.normalizer = FeatureNormalizer(body_relative, root_unit)
        #: Pair every training clip with a clip of another skeleton when
        #: collating (``batch.pairing``, see
        #: :class:`~satagraph.data.pairing.PartnerCollate`); a module with an
        #: unpaired retargeting term switches it on in its ``setup``.
        self.pair_partners = False
        #: The splits :meth:`setup` reads (scoring one split reads it alone,
        #: :func:`~satagraph.pipelines.evaluation.scoring_data`: a bad file of
        #: another split then stops nothing).
        self.splits: Tuple[str, ...] = SPLITS
        self._normalizer_fitted = False

    def setup(self, stage: Optional[str] = None) -> None:
        """Read the splits once; fit the normaliser on the training split
        at the first ``"fit"`` (or ``None``) stage, also when another stage
        (``trainer.validate`` before ``trainer.fit``) read the splits first."""
        if not self.datasets:
            self._train, self._zoos = self._read_splits()
        if stage not in (None, "fit") or self._normalizer_fitted:
            return  # scoring a trained model: its own statistics
        if not len(self.datasets["train"]):
            raise ValueError(f"no training windows in {self.sources!r}")
        if not len(self.datasets["val"]):
            warnings.warn(f"no validation windows in {self.sources!r}: no file is in the "
                          "'val' split (a manifest's split column; a folder without one is "
                          "split 80/10/10 by file name), so nothing is validated and the "
                          "checkpoints are the last epoch's", stacklevel=2)
        else:
            _warn_unvalidated(self.datasets["train"], self.datasets["val"])
        self._fit_normalizer(self._train, self._zoos)
        self._normalizer_fitted = True

    def _read_splits(self) -> tuple:
        """Build every split's dataset; the training files' ``(files,
        features)`` and the zoo sources, for the normaliser."""
        sources = self.sources if isinstance(self.sources, (list, tuple)) \
            else [self.sources]
        if not [s for s in sources if s]:
            raise ValueError(f"data.sources is empty: {SOURCES_HINT}")
        zoos = [zoo_entry(s) for s in sources if is_zoo_entry(s)]
        files = resolve_sources([s for s in sources if not is_zoo_entry(s)])
        if self.augment is not None and not files:
            warnings.warn("data.augment changes no window here: it augments the windows of "
                          "files, and the endless zoo draws a new rig, proportions and rest "
                          "pose for each of its windows already", stacklevel=3)
        embed = semantic_embedder(self.semantic_encoder, self.cache_dir)
        loaded, errors, total, limited = {}, [], 0, []
        with rig_warnings_capped():  # a rig's doubts capped over all splits
            for split in self.splits:
                chosen, note = limit_files(files, split, self.max_files)
                limited += note
                kept, feats, bad = try_load_features(chosen, self.preprocessing, self.cache_dir)
                loaded[split] = (kept, feats)
                errors += [f"{split}: {e}" for e in bad]
                total += len(chosen)
        if limited:
            warnings.warn(limit_warning(self.max_files, limited), stacklevel=3)
        if errors and self.on_error == "raise":
            raise dataset_error(errors, total)
        if errors:
            self.skipped = errors
            warnings.warn(f"data.on_error=skip: left out {len(errors)} of {total} motion "
                          "files:\n" + "\n".join(f"  {e}" for e in errors), stacklevel=3)
        for split, (kept, feats) in loaded.items():
            stride = self.stride if split == "train" else self.eval_stride
            augment = self.augment if split == "train" else None
            self.datasets[split] = MotionDataset(kept, feats, embed, self.window, stride,
                                                 augment)
            if zoos:
                self.datasets[split] = MixedDataset([self.datasets[split]] + [
                    d for z in zoos for d in zoo_datasets(
                        z, split, self.window, embed, self.preprocessing, self.seed)])
        return loaded.get("train", ([], [])), zoos

    def _fit_normalizer(self, train, zoos) -> None:
        """Statistics of the training files and of ``fit_windows`` windows
        of each zoo source's first epoch."""
        kept, feats = list(train[0]), list(train[1])
        names = [f.path for f in kept]
        for z, spec in zip(self._zoo_parts("train"), zoos):
            extra = z.fit_features(int(spec["fit_windows"]))
            feats += extra
            names += [f"<endless zoo window {i}>" for i in range(len(extra))]
        self.normalizer.fit(feats, names)

    def _zoo_parts(self, split: str) -> list:
        ds = self.datasets[split]
        return [p for p in getattr(ds, "parts", []) if hasattr(p, "zoo")]

    @property
    def semantic_channels(self) -> int:
        """Width of the semantic embedding (0 without one).

        Raises:
            RuntimeError: The splits are not read yet (:meth:`setup` first).
        """
        if "train" not in self.datasets:
            raise RuntimeError(f"{type(self).__name__}.semantic_channels: the data is not "
                               "read yet: call datamodule.setup('fit') first")
        ds = self.datasets["train"]
        return ds[0].semantic.shape[1]

    def _loader(self, split: str, shuffle: bool) -> DataLoader:
        collate = (PartnerCollate(self.seed) if self.pair_partners and split == "train"
                   else collate_clips)
        transform = window_transform(self.train_transform) if split == "train" else None
        if transform is not None:
            collate = TransformedCollate(collate, transform)
        return window_loader(self.datasets[split], self.batch_size, self.seed, shuffle,
                             self.balanced, self.num_workers, collate, self._resume)


