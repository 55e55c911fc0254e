"""Canonicalisation: +Y up, facing +Z and root xz at the origin at frame 0,
floor at y = 0, metres, one frame rate."""
from __future__ import annotations

from typing import List, Optional, Tuple

import numpy as np

from satagraph.transforms.rig_reading import axis_vector
from satagraph.motion import CanonicalTransform, Motion, RigSettings, require_motion
from satagraph.ops.rotation_numpy import (matrix_to_quaternion_numpy,
                                          quaternion_to_matrix_numpy,
                                          rotation_between_numpy, yaw_of)
from satagraph.sides import side_pairs
from satagraph.skeleton import Skeleton


def detect_up_axis(motion: Motion) -> str:
    r"""Guess the up axis of a motion (``"+Y"``, ``"-Z"``, ...) from its
    motion and pose; :func:`~satagraph.transforms.rig_reading.guess_up_axis` gives
    the confidence and the evidence too."""
    from satagraph.transforms.rig_reading import guess_up_axis

    return guess_up_axis(motion).axis


def lateral_pairs(names: List[str]) -> Tuple[List[int], List[int]]:
    """Indices of left joints and their right counterparts (by
    :func:`satagraph.sides.side_pairs`, matched case-blind with exporter
    noise such as ``__x7Q`` and the prefix every name shares removed)."""
    from satagraph.semantics.lexicon import drop_noise_tokens, shared_prefix
    cut = len(shared_prefix(names))
    return side_pairs([name[cut:] for name in names], key=drop_noise_tokens)


def lateral_forward(positions: np.ndarray, names: List[str],
                    up: np.ndarray) -> Optional[np.ndarray]:
    r"""Forward direction ``across x up`` with ``across`` the mean of
    left - right over the joint pairs found by name (not normalised);
    ``None`` for a skeleton without such pairs.

    Shapes:
        - **positions**: :math:`(..., J, 3)`
        - **output**: :math:`(..., 3)`
    """
    return _across_forward(positions, *lateral_pairs(names), up)


def _across_forward(positions: np.ndarray, left: List[int], right: List[int],
                    up: np.ndarray) -> Optional[np.ndarray]:
    """``across x up`` over the given pairs (``None`` without pairs)."""
    if not left:
        return None
    across = (positions[..., left, :] - positions[..., right, :]).mean(-2)
    return np.cross(across, up)


#: A left/right pair gives the facing (:func:`facing_pairs`) only if its
#: joints stand at least this share of the pose's extent apart: CMU's
#: ``LHipJoint`` sits on the hips.
FACING_PAIR_GAP = 0.02
#: The floor of a canonical motion: this percentile of its per-frame lowest
#: joint's height (a low one, so that a few frames of noise or a foot
#: pushed through the floor do not lift the body).
FLOOR_PERCENTILE = 2.0


def facing_pairs(skeleton: Skeleton, pose: np.ndarray) -> Tuple[List[int], List[int]]:
    r"""The left/right joint pairs that give a body's facing: of the pairs
    :func:`lateral_pairs` finds (helper joints left out:
    :func:`~satagraph.semantics.helper_joints`), those fewest hops from the root among the
    ones at least :data:`FACING_PAIR_GAP` of the pose's extent apart (the
    hips of a human or a dog, the legs' roots of a zoo rig); every pair
    where none is that far apart.

    Hands and feet swing with the stride: read from every pair, a walk's
    first frame turns its facing with the stride's phase (15 degrees on
    average, up to 50, on zoo bipeds and quadrupeds), and with it the
    facing frame of the clip's features; the pairs nearest the root move
    with the root.

    Shapes:
        - **pose**: :math:`(J, 3)`, the global joint positions of one frame
    """
    from satagraph.semantics import helper_joints
    left, right = lateral_pairs(skeleton.names)
    if left:  # Unreal's ik_foot_l / ik_foot_r: targets, not the body
        helpers = helper_joints(skeleton)
        pairs = [(a, b) for a, b in zip(left, right) if not (helpers[a] or helpers[b])]
        left, right = [a for a, _ in pairs], [b for _, b in pairs]
    if not left:
        return left, right
    left, right = np.asarray(left), np.asarray(right)
    gap = np.linalg.norm(pose[left] - pose[right], axis=-1)
    apart = gap >= FACING_PAIR_GAP * max(float(np.ptp(pose, axis=0).max()), 1e-9)
    if not apart.any():
        return left.tolist(), right.tolist()
    hops = np.minimum(skeleton.depth[left], skeleton.depth[right])
    keep = apart & (hops == hops[apart].min())
    return left[keep].tolist(), right[keep].tolist()


def body_forward(positions: np.ndarray, skeleton: Skeleton,
                 up: np.ndarray) -> Optional[np.ndarray]:
    r""":func:`lateral_forward` over the :func:`facing_pairs` (chosen on
    the first frame given): the body's facing, the one rule every reader of
    it uses (canonicalisation, re-rests of tilted clips, the retarget
    quality measures). ``None`` without left/right pairs.

    Shapes:
        - **positions**: :math:`(..., J, 3)`
        - **output**: :math:`(..., 3)`
    """
    first = positions.reshape(-1, *positions.shape[-2:])[0]
    return _across_forward(positions, *facing_pairs(skeleton, first), up)


def detect_forward(motion: Motion, up: np.ndarray) -> np.ndarray:
    r"""Horizontal facing direction at frame 0 (unit vector, world axes).

    From the left/right joint pairs nearest the root (:func:`body_forward`;
    pairs found by name: ``Left*``/``Right*``, ``L_``, ``.L``, ``_r``, ...):
    forward = across x up with across = left - right. Falls back to the
    root's local +Z axis.
    """
    forward = body_forward(motion.first_pose(), motion.skeleton, up)
    if forward is None or np.linalg.norm(forward - up * forward.dot(up)) < 1e-8:
        root = motion.rotations[0, 0] if motion.num_frames else np.eye(3)
        forward = root[:, 2]
    forward = forward - up * forward.dot(up)
    norm = np.linalg.norm(forward)
    return forward / norm if norm > 1e-8 else _orthogonal(up)


def _orthogonal(up: np.ndarray) -> np.ndarray:
    other = np.array([0.0, 0, 1]) if abs(up[2]) < 0.9 else np.array([1.0, 0, 0])
    vec = other - up * other.dot(up)
    return vec / np.linalg.norm(vec)


#: A moving root is folded into its only child (:func:`fold_root`) when the
#: child sits at least this share of the body's size away from it: a
#: ground reference that carries the body's travel along the floor, far
#: below the hips (Bandai's ``joint_Root`` in four of its takes,
#: Reallusion's ``RL_BoneRoot``), not a joint of the body that has one
#: child (the zoo's crab ``Root`` and fowl ``Bip01`` sit 0.7-5 % of the
#: body's size from their child; Bandai's and ``RL_BoneRoot``'s hips 60 %).
FLOOR_ROOT_DISTANCE = 0.25
#: ... or when the child sits on it, within this share of the body's size:
#: 3ds Max's ``Bip01`` carries the body and ``Bip01 Pelvis`` sits at its
#: origin (read as the root, a Bandai walk retargeted onto such a rig went
#: 0.84 of the distance it goes onto the same rig without ``Bip01``).
COINCIDENT_ROOT_DISTANCE = 1e-3


def fold_root(motion: Motion) -> Tuple[Motion, Optional[dict]]:
    r"""Fold a root joint above the hips into its one body child.

    Some rigs put a helper root above the hips: motionless (Bandai's
    ``joint_Root`` in most takes), carrying the body's travel along the
    floor while the hips ride on it (``RL_BoneRoot``, Bandai's run and dash
    takes; :data:`FLOOR_ROOT_DISTANCE`) or carrying the body with the hips
    at its origin (3ds Max's ``Bip01``; :data:`COINCIDENT_ROOT_DISTANCE`).
    Either way the hips become joint 0,
    as on every other rig, so that the root's features describe the body.
    Helper chains hanging from such a root beside the hips (Unreal's
    ``ik_foot_root`` and ``ik_hand_root``:
    :func:`~satagraph.semantics.helper_joints`) are set aside with it.
    Global positions of the remaining joints are unchanged.

    Returns:
        The motion, and a description of the removed root (name, channels,
        offset, frame 0's rotation and translation, the child's offset,
        ``carries``: whether it moved, and ``helpers``: the chains set aside,
        with frame 0's pose, or ``None``) or ``None``.
    """
    skel = motion.skeleton
    if motion.num_frames < 1 or skel.num_joints < 2:
        return motion, None
    child, aside = _body_below_root(skel)
    if child is None:
        return motion, None
    rot0, trans0 = motion.rotations[:, 0], motion.translations[:, 0]
    moves = np.ptp(rot0, axis=0).max() > 1e-9 or np.ptp(trans0, axis=0).max() > 1e-9
    # one frame cannot tell a still root from a moving one: its place must
    if (moves or motion.num_frames < 2) and not _redundant_root(motion, child):
        return motion, None
    keep = [j for j in range(1, skel.num_joints) if j not in set(aside)]
    rot = motion.rotations[:, keep].copy()
    trans = motion.translations[:, keep].copy()
    rot[:, 0] = rot0 @ motion.rotations[:, child]  # keep[0] is the child: the rest hang below
    trans[:, 0] = trans0 + np.einsum("tij,tj->ti", rot0, motion.translations[:, child])
    sub = skel.subset(keep)
    offsets = sub.offsets.copy()
    offsets[0] = trans[0, 0]
    removed = {"name": skel.names[0], "channels": skel.channels[0],
               "offset": skel.offsets[0].copy(), "rotation": rot0[0].copy(),
               "translation": trans0[0].copy(), "child_offset": skel.offsets[child].copy(),
               "carries": bool(moves), "helpers": _set_aside(motion, aside)}
    return motion.with_(skeleton=sub.replace(offsets=offsets), rotations=rot,
                        translations=trans), removed


def _body_below_root(skel: Skeleton) -> Tuple[Optional[int], List[int]]:
    """The root's one child that is not a helper chain's top, and the
    joints of the helper chains beside it; ``(None, [])`` where the root
    has several body children."""
    kids = list(skel.children[0])
    if len(kids) == 1:
        return kids[0], []
    from satagraph.semantics import helper_joints
    helpers = helper_joints(skel)
    below = {k: skel.subtree(k) for k in kids}
    body = [k for k in kids if not helpers[below[k]].all()]
    if len(body) != 1:
        return None, []
    return body[0], sorted(j for k in kids if k != body[0] for j in below[k])


def _set_aside(motion: Motion, joints: List[int]) -> Optional[dict]:
    """The helper joints :func:`fold_root` leaves out, as
    :func:`_restore_root` puts them back: where they were, their parents,
    rest and channels, and frame 0's local pose (held)."""
    if not joints:
        return None
    skel = motion.skeleton
    return {"index": np.array(joints), "names": [skel.names[j] for j in joints],
            "parents": skel.parents[joints].copy(), "offsets": skel.offsets[joints].copy(),
            "channels": [skel.channels[j] for j in joints],
            "end_site": skel.end_site[joints].copy(),
            "rotation": motion.rotations[0, joints].copy(),
            "translation": motion.translations[0, joints].copy()}


def _redundant_root(motion: Motion, child: int) -> bool:
    """Whether a moving root is no joint of the body: its body
    :obj:`child` sits :data:`FLOOR_ROOT_DISTANCE` of the body's size or
    more away from it, or within :data:`COINCIDENT_ROOT_DISTANCE` of it
    (the median distance: the norm of the child's own translation)."""
    size = float(np.ptp(motion.first_pose(), axis=0).max())
    gap = float(np.median(np.linalg.norm(motion.translations[:, child], axis=-1)))
    return size > 0 and not COINCIDENT_ROOT_DISTANCE * size < gap < FLOOR_ROOT_DISTANCE * size


def resample(motion: Motion, fps: float) -> Motion:
    r"""Resample to :obj:`fps` frames per second: slerp for rotations, linear
    interpolation for translations (:func:`resample_frames`). The first
    frame is kept; the last new frame is at or before the last old frame."""
    if abs(motion.fps - fps) < 1e-9 or motion.num_frames < 2:
        return motion.with_(fps=fps)
    count = int(np.floor((motion.num_frames - 1) * fps / motion.fps + 1e-9)) + 1
    return resample_frames(motion, fps, count)


def resample_frames(motion: Motion, fps: float, num_frames: int) -> Motion:
    r"""Exactly :obj:`num_frames` frames at :obj:`fps` from time 0 (slerp for
    rotations, linear interpolation for translations); frames past the end
    of :obj:`motion` hold its last frame.

    Resampling a clip to the model's rate and back can lose the last source
    frames (a 100-frame 60 fps clip has 50 frames at 30 fps, which give 99
    at 60 fps); this gives the source's frame count back.
    """
    import torch  # only here: reading a rig (evidence, inspect) stays torch-free

    from satagraph.ops.rotation import quaternion_slerp

    if num_frames < 1 or motion.num_frames < 1:
        raise ValueError(f"cannot resample {motion.num_frames} frames to {num_frames}")
    if motion.num_frames == num_frames and abs(motion.fps - fps) < 1e-9:
        return motion
    last = motion.num_frames - 1
    times = np.minimum(np.arange(num_frames) * (motion.fps / fps), last)
    lo = np.minimum(np.floor(times).astype(np.int64), max(last - 1, 0))
    hi = np.minimum(lo + 1, last)
    w = times - lo
    used, pick = np.unique(np.concatenate([lo, hi]), return_inverse=True)  # only these
    quat = torch.from_numpy(matrix_to_quaternion_numpy(motion.rotations[used]))
    weight = torch.from_numpy(w)[:, None].expand(num_frames, motion.num_joints)
    slerp = quaternion_slerp(quat[pick[:num_frames]], quat[pick[num_frames:]], weight)
    rot = quaternion_to_matrix_numpy(slerp.numpy())
    t0, t1 = motion.translations[lo], motion.translations[hi]
    trans = t0 + w[:, None, None] * (t1 - t0)
    return motion.with_(rotations=rot, translations=trans, fps=float(fps))


def canonicalize(
    motion: Motion,
    fps: Optional[float] = 30.0,
    up_axis: Optional[str] = None,
    unit_scale: Optional[float] = None,
    floor: bool = True,
    remove_root: bool = True,
    replace_bind: bool = True,
) -> Motion:
    r"""Bring a motion into the canonical frame used by the features.

    +Y up, the character facing +Z and its root at x = z = 0 at frame 0,
    the floor (:data:`FLOOR_PERCENTILE` of the per-frame lowest joint) at
    y = 0, metres, :obj:`fps` frames per second (``None`` keeps the source rate).
    Up axis and units are :obj:`up_axis` / :obj:`unit_scale` when given,
    else the motion's :attr:`~Motion.rig` settings (a file's declaration, or
    overrides from a manifest or the command line), else guessed by
    :func:`~satagraph.transforms.rig_reading.read_rig`; a low-confidence or
    undecided guess warns (:class:`~satagraph.transforms.rig_reading.RigReadingWarning`).
    The returned motion's :attr:`~Motion.transform` records what was done;
    :func:`decanonicalize` undoes it. The result declares itself canonical
    (:attr:`~Motion.rig`), so it is never re-guessed, also once written.
    A leading bind-pose frame (:mod:`~satagraph.transforms.bind_frame`:
    CMU's and CC_Base's exporters write one) is first given frame 1's pose
    unless :obj:`replace_bind` is ``False``.

    Args:
        motion (Motion): A motion as read (:func:`~satagraph.io.read_bvh`).
        fps (float, optional): Frame rate of the result (``None``: the source's).
        up_axis (str, optional): The source's up axis (``"+Z"``), instead of
            its declaration or a guess.
        unit_scale (float, optional): Source units to metres, likewise.
        floor (bool): Put the floor at y = 0.
        remove_root (bool): Fold a root above the hips into them
            (:func:`fold_root`).
        replace_bind (bool): Give a leading bind-pose frame frame 1's pose.

    Returns:
        Motion: The canonical motion, its :attr:`~Motion.transform` set.

    Raises:
        TypeError: :obj:`motion` is not a :class:`~satagraph.motion.Motion`.
    """
    from satagraph.transforms.bind_frame import replace_bind_frame
    from satagraph.transforms.rig_reading import read_body, read_rig, warn_reading

    require_motion(motion)
    if replace_bind:
        motion = replace_bind_frame(motion)
    if remove_root:  # folded once: the rig is read on the body
        motion, removed = fold_root(motion)
        reading = read_body(motion, up_axis, unit_scale)
    else:
        removed, reading = None, read_rig(motion, up_axis, unit_scale)
    warn_reading(reading, motion.source)
    up_name = reading.up.axis
    up_rot = rotation_between_numpy(axis_vector(up_name), np.array([0.0, 1.0, 0.0]))
    first = motion.slice(0, 1)  # the facing is frame 0's: no turned copy of the take
    forward = detect_forward(_apply_rotation(first, up_rot, 1.0, np.zeros(3), frame=up_rot),
                             np.array([0.0, 1.0, 0.0]))
    yaw = -float(yaw_of(forward))  # rotate forward onto +Z
    transform = CanonicalTransform(up_axis=up_name, up_rotation=up_rot, yaw=yaw,
                                   scale=reading.units.scale, source_fps=motion.fps,
                                   removed_root=removed,
                                   source_rig=_as_read(reading))
    out = _apply_rotation(motion, transform.rotation, transform.scale, np.zeros(3),
                          frame=up_rot)
    shift = np.zeros(3)
    if out.num_frames:
        shift[[0, 2]] = -out.translations[0, 0, [0, 2]]
        if floor:
            lowest = out.global_positions()[:, :, 1].min(axis=1)
            shift[1] = -float(np.percentile(lowest, FLOOR_PERCENTILE))
    transform.translation = shift
    out = out.with_(translations=_shift_root(out.translations, shift),
                    rig=CANONICAL_RIG)
    out.transform = transform
    return resample(out, fps) if fps else out


def _as_read(reading) -> RigSettings:
    """The reading of a source as settings: what :func:`decanonicalize`
    gives back, so that a result on the source's rig is read the same way
    (units left unset where they were the file's own, undecided)."""
    return RigSettings(reading.up.axis,
                       None if reading.units.kept else reading.units.scale,
                       declared=True)


#: What a canonical motion is: +Y up, metres (declared, never re-guessed).
CANONICAL_RIG = RigSettings("+Y", 1.0, declared=True)


def _shift_root(translations: np.ndarray, shift: np.ndarray) -> np.ndarray:
    out = translations.copy()
    out[:, 0] += shift
    return out


def _apply_rotation(motion: Motion, rot: np.ndarray, scale: float,
                    shift: np.ndarray, frame: Optional[np.ndarray] = None) -> Motion:
    r"""p' = scale * rot @ p + shift applied to the whole motion, with every
    joint's local axes turned by :obj:`frame` (default: kept): offsets and
    translations below the root become ``frame @ t``, local rotations
    ``frame @ R @ frame.T`` and the root's ``rot @ R @ frame.T``, so that
    the rest pose is turned with the motion (a +Z-up rig's rest stands up
    in +Y) while every global position is the same."""
    skel = motion.skeleton
    rotations = motion.rotations.copy()
    trans = motion.translations * scale
    offsets = skel.offsets * scale
    if frame is not None:
        _turn_local_axes(rotations, trans, frame)
        offsets[1:] = offsets[1:] @ frame.T
    rotations[:, 0] = rot @ rotations[:, 0]
    trans[:, 0] = trans[:, 0] @ rot.T + shift
    offsets[0] = offsets[0] @ rot.T
    return motion.with_(skeleton=skel.replace(offsets=offsets),
                        rotations=rotations, translations=trans)


#: Frames :func:`_turn_local_axes` turns at once: its temporaries are
#: those of this many frames, not of the take.
TURN_CHUNK = 2048


def _turn_local_axes(rotations: np.ndarray, translations: np.ndarray,
                     frame: np.ndarray) -> None:
    r"""Every joint's local axes turned by :obj:`frame`, in place: local
    rotations below the root ``frame @ R @ frame.T``, the root's
    ``R @ frame.T``, translations below the root ``frame @ t``; a chunk of
    :data:`TURN_CHUNK` frames at a time (the same values as all at once).

    Shapes:
        - **rotations**: :math:`(T, J, 3, 3)`; **translations**: :math:`(T, J, 3)`
        - **frame**: :math:`(3, 3)`
    """
    for start in range(0, len(rotations), TURN_CHUNK):
        part = slice(start, start + TURN_CHUNK)
        rotations[part, 1:] = frame @ rotations[part, 1:] @ frame.T
        translations[part, 1:] = translations[part, 1:] @ frame.T
    rotations[:, 0] = rotations[:, 0] @ frame.T


def decanonicalize(motion: Motion, transform: Optional[CanonicalTransform] = None,
                   fps: Optional[float] = None) -> Motion:
    r"""Undo :func:`canonicalize`: back to the source's axes, units, frame
    rate (unless :obj:`fps` is given) and, where one was removed, the
    motionless root joint."""
    tf = transform or motion.transform
    if tf is None:
        return motion
    back = _apply_rotation(motion.with_(
        translations=_shift_root(motion.translations, -tf.translation)),
        tf.rotation.T, 1.0 / tf.scale, np.zeros(3), frame=tf.up_rotation.T)
    back.transform = None
    back.rig = tf.source_rig
    back = resample(back, fps or tf.source_fps)
    if tf.removed_root is not None:
        back = _restore_root(back, tf.removed_root, axis_vector(tf.up_axis))
    return back


def _restore_root(motion: Motion, removed: dict, up: np.ndarray) -> Motion:
    """Put the root folded by :func:`fold_root` back: held at frame 0's
    transform, the hips moving below it, where it stood still in the
    source; where it moved, carrying the hips' travel (its rotation held)
    at its frame-0 level along :obj:`up` when the hips have position
    channels to rise and fall by (Bandai), the whole of it when they have
    none (``RL_BoneRoot``'s hips). Hips without position channels have the
    root carry them also where it stood still (a one-frame clip of a
    CC_Base rig, read as still): held, the travel put on the hips was
    dropped by the writer, and the written body walked in place."""
    skel = motion.skeleton
    num_frames = motion.num_frames
    rot0, trans0 = removed["rotation"], removed["translation"]
    rotations = motion.rotations.copy()
    translations = motion.translations.copy()
    offsets = np.concatenate([removed["offset"][None], skel.offsets])
    offsets[1] = removed["child_offset"]  # the hips' own rest, not frame 0's place
    rotations[:, 0] = rot0.T @ rotations[:, 0]
    root_trans = np.broadcast_to(trans0, (num_frames, 3))
    # hips without position channels cannot carry the travel: a file would drop it
    if removed.get("carries") or not skel.has_position_channels[0]:
        root_trans = translations[:, 0] - rot0 @ offsets[1]
        if skel.has_position_channels[0]:
            root_trans = root_trans - np.outer(root_trans @ up - trans0 @ up, up)
    translations[:, 0] = (translations[:, 0] - root_trans) @ rot0
    rot = np.concatenate([np.broadcast_to(rot0, (num_frames, 1, 3, 3)),
                          rotations], axis=1)
    trans = np.concatenate([root_trans[:, None], translations], axis=1)
    new = Skeleton(names=[removed["name"]] + skel.names,
                   parents=np.concatenate([[-1, 0], skel.parents[1:] + 1]),
                   offsets=offsets, channels=[removed["channels"]] + skel.channels,
                   end_site=np.concatenate([[False], skel.end_site]))
    motion = motion.with_(skeleton=new, rotations=rot, translations=trans)
    return motion if removed.get("helpers") is None else _helpers_back(motion,
                                                                       removed["helpers"])


def _helpers_back(motion: Motion, helpers: dict) -> Motion:
    """The helper chains :func:`fold_root` set aside, back in their places
    of the rig's joint order, held in frame 0's pose."""
    skel, aside = motion.skeleton, [int(j) for j in helpers["index"]]
    count = skel.num_joints + len(aside)
    kept = [j for j in range(count) if j not in set(aside)]
    names, channels = [""] * count, [()] * count
    parents, end_site = np.zeros(count, dtype=np.int64), np.zeros(count, dtype=bool)
    offsets = np.zeros((count, 3))
    rot = np.zeros((motion.num_frames, count, 3, 3))
    trans = np.zeros((motion.num_frames, count, 3))
    for new, old in enumerate(kept):
        names[old], channels[old] = skel.names[new], skel.channels[new]
        parents[old] = -1 if skel.parents[new] < 0 else kept[skel.parents[new]]
    offsets[kept], end_site[kept] = skel.offsets, skel.end_site
    rot[:, kept], trans[:, kept] = motion.rotations, motion.translations
    for i, old in enumerate(aside):
        names[old], channels[old] = helpers["names"][i], tuple(helpers["channels"][i])
        parents[old], end_site[old] = helpers["parents"][i], helpers["end_site"][i]
        offsets[old] = helpers["offsets"][i]
        rot[:, old], trans[:, old] = helpers["rotation"][i], helpers["translation"][i]
    rig = Skeleton(names=names, parents=parents, offsets=offsets, channels=channels,
                   end_site=end_site)
    return motion.with_(skeleton=rig, rotations=rot, translations=trans)
