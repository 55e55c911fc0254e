"""Windows of motion features from many files and skeletons."""
from __future__ import annotations

import contextlib
import hashlib
import warnings
from collections import Counter
from dataclasses import asdict, replace
from pathlib import Path
from typing import (Any, Callable, Dict, Iterator, List, Mapping, Optional, Sequence,
                    Tuple, Union)

import numpy as np
import torch
from torch.utils.data import Dataset, Sampler

from satagraph.transforms.augment import AUGMENT, SkeletonAugment
from satagraph.transforms.augment import mirror as mirror_motion
from satagraph.data.cache import cache_key, feature_cache_dir, load_cached, store_cached
from satagraph.transforms.canonical import canonicalize
from satagraph.transforms.rest import REST_MODES, shown_rest
from satagraph.transforms.rig_reading import RigReadingWarning, UnitsWarning
from satagraph.data.clip import MotionClip
from satagraph.data.features import MotionFeatures, features_to_motion, motion_to_features
from satagraph.semantics.evidence import (JointEvidence, call_semantic,
                                          evidence_from_features, remap_evidence)
from satagraph.semantics.limbs import limb_end_index
from satagraph.datasets.sources import MotionFile
from satagraph.data.validate import check_features, check_motion
from satagraph.io import BVHError, read_bvh
from satagraph.motion import CONTACT_HEIGHT, CONTACT_SPEED, Motion
from satagraph.skeleton import Skeleton

#: Preprocessing defaults; every key is part of the cache key.
DEFAULT_PREPROCESSING: Dict = {"fps": 30.0, "up_axis": None, "scale": None,
                               "floor": True,
                               "contact_height": CONTACT_HEIGHT,
                               "contact_speed": CONTACT_SPEED,
                               "facing_smooth": 0.0, "rest": "file"}

#: The preprocessing keys that are options of
#: :func:`~satagraph.data.features.motion_to_features`.
FEATURE_OPTIONS = ("contact_height", "contact_speed", "facing_smooth")


def feature_options(config: Optional[Mapping[str, Any]] = None) -> Dict[str, float]:
    """The :func:`~satagraph.data.features.motion_to_features` options of a
    preprocessing config (defaults where it has none)."""
    config = dict(DEFAULT_PREPROCESSING, **(config or {}))
    return {key: float(config[key]) for key in FEATURE_OPTIONS}


def shown_as(motion: Motion, config: Optional[Mapping[str, Any]] = None) -> Motion:
    r"""A canonical motion in the rest pose a preprocessing config's
    ``rest`` names (:func:`~satagraph.transforms.rest.shown_rest`):
    ``"file"`` (the default) as read; ``"auto"`` as inference shows a rig
    (a line or captured rest re-rested on its mean standing pose), so that a
    model trains on rigs as it will be shown them; ``"first-frame"``."""
    return shown_rest(motion, _rest_mode(config))[0]


def _rest_mode(config: Optional[Mapping[str, Any]]) -> str:
    """A preprocessing config's ``rest``, checked."""
    rest = dict(DEFAULT_PREPROCESSING, **(config or {}))["rest"]
    if rest not in REST_MODES:
        raise ValueError(f"data.preprocessing.rest must be one of {list(REST_MODES)}, "
                         f"got {rest!r}")
    return rest


def data_facing_smooth(data: Optional[Mapping[str, Any]]) -> float:
    """The facing smoothing (seconds) of a ``data`` section's features
    (its ``preprocessing.facing_smooth``; 0 where it sets none): what a
    model trained on them reads the root's facing frame with."""
    return feature_options((data or {}).get("preprocessing"))["facing_smooth"]


#: ``data.augment`` defaults as a dict: the one set,
#: :class:`~satagraph.transforms.augment.AugmentConfig`.
AUGMENT_DEFAULTS: Dict[str, float] = asdict(AUGMENT)

#: Semantic embeddings a dataset keeps (oldest dropped first).
SEMANTIC_CACHE_SIZE = 4096

#: A window key: an index, or ``(epoch, index)`` (see :class:`EpochSampler`).
WindowKey = Union[int, Tuple[int, int]]


#: ``data.on_error`` values: fail listing every bad file, or train on the rest.
ON_ERROR = ("raise", "skip")


class MotionDatasetError(ValueError):
    """Some files of a dataset could not be processed; lists every one
    (with its split) and why."""


def file_config(f: MotionFile, config: Dict) -> Dict:
    """The preprocessing of one file: :obj:`config` with the file's own up
    axis and units (manifest or source entry) where it has them."""
    own = {k: getattr(f, k) for k in ("up_axis", "scale") if getattr(f, k) is not None}
    return dict(config, **own) if own else config


def preprocess_file(path: str, config: Dict) -> MotionFeatures:
    """Read, check (:func:`~satagraph.data.validate.check_motion`),
    canonicalise and featurise one BVH file; ``config["up_axis"]`` and
    ``config["scale"]`` (when set) override the file's declaration and
    detection."""
    from satagraph.transforms.rig_reading import parse_units
    scale = None if config.get("scale") is None else parse_units(config["scale"])
    motion = read_bvh(path)
    check_motion(motion, path, fps=config["fps"])
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        motion = canonicalize(motion, fps=config["fps"], up_axis=config["up_axis"],
                              unit_scale=scale, floor=config["floor"])
    for w in said:  # as they were, and kept with the features
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    feats = motion_to_features(shown_as(motion, config), **feature_options(config))
    check_features(feats, path)
    return replace(feats, rig_warnings=tuple(
        (RIG_WARNING_KINDS[w.category], str(w.message)) for w in said
        if w.category in RIG_WARNING_KINDS))


#: The rig-reading warnings kept with a file's features (:func:`preprocess_file`),
#: by their kind's name there.
RIG_WARNING_KINDS = {RigReadingWarning: "up_axis", UnitsWarning: "units"}
_RIG_WARNING_CATEGORIES = {kind: category for category, kind in RIG_WARNING_KINDS.items()}


def warn_rig_again(feats: MotionFeatures) -> None:
    """Say again what reading a cached file's rig doubted (a run served
    from the cache said nothing of a dog whose units no file tells)."""
    for kind, line in feats.rig_warnings:
        warnings.warn(line, _RIG_WARNING_CATEGORIES.get(kind, RigReadingWarning), stacklevel=2)


def _error_text(path: str, err: Exception) -> str:
    """One line: the error, naming :obj:`path` once."""
    text = " ".join(str(err).split()) or type(err).__name__
    return text if text.startswith(path) else f"{path}: {text}"


def try_load_features(files: Sequence[MotionFile], config: Optional[Dict] = None,
                      cache_dir: Optional[str] = None,
                      progress: Optional[Callable] = None
                      ) -> Tuple[List[MotionFile], List[MotionFeatures], List[str]]:
    r"""Features of every file that can be processed, from the cache where
    possible, and one line per file that cannot (nothing is cached for it).

    Returns:
        The good files, their features, and the errors of the others.
    """
    config = dict(DEFAULT_PREPROCESSING, **(config or {}))
    folder: Optional[Path] = feature_cache_dir(cache_dir)
    kept, out, errors = [], [], []
    with rig_warnings_capped():
        for f in progress(files) if progress else files:
            folder = _load_one(f, config, folder, kept, out, errors)
    return kept, out, errors


def _load_one(f: MotionFile, config: Dict, folder: Optional[Path], kept: List[MotionFile],
              out: List[MotionFeatures], errors: List[str]) -> Optional[Path]:
    """Features of one file into :obj:`kept` and :obj:`out`, or its error
    into :obj:`errors`; the cache folder to go on with."""
    try:
        own = file_config(f, config)
        key = cache_key(f.path, own)
        feats = _cache_read(folder, key)
        if feats is None:
            feats = preprocess_file(f.path, own)
            folder = _cache_write(folder, key, feats)
        else:
            check_features(feats, f.path)
            warn_rig_again(feats)
    except (BVHError, OSError, ValueError, MemoryError) as err:
        errors.append(_error_text(f.path, err))
        return folder
    kept.append(f)
    out.append(feats)
    return folder


#: Rig-reading warnings of each kind (up axis, units) shown while a set of
#: files is processed; the rest are counted in one line.
RIG_WARNINGS_SHOWN = 3


_capping = False


@contextlib.contextmanager
def rig_warnings_capped() -> Iterator[None]:
    """Record the warnings of the files read inside, and issue them again
    capped (:func:`_rewarn_capped`) at the end; inside an outer one, the
    outer caps them all (a data module's three splits said three first
    warnings and three counts)."""
    global _capping
    if _capping:
        yield
        return
    _capping, said = True, []
    try:
        with warnings.catch_warnings(record=True) as said:
            yield
    finally:
        _capping = False
        _rewarn_capped(said)


def _rewarn_capped(said: Sequence[warnings.WarningMessage],
                   shown: int = RIG_WARNINGS_SHOWN) -> None:
    """Issue again the warnings recorded while files were processed: the
    first :obj:`shown` rig-reading warnings of each kind, then one line
    counting the others (a folder of a thousand rigs that tell no units
    warned a line per file), and any other warning as it was."""
    seen, left = Counter(), Counter()
    for w in said:
        if issubclass(w.category, RigReadingWarning):
            seen[w.category] += 1
            if seen[w.category] > shown:
                left[w.category] += 1
                continue
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    for kind, count in left.items():
        what, flag = (("units", "--units") if issubclass(kind, UnitsWarning)
                      else ("up axis", "--up-axis"))
        warnings.warn(f"{count} more {what} warnings like those above are not shown "
                      f"(`satagraph inspect FOLDER` reads every file's rig); pass {flag} "
                      "to set them", kind, stacklevel=3)


def _cache_failed(folder: Path, err: OSError) -> None:
    warnings.warn(f"feature cache {folder} cannot be used ({err.strerror or err}): features "
                  "are computed without it (data.cache_dir or SATAGRAPH_CACHE sets another)",
                  stacklevel=3)


def _cache_read(folder: Optional[Path], key: str) -> Optional[MotionFeatures]:
    """A cached entry; ``None`` without a cache, on a miss, or when the cache
    cannot be read (said once: a problem of the cache, not of a data file)."""
    if folder is None:
        return None
    try:
        return load_cached(folder, key)
    except OSError as err:
        _cache_failed(folder, err)
        return None


def _cache_write(folder: Optional[Path], key: str, feats: MotionFeatures) -> Optional[Path]:
    """Store an entry; the cache folder to go on with (``None`` once it
    cannot be written: said once, and no data file is blamed for it)."""
    if folder is None:
        return None
    try:
        store_cached(folder, key, feats)
    except OSError as err:
        _cache_failed(folder, err)
        return None
    return folder


def dataset_error(errors: Sequence[str], total: int) -> MotionDatasetError:
    """The error listing every bad file (lines ``split: path: reason``)."""
    return MotionDatasetError(
        f"{len(errors)} of {total} motion files could not be processed (set "
        "data.on_error=skip, or eval --on-error skip, to go on with the others):\n"
        + "\n".join(f"  {e}" for e in errors))


def load_features(files: Sequence[MotionFile], config: Optional[Dict] = None,
                  cache_dir: Optional[str] = None,
                  progress: Optional[Callable] = None) -> List[MotionFeatures]:
    r"""Features of every file, from the cache where possible.

    All files are tried before failing: the error then lists each bad file
    and why. Nothing is cached for a bad file.

    Raises:
        MotionDatasetError: Listing every file that cannot be processed.
    """
    _, out, errors = try_load_features(files, config, cache_dir, progress)
    if errors:
        raise dataset_error(errors, len(files))
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


def _frames(feats: MotionFeatures, frames: slice) -> MotionFeatures:
    """The features of some frames only (static parts shared)."""
    return replace(feats, q=feats.q[frames], x=feats.x[frames],
                   x_rel=feats.x_rel[frames], v_q=feats.v_q[frames],
                   v_x=feats.v_x[frames], r=feats.r[frames], c=feats.c[frames])


def window_height(feats: MotionFeatures, source: Motion, augmented: Motion) -> float:
    r"""The character height of an augmented window of a clip: the clip's
    (:obj:`feats`), times the change the augmentation made to the window's
    own (:meth:`~satagraph.motion.Motion.height`). A window's own height is
    a median over its frames alone (1.41 times its clip's in a window of
    ``dog/D1_009_KAN01_002``), so the heights and contacts of a mirrored
    or reversed window would not be those of the window as it is.

    Args:
        feats (MotionFeatures): Features of the whole clip.
        source (Motion): The window before augmentation.
        augmented (Motion): The window after it.
    """
    return feats.height * augmented.height() / max(source.height(), 1e-12)


class WindowAugment:
    r"""On-the-fly skeleton augmentation of feature windows.

    A window is turned back into a motion (losslessly, see
    :func:`~satagraph.data.features_to_motion`), mirrored and put on a
    changed skeleton (bone scaling, leaf chain dropped, trunk segments
    merged, joint inserted; see :class:`~satagraph.transforms.augment.SkeletonAugment`)
    and featurised again, static features included. One frame before the
    window is carried along so that the velocities and root deltas of its
    first frame are those of the clip. The random draws depend only on
    ``(seed, epoch, index)``, so a run is reproducible with any number of
    workers.

    Args:
        scale (float): Probability of scaling the bones.
        mirror (float): Probability of mirroring left and right.
        drop (float): Probability of dropping a leaf chain.
        merge (float): Probability of merging two trunk segments.
        insert (float): Probability of inserting a joint.
        rest (float): Probability of the same motion under another
            rest-pose convention (:func:`~satagraph.transforms.augment.new_rest`:
            a random frame's pose, or every bone along its joint's +X).
        low (float): Smallest per-axis bone scale.
        high (float): Largest per-axis bone scale.
        max_drop (int): Longest leaf chain dropped.
        seed (int): Base seed.
        contact_height (float): Contact height threshold (see
            :func:`~satagraph.data.motion_to_features`).
        contact_speed (float): Contact speed threshold.
        facing_smooth (float): Facing yaw smoothing in seconds (see
            :func:`~satagraph.data.motion_to_features`).
        show_rest (str): The rest pose each augmented window is shown in
            (:func:`shown_as`; ``data.preprocessing.rest``).
    """

    def __init__(self, scale: float = AUGMENT.scale, mirror: float = AUGMENT.mirror,
                 drop: float = AUGMENT.drop, merge: float = AUGMENT.merge,
                 insert: float = AUGMENT.insert, low: float = AUGMENT.low,
                 high: float = AUGMENT.high, max_drop: int = AUGMENT.max_drop,
                 rest: float = AUGMENT.rest, seed: int = 0,
                 contact_height: float = CONTACT_HEIGHT,
                 contact_speed: float = CONTACT_SPEED, facing_smooth: float = 0.0,
                 show_rest: str = "file") -> None:
        if not 0.0 <= mirror <= 1.0:
            raise ValueError("data.augment.mirror must be in [0, 1]")
        if not 0.0 < low <= high:
            raise ValueError(f"data.augment: need 0 < low <= high, got {low}, {high}")
        self.p_mirror, self.seed = float(mirror), int(seed)
        self.options = feature_options(dict(contact_height=contact_height,
                                            contact_speed=contact_speed,
                                            facing_smooth=facing_smooth))
        self.show_rest = _rest_mode({"rest": show_rest})
        self.skeleton_augment = dict(p_scale=float(scale), p_mirror=0.0,
                                     p_drop=float(drop), p_merge=float(merge),
                                     p_insert=float(insert), p_rest=float(rest),
                                     scale_range=(low, high),
                                     max_drop=int(max_drop))
        SkeletonAugment(**self.skeleton_augment)  # checks the probabilities
        #: Windows whose augmentation gave an implausible root motion and
        #: were used as they are (see :func:`_plausible_root`).
        self.rejected = 0

    @classmethod
    def from_config(cls, spec: Union[None, bool, Mapping[str, Any]], seed: int = 0,
                    preprocessing: Optional[Mapping[str, Any]] = None
                    ) -> Optional["WindowAugment"]:
        r"""The augmentation of a ``data.augment`` config section:
        ``null``/``false`` (off), ``true`` (:data:`AUGMENT_DEFAULTS`) or a
        mapping overriding some of its keys."""
        if spec is None or spec is False:
            return None
        spec = {} if spec is True else dict(spec)
        unknown = sorted(set(spec) - set(AUGMENT_DEFAULTS))
        if unknown:
            raise ValueError(f"data.augment: unknown keys {unknown}; known: "
                             f"{sorted(AUGMENT_DEFAULTS)}")
        return cls(**dict(AUGMENT_DEFAULTS, **spec), seed=seed,
                   **feature_options(preprocessing), show_rest=_rest_mode(preprocessing))

    def __call__(self, feats: MotionFeatures, start: int, stop: int,
                 epoch: int = 0, index: int = 0) -> Tuple[MotionFeatures, int]:
        """Augmented features of frames ``start - 1:stop`` (``start:stop``
        when :obj:`start` is 0) and the position of frame :obj:`start` in
        them."""
        lead = 1 if start > 0 else 0
        motion = features_to_motion(_frames(feats, slice(start - lead, stop)))
        rng = np.random.default_rng([self.seed, epoch, index])
        axis = feats.facing_axis
        if rng.random() < self.p_mirror:
            try:
                motion = mirror_motion(motion)
                axis = axis * np.array([-1.0, 1.0, 1.0])  # the root turns with it
            except ValueError:
                pass  # asymmetric skeleton: left as it is
        augment = SkeletonAugment(**self.skeleton_augment,
                                  seed=int(rng.integers(2 ** 31)))
        augmented = shown_rest(augment(motion), self.show_rest)[0]
        # a new rest pose turns the root's local frame: turn its facing axis too
        axis = augmented.rotations[0, 0].T @ motion.rotations[0, 0] @ axis
        out = motion_to_features(augmented, **self.options, facing_axis=axis,
                                 height=window_height(feats, motion, augmented))
        source = _frames(feats, slice(start - lead, stop))
        if not _plausible_root(out, source):
            # a guard, not a fix: bone scaling of ccbase/007_01 (a moving
            # RL_BoneRoot above the hips) gives root speeds of 1e5; train on
            # the window as it is rather than on a poisoned one
            self.rejected += 1
            return source, lead
        return out, lead


def _plausible_root(augmented: MotionFeatures, source: MotionFeatures) -> bool:
    """Whether an augmented window's root motion (yaw and ground speed) is
    within 4x of its source's: a bone scale of at most 1.2 and a mirror
    cannot make it faster."""
    bound = 4.0 * max(float(np.abs(source.r[:, :3]).max(initial=0.0)), 0.5)
    return bool(np.isfinite(augmented.r).all()
                and np.abs(augmented.r[:, :3]).max(initial=0.0) <= bound)


class MotionDataset(Dataset):
    r"""Fixed-length windows (default 64 frames) of motion features.

    With :obj:`augment`, a window asked for by the key ``(epoch, index)``
    (what :class:`EpochSampler` yields to the training loader) is drawn on
    an augmented skeleton seeded by that key (see :class:`WindowAugment`);
    a plain index always gives the window as it is.

    Args:
        files (list[MotionFile]): The files.
        features (list[MotionFeatures]): Their features (see
            :func:`load_features`).
        semantic (Callable, optional): Maps a :class:`~satagraph.Skeleton` to
            its semantic embedding ``[J, D_t]``; called once per skeleton
            and evidence. An embedder with an ``evidence`` keyword (as
            :func:`~satagraph.data.datamodule.semantic_embedder` returns)
            gets the evidence of the window's whole file (which chains bear
            weight, spread, lie in front; see
            :mod:`satagraph.semantics.evidence`), carried over by joint
            name to augmented skeletons.
        window (int): Frames per window.
        stride (int): Frames between window starts.
        augment (WindowAugment, optional): Skeleton augmentation (training
            data only).
    """

    def __init__(self, files: Sequence[MotionFile], features: Sequence[MotionFeatures],
                 semantic: Optional[Callable] = None, window: int = 64,
                 stride: int = 32, augment: Optional[WindowAugment] = None) -> None:
        self.files, self.features = list(files), list(features)
        self.window, self.stride = window, stride
        self.augment = augment
        self._semantic: Dict[Tuple, torch.Tensor] = {}
        self._limbs: Dict[Tuple, Tuple[int, ...]] = {}
        self._evidence: Dict[int, JointEvidence] = {}
        self.semantic_fn = semantic
        #: :func:`skeleton_id` of every file.
        self.skeletons = [skeleton_id(f, feats.skeleton)
                          for f, feats in zip(self.files, self.features)]
        self.index: List[Tuple[int, int]] = [
            (i, s) for i, f in enumerate(self.features)
            for s in window_starts(f.num_frames, window, stride)]

    def __len__(self) -> int:
        return len(self.index)

    def evidence(self, i: int) -> JointEvidence:
        """Geometry / motion evidence of file :obj:`i` (its whole motion),
        computed once."""
        if i not in self._evidence:
            self._evidence[i] = evidence_from_features(self.features[i])
        return self._evidence[i]

    def semantic(self, feats: MotionFeatures,
                 evidence: Optional[JointEvidence] = None) -> Optional[torch.Tensor]:
        """The semantic embedding of a skeleton, computed once per skeleton
        and evidence."""
        return _semantic_once(self._semantic, self.semantic_fn, feats.skeleton, evidence)

    def limb_ends(self, feats: MotionFeatures,
                  evidence: Optional[JointEvidence] = None) -> Tuple[int, ...]:
        """Terminal joint of each limb of a skeleton (in the order of
        :data:`~satagraph.semantics.LIMBS`, ``-1`` where missing),
        computed once per skeleton and evidence; clips carry it as
        ``meta["limb_ends"]``."""
        return _per_skeleton(self._limbs, feats.skeleton,
                             lambda skeleton: tuple(limb_end_index(skeleton, evidence)),
                             evidence)

    def group(self, idx: int) -> str:
        """(dataset, skeleton) group of a window, for balanced sampling
        (:func:`skeleton_id`: a group per rig where the source names no
        skeleton)."""
        i = self.index[idx][0]
        return f"{self.files[i].dataset}/{self.skeletons[i]}"

    def __getitem__(self, key: WindowKey) -> MotionClip:
        epoch, idx = key if isinstance(key, tuple) else (None, key)
        i, start = self.index[idx]
        feats, f = self.features[i], self.files[i]
        meta = {"path": f.path, "dataset": f.dataset, "skeleton": self.skeletons[i]}
        evidence = self.evidence(i)
        if self.augment is None or epoch is None:
            meta["limb_ends"] = self.limb_ends(feats, evidence)
            return feats.to_clip(start, start + self.window,
                                 self.semantic(feats, evidence), meta)
        stop = min(start + self.window, feats.num_frames)
        aug, lead = self.augment(feats, start, stop, epoch, idx)
        evidence = remap_evidence(evidence, feats.skeleton.names, aug.skeleton)
        meta.update(augmented=True, limb_ends=self.limb_ends(aug, evidence))
        clip = aug.to_clip(lead, None, self.semantic(aug, evidence), meta)
        clip.meta["start"] = start
        return clip


def _per_skeleton(cache: Dict[Tuple, Any], skeleton: Skeleton,
                  compute: Callable[[Skeleton], Any],
                  evidence: Optional[JointEvidence] = None) -> Any:
    """:obj:`compute` of :obj:`skeleton`, once per skeleton key and evidence
    (what the descriptions depend on); the oldest of
    :data:`SEMANTIC_CACHE_SIZE` entries goes first (augmented skeletons)."""
    key = (_skeleton_key(skeleton), evidence)
    if key not in cache:
        if len(cache) >= SEMANTIC_CACHE_SIZE:
            del cache[next(iter(cache))]
        cache[key] = compute(skeleton)
    return cache[key]


def _semantic_once(cache: Dict[Tuple, Any], semantic_fn: Optional[Callable],
                   skeleton: Skeleton, evidence: Optional[JointEvidence]
                   ) -> Optional[torch.Tensor]:
    """The float semantic embedding of :obj:`skeleton` by :obj:`semantic_fn`
    (``None`` without one), once per skeleton and evidence in :obj:`cache`."""
    if semantic_fn is None:
        return None
    return _per_skeleton(
        cache, skeleton,
        lambda skel: call_semantic(semantic_fn, skel, evidence).float(), evidence)


def skeleton_id(f: MotionFile, skeleton: Skeleton) -> str:
    """The skeleton id of a file's windows (their ``meta["skeleton"]`` and
    balanced-sampling group): its source's, or, where the source names
    none (:attr:`~satagraph.datasets.sources.MotionFile.skeleton_named`),
    the dataset's name with the rig's joint count and a digest of its
    joint names and parents (``mixed:31j-1a2b3c4d``), so that a folder of
    several rigs has a group per rig."""
    if f.skeleton_named:
        return f.skeleton
    digest = hashlib.sha1(repr(_skeleton_key(skeleton)[:2]).encode()).hexdigest()[:8]
    return f"{f.skeleton}:{skeleton.num_joints}j-{digest}"


def _skeleton_key(skeleton: Skeleton) -> Tuple:
    """What the semantic embedding of a skeleton depends on."""
    return (tuple(skeleton.names), tuple(skeleton.parents.tolist()),
            tuple(skeleton.end_site.tolist()))


class EpochSampler(Sampler):
    r"""Yields ``(epoch, index)`` keys from another sampler's indices, so
    that datasets can draw per-epoch augmentation deterministically, in any
    worker process. Lightning calls :meth:`set_epoch` before every epoch.

    Args:
        sampler (Sampler): The sampler of indices.
    """

    def __init__(self, sampler: Sampler) -> None:
        self.sampler, self.epoch = sampler, 0

    def set_epoch(self, epoch: int) -> None:
        """The epoch of the next iteration."""
        self.epoch = int(epoch)

    def __iter__(self) -> Iterator[Tuple[int, int]]:
        return ((self.epoch, int(i)) for i in self.sampler)

    def __len__(self) -> int:
        return len(self.sampler)
