r"""Captioned windows of motion for text-to-motion training (issue 19).

Every item is a :class:`~satagraph.data.MotionClip` whose ``meta`` holds
the caption it is trained with:

- ``meta["text"]``: one caption of the window (a seeded choice per
  ``(epoch, index)`` in training, the first one in evaluation);
- ``meta["captions"]``: every caption of the window;
- ``meta["seconds"]``: the duration of the motion the caption describes
  (what the length model learns): its clip's or time range's, which may
  be longer than the window cut from it;
- ``meta["censored"]``: whether that duration is only a lower bound (an
  endless-zoo clip, whose length was drawn while its motion could have
  gone on; see :class:`~satagraph.nn.generators.LengthModel`);
- ``meta["mirrored"]``: whether the window was mirrored left/right, in
  which case the motion (:func:`~satagraph.transforms.augment.mirror`) and every
  caption (:func:`~satagraph.datasets.mirror.mirror_text`) were mirrored
  together;
- ``meta["reversed"]``: whether the window was played backwards
  (:func:`~satagraph.transforms.augment.reverse_time`), its captions
  reversed with it (:func:`~satagraph.datasets.reverse.reverse_text`; walks
  only: a window none of whose captions has a known reversal is never
  reversed).

Two sources:

- :class:`FileCaptionWindows`: windows of captioned files (bandai, cmu,
  ccbase, user sidecars; see :func:`~satagraph.datasets.captions_for`),
  in the manifest's splits;
- :class:`ZooCaptionWindows`: endless-zoo clips of drawn lengths, captioned
  from the generator's facts (:class:`~satagraph.datasets.zoo.ClipFacts`).

:func:`collate_clips` batches them as any clip; the texts come back with
:func:`batch_texts`.
"""
from __future__ import annotations

from typing import Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import torch
from torch.utils.data import Dataset

from satagraph.transforms.augment import mirror as mirror_motion, reverse_time
from satagraph.transforms.canonical import canonicalize
from satagraph.data.clip import MotionClip
from satagraph.data.dataset import (DEFAULT_PREPROCESSING, WindowAugment, _frames, shown_as,
                                    feature_options, skeleton_id, window_height,
                                    window_starts)
from satagraph.data.features import MotionFeatures, features_to_motion, motion_to_features
from satagraph.semantics.evidence import call_semantic, evidence_from_features
from satagraph.datasets.sources import MotionFile
from satagraph.datasets.zoo.endless import EndlessZoo
from satagraph.datasets.caption import Caption
from satagraph.datasets.captions import captions_for

#: A window key: an index (evaluation), or ``(epoch, index)`` (training).
WindowKey = Union[int, Tuple[int, int]]


def mirror_features(feats: MotionFeatures, start: int, stop: int,
                    options: Dict[str, float]) -> Optional[Tuple[MotionFeatures, int]]:
    r"""Frames ``start:stop`` of a clip mirrored left/right (the character's
    X axis), featurised again with one frame before them where there is one
    (so that the first frame's velocities are the clip's).

    Args:
        feats: Features of the clip.
        start: First frame.
        stop: Frame after the last.
        options: :func:`~satagraph.data.dataset.feature_options`.

    Returns:
        The mirrored features and the position of frame :obj:`start` in
        them; ``None`` for a skeleton without matching left/right joints.
    """
    lead = 1 if start > 0 else 0
    motion = features_to_motion(_frames(feats, slice(start - lead, stop)))
    try:
        mirrored = mirror_motion(motion)
    except ValueError:
        return None
    axis = feats.facing_axis * np.array([-1.0, 1.0, 1.0])  # the root turns with it
    return motion_to_features(mirrored, **options, facing_axis=axis,
                              height=window_height(feats, motion, mirrored)), lead


def reverse_features(feats: MotionFeatures, start: int, stop: int,
                     options: Dict[str, float]) -> Tuple[MotionFeatures, int]:
    r"""Frames ``start:stop`` of a clip played backwards, featurised again
    with the frame after them in front where there is one (so that the
    first frame's velocities are those of the reversed clip); the arguments
    are :func:`mirror_features`'.

    Returns:
        The reversed features and the position of frame ``stop - 1`` (the
        reversed window's first) in them.
    """
    lead = 1 if stop < feats.num_frames else 0
    window = features_to_motion(_frames(feats, slice(start, stop + lead)))
    motion = reverse_time(window)
    return motion_to_features(motion, **options, facing_axis=feats.facing_axis,
                              height=window_height(feats, window, motion)), lead


def reversible(captions: Sequence[Caption]) -> List[Caption]:
    """The captions of a window played backwards: those whose reversal is
    known (:meth:`~satagraph.datasets.caption.Caption.reversed`)."""
    return [c for c in (c.reversed() for c in captions) if c is not None]


def choose_caption(captions: Sequence[Caption], rng: Optional[np.random.Generator]
                   ) -> Caption:
    """One caption: a draw of :obj:`rng`, or the first without one."""
    if rng is None or len(captions) == 1:
        return captions[0]
    return captions[int(rng.integers(len(captions)))]


def overlapping(captions: Sequence[Caption], fps: float, num_frames: int, start: int,
                stop: int) -> List[Caption]:
    """The captions that cover ``start:stop``: whose frames overlap it by
    half the shorter of the two at least (a clip's whole captions always
    do). A window of a standing stretch took "walks backward" from the next
    stretch's caption for a single shared frame."""
    out = []
    for caption in captions:
        part = caption.frames(fps, num_frames)
        shared = min(stop, part.stop) - max(start, part.start)
        if shared > 0 and 2 * shared >= min(stop - start, part.stop - part.start):
            out.append(caption)
    return out


def outside_captions(path: str, captions: Sequence[Caption], fps: float,
                     num_frames: int) -> List[str]:
    """The captions of a clip that cover none of its frames (their range
    starts at or past its end), one line each naming the file, the text and
    the range: no window ever takes them."""
    lines = []
    for caption in captions:
        part = caption.frames(fps, num_frames)
        if part.stop <= part.start:
            end = "end" if caption.end is None else f"{caption.end:g}"
            lines.append(f"{path}: {caption.text[:40]!r} at {caption.start:g}-{end} s "
                         f"of a {num_frames / fps:.2f} s clip")
    return lines


class CaptionWindows(Dataset):
    r"""Base of the captioned window datasets: seeded mirroring, caption
    choice and the ``meta`` every item carries.

    Args:
        semantic (Callable, optional): Skeleton -> semantic embedding (see
            :func:`~satagraph.data.datamodule.semantic_embedder`); the
            autoencoder's own.
        mirror (float): Probability of mirroring a training window with its
            captions.
        scale (float): Probability of putting a training window on a
            bone-scaled copy of its skeleton (every bone scaled per axis in
            ``[low, high]`` of :class:`~satagraph.data.dataset.WindowAugment`;
            the captions still hold: no word names a size).
        seed (int): Seed of mirroring, reversal, scaling and caption choice.
        preprocessing (dict, optional): Overrides of
            :data:`~satagraph.data.dataset.DEFAULT_PREPROCESSING`.
        reverse (float): Probability of playing a training window backwards
            with its captions, where its captions' reversal is known (a walk
            becomes a backward walk; see
            :func:`~satagraph.datasets.reverse.reverse_text`).
    """

    def __init__(self, semantic: Optional[Callable] = None, mirror: float = 0.0,
                 seed: int = 0, preprocessing: Optional[Mapping] = None,
                 scale: float = 0.0, reverse: float = 0.0) -> None:
        for name, p in (("mirror", mirror), ("scale", scale), ("reverse", reverse)):
            if not 0.0 <= p <= 1.0:
                raise ValueError(f"{name} must be in [0, 1], got {p}")
        self.semantic_fn, self.p_mirror, self.seed = semantic, float(mirror), int(seed)
        self.p_scale, self.p_reverse = float(scale), float(reverse)
        self.config = dict(DEFAULT_PREPROCESSING, **(preprocessing or {}))
        self.options = feature_options(self.config)
        self.scaler = WindowAugment(scale=1.0, mirror=0.0, drop=0.0, merge=0.0, insert=0.0,
                                    rest=0.0, seed=self.seed, **self.options)
        #: Keyed by ``(epoch, index)`` in training (see
        #: :class:`~satagraph.data.sampler.ResumableSampler`).
        self.keyed = True

    def rng(self, epoch: Optional[int], index: int) -> Optional[np.random.Generator]:
        """The generator of a training key (``None`` in evaluation)."""
        if epoch is None:
            return None
        return np.random.default_rng([self.seed, 19, int(epoch), int(index)])

    def semantic(self, feats: MotionFeatures) -> Optional[torch.Tensor]:
        """Semantic embedding of a window's skeleton, with its evidence."""
        if self.semantic_fn is None:
            return None
        evidence = evidence_from_features(feats)
        return call_semantic(self.semantic_fn, feats.skeleton, evidence).float()

    def make_clip(self, feats: MotionFeatures, start: int, stop: int,
                  captions: Sequence[Caption], rng: Optional[np.random.Generator],
                  meta: Dict, censored: bool = False) -> MotionClip:
        """The item of frames ``start:stop``: mirrored with its captions at
        probability :attr:`p_mirror`, played backwards at :attr:`p_reverse`
        and bone-scaled at :attr:`p_scale` (training only), with a caption
        drawn; its duration is the drawn caption's time range in
        :obj:`feats`, or the item's own where it is only a lower bound
        (:obj:`censored`)."""
        total, mirrored, backwards = feats.num_frames, None, []
        if rng is not None and rng.random() < self.p_mirror:
            mirrored = mirror_features(feats, start, stop, self.options)
        if mirrored is not None:
            feats, lead = mirrored
            start, stop = lead, None
            captions = [c.mirrored() for c in captions]
        if rng is not None and self.p_reverse and rng.random() < self.p_reverse:
            backwards = reversible(captions)
        if backwards:
            stop = feats.num_frames if stop is None else stop
            feats, start = reverse_features(feats, start, stop, self.options)
            stop, captions = None, backwards
        scaled = rng is not None and rng.random() < self.p_scale
        if scaled:
            feats, start = self.scaler(feats, start, stop, int(rng.integers(2 ** 31)))
            stop = None
        clip = feats.to_clip(start, stop, self.semantic(feats), meta)
        fps = float(self.config["fps"])
        caption = choose_caption(captions, rng)
        span = caption.frames(fps, total)
        frames = clip.num_frames if censored else span.stop - span.start
        clip.meta.update(text=caption.text, seconds=frames / fps, censored=bool(censored),
                         captions=[c.text for c in captions], mirrored=mirrored is not None,
                         reversed=bool(backwards), scaled=scaled)
        return clip

    @staticmethod
    def split_key(key: WindowKey) -> Tuple[Optional[int], int]:
        """``(epoch, index)`` of a key (epoch ``None`` for a plain index)."""
        return key if isinstance(key, tuple) else (None, int(key))


class FileCaptionWindows(CaptionWindows):
    r"""Windows of captioned motion files.

    A window covers at most :obj:`window` frames of one file (a shorter file
    is one shorter window); its captions are those of the file that overlap
    it (user captions with a time range, templates of the whole clip).
    Files without captions are left out.

    Args:
        files (list[MotionFile]): The files.
        features (list[MotionFeatures]): Their features.
        window (int): Most frames per window.
        stride (int): Frames between window starts.
        captions (list[list[Caption]], optional): Captions per file
            (default: :func:`~satagraph.datasets.captions_for` of each).
        **kwargs: See :class:`CaptionWindows`.
    """

    def __init__(self, files: Sequence[MotionFile], features: Sequence[MotionFeatures],
                 window: int = 64, stride: int = 32,
                 captions: Optional[Sequence[Sequence[Caption]]] = None,
                 **kwargs) -> None:
        super().__init__(**kwargs)
        if captions is None:
            captions = [captions_for(f.path, f.dataset) for f in files]
        self.files, self.features, self.captions = [], [], []
        #: Paths of the files left out for having no caption.
        self.uncaptioned: List[str] = []
        #: Captions left out for lying past their clip's end, one line each.
        self.outside: List[str] = []
        for f, feats, caps in zip(files, features, captions):
            self.outside += outside_captions(f.path, caps, feats.fps, feats.num_frames)
            if caps:
                self.files.append(f), self.features.append(feats)
                self.captions.append(list(caps))
            else:
                self.uncaptioned.append(f.path)
        #: :func:`~satagraph.data.dataset.skeleton_id` of every file.
        self.skeletons = [skeleton_id(f, feats.skeleton)
                          for f, feats in zip(self.files, self.features)]
        self.window, self.stride = int(window), int(stride)
        self.index = [(i, s) for i, feats in enumerate(self.features)
                      for s in window_starts(feats.num_frames, self.window, self.stride)
                      if self.window_captions(i, s)]

    def window_captions(self, i: int, start: int) -> List[Caption]:
        """Captions of file :obj:`i` overlapping the window from :obj:`start`."""
        feats = self.features[i]
        stop = min(start + self.window, feats.num_frames)
        return overlapping(self.captions[i], feats.fps, feats.num_frames, start, stop)

    def __len__(self) -> int:
        return len(self.index)

    def group(self, idx: int) -> str:
        """``dataset/skeleton`` of a window (balanced sampling; a group per
        rig where the source names no skeleton)."""
        i = self.index[idx][0]
        return f"{self.files[i].dataset}/{self.skeletons[i]}"

    def __getitem__(self, key: WindowKey) -> MotionClip:
        epoch, idx = self.split_key(key)
        i, start = self.index[idx]
        feats, f = self.features[i], self.files[i]
        stop = min(start + self.window, feats.num_frames)
        meta = {"path": f.path, "dataset": f.dataset, "skeleton": self.skeletons[i]}
        return self.make_clip(feats, start, stop, self.window_captions(i, start),
                              self.rng(epoch, idx), meta)


class ZooCaptionWindows(CaptionWindows):
    r"""Endless-zoo clips with the captions of what the generator drew.

    Clip :obj:`index` of an epoch is a new rig and clip
    (:meth:`~satagraph.datasets.zoo.endless.EndlessZoo.sample`) of a length drawn
    uniformly in ``[min_frames, window]`` (evaluation streams: fixed per
    index, seeds training never draws). The same caption fits a clip of any
    length, so a clip's duration is only a lower bound of its motion's
    (``meta["censored"]``).

    Args:
        zoo (EndlessZoo): The zoo.
        windows (int): Clips per epoch.
        window (int): Most frames per clip.
        min_frames (int): Fewest frames per clip.
        stream (str): ``"train"``, ``"val"`` or ``"test"``.
        holdout (bool): Draw the held-out body plans.
        dataset (str): ``meta["dataset"]`` of the clips.
        **kwargs: See :class:`CaptionWindows`.
    """

    def __init__(self, zoo: EndlessZoo, windows: int, window: int = 64,
                 min_frames: int = 32, stream: str = "train", holdout: bool = False,
                 dataset: str = "zoo-endless", **kwargs) -> None:
        super().__init__(**kwargs)
        if not 2 <= min_frames <= window:
            raise ValueError(f"need 2 <= min_frames <= window, got {min_frames}, {window}")
        self.zoo, self.windows, self.window = zoo, int(windows), int(window)
        self.min_frames, self.stream, self.holdout = int(min_frames), stream, holdout
        self.dataset = dataset

    def __len__(self) -> int:
        return self.windows

    def group(self, idx: int) -> str:
        """``dataset/species`` of a clip (known without drawing it)."""
        return f"{self.dataset}/{self.zoo.species_of(idx, self.holdout)}"

    def num_frames(self, epoch: int, idx: int) -> int:
        """Frames of a clip, drawn from its key."""
        rng = np.random.default_rng([self.seed, 191, epoch, idx])
        return int(rng.integers(self.min_frames, self.window + 1))

    def __getitem__(self, key: WindowKey) -> MotionClip:
        epoch, idx = self.split_key(key)
        draw = 0 if epoch is None else int(epoch)
        frames = self.num_frames(draw, idx)
        sample = self.zoo.sample(draw, idx, frames + 1, self.stream, self.holdout)
        motion = canonicalize(sample.motion, fps=self.config["fps"], up_axis="+Y",
                              unit_scale=1.0, floor=self.config["floor"],
                              replace_bind=False)  # procedural: no bind frame
        feats = motion_to_features(shown_as(motion, self.config), **self.options)
        meta = {"path": f"<zoo {self.stream} {draw} {idx}: {sample.plan} {sample.kind}>",
                "dataset": self.dataset, "skeleton": sample.plan,
                "species": sample.species, "kind": sample.kind}
        return self.make_clip(feats, 1, None, captions_for(sample), self.rng(epoch, idx),
                              meta, censored=True)


def batch_texts(batch) -> List[str]:
    """The training caption of every clip of a collated batch."""
    return [str(m["text"]) for m in batch.meta]


def batch_seconds(batch) -> torch.Tensor:
    r"""Duration of the captioned motion of every clip of a collated batch
    (``meta["seconds"]``).

    Shapes:
        - **output**: :math:`(B,)` seconds
    """
    return torch.tensor([float(m["seconds"]) for m in batch.meta])


def batch_censored(batch) -> torch.Tensor:
    r"""Whether each clip's duration is only a lower bound
    (``meta["censored"]``; ``False`` where a clip does not say).

    Shapes:
        - **output**: :math:`(B,)` bool
    """
    return torch.tensor([bool(m.get("censored", False)) for m in batch.meta])


__all__ = ["CaptionWindows", "FileCaptionWindows", "ZooCaptionWindows", "mirror_features",
           "outside_captions",
           "reverse_features", "reversible",
           "overlapping", "choose_caption", "batch_texts", "batch_seconds",
           "batch_censored"]
