"""A decoded root held still where the decoded body stands still: still
frames, contact steps, and walks, flights and wrong shapes left alone; a
retarget's root held where its source stands."""
from __future__ import annotations

import numpy as np
import pytest

from satagraph.motion import Motion
from satagraph.ops.rotation_numpy import rotation_about_numpy
from satagraph.skeleton import Skeleton
from satagraph.transforms.still_root import (contact_steps, hold_still_source, settle_root,
                                             source_still_steps, still_frames)

FPS = 30.0
NAMES = ["Hips", "Spine", "Head", "LeftUpLeg", "LeftLeg", "LeftFoot", "RightUpLeg",
         "RightLeg", "RightFoot"]
PARENTS = np.array([-1, 0, 1, 0, 3, 4, 0, 6, 7])
OFFSETS = np.array([[0, 0, 0], [0, 0.3, 0], [0, 0.4, 0], [0.1, 0, 0], [0, -0.45, 0],
                    [0, -0.45, 0], [-0.1, 0, 0], [0, -0.45, 0], [0, -0.45, 0]], dtype=float)
FEET = [5, 8]


def biped(frames: int = 60, speed: float = 1.0, swing_degrees: float = 0.0) -> Motion:
    """A biped whose root travels +Z at :obj:`speed` m/s, its legs swinging
    about X by :obj:`swing_degrees` at 1 Hz in opposite phase (0: they
    hang still under a gliding body)."""
    skeleton = Skeleton(names=NAMES, parents=PARENTS, offsets=OFFSETS)
    t = np.arange(frames) / FPS
    rotations = np.broadcast_to(np.eye(3), (frames, len(NAMES), 3, 3)).copy()
    swing = np.radians(swing_degrees) * np.sin(2 * np.pi * t)
    rotations[:, 3] = rotation_about_numpy(np.array([1.0, 0, 0]), swing)
    rotations[:, 6] = rotation_about_numpy(np.array([1.0, 0, 0]), -swing)
    translations = np.broadcast_to(OFFSETS, (frames, len(NAMES), 3)).copy()
    translations[:, 0] = np.stack([np.zeros(frames), np.full(frames, 0.9), speed * t], -1)
    return Motion(skeleton, rotations, translations, fps=FPS)


def feet_down(motion: Motion, value: float = 0.9) -> np.ndarray:
    """Contact probabilities: :obj:`value` on both feet in every frame."""
    contacts = np.zeros((motion.num_frames, motion.num_joints))
    contacts[:, FEET] = value
    return contacts


def test_a_standing_body_that_drifts_is_held_where_it_stands():
    drifting = biped(speed=1.0)
    out = settle_root(drifting, feet_down(drifting))
    root = out.translations[:, 0]
    np.testing.assert_allclose(root[:, [0, 2]], np.broadcast_to(root[0, [0, 2]], (60, 2)),
                               atol=1e-12)
    np.testing.assert_allclose(root[:, 1], drifting.translations[:, 0, 1])  # height as decoded
    np.testing.assert_array_equal(out.rotations, drifting.rotations)
    np.testing.assert_array_equal(out.translations[:, 1:], drifting.translations[:, 1:])


def test_a_walk_keeps_the_decoded_root_path():
    """Legs swinging 30 degrees at 1 Hz move the feet relative to the root
    far faster than a standing body's: no frame is still."""
    walk = biped(speed=1.0, swing_degrees=30.0)
    assert not still_frames(walk.global_positions(), feet_down(walk), FEET, FPS, 1.6).any()
    np.testing.assert_array_equal(settle_root(walk, feet_down(walk)).translations,
                                  walk.translations)


def test_a_body_with_no_joint_in_contact_keeps_its_path():
    """A glide with every contact below the threshold (a flight, a swim)."""
    glide = biped(speed=1.0)
    np.testing.assert_array_equal(settle_root(glide, feet_down(glide, 0.3)).translations,
                                  glide.translations)


def test_only_the_still_stretch_is_held_and_the_rest_keeps_the_decoded_steps():
    """Standing for the first second, walking for the second: the root
    stays put, then takes the decoder's steps from where it stood."""
    stand, walk = biped(30, speed=1.0), biped(60, speed=1.0, swing_degrees=30.0)
    motion = stand.with_(rotations=np.concatenate([stand.rotations, walk.rotations[30:]]),
                         translations=np.concatenate([stand.translations,
                                                      walk.translations[30:]]))
    out = settle_root(motion, feet_down(motion)).translations[:, 0]
    assert np.abs(out[:20, 2] - out[0, 2]).max() < 1e-12
    steps, decoded = np.diff(out[:, 2]), np.diff(motion.translations[:, 0, 2])
    np.testing.assert_allclose(steps[40:], decoded[40:])
    assert out[-1, 2] < motion.translations[-1, 0, 2] - 0.5  # it lost the drift


def test_contact_steps_keep_a_planted_foot_in_place():
    """A foot in contact that moves back relative to the root by 2 cm a
    frame moves the root forward by 2 cm a frame; nothing in contact: 0."""
    frames = 5
    pos = np.zeros((frames, 2, 3))
    pos[:, 1, 2] = -0.02 * np.arange(frames)
    contacts = np.zeros((frames, 2))
    contacts[:, 1] = 1.0
    np.testing.assert_allclose(contact_steps(pos, contacts), [[0, 0, 0.02]] * (frames - 1))
    np.testing.assert_array_equal(contact_steps(pos, np.zeros((frames, 2))), 0.0)


def test_contacts_of_the_wrong_shape_are_refused():
    motion = biped(10)
    with pytest.raises(ValueError, match=r"contacts must be \[10, 9\]"):
        settle_root(motion, np.zeros((10, 4)))


def test_a_retarget_stands_where_its_source_stands_and_moves_where_it_moves():
    """Source: one second standing, then one walking. The retarget glides
    throughout; held, it takes no step while the source stands, then the
    decoder's steps; its height and rotations stay as decoded."""
    stand, walk = biped(30, speed=0.0), biped(60, speed=1.0, swing_degrees=30.0)
    source = stand.with_(rotations=np.concatenate([stand.rotations, walk.rotations[30:]]),
                         translations=np.concatenate([stand.translations,
                                                      walk.translations[30:]]))
    source.translations[30:, 0, 2] -= source.translations[30, 0, 2]  # walks off from 0
    still = source_still_steps(source)
    assert still[:25].all() and not still[35:].any()
    glide = biped(60, speed=1.0)
    held = hold_still_source(glide, source)
    root, decoded = held.translations[:, 0], glide.translations[:, 0]
    assert np.abs(root[:25, [0, 2]] - root[0, [0, 2]]).max() < 1e-12
    np.testing.assert_allclose(np.diff(root[:, 2])[35:], np.diff(decoded[:, 2])[35:])
    np.testing.assert_array_equal(root[:, 1], decoded[:, 1])
    np.testing.assert_array_equal(held.rotations, glide.rotations)


def test_a_moving_source_leaves_the_retarget_as_decoded_and_frames_must_match():
    walk, glide = biped(40, speed=1.0, swing_degrees=30.0), biped(40, speed=0.7)
    assert not source_still_steps(walk).any()
    np.testing.assert_array_equal(hold_still_source(glide, walk).translations,
                                  glide.translations)
    with pytest.raises(ValueError, match="the retarget has 40 frames and its source 30"):
        hold_still_source(glide, biped(30))
