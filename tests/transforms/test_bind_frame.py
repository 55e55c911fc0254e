"""A leading bind-pose frame: found on synthetic and real clips, given frame
1's pose (the clip keeps its length), and left alone where there is none."""
from __future__ import annotations

import numpy as np
import pytest

from satagraph.motion import Motion
from satagraph.ops.rotation_numpy import rotation_about_numpy
from satagraph.skeleton import Skeleton
from satagraph.transforms.bind_frame import has_bind_frame, replace_bind_frame
from satagraph.transforms.canonical import canonicalize

FPS = 30.0
NAMES = ["Hips", "Spine", "Head", "LeftArm", "LeftHand", "RightArm", "RightHand"]
PARENTS = np.array([-1, 0, 1, 1, 3, 1, 5])
OFFSETS = np.array([[0, 0.9, 0], [0, 0.3, 0], [0, 0.4, 0], [0.2, 0.2, 0], [0.3, 0, 0],
                    [-0.2, 0.2, 0], [-0.3, 0, 0]], dtype=float)


def walker(frames: int = 60) -> Motion:
    """Arms down at the sides, swinging 20 degrees at 1 Hz; the root
    travels +Z at 1 m/s."""
    t = np.arange(frames) / FPS
    rotations = np.broadcast_to(np.eye(3), (frames, len(NAMES), 3, 3)).copy()
    swing = np.radians(20.0) * np.sin(2 * np.pi * t)
    rotations[:, 3] = rotation_about_numpy(np.array([1.0, 0, 0]), swing) @ \
        rotation_about_numpy(np.array([0, 0, 1.0]), np.full(frames, -np.pi / 2))
    rotations[:, 5] = rotation_about_numpy(np.array([1.0, 0, 0]), -swing) @ \
        rotation_about_numpy(np.array([0, 0, 1.0]), np.full(frames, np.pi / 2))
    translations = np.broadcast_to(OFFSETS, (frames, len(NAMES), 3)).copy()
    translations[:, 0, 2] = 5.0 + t
    skeleton = Skeleton(names=NAMES, parents=PARENTS, offsets=OFFSETS)
    return Motion(skeleton, rotations, translations, fps=FPS)


def with_bind(motion: Motion, teleport: bool) -> Motion:
    """:obj:`motion` with frame 0 the T-pose of the rest offsets (at the
    origin when :obj:`teleport`, else where frame 1 stands)."""
    rotations, translations = motion.rotations.copy(), motion.translations.copy()
    rotations[0] = np.eye(3)
    translations[0] = OFFSETS if teleport else translations[1]
    return motion.with_(rotations=rotations, translations=translations)


@pytest.mark.parametrize("teleport", [False, True])
def test_a_bind_frame_is_given_frame_one_s_pose(teleport: bool) -> None:
    clean = walker()
    bound = with_bind(clean, teleport)
    assert has_bind_frame(bound) and not has_bind_frame(clean)
    fixed = replace_bind_frame(bound)
    assert fixed.num_frames == bound.num_frames
    np.testing.assert_array_equal(fixed.rotations[0], bound.rotations[1])
    np.testing.assert_array_equal(fixed.translations[0], bound.translations[1])
    np.testing.assert_array_equal(fixed.rotations[1:], bound.rotations[1:])
    assert not has_bind_frame(fixed)
    assert replace_bind_frame(clean) is clean


def test_a_short_clip_or_a_small_jump_is_no_bind_frame() -> None:
    bound = with_bind(walker(), teleport=True)
    assert not has_bind_frame(bound.slice(0, 7))
    nudged = walker()
    rotations = nudged.rotations.copy()
    rotations[0, 3] = rotation_about_numpy(np.array([0, 0, 1.0]), np.array([-1.4]))[0]
    assert not has_bind_frame(nudged.with_(rotations=rotations))  # one joint, 0.17 rad


def test_canonicalize_replaces_it_unless_asked_not_to() -> None:
    bound = with_bind(walker(), teleport=True)
    root = canonicalize(bound, fps=None).root_translation
    kept = canonicalize(bound, fps=None, replace_bind=False).root_translation
    steps, kept_steps = (np.linalg.norm(np.diff(r[:, [0, 2]], axis=0), axis=1)
                         for r in (root, kept))
    assert steps.max() < 0.05 and kept_steps[0] > 4.0
    np.testing.assert_allclose(root[0, [0, 2]], 0.0, atol=1e-9)  # the origin: the motion's start


def test_real_exports_with_and_without_one(read_real) -> None:
    for path in ("cmu/01_01.bvh", "ccbase/007_07.bvh", "ccbase/007_12.bvh"):
        motion = read_real(path)
        assert has_bind_frame(motion), path
        canon = canonicalize(motion, fps=None)
        step = np.linalg.norm(np.diff(canon.root_translation, axis=0), axis=1)
        assert step[0] <= 2 * np.median(step) + 1e-6, path
    for path in ("ccbase/006_01.bvh", "cmu/angry_13_000.bvh", "bandai/dataset-1_walk_normal_002.bvh",
                 "dog/D1_001_KAN01_001.bvh"):
        assert not has_bind_frame(read_real(path)), path


def test_every_zoo_body_plan() -> None:
    """A zoo walk of every body plan is no bind frame; given its rest pose
    as frame 0 where frame 1 stands (CMU's case: no teleport), it is one,
    arthropods and their fast legs included."""
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    for rig in zoo_rigs(seed=0):
        clip = generate_clip(rig, "walk", frames=30, seed=1)
        rotations, translations = clip.rotations.copy(), clip.translations.copy()
        rotations[0] = np.eye(3)
        translations[0] = clip.skeleton.offsets
        translations[0, 0] = clip.translations[1, 0]
        bound = clip.with_(rotations=rotations, translations=translations)
        assert not has_bind_frame(clip) and has_bind_frame(bound), rig.species
