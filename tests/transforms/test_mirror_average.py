"""Averaging a reading with its mirror image's
(:mod:`satagraph.transforms.mirror_average`) and the pairing it mirrors by."""
from __future__ import annotations

import numpy as np
import pytest

from satagraph.datasets.zoo import generate_clip, zoo_rigs
from satagraph.ops.rotation_numpy import rotation_about_numpy, yaw_matrix_numpy
from satagraph.skeleton import Skeleton
from satagraph.transforms.augment import mirror, mirror_pairs
from satagraph.transforms.canonical import canonicalize
from satagraph.transforms.mirror_average import (average_readings, mirror_back,
                                                 mirror_canonical, place_reading)

RIGS = {r.species: r for r in zoo_rigs(seed=0)}


@pytest.fixture(scope="module")
def canon():
    return canonicalize(generate_clip(RIGS["biped"], "turn", frames=12, seed=1))


def _moved(motion, yaw: float, shift: np.ndarray):
    """:obj:`motion` turned about +Y through the origin and shifted."""
    turn = yaw_matrix_numpy(yaw)
    rotations, translations = motion.rotations.copy(), motion.translations.copy()
    rotations[:, 0] = turn @ rotations[:, 0]
    translations[:, 0] = translations[:, 0] @ turn.T + shift
    return motion.with_(rotations=rotations, translations=translations)


def test_mirror_pairs_see_through_exporter_tags() -> None:
    """Training mirrors tagged rigs (a third of the zoo's) with their sides
    swapped: ``LeftUpLeg__x7Q`` pairs with ``RightUpLeg__k3Z``."""
    names = ["Hips__m2K", "LeftUpLeg__x7Q", "RightUpLeg__k3Z", "LeftLeg__a1B", "RightLeg__c2D"]
    skeleton = Skeleton(names=names, parents=np.array([-1, 0, 0, 1, 2]),
                        offsets=np.array([[0, 1, 0], [.1, 0, 0], [-.1, 0, 0],
                                          [0, -.4, 0], [0, -.4, 0]], float),
                        channels=[("Xrotation",)] * 5, end_site=np.zeros(5, bool))
    assert mirror_pairs(skeleton).tolist() == [0, 2, 1, 4, 3]


def test_a_rig_without_sides_has_no_mirror_image() -> None:
    snake = canonicalize(generate_clip(RIGS["snake"], "walk", frames=8, seed=0))
    assert mirror_canonical(snake) is None


def test_mirror_back_undoes_the_mirror_wherever_the_twin_was_placed(canon) -> None:
    """The pipeline turns and places the mirror image as its own rule says;
    the mirrored-back output lands on the source (global positions exact)."""
    twin = mirror_canonical(canon)
    assert twin is not None
    assert not np.allclose(twin.global_positions(), canon.global_positions())
    moved = _moved(twin, 0.7, np.array([0.3, 0.0, -1.2]))
    back = mirror_back(moved, moved, canon)
    assert np.allclose(back.global_positions(), canon.global_positions(), atol=1e-9)
    assert back.skeleton.names == canon.skeleton.names


def test_the_average_of_two_opposite_errors_is_the_truth(canon) -> None:
    """Rotations off by +-0.2 rad about one axis and a root off by +-d
    average back to the motion itself; a motion averaged with itself is
    unchanged."""
    rng = np.random.default_rng(0)
    axis = rng.normal(size=3)
    shift = np.array([0.05, -0.02, 0.1])
    plus = canon.with_(rotations=canon.rotations @ rotation_about_numpy(axis, 0.2),
                       translations=canon.translations + shift)
    minus = canon.with_(rotations=canon.rotations @ rotation_about_numpy(axis, -0.2),
                        translations=canon.translations - shift)
    mean = average_readings(plus, minus)
    assert np.allclose(mean.rotations, canon.rotations, atol=1e-12)
    assert np.allclose(mean.translations[:, 0], canon.translations[:, 0], atol=1e-12)
    assert np.allclose(mean.translations[:, 1:], plus.translations[:, 1:])  # offsets: the first's
    same = average_readings(canon, canon)
    assert np.allclose(same.global_positions(), canon.global_positions(), atol=1e-12)


def test_three_readings_average_to_their_common_truth(canon) -> None:
    """Rotations off by 0 and +-0.3 rad about one axis, roots off by 0 and
    +-d: the mean of the three is the motion; one reading is itself."""
    axis, shift = np.array([0.2, 1.0, -0.4]), np.array([0.1, 0.0, -0.05])
    off = []
    for angle, k in ((0.3, 1), (0.0, 0), (-0.3, -1)):
        translations = canon.translations.copy()
        translations[:, 0] += k * shift
        off.append(canon.with_(rotations=canon.rotations @ rotation_about_numpy(axis, angle),
                               translations=translations))
    mean = average_readings(*off)
    assert np.allclose(mean.global_positions(), canon.global_positions(), atol=1e-12)
    assert average_readings(off[0]) is off[0]


def test_place_reading_undoes_the_turn_a_second_reading_was_given(canon) -> None:
    """A second reading's pipeline may turn its source about +Y and place
    it elsewhere; its output, placed by the source it was given, lands on
    the first reading's (global positions exact)."""
    moved = _moved(canon, -1.1, np.array([0.4, 0.0, 0.9]))
    assert not np.allclose(moved.global_positions(), canon.global_positions())
    placed = place_reading(moved, moved, canon)
    assert np.allclose(placed.global_positions(), canon.global_positions(), atol=1e-9)


def test_readings_of_different_clips_do_not_average(canon) -> None:
    with pytest.raises(ValueError, match="frames, joints"):
        average_readings(canon, canon.with_(rotations=canon.rotations[:5],
                                            translations=canon.translations[:5]))


def test_mirror_of_the_mirror_is_the_motion(canon) -> None:
    twin = mirror_canonical(canon)
    assert np.allclose(mirror(twin).global_positions(), canon.global_positions(), atol=1e-12)


def test_legs_numbered_across_the_body_have_no_mirror_image() -> None:
    """The zoo's spiders name their legs ``Leg_L_01`` ... ``Leg_R_08``: no
    leg has a counterpart by name, and a reflection that swaps none would
    carry left-named legs on the right. ``mirror`` refuses it; training's
    augmentation and the averaged reading leave such a rig as it is."""
    spider = canonicalize(generate_clip(RIGS["spider"], "walk", frames=8, seed=0))
    assert any("_L_0" in n for n in spider.skeleton.names)
    with pytest.raises(ValueError, match="no counterpart"):
        mirror(spider)
    assert mirror_canonical(spider) is None
