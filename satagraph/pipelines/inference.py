"""Sliding-window reconstruction and retargeting onto any skeleton
(:func:`resample_frames` is :mod:`satagraph.transforms.canonical`'s)."""
from __future__ import annotations

import os
from dataclasses import replace
from functools import partial
from typing import (Any, Callable, Dict, Hashable, Iterable, List, Optional, Sequence, Tuple,
                    TypeVar, Union, overload)

import numpy as np
import torch

from satagraph.ops.rotation_numpy import yaw_matrix_numpy, yaw_of
from satagraph.transforms.augment import mirror_pairs, root_tilted
from satagraph.transforms.rest import (POSED_REST_DEGREES, REST_MODES, is_line_rest,  # noqa: F401
                                      needs_rest, rest_asymmetry, restore_rest, second_rest,
                                      shown_rest)
from satagraph.transforms.canonical import (body_forward, canonicalize, decanonicalize,
                                           resample_frames)
from satagraph.transforms.foot_plant import plant_feet
from satagraph.transforms.mirror_average import (average_readings, mirror_back, mirror_canonical,
                                                 place_reading)
from satagraph.transforms.still_root import hold_still_source, settle_root
from satagraph.transforms.carriage import CARRIAGE_MODES, carry_like, mean_carriage
from satagraph.transforms.ground import (STANDING_SHARE, ground_level,  # noqa: F401
                                         ground_retarget, stands, standing_frame,
                                         standing_frames)
from satagraph.data.clip import MotionClip
from satagraph.data.collate import collate_clips
from satagraph.data.dataset import data_facing_smooth, window_starts
from satagraph.data.features import DYNAMIC_CHANNELS, MotionFeatures, features_to_motion, motion_to_features
from satagraph.data.validate import (check_features, check_motion, check_shown_body,
                                     check_windows, default_windows)
from satagraph.semantics.evidence import call_semantic, evidence_from_features
from satagraph.motion import Motion, require_motion
from satagraph.pipelines.quality import lands_against, standing_shares

Kept = TypeVar("Kept")


def window_plan(num_frames: int, window: int = 64, overlap: int = 16) -> List[Tuple[int, int, int]]:
    r"""Windows covering a clip as ``(start, stop, keep_from)``: the
    training windows (:func:`~satagraph.data.dataset.window_starts` with
    stride ``window - overlap``), where each window's frames before the
    previous window's stop are cropped (``keep_from`` is the first frame of
    the window that is kept). A clip shorter than a window is one window."""
    check_windows(window, overlap)
    starts = window_starts(num_frames, window, window - overlap)
    keep = [0] + [start + window for start in starts[:-1]]
    return [(start, min(start + window, num_frames), k) for start, k in zip(starts, keep)]


def clip_frames(clip: MotionClip, start: int, stop: int) -> MotionClip:
    """Frames ``start:stop`` of :obj:`clip` (its static parts shared)."""
    meta = dict(clip.meta, start=int(clip.meta.get("start", 0)) + start)
    return replace(clip, dynamic=clip.dynamic[start:stop], root=clip.root[start:stop],
                   meta=meta)


@torch.no_grad()
def window_codes(autoencoder, clips: Sequence[MotionClip]) -> List[torch.Tensor]:
    r"""Per-frame codes of every clip by a SATA-RVQ, encoded in its
    training windows (:func:`default_windows`, :func:`window_plan`; all
    windows of all clips in one batch), each window's frames before the
    previous window's stop left out. The temporal layers' sinusoidal
    positions were learnt on that many frames: codes of a longer clip
    encoded whole are codes of an encoder past its positions.

    Shapes:
        - **output**: one :math:`(T_b, Q)` tensor per clip
    """
    window, overlap = default_windows(autoencoder)
    plans = [window_plan(clip.num_frames, window, overlap) for clip in clips]
    pieces = [clip_frames(clip, start, stop)
              for clip, plan in zip(clips, plans) for start, stop, _ in plan]
    device = next(autoencoder.parameters()).device
    codes = iter(autoencoder.codes(collate_clips(pieces).to(device)).split(
        [piece.num_frames for piece in pieces]))
    return [torch.cat([next(codes)[keep - start:] for start, _, keep in plan])
            for plan in plans]


def target_clip(feats: MotionFeatures, num_frames: int,
                semantic: Optional[torch.Tensor]) -> MotionClip:
    """A clip of the target skeleton with its static features and no motion
    (its height and leg length are those of :obj:`feats`' frames)."""
    num = feats.skeleton.num_joints
    return MotionClip(dynamic=torch.zeros(num_frames, num, DYNAMIC_CHANNELS),
                      root=torch.zeros(num_frames, 4),
                      static=torch.from_numpy(feats.static).float(),
                      semantic=(semantic.float() if semantic is not None
                                else torch.zeros(num, 0)),
                      parents=torch.from_numpy(feats.skeleton.parents),
                      edge_attr=torch.from_numpy(feats.edge_attr).float(),
                      meta={"height": feats.height, "leg": feats.leg_length,
                            "fps": feats.fps})


def static_features(motion: Motion) -> MotionFeatures:
    """Features of a target motion (only its static part is used), checked
    as training checks a file's (:func:`~satagraph.data.validate.check_features`:
    a body of some height)."""
    feats = motion_to_features(motion if motion.num_frames else motion.with_(
        rotations=np.broadcast_to(np.eye(3), (1, motion.num_joints, 3, 3)).copy(),
        translations=motion.skeleton.offsets[None].copy()))
    check_features(feats, motion.source or "<target>")
    return feats


def decoding_target(feats: MotionFeatures) -> MotionFeatures:
    r""":obj:`feats` of a target rig less the per-frame features a decoding
    never reads of it (``q``, ``x_rel``, ``v_q``, ``v_x``, ``r``: the
    decoder is shown its static part, height and leg length, and its
    semantic embedding reads ``x`` and ``c``): a reconstruction's target is
    the whole take.

    Shapes:
        - **output**: ``x`` :math:`(T, J, 3)` and ``c`` :math:`(T, J)` kept;
          the others :math:`(0, \dots)`
    """
    none = {key: getattr(feats, key)[:0].copy()  # a copy: a view would keep the take's
            for key in ("q", "x_rel", "v_q", "v_x", "r")}
    return replace(feats, **none)


@torch.no_grad()
def transfer(module, source: MotionFeatures, target: MotionFeatures,
             semantic: Optional[Callable] = None, window: Optional[int] = None,
             overlap: Optional[int] = None, batch_size: int = 16,
             memo: Optional["RigMemo"] = None, refine: int = 0,
             progress: Optional[Callable[[int], None]] = None
             ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""Encode :obj:`source` window by window and decode onto :obj:`target`'s
    skeleton. Returns physical ``q [T, J_t, 6]``, ``r [T, 4]`` and contact
    probabilities ``c [T, J_t]`` for every source frame. The module is run
    in evaluation mode and given back in the mode it was in. :obj:`window`
    defaults to the module's training window and :obj:`overlap` to a
    quarter of the window (see :func:`default_windows`). :obj:`semantic`
    defaults to the module's own encoder (``module.embed``).

    Args:
        module: A motion autoencoder (:func:`~satagraph.experiment.train.load_module`).
        source (MotionFeatures): The motion's features, canonical.
        target (MotionFeatures): Features of the target skeleton (its motion
            is not read).
        semantic (callable, optional): The semantic encoder of joint names.
        window (int, optional): Frames per window.
        overlap (int, optional): Frames two windows share, blended.
        batch_size (int): Windows decoded at once.
        memo (RigMemo, optional): Keeps :obj:`target`'s semantic embedding
            across calls (:class:`RigMemo`).
        refine (int): Steps that fit each window's latent to the source
            before it is decoded (``module.refine_latent``; 0: the
            encoder's latent).
        progress (callable, optional): Called as ``progress(n)`` after
            each batch with the :math:`n` windows it decoded (what a
            long refined take reports as it goes).

    Returns:
        (np.ndarray, np.ndarray, np.ndarray): ``q``, ``r`` and ``c``.

    Shapes:
        - **input:** source features of :math:`T` frames, a target of
          :math:`J_t` joints.
        - **output:** :math:`(T, J_t, 6)`, :math:`(T, 4)`, :math:`(T, J_t)`.
    """
    window, overlap = default_windows(module, window, overlap)
    semantic = semantic if semantic is not None else getattr(module, "embed", None)
    was_training = module.training
    module.eval()
    try:
        return _transfer(module, source, target, semantic, window, overlap, batch_size, memo,
                         refine, progress)
    finally:
        module.train(was_training)


def _transfer(module, source: MotionFeatures, target: MotionFeatures,
              semantic: Optional[Callable], window: int, overlap: int, batch_size: int,
              memo: Optional["RigMemo"] = None, refine: int = 0,
              progress: Optional[Callable[[int], None]] = None
              ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The window loop of :func:`transfer`: each batch's windows are
    written into the take's outputs as they are decoded, cross-faded where
    they overlap (:func:`cross_fade`; no batch outlives its step)."""
    sem_s = _embed(semantic, source)
    sem_t = _target_embedding(memo, semantic, target)
    plan = window_plan(source.num_frames, window, overlap)
    num = target.skeleton.num_joints
    q, r, c = (np.empty((source.num_frames, num, 6)), np.empty((source.num_frames, 4)),
               np.empty((source.num_frames, num)))
    device = next(module.parameters()).device
    done = 0
    for i in range(0, len(plan), batch_size):
        chunk = plan[i:i + batch_size]
        src = collate_clips([source.to_clip(a, b, sem_s) for a, b, _ in chunk]).to(device)
        tgt = collate_clips([target_clip(target, b - a, sem_t) for a, b, _ in chunk]).to(device)
        out = module(src, tgt, refine=refine) if refine else module(src, tgt)
        decoded = (out["q"].view(-1, num, 6).cpu().double(), out["r"].cpu().double(),
                   torch.sigmoid(out["c"]).view(-1, num).cpu().double())  # any dtype: bf16 too
        offset = 0
        for a, b, _ in chunk:
            for whole, part in zip((q, r, c), decoded):
                cross_fade(whole, part[offset:offset + b - a].numpy(), a, done)
            done, offset = b, offset + b - a
        if progress is not None:
            progress(len(chunk))
    return q, r, c


def cross_fade(whole: np.ndarray, window: np.ndarray, start: int, written: int) -> None:
    r"""Write a window decoded from frame :obj:`start` into the take's
    :obj:`whole` outputs, whose first :obj:`written` frames are decoded:
    the frames it shares with them are cross-faded from theirs into its
    own (weights rising linearly across the shared frames), the rest
    taken as it decoded them. Cut at the previous window's last frame,
    every seam was a jump of the pose (2-13 times a frame's usual change
    on real retargets, ``Bandai`` and fixture rigs).

    Shapes:
        - **whole**: :math:`(T, \dots)`, changed in place
        - **window**: :math:`(W, \dots)`
    """
    shared = max(0, written - start)
    fade = (np.arange(1, shared + 1) / (shared + 1)).reshape((-1,) + (1,) * (window.ndim - 1))
    whole[start:written] = (1.0 - fade) * whole[start:written] + fade * window[:shared]
    whole[written:start + len(window)] = window[shared:]


def _embed(semantic: Optional[Callable], feats: MotionFeatures) -> Optional[torch.Tensor]:
    """Semantic embedding of a skeleton with the evidence of its features
    (an embedder without an ``evidence`` keyword gets the skeleton only)."""
    if semantic is None:
        return None
    return call_semantic(semantic, feats.skeleton, evidence_from_features(feats))


def _target_embedding(memo: Optional["RigMemo"], semantic: Optional[Callable],
                      target: MotionFeatures) -> Optional[torch.Tensor]:
    """:func:`_embed` of a target's features, kept in :obj:`memo` per
    embedder (computed each time for one that cannot be a key)."""
    key = ("embedding", semantic)
    try:
        hash(key)
    except TypeError:  # an unhashable embedder object
        return _embed(semantic, target)
    return _kept(memo, target, key, lambda: _embed(semantic, target))


class RigMemo:
    r"""What a retarget computes of its target rig alone (canonicalised, its
    mirror image, shown in a rest pose with its static features and their
    semantic embedding, its ground level, how its character carries
    itself), kept for
    the next source retargeted onto the same rig: a folder of sources
    (``satagraph retarget SRC_DIR``, a :class:`Retargeter`) computes it
    once, not once per file (what that saves: :class:`Retargeter`). Each
    value is kept with the object it was computed from, held while kept,
    so that its ``id`` is never another's; a :func:`retarget_motion`
    without one computes everything afresh."""

    def __init__(self) -> None:
        self.kept: Dict[Tuple[int, Hashable], Tuple[Any, Any]] = {}

    def __call__(self, of: Any, key: Hashable, make: Callable[[], Kept]) -> Kept:
        """:obj:`make`'s value for :obj:`of` and :obj:`key`, made the first time."""
        if (id(of), key) not in self.kept:
            self.kept[(id(of), key)] = (of, make())
        return self.kept[(id(of), key)][1]


def _kept(memo: Optional[RigMemo], of: Any, key: Hashable, make: Callable[[], Kept]) -> Kept:
    """:obj:`memo`'s value (:class:`RigMemo`), or :obj:`make`'s, held by no
    one, without one (a long take's target features freed once read)."""
    return make() if memo is None else memo(of, key, make)


#: ``two_rests`` value: a second rest only for rigs without a mirror image
#: (``experiments/PRETRAIN.md`` section 40).
UNMIRRORED = "unmirrored"


def retarget_motion(module, source: Motion, target: Motion,
                    semantic: Optional[Callable] = None, window: Optional[int] = None,
                    overlap: Optional[int] = None, fps: Optional[float] = None,
                    rest: str = "auto", ground: bool = True, plant: bool = False,
                    settle: bool = False, still: bool = True, mirror: bool = False,
                    two_rests: Union[bool, str] = False, carriage: str = "auto",
                    memo: Optional[RigMemo] = None) -> Motion:
    r"""Retarget :obj:`source` onto :obj:`target`'s skeleton (any species).

    The result is in the target's own axes, units, rest pose, joint order and
    channel layout (motionless helper roots included), has the source's frame
    rate and number of frames, and follows the source's root path from the
    target's start position.

    Args:
        module: A trained :class:`~satagraph.lightning.MotionAutoencoderModule`.
        source (Motion): The motion to transfer (as read from a file).
        target (Motion): A motion (or zero-frame skeleton) of the target rig.
        semantic (Callable, optional): Skeleton -> semantic embedding, the
            one used in training; given the evidence of the source motion
            and of the target motion (or the target's rest pose) where it
            takes an ``evidence`` keyword.
        window (int, optional): Frames per window (default: the training
            window, see :func:`default_windows`).
        overlap (int, optional): Frames shared by consecutive windows
            (default: a quarter of the window).
        fps (float, optional): Feature frame rate (the model's, default 30).
        rest (str): ``"file"`` shows both skeletons to the model in their
            files' rest poses; ``"first-frame"`` re-rests each on its first
            frame's pose (:func:`~satagraph.transforms.augment.rebase_rest`)
            and undoes it on the output, so the written file keeps the
            target's own rest either way; ``"auto"`` (default) re-rests, on
            the mean pose of the frames in which the body stands
            (:func:`standing_frames`,
            :func:`~satagraph.transforms.augment.mean_pose_rotations`),
            only the skeletons whose rest is no designed pose (:func:`needs_rest`):
            a line (:func:`is_line_rest`: every bone along its joint's +X,
            as Bandai's and the dog's) or a pose whose left and right sides
            bend differently (a captured frame, an arbitrary pose);
            ``"standing"`` re-rests every skeleton so, and ``"alternate"``
            shows each in the pose ``"auto"`` does not choose
            (:data:`~satagraph.transforms.rest.REST_MODES`).
        ground (bool): Move the output up or down by one constant so that
            it stands as the target character does in :obj:`target`'s
            frames (its median lowest joint, in its heights), as the source
            does for a target without frames
            (:func:`~satagraph.transforms.ground.ground_retarget`: then each
            frame that would sink below the floor is raised onto it);
            ``False`` keeps the decoder's root height.
        plant (bool): Hold the limb ends still through their stances
            (:func:`~satagraph.transforms.foot_plant.plant_feet`).
        settle (bool): Hold the root still where the decoded body stands
            still (:func:`~satagraph.transforms.still_root.settle_root`):
            it stops a standing body that the decoder drives away, and
            also a sidestep whose decoded legs do not step (off by default,
            ``experiments/PRETRAIN.md`` section 24).
        still (bool): Keep the root still wherever the source's root
            stands still
            (:func:`~satagraph.transforms.still_root.hold_still_source`;
            ``experiments/PRETRAIN.md`` section 26); ``False`` keeps the
            decoder's root path there.
        mirror (bool): Also decode both rigs' left-right mirror images and
            average the readings (:func:`averaged_reading`; twice the
            model's time). A rig whose sides do not pair by joint name
            (:func:`~satagraph.transforms.mirror_average.mirror_canonical`) is
            read once.
        two_rests (bool or str): Also decode both rigs shown in a second
            rest pose (:func:`~satagraph.transforms.rest.second_rest` of
            :obj:`rest`: for ``"auto"``, the pose it does not choose) and
            average the readings (:func:`averaged_reading`; twice the
            model's time, four times with :obj:`mirror`); :data:`UNMIRRORED`:
            only for a rig without a mirror image.
        carriage (str): ``"auto"`` (default) carries the retarget as the
            target character carries itself in :obj:`target`'s frames
            wherever it never puts down a limb the character stands on
            there (:func:`carried_as_character`: a human's walk onto a
            quadruped held its forepaws up like hands); ``"always"``
            wherever :obj:`target` has frames; ``"never"`` keeps the
            decoder's carriage (:data:`CARRIAGE_MODES`).
        memo (RigMemo, optional): What is computed of :obj:`target` alone,
            kept across calls onto the same target (a folder of sources);
            the output is the same with or without it.
    """
    check_inputs(module, source, target)
    _, canon = retarget_canonical(module, source, target, semantic, window, overlap, fps,
                                  rest, ground, plant, settle, still, mirror, two_rests,
                                  carriage, memo)
    return from_canonical(canon, source)


class Retargeter:
    r"""One model and one target rig, ready for any number of sources: each
    call is :func:`retarget_motion` of its source onto :obj:`target` with
    the settings given here (the output the same to the bit), and what is
    computed of the target alone (canonicalised, its mirror image, shown in
    a rest pose with its static features and their semantic embedding, its
    ground level: :class:`RigMemo`) is computed for the first source only.
    ``satagraph retarget SRC_DIR`` runs through one
    (``benchmarks/retarget_many.py``: ten Bandai clips onto the dog's
    1531-frame clip in 0.58 of the CPU time of one :func:`retarget_motion`
    per clip).

    Args:
        module: A trained :class:`~satagraph.lightning.MotionAutoencoderModule`.
        target (Motion): A motion (or zero-frame skeleton) of the target
            rig, checked here (:func:`check_inputs`); keep it unchanged
            while the retargeter is used.
        semantic (Callable, optional): As in :func:`retarget_motion`.
        window (int, optional): As in :func:`retarget_motion`.
        overlap (int, optional): As in :func:`retarget_motion`.
        fps (float, optional): As in :func:`retarget_motion`.
        rest (str): As in :func:`retarget_motion`.
        ground (bool): As in :func:`retarget_motion`.
        plant (bool): As in :func:`retarget_motion`.
        settle (bool): As in :func:`retarget_motion`.
        still (bool): As in :func:`retarget_motion`.
        mirror (bool): As in :func:`retarget_motion`.
        two_rests (bool or str): As in :func:`retarget_motion`.
        carriage (str): As in :func:`retarget_motion`.
        memo (RigMemo, optional): Where the target's work is kept (default:
            a new one; retargeters of several models onto the same
            :obj:`target` object may share one).

    Returns:
        Called on a :class:`~satagraph.motion.Motion`, its retarget; on any
        iterable of them (a list, a generator reading files), the list of
        their retargets (every source checked before the first is
        retargeted).

    Example:
        >>> from satagraph.experiment.train import load_module
        >>> from satagraph.io import read_bvh, write_bvh
        >>> from satagraph.pipelines import Retargeter
        >>> onto_dog = Retargeter(load_module("builtin"), read_bvh("dog.bvh"))
        >>> for path, out in zip(paths, onto_dog([read_bvh(p) for p in paths])):
        ...     write_bvh(out, path.replace(".bvh", "_dog.bvh"))
    """

    def __init__(self, module, target: Motion, semantic: Optional[Callable] = None,
                 window: Optional[int] = None, overlap: Optional[int] = None,
                 fps: Optional[float] = None, rest: str = "auto", ground: bool = True,
                 plant: bool = False, settle: bool = False, still: bool = True,
                 mirror: bool = False, two_rests: Union[bool, str] = False,
                 carriage: str = "auto", memo: Optional[RigMemo] = None) -> None:
        check_module(module)
        check_target(target)
        check_settings(module, window, overlap, rest, two_rests, carriage)
        self.module, self.target = module, target
        self.options = dict(semantic=semantic, window=window, overlap=overlap, fps=fps,
                            rest=rest, ground=ground, plant=plant, settle=settle, still=still,
                            mirror=mirror, two_rests=two_rests, carriage=carriage)
        self.memo = RigMemo() if memo is None else memo

    @overload
    def __call__(self, source: Motion) -> Motion: ...

    @overload
    def __call__(self, source: Iterable[Motion]) -> List[Motion]: ...

    def __call__(self, source: Union[Motion, Iterable[Motion]]
                 ) -> Union[Motion, List[Motion]]:
        if isinstance(source, (Motion, str, bytes, os.PathLike)) or \
                not isinstance(source, Iterable):
            return self.one(source)
        sources, fps = list(source), getattr(self.module, "fps", None)
        for i, each in enumerate(sources):  # all refused before any is retargeted
            check_motion(require_motion(each, f"sources[{i}]"), each.source or f"sources[{i}]",
                         fps=fps)
        return [self._retarget(each) for each in sources]

    def one(self, source: Motion) -> Motion:
        """:func:`retarget_motion` of :obj:`source` with this retargeter's
        model, target, settings and memo (the model and target checked once,
        when it was made)."""
        check_motion(require_motion(source, "source"), fps=getattr(self.module, "fps", None))
        return self._retarget(source)

    def _retarget(self, source: Motion) -> Motion:
        """:func:`retarget_motion` of a checked :obj:`source`."""
        _, canon = retarget_canonical(self.module, source, self.target, memo=self.memo,
                                      **self.options)
        return from_canonical(canon, source)


def check_inputs(module, source: Motion, target: Optional[Motion] = None) -> None:
    """What ``retarget`` and ``reconstruct`` check on the command line,
    for both: a loaded model, a source that is a valid motion at the
    model's frame rate (:func:`~satagraph.data.validate.check_motion`: two
    frames or more, a skeleton of two joints or more, finite values) and a
    target skeleton
    that is one (:func:`~satagraph.data.validate.check_skeleton`).

    Raises:
        TypeError: A path or name where a model or a motion is expected.
        MotionValidationError: One line naming the motion and the problem.
    """
    from satagraph.data.validate import check_writable
    check_module(module)
    check_motion(require_motion(source, "source"), fps=getattr(module, "fps", None))
    if target is not None:
        check_target(target)
    else:
        check_writable(source)


def check_module(module) -> None:
    """A loaded model, not its path or name (:func:`check_inputs`).

    Raises:
        TypeError: One line saying how to load it.
    """
    if isinstance(module, (str, bytes, os.PathLike)):
        raise TypeError(f"module: expected a loaded model, got {module!r}; load it first: "
                        "satagraph.experiment.train.load_module(...)")


def check_target(target: Motion) -> None:
    """A target that is a skeleton (:func:`~satagraph.data.validate.check_skeleton`),
    shows a body (:func:`check_shown_body`) and can be written
    (:func:`check_inputs`).

    Raises:
        TypeError: A path or name where a motion is expected.
        MotionValidationError: One line naming the target.
    """
    from satagraph.data.validate import check_skeleton, check_writable
    check_skeleton(require_motion(target, "target"), target.source or "<target>")
    check_shown_body(target)
    check_writable(target)


def check_settings(module, window: Optional[int], overlap: Optional[int], rest: str,
                   two_rests: Union[bool, str], carriage: str = "auto",
                   refine: int = 0) -> None:
    """:func:`retarget_motion`'s settings, refused in one line before any
    work: a rest mode of :data:`REST_MODES`, a ``two_rests`` of
    :func:`averaged_reading`, a ``carriage`` of :data:`CARRIAGE_MODES`,
    windows that plan frames and a whole number of :obj:`refine` steps,
    0 or more, for a module that refines (``refine_latent``).

    Raises:
        ValueError: One line naming the setting.
    """
    if rest not in REST_MODES:
        raise ValueError(f"rest must be one of {list(REST_MODES)}, got {rest!r}")
    check_two_rests(two_rests)
    if carriage not in CARRIAGE_MODES:
        raise ValueError(f"carriage must be one of {list(CARRIAGE_MODES)}, got {carriage!r}")
    check_windows(*default_windows(module, window, overlap))
    if isinstance(refine, bool) or not isinstance(refine, int) or refine < 0:
        raise ValueError(f"refine is a whole number of steps, 0 or more, got {refine!r}")
    if refine and not hasattr(module, "refine_latent"):
        raise ValueError(f"refine: a {type(module).__name__} cannot fit its latent "
                         "(it has no refine_latent)")


def check_two_rests(two_rests: Union[bool, str]) -> None:
    """``two_rests`` is ``True``, ``False`` or :data:`UNMIRRORED` (one line)."""
    if two_rests not in (False, True, UNMIRRORED):
        raise ValueError(f"two_rests must be True, False or {UNMIRRORED!r}, got {two_rests!r}")


def from_canonical(canon: Motion, source: Motion) -> Motion:
    r"""A canonical retarget (:func:`retarget_canonical`) back on its rig:
    the target's axes, units and channel layout, at the source's frame rate
    and frame count."""
    canon = resample_frames(canon, source.fps, source.num_frames)
    return decanonicalize(canon, canon.transform, fps=source.fps)


def retarget_canonical(module, source: Motion, target: Motion,
                       semantic: Optional[Callable] = None, window: Optional[int] = None,
                       overlap: Optional[int] = None, fps: Optional[float] = None,
                       rest: str = "auto", ground: bool = True,
                       plant: bool = False, settle: bool = False,
                       still: bool = True, mirror: bool = False,
                       two_rests: Union[bool, str] = False, carriage: str = "auto",
                       memo: Optional[RigMemo] = None, refine: int = 0,
                       progress: Optional[Callable[[int], None]] = None
                       ) -> Tuple[Motion, Motion]:
    r""":func:`retarget_motion` in the model's canonical frame (+Y up,
    metres, floor at 0, the model's frame rate): the canonical source and
    its retarget, whose :attr:`~Motion.transform` is the target's (what
    :func:`~satagraph.transforms.canonical.decanonicalize` undoes), the
    source turned about +Y where :func:`source_features` turns it. What
    :mod:`satagraph.pipelines.quality` measures. With :obj:`mirror` and
    :obj:`two_rests`, the decoding is averaged with that of both rigs'
    mirror images and of both rigs in a second rest pose
    (:func:`averaged_reading`), then carried as the target character
    (:func:`carried_as_character`; never for a reconstruction). :obj:`memo`
    keeps what is computed of the target alone across calls
    (:class:`RigMemo`); :obj:`refine` steps fit each latent to the source
    first and :obj:`progress` hears of each batch of windows decoded, in
    every reading (:func:`transfer`)."""
    check_settings(module, window, overlap, rest, two_rests, carriage, refine)
    fps = fps or float(getattr(module, "fps", 30.0))
    same = target is source  # a reconstruction: canonicalized and mirrored once
    memo = None if same else memo
    source = canonicalize(source, fps=fps)
    target = source if same else _kept(memo, target, ("canonical", fps),
                                       lambda: canonicalize(target, fps=fps))
    reading = partial(read_once, module, semantic, window, overlap, fps, memo=memo,
                      refine=refine, progress=progress)
    src_canon, out, c = averaged_reading(reading, source, target, rest, mirror, two_rests, memo)
    out = settle_root(out, c) if settle else out
    out = hold_still_source(out, src_canon) if still else out
    level = (_kept(memo, target, "ground", partial(ground_level, target))
             if target.num_frames and (ground or not same) else None)
    grounded = once_per_motion(lambda m: ground_retarget(m, src_canon, target, level))
    if not same:  # a retarget: carried as the target character, checked as grounded
        out = carried_as_character(out, target, carriage, grounded, memo)
    if ground:  # the gate's grounded reading where it kept the motion
        out = grounded(out)
    return src_canon, plant_feet(out) if plant else out


def once_per_motion(fn: Callable[[Motion], Motion]) -> Callable[[Motion], Motion]:
    """:obj:`fn`, giving its last result again when called on the same
    motion object: a motion grounded to be checked by
    :func:`carried_as_character` and kept by it is not grounded twice."""
    last: List[Any] = [None, None]

    def call(motion: Motion) -> Motion:
        if last[0] is not motion:
            last[0], last[1] = motion, fn(motion)
        return last[1]
    return call


#: ``carriage="auto"`` carries a retarget whose
#: :func:`~satagraph.pipelines.quality.lands` is below this.
CARRIAGE_LANDS = 0.5


def carried_as_character(out: Motion, own: Motion, carriage: str = "auto",
                         grounded: Optional[Callable[[Motion], Motion]] = None,
                         memo: Optional[RigMemo] = None, paced: bool = True) -> Motion:
    r"""A canonical motion decoded onto a character, carried as the
    character carries itself in its own clip :obj:`own` (canonical, on the
    same rig; :func:`~satagraph.transforms.carriage.carry_like`), as
    :obj:`carriage` asks: ``"auto"`` where the motion, put on the floor by
    :obj:`grounded` (default: as it is), never puts down a limb the
    character stands on in :obj:`own` (:func:`~satagraph.pipelines.quality.lands`
    below :data:`CARRIAGE_LANDS`: the built-in model's human walks onto
    the dog and a zoo quadruped read 0.00, their forepaws held up like
    hands, its retargets onto humans 0.94-1.00), so that a motion that
    lands its limbs keeps its carriage (a stooped walk stays stooped) and
    one that does not stand is not asked to; ``"always"``; ``"never"``.
    A character without frames shows no carriage: the motion is kept. The
    result is not grounded; its root path is scaled with its leg length
    where :obj:`paced` (a retarget: ``carry_like``'s). :obj:`memo` keeps the
    character's carriage and landing shares (:class:`RigMemo`)."""
    if carriage == "never" or not own.num_frames:
        return out
    reference, shares = _kept(memo, own, "carriage",
                              lambda: (mean_carriage(own), standing_shares(own, own_floor=True)))
    if carriage == "auto":
        landing = lands_against(out if grounded is None else grounded(out), shares)
        if landing is None or landing >= CARRIAGE_LANDS:
            return out
    return carry_like(out, reference, paced)


def read_once(module, semantic: Optional[Callable], window: Optional[int],
              overlap: Optional[int], fps: float, rest: str, source: Motion,
              target: Motion, memo: Optional[RigMemo] = None, refine: int = 0,
              progress: Optional[Callable[[int], None]] = None
              ) -> Tuple[Motion, Motion, np.ndarray]:
    """One reading of a canonical source onto a canonical target by
    :obj:`module` (:func:`retarget_canonical`'s settings): the source as
    shown to the model (:func:`source_features`), the decoded motion on
    the target's rig (its rest restored) and the decoder's contact
    probabilities :math:`(T, J_t)`. :obj:`memo` keeps the target's shown
    features (:func:`target_features`) across calls."""
    src_canon, src = source_features(source, rest, facing_smooth_of(module))
    tgt, undo = _kept(memo, target, ("shown", rest), lambda: target_features(target, rest))
    q, r, c = transfer(module, src, tgt, semantic, window, overlap, memo=memo, refine=refine,
                       progress=progress)
    del src  # the source's per-frame features: the take's largest arrays, read
    out = features_to_motion(replace(tgt, q=q, r=r, fps=fps, transform=target.transform),
                             use_positions=False)
    del tgt, q, r
    return src_canon, restore_rest(out, undo, target.skeleton), c


def target_features(target: Motion, rest: str
                    ) -> Tuple[MotionFeatures, Optional[np.ndarray]]:
    """A canonical target as a decoding is shown it (:func:`decoding_target`
    of its :func:`static_features` in the rest pose :obj:`rest` names) and
    the rest rotations that undo that rest (:func:`shown_rest`)."""
    tgt_rest, undo = shown_rest(target, rest)
    return decoding_target(static_features(tgt_rest)), undo


def averaged_reading(reading: Callable, source: Motion, target: Motion, rest: str,
                     mirror: bool, two_rests: Union[bool, str] = False,
                     memo: Optional[RigMemo] = None) -> Tuple[Motion, Motion, np.ndarray]:
    r"""The mean of :obj:`reading`\ s (:func:`read_once` with the module
    and its settings bound) of a canonical source onto a canonical target
    in the rest pose :obj:`rest` and, with :obj:`two_rests`, in
    :func:`~satagraph.transforms.rest.second_rest` too (``True``: always;
    :data:`UNMIRRORED`: only where a rig has no mirror image, whether or
    not :obj:`mirror` reads it), and,
    with :obj:`mirror`, of both rigs' mirror images too
    (:mod:`~satagraph.transforms.mirror_average`; rigs without a mirror
    image are read as they are): the first reading's source, the averaged
    motion placed on it and the mean contact probabilities. :obj:`memo`
    keeps the target's mirror image across calls (:class:`RigMemo`).

    Shapes:
        - **contacts**: :math:`(T, J_t)`
    """
    check_two_rests(two_rests)
    twin_source = mirror_canonical(source) if mirror or two_rests == UNMIRRORED else None
    twin_target = twin_source if target is source else (
        _kept(memo, target, "mirror", lambda: mirror_canonical(target))
        if twin_source is not None else None)
    second = two_rests is True or (two_rests == UNMIRRORED and twin_target is None)
    pair = mirror_pairs(target.skeleton) if mirror and twin_target is not None else None
    src_canon, outs, contacts = None, [], []
    for shown_in in (rest, second_rest(rest)) if second else (rest,):
        shown, out, c = reading(shown_in, source, target)
        src_canon = shown if src_canon is None else src_canon
        outs.append(out if shown is src_canon else place_reading(out, shown, src_canon))
        contacts.append(c)
        if pair is not None:
            twin_src, twin_out, twin_c = reading(shown_in, twin_source, twin_target)
            outs.append(mirror_back(twin_out, twin_src, src_canon))
            contacts.append(twin_c[:, pair])
    return src_canon, average_readings(*outs), np.mean(contacts, axis=0)


def reconstruct_canonical(module, motion: Motion, semantic: Optional[Callable] = None,
                          mirror: bool = True, two_rests: Union[bool, str] = UNMIRRORED,
                          **options) -> Tuple[Motion, Motion]:
    r""":func:`retarget_canonical` of :obj:`motion` onto its own skeleton,
    the model's alone: the root is never held where the input stands
    (``still=False``: there the input is the answer). Unlike a retarget it
    averages the model's reading with that of the mirror image by default
    (:obj:`mirror`; ``experiments/PRETRAIN.md`` sections 37-37c: on
    validation clips the error falls to 0.83-0.91 of one reading's in the
    median). A rig without a mirror image (its sides do not pair) it reads
    in a second rest pose instead
    (:obj:`two_rests` :data:`UNMIRRORED`, the default: section 40, the
    spider's error 0.83 of one reading's; ``True``: both, always, which
    helped no other plan in section 39; ``False``: one rest).
    :obj:`options` are :func:`retarget_canonical`'s (``ground`` still on
    unless turned off)."""
    return retarget_canonical(module, motion, motion, semantic, still=False, mirror=mirror,
                              two_rests=two_rests, **options)


def facing_smooth_of(module) -> float:
    """The facing smoothing (seconds) of the features :obj:`module` was
    trained on (its config's ``data.preprocessing.facing_smooth``; 0 for a
    module without one)."""
    return data_facing_smooth((getattr(module, "meta", None) or {}).get("data"))


def source_features(canon: Motion, rest: str, facing_smooth: float = 0.0
                    ) -> Tuple[Motion, MotionFeatures]:
    """A canonical source and its features as the model is shown them: in
    the rest pose :obj:`rest` names (:func:`shown_rest`), with the facing
    axis of :func:`standing_facing_axis` where it has one, the motion then
    turned about +Y so that this axis points to +Z at frame 0 (as the
    features' own rule makes it), the facing smoothed over
    :obj:`facing_smooth` seconds (:func:`facing_smooth_of` the module)."""
    shown, _ = shown_rest(canon, rest)
    axis = standing_facing_axis(shown)
    if axis is not None:
        turn = yaw_matrix_numpy(-yaw_of(shown.rotations[0, 0] @ axis))
        canon, shown = turn_world(canon, turn), turn_world(shown, turn)
    feats = motion_to_features(shown, facing_axis=axis, facing_smooth=facing_smooth)
    check_features(feats, canon.source or "<source>")  # as training checks a file's
    return canon, feats


def standing_facing_axis(motion: Motion) -> Optional[np.ndarray]:
    r"""The root-local axis along the body's facing (the horizontal forward
    of its left/right joint pairs nearest the root,
    :func:`~satagraph.transforms.canonical.body_forward`) in the first frame in which it stands
    (:func:`standing_frame`), as the source's facing axis of its features
    (:func:`~satagraph.data.features.motion_to_features`) where the root
    tilted between frame 0 and that frame
    (:func:`~satagraph.transforms.augment.root_tilted`); else ``None``
    (the features' own rule: the axis pointing to +Z at frame 0), also
    without left/right pairs. A dog lying on its side at frame 0 gave an
    axis that points up or sideways once it stands, so its facing frames
    turned with every sway.

    Shapes:
        - **output**: :math:`(3,)`
    """
    if not motion.num_frames:
        return None
    pos = motion.global_positions()
    frame = int(np.argmax(stands(pos, motion.skeleton, motion.fps)))
    if not root_tilted(motion, frame):
        return None
    # across x up: already horizontal
    forward = body_forward(pos[frame], motion.skeleton, np.array([0.0, 1.0, 0.0]))
    if forward is None or np.linalg.norm(forward) < 1e-9:
        return None
    return motion.rotations[frame, 0].T @ (forward / np.linalg.norm(forward))


def turn_world(motion: Motion, turn: np.ndarray) -> Motion:
    """A motion turned as a whole about the world's origin by :obj:`turn`
    (its root's rotations and translations)."""
    rotations, translations = motion.rotations.copy(), motion.translations.copy()
    rotations[:, 0] = turn @ rotations[:, 0]
    translations[:, 0] = translations[:, 0] @ turn.T
    return motion.with_(rotations=rotations, translations=translations)


def reconstruct_motion(module, motion: Motion, semantic: Optional[Callable] = None,
                       window: Optional[int] = None, overlap: Optional[int] = None,
                       rest: str = "auto", ground: bool = False,
                       settle: bool = False, mirror: bool = True,
                       two_rests: Union[bool, str] = UNMIRRORED, refine: int = 0,
                       progress: Optional[Callable[[int], None]] = None) -> Motion:
    """Encode and decode a motion on its own skeleton (:obj:`rest`,
    :obj:`ground`, :obj:`settle`, :obj:`mirror` and :obj:`two_rests`: see
    :func:`retarget_motion`; ground
    is off by default here: on its own skeleton the decoder's root height
    is closer than a shift that matches the lowest joints of two
    different poses, and mirror on: see :func:`reconstruct_canonical`).
    The root is never held where the input stands still
    (:func:`reconstruct_canonical`): a reconstruction is the model's
    alone.

    Args:
        module: A motion autoencoder (:func:`~satagraph.experiment.train.load_module`).
        motion (Motion): The motion as read (any axes, units and rig).
        semantic (callable, optional): The semantic encoder of joint names
            (default: the module's own).
        window (int, optional): Frames per window (default: the module's).
        overlap (int, optional): Frames two windows share.
        rest, ground, settle, mirror, two_rests: See :func:`retarget_motion`.
        refine (int): Adam steps that fit each window's latent to the input
            before it is decoded
            (:meth:`~satagraph.lightning.MotionAutoencoderModule.refine_latent`;
            ``experiments/PRETRAIN.md`` section 56: 30 steps brought the
            validation clips' error of rigs never trained on to a third to a
            fifth, at about 0.1 s a step per 128 frames read on 2 CPU
            cores); 0, the default, decodes the encoder's latent, what the
            benchmarks' reconstruction rows measure.
        progress (callable, optional): Called as ``progress(n)`` as each
            batch of :math:`n` windows is decoded, in each reading (the
            mirror image's too): ``satagraph reconstruct --refine`` counts
            them on stderr.

    Returns:
        Motion: The decoded motion on the input's own rig, axes and units,
        at its frame rate.

    Raises:
        TypeError: A path or name where a model or a motion is expected.
        MotionValidationError: A motion unfit for the model (one line).
    """
    check_inputs(module, motion)
    _, canon = reconstruct_canonical(module, motion, semantic, window=window, overlap=overlap,
                                     rest=rest, ground=ground, settle=settle, mirror=mirror,
                                     two_rests=two_rests, refine=refine, progress=progress)
    return from_canonical(canon, motion)

