"""Skeleton augmentation: bone scaling (with paired ground truth for
retargeting), left/right mirroring, a new rest pose (the same motion under
another rest-pose convention), topology changes (drop a leaf chain, merge
two trunk segments, split a bone), and :class:`SkeletonAugment`, which
applies them at random on the fly."""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import List, Optional, Sequence, Tuple

import numpy as np

from satagraph.motion import Motion
from satagraph.ops.fk import forward_kinematics_numpy
from satagraph.ops.rotation_numpy import mean_rotation_numpy, yaw_matrix_numpy, yaw_of
from satagraph.sides import side_of, side_pairs, swap_side  # noqa: F401 (re-exported)
from satagraph.skeleton import Skeleton


def scale_bones(motion: Motion, low: float = 0.8, high: float = 1.2,
                seed: int = 0) -> Motion:
    r"""The same motion on a differently proportioned copy of its skeleton.

    Every bone offset is scaled per axis by a factor drawn uniformly from
    ``[low, high]`` (mirror pairs are not forced to match). Local rotations
    are kept, and the root trajectory is scaled by the ratio of the first
    frame's root heights above the lowest joint (leg length), so the result
    is the ground truth of retargeting :obj:`motion` onto the new skeleton.

    Args:
        motion (Motion): A motion (canonical or not, +Y up for the height).
        low (float): Smallest per-axis scale.
        high (float): Largest per-axis scale.
        seed (int): Random seed.
    """
    rng = np.random.default_rng(seed)
    skel = motion.skeleton
    scale = rng.uniform(low, high, size=skel.offsets.shape)
    scale[0] = 1.0
    offsets = skel.offsets * scale
    new = skel.replace(offsets=offsets)
    trans = motion.translations * scale[None]
    trans[:, 0] = motion.translations[:, 0]
    scaled = motion.with_(skeleton=new, translations=trans)
    ratio = _leg_ratio(motion.first_pose(), scaled.first_pose())
    trans[:, 0] = motion.translations[:, 0] * ratio
    return motion.with_(skeleton=new, translations=trans)


def _leg_ratio(old: np.ndarray, new: np.ndarray) -> float:
    """Ratio of root heights above the lowest joint."""
    def leg(pos: np.ndarray) -> float:
        return max(pos[0, 1] - pos[:, 1].min(), 1e-6)
    return leg(new) / leg(old)


def paired(motion: Motion, seed: int = 0, low: float = 0.8,
           high: float = 1.2) -> Tuple[Motion, Motion]:
    """(source, scaled ground truth) pair for retargeting evaluation."""
    return motion, scale_bones(motion, low, high, seed)


# ------------------------------------------------------------- rest pose
def rebase_rest(motion: Motion, frame: int = 0) -> Motion:
    r"""The same motion on a skeleton whose rest pose is frame
    :obj:`frame`'s pose, turned to face like frame 0 (the root keeps its
    world position).

    Rigs differ in their rest-pose convention (T-pose, A-pose, every bone
    along one axis), so one pose has different local rotations on each.
    With :math:`A_j` the global rotation of joint :math:`j` in the new rest
    pose (:func:`rebase_rotations`), offsets become :math:`A_{p(j)} o_j`
    and local rotations :math:`A_{p(j)} R_j A_j^\top`
    (:math:`A_{p(root)} = I`): global positions are unchanged, and every
    joint's rotation is the identity at :obj:`frame` except the root's
    heading change since frame 0.

    Args:
        motion (Motion): A motion (+Y up) with at least one frame.
        frame (int): The frame whose pose becomes the rest pose.
    """
    return set_rest_rotations(motion, rebase_rotations(motion, frame))


def rebase_rotations(motion: Motion, frame: int = 0) -> np.ndarray:
    r"""The global rest rotations :math:`A` of :func:`rebase_rest`; the
    rest is undone by :func:`set_rest_rotations` with :math:`A^\top`.

    Shapes:
        - **output**: :math:`(J, 3, 3)`
    """
    if not 0 <= frame < motion.num_frames:
        raise ValueError(f"rebase_rest: frame {frame} of a {motion.num_frames}-frame motion")
    return _pose_rest(motion, motion.rotations[frame].copy(), frame)


def mean_pose_rotations(motion: Motion, frames: Sequence[int], root_frame: int) -> np.ndarray:
    r"""Global rest rotations :math:`A` (as :func:`rebase_rotations`') of
    the mean pose of :obj:`frames`: each joint's local rotation averaged
    over them (:func:`~satagraph.ops.rotation_numpy.mean_rotation_numpy`),
    the root's taken from :obj:`root_frame` and turned to face like frame
    0. A walk's mean pose has its legs side by side where any one of its
    frames has one forward.

    Shapes:
        - **output**: :math:`(J, 3, 3)`
    """
    frames = np.asarray(frames, dtype=np.int64)
    if not len(frames) or frames.min() < 0 or frames.max() >= motion.num_frames:
        raise ValueError(f"mean_pose_rotations: frames outside a {motion.num_frames}-frame motion")
    pose = mean_rotation_numpy(motion.rotations[frames])
    pose[0] = motion.rotations[root_frame, 0]
    return _pose_rest(motion, pose, root_frame)


def _pose_rest(motion: Motion, pose: np.ndarray, frame: int) -> np.ndarray:
    """Global rotations of local :obj:`pose` :math:`(J, 3, 3)`, its root
    turned back by the body's turn from frame 0 to :obj:`frame`."""
    pose[0] = _turn_back(motion, frame) @ pose[0]
    return forward_kinematics_numpy(pose[None], motion.translations[frame:frame + 1],
                                    motion.skeleton.parents)[0][0]


#: Tilt of the root between frame 0 and the re-rest frame (degrees) above
#: which :func:`rebase_rotations` reads the turn from the body's facing:
#: the root's heading is no measure of it once the body has rolled or
#: pitched over (a dog lying on its side at frame 0, standing later).
TURN_TILT = 30.0


def root_tilted(motion: Motion, frame: int) -> bool:
    """Whether the root tilted by more than :data:`TURN_TILT` between frame
    0 and :obj:`frame` (+Y up): its heading then says nothing of how the
    body turned."""
    relative = motion.rotations[frame, 0] @ motion.rotations[0, 0].T
    return bool(np.degrees(np.arccos(np.clip(relative[1, 1], -1.0, 1.0))) > TURN_TILT)


def _turn_back(motion: Motion, frame: int) -> np.ndarray:
    """The rotation about +Y that undoes the body's turn from frame 0 to
    :obj:`frame`: the root's heading change, or where the root tilted in
    between (:func:`root_tilted`), the change of the facing of the
    left/right joint pairs (the root's heading then as a fallback for a
    skeleton without them)."""
    relative = motion.rotations[frame, 0] @ motion.rotations[0, 0].T
    up = np.array([0.0, 1.0, 0.0])
    if not root_tilted(motion, frame):
        return _heading(relative).T
    from satagraph.transforms.canonical import body_forward  # imports this module
    pos = motion.slice(0, frame + 1).global_positions()[[0, frame]]
    facing = body_forward(pos, motion.skeleton, up)
    if facing is None:
        return _heading(relative).T
    return yaw_matrix_numpy(yaw_of(facing[0]) - yaw_of(facing[1]))


def set_rest_rotations(motion: Motion, rest: np.ndarray) -> Motion:
    r"""The same motion on a skeleton whose rest pose has global joint
    rotations :obj:`rest` (in the rest frame of the old one).

    Offsets become :math:`A_{p(j)} o_j` and local rotations
    :math:`A_{p(j)} R_j A_j^\top` (:math:`A_{p(root)} = I`), so every frame
    keeps its global joint positions (and :math:`G_j A_j^\top` replaces the
    global rotation :math:`G_j`).

    Args:
        motion (Motion): The motion.
        rest (np.ndarray): Global rest rotations :math:`A`, :math:`(J, 3, 3)`.
    """
    parents = motion.skeleton.parents
    outer = np.where((parents < 0)[:, None, None], np.eye(3),
                     rest[np.where(parents < 0, 0, parents)])
    rotations = outer[None] @ motion.rotations @ np.swapaxes(rest, -1, -2)[None]
    translations = (outer[None] @ motion.translations[..., None])[..., 0]
    offsets = (outer @ motion.skeleton.offsets[..., None])[..., 0]
    return motion.with_(skeleton=motion.skeleton.replace(offsets=offsets),
                        rotations=rotations, translations=translations)


def axis_rest_rotations(skeleton: Skeleton) -> np.ndarray:
    r"""Rest rotations :math:`A_j` of the ``axis`` convention (files exported
    with joint orients baked in, e.g. Bandai and the dog): each joint's
    first child :math:`c` lies on its +X (:func:`set_rest_rotations` makes
    :math:`A_{p(c)} o_c` the new offsets), so the rest pose is a line.

    The roll about the bone is fixed, not drawn: the static features of a
    line show no roll for a single-child chain, so a decoder could not
    tell a random one. Local +Y is the rig's left (+X) made orthogonal to
    the bone, or its forward (+Z) for bones within 30 degrees of the
    left-right axis; for a downward leg the knee's hinge is then local +Y
    and forward +Z, as in Bandai's legs. Joints without a child, or with a
    zero-length first bone, keep their parent's rotation.

    Shapes:
        - **output**: :math:`(J, 3, 3)`
    """
    out = np.empty((skeleton.num_joints, 3, 3))
    for j in range(skeleton.num_joints):
        kids, p = skeleton.children[j], int(skeleton.parents[j])
        bone = skeleton.offsets[kids[0]] if kids else np.zeros(3)
        if np.linalg.norm(bone) < 1e-9:
            out[j] = out[p] if p >= 0 else np.eye(3)
            continue
        x = bone / np.linalg.norm(bone)
        ref = np.array([1.0, 0.0, 0.0]) if abs(x[0]) < np.cos(np.radians(30)) \
            else np.array([0.0, 0.0, 1.0])
        y = ref - (ref @ x) * x
        y /= np.linalg.norm(y)
        out[j] = np.stack([x, y, np.cross(x, y)])
    return out


def _heading(rotation: np.ndarray) -> np.ndarray:
    """The rotation about +Y that turns +Z where :obj:`rotation` turns it."""
    return yaw_matrix_numpy(yaw_of(rotation @ np.array([0.0, 0.0, 1.0])))


# ------------------------------------------------------------- mirroring
def mirror_pairs(skeleton: Skeleton) -> np.ndarray:
    r"""Index of each joint's mirror counterpart (itself for joints without
    a side or whose counterpart is missing), by
    :func:`~satagraph.transforms.canonical.lateral_pairs` (the names'
    sides, exporter tags such as ``__x7Q`` dropped).

    Shapes:
        - **output**: :math:`(J,)`
    """
    from satagraph.transforms.canonical import lateral_pairs

    left, right = lateral_pairs(skeleton.names)
    out = np.arange(skeleton.num_joints)
    out[left], out[right] = right, left
    return out


def _lone_sides(names: List[str], pair: np.ndarray) -> List[str]:
    """The names among :obj:`names` that carry a side (exporter tags
    dropped, as :func:`mirror_pairs` reads them) but have no counterpart
    in :obj:`pair`."""
    from satagraph.semantics.lexicon import drop_noise_tokens

    return [name for j, name in enumerate(names)
            if pair[j] == j and side_of(drop_noise_tokens(name)) is not None]


def mirror(motion: Motion, axis: int = 0) -> Motion:
    r"""Mirror a motion across the plane normal to :obj:`axis` (0: the
    character's left-right axis X of a canonical motion), swapping left and
    right joints by name.

    Global positions become the reflected originals, with the data of
    ``LeftFoot`` and ``RightFoot`` exchanged; joint order and names are
    kept, so mirroring twice gives the original motion back.

    Args:
        motion (Motion): The motion.
        axis (int): Axis reflected (0, 1 or 2).

    Raises:
        ValueError: A joint named for one side has no counterpart on the
            other (legs numbered across the body, ``Leg_L_01`` ... ``Leg_R_08``:
            its mirror image would carry left-named legs on its right), or
            the two sides' hierarchies differ.
    """
    reflect = np.eye(3)
    reflect[axis, axis] = -1.0
    skel = motion.skeleton
    pair = mirror_pairs(skel)
    lone = _lone_sides(skel.names, pair)
    if lone:
        raise ValueError(f"mirror: {len(lone)} joints named for one side have no "
                         f"counterpart on the other (first: {lone[0]!r})")
    parents = pair[np.maximum(skel.parents[pair], 0)]
    parents[0] = -1
    if not np.array_equal(parents, skel.parents):
        raise ValueError("mirror: left and right joints are not symmetric "
                         "in the hierarchy")
    new = skel.replace(offsets=skel.offsets[pair] @ reflect,
                       channels=[skel.channels[j] for j in pair],
                       end_site=skel.end_site[pair])
    rot = reflect @ motion.rotations[:, pair] @ reflect
    trans = motion.translations[:, pair] @ reflect
    return motion.with_(skeleton=new, rotations=rot, translations=trans)


def reverse_time(motion: Motion) -> Motion:
    r"""The motion played backwards: frame :math:`t` becomes frame
    :math:`T - 1 - t`, the skeleton and frame rate kept. A walk becomes a
    backward walk facing the same way (see
    :func:`~satagraph.datasets.reverse.reverse_text` for its caption);
    reversing twice gives the motion back.

    Args:
        motion (Motion): The motion.
    """
    return motion.with_(rotations=motion.rotations[::-1].copy(),
                        translations=motion.translations[::-1].copy())


# ------------------------------------------------------- topology changes
def _rebuild(motion: Motion, keep: List[int], parents: List[int],
             offsets: np.ndarray, rotations: np.ndarray,
             translations: np.ndarray, channels: list,
             names: Optional[List[str]] = None) -> Motion:
    """A motion on the joints :obj:`keep` (old indices, in the new order)
    with new parents (new indices) and data."""
    skel = motion.skeleton
    new = Skeleton(names=names or [skel.names[j] for j in keep],
                   parents=np.array(parents), offsets=offsets,
                   channels=channels, end_site=skel.end_site[keep])
    return motion.with_(skeleton=new, rotations=rotations,
                        translations=translations)


def _subset(motion: Motion, keep: List[int]) -> Motion:
    skel = motion.skeleton
    sub = skel.subset(keep)
    return motion.with_(skeleton=sub, rotations=motion.rotations[:, keep],
                        translations=motion.translations[:, keep])


def leaf_chains(skeleton: Skeleton, max_length: int = 3) -> List[List[int]]:
    """For every leaf, the joints of its unbranched chain (leaf last, at
    most :obj:`max_length`, never the root)."""
    out = []
    for leaf in np.flatnonzero(skeleton.is_leaf):
        chain = [int(leaf)]
        p = int(skeleton.parents[leaf])
        while (p > 0 and len(chain) < max_length
               and len(skeleton.children[p]) == 1):
            chain.insert(0, p)
            p = int(skeleton.parents[p])
        out.append(chain)
    return out


def drop_leaf_chain(motion: Motion, seed: int = 0, max_length: int = 3) -> Motion:
    r"""Remove a random leaf chain (up to :obj:`max_length` joints of an
    unbranched chain ending in a leaf: a tail tip, toes, a head end).
    The remaining joints keep their global positions exactly.

    Args:
        motion (Motion): The motion.
        seed (int): Random seed.
        max_length (int): Longest chain removed.
    """
    rng = np.random.default_rng(seed)
    chains = [c for c in leaf_chains(motion.skeleton, max_length)
              if len(c) < motion.num_joints]
    if not chains:
        return motion
    drop = set(chains[int(rng.integers(len(chains)))][-int(
        rng.integers(1, max_length + 1)):])
    keep = [j for j in range(motion.num_joints) if j not in drop]
    return _subset(motion, keep)


_TRUNK = re.compile(r"spine|neck|tail|back|chest|torso|vertebra|abdomen|"
                    r"thorax|lumbar|body", re.IGNORECASE)


def merge_candidates(skeleton: Skeleton) -> List[int]:
    """Joints that can be merged into their parent: trunk joints (spine,
    neck, tail, ... by name) with a trunk or root parent and children."""
    names, parents = skeleton.names, skeleton.parents
    return [j for j in range(1, skeleton.num_joints)
            if _TRUNK.search(names[j]) and skeleton.children[j]
            and all(skeleton.channels[c] for c in skeleton.children[j])
            and (parents[j] == 0 or _TRUNK.search(names[parents[j]]))]


def merge_segments(motion: Motion, seed: int = 0) -> Motion:
    r"""Merge two consecutive spine / neck / tail segments by removing the
    joint between them (see :func:`merge_candidates`).

    The removed joint's children hang from its parent: their rest offsets
    add up and their local rotations absorb the removed joint's. They get
    position channels carrying the per-frame offset, so every remaining
    joint keeps its global position and rotation exactly.

    Args:
        motion (Motion): The motion.
        seed (int): Random seed.
    """
    skel = motion.skeleton
    options = merge_candidates(skel)
    if not options:
        return motion
    j = options[int(np.random.default_rng(seed).integers(len(options)))]
    rot, trans = motion.rotations.copy(), motion.translations.copy()
    offsets, channels = skel.offsets.copy(), list(skel.channels)
    for c in skel.children[j]:
        offsets[c] = skel.offsets[j] + skel.offsets[c]
        trans[:, c] = trans[:, j] + np.einsum("tij,tj->ti", rot[:, j], trans[:, c])
        rot[:, c] = rot[:, j] @ rot[:, c]
        if channels[c] and not skel.has_position_channels[c]:
            channels[c] = ("Xposition", "Yposition", "Zposition") + channels[c]
    keep = [k for k in range(skel.num_joints) if k != j]
    remap = {old: new for new, old in enumerate(keep)}
    parents = [-1 if k == 0 else remap[skel.parents[k] if skel.parents[k] != j
                                       else skel.parents[j]] for k in keep]
    return _rebuild(motion, keep, parents, offsets[keep], rot[:, keep],
                    trans[:, keep], [channels[k] for k in keep])


def insert_joint(motion: Motion, seed: int = 0, low: float = 0.3,
                 high: float = 0.7) -> Motion:
    r"""Split a random bone in two by inserting a joint at a fraction
    (uniform in ``[low, high]``) of its length. The new joint has no
    rotation of its own (identity), so every original joint keeps its
    global position and rotation exactly.

    The new joint is named after the bone's child with a ``_split`` suffix
    and has the rotation channels of the bone's parent.

    Args:
        motion (Motion): The motion.
        seed (int): Random seed.
        low (float): Smallest fraction.
        high (float): Largest fraction.
    """
    skel = motion.skeleton
    rng = np.random.default_rng(seed)
    bones = [c for c in range(1, skel.num_joints)
             if np.linalg.norm(skel.offsets[c]) > 1e-8
             and not skel.has_position_channels[c]]
    if not bones:
        return motion
    c = bones[int(rng.integers(len(bones)))]
    frac = rng.uniform(low, high)
    p = int(skel.parents[c])
    order = list(range(c)) + [-1] + list(range(c, skel.num_joints))
    old_to_new = {old: new for new, old in enumerate(order) if old >= 0}
    parents = [-1 if k == 0 else old_to_new[p] if k == -1 else c if k == c
               else old_to_new[skel.parents[k]] for k in order]
    return _insert(motion, order, parents, c, frac)


def _insert(motion: Motion, order: List[int], parents: List[int], c: int,
            frac: float) -> Motion:
    """Data of :func:`insert_joint` (``-1`` in :obj:`order` is the new joint)."""
    skel = motion.skeleton
    p = int(skel.parents[c])
    src = [k if k >= 0 else c for k in order]
    offsets = skel.offsets[src].copy()
    trans = motion.translations[:, src].copy()
    rot = motion.rotations[:, src].copy()
    at = order.index(-1)
    offsets[at] = frac * skel.offsets[c]
    offsets[at + 1] = (1 - frac) * skel.offsets[c]
    trans[:, at] = frac * motion.translations[:, c]
    trans[:, at + 1] = (1 - frac) * motion.translations[:, c]
    rot[:, at] = np.eye(3)
    names = [skel.names[k] for k in src]
    names[at] = _unique(f"{skel.names[c]}_split", skel.names)
    channels = [skel.channels[k] for k in src]
    channels[at] = tuple(ch for ch in skel.channels[p] if ch.endswith(
        "rotation")) or ("Zrotation", "Xrotation", "Yrotation")
    end_site = skel.end_site[src].copy()
    end_site[at] = False
    new = Skeleton(names=names, parents=np.array(parents), offsets=offsets,
                   channels=channels, end_site=end_site)
    return motion.with_(skeleton=new, rotations=rot, translations=trans)


def _unique(name: str, names: Sequence[str]) -> str:
    taken, out, k = set(names), name, 2
    while out in taken:
        out, k = f"{name}{k}", k + 1
    return out


def restructure(motion: Motion, low: float = 0.8, high: float = 1.2,
                seed: int = 0) -> Motion:
    r"""The same motion on a skeleton of another structure and other
    proportions: a random leaf chain of up to two joints dropped
    (:func:`drop_leaf_chain`), a random bone split by a new joint
    (:func:`insert_joint`), then every bone scaled per axis in
    ``[low, high]`` (:func:`scale_bones`).

    The first two keep every remaining joint's global position exactly and
    the third keeps the local motion, so the result is the ground truth of
    retargeting :obj:`motion` onto a differently built skeleton (the
    "cross" setting of a retargeting table; :func:`scale_bones` alone gives
    the "internal" one). :func:`merge_segments` is left out: its bent
    segments carry per-frame offsets, which no rotation-only decoder can
    reproduce.

    Args:
        motion (Motion): A motion (+Y up for the height).
        low (float): Smallest per-axis bone scale.
        high (float): Largest per-axis bone scale.
        seed (int): Random seed.
    """
    drop, split, scale = (int(s) for s in np.random.default_rng(seed).integers(2 ** 31, size=3))
    motion = insert_joint(drop_leaf_chain(motion, drop, max_length=2), split)
    return scale_bones(motion, low, high, scale)


# --------------------------------------------------------- on the fly
@dataclass(frozen=True)
class AugmentConfig:
    r"""The one set of augmentation defaults (``data.augment`` keys; the
    defaults of :class:`SkeletonAugment` and
    :class:`~satagraph.data.dataset.WindowAugment` too): probabilities of
    bone scaling, mirroring, dropping a leaf chain, merging two trunk
    segments, inserting a joint and a new rest pose (half of them a random
    frame's pose, half the ``axis`` convention), the per-axis bone
    scale range and the longest leaf chain dropped. Only scaling and
    mirroring are on by default; a config switches the others on."""

    scale: float = 0.5
    mirror: float = 0.5
    drop: float = 0.0
    merge: float = 0.0
    insert: float = 0.0
    rest: float = 0.0
    low: float = 0.8
    high: float = 1.2
    max_drop: int = 2


#: The augmentation defaults (see :class:`AugmentConfig`).
AUGMENT = AugmentConfig()


@dataclass
class SkeletonAugment:
    r"""Random skeleton augmentation, applied on the fly.

    Each operation is applied with its probability (defaults:
    :class:`AugmentConfig`), in this order: bone
    scaling (:func:`scale_bones`), mirroring (:func:`mirror`), dropping a
    leaf chain (:func:`drop_leaf_chain`), merging two trunk segments
    (:func:`merge_segments`), inserting a joint (:func:`insert_joint`) and
    a new rest-pose convention: a random frame's pose (:func:`rebase_rest`)
    or, as often, every bone along its joint's +X
    (:func:`axis_rest_rotations`).

    Args:
        p_scale (float): Probability of scaling the bones.
        p_mirror (float): Probability of mirroring.
        p_drop (float): Probability of dropping a leaf chain.
        p_merge (float): Probability of merging two trunk segments.
        p_insert (float): Probability of inserting a joint.
        p_rest (float): Probability of a new rest pose (off by default).
        scale_range (tuple[float, float]): Per-axis bone scale range.
        max_drop (int): Longest leaf chain dropped.
        seed (int, optional): Seed of the generator drawing the decisions
            (``None``: fresh entropy).

    Example::

        augment = SkeletonAugment(p_mirror=0.5, p_drop=0.2, seed=0)
        motion = augment(motion)
    """

    p_scale: float = AUGMENT.scale
    p_mirror: float = AUGMENT.mirror
    p_drop: float = AUGMENT.drop
    p_merge: float = AUGMENT.merge
    p_insert: float = AUGMENT.insert
    p_rest: float = AUGMENT.rest
    scale_range: Tuple[float, float] = (AUGMENT.low, AUGMENT.high)
    max_drop: int = AUGMENT.max_drop
    seed: Optional[int] = None
    rng: np.random.Generator = field(init=False, repr=False)

    def __post_init__(self) -> None:
        for name in ("p_scale", "p_mirror", "p_drop", "p_merge", "p_insert", "p_rest"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ValueError(f"SkeletonAugment: {name} must be in [0, 1]")
        self.rng = np.random.default_rng(self.seed)

    def __call__(self, motion: Motion) -> Motion:
        """An augmented copy of :obj:`motion` (the input is not changed)."""
        def draw(p: float) -> Optional[int]:
            seed = int(self.rng.integers(2 ** 31))
            return seed if self.rng.random() < p else None

        if (s := draw(self.p_scale)) is not None:
            motion = scale_bones(motion, *self.scale_range, seed=s)
        if draw(self.p_mirror) is not None:
            try:
                motion = mirror(motion)
            except ValueError:
                pass  # asymmetric skeleton: leave it
        if (s := draw(self.p_drop)) is not None:
            motion = drop_leaf_chain(motion, s, self.max_drop)
        if (s := draw(self.p_merge)) is not None:
            motion = merge_segments(motion, s)
        if (s := draw(self.p_insert)) is not None:
            motion = insert_joint(motion, s)
        if (s := draw(self.p_rest)) is not None and motion.num_frames:
            motion = new_rest(motion, np.random.default_rng(s))
        return motion


def new_rest(motion: Motion, rng: np.random.Generator) -> Motion:
    """The same motion under another rest-pose convention: a random
    frame's pose (:func:`rebase_rest`) or, with probability 1/2, the
    ``axis`` convention (:func:`axis_rest_rotations`)."""
    frame = int(rng.integers(motion.num_frames))
    if rng.random() < 0.5:
        return set_rest_rotations(motion, axis_rest_rotations(motion.skeleton))
    return rebase_rest(motion, frame)
