r"""The data module of text-to-motion training: captioned windows of files
and of the endless zoo (:mod:`satagraph.data.captioned`), batched as
:class:`~satagraph.data.FrameBatch` objects whose ``meta`` carries the
captions.

A config's ``data`` section (``module: t2m``)::

    data:
      sources:
        - {zoo: endless, species: [biped, quadruped, bird], windows_per_epoch: 256,
           val_windows: 32, test_windows: 32}
        - {path: ../shared/data/manifest.tsv, dataset: bandai}
      window: 64          # most frames per window (and per zoo clip)
      min_frames: 32      # fewest frames per zoo clip
      batch_size: 16
      mirror: 0.5         # left/right mirroring of motion and captions
      reverse: 0.0        # files' walks played backwards as backward walks
      scale: 0.5          # bone scaling of the skeleton (training windows)
      semantic_encoder: offline   # the autoencoder's
"""
from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any, Dict, List, Mapping, Optional, Sequence, Union

from torch.utils.data import DataLoader, Dataset

from satagraph.data.code_bank import CodeBank, concat_banks
from satagraph.data.dataset import (DEFAULT_PREPROCESSING, rig_warnings_capped,
                                    try_load_features)
from satagraph.data.datamodule import WindowDataModule, semantic_embedder, window_loader
from satagraph.data.endless import MixedDataset, endless_zoo, is_zoo_entry, zoo_entry
from satagraph.datasets.sources import SPLITS, limit_files, limit_warning, resolve_sources
from satagraph.data.captioned import FileCaptionWindows, ZooCaptionWindows
from satagraph.utils.files import check_input_file


def zoo_caption_datasets(spec: Mapping[str, Any], split: str, window: int, min_frames: int,
                         seed: int, **kwargs: Any) -> List[ZooCaptionWindows]:
    """The captioned zoo datasets of one split of a ``{zoo: endless}``
    entry (see :func:`~satagraph.data.endless.zoo_entry`): training clips of
    the training plans; validation and test clips of held-out seeds, of the
    training plans and of the held-out plans (``<name>-holdout``)."""
    spec = zoo_entry(spec)
    fps = float(kwargs.get("preprocessing", {}).get("fps", DEFAULT_PREPROCESSING["fps"]))
    zoo = endless_zoo(spec, fps, seed)
    name = spec["dataset"]
    if split == "train":
        return [ZooCaptionWindows(zoo, spec["windows_per_epoch"], window, min_frames,
                                  "train", False, name, seed=seed, **kwargs)]
    count = spec[f"{split}_windows"]
    out = [ZooCaptionWindows(zoo, count, window, min_frames, split, False, name, seed=seed,
                             **kwargs)]
    if zoo.holdout_plans:
        out.append(ZooCaptionWindows(zoo, count, window, min_frames, split, True,
                                     f"{name}-holdout", seed=seed, **kwargs))
    return out


def _bank_paths(code_bank) -> List[str]:
    """``data.code_bank`` (one path, several, or none) as a list."""
    if not code_bank:
        return []
    if isinstance(code_bank, (str, Path)):
        return [str(code_bank)]
    return [str(path) for path in code_bank]


class CaptionDataModule(WindowDataModule):
    r"""Captioned windows of files and of the endless zoo, in the sources'
    own splits (a manifest's, the zoo's seed streams); nothing re-split.

    Args:
        sources: ``data.sources`` entries as for
            :class:`~satagraph.data.datamodule.MotionDataModule` (folders,
            manifests, ``{path, dataset, include, exclude}`` dicts and
            ``{zoo: endless, ...}`` entries); files without captions are
            left out.
        window (int): Most frames per window.
        stride (int): Frames between file window starts.
        min_frames (int): Fewest frames of a zoo clip.
        batch_size (int): Windows per batch.
        mirror (float): Probability of mirroring a training window (motion
            and captions together).
        reverse (float): Probability of playing a file's training window
            backwards with its captions, where their reversal is known (walks;
            :func:`~satagraph.datasets.reverse.reverse_text`). The zoo draws
            its backward walks itself and is never reversed.
        scale (float): Probability of putting a training window on a
            bone-scaled skeleton (see
            :class:`~satagraph.data.captioned.CaptionWindows`).
        balanced (bool): Draw every (dataset, skeleton) group equally often.
        semantic_encoder (str, optional): Semantic encoder of the joints
            (the frozen autoencoder's).
        preprocessing (dict, optional): See
            :data:`~satagraph.data.dataset.DEFAULT_PREPROCESSING`.
        cache_dir (str, optional): Feature cache folder.
        num_workers (int): DataLoader workers.
        max_files (int, optional): At most this many files per split, taken
            in turn from each dataset and skeleton
            (:func:`~satagraph.datasets.sources.spread_files`); a warning
            says what was kept.
        seed (int): Seed of sampling, mirroring and caption choice.
        code_bank (str or list, optional): Train on the windows of this
            :class:`~satagraph.data.code_bank.CodeBank` (``satagraph
            code-bank``), or of these joined, instead of coding the sources'
            windows every step; validation and test stay on the sources.
    """

    def __init__(self, sources: Union[str, Sequence], window: int = 64, stride: int = 32,
                 min_frames: int = 32, batch_size: int = 16, mirror: float = 0.5,
                 balanced: bool = True, semantic_encoder: Optional[str] = "offline",
                 preprocessing: Optional[Dict] = None, cache_dir: Optional[str] = None,
                 num_workers: int = 0, max_files: Optional[int] = None,
                 seed: int = 0, scale: float = 0.0,
                 code_bank: Optional[Union[str, Sequence[str]]] = None,
                 reverse: float = 0.0) -> None:
        super().__init__()
        self.reverse = float(reverse)
        #: The bank files (``code_bank``, as a list; empty: none).
        self.code_bank = _bank_paths(code_bank)
        #: The training bank (``code_bank``), read by :meth:`setup`.
        self.bank: Optional[CodeBank] = None
        self.scale = float(scale)
        self.sources = list(sources) if isinstance(sources, (list, tuple)) else [sources]
        self.window, self.stride, self.min_frames = int(window), int(stride), int(min_frames)
        self.batch_size, self.mirror, self.balanced = int(batch_size), float(mirror), balanced
        self.semantic_encoder, self.cache_dir = semantic_encoder, cache_dir
        self.preprocessing = dict(preprocessing or {})
        self.num_workers, self.max_files, self.seed = num_workers, max_files, int(seed)
        self.datasets: Dict[str, Dataset] = {}
        #: Files left out because they could not be processed.
        self.skipped: List[str] = []

    def setup(self, stage: Optional[str] = None) -> None:
        if self.datasets:
            return
        embed = semantic_embedder(self.semantic_encoder, self.cache_dir)
        files = resolve_sources([s for s in self.sources if not is_zoo_entry(s)])
        zoos = [s for s in self.sources if is_zoo_entry(s)]
        limited: List[str] = []
        with rig_warnings_capped():  # a rig's doubts capped over all splits
            for split in SPLITS:
                chosen, note = limit_files(files, split, self.max_files)
                limited += note
                self.datasets[split] = self._split(split, chosen, zoos, embed)
        if limited:
            warnings.warn(limit_warning(self.max_files, limited), stacklevel=2)
        if not len(self.datasets["train"]):
            raise ValueError(f"no captioned training windows in {self.sources!r}")
        if self.code_bank:
            self.bank = self._read_banks()

    def _read_banks(self) -> CodeBank:
        """The bank of ``code_bank``, several joined into one."""
        for path in self.code_bank:
            check_input_file(path, "code bank (data.code_bank)")
        banks = [CodeBank.load(path) for path in self.code_bank]
        for path, bank in zip(self.code_bank, banks):
            bank.check_data(list(self.sources), self.window, path)
        if len({bank.fingerprint for bank in banks}) > 1:
            raise ValueError(f"data.code_bank: {', '.join(self.code_bank)} hold the codes of "
                             "different autoencoders")
        return banks[0] if len(banks) == 1 else concat_banks(banks)

    def _split(self, split: str, chosen, zoos, embed) -> Dataset:
        """The captioned windows of one split's files (training windows
        mirrored)."""
        kwargs = {"semantic": embed, "preprocessing": self.preprocessing,
                  "mirror": self.mirror if split == "train" else 0.0,
                  "scale": self.scale if split == "train" else 0.0}
        kept, feats, bad = try_load_features(chosen, self.preprocessing, self.cache_dir)
        if bad:
            self.skipped += [f"{split}: {e}" for e in bad]
            warnings.warn(f"left out {len(bad)} {split} files: {bad[:3]}", stacklevel=2)
        stride = self.stride if split == "train" else self.window
        reverse = self.reverse if split == "train" else 0.0
        windows = FileCaptionWindows(kept, feats, self.window, stride, seed=self.seed,
                                     reverse=reverse, **kwargs)
        if windows.uncaptioned:
            warnings.warn(f"{split}: {len(windows.uncaptioned)} of {len(kept)} files have no "
                          f"captions and are left out ({windows.uncaptioned[0]}, ...): a "
                          "file's captions are a sidecar beside it, NAME.txt (HumanML3D "
                          "lines caption#tokens#from#to) or NAME.json", stacklevel=2)
        if windows.outside:
            warnings.warn(f"{split}: {len(windows.outside)} captions lie past their clip's "
                          f"end and are left out ({windows.outside[0]}, ...)", stacklevel=2)
        parts: List[Dataset] = [windows]
        for spec in zoos:
            parts += zoo_caption_datasets(spec, split, self.window, self.min_frames,
                                          self.seed, **kwargs)
        return MixedDataset(parts)

    def _loader(self, split: str, shuffle: bool) -> DataLoader:
        if split == "train" and self.bank is not None:  # epoch by epoch, as a resume sees it
            return window_loader(self.bank, self.batch_size, self.seed, shuffle, False,
                                 collate=self.bank.collate, resume=self._resume)
        return window_loader(self.datasets[split], self.batch_size, self.seed, shuffle,
                             self.balanced, self.num_workers, resume=self._resume)


__all__ = ["CaptionDataModule", "zoo_caption_datasets"]
