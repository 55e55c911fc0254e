"""Sliding-window reconstruction and retargeting onto any skeleton."""
from __future__ import annotations

from dataclasses import replace
from typing import Callable, List, Optional, Tuple

import numpy as np
import torch

from satagraph.transforms.canonical import canonicalize, decanonicalize
from satagraph.data.clip import MotionClip
from satagraph.data.collate import collate_clips
from satagraph.data.features import DYNAMIC_CHANNELS, MotionFeatures, features_to_motion, motion_to_features
from satagraph.semantics.evidence import call_semantic, evidence_from_features
from satagraph.motion import Motion
from satagraph.ops.rotation import matrix_to_quaternion, quaternion_slerp, quaternion_to_matrix


def window_plan(num_frames: int, window: int = 64, overlap: int = 16) -> List[Tuple[int, int, int]]:
    r"""Windows covering a clip as ``(start, stop, keep_from)``: each later
    window's first :obj:`overlap` frames are cropped (``keep_from`` is the
    first frame of the window that is kept). A clip shorter than a window
    is one window."""
    if overlap >= window:
        raise ValueError(f"overlap ({overlap}) must be smaller than window ({window})")
    if num_frames <= window:
        return [(0, num_frames, 0)]
    plan, start, covered = [], 0, 0
    while covered < num_frames:
        start = min(start, num_frames - window)
        plan.append((start, start + window, covered))
        covered = start + window
        start = covered - overlap
    return plan


def target_clip(feats: MotionFeatures, num_frames: int,
                semantic: Optional[torch.Tensor]) -> MotionClip:
    """A clip of the target skeleton with its static features and no motion."""
    num = feats.skeleton.num_joints
    return MotionClip(dynamic=torch.zeros(num_frames, num, DYNAMIC_CHANNELS),
                      root=torch.zeros(num_frames, 4),
                      static=torch.from_numpy(feats.static).float(),
                      semantic=(semantic.float() if semantic is not None
                                else torch.zeros(num, 0)),
                      parents=torch.from_numpy(feats.skeleton.parents),
                      edge_attr=torch.from_numpy(feats.edge_attr).float(),
                      meta={"height": feats.height, "fps": feats.fps})


def static_features(motion: Motion) -> MotionFeatures:
    """Features of a target motion (only its static part is used)."""
    return motion_to_features(motion if motion.num_frames else motion.with_(
        rotations=np.broadcast_to(np.eye(3), (1, motion.num_joints, 3, 3)).copy(),
        translations=motion.skeleton.offsets[None].copy()))


def default_windows(module, window: Optional[int] = None,
                    overlap: Optional[int] = None) -> Tuple[int, int]:
    """The window the module was trained on (``meta["window"]``, else 64)
    and a quarter of it as overlap, unless given."""
    if window is None:
        window = int((getattr(module, "meta", None) or {}).get("window", 64))
    return window, window // 4 if overlap is None else overlap


@torch.no_grad()
def transfer(module, source: MotionFeatures, target: MotionFeatures,
             semantic: Optional[Callable] = None, window: Optional[int] = None,
             overlap: Optional[int] = None,
             batch_size: int = 16) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""Encode :obj:`source` window by window and decode onto :obj:`target`'s
    skeleton. Returns physical ``q [T, J_t, 6]``, ``r [T, 4]`` and contact
    probabilities ``c [T, J_t]`` for every source frame. The module is run
    in evaluation mode and given back in the mode it was in. :obj:`window`
    defaults to the module's training window and :obj:`overlap` to a
    quarter of the window (see :func:`default_windows`). :obj:`semantic`
    defaults to the module's own encoder (``module.embed``)."""
    window, overlap = default_windows(module, window, overlap)
    semantic = semantic if semantic is not None else getattr(module, "embed", None)
    was_training = module.training
    module.eval()
    try:
        return _transfer(module, source, target, semantic, window, overlap, batch_size)
    finally:
        module.train(was_training)


def _transfer(module, source: MotionFeatures, target: MotionFeatures,
              semantic: Optional[Callable], window: int, overlap: int,
              batch_size: int) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The window loop of :func:`transfer`."""
    sem_s = _embed(semantic, source)
    sem_t = _embed(semantic, target)
    plan = window_plan(source.num_frames, window, overlap)
    qs, rs, cs = [], [], []
    device = next(module.parameters()).device
    for i in range(0, len(plan), batch_size):
        chunk = plan[i:i + batch_size]
        src = collate_clips([source.to_clip(a, b, sem_s) for a, b, _ in chunk]).to(device)
        tgt = collate_clips([target_clip(target, b - a, sem_t) for a, b, _ in chunk]).to(device)
        out = module(src, tgt)
        num = target.skeleton.num_joints
        q = out["q"].view(-1, num, 6).cpu().double()
        c = torch.sigmoid(out["c"]).view(-1, num).cpu().double()
        r = out["r"].cpu().double()
        offset = 0
        for a, b, keep in chunk:
            sl = slice(offset + keep - a, offset + b - a)
            qs.append(q[sl]), rs.append(r[sl]), cs.append(c[sl])
            offset += b - a
    return (torch.cat(qs).numpy(), torch.cat(rs).numpy(), torch.cat(cs).numpy())


def _embed(semantic: Optional[Callable], feats: MotionFeatures) -> Optional[torch.Tensor]:
    """Semantic embedding of a skeleton with the evidence of its features
    (an embedder without an ``evidence`` keyword gets the skeleton only)."""
    if semantic is None:
        return None
    return call_semantic(semantic, feats.skeleton, evidence_from_features(feats))


def retarget_motion(module, source: Motion, target: Motion,
                    semantic: Optional[Callable] = None, window: Optional[int] = None,
                    overlap: Optional[int] = None, fps: Optional[float] = None) -> Motion:
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
    """
    _, canon = retarget_canonical(module, source, target, semantic, window, overlap, fps)
    return from_canonical(canon, source)


def from_canonical(canon: Motion, source: Motion) -> Motion:
    r"""A canonical retarget (:func:`retarget_canonical`) back on its rig:
    the target's axes, units and channel layout, at the source's frame rate
    and frame count."""
    canon = resample_frames(canon, source.fps, source.num_frames)
    return decanonicalize(canon, canon.transform, fps=source.fps)


def retarget_canonical(module, source: Motion, target: Motion,
                       semantic: Optional[Callable] = None, window: Optional[int] = None,
                       overlap: Optional[int] = None, fps: Optional[float] = None
                       ) -> Tuple[Motion, Motion]:
    r""":func:`retarget_motion` in the model's canonical frame (+Y up,
    metres, floor at 0, the model's frame rate): the canonical source and
    its retarget, whose :attr:`~Motion.transform` is the target's (what
    :func:`~satagraph.transforms.canonical.decanonicalize` undoes). What
    :mod:`satagraph.quality` measures."""
    fps = fps or float(getattr(module, "fps", 30.0))
    src_canon = canonicalize(source, fps=fps)
    tgt_canon = canonicalize(target, fps=fps)
    tgt = static_features(tgt_canon)
    q, r, _ = transfer(module, motion_to_features(src_canon), tgt, semantic, window, overlap)
    out_feats = replace(tgt, q=q, r=r, fps=fps, transform=tgt_canon.transform)
    return src_canon, features_to_motion(out_feats, q=q, r=r, use_positions=False)


def resample_frames(motion: Motion, fps: float, num_frames: int) -> Motion:
    r"""Exactly :obj:`num_frames` frames at :obj:`fps` from time 0 (slerp for
    rotations, linear interpolation for translations); frames past the end
    of :obj:`motion` hold its last frame.

    Resampling a clip to the model's rate and back can lose the last source
    frames (a 100-frame 60 fps clip has 50 frames at 30 fps, which give 99
    at 60 fps); this gives the source's frame count back.
    """
    if num_frames < 1 or motion.num_frames < 1:
        raise ValueError(f"cannot resample {motion.num_frames} frames to {num_frames}")
    if motion.num_frames == num_frames and abs(motion.fps - fps) < 1e-9:
        return motion
    last = motion.num_frames - 1
    times = np.minimum(np.arange(num_frames) * (motion.fps / fps), last)
    lo = np.minimum(np.floor(times).astype(np.int64), max(last - 1, 0))
    hi = np.minimum(lo + 1, last)
    w = times - lo
    quat = matrix_to_quaternion(torch.from_numpy(motion.rotations))
    weight = torch.from_numpy(w)[:, None].expand(num_frames, motion.num_joints)
    rot = quaternion_to_matrix(quaternion_slerp(quat[lo], quat[hi], weight)).numpy()
    t0, t1 = motion.translations[lo], motion.translations[hi]
    trans = t0 + w[:, None, None] * (t1 - t0)
    return motion.with_(rotations=rot, translations=trans, fps=float(fps))


def reconstruct_motion(module, motion: Motion, semantic: Optional[Callable] = None,
                       window: Optional[int] = None,
                       overlap: Optional[int] = None) -> Motion:
    """Encode and decode a motion on its own skeleton."""
    return retarget_motion(module, motion, motion, semantic, window, overlap)

