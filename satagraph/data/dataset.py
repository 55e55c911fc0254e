"""Windows of motion features from many files and skeletons."""
from __future__ import annotations

from pathlib import Path
from typing import Callable, Dict, List, Optional, Sequence, Tuple

import torch
from torch.utils.data import Dataset

from satagraph.data.cache import cache_key, default_cache_dir, load_cached, store_cached
from satagraph.data.canonical import canonicalize
from satagraph.data.clip import MotionClip
from satagraph.data.features import CONTACT_HEIGHT, CONTACT_SPEED, MotionFeatures, motion_to_features
from satagraph.data.sources import MotionFile
from satagraph.io import BVHError, read_bvh

#: Preprocessing defaults; every key is part of the cache key.
DEFAULT_PREPROCESSING: Dict = {"fps": 30.0, "up_axis": None, "floor": True,
                               "contact_height": CONTACT_HEIGHT,
                               "contact_speed": CONTACT_SPEED}


class MotionDatasetError(RuntimeError):
    """Some files of a dataset could not be processed; lists every one."""


def preprocess_file(path: str, config: Dict) -> MotionFeatures:
    """Read, canonicalise and featurise one BVH file."""
    motion = canonicalize(read_bvh(path), fps=config["fps"],
                          up_axis=config["up_axis"], floor=config["floor"])
    return motion_to_features(motion, contact_height=config["contact_height"],
                              contact_speed=config["contact_speed"])


def load_features(files: Sequence[MotionFile], config: Optional[Dict] = None,
                  cache_dir: Optional[str] = None,
                  progress: Optional[Callable] = None) -> List[MotionFeatures]:
    r"""Features of every file, from the cache where possible.

    All files are tried before failing: the error then lists each bad file
    and why. Nothing is cached for a bad file.
    """
    config = dict(DEFAULT_PREPROCESSING, **(config or {}))
    folder = Path(cache_dir or default_cache_dir()) / "processed"
    out, errors = [], []
    iterator = progress(files) if progress else files
    for f in iterator:
        try:
            key = cache_key(f.path, config)
            feats = load_cached(folder, key)
            if feats is None:
                feats = preprocess_file(f.path, config)
                store_cached(folder, key, feats)
            out.append(feats)
        except (BVHError, OSError, ValueError) as err:
            errors.append(f"  {f.path}: {err}")
    if errors:
        raise MotionDatasetError(f"{len(errors)} of {len(files)} motion files could "
                                 "not be processed:\n" + "\n".join(errors))
    return out


def window_starts(num_frames: int, window: int, stride: int) -> List[int]:
    """Start frames of windows covering a clip (a clip shorter than a window
    gives one shorter window)."""
    if num_frames <= window:
        return [0]
    starts = list(range(0, num_frames - window + 1, stride))
    if starts[-1] + window < num_frames:
        starts.append(num_frames - window)
    return starts


class MotionDataset(Dataset):
    r"""Fixed-length windows (default 64 frames) of motion features.

    Args:
        files (list[MotionFile]): The files.
        features (list[MotionFeatures]): Their features (see
            :func:`load_features`).
        semantic (Callable, optional): Maps a :class:`~satagraph.Skeleton` to
            its semantic embedding ``[J, D_t]``; called once per skeleton.
        window (int): Frames per window.
        stride (int): Frames between window starts.
    """

    def __init__(self, files: Sequence[MotionFile], features: Sequence[MotionFeatures],
                 semantic: Optional[Callable] = None, window: int = 64,
                 stride: int = 32) -> None:
        self.files, self.features = list(files), list(features)
        self.window, self.stride = window, stride
        self._semantic: Dict[Tuple[str, ...], torch.Tensor] = {}
        self.semantic_fn = semantic
        self.index: List[Tuple[int, int]] = [
            (i, s) for i, f in enumerate(self.features)
            for s in window_starts(f.num_frames, window, stride)]

    def __len__(self) -> int:
        return len(self.index)

    def semantic(self, feats: MotionFeatures) -> Optional[torch.Tensor]:
        if self.semantic_fn is None:
            return None
        key = tuple(feats.skeleton.names)
        if key not in self._semantic:
            self._semantic[key] = self.semantic_fn(feats.skeleton).float()
        return self._semantic[key]

    def group(self, idx: int) -> str:
        """(dataset, skeleton) group of a window, for balanced sampling."""
        f = self.files[self.index[idx][0]]
        return f"{f.dataset}/{f.skeleton}"

    def __getitem__(self, idx: int) -> MotionClip:
        i, start = self.index[idx]
        feats, f = self.features[i], self.files[i]
        meta = {"path": f.path, "dataset": f.dataset, "skeleton": f.skeleton}
        return feats.to_clip(start, start + self.window, self.semantic(feats), meta)
