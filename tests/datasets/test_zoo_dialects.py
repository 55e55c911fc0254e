"""Exporter dialects of the zoo: exact up-axis / unit changes, rest poses
that keep the motion, deterministic name noise, the manifest's truth
columns and the ``satagraph zoo`` dialect options."""
from __future__ import annotations

import csv
import re

import numpy as np
import pytest

from satagraph.cli import main
from satagraph.datasets.zoo import (DIALECT_COLUMNS, MANIFEST_COLUMNS, NOISE_STYLES, REST_POSES,
                                    UP_AXES, Dialect, add_name_noise, change_rest_pose,
                                    dialect_variants, export_dialect, generate_clip, unit_scale,
                                    up_rotation, write_dialect_zoo, write_zoo, zoo_rigs)
from satagraph.io import read_bvh, write_bvh

RIGS = {r.species: r for r in zoo_rigs(["biped", "crab", "fowl"], seed=0)}
MOTION = generate_clip(RIGS["biped"], "walk", frames=15, seed=1)
AXES = {"+X": [1, 0, 0], "-X": [-1, 0, 0], "+Y": [0, 1, 0], "-Y": [0, -1, 0],
        "+Z": [0, 0, 1], "-Z": [0, 0, -1]}


def _read(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f, delimiter="\t"))


@pytest.mark.parametrize("axis", UP_AXES)
def test_export_dialect_is_rigid_and_scaled(axis, tmp_path):
    rot = up_rotation(axis)
    assert np.isclose(np.linalg.det(rot), 1.0) and np.allclose(rot @ [0, 1, 0], AXES[axis])
    scale = 0.0254
    out = export_dialect(MOTION, axis, scale)
    rot_g, pos_g = MOTION.global_transforms()
    rot_e, pos_e = out.global_transforms()
    np.testing.assert_allclose(pos_e, pos_g @ rot.T / scale, atol=1e-9)
    np.testing.assert_allclose(rot_e, rot @ rot_g @ rot.T, atol=1e-12)
    # The rest pose stands along the new up axis too.
    rest = out.skeleton.rest_positions()
    assert np.argmax(np.ptp(rest, axis=0)) in (np.flatnonzero(AXES[axis])[0], 0)
    assert np.ptp(rest @ np.array(AXES[axis], float)) * scale == pytest.approx(
        np.ptp(MOTION.skeleton.rest_positions()[:, 1]))
    write_bvh(out, tmp_path / "a.bvh")
    back = read_bvh(tmp_path / "a.bvh")
    assert back.skeleton.names == MOTION.skeleton.names
    err = np.abs(back.global_positions() * scale - pos_g @ rot.T).max()
    assert err < 1e-4 * MOTION.height()


def test_units():
    assert unit_scale("cm", 2.0) == 0.01 and unit_scale("in", 2.0) == 0.0254
    assert unit_scale(28, 0.7) == pytest.approx(0.025) == unit_scale("28", 0.7)
    for bad in ("furlong", 0, "-3"):
        with pytest.raises(ValueError):
            unit_scale(bad, 1.0)
    with pytest.raises(ValueError):
        export_dialect(MOTION, "up")


@pytest.mark.parametrize("pose", REST_POSES)
@pytest.mark.parametrize("species", ["biped", "crab", "fowl"])
def test_rest_pose_keeps_positions(pose, species):
    motion = MOTION if species == "biped" else generate_clip(RIGS[species], "walk", frames=10)
    out = change_rest_pose(motion, pose, seed=4)
    ref = motion.global_positions()
    err = np.abs(out.global_positions() - ref).max()
    assert err <= 1e-6 * np.abs(ref).max()
    lengths = np.linalg.norm(motion.skeleton.offsets, axis=1)
    np.testing.assert_allclose(np.linalg.norm(out.skeleton.offsets, axis=1), lengths)
    moved = np.abs(out.skeleton.rest_positions() - motion.skeleton.rest_positions()).max()
    assert (moved > 1e-3 * motion.height()) == (pose != "native")


def test_apose_lowers_arms_and_crouch_bends_legs():
    skel = MOTION.skeleton
    hand, hips, foot = (skel.index(n) for n in ("LeftHand", "Hips", "LeftFoot"))
    before = skel.rest_positions()
    apose = change_rest_pose(MOTION, "apose").skeleton.rest_positions()
    assert apose[hand, 1] < before[hand, 1] - 0.1 * MOTION.height()
    crouched = change_rest_pose(MOTION, "crouched").skeleton.rest_positions()
    assert crouched[hips, 1] - crouched[foot, 1] < before[hips, 1] - before[foot, 1]


@pytest.mark.parametrize("style", NOISE_STYLES)
def test_name_noise(style):
    a = add_name_noise(MOTION, style, seed=7).skeleton.names
    assert a == add_name_noise(MOTION, style, seed=7).skeleton.names
    pattern = {"tag": r"__[a-z][0-9][A-Z]", "version": r"_v[2-9]",
               "hash": r"_(?:[a-f][0-9]){3}"}[style]
    skel = MOTION.skeleton
    for j, (old, new) in enumerate(zip(skel.names, a)):
        if skel.end_site[j]:
            assert new == a[skel.parents[j]] + "_end"
        else:
            assert re.fullmatch(re.escape(old) + pattern, new), new
    if style != "version":
        assert a != add_name_noise(MOTION, style, seed=8).skeleton.names
    with pytest.raises(ValueError):
        add_name_noise(MOTION, "emoji")


def test_write_zoo_dialects_record_the_truth(tmp_path):
    dialects = [Dialect(), Dialect("-Z", "cm", "apose", "tag"), Dialect("+X", 28.0, "flat")]
    rows = write_zoo(tmp_path, species=["fowl"], clips=1, frames=10, seed=2,
                     dialects=dialects)
    assert len(rows) == 2 * len(dialects)
    manifest = _read(tmp_path / "manifest.tsv")
    assert tuple(manifest[0]) == MANIFEST_COLUMNS and set(DIALECT_COLUMNS) <= set(manifest[0])
    canon = {r["skeleton"]: read_bvh(tmp_path / r["path"]) for r in manifest
             if r["up_axis"] == "+Y"}
    for row in manifest:
        motion = read_bvh(tmp_path / row["path"])
        ref = canon[row["skeleton"]]
        scale, rot = float(row["scale"]), up_rotation(row["up_axis"])
        assert motion.num_joints == int(row["joints"])
        assert float(row["height_m"]) == pytest.approx(ref.height(), rel=1e-5)
        back = motion.global_positions() * scale @ rot
        assert np.abs(back - ref.global_positions()).max() < 1e-4 * ref.height()
        if row["name_noise"] == "tag":
            assert all(re.search(r"__[a-z][0-9][A-Z](_end)?$", n) for n in motion.skeleton.names)
        if row["up_axis"] == "+X":  # an arbitrary unit: the bird is 28 units tall
            assert ref.height() / scale == pytest.approx(28.0, rel=1e-4)
            assert row["path"].split("/")[1] == "Xup-u28-flat"


def test_dialect_variants_cover_axes_and_units(tmp_path):
    variants = list(dialect_variants(seed=1))
    again = [(v.rig.name, v.kind, v.dialect) for v in dialect_variants(seed=1)]
    assert [(v.rig.name, v.kind, v.dialect) for v in variants] == again
    rigs = zoo_rigs(seed=1)
    for rig in rigs:
        mine = [v.dialect for v in variants if v.rig.name == rig.name]
        assert sorted(d.up_axis for d in mine) == sorted(UP_AXES)
        assert len({str(d.unit) for d in mine}) >= 3
    dialects = [v.dialect for v in variants]
    assert {d.rest for d in dialects} == set(REST_POSES)
    assert {d.noise for d in dialects} == {None, *NOISE_STYLES}
    assert any(isinstance(d.unit, float) for d in dialects)
    few = [v for v in variants if v.rig.species == "crab"][:3]
    rows = write_dialect_zoo(tmp_path, few, frames=8)
    assert [r["up_axis"] for r in rows] == [v.dialect.up_axis for v in few]
    assert all((tmp_path / r["path"]).is_file() for r in rows)


def test_cli_dialect_options(tmp_path, capsys):
    out = tmp_path / "zoo"
    code = main(["zoo", str(out), "--species", "crab", "--clips", "1", "--frames", "8",
                 "--up-axes", "+Z", "negX", "--units", "cm", "28",
                 "--rest-poses", "crouched", "--name-noise", "none", "hash"])
    assert code == 0 and "wrote 16 BVH files" in capsys.readouterr().out
    rows = _read(out / "manifest.tsv")
    assert {r["up_axis"] for r in rows} == {"+Z", "-X"}
    assert {r["rest_pose"] for r in rows} == {"crouched"}
    assert {r["name_noise"] for r in rows} == {"", "hash"}
    assert main(["zoo", str(tmp_path / "v"), "--species", "spider", "--frames", "8",
                 "--dialect-variants"]) == 0
    rows = _read(tmp_path / "v" / "manifest.tsv")
    assert len(rows) == 2 * 6 and {r["up_axis"] for r in rows} == set(UP_AXES)
    assert main(["zoo", str(tmp_path / "w"), "--up-axes=-Y,+X", "--species", "snake",
                 "--clips", "1", "--frames", "4"]) == 0
    assert {r["up_axis"] for r in _read(tmp_path / "w" / "manifest.tsv")} == {"-Y", "+X"}
    with pytest.raises(SystemExit):
        main(["zoo", str(out), "--up-axes", "W"])


@pytest.mark.parametrize("species", ["biped", "crab", "fowl"])
def test_axis_rest_puts_every_first_child_along_x(species):
    """The Bandai / dog convention: each joint's first child lies on its +X."""
    motion = MOTION if species == "biped" else generate_clip(RIGS[species], "walk", frames=10)
    skel = change_rest_pose(motion, "axis", seed=2).skeleton
    for j, kids in enumerate(skel.children):
        if kids and np.linalg.norm(skel.offsets[kids[0]]) > 1e-9:
            direction = skel.offsets[kids[0]] / np.linalg.norm(skel.offsets[kids[0]])
            np.testing.assert_allclose(direction, [1.0, 0.0, 0.0], atol=1e-9)
    # one roll convention, not a random one: the same rig gets the same rest
    np.testing.assert_array_equal(change_rest_pose(motion, "axis", seed=5).skeleton.offsets,
                                  skel.offsets)
