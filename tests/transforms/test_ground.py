"""Grounding a decoded motion: where its source or its target stands."""
from __future__ import annotations

import numpy as np

from satagraph.datasets.zoo import generate_clip, zoo_rigs
from satagraph.transforms.canonical import canonicalize
from satagraph.transforms.ground import (ground_like, ground_retarget, lift_above_floor,
                                         ground_frames, lowest_heights, standing_frames)


def _clip(species: str, kind: str = "walk", seed: int = 0):
    return canonicalize(generate_clip(zoo_rigs([species])[0], kind, frames=60, seed=seed),
                        fps=30.0)


def _lifted(motion, dy):
    trans = motion.translations.copy()
    trans[:, 0, 1] += dy
    return motion.with_(translations=trans)


def test_a_floating_retarget_comes_down_by_one_constant():
    """A quadruped floating 0.3 m (and bobbing as it did) is moved down so
    that its median lowest joint is where the biped source's is, in
    heights; frame-to-frame height changes are kept."""
    source, target = _clip("biped"), _clip("quadruped", seed=1)
    floating = _lifted(target, 0.3 + 0.05 * np.sin(np.arange(60) / 5.0))
    out = ground_like(floating, source)
    want = np.median(lowest_heights(source)) / source.height() * out.height()
    assert abs(np.median(lowest_heights(out)) - want) < 1e-9
    shift = out.translations[:, 0, 1] - floating.translations[:, 0, 1]
    np.testing.assert_allclose(shift, shift[0])
    np.testing.assert_array_equal(out.rotations, floating.rotations)
    np.testing.assert_array_equal(out.translations[:, 1:], floating.translations[:, 1:])


def test_the_source_height_above_the_floor_carries_over_in_heights():
    """A source standing 10 % of its height above the floor puts a target
    of another size 10 % of the target's height above it."""
    source, target = _clip("biped"), _clip("bird", seed=2)
    raised = _lifted(source, 0.1 * source.height() - np.median(lowest_heights(source)))
    out = ground_like(target, raised)
    np.testing.assert_allclose(np.median(lowest_heights(out)) / out.height(), 0.1, atol=1e-9)


def test_a_motion_without_frames_is_unchanged():
    source = _clip("biped")
    empty = source.slice(0, 0)
    assert ground_like(empty, source) is empty


def test_a_retarget_stands_as_its_target_stands_not_as_its_source():
    """A source whose lowest joint stays 9 % of its height above the floor
    (the dog's paw end sites) does not lift a retarget: it stands as the
    target clip does; a target without frames falls back to the source."""
    source, target = _clip("quadruped"), _clip("biped", seed=1)
    offset = _lifted(source, 0.09 * source.height() - np.median(lowest_heights(source)))
    floating = _lifted(_clip("biped", seed=2), 0.4)
    out = ground_retarget(floating, offset, target)
    np.testing.assert_allclose(np.median(lowest_heights(out)) / out.height(),
                               np.median(lowest_heights(target)) / target.height(), atol=1e-9)
    assert abs(np.median(lowest_heights(out))) < 0.03 * out.height()
    out = ground_retarget(floating, offset, target.slice(0, 0))
    np.testing.assert_allclose(np.median(lowest_heights(out)) / out.height(), 0.09, atol=1e-9)


def test_a_sinking_frame_is_raised_to_the_floor_and_no_other_moves():
    """Frames whose lowest joint is below the floor come up by exactly that
    depth; frames above it, the horizontal path and the rotations stay."""
    walk = _clip("biped")
    dip = np.where(np.arange(60) < 15, -0.2 * walk.height(), 0.0)  # the first quarter sinks
    sunk = _lifted(walk, dip + 0.01)
    out = lift_above_floor(sunk)
    low = lowest_heights(out)
    assert low.min() >= -1e-9
    np.testing.assert_allclose(low[:15], 0.0, atol=1e-9)
    np.testing.assert_array_equal(out.translations[15:], sunk.translations[15:])
    np.testing.assert_array_equal(out.translations[:, 0, [0, 2]], sunk.translations[:, 0, [0, 2]])
    np.testing.assert_array_equal(out.rotations, sunk.rotations)
    above = _lifted(walk, 0.05)
    assert lift_above_floor(above) is above


def test_a_body_stands_on_the_chains_that_touch_the_floor_nearest_its_root(read_real):
    """Stripped of its finger and face bones, a CC_Base rig's largest chain
    from the root was its legs, and the waist and hands became what it
    stood on: 2 of 288 frames stood. Its support is its feet with or
    without them, and the same frames stand."""
    from satagraph.transforms.augment import _subset
    from satagraph.transforms.canonical import canonicalize
    from satagraph.transforms.ground import stands, support_joints
    full = canonicalize(read_real("ccbase/006_07.bvh"))
    skel = full.skeleton
    hands = [skel.index(f"CC_Base_{s}_Hand") for s in "LR"] + [skel.index("CC_Base_FacialBone")]
    below = {int(j) for h in hands for j in skel.subtree(h)} - set(hands)
    stripped = _subset(full, [j for j in range(skel.num_joints) if j not in below])
    assert len(stripped.skeleton.subtree(1)) > stripped.skeleton.num_joints / 2  # legs largest
    for motion in (full, stripped):
        pos = motion.global_positions()
        ends = {motion.skeleton.names[j] for j in support_joints(motion.skeleton, pos)
                if motion.skeleton.is_leaf[j]}
        assert ends and all("Toe" in n for n in ends), ends
    np.testing.assert_array_equal(stands(full.global_positions(), full.skeleton, full.fps),
                                  stands(stripped.global_positions(), stripped.skeleton,
                                         stripped.fps))


def test_a_retarget_stands_on_the_floor_where_its_source_stands():
    """A dog that lies most of a clip, its human retarget standing all along
    with its root lower while the dog lies, was grounded on the lying
    frames' median: the human hovered where the dog stood (0.7 m up on a
    real clip). Read over the frames where the source stands, it stands
    on the floor there, and the lying frames come up onto the floor. A
    walk, up on its legs throughout, is read over every frame."""
    lie = canonicalize(generate_clip(zoo_rigs(["quadruped"])[0], "lie", frames=90, seed=0),
                       fps=30.0)
    pos = lie.global_positions()
    depth = pos[:, 0, 1] - pos[:, :, 1].min(axis=1)
    standing = standing_frames(lie)
    assert 5 <= len(standing) <= 20 and standing.max() < 20  # it stands, then lies
    decoded = canonicalize(generate_clip(zoo_rigs(["biped"])[0], "idle", frames=90, seed=2),
                           fps=30.0)
    sinking = _lifted(decoded, 0.4 * decoded.height() * (depth / depth.max() - 1.0) + 0.3)
    target = _clip("biped", seed=1)
    out = ground_retarget(sinking, lie, target)
    level = np.median(lowest_heights(target)) / target.height()
    low = lowest_heights(out) / out.height()
    np.testing.assert_allclose(np.median(low[standing]), level, atol=1e-3)
    assert low.min() >= -1e-9 and low.max() < level + 0.02
    old = lift_above_floor(ground_like(sinking, target))  # every frame's median
    assert (lowest_heights(old) / old.height())[standing].min() > 0.2
    np.testing.assert_array_equal(ground_frames(lie), standing)
    assert ground_frames(_clip("quadruped")) is None


def test_a_snake_stands_in_every_frame_and_its_retarget_on_the_floor_in_all(tmp_path):
    """A snake's root lies among its support joints: read from a file, its
    stance is 1e-17 m of rounding, and read against it the snake lay in
    89 % of this walk's frames, so a retarget of it was stood on the
    floor over the other 5 and hovered over the rest (a human 8-9 % of its
    height up over most of a real zoo clip). It stands in every frame,
    and a retarget of it is grounded over all of them."""
    from satagraph.io import read_bvh, write_bvh
    from satagraph.transforms.ground import UP_SHARE, stands
    path = tmp_path / "snake.bvh"
    write_bvh(generate_clip(zoo_rigs(["snake"])[1], "walk", frames=90, seed=0), str(path))
    snake = canonicalize(read_bvh(str(path)), fps=30.0)
    assert snake.num_frames == 90
    assert stands(snake.global_positions(), snake.skeleton, snake.fps, UP_SHARE).all()
    assert ground_frames(snake) is None
    decoded = canonicalize(generate_clip(zoo_rigs(["biped"])[0], "idle", frames=90, seed=2),
                           fps=30.0)
    bobbing = _lifted(decoded, 0.3 + 0.1 * decoded.height() * np.sin(np.arange(90) / 4.0))
    target = _clip("biped", seed=1)
    out = ground_retarget(bobbing, snake, target)
    level = np.median(lowest_heights(target)) / target.height()
    low = lowest_heights(out) / out.height()
    np.testing.assert_allclose(np.median(low), level, atol=1e-3)
    assert low.max() < level + 0.25  # the bob's crest, not a hover on top of it
