"""A motion carried as its character carries itself: the root's tilt without
its heading, the mean carriage, forepaws held up brought down with their
swing and heading kept, travel in leg lengths kept, and bad inputs."""
from __future__ import annotations

import numpy as np
import pytest

from satagraph.ops.rotation_numpy import (mean_rotation_numpy, rotation_about_numpy,
                                          yaw_matrix_numpy)
from satagraph.pipelines.quality import lands, posture, root_travel, step_correlation
from satagraph.transforms.carriage import (MIN_STANDING, carried_frames, carry_like,
                                           mean_carriage, tilts, twist_yaw)
from satagraph.transforms.ground import standing_frames
from tests.pipelines.test_quality import _forelegs_up, _pitched, _walk

X = np.array([1.0, 0.0, 0.0])


def test_twist_yaw_reads_the_turn_and_tilts_keep_the_lean():
    """A turn about +Y by psi after a lean about +X: the turn read back is
    psi, for any psi in (-pi, pi), and the tilt is the lean itself."""
    yaw = np.linspace(-3.0, 3.0, 13)
    lean = rotation_about_numpy(X, np.radians(25.0))
    rotations = yaw_matrix_numpy(yaw) @ lean
    np.testing.assert_allclose(twist_yaw(rotations), yaw, atol=1e-9)
    np.testing.assert_allclose(tilts(rotations), np.broadcast_to(lean, (13, 3, 3)), atol=1e-9)
    np.testing.assert_allclose(twist_yaw(np.eye(3)), 0.0, atol=1e-12)


def test_a_half_turn_is_read_as_one():
    """A body heading back along -Z (a turn of pi about +Y) after a lean:
    the turn read back is pi and the tilt the lean. Read as the quaternion's
    2 atan2(y, w) with w clipped at 0, the exact half turn read 0 after
    each of these 64 leans, and ``yaw_matrix_numpy(pi)`` 56 degrees off
    after 3 of them."""
    rng = np.random.default_rng(0)
    axes = rng.normal(size=(64, 3)) * [1.0, 0.0, 1.0]
    leans = rotation_about_numpy(axes / np.linalg.norm(axes, axis=-1, keepdims=True),
                                 rng.uniform(0.0, 1.0, 64))
    for half in (np.diag([-1.0, 1.0, -1.0]), yaw_matrix_numpy(np.pi)):
        rotations = half @ leans
        np.testing.assert_allclose(np.cos(twist_yaw(rotations)), -1.0, atol=1e-12)
        np.testing.assert_allclose(tilts(rotations), leans, atol=1e-9)


def test_a_motion_carried_as_itself_is_unchanged():
    """The carriage of a walk's own clip turns nothing: every rotation and
    translation kept."""
    walk = _walk("quadruped")
    carried = carry_like(walk, mean_carriage(walk))
    np.testing.assert_allclose(carried.rotations, walk.rotations, atol=1e-9)
    np.testing.assert_allclose(carried.translations, walk.translations, atol=1e-9)


def test_forepaws_held_up_come_down_with_their_swing_kept():
    """A zoo quadruped walk with both forelegs swung 65 degrees up never
    puts its forepaws down (lands 0); carried as the walk's own clip, it
    lands them as the clip does and rides at its joint heights, its limbs
    still in step with the walk and the hind legs untouched."""
    walk = _walk("quadruped")
    lifted = _forelegs_up(walk)
    assert lands(lifted, walk) == 0.0
    carried = carry_like(lifted, mean_carriage(walk))
    assert lands(carried, walk) > 0.9
    assert posture(carried, walk) > 0.99 > 0.9 > posture(lifted, walk)
    assert step_correlation(walk, carried) > 0.95
    hind = [j for j, name in enumerate(walk.skeleton.names) if "Hind" in name]
    assert len(hind) == 12
    np.testing.assert_allclose(carried.rotations[:, hind], lifted.rotations[:, hind], atol=1e-9)


def test_the_heading_is_kept_and_the_lean_taken_from_the_reference():
    """A biped whose root pitches forward from 0 to 60 degrees while it
    turns about +Y, carried as its unpitched clip: per frame the turn about
    +Y is the motion's own, the mean lean the reference's (its swing about
    that mean kept)."""
    walk = _walk("biped")
    pitched = _pitched(walk, 60.0)
    turned = pitched.rotations.copy()
    turned[:, 0] = yaw_matrix_numpy(np.linspace(0.0, 1.5, walk.num_frames)) @ turned[:, 0]
    turning = pitched.with_(rotations=turned)
    carried = carry_like(turning, mean_carriage(walk))
    np.testing.assert_allclose(twist_yaw(carried.rotations[:, 0]),
                               twist_yaw(turning.rotations[:, 0]), atol=1e-9)
    lean = np.einsum("tii->t", np.swapaxes(tilts(carried.rotations[:, 0]), -1, -2)
                     @ mean_carriage(walk)[0])
    assert abs(np.degrees(np.arccos(np.clip((lean.mean() - 1) / 2, -1, 1)))) < 20.0


def test_the_root_travels_as_many_leg_lengths_as_before():
    """Carried with its forelegs down, the quadruped's hips ride higher,
    so its leg is longer: the root's path is scaled with it, and the travel
    in leg lengths is the lifted walk's."""
    walk = _walk("quadruped")
    lifted = _forelegs_up(walk, 80.0)
    carried = carry_like(lifted, mean_carriage(walk))
    assert root_travel(carried) == pytest.approx(root_travel(lifted), rel=1e-6)
    np.testing.assert_allclose(carried.translations[0, 0], lifted.translations[0, 0])


def _lying(walk, frames: slice = slice(30, 60)):
    """:obj:`walk` rolled onto its side (a quarter turn about +Z at the
    root) in :obj:`frames`."""
    rot = walk.rotations.copy()
    rot[frames, 0] = rotation_about_numpy(np.array([0.0, 0.0, 1.0]), np.pi / 2) @ rot[frames, 0]
    return walk.with_(rotations=rot)


def test_carried_frames_are_the_standing_ones_or_all():
    """A walk that lies on its side in frames 30-59 is read in the other
    60; a clip in which it stands in fewer than ``MIN_STANDING`` frames (5
    of 15) is read whole."""
    walk = _walk("quadruped")
    lying = _lying(walk)
    np.testing.assert_array_equal(carried_frames(lying), np.r_[0:30, 60:walk.num_frames])
    np.testing.assert_array_equal(carried_frames(lying.slice(25, 40)), np.arange(15))


def test_a_clip_standing_in_min_standing_frames_is_read_there():
    """The edge of ``MIN_STANDING`` (8): a clip standing in exactly 8 of
    its 23 frames is read in those 8; one standing in 7 of 22, whole."""
    lying = _lying(_walk("quadruped"))
    eight, seven = lying.slice(22, 45), lying.slice(23, 45)
    assert len(standing_frames(eight)) == MIN_STANDING == len(standing_frames(seven)) + 1
    np.testing.assert_array_equal(carried_frames(eight), np.arange(MIN_STANDING))
    np.testing.assert_array_equal(carried_frames(seven), np.arange(22))


def test_what_a_clip_does_lying_down_is_no_part_of_its_carriage():
    """A walk lying in frames 30-59, its forelegs swung 80 degrees up
    there or not: the same carriage, each joint's below the root the mean
    of its 60 standing frames."""
    walk = _walk("quadruped")
    lying = _lying(walk)
    rot = lying.rotations.copy()
    rot[30:60] = _forelegs_up(lying, 80.0).rotations[30:60]
    kicking = lying.with_(rotations=rot)
    standing = np.r_[0:30, 60:walk.num_frames]
    np.testing.assert_array_equal(carried_frames(kicking), standing)
    np.testing.assert_allclose(mean_carriage(kicking), mean_carriage(lying), atol=1e-9)
    np.testing.assert_allclose(mean_carriage(lying)[1:],
                               mean_rotation_numpy(walk.rotations[standing, 1:]), atol=1e-9)


def test_the_path_is_scaled_about_its_first_frame_and_heights_kept():
    """Started 3 m along +X and 2 m along -Z, a carried walk's root path is
    the one it takes from the origin, moved along: scaled about its first
    frame, not about the origin. The root's heights stay the decoded ones
    (grounding sets them), and unpaced the whole path is kept."""
    walk = _walk("quadruped")
    lifted = _forelegs_up(walk, 80.0)
    trans = lifted.translations.copy()
    trans[:, 0] += [3.0, 0.0, -2.0]
    away = lifted.with_(translations=trans)
    reference = mean_carriage(walk)
    carried, moved = carry_like(lifted, reference), carry_like(away, reference)
    path = [np.linalg.norm(m.translations[-1, 0, [0, 2]] - m.translations[0, 0, [0, 2]])
            for m in (carried, lifted)]
    assert path[0] / path[1] - 1.0 > 1e-4  # scaled up: the leg is longer carried
    np.testing.assert_allclose(moved.translations[:, 0],
                               carried.translations[:, 0] + [3.0, 0.0, -2.0], atol=1e-9)
    np.testing.assert_array_equal(carried.translations[:, 0, 1], lifted.translations[:, 0, 1])
    np.testing.assert_array_equal(carry_like(away, reference, paced=False).translations,
                                  away.translations)


def test_bad_inputs_are_refused_in_one_line():
    walk = _walk("quadruped")
    with pytest.raises(ValueError, match=r"carriage of \d+ joints is \[\d+, 3, 3\], got \[2, 3, 3\]"):
        carry_like(walk, np.broadcast_to(np.eye(3), (2, 3, 3)))
    with pytest.raises(ValueError, match="without frames"):
        mean_carriage(walk.slice(0, 0))
