"""satagraph.pipelines.quality: retarget quality without a ground truth (limb steps,
root travel, ground contact, uprightness), on real clips and zoo walks."""
from __future__ import annotations

import copy
from functools import lru_cache

import numpy as np
import pytest

from satagraph.transforms.canonical import canonicalize
from satagraph.data.features import motion_to_features
from satagraph.semantics import LIMBS, limb_ends
from satagraph.datasets.zoo.endless import EndlessZoo
from satagraph.pipelines.quality import (correlate, facing_axis, foot_slide, forward_tracks,
                                         hover, joint_raise, trunk_bend, landing_shares, lands,
                                         ground_height, heading_gap,
                                         head_index, leg_length, limb_tracks, mean_correlation,
                                         most_active, pace_drift, posture, retarget_quality,
                                         root_travel,
                                         step_correlation, stride, turn_rate, upright_fraction,
                                         cadence, standing_shares, stood_on)


def _walk(species: str, kind: str = "walk", frames: int = 90):
    """The first test-stream endless-zoo sample of a species and clip kind,
    canonical at 30 fps (a copy: the tests may change it)."""
    return copy.deepcopy(_first_sample(species, kind, frames))


@lru_cache(maxsize=None)
def _first_sample(species: str, kind: str, frames: int):
    """:func:`_walk`, drawn once a worker (up to 64 zoo clips each)."""
    zoo = EndlessZoo(species=[species], noise=0.0)
    for index in range(64):
        sample = zoo.sample(0, index, frames, "test")
        if sample.kind == kind:
            return canonicalize(sample.motion, fps=30.0)
    raise AssertionError(f"no {species} {kind} in the first 64 samples")


def test_limb_swing_on_a_real_dog(read_real):
    """The limb ends are the dog's paws, the most active window is where it
    moves, and the tracks measure limb swing relative to the root: a clip
    against itself correlates 1, against a time-reversed copy not."""
    dog = read_real("dog/D1_004_KAN01_001.bvh")
    human = read_real("cmu/01_01.bvh")
    names = {k: dog.skeleton.names[j] for k, j in limb_ends(dog.skeleton).items()}
    assert names == {"left front": "LeftHand", "right front": "RightHand",
                     "left hind": "LeftFoot", "right hind": "RightFoot"}
    assert set(limb_ends(human.skeleton)) == set(LIMBS)
    window = most_active(dog, 300)
    assert window.num_frames == 300
    ends = list(limb_ends(dog.skeleton).values())
    opening = forward_tracks(canonicalize(dog.slice(0, 300), fps=30.0))[:, ends]
    active = forward_tracks(canonicalize(window, fps=30.0))[:, ends]
    assert np.diff(active, axis=0).std() > 3 * np.diff(opening, axis=0).std()
    tracks = limb_tracks(canonicalize(window, fps=30.0))
    same = correlate(tracks, tracks)
    same.update({k + " pos": v for k, v in correlate(tracks, tracks, lag=None).items()})
    assert len(same) == 8 and all(abs(c - 1.0) < 1e-9 for c in same.values())
    reversed_ = window.with_(rotations=window.rotations[::-1].copy(),
                             translations=window.translations[::-1].copy(), raw_channels=None)
    back = correlate(tracks, limb_tracks(canonicalize(reversed_, fps=30.0)))
    assert mean_correlation(back) < 0.5


def test_facing_axis_follows_the_walk(read_real):
    """The clip-averaged facing axis points where a walk goes, and agrees
    with the first-frame one within 30 degrees on a plain walk."""
    walk = canonicalize(read_real("bandai/dataset-1_walk_normal_001.bvh"), fps=30.0)
    axis = facing_axis(walk)
    assert abs(np.linalg.norm(axis) - 1.0) < 1e-9
    feats = motion_to_features(walk, facing_axis=axis)
    assert feats.r[:, 2].mean() > 0.3 * np.abs(feats.r[:, 1:3]).sum(1).mean()
    first = motion_to_features(walk).facing_axis
    assert np.degrees(np.arccos(np.clip(axis @ first / np.linalg.norm(first), -1, 1))) < 30


def test_a_walk_scores_as_its_own_perfect_retarget():
    """A zoo biped walk against itself: in step (1), same travel (ratio 1),
    feet on the floor, head above the hips in every frame."""
    walk = _walk("biped")
    quality = retarget_quality(walk, walk)
    assert quality["steps"] == pytest.approx(1.0)
    assert quality["travel"] == pytest.approx(1.0)
    assert abs(quality["ground"]) < 0.03
    assert quality["upright"] == 1.0
    assert walk.skeleton.names[head_index(walk)].lower().endswith("head")


def test_posture_tells_a_leg_pointing_up_from_the_rigs_own_carriage():
    """A walk carries its joints as its own clip does (posture 1, and
    still 1 for a copy shifted up or turned about +Y: heights above the
    root); with one leg turned half over at the hip, its foot above the
    root, posture falls well below; another rig has no posture."""
    from satagraph.ops.rotation_numpy import rotation_about_numpy, yaw_matrix_numpy
    walk = _walk("biped")
    assert posture(walk, walk) == pytest.approx(1.0)
    rotations, translations = walk.rotations.copy(), walk.translations.copy()
    rotations[:, 0] = yaw_matrix_numpy(1.0) @ rotations[:, 0]
    translations[:, 0] += [0.3, 0.2, -0.1]
    assert posture(walk.with_(rotations=rotations, translations=translations),
                   walk) == pytest.approx(1.0)
    hip = next(j for j, n in enumerate(walk.skeleton.names) if n.lower().endswith("upleg"))
    rotations = walk.rotations.copy()
    rotations[:, hip] = rotation_about_numpy(np.array([1.0, 0.0, 0.0]), np.pi) @ rotations[:, hip]
    broken = walk.with_(rotations=rotations)
    assert posture(broken, walk) < 0.8
    assert retarget_quality(walk, broken, ("posture",), target=walk)["posture"] < 0.8
    assert retarget_quality(walk, walk, ("posture",))["posture"] is None
    assert posture(walk, _walk("quadruped")) is None


def test_posture_tells_forepaws_carried_off_the_floor():
    """A quadruped walk with both forelegs swung 65 degrees at the upper
    leg carries its forepaws a quarter of its height above where its own
    clip carries them (as the built-in model's human -> quadruped retargets
    did, hands held like a human's): posture falls below 0.9 (a correlation
    over joints read it 0.94, the spine's spread outweighing two legs)."""
    from satagraph.ops.rotation_numpy import rotation_about_numpy
    walk = _walk("quadruped")
    ends = limb_ends(walk.skeleton)
    rotations = walk.rotations.copy()
    for limb in ("left front", "right front"):
        upper = walk.skeleton.parents[walk.skeleton.parents[ends[limb]]]
        rotations[:, upper] = rotations[:, upper] @ rotation_about_numpy(
            np.array([1.0, 0.0, 0.0]), np.radians(65.0))
    lifted = walk.with_(rotations=rotations)
    paw = ends["left front"]
    lift = (lifted.global_positions()[:, paw, 1] - walk.global_positions()[:, paw, 1]).mean()
    assert lift > 0.25 * walk.height()
    assert posture(walk, walk) == pytest.approx(1.0)
    assert posture(lifted, walk) < 0.9


def _forelegs_up(walk, degrees: float = 65.0):
    """:obj:`walk` with both forelegs swung :obj:`degrees` at the upper leg
    (the paws carried as a human carries its hands)."""
    from satagraph.ops.rotation_numpy import rotation_about_numpy
    ends = limb_ends(walk.skeleton)
    rotations = walk.rotations.copy()
    for limb in ("left front", "right front"):
        upper = walk.skeleton.parents[walk.skeleton.parents[ends[limb]]]
        rotations[:, upper] = rotations[:, upper] @ rotation_about_numpy(
            np.array([1.0, 0.0, 0.0]), np.radians(degrees))
    return walk.with_(rotations=rotations)


def test_lands_tells_forepaws_that_never_come_down():
    """A zoo quadruped walk against itself lands every paw as often (1.0);
    with its forelegs swung up the forepaws never come within 5 % of its
    height of the floor (0.0 on those limbs, the hind paws' shares kept),
    so lands reads 0 while the ground row, read off the lowest joint, still
    passes it. A biped's hands, never down in its own clip, are not read."""
    walk = _walk("quadruped")
    own = landing_shares(walk)
    assert set(own) == set(LIMBS) and min(own.values()) > 0.8
    assert lands(walk, walk) == pytest.approx(1.0)
    lifted = _forelegs_up(walk)
    shares = landing_shares(lifted)
    assert shares["left front"] == shares["right front"] == 0.0
    assert shares["left hind"] == own["left hind"] and shares["right hind"] == own["right hind"]
    assert lands(lifted, walk) == 0.0
    assert abs(ground_height(lifted)) < 0.03
    biped = _walk("biped")
    assert landing_shares(biped)["left front"] == 0.0
    assert lands(biped, biped) == pytest.approx(1.0)
    assert lands(walk, _walk("snake")) is None  # no limb to land


def test_the_limbs_a_character_stands_on_are_those_lands_reads():
    """A quadruped stands on its four paws, a biped on its feet (its hands
    never down), a snake on none (``lands`` reads ``None`` against it)."""
    assert set(stood_on(standing_shares(_walk("quadruped")))) == set(LIMBS)
    assert set(stood_on(standing_shares(_walk("biped")))) == {"left hind", "right hind"}
    assert stood_on(standing_shares(_walk("snake"))) == []


def test_stood_on_reads_limbs_down_in_half_the_standing_frames_or_more():
    """``LANDS_SHARE`` (0.5) on its edge: a limb down in exactly half of
    the standing frames is stood on, one down in 0.49 of them not."""
    shares = {"left front": 0.5, "right front": 0.49, "left hind": 1.0, "right hind": 0.0}
    assert stood_on(shares) == ["left front", "left hind"]


def test_a_motion_reads_from_the_floor_it_stands_on_and_lands_at_most_1():
    """A zoo walk raised 6 % of its height: read from y = 0 (the default)
    no paw is down; from the floor it stands on, each is down as often as
    in the walk, and, as a retarget hovering so, it lands as the walk
    (1.0). Against a clip whose left forepaw is down in 0.51 of its
    standing frames (forelegs swung up 20 degrees), the walk's, down in
    0.83, lands 1.6 times as often: capped at 1."""
    from satagraph.transforms.ground import raise_root
    walk = _walk("quadruped")
    raised = raise_root(walk, 0.06 * walk.height())
    assert set(standing_shares(raised).values()) == {0.0}
    assert standing_shares(raised, own_floor=True) == pytest.approx(standing_shares(walk))
    assert lands(raised, walk) == pytest.approx(1.0)
    half = _forelegs_up(walk, 20.0)
    assert standing_shares(walk)["left front"] > 1.6 * standing_shares(half)["left front"] > 0.8
    assert lands(walk, half) == 1.0


def test_lands_on_the_real_dog_and_a_human(read_real):
    """The dog's walk lands all four paws in 90-97 % of its standing frames
    and reads 1.0 against itself, 0 with its forelegs swung up; a Bandai
    human walk, measured against the dog's clip as a retarget onto it is,
    never puts its hands down (0), and against its own clip reads 1.0."""
    from satagraph.transforms.ground import standing_frames
    from satagraph.transforms.rig_reading import with_rig
    dog = canonicalize(with_rig(read_real("dog/D1_001_KAN01_001.bvh"), scale="cm"), fps=30.0)
    shares = landing_shares(dog, standing_frames(dog))
    assert all(0.85 < v < 0.99 for v in shares.values()), shares
    assert lands(dog, dog) == pytest.approx(1.0)
    assert lands(_forelegs_up(dog), dog) < 0.05
    human = canonicalize(read_real("bandai/dataset-1_walk_sad_001.bvh"), fps=30.0)
    assert lands(human, human) == pytest.approx(1.0)
    assert lands(human, dog) == 0.0


def test_lands_reads_the_reference_from_the_floor_it_stands_on(read_real):
    """A character's own clip whose lowest point is no paw's: the dog of
    ``D1_058`` stands on all four in 721 of its 1090 frames, the paws 5-6
    cm above the tail tip it lies on, which set the clip's floor; read from
    y = 0 no paw came down and ``lands`` said nothing (None) of any
    retarget onto it. Read from the floor of its standing frames, its paws
    land (1.0 against itself) and forepaws held up read 0; a zoo walk
    raised 6 % of its height alike."""
    from satagraph.transforms.ground import raise_root, standing_frames
    from satagraph.transforms.rig_reading import with_rig
    walk = _walk("quadruped")
    raised = raise_root(walk, 0.06 * walk.height())
    assert lands(walk, raised) == pytest.approx(1.0)
    assert lands(_forelegs_up(walk), raised) == 0.0
    dog = canonicalize(with_rig(read_real("dog/D1_058_KAN01_001.bvh"), scale="cm"), fps=30.0)
    assert max(landing_shares(dog, standing_frames(dog)).values()) == 0.0  # from y = 0
    assert lands(dog, dog) == pytest.approx(1.0)
    assert lands(_forelegs_up(dog), dog) < 0.05


def test_posture_reads_a_dog_that_lies_most_of_its_clip_where_it_stands(read_real):
    """This dog lies on its side for most of its clip: measured against
    every frame, its own standing frames would read as a poor posture
    (its joints' heights above the root are those of a lying body); the
    reference is where it stands, so its standing stretch reads near 1."""
    from satagraph.transforms.ground import standing_frames
    from satagraph.transforms.rig_reading import with_rig
    dog = canonicalize(with_rig(read_real("dog/D1_031_KAN01_001.bvh"), scale="cm"), fps=30.0)
    frames = standing_frames(dog)
    assert len(frames) < 0.2 * dog.num_frames
    standing = dog.with_(rotations=dog.rotations[frames], translations=dog.translations[frames])
    assert posture(standing, dog) > 0.99
    every = np.median(dog.global_positions()[..., 1] - dog.global_positions()[:, :1, 1], axis=0)
    own = np.median(standing.global_positions()[..., 1]
                    - standing.global_positions()[:, :1, 1], axis=0)
    assert np.corrcoef(own, every)[0, 1] < 0.9


def test_a_still_or_sliding_body_is_caught():
    """A frozen copy of the walk (its first pose in every frame) travels 0 and
    has no steps; lifted by half its height it floats; turned upside down
    its head is below its hips."""
    walk = _walk("biped")
    frozen = walk.with_(rotations=np.repeat(walk.rotations[:1], walk.num_frames, 0),
                        translations=np.repeat(walk.translations[:1], walk.num_frames, 0),
                        raw_channels=None)
    assert root_travel(frozen) == pytest.approx(0.0, abs=1e-12)
    assert step_correlation(walk, frozen) == 0.0  # still limbs count as not in step
    translations = walk.translations.copy()
    translations[:, 0, 1] += 0.5 * walk.height()
    lifted = walk.with_(translations=translations)
    assert ground_height(lifted) == pytest.approx(ground_height(walk) + 0.5, abs=1e-6)
    flip = np.diag([1.0, -1.0, -1.0])  # half a turn about x, applied at the root
    rotations, translations = walk.rotations.copy(), walk.translations.copy()
    rotations[:, 0] = flip @ rotations[:, 0]
    translations[:, 0] = translations[:, 0] @ flip.T
    upside = walk.with_(rotations=rotations, translations=translations)
    assert upright_fraction(upside) == 0.0


def test_travel_is_relative_to_the_leg_length():
    """Scaling a walk (bones and path) leaves its travel in leg lengths
    unchanged; a faster clip of the same rig travels further."""
    walk = _walk("quadruped")
    big = walk.with_(skeleton=walk.skeleton.replace(offsets=walk.skeleton.offsets * 2.5),
                     translations=walk.translations * 2.5)
    assert leg_length(big) == pytest.approx(2.5 * leg_length(walk))
    assert root_travel(big) == pytest.approx(root_travel(walk))
    assert root_travel(walk) > 0.5


def test_foot_slide_tells_planted_feet_from_skating():
    """A zoo walk plants its feet (under 0.15 heights/s of sliding, as
    captured walks); the same steps with the root dragged forward at the
    walk's own speed once more skate at about that speed; slide is
    reported by retarget_quality when asked for."""
    walk = _walk("biped")
    planted = foot_slide(walk)
    assert planted < 0.15
    translations = walk.translations.copy()
    path = translations[:, 0] - translations[:1, 0]
    translations[:, 0] += path * np.array([1.0, 0.0, 1.0])  # twice the travel
    speed = np.linalg.norm(np.diff(path[:, [0, 2]], axis=0), axis=-1).mean() * walk.fps
    skating = foot_slide(walk.with_(translations=translations))
    assert skating > planted + 0.5 * speed / walk.height()
    assert retarget_quality(walk, walk, ("slide",)) == {"slide": pytest.approx(planted)}


def test_hover_reads_a_body_held_off_its_floor_where_the_ground_row_cannot():
    """A zoo walk keeps a foot on its floor (hover 0); the same walk whose
    body sinks a fifth of its height in its first quarter stands a fifth
    above that floor the rest of the time (a mean of 0.15), though its
    median ground is the walk's; retarget_quality reports it."""
    walk = _walk("quadruped")
    assert hover(walk) == pytest.approx(0.0, abs=0.005)
    translations = walk.translations.copy()
    translations[: walk.num_frames // 4, 0, 1] -= 0.2 * walk.height()
    sunk = walk.with_(translations=translations)
    assert hover(sunk) == pytest.approx(0.15, abs=0.02)
    assert ground_height(sunk) == pytest.approx(ground_height(walk), abs=1e-6)
    assert retarget_quality(walk, sunk, ("hover",)) == {"hover": pytest.approx(hover(sunk))}


@pytest.mark.parametrize("species", ["biped", "quadruped"])
def test_stride_reads_the_limb_swing_in_leg_lengths(species):
    """A walk swings its limb ends fore and aft by a sizeable share of its
    leg (whatever the character's size); its first pose dragged along the
    same path has no stride at all, and retarget_quality gives the
    output's stride over the source's."""
    walk = _walk(species)
    swing = stride(walk)
    assert 0.2 < swing < 1.5
    big = walk.with_(skeleton=walk.skeleton.replace(offsets=walk.skeleton.offsets * 2.5),
                     translations=walk.translations * 2.5)
    assert stride(big) == pytest.approx(swing, rel=1e-6)
    rotations = np.repeat(walk.rotations[:1], walk.num_frames, axis=0)
    frozen = walk.with_(rotations=rotations)
    assert stride(frozen) < 0.02 * swing
    assert retarget_quality(walk, walk, ("stride",)) == {"stride": pytest.approx(1.0)}
    assert retarget_quality(walk, frozen, ("stride",))["stride"] < 0.02
    # a source that swings no stride (a stand, a jump in place) has no ratio
    assert retarget_quality(frozen, walk, ("stride",)) == {"stride": None}


@pytest.mark.parametrize("species", ["biped", "quadruped"])
def test_cadence_reads_the_gait_frequency(species):
    """A zoo walk's limbs swing at a walking rate; the same frames played
    at half the frame rate swing at half of it, and a copy with the
    limbs swinging twice as fast (every second frame, repeated to the same
    length) at about twice of it."""
    walk = _walk(species, frames=120)
    rate = cadence(walk)
    assert 0.6 < rate < 2.5
    assert cadence(walk.with_(fps=walk.fps / 2)) == pytest.approx(rate / 2)
    fast = np.concatenate([walk.rotations[::2], walk.rotations[::2]])
    assert cadence(walk.with_(rotations=fast)) == pytest.approx(2 * rate, abs=0.3)
    assert cadence(walk.slice(0, 3)) is None



@pytest.mark.parametrize("hz", [0.9, 1.5, 2.2])
def test_cadence_reads_a_known_swing_between_the_spectrum_bins(hz):
    """Limb tracks swinging at a known rate over 3 s at 30 fps: the
    cadence is that rate within 0.02 Hz (it read the nearest multiple of
    1/3 Hz: 1.0, 1.667 and 2.333)."""
    walk = _walk("biped")
    t = np.arange(walk.num_frames) / walk.fps
    tracks = {limb: 0.2 * np.sin(2 * np.pi * hz * t + 0.3) for limb in LIMBS}
    assert cadence(walk, tracks) == pytest.approx(hz, abs=0.02)

@pytest.mark.parametrize("species", ["biped", "quadruped"])
def test_heading_gap_tells_a_walk_from_a_side_step_and_a_crab(species):
    """A zoo walk travels the way its hips face (under a degree), the zoo's
    side walks (which go diagonally) about 50 degrees off; the walk's root path turned 60 degrees
    to the left about its start, the body still facing ahead, is 60
    degrees more: retarget_quality's sideways reads the difference."""
    from satagraph.ops.rotation_numpy import yaw_matrix_numpy
    walk = _walk(species)
    assert abs(heading_gap(walk)) < 2.0
    assert 40.0 < abs(heading_gap(_walk(species, "side"))) < 65.0
    translations = walk.translations.copy()
    start = translations[:1, 0]
    translations[:, 0] = (translations[:, 0] - start) @ yaw_matrix_numpy(np.radians(60)).T + start
    crab = walk.with_(translations=translations)
    assert heading_gap(crab) - heading_gap(walk) == pytest.approx(60.0, abs=1e-6)
    assert retarget_quality(walk, crab, ("sideways",))["sideways"] == pytest.approx(60.0, abs=1e-6)
    translations[:, 0] = start  # a walk on the spot
    assert heading_gap(walk.with_(translations=translations)) is None


@pytest.mark.parametrize("species", ["biped", "quadruped"])
def test_turn_rate_reads_a_straight_walk_and_a_turned_one(species):
    """A zoo walk keeps its facing (under 8 degrees a second: the hips'
    sway is averaged out at both ends); the same walk turned progressively
    to the left about +Y, 60 degrees from its first frame to its last,
    reads exactly 60 over its duration more, and to the right as much less."""
    from satagraph.ops.rotation_numpy import yaw_matrix_numpy
    walk = _walk(species)
    base = turn_rate(walk)
    assert abs(base) < 8.0
    for sign in (1.0, -1.0):
        yaw = yaw_matrix_numpy(np.radians(sign * 60.0) * np.linspace(0.0, 1.0, walk.num_frames))
        rotations = walk.rotations.copy()
        rotations[:, 0] = yaw @ rotations[:, 0]
        translations = walk.translations.copy()
        translations[:, 0] = np.einsum("tij,tj->ti", yaw, translations[:, 0])
        turned = walk.with_(rotations=rotations, translations=translations)
        expected = sign * 60.0 / ((walk.num_frames - 1) / walk.fps)
        assert turn_rate(turned) - base == pytest.approx(expected, abs=1e-6)
    assert turn_rate(walk.slice(0, 10)) is None  # shorter than both ends


@pytest.mark.parametrize("seed", [0, 3])
def test_trunk_bend_and_joint_raise_tell_a_bow_a_wave_and_a_walk(seed):
    zoo = EndlessZoo(species=["biped"], kinds=["walk", "bow", "wave"], seed=seed)
    read = {}
    for i in range(12):
        sample = zoo.sample(0, i, 120)
        if sample.kind not in read:
            motion = canonicalize(sample.motion, fps=30.0)
            read[sample.kind] = (trunk_bend(motion), joint_raise(motion))
    assert set(read) == {"walk", "bow", "wave"}
    assert 25.0 < read["bow"][0] < 75.0 and read["wave"][0] < 12.0 and read["walk"][0] < 12.0
    assert read["wave"][1] > 0.4 and read["walk"][1] < 0.2 and read["bow"][1] < 0.2


def test_trunk_bend_is_the_lean_from_the_first_frame():
    motion = canonicalize(EndlessZoo(species=["biped"], kinds=["walk"]).sample(0, 0, 60).motion,
                          fps=30.0)
    rotations = motion.rotations.copy()
    tilt = np.radians(np.linspace(0.0, 40.0, motion.num_frames))
    c, s = np.cos(tilt), np.sin(tilt)
    pitch = np.zeros((len(tilt), 3, 3))
    pitch[:, 0, 0], pitch[:, 1, 1], pitch[:, 1, 2] = 1.0, c, -s
    pitch[:, 2, 1], pitch[:, 2, 2] = s, c
    rotations[:, 0] = pitch @ rotations[:, 0]  # the whole body tips forward to 40 degrees
    tipped = motion.with_(rotations=rotations)
    assert trunk_bend(tipped) == pytest.approx(trunk_bend(motion) + 40.0, abs=8.0)
    assert trunk_bend(tipped) > 35.0


@pytest.mark.parametrize("species", ["biped", "quadruped"])
def test_pace_drift_reads_a_steady_walk_and_one_that_speeds_up(species):
    """A zoo walk holds its pace (drift under 0.1); its root re-timed so
    that its speed ramps from 0.7 to 1.3 times along the clip reads the
    ramp's thirds (1.2 / 0.8 - 1 = +0.5), the reverse ramp -1/3; a short
    clip and a clip standing still have no pace to read."""
    walk = _walk(species, frames=120)
    assert abs(pace_drift(walk)) < 0.1
    frames = walk.num_frames
    t = np.linspace(0.0, 1.0, frames - 1)
    for speed, expected in ((0.7 + 0.6 * t, 0.5), (1.3 - 0.6 * t, -1.0 / 3.0)):
        warp = np.concatenate([[0.0], np.cumsum(speed)])
        warp *= (frames - 1) / warp[-1]  # frame index each new frame reads, same span
        translations = walk.translations.copy()
        for axis in (0, 2):
            translations[:, 0, axis] = np.interp(warp, np.arange(frames),
                                                 walk.translations[:, 0, axis])
        drift = pace_drift(walk.with_(translations=translations))
        assert drift == pytest.approx(expected, abs=0.08)
    assert pace_drift(walk.slice(0, 30)) is None  # one second
    still = walk.translations.copy()
    still[:, 0, [0, 2]] = still[:1, 0, [0, 2]]
    assert pace_drift(walk.with_(translations=still)) is None


def _pitched(motion, degrees: float):
    """:obj:`motion` frozen in its first pose, its root pitched forward
    about +X from 0 to :obj:`degrees` along the clip."""
    tilt = np.radians(np.linspace(0.0, degrees, motion.num_frames))
    c, s = np.cos(tilt), np.sin(tilt)
    pitch = np.zeros((len(tilt), 3, 3))
    pitch[:, 0, 0], pitch[:, 1, 1], pitch[:, 1, 2] = 1.0, c, -s
    pitch[:, 2, 1], pitch[:, 2, 2] = s, c
    rotations = np.repeat(motion.rotations[:1], motion.num_frames, 0)
    rotations[:, 0] = pitch @ rotations[:, 0]
    return motion.with_(rotations=rotations, raw_channels=None,
                        translations=np.repeat(motion.translations[:1], motion.num_frames, 0))


def _nameless(motion):
    """:obj:`motion` with joints no name describes: no head, no limb ends."""
    names = [f"j{j}" for j in range(motion.skeleton.num_joints)]
    return motion.with_(skeleton=motion.skeleton.replace(names=names), raw_channels=None)


def test_travel_and_pace_drift_follow_the_root_alone():
    """A body whose root slides 2 leg lengths along +X or (0.6, 0, 0.8) at
    a steady pace while it pitches forward to 60 degrees (its spine
    sweeping ahead, more at first) travels 2 leg lengths with no pace drift."""
    rocking = _pitched(_walk("biped"), 60.0)
    leg = leg_length(rocking)
    for way in ([1.0, 0.0, 0.0], [0.6, 0.0, 0.8]):
        translations = rocking.translations.copy()
        translations[:, 0] += np.linspace(0.0, 2.0 * leg, rocking.num_frames)[:, None] * way
        moved = rocking.with_(translations=translations)
        assert root_travel(moved) == pytest.approx(2.0)
        assert pace_drift(moved) == pytest.approx(0.0, abs=1e-9)


def test_heading_gap_reads_travel_in_leg_lengths():
    """The walk scaled 2.5 times with its root path cut to 0.45 leg lengths
    of net travel has no heading to read; cut to 0.55 it reads the walk's."""
    walk = _walk("biped")
    big = walk.with_(skeleton=walk.skeleton.replace(offsets=walk.skeleton.offsets * 2.5),
                     translations=walk.translations * 2.5)
    translations = big.translations.copy()
    start = translations[:1, 0, [0, 2]]
    net = np.linalg.norm(translations[-1, 0, [0, 2]] - start) / leg_length(big)
    for legs, gap in ((0.45, None), (0.55, pytest.approx(heading_gap(walk), abs=1e-6))):
        translations[:, 0, [0, 2]] = start + (big.translations[:, 0, [0, 2]] - start) * (legs / net)
        assert heading_gap(big.with_(translations=translations)) == gap


def test_trunk_bend_and_most_active_of_a_body_without_names():
    """Without a head, trunk_bend follows the first frame's highest joint:
    the tipped body still reads its 40 degrees; without limb ends,
    most_active is the clip's start."""
    walk = _nameless(_walk("biped"))
    assert head_index(walk) is None and limb_tracks(walk) == {}
    assert trunk_bend(_pitched(walk, 40.0)) == pytest.approx(40.0, abs=1e-6)
    np.testing.assert_array_equal(most_active(walk, 40).rotations, walk.rotations[:40])


def test_travel_ratio_of_a_short_clip_as_its_own_retarget():
    """A third of a second of the walk travels under a leg length: as its
    own retarget its travel ratio is still 1."""
    short = _walk("biped").slice(0, 10)
    assert 0.1 < root_travel(short) < 1.0
    assert retarget_quality(short, short, ("travel",)) == {"travel": pytest.approx(1.0)}


def test_joint_raise_is_in_heights_and_mean_correlation_counts_still_limbs():
    """A walk scaled to a quarter (0.48 m tall) raises its joints by as many
    of its heights; a still limb counts 0 in the mean, no limb gives nan."""
    walk = _walk("biped")
    small = walk.with_(skeleton=walk.skeleton.replace(offsets=walk.skeleton.offsets * 0.25),
                       translations=walk.translations * 0.25)
    assert small.height() < 0.5
    assert joint_raise(small) == pytest.approx(joint_raise(walk)) and joint_raise(walk) > 0.01
    assert mean_correlation({"a": float("nan"), "b": 0.5}) == 0.25
    assert np.isnan(mean_correlation({}))


@pytest.mark.parametrize("species", ["biped", "quadruped"])
def test_sideways_reads_the_turn_across_half_a_turn(species):
    """The zoo's side walk (about 50 degrees off its facing) with its root
    path turned 150 degrees further the same way: its heading gap wraps
    past 180 degrees and sideways still reads 150."""
    from satagraph.ops.rotation_numpy import yaw_matrix_numpy
    side = _walk(species, "side")
    turn = 150.0 * np.sign(heading_gap(side))
    translations = side.translations.copy()
    start = translations[:1, 0]
    translations[:, 0] = (translations[:, 0] - start) @ yaw_matrix_numpy(np.radians(turn)).T + start
    turned = side.with_(translations=translations)
    assert abs(heading_gap(side) + turn) > 180.0
    assert heading_gap(turned) == pytest.approx(heading_gap(side) + turn - 360.0 * np.sign(turn),
                                                abs=1e-6)
    assert retarget_quality(side, turned, ("sideways",))["sideways"] == pytest.approx(150.0, abs=1e-6)


def test_lands_of_a_clip_without_frames_is_none():
    """A target rig read without frames (a zero-frame BVH retargets onto
    its rest) has no standing frames to read: lands is ``None`` either way
    round, as for a clip that lands no limb, not numpy's 'cannot extend
    empty axis' from the standing test."""
    walk = _walk("quadruped")
    empty = walk.slice(0, 0)
    assert empty.num_frames == 0
    assert lands(walk, empty) is None
    assert lands(empty, walk) is None
    assert retarget_quality(walk, walk, ("lands",), target=empty) == {"lands": None}


def test_knee_bend_reads_standing_and_walking_humans(read_real):
    """A Bandai bow stands on nearly straight knees, a walk bends them
    about 18 degrees in median; each knee is found by its segments on both
    human rigs and the dog's hind legs; a snake has none."""
    from satagraph.pipelines.quality import knee_bend
    bow = knee_bend(canonicalize(read_real("bandai/dataset-1_bow_normal_001.bvh")))
    walk = knee_bend(canonicalize(read_real("bandai/dataset-1_walk_normal_002.bvh")))
    cmu = knee_bend(canonicalize(read_real("cmu/01_01.bvh")))
    assert 3.0 < bow < 12.0 < walk < 25.0 and 20.0 < cmu < 45.0
    assert knee_bend(canonicalize(read_real("dog/D1_001_KAN01_001.bvh"))) > 45.0
    assert knee_bend(_walk("snake")) is None
