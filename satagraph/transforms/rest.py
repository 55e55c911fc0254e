r"""Which rest pose a model is shown a rig in (``rest=``): the file's, its
first frame's, or (``"auto"``) the file's unless it is no pose of the body
(:func:`needs_rest`: a line, :func:`is_line_rest`, or a captured pose,
:func:`rest_asymmetry`), in which case its mean standing pose
(:func:`~satagraph.transforms.augment.mean_pose_rotations` over
:func:`~satagraph.transforms.ground.standing_frames`). Torch-free: the
data pipeline shows training clips by the same rule
(``data.preprocessing.rest``) as :mod:`satagraph.pipelines.inference`
shows inputs."""
from __future__ import annotations

from typing import Optional, Tuple

import numpy as np

from satagraph.motion import Motion
from satagraph.transforms.augment import (mean_pose_rotations, rebase_rotations,
                                          set_rest_rotations)
from satagraph.transforms.ground import standing_frames

#: How a rig is shown to a model
#: (:func:`~satagraph.pipelines.inference.retarget_canonical`'s ``rest``,
#: ``data.preprocessing.rest``): in the rest pose of its file, re-rested on
#: its first frame's pose, re-rested on its mean standing pose
#: (:func:`~satagraph.transforms.ground.standing_frames`) only where the
#: file's rest is a line or a captured pose (:func:`needs_rest`:
#: ``"auto"``) or always (``"standing"``), or in the pose ``"auto"`` does
#: not choose (``"alternate"``: the mean standing pose where ``"auto"``
#: keeps the file's, the first frame's where it re-rests), a second
#: reading's (:func:`second_rest`).
REST_MODES = ("auto", "file", "first-frame", "standing", "alternate")


def shown_rest(motion: Motion, rest: str) -> Tuple[Motion, Optional[np.ndarray]]:
    """A canonical motion in the rest pose :obj:`rest` (:data:`REST_MODES`)
    names, and the rest rotations that undo it (``None``: unchanged; a
    skeleton without frames keeps its file's rest); :func:`restore_rest`
    undoes it. A file's rest that faces away from +Z is shown turned
    about +Y to face it (:func:`rest_facing_turn`; not without frames)."""
    if rest in ("auto", "alternate"):
        needs = needs_rest(motion.skeleton)
        rest = (("standing" if needs else "file") if rest == "auto"
                else ("first-frame" if needs else "standing"))
    if not motion.num_frames:
        return motion, None
    if rest == "file":
        turn = rest_facing_turn(motion.skeleton)
        if turn is None:
            return motion, None
        new = np.repeat(turn[None], motion.num_joints, axis=0)  # the whole rest, rigidly
        return set_rest_rotations(motion, new), np.swapaxes(new, -1, -2)
    if rest == "first-frame":
        new = rebase_rotations(motion, 0)
    else:
        frames = standing_frames(motion)  # the first is the standing frame
        new = mean_pose_rotations(motion, frames, int(frames[0]))
    return set_rest_rotations(motion, new), np.swapaxes(new, -1, -2)


#: Degrees by which a rest pose shown as it is may face away from +Z
#: (:func:`rest_facing_turn`): the real rigs here face within 1.2.
FACING_DEGREES = 10.0


def rest_facing_turn(skeleton) -> Optional[np.ndarray]:
    r"""The turn about +Y that makes a canonical skeleton's rest pose face
    +Z (its body's facing, :func:`~satagraph.transforms.canonical.body_forward`),
    where it faces more than :data:`FACING_DEGREES` away; ``None`` where it
    does not, has no left/right pairs or is a line (:func:`is_line_rest`:
    no body to face anywhere). A model reads a rig's root
    rotation against its rest's +Z: a -Y-up rig (its rest facing -Z once
    stood up) or a +Y-up one facing +X or -Z was decoded walking backwards
    or sideways, its limbs stepping against its source's.

    Shapes:
        - **output**: :math:`(3, 3)`
    """
    from satagraph.ops.rotation_numpy import yaw_matrix_numpy, yaw_of
    from satagraph.transforms.canonical import body_forward
    if is_line_rest(skeleton):
        return None
    forward = body_forward(skeleton.rest_positions(), skeleton, np.array([0.0, 1.0, 0.0]))
    if forward is None or np.linalg.norm(forward) < 1e-9:
        return None
    yaw = float(yaw_of(forward))
    if abs(np.degrees(yaw)) <= FACING_DEGREES:
        return None
    return yaw_matrix_numpy(-yaw)


def second_rest(rest: str) -> str:
    """The rest pose of a second reading of a rig shown in :obj:`rest`
    (:data:`REST_MODES`): ``"alternate"`` for ``"auto"`` (and the
    reverse), ``"first-frame"`` for ``"standing"``, ``"standing"`` for
    the others."""
    return {"auto": "alternate", "alternate": "auto",
            "standing": "first-frame"}.get(rest, "standing")


def restore_rest(motion: Motion, undo: Optional[np.ndarray], skeleton) -> Motion:
    """A motion decoded on a skeleton :func:`shown_rest` re-rested, back on
    the original :obj:`skeleton` (unchanged when :obj:`undo` is ``None``)."""
    if undo is None:
        return motion
    return set_rest_rotations(motion, undo).with_(skeleton=skeleton)


def is_line_rest(skeleton, share: float = 0.8, degrees: float = 10.0) -> bool:
    r"""Whether a rest pose is a line rather than a pose: at least
    :obj:`share` of the bone length (each joint below the root to its first
    child; a root's offset is often a helper's, as Bandai's ``joint_Root``
    on the floor under the hips) lies
    within :obj:`degrees` of one direction, as exporters that bake joint
    orients into the offsets write it: along +X or -X (the dog's files, and
    Bandai's with the right side mirrored onto -X), or all one way along Y
    or Z (Reallusion's CC rigs point every bone up, +Y, legs included).
    A body's designed rest has bones both up (the spine) and down (the
    legs), and forward and back (a snake's or a tail's line is at most
    three quarters one way on the zoo's rigs)."""
    bones = np.array([skeleton.offsets[kids[0]] for kids in skeleton.children[1:] if kids])
    length = np.linalg.norm(bones, axis=1) if len(bones) else np.zeros(0)
    if not length.sum() > 1e-9:
        return False
    unit = bones / np.maximum(length, 1e-12)[:, None]
    ways = np.stack([np.abs(unit[:, 0]), unit[:, 1], -unit[:, 1], unit[:, 2], -unit[:, 2]],
                    axis=1) >= np.cos(np.radians(degrees))
    return bool((length @ ways).max() / length.sum() >= share)


def rest_asymmetry(skeleton, shortest: float = 0.05) -> Optional[float]:
    r"""How differently a rest pose bends its left and right sides: the mean
    over left/right joint pairs (matched by name,
    :func:`~satagraph.transforms.canonical.lateral_pairs`) of the difference
    of their bend angles (parent bone to each paired child bone), in
    degrees; bones shorter than :obj:`shortest` of the pose's extent (twist
    and share bones) are left out. About 0 for a designed rest (T, A,
    crouched, flat, a line), several degrees for a captured frame or an
    arbitrary pose; ``None`` without a measurable pair. Rotation-invariant:
    it needs no up axis or facing."""
    from satagraph.transforms.canonical import lateral_pairs
    pos = skeleton.rest_positions()
    least = shortest * float(np.linalg.norm(np.ptp(pos, axis=0)))
    left, right = lateral_pairs(skeleton.names)
    mate = dict(zip(left, right))
    diffs = []
    for l, r in zip(left, right):
        if skeleton.parents[l] < 0 or skeleton.parents[r] < 0:
            continue
        for cl in skeleton.children[l]:
            cr = mate.get(cl)
            if cr not in skeleton.children[r]:
                continue
            a = _bend(pos, skeleton.parents[l], l, cl, least)
            b = _bend(pos, skeleton.parents[r], r, cr, least)
            if a is not None and b is not None:
                diffs.append(abs(a - b))
    return float(np.mean(diffs)) if diffs else None


def _bend(pos: np.ndarray, parent: int, joint: int, child: int, least: float
          ) -> Optional[float]:
    """Angle (degrees) at :obj:`joint` between its parent and child bones
    (``None`` for a bone shorter than :obj:`least`)."""
    u, v = pos[parent] - pos[joint], pos[child] - pos[joint]
    nu, nv = float(np.linalg.norm(u)), float(np.linalg.norm(v))
    if min(nu, nv) < max(least, 1e-9):
        return None
    return float(np.degrees(np.arccos(np.clip(u @ v / (nu * nv), -1.0, 1.0))))


#: Left/right bend difference (degrees) above which a rest is a pose
#: (:func:`rest_asymmetry`): designed rests of the zoo's dialects and the
#: real rigs here measure 0-1.1, captured frames 8.5 and arbitrary poses
#: 12 (medians of the zoo's validation seeds).
POSED_REST_DEGREES = 3.0


def needs_rest(skeleton) -> bool:
    r"""Whether ``rest="auto"`` re-rests a skeleton (on its mean standing pose): its
    rest is a line (:func:`is_line_rest`) or a pose left and right bend
    differently (:func:`rest_asymmetry` above
    :data:`POSED_REST_DEGREES`). On the zoo's validation seeds
    (``benchmarks/rest_modes.py``) the built-in model reconstructs arbitrary
    rest poses at 3.1 % of the height re-rested against 7.5 % as read, and
    designed rests better as read."""
    if is_line_rest(skeleton):
        return True
    asym = rest_asymmetry(skeleton)
    return asym is not None and asym > POSED_REST_DEGREES


__all__ = ["REST_MODES", "shown_rest", "FACING_DEGREES", "rest_facing_turn", "second_rest",
           "restore_rest", "is_line_rest", "rest_asymmetry", "POSED_REST_DEGREES", "needs_rest"]
