r"""Retarget quality without a ground truth, on any pair of skeletons.

A retarget has no paired truth when the target is another species, yet a
user can judge it at a glance: do the limbs step with the source's, does
the character travel as far for its size, do its feet touch the ground,
does an upright character stay upright? Each question is one number here,
computed the same way on the source and on the output:

* :func:`step_correlation`: per limb (left/right, front/hind, found by the
  semantic descriptions), the Pearson correlation of the limb end's forward
  displacement over 0.1 s in the character's facing frame, relative to the
  root. In step means clearly positive; chance is 0.
* :func:`root_travel`: the root's horizontal path length divided by the
  leg length (the root's median height above the lowest joint), so that a
  cat and a horse that walk alike travel alike.
* :func:`stride`: how far the limb ends swing fore and aft relative to the
  root, in leg lengths; a retarget that travels as far as its source on a
  shorter stride skates.
* :func:`ground_height`: the median over frames of the lowest joint's
  height, as a fraction of the character's height (0: feet on the floor).
* :func:`upright_fraction`: the share of frames whose head is above the
  hips (``None`` for a skeleton without a head).
* :func:`heading_gap`: the angle between where the body travels and where
  it faces (0 for a walk, 90 for a side-step); a retarget should keep the
  source's (``sideways``: the difference).
* :func:`posture`: whether each joint rides as high above the root as in
  the target character's own clip (1 minus the squared gaps over the
  reference's spread).
* :func:`lands`: whether each limb the target character stands on in its
  own clip comes down to the floor as often (the least share over those
  limbs).
* :func:`turn_rate`: how fast the body's facing turns over the clip, in
  degrees per second (2-3 for the zoo's forward walks and runs).
* :func:`pace_drift`: how much faster the root moves over the clip's last
  third than over its first (0 for a steady walk; a generator whose walks
  speed up reads above 0).

All of them take canonical motions (:func:`~satagraph.transforms.canonical.canonicalize`:
+Y up, metres, floor at 0); :func:`retarget_quality` compares a source with
its retarget.
"""
from __future__ import annotations

from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from satagraph.transforms.canonical import body_forward, canonicalize
from satagraph.transforms.ground import ground_level, levels, stands
from satagraph.data.features import motion_to_features
from satagraph.pipelines.motion_descriptor import contact_quality
from satagraph.semantics import LIMBS, describe_joints, limb_ends
from satagraph.motion import Motion, character_height, leg_length as motion_leg_length

#: Displacement interval of :func:`step_correlation` (frames at 30 fps, 0.1 s):
#: the stepping band (1-3 Hz) without frame-to-frame capture jitter.
LAG = 3


def _body_facing(canonical: Motion) -> Tuple[np.ndarray, Optional[np.ndarray]]:
    r"""Global joint positions of a canonical motion and its body's
    horizontal forward per frame (:func:`~satagraph.transforms.canonical.body_forward`
    about +Y; ``None`` without left/right pairs).

    Shapes:
        output: :math:`(T, J, 3)` and :math:`(T, 3)`.
    """
    pos = canonical.global_positions()
    return pos, body_forward(pos, canonical.skeleton, np.array([0.0, 1.0, 0.0]))


def facing_axis(canonical: Motion) -> Optional[np.ndarray]:
    r"""Root-local facing axis of a canonical motion: the mean over its
    frames of the horizontal forward direction (from the left/right joint
    pairs nearest the root, :func:`~satagraph.transforms.canonical.body_forward`)
    in the root's frame; ``None`` without left/right pairs.

    Shapes:
        output: :math:`(3,)`.
    """
    rot, pos = canonical.global_transforms()
    forward = body_forward(pos, canonical.skeleton, np.array([0.0, 1.0, 0.0]))
    if forward is None:
        return None
    forward /= np.maximum(np.linalg.norm(forward, axis=-1, keepdims=True), 1e-9)
    axis = np.einsum("tji,tj->i", rot[:, 0], forward)
    return axis / max(np.linalg.norm(axis), 1e-9)


def forward_tracks(canonical: Motion, averaged: bool = True) -> np.ndarray:
    r"""Forward coordinate of every joint relative to the root's ground
    projection, in the facing frame of :func:`facing_axis` (``averaged``) or
    of the first frame (as the features take it).

    Shapes:
        output: :math:`(T, J)`.
    """
    axis = facing_axis(canonical) if averaged else None
    return motion_to_features(canonical, facing_axis=axis).x[..., 2]


def limb_tracks(canonical: Motion, averaged: bool = True) -> Dict[str, np.ndarray]:
    r""":func:`forward_tracks` of each limb end the skeleton has, by limb
    name (:data:`~satagraph.semantics.LIMBS`).

    Shapes:
        values: :math:`(T,)`.
    """
    track = forward_tracks(canonical, averaged)
    return {limb: track[:, j] for limb, j in limb_ends(canonical.skeleton).items()}


def correlate(source: Dict[str, np.ndarray], output: Dict[str, np.ndarray],
              lag: Optional[int] = LAG) -> Dict[str, float]:
    """Per limb found on both, the Pearson correlation of the tracks'
    displacements over :obj:`lag` frames (``None``: of the tracks
    themselves); a still track gives ``nan``."""
    out = {}
    for limb in LIMBS:
        if limb in source and limb in output:
            frames = min(len(source[limb]), len(output[limb]))
            x, y = source[limb][:frames], output[limb][:frames]
            if lag:
                x, y = x[lag:] - x[:-lag], y[lag:] - y[:-lag]
            if x.std() < 1e-9 or y.std() < 1e-9:
                out[limb] = float("nan")
            else:
                out[limb] = float(np.corrcoef(x, y)[0, 1])
    return out


def mean_correlation(correlations: Dict[str, float]) -> float:
    """Mean over limbs; a still limb counts as 0 (not in step), no limb at
    all gives ``nan``."""
    if not correlations:
        return float("nan")
    return float(np.mean([0.0 if np.isnan(v) else v for v in correlations.values()]))


def step_correlation(source: Motion, output: Motion,
                     tracks: Optional[Tuple[Dict[str, np.ndarray], Dict[str, np.ndarray]]] = None
                     ) -> float:
    """:func:`mean_correlation` of the limb-end step correlations of two
    canonical motions at the same frame rate (:obj:`tracks`: their
    :func:`limb_tracks` where the caller has them)."""
    if tracks is None:
        tracks = limb_tracks(source), limb_tracks(output)
    return mean_correlation(correlate(*tracks))


def leg_length(canonical: Motion, positions: Optional[np.ndarray] = None) -> float:
    """:func:`satagraph.motion.leg_length` of a canonical motion (from its
    global joint positions where the caller has them)."""
    pos = canonical.global_positions() if positions is None else positions
    return motion_leg_length(pos, character_height(canonical.skeleton, pos))


def root_travel(canonical: Motion) -> float:
    """Horizontal path length of the root divided by :func:`leg_length`."""
    xz = canonical.global_positions()[:, 0, [0, 2]]
    return float(np.linalg.norm(np.diff(xz, axis=0), axis=-1).sum() / leg_length(canonical))


#: Shortest source :func:`stride` (leg lengths) that a stride ratio is read
#: against: a jump or a stand in place swings its limbs by noise alone.
MIN_STRIDE = 0.05


def stride(canonical: Motion, tracks: Optional[Dict[str, np.ndarray]] = None
           ) -> Optional[float]:
    """How far the limb ends swing fore and aft relative to the root, in
    leg lengths: the mean over limbs of the spread (10th to 90th
    percentile) of :func:`limb_tracks`. A walk whose feet stay planted
    swings them as far as the root travels in a stance; a retarget whose
    stride is shorter than its source's while it travels as far skates.
    ``None`` for a skeleton without limb ends (:obj:`tracks`: its
    :func:`limb_tracks` where the caller has them)."""
    tracks = limb_tracks(canonical) if tracks is None else tracks
    if not tracks:
        return None
    spread = [np.percentile(t, 90) - np.percentile(t, 10) for t in tracks.values()]
    return float(np.mean(spread) / leg_length(canonical))


#: Zero-padding factor of :func:`cadence`'s spectrum: its frequencies
#: :data:`CADENCE_PAD` times finer than one cycle per clip.
CADENCE_PAD = 16


def cadence(canonical: Motion, tracks: Optional[Dict[str, np.ndarray]] = None
            ) -> Optional[float]:
    """The gait's frequency in Hz: the median over limb ends of the
    dominant frequency of each :func:`limb_tracks` fore-aft track
    (Hann-windowed spectrum zero-padded :data:`CADENCE_PAD` times, the
    constant left out, so that a 1.5 Hz swing over 3 s reads 1.5, not the
    nearest multiple of 1/3 Hz). A walk's limbs swing once a stride, so a
    glide with no gait reads low. ``None`` for a skeleton without limb
    ends or a motion of fewer than 4 frames."""
    tracks = limb_tracks(canonical) if tracks is None else tracks
    if not tracks or canonical.num_frames < 4:
        return None
    peaks = []
    size = CADENCE_PAD * canonical.num_frames
    for track in tracks.values():
        track = track - track.mean()
        spectrum = np.abs(np.fft.rfft(track * np.hanning(len(track)), size))
        freqs = np.fft.rfftfreq(size, 1.0 / canonical.fps)
        peaks.append(freqs[1:][np.argmax(spectrum[1:])])
    return float(np.median(peaks))


def ground_height(canonical: Motion) -> float:
    """:func:`satagraph.transforms.ground.ground_level` of a canonical
    motion: its median lowest joint above the floor, in its heights."""
    return ground_level(canonical)


def head_index(canonical: Motion) -> Optional[int]:
    """The joint described as the head, if any."""
    for j, text in enumerate(describe_joints(canonical.skeleton)):
        if text == "head" or text.startswith("head,"):
            return j
    return None


def upright_fraction(canonical: Motion) -> Optional[float]:
    """Share of frames whose head is above the root (hips); ``None`` for a
    skeleton without a head."""
    head = head_index(canonical)
    if head is None:
        return None
    pos = canonical.global_positions()
    return float((pos[:, head, 1] > pos[:, 0, 1]).mean())


def trunk_bend(canonical: Motion) -> float:
    """The largest angle (degrees) by which the line from the root to the
    head (:func:`head_index`; the first frame's highest joint for a
    skeleton without one) turns away from where it pointed at frame 0: a
    bow's lean, a few degrees in a walk."""
    pos = canonical.global_positions()
    head = head_index(canonical)
    top = int(np.argmax(pos[0, :, 1])) if head is None else head
    line = pos[:, top] - pos[:, 0]
    line = line / np.maximum(np.linalg.norm(line, axis=-1, keepdims=True), 1e-9)
    return float(np.degrees(np.arccos(np.clip(line @ line[0], -1.0, 1.0))).max())


def knee_bend(canonical: Motion) -> Optional[float]:
    """The median bend (degrees; 0: straight) over the frames and hind legs
    of the joint between a leg's upper and lower segments (a knee; a
    bird's or a dog's hind leg too), the angle between the thigh's and the
    shin's directions; ``None`` for a skeleton without such a joint. A
    standing human reads 3-15, a walk 15-20, the zoo's crouched bipeds 40.
    """
    described = describe_joints(canonical.skeleton)
    parents = canonical.skeleton.parents
    knees = [j for j, text in enumerate(described)
             if "hind limb lower segment" in text and parents[j] >= 0
             and "hind limb upper segment" in described[parents[j]]]
    ends = {int(parents[c]): c for c in range(len(parents))
            if parents[c] in knees and "hind limb terminal segment" in described[c]}
    knees = [j for j in knees if j in ends]
    if not knees:
        return None
    pos = canonical.global_positions()
    upper = pos[:, knees] - pos[:, parents[knees]]
    lower = pos[:, [ends[j] for j in knees]] - pos[:, knees]
    cos = (upper * lower).sum(-1) / np.maximum(
        np.linalg.norm(upper, axis=-1) * np.linalg.norm(lower, axis=-1), 1e-9)
    return float(np.degrees(np.median(np.arccos(np.clip(cos, -1.0, 1.0)))))


def joint_raise(canonical: Motion) -> float:
    """The largest height any joint gains over its height at frame 0, in
    character heights: a hand raised to wave gains about half a height, a
    walk's feet a tenth."""
    pos = canonical.global_positions()
    height = character_height(canonical.skeleton, pos)  # Motion.height() without a second FK
    return float((pos[..., 1] - pos[:1, :, 1]).max() / max(height, 1e-9))


#: Travel (leg lengths) below which a motion has no direction to compare
#: with its facing (:func:`heading_gap`).
HEADING_TRAVEL = 0.5


def heading_gap(canonical: Motion) -> Optional[float]:
    r"""Signed degrees from the body's mean facing over the clip (its
    left/right pairs nearest the root,
    :func:`~satagraph.transforms.canonical.body_forward`) to the root's net
    horizontal travel, positive to the left (+X of a body facing +Z): about
    0 for a walk, 90 for a side-step; a body that walks crabwise shows the
    angle. ``None`` without left/right pairs, or under
    :data:`HEADING_TRAVEL` leg lengths of travel."""
    pos, facing = _body_facing(canonical)
    travel = pos[-1, 0] - pos[0, 0]
    if facing is None or (np.linalg.norm(travel[[0, 2]])
                          < HEADING_TRAVEL * leg_length(canonical, pos)):
        return None
    facing = (facing / np.maximum(np.linalg.norm(facing, axis=-1, keepdims=True), 1e-9)).sum(0)
    gap = np.arctan2(travel[0], travel[2]) - np.arctan2(facing[0], facing[2])
    return float(np.degrees((gap + np.pi) % (2 * np.pi) - np.pi))


#: Seconds averaged at each end of a clip by :func:`turn_rate` (about half
#: a stride, so that the sway of the hips does not count as a turn).
TURN_EDGE = 0.25


def turn_rate(canonical: Motion) -> Optional[float]:
    r"""Signed degrees per second by which the body's facing (its left/right
    pairs nearest the root, :func:`~satagraph.transforms.canonical.body_forward`)
    turns from the clip's start to its end, positive to the left: the
    unwrapped facing yaw averaged over :data:`TURN_EDGE` seconds at each end.
    ``None`` without left/right pairs or for a clip under twice that long."""
    _, facing = _body_facing(canonical)
    edge = max(1, int(round(TURN_EDGE * canonical.fps)))
    if facing is None or canonical.num_frames < 2 * edge:
        return None
    yaw = np.unwrap(np.arctan2(facing[:, 0], facing[:, 2]))
    seconds = (canonical.num_frames - edge) / canonical.fps
    return float(np.degrees(yaw[-edge:].mean() - yaw[:edge].mean()) / seconds)


#: Seconds below which a clip has no pace drift to read (:func:`pace_drift`):
#: each third should hold about a stride.
DRIFT_SECONDS = 1.5
#: Leg lengths the root must cover in a clip's first third for
#: :func:`pace_drift` to read it (a standing body has no pace).
DRIFT_TRAVEL = 0.25


def pace_drift(canonical: Motion) -> Optional[float]:
    r"""How much faster the root moves horizontally over the clip's last
    third than over its first, as a share of the first (``0.2``: a fifth
    faster at the end; 0 for a steady walk, below 0 for one that slows).
    ``None`` for a clip under :data:`DRIFT_SECONDS` or one whose root
    travels under :data:`DRIFT_TRAVEL` leg lengths in its first third."""
    if canonical.num_frames < DRIFT_SECONDS * canonical.fps:
        return None
    pos = canonical.global_positions()
    step = np.linalg.norm(np.diff(pos[:, 0, [0, 2]], axis=0), axis=-1)
    third = len(step) // 3
    first, last = step[:third].sum(), step[-third:].sum()
    if first < DRIFT_TRAVEL * leg_length(canonical, pos):
        return None
    return float(last / first - 1.0)


def _sideways(source: Motion, output: Motion) -> Optional[float]:
    """Degrees between the output's :func:`heading_gap` and the source's."""
    a, b = heading_gap(source), heading_gap(output)
    if a is None or b is None:
        return None
    return float(abs((b - a + 180.0) % 360.0 - 180.0))


def most_active(motion: Motion, frames: int) -> Motion:
    """The :obj:`frames`-long slice of :obj:`motion` (at its own frame rate)
    whose limb ends move most."""
    if motion.num_frames <= frames:
        return motion
    tracks = limb_tracks(canonicalize(motion, fps=None))
    if not tracks:
        return motion.slice(0, frames)
    speed = np.abs(np.diff(np.stack(list(tracks.values()), axis=1), axis=0)).sum(axis=1)
    start = int(np.argmax(np.convolve(speed, np.ones(frames - 1), mode="valid")))
    return motion.slice(start, start + frames)


def contact(canonical: Motion) -> Tuple[float, float]:
    """:func:`foot_slide` and :func:`hover` of a canonical motion from one
    feature pass (:func:`~satagraph.pipelines.motion_descriptor.contact_quality`)."""
    return contact_quality(motion_to_features(canonical))


def foot_slide(canonical: Motion) -> float:
    """How fast the joints near the ground slide, in heights per second
    (:func:`contact`): 0.02-0.12 for the zoo's and Bandai's walks and runs,
    whose planted feet stay."""
    return contact(canonical)[0]


def hover(canonical: Motion) -> float:
    """How high the body keeps off its floor: the mean over frames of the
    lowest joint's height above the motion's floor, in heights
    (:func:`contact`): at most 0.01 for captured walks; a decoded body that
    bobs reads more, wherever the motion was grounded."""
    return contact(canonical)[1]


def posture(canonical: Motion, reference: Motion) -> Optional[float]:
    """How the joints of a motion are carried against how the same rig
    carries them where it stands in :obj:`reference` (its own clip,
    :func:`~satagraph.transforms.ground.standing_frames`: a dog's clip
    that lies most of the time still shows how it stands): one minus the
    squared gaps, over joints, between each joint's median height above the
    root in the two, over the spread of the reference's heights about their
    mean (``None`` for rigs that differ or a reference without height to
    compare). 1 where each joint rides where the character's own clip has
    it (0.99-1.00 for the built-in model's retargets onto real humans), less
    the further any rides from there, below 0 for a retarget with one leg
    pointing up (-0.59), 0.75-0.85 for a quadruped carrying its forepaws a
    quarter of its height off the floor, as a human carries its hands. (A
    correlation over joints read those 0.37 and 0.95-0.97: it forgives any
    scale and offset of the heights, and the spine's long spread outweighs
    two legs.)"""
    if canonical.skeleton.names != reference.skeleton.names:
        return None
    ref, standing = _standing(reference)
    a, b = _carried(canonical.global_positions()), _carried(ref[standing])
    spread = float(((b - b.mean()) ** 2).sum())
    if spread < 1e-18:
        return None
    return float(1.0 - ((a - b) ** 2).sum() / spread)


def _carried(positions: np.ndarray) -> np.ndarray:
    """Each joint's median height above the root :math:`(J,)` of global
    positions :math:`(T, J, 3)`."""
    return np.median(positions[..., 1] - positions[:, :1, 1], axis=0)


#: How near the floor (y = 0), in character heights, a limb's lowest point
#: comes where it lands (:func:`landing_shares`) ...
LANDING_HEIGHT = 0.05
#: ... and the share of its standing frames in which the reference lands a
#: limb for :func:`lands` to read that limb.
LANDS_SHARE = 0.5


def landing_shares(canonical: Motion, frames: Optional[np.ndarray] = None,
                   positions: Optional[np.ndarray] = None) -> Dict[str, float]:
    r"""Per limb end the skeleton has (:func:`~satagraph.semantics.limb_ends`,
    the limbs of :func:`limb_tracks`), the share of frames (of :obj:`frames`
    only, where given) in which the limb's lowest point (its end and the
    joints below it) is within :data:`LANDING_HEIGHT` character heights of
    the floor (y = 0); from the global :obj:`positions` where the caller
    has them.

    Shapes:
        - **frames**: :math:`(F,)` frame indices
        - **positions**: :math:`(T, J, 3)`
    """
    pos = canonical.global_positions() if positions is None else positions
    height = character_height(canonical.skeleton, pos)
    shown = pos if frames is None else pos[frames]
    if not len(shown):
        return {}
    return {limb: float((shown[:, canonical.skeleton.subtree(j), 1].min(axis=1)
                         < LANDING_HEIGHT * height).mean())
            for limb, j in limb_ends(canonical.skeleton).items()}


def lands(canonical: Motion, reference: Motion) -> Optional[float]:
    """Whether a motion puts down the limbs its character stands on: over
    the limbs that :obj:`reference` (the character's own clip, canonical)
    lands in at least :data:`LANDS_SHARE` of its standing frames
    (:func:`~satagraph.transforms.ground.stands`), the least ratio of the
    motion's :func:`landing_shares` over its own standing frames (a
    retarget of a dog that sits is not asked to stand) to the
    reference's, each read from the floor it stands on there
    (:func:`standing_shares`' ``own_floor``), capped at 1 (``None`` where the reference lands no limb
    that often, or either has no frames). 1 where every limb comes down as
    often as in the character's own clip (the built-in model's retargets onto Bandai's
    human, a zoo biped, bird and Reallusion's rig read 0.94-1.00); 0 where
    one never does: its human -> dog and zoo biped -> quadruped retargets
    walk on their hind legs with the forepaws held up like hands, never
    within 5 % of the height of the floor, while the dog's clip lands all
    four paws in 90-97 % of its standing frames (``ground`` passes them,
    the hind paws being down, and :func:`posture` reads 0.75-0.85); onto
    the held-out longtail plan 0.10-0.27. CMU's 01_01 puts its feet down
    in 91-95 % of its standing frames from the floor it stands on there
    (22-24 % from its lowest point, y = 0, which read ``None``)."""
    return lands_against(canonical, standing_shares(reference, own_floor=True))


def lands_against(canonical: Motion, own: Dict[str, float]) -> Optional[float]:
    """:func:`lands` against the character's own :func:`standing_shares`
    :obj:`own`, computed once for many motions of one character."""
    got = standing_shares(canonical, own_floor=True)
    ratios = [min(got[limb] / own[limb], 1.0) for limb in stood_on(own) if limb in got]
    return float(min(ratios)) if ratios else None


def stood_on(own: Dict[str, float]) -> List[str]:
    """The limbs a character stands on in its own clip, whose
    :func:`standing_shares` are :obj:`own`: those down in at least
    :data:`LANDS_SHARE` of its standing frames, which :func:`lands` reads
    (none: a clip in which it sits or lies, which ``lands`` cannot be read
    against)."""
    return [limb for limb, share in own.items() if share >= LANDS_SHARE]


def standing_shares(canonical: Motion, own_floor: bool = False) -> Dict[str, float]:
    """:func:`landing_shares` over the frames in which a canonical motion
    stands (:func:`~satagraph.transforms.ground.stands`; none without
    frames); with :obj:`own_floor` (as :func:`lands` reads both motions),
    read from the floor it stands on there, the median height
    of its lowest joint over those frames
    (:func:`~satagraph.transforms.ground.levels`), not from y = 0, which a
    clip's lowest point sets: 20 of the dog's 34 clips lie or sit with the
    tail tip on the floor, the paws 4-11 cm above it where they stand on
    all four (``dog/D1_058_KAN01_001``: 721 of 1090 frames), and read every
    paw down in none of them."""
    if not canonical.num_frames:
        return {}
    pos, standing = _standing(canonical)
    frames = np.flatnonzero(standing)
    if own_floor and len(frames):
        pos = pos - np.array([0.0, levels(canonical.skeleton, pos, frames)[0], 0.0])
    return landing_shares(canonical, frames, pos)


def _standing(canonical: Motion) -> Tuple[np.ndarray, np.ndarray]:
    """The global positions of a canonical motion and the mask of its
    frames in which it stands (:func:`~satagraph.transforms.ground.stands`),
    which :func:`posture` and :func:`lands` read the character's own clip
    over.

    Shapes:
        - **output**: :math:`(T, J, 3)` and :math:`(T,)`
    """
    pos = canonical.global_positions()
    return pos, stands(pos, canonical.skeleton, canonical.fps)


def retarget_quality(source: Motion, output: Motion,
                     keys: Sequence[str] = ("steps", "travel", "ground", "upright"),
                     target: Optional[Motion] = None) -> Dict[str, Optional[float]]:
    r"""The quality numbers of a retarget next to the source's.

    Args:
        source (Motion): The source, canonical.
        output (Motion): Its retarget, canonical, same frame rate and frames.
        keys: Which numbers.
        target (Motion, optional): The target rig's own clip, canonical
            (for ``posture`` and ``lands``).

    Returns:
        dict: ``steps`` (:func:`step_correlation`), ``travel`` (the output's
        :func:`root_travel` over the source's), ``ground``
        (:func:`ground_height` of the output), ``upright``
        (:func:`upright_fraction` of the output) and, when asked for,
        ``slide`` (:func:`foot_slide` of the output), ``hover``
        (:func:`hover` of the output) and ``sideways``
        (degrees between the output's :func:`heading_gap` and the source's;
        ``None`` where either has none) and ``stride`` (the output's
        :func:`stride` over the source's; ``None`` where the source swings
        its limbs less than :data:`MIN_STRIDE`), and ``posture`` (:func:`posture`
        of the output against :obj:`target`, the target rig's own canonical
        clip; ``None`` without one) and ``lands`` (:func:`lands` of the
        output against :obj:`target`; ``None`` without one).
    """
    out: Dict[str, Optional[float]] = {}
    if "steps" in keys or "stride" in keys:  # both read the limb tracks
        tracks = limb_tracks(source), limb_tracks(output)
    if "steps" in keys:
        out["steps"] = step_correlation(source, output, tracks)
    if "travel" in keys:
        out["travel"] = root_travel(output) / max(root_travel(source), 1e-9)
    if "stride" in keys:
        a, b = stride(source, tracks[0]), stride(output, tracks[1])
        out["stride"] = (None if a is None or b is None or a < MIN_STRIDE
                         else b / a)
    if "ground" in keys:
        out["ground"] = ground_height(output)
    if "upright" in keys:
        out["upright"] = upright_fraction(output)
    if "slide" in keys or "hover" in keys:
        slide, hovering = contact(output)
        out.update({k: v for k, v in (("slide", slide), ("hover", hovering)) if k in keys})
    if "sideways" in keys:
        out["sideways"] = _sideways(source, output)
    if "posture" in keys:
        out["posture"] = None if target is None else posture(output, target)
    if "lands" in keys:
        out["lands"] = None if target is None else lands(output, target)
    return out


__all__ = ["LAG", "facing_axis", "forward_tracks", "limb_tracks", "correlate",
           "mean_correlation", "step_correlation", "leg_length", "root_travel", "stride", "CADENCE_PAD",
           "cadence",
           "ground_height", "contact", "foot_slide", "hover", "head_index", "upright_fraction",
           "trunk_bend", "knee_bend", "joint_raise", "most_active",
           "HEADING_TRAVEL", "heading_gap", "TURN_EDGE", "turn_rate", "posture",
           "LANDING_HEIGHT", "LANDS_SHARE", "landing_shares", "lands", "lands_against",
           "stood_on", "standing_shares", "retarget_quality"]
