"""Canonicalisation: axes, facing, units, floor, resampling, inverse."""
import numpy as np
import pytest

from satagraph.ops.rotation_numpy import rotation_between_numpy
from satagraph.transforms.canonical import (_apply_rotation,
                                            canonicalize, decanonicalize,
                                            detect_up_axis, resample)
from satagraph.io import read_bvh, write_bvh
from satagraph.skeleton import Skeleton


@pytest.fixture(scope="module")
def human(shared_data):
    return read_bvh(shared_data / "cmu" / "01_01.bvh")


def test_canonical_frame(human):
    c = canonicalize(human)
    pos = c.global_positions()
    assert c.fps == 30 and c.transform.source_fps == 120
    np.testing.assert_allclose(c.translations[0, 0, [0, 2]], 0, atol=1e-9)
    assert 1.3 < c.height() < 2.0  # metres
    assert abs(np.percentile(pos[:, :, 1].min(1), 2)) < 5e-3  # floor at 0
    names = c.skeleton.names
    left = pos[0, names.index("LeftUpLeg")] - pos[0, names.index("RightUpLeg")]
    assert left[0] > 0.8 * np.linalg.norm(left)  # facing +Z: left is +X


def test_detects_and_undoes_z_up(human):
    to_z = rotation_between_numpy(np.array([0, 1.0, 0]), np.array([0, 0, 1.0]))
    z_up = _apply_rotation(human, to_z, 1.0, np.zeros(3))
    assert detect_up_axis(z_up) == "+Z"
    a, b = canonicalize(human, fps=None), canonicalize(z_up, fps=None)
    np.testing.assert_allclose(a.global_positions(), b.global_positions(), atol=1e-6)
    assert canonicalize(z_up, up_axis="+Y", fps=None).transform.up_axis == "+Y"
    with pytest.raises(ValueError, match="up_axis"):
        canonicalize(human, up_axis="up")


def test_static_root_removed_and_restored(shared_data, tmp_path):
    src = read_bvh(shared_data / "bandai" / "dataset-1_bow_active_001.bvh")
    c = canonicalize(src, fps=None)
    assert c.skeleton.names[0] == "Hips"
    assert c.transform.removed_root["name"] == "joint_Root"
    back = decanonicalize(c)
    write_bvh(back, tmp_path / "back.bvh")
    again = read_bvh(tmp_path / "back.bvh")
    assert again.skeleton.names == src.skeleton.names
    assert again.skeleton.channels == src.skeleton.channels
    # every rest offset the file's, the hips' too (not where they stood at frame 0)
    np.testing.assert_allclose(again.skeleton.offsets, src.skeleton.offsets, atol=1e-9)
    np.testing.assert_allclose(again.global_positions(), src.global_positions(),
                               atol=1e-4)


@pytest.mark.parametrize("rel, hips", [
    ("bandai/dataset-1_run_normal_001.bvh", "Hips"),  # the hips have position channels
    ("ccbase/007_01.bvh", "CC_Base_Hip")])            # RL_BoneRoot's hips have none
def test_a_root_carrying_the_hips_along_the_floor_is_folded_into_them(
        shared_data, tmp_path, rel: str, hips: str):
    """A root that travels on the floor below the hips (Bandai's run take,
    Reallusion's RL_BoneRoot) is folded into them like a motionless one:
    the hips are joint 0, at hip height, as on the rig's other takes; the
    file written back has the rig's joints and channels and every body
    joint where the source had it; the root travels with the body, at the
    source root's height (the floor)."""
    src = read_bvh(shared_data / rel)
    c = canonicalize(src, fps=None, replace_bind=False)
    assert c.skeleton.names[0] == hips and c.transform.removed_root["carries"]
    pos = c.global_positions()
    assert 0.45 < np.median(pos[:, 0, 1]) / c.height() < 0.75
    write_bvh(decanonicalize(c), tmp_path / "back.bvh")
    again = read_bvh(tmp_path / "back.bvh")
    assert again.skeleton.names == src.skeleton.names
    assert again.skeleton.channels == src.skeleton.channels
    a, b = again.global_positions(), src.global_positions()
    np.testing.assert_allclose(a[:, 1:], b[:, 1:], atol=1e-3)
    travel = lambda p: np.linalg.norm(p[-1, 0] - p[0, 0])
    assert abs(travel(a) - travel(b)) < 0.02 * travel(b)
    np.testing.assert_allclose(a[:, 0, 1], b[:, 0, 1], atol=1e-3)  # +Y up, on the floor


def unreal_wrap(motion, ik_first: bool = False):
    """:obj:`motion` (root = hips, +Y up, metres) as Unreal exports root
    motion: a ``root`` on the floor under the hips carrying their travel,
    the hips at a fixed offset above it, and the IK targets' helper chains
    (``ik_foot_root``, ``ik_hand_root``) hanging from the root beside them,
    before or after the body in the file."""
    from satagraph.motion import Motion
    sk, frames = motion.skeleton, motion.num_frames
    rot3 = ("Zrotation", "Xrotation", "Yrotation")
    lift = np.array([0.0, motion.translations[0, 0, 1], 0.0])
    ik = [(name, parent, np.array(offset, dtype=float), rot3, np.eye(3), None)
          for name, parent, offset in [
              ("ik_foot_root", "root", (0, 0, 0)), ("ik_foot_l", "ik_foot_root", (0.09, 0.08, 0)),
              ("ik_foot_r", "ik_foot_root", (-0.09, 0.08, 0)), ("ik_hand_root", "root", (0, 0, 0)),
              ("ik_hand_gun", "ik_hand_root", (0, 1.1, 0.4)),
              ("ik_hand_l", "ik_hand_gun", (0.2, 0, 0)), ("ik_hand_r", "ik_hand_gun", (0, 0, 0))]]
    body = [(n, "root" if p < 0 else sk.names[p], lift if p < 0 else sk.offsets[j],
             rot3 if p < 0 else sk.channels[j], motion.rotations[:, j],
             lift if p < 0 else motion.translations[:, j]) for j, (n, p) in enumerate(zip(
                 sk.names, sk.parents))]
    root = [("root", None, np.zeros(3), ("Xposition", "Yposition", "Zposition") + rot3,
             np.eye(3), motion.translations[:, 0] - lift)]
    joints = root + (ik + body if ik_first else body + ik)
    names = [j[0] for j in joints]
    skeleton = Skeleton(names=names, parents=np.array([-1] + [names.index(j[1]) for j in joints[1:]]),
                        offsets=np.array([j[2] for j in joints]), channels=[j[3] for j in joints],
                        end_site=np.array([bool(n in sk.names and sk.end_site[sk.names.index(n)])
                                           for n in names]))
    rot = np.stack([np.broadcast_to(j[4], (frames, 3, 3)) for j in joints], axis=1)
    trans = np.stack([np.broadcast_to(j[2] if j[5] is None else j[5], (frames, 3))
                      for j in joints], axis=1)
    return Motion(skeleton, rot, trans, fps=motion.fps)


@pytest.mark.parametrize("ik_first", [False, True])
def test_an_unreal_root_with_ik_chains_is_folded_and_put_back(tmp_path, ik_first: bool):
    """Unreal's ``root`` has three children, the hips and two IK chains:
    the IK chains are set aside, the root folded into the hips, and the
    canonical motion is the body's alone, the same as the unwrapped clip's;
    written back, the rig has its joints in its order and the body is where
    it was."""
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    plain = generate_clip(zoo_rigs(["biped"])[0], "walk", frames=40, seed=2)
    wrapped = unreal_wrap(plain, ik_first)
    a, b = canonicalize(plain, fps=None), canonicalize(wrapped, fps=None)
    assert b.skeleton.names == plain.skeleton.names
    np.testing.assert_allclose(b.global_positions(), a.global_positions(), atol=1e-9)
    assert b.transform.removed_root["carries"]
    write_bvh(decanonicalize(b), tmp_path / "back.bvh")
    again = read_bvh(tmp_path / "back.bvh")
    assert again.skeleton.names == wrapped.skeleton.names
    assert list(again.skeleton.parents) == list(wrapped.skeleton.parents)
    body = [wrapped.skeleton.names.index(n) for n in plain.skeleton.names]
    np.testing.assert_allclose(again.global_positions()[:, body],
                               wrapped.global_positions()[:, body], atol=1e-4)


def test_a_root_carrying_the_body_with_the_hips_at_its_origin_is_folded(tmp_path):
    """3ds Max's ``Bip01`` carries the body and ``Bip01 Pelvis`` sits at its
    origin, turning below it: folded, the clip reads as the bare one, and
    written back the rig keeps both joints and every position."""
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    from satagraph.motion import Motion
    from satagraph.ops.rotation_numpy import rotation_about_numpy
    plain = generate_clip(zoo_rigs(["biped"])[0], "walk", frames=40, seed=2)
    sk, frames = plain.skeleton, plain.num_frames
    yaw = rotation_about_numpy(np.array([0.0, 1, 0]), np.linspace(0, 0.5, frames))
    rig = Skeleton(names=["Bip01"] + sk.names, parents=np.r_[-1, 0, sk.parents[1:] + 1],
                   offsets=np.r_[sk.offsets[:1], np.zeros((1, 3)), sk.offsets[1:]],
                   channels=[sk.channels[0], ("Zrotation", "Xrotation", "Yrotation")]
                   + list(sk.channels[1:]), end_site=np.r_[False, sk.end_site])
    rot = np.concatenate([yaw[:, None], np.swapaxes(yaw, -1, -2)[:, None] @ plain.rotations[:, :1],
                          plain.rotations[:, 1:]], axis=1)
    trans = np.concatenate([plain.translations[:, :1], np.zeros((frames, 1, 3)),
                            plain.translations[:, 1:]], axis=1)
    biped = Motion(rig, rot, trans, fps=plain.fps)
    np.testing.assert_allclose(biped.global_positions()[:, 1:], plain.global_positions(), atol=1e-9)
    a, b = canonicalize(plain, fps=None), canonicalize(biped, fps=None)
    assert b.skeleton.names == sk.names
    np.testing.assert_allclose(b.global_positions(), a.global_positions(), atol=1e-9)
    write_bvh(decanonicalize(b), tmp_path / "back.bvh")
    again = read_bvh(tmp_path / "back.bvh")
    assert again.skeleton.names == rig.names and again.skeleton.channels == rig.channels
    np.testing.assert_allclose(again.global_positions()[:, 1:], plain.global_positions(),
                               atol=1e-4)


def test_a_root_moving_with_the_body_stays_the_root():
    """The zoo's crab ``Root`` and 3ds Max's ``Bip01`` move with the body
    and sit at its centre, right on their only child: not folded."""
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    from satagraph.transforms.canonical import fold_root
    for species in ("crab", "fowl"):
        rig = zoo_rigs([species])[0]
        motion = generate_clip(rig, "walk", frames=30, seed=1)
        assert len(motion.skeleton.children[0]) == 1
        assert np.ptp(motion.translations[:, 0], axis=0).max() > 0.05  # it moves
        folded, removed = fold_root(motion)
        assert removed is None and folded is motion


def test_a_one_frame_rig_folds_the_roots_its_full_clip_folds(shared_data):
    """One frame cannot tell a still root from a moving one: Bandai's
    ``joint_Root`` on the floor under the hips stayed the model's root of a
    one-frame target (a retarget onto it travelled 0.69 heights, onto the
    whole file 1.75); a root at the body's centre stays, as in a clip."""
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    from satagraph.transforms.canonical import fold_root
    src = read_bvh(shared_data / "bandai" / "dataset-1_walk_normal_001.bvh")
    for frames in (1, 2):
        c = canonicalize(src.slice(0, frames), fps=None)
        assert c.skeleton.names[0] == "Hips"
        assert c.transform.removed_root["name"] == "joint_Root"
    for species in ("crab", "fowl"):
        motion = generate_clip(zoo_rigs([species])[0], "walk", frames=30, seed=1).slice(0, 1)
        assert fold_root(motion)[1] is None


def test_resample_keeps_endpoints_and_is_slerp(human):
    clip = human.slice(0, 121)
    down = resample(clip, 30)
    assert down.num_frames == 31 and down.fps == 30
    np.testing.assert_allclose(down.rotations[::1], clip.rotations[::4], atol=1e-9)
    up = resample(clip.slice(0, 5), 240)
    assert up.num_frames == 9
    mid = up.rotations[1]
    rel = np.einsum("jki,jkl->jil", clip.rotations[0], mid)
    rel2 = np.einsum("jki,jkl->jil", mid, clip.rotations[1])
    ang = lambda r: np.arccos(np.clip((np.trace(r, axis1=1, axis2=2) - 1) / 2, -1, 1))
    np.testing.assert_allclose(ang(rel), ang(rel2), atol=1e-6)  # halfway


def test_decanonicalize_round_trip(human):
    """Exact, but for the bind frame CMU's exporter writes first (frame 0
    given frame 1's pose), and exact to the letter with it kept."""
    from satagraph.transforms.bind_frame import has_bind_frame, replace_bind_frame
    clip = human.slice(0, 200)
    assert has_bind_frame(clip)
    back = decanonicalize(canonicalize(clip, fps=None))
    np.testing.assert_allclose(back.global_positions(),
                               replace_bind_frame(clip).global_positions(), atol=1e-8)
    kept = decanonicalize(canonicalize(clip, fps=None, replace_bind=False))
    np.testing.assert_allclose(kept.global_positions(), clip.global_positions(), atol=1e-8)


def test_one_resampling_rule(human):
    """resample and the inference's exact-count resampling are one rule."""
    from satagraph.pipelines import inference
    from satagraph.transforms.canonical import resample_frames

    assert inference.resample_frames is resample_frames
    clip = human.slice(0, 37)
    down = resample(clip, 30)
    same = resample_frames(clip, 30, down.num_frames)
    np.testing.assert_array_equal(down.rotations, same.rotations)
    np.testing.assert_array_equal(down.translations, same.translations)
    held = resample_frames(clip, 30, down.num_frames + 2)
    np.testing.assert_allclose(held.translations[-2:], clip.translations[[-1, -1]])


def _facing_error(motion) -> float:
    """Degrees between the canonical frame 0's facing (+Z, the root-local
    axis the features' facing frame follows) and the body's mean forward
    over the clip (every left/right pair), both in the root's frame."""
    from satagraph.transforms.canonical import lateral_pairs
    canon = canonicalize(motion, fps=None)
    rot, pos = canon.rotations[:, 0], canon.global_positions()
    left, right = lateral_pairs(canon.skeleton.names)
    body = np.cross((pos[:, left] - pos[:, right]).mean(1), [0.0, 1.0, 0.0])
    mean = rot[0] @ np.einsum("tji,tj->i", rot, body / np.linalg.norm(body, axis=-1,
                                                                       keepdims=True))
    return abs(np.degrees(np.arctan2(mean[0], mean[2])))


@pytest.mark.parametrize("species", ["biped", "quadruped"])
def test_facing_is_read_from_the_pairs_nearest_the_root(species, monkeypatch):
    """Feet and hands swing with the stride: read from every left/right
    pair, a walk's frame 0 set its facing 12 (biped) and 35 (quadruped)
    degrees off the body's mean forward on these eight walks, with the
    stride's phase; from the hips it is 3-4 degrees off, so a clip's facing frame does not depend on where
    in the stride it starts."""
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    import satagraph.transforms.canonical as canonical
    rigs = [r for r in zoo_rigs(seed=1) if r.species == species][:1] + \
        [r for r in zoo_rigs(seed=2) if r.species == species][:1]
    walks = [generate_clip(rig, "walk", frames=60, seed=s) for rig in rigs for s in range(4)]
    new = np.mean([_facing_error(w) for w in walks])
    monkeypatch.setattr(canonical, "facing_pairs",
                        lambda skeleton, pose: canonical.lateral_pairs(skeleton.names))
    old = np.mean([_facing_error(w) for w in walks])
    assert new < 4.0 < 10.0 < old


def test_an_unreal_rig_is_read_on_its_body(shared_data):
    """``read_rig`` (what ``inspect`` and ``render`` print) reads the body
    below a folded root: a human on Unreal's rig in cm is a human in cm,
    where the floor root with three children hid its hips."""
    from satagraph.transforms.rig_reading import read_rig
    human = canonicalize(read_bvh(shared_data / "bandai" / "dataset-1_walk_normal_001.bvh"))
    wrapped = unreal_wrap(human)
    in_cm = wrapped.with_(skeleton=wrapped.skeleton.replace(offsets=wrapped.skeleton.offsets * 100),
                          translations=wrapped.translations * 100)
    in_cm.rig = None
    reading = read_rig(in_cm)
    assert reading.up.axis == "+Y" and reading.units.scale == 0.01 and not reading.units.kept


@pytest.mark.parametrize("up", ["+Z", "-Z", "-X"])
def test_a_rig_of_another_up_axis_stands_up_whole(up):
    """A rig exported with another up axis (offsets along +Z, as Blender
    writes) canonicalises to its +Y twin's rest pose and local rotations, not
    only its global positions (a lying rest made every retarget onto a +Z rig
    collapse to 0.8 of the height); the inverse gives the file back."""
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    from satagraph.datasets.zoo.dialects import Dialect, apply_dialect
    clip = generate_clip(zoo_rigs(["biped"])[0], "walk", frames=30, seed=3)
    twin, _ = apply_dialect(clip, Dialect(up_axis=up))
    assert not np.allclose(twin.skeleton.offsets, clip.skeleton.offsets)
    a, b = canonicalize(clip, up_axis="+Y"), canonicalize(twin, up_axis=up)
    np.testing.assert_allclose(b.skeleton.offsets[1:], a.skeleton.offsets[1:], atol=1e-9)
    np.testing.assert_allclose(b.rotations, a.rotations, atol=1e-9)
    np.testing.assert_allclose(b.global_positions(), a.global_positions(), atol=1e-9)
    back = decanonicalize(b, fps=twin.fps)
    np.testing.assert_allclose(back.skeleton.offsets, twin.skeleton.offsets, atol=1e-9)
    np.testing.assert_allclose(back.global_positions(), twin.global_positions(), atol=1e-9)


def test_a_one_frame_rig_whose_hips_have_no_position_channels_writes_the_travel(
        shared_data, tmp_path):
    """CC_Base's ``RL_BoneRoot`` above hips with rotation channels only,
    read from one frame, is folded as a still root: put back held, it left
    the travel on the hips, which the writer drops (a retarget of a 4 m
    walk onto a one-frame 007_01 walked in place, 3-9 of the rig's sizes
    from the motion it decoded). The root carries it, as in the clip."""
    clip = read_bvh(shared_data / "ccbase" / "007_01.bvh")
    one = canonicalize(clip.slice(0, 1), fps=None)
    assert one.transform.removed_root["name"] == "RL_BoneRoot"
    assert not one.transform.removed_root["carries"]
    walk = canonicalize(clip, fps=None)  # the clip's walk on the one-frame rig's axes
    out = decanonicalize(walk.with_(transform=one.transform), one.transform)
    write_bvh(out, tmp_path / "out.bvh")
    back = read_bvh(tmp_path / "out.bvh")
    size = float(np.ptp(clip.first_pose(), axis=0).max())
    np.testing.assert_allclose(back.global_positions(), out.global_positions(),
                               atol=1e-4 * size)
    hips = back.global_positions()[:, 1]
    assert np.linalg.norm(hips[-1] - hips[0]) > 0.5 * size


def _slerp_of_every_frame(motion, fps: float, num_frames: int) -> np.ndarray:
    """The rotations resample_frames gave before it converted in numpy, and
    only the frames it reads: every frame through roma, torch's slerp."""
    import torch
    from satagraph.ops.rotation import (matrix_to_quaternion, quaternion_slerp,
                                        quaternion_to_matrix)
    last = motion.num_frames - 1
    times = np.minimum(np.arange(num_frames) * (motion.fps / fps), last)
    lo = np.minimum(np.floor(times).astype(np.int64), max(last - 1, 0))
    hi = np.minimum(lo + 1, last)
    quat = matrix_to_quaternion(torch.from_numpy(motion.rotations))
    weight = torch.from_numpy(times - lo)[:, None].expand(num_frames, motion.num_joints)
    return quaternion_to_matrix(quaternion_slerp(quat[lo], quat[hi], weight)).numpy()


@pytest.mark.parametrize("fps, extra", [(30, 0), (30, 3), (47, 0), (240, 0)])
def test_resample_frames_gives_the_old_values_to_an_ulp(read_real, fps, extra):
    """Down (every 4th frame read), odd and up rates, frames held past the
    end: the same rotations as converting every frame through roma."""
    from satagraph.transforms.canonical import resample_frames
    clip = read_real("cmu/01_01.bvh").slice(0, 90)  # 120 fps
    count = int(np.floor((clip.num_frames - 1) * fps / clip.fps + 1e-9)) + 1 + extra
    out = resample_frames(clip, fps, count)
    np.testing.assert_allclose(out.rotations, _slerp_of_every_frame(clip, fps, count),
                               rtol=0, atol=1e-15)  # bit for bit on the VM
