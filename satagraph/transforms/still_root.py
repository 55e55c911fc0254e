r"""Holding a decoded root still where the decoded body stands still.

A decoder can contradict itself: on a clip where a dog stands, the
built-in model predicts all four paws on the ground and barely moves them
relative to the body, yet moves the root at two heights a second
(``experiments/PRETRAIN.md`` section 24). Its pose says "standing", its
root velocity says "running", and the reconstruction drifts away.

:func:`settle_root` applies a zero-velocity update, as inertial navigation
does with a foot that is known to rest: a frame is *still*
(:func:`still_frames`) when some joint is predicted in contact and no
limb end (:func:`~satagraph.semantics.limb_ends`) moves horizontally
relative to the root faster than :data:`STILL_SPEED` character heights a
second anywhere within :data:`STILL_WINDOW` seconds. On still frames the
root's horizontal step is the one that keeps the contact joints where
they are; elsewhere, the decoder's. A walking body swings a limb end
relative to its root at about twice its travel speed, so walks, runs and
slow starts keep the decoded path; a body in the air (no contact) keeps it
too. The root's height, every rotation and so the facing stay as decoded.

What it cannot tell apart: a decoded sidestep whose legs barely step while
the root, rightly, moves looks the same as the standing dog, and is
stopped too (the zoo's validation sidesteps: 5.3 -> 22.8 % of the height
on average). The pipelines therefore apply it only on request
(``settle=True``, ``--settle``).

A retarget knows what a reconstruction cannot: its source, an input. Where
the source's root stands still, :func:`hold_still_source` keeps the
retarget's root still too (:func:`source_still_steps`), whatever the
decoder made of it; a sidestep's source moves, so it is left alone.
"""
from __future__ import annotations

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from satagraph.motion import Motion, character_height
from satagraph.semantics.limbs import limb_ends

#: Fastest horizontal speed of a limb end relative to the root, in
#: character heights a second, on a still frame.
STILL_SPEED = 0.5
#: Seconds around a frame over which every limb end must stay that slow.
STILL_WINDOW = 0.3
#: Contact probability above which a joint counts as on the ground.
CONTACT_PROB = 0.5
#: Fastest horizontal root speed of a source that stands still, in its
#: character heights a second (averaged over :data:`STILL_WINDOW`).
SOURCE_STILL_SPEED = 0.05


def _windows(x: np.ndarray, width: int) -> np.ndarray:
    """Centred windows of :obj:`width` samples of :obj:`x`, one per sample
    (edges repeated; :obj:`x` not empty).

    Shapes:
        - **x**: :math:`(T,)`, **output**: :math:`(T, W)`
    """
    width = max(width, 1)
    pad = width // 2
    return sliding_window_view(np.pad(x, (pad, width - 1 - pad), mode="edge"), width)


def _window_max(x: np.ndarray, width: int) -> np.ndarray:
    """The largest value of :obj:`x` within a centred window of
    :obj:`width` samples."""
    return _windows(x, width).max(-1) if len(x) else x


def _window_mean(x: np.ndarray, width: int) -> np.ndarray:
    """The mean of :obj:`x` over a centred window of :obj:`width` samples."""
    return _windows(x, width).mean(-1) if len(x) else x


def still_frames(positions: np.ndarray, contacts: np.ndarray, ends, fps: float,
                 height: float) -> np.ndarray:
    r"""Steps (frame ``t`` to ``t + 1``) on which the body stands still:
    some joint in contact at both frames (:data:`CONTACT_PROB`), and every
    limb end of :obj:`ends` horizontally slower relative to the root than
    :data:`STILL_SPEED` heights a second throughout :data:`STILL_WINDOW`
    seconds around it (+Y up).

    Shapes:
        - **positions**: :math:`(T, J, 3)`, **contacts**: :math:`(T, J)`
          probabilities
        - **output**: :math:`(T - 1,)` bool
    """
    ends = list(ends)
    if len(positions) < 2 or not ends:
        return np.zeros(max(len(positions) - 1, 0), dtype=bool)
    rel = positions[:, ends, :] - positions[:, :1, :]
    speed = np.linalg.norm(np.diff(rel[..., [0, 2]], axis=0), axis=-1).max(axis=1) * fps
    slow = _window_max(speed, int(round(STILL_WINDOW * fps)) | 1) < STILL_SPEED * height
    touching = (np.minimum(contacts[1:], contacts[:-1]) > CONTACT_PROB).any(axis=1)
    return slow & touching


def contact_steps(positions: np.ndarray, contacts: np.ndarray) -> np.ndarray:
    r"""The root's step from each frame to the next that keeps the joints
    in contact in place: minus the contact-weighted mean step of their
    positions relative to the root (zero where nothing touches).

    Shapes:
        - **positions**: :math:`(T, J, 3)`, **contacts**: :math:`(T, J)`
        - **output**: :math:`(T - 1, 3)`
    """
    weight = np.minimum(contacts[1:], contacts[:-1])
    weight = np.where(weight > CONTACT_PROB, weight, 0.0)
    rel = positions - positions[:, :1]
    step = (weight[..., None] * np.diff(rel, axis=0)).sum(axis=1)
    return -step / np.maximum(weight.sum(axis=1), 1e-12)[:, None]


def _with_steps(motion: Motion, where: np.ndarray, steps: np.ndarray) -> Motion:
    r""":obj:`motion` whose root takes the horizontal :obj:`steps` on the
    steps :obj:`where` marks and the decoded ones elsewhere, from its first
    frame's position.

    Shapes:
        - **where**: :math:`(T - 1,)` bool, **steps**: :math:`(T - 1, 3)`
    """
    root = motion.translations[:, 0]
    step = np.where(where[:, None], steps, np.diff(root, axis=0))
    translations = motion.translations.copy()
    translations[1:, 0, [0, 2]] = root[0, [0, 2]] + np.cumsum(step[:, [0, 2]], axis=0)
    return motion.with_(translations=translations)


def settle_root(motion: Motion, contacts: np.ndarray) -> Motion:
    r""":obj:`motion` with its root held where the body stands still (see
    the module's text): on :func:`still_frames`, the root's horizontal step
    is :func:`contact_steps`' (+Y up, canonical).

    Args:
        motion (Motion): A decoded motion, canonical.
        contacts (np.ndarray): The decoder's contact probability per frame
            and joint, in :obj:`motion`'s joint order.

    Shapes:
        - **contacts**: :math:`(T, J)`
    """
    if contacts.shape != (motion.num_frames, motion.num_joints):
        raise ValueError(f"settle_root: contacts must be [{motion.num_frames}, "
                         f"{motion.num_joints}], got {list(contacts.shape)}")
    if motion.num_frames < 2:
        return motion
    pos = motion.global_positions()
    ends = limb_ends(motion.skeleton).values()
    still = still_frames(pos, contacts, ends, motion.fps,
                         character_height(motion.skeleton, pos))
    if not still.any():
        return motion
    return _with_steps(motion, still, contact_steps(pos, contacts))


def source_still_steps(source: Motion) -> np.ndarray:
    r"""Steps (frame ``t`` to ``t + 1``) on which :obj:`source`'s root
    stands still: its horizontal speed, averaged over :data:`STILL_WINDOW`
    seconds, under :data:`SOURCE_STILL_SPEED` of its height a second (+Y
    up, canonical).

    Shapes:
        - **output**: :math:`(T - 1,)` bool
    """
    if source.num_frames < 2:
        return np.zeros(0, dtype=bool)
    root = source.translations[:, 0, [0, 2]]
    speed = np.linalg.norm(np.diff(root, axis=0), axis=-1) * source.fps
    width = int(round(STILL_WINDOW * source.fps)) | 1
    return _window_mean(speed, width) < SOURCE_STILL_SPEED * source.height()


def hold_still_source(motion: Motion, source: Motion) -> Motion:
    r""":obj:`motion` (a retarget of :obj:`source`, frame for frame) with no
    horizontal root step wherever the source's root stands still
    (:func:`source_still_steps`); its other steps, the root's height and
    every rotation as decoded (+Y up, canonical).

    Raises:
        ValueError: The two have different numbers of frames.
    """
    if motion.num_frames != source.num_frames:
        raise ValueError(f"hold_still_source: the retarget has {motion.num_frames} frames "
                         f"and its source {source.num_frames}")
    still = source_still_steps(source)
    if not still.any():
        return motion
    return _with_steps(motion, still, np.zeros((len(still), 3)))
