"""Up axis and units read right on any body plan, overrides that stick."""
from __future__ import annotations

import csv
import json
import warnings
from pathlib import Path

import numpy as np
import pytest

import satagraph.transforms.rig_reading as rr
from satagraph.cli import main
from satagraph.transforms.canonical import canonicalize
from satagraph.data.dataset import load_features
from satagraph.transforms.rig_reading import (RigReadingWarning, guess_up_axis, parse_units,
                                              read_rig, with_rig)
from satagraph.datasets.sources import resolve_sources
from satagraph.datasets.zoo import Dialect, apply_dialect, generate_clip, zoo_rigs
from satagraph.io import read_bvh, write_bvh
from satagraph.motion import Motion
from satagraph.semantics.reference_rigs import build_skeleton
from satagraph.skeleton import Skeleton

AXES = ("+X", "-X", "+Y", "-Y", "+Z", "-Z")


def _clip(species: str, variant: int = 0, kind: str = "walk", frames: int = 60):
    rig = zoo_rigs([species], seed=3)[variant]
    return generate_clip(rig, kind, frames=frames, seed=5)


@pytest.mark.parametrize("species", ["biped", "crab", "fowl", "longtail", "spider"])
def test_up_axis_of_walking_zoo_rigs_in_every_axis(species: str) -> None:
    clip = _clip(species)
    for axis in AXES:
        motion, _ = apply_dialect(clip, Dialect(up_axis=axis, unit="cm"))
        guess = guess_up_axis(motion)
        assert guess.axis == axis and not guess.low_confidence, guess.summary()
        assert guess.evidence["ground"][axis] > 0.8  # planted feet on one floor


def test_a_still_clip_is_decided_on_its_pose_and_flagged_when_doubtful() -> None:
    clip = _clip("snake", kind="idle")
    motion = apply_dialect(clip, Dialect(up_axis="-X"))[0]
    guess = guess_up_axis(motion)
    assert guess.axis == "-X"
    assert not guess.moving and guess.confidence < 0.6
    reading = read_rig(motion)
    assert reading.up_warnings and reading.warnings[:1] == reading.up_warnings
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        rr.warn_reading(reading, "snake")
    up = [w for w in caught if "up axis" in str(w.message)]
    assert up and all(w.category is RigReadingWarning for w in up)  # not a units warning
    assert issubclass(rr.UnitsWarning, RigReadingWarning)


def test_units_of_a_human_from_its_body_plan() -> None:
    clip = _clip("biped")
    for unit, scale in (("cm", 0.01), ("in", 0.0254), ("m", 1.0), ("mm", 0.001)):
        units = read_rig(apply_dialect(clip, Dialect(up_axis="+Z", unit=unit))[0]).units
        assert units.how in ("human", "magnitude") and units.scale == scale


def test_a_human_with_a_ponytail_is_a_human() -> None:
    """3ds Max biped's ``Bip01 Ponytail1`` made a human "not a human" (its
    "tail"): a 1.6 m character in cm kept 160 file units as metres."""
    clip = _clip("biped")
    names = ["Bip01 Ponytail1" if n == "Head_end" else n for n in clip.skeleton.names]
    clip = clip.with_(skeleton=clip.skeleton.replace(names=names))
    units = read_rig(apply_dialect(clip, Dialect(unit="cm"))[0]).units
    assert (units.how, units.scale) == ("human", 0.01), units.summary()


def test_units_of_an_animal_are_kept_and_reported_not_humanised() -> None:
    bird = _clip("fowl")  # 28 units tall: a chicken in cm, not a 1.56 m human
    motion, _ = apply_dialect(bird, Dialect(unit=28.0))
    reading = read_rig(motion)
    assert reading.units.kept and reading.units.scale == 1.0
    assert any("units unknown" in w for w in reading.warnings)
    with pytest.warns(rr.UnitsWarning, match="units unknown"):  # a RigReadingWarning too
        canonicalize(motion)
    metres = read_rig(apply_dialect(bird, Dialect(unit="m"))[0]).units
    assert metres.how == "magnitude" and metres.scale == 1.0


@pytest.mark.parametrize("unit", ["in", "m", "cm"])
def test_units_of_an_arthropod_are_kept_whatever_its_size(unit: str) -> None:
    # a 7 cm spider is 2.8 inches across: as many units as a 2.8 m body in
    # metres (the benchmark's zoo0-spider-palps, once read as metres)
    spider = generate_clip(zoo_rigs(["spider"], seed=0)[1], "walk", frames=60, seed=5)
    reading = read_rig(apply_dialect(spider, Dialect(up_axis="-X", unit=unit))[0])
    assert reading.units.kept and reading.units.scale == 1.0, reading.units.summary()
    assert reading.units.reason.split(", ")[1].startswith("8 legs: an arthropod")


def test_a_human_in_an_arbitrary_unit_is_kept_unless_it_looks_standard() -> None:
    human = _clip("biped")
    odd = read_rig(apply_dialect(human, Dialect(unit=12.0))[0]).units  # no unit fits
    assert odd.kept and "pass --units" in odd.reason
    # 160 units tall is what a 1.6 m human in cm is: no file tells them apart
    alike = read_rig(apply_dialect(human, Dialect(unit=160.0))[0]).units
    assert (alike.how, alike.scale) == ("human", 0.01) and " m in cm" in alike.reason


def test_a_reading_s_warning_says_how_to_set_it_in_python_too() -> None:
    """The warnings named only the command-line flags; a Python user is
    told the call that sets the reading, and that call silences them."""
    spider = generate_clip(zoo_rigs(["spider"], seed=0)[1], "walk", frames=60, seed=5)
    motion = apply_dialect(spider, Dialect(unit="cm"))[0]
    (line,) = read_rig(motion).unit_warnings
    assert "--units" in line and "with_rig(motion, scale=...)" in line
    assert read_rig(rr.with_rig(motion, scale=0.01)).warnings == []
    still = _clip("biped", kind="idle")
    for axis in ("+Y", "-Z"):
        assert read_rig(rr.with_rig(apply_dialect(still, Dialect(up_axis=axis))[0],
                                    up_axis=axis)).up_warnings == []
    assert "with_rig(motion, up_axis=...)" in rr.SET_UP_AXIS


@pytest.mark.parametrize("unit, scale, how", [("cm", 0.01, "dialect"), ("m", 1.0, "human"),
                                               ("in", 0.0254, "human")])
def test_an_exporters_units_give_way_to_a_human_height_they_contradict(
        unit: str, scale: float, how: str) -> None:
    """Mixamo's names mean cm, unless the body is then no human: the same
    rig re-exported in metres read as cm was 1.5 cm tall, in inches 0.6 m."""
    clip = _clip("biped")
    mixamo = clip.with_(skeleton=clip.skeleton.replace(
        names=[f"mixamorig:{n}" for n in clip.skeleton.names]))
    units = read_rig(apply_dialect(mixamo, Dialect(unit=unit))[0]).units
    assert (units.scale, units.how) == (scale, how)


#: Blender Rigify's deform bones for the zoo's Mixamo-style limb names.
RIGIFY_LIMBS = {"Shoulder": "shoulder", "Arm": "upper_arm", "ForeArm": "forearm",
                "Hand": "hand", "UpLeg": "thigh", "Leg": "shin", "Foot": "foot", "ToeBase": "toe"}
#: Daz Genesis 8's bones for the same names (``pelvis`` is inserted under ``hip``).
DAZ_NAMES = {"Hips": "hip", "Spine": "abdomenLower", "Spine1": "chestUpper", "Neck": "neckLower",
             "Neck1": "neckUpper", "Head": "head", "Shoulder": "Collar", "Arm": "ShldrBend",
             "ForeArm": "ForearmBend", "Hand": "Hand", "UpLeg": "ThighBend", "Leg": "Shin",
             "Foot": "Foot", "ToeBase": "Toe"}


def _renamed(motion, rename):
    """:obj:`motion` with each name through :obj:`rename` (end sites keep ``_end``)."""
    names = [rename(n[:-4]) + "_end" if n.endswith("_end") else rename(n)
             for n in motion.skeleton.names]
    return motion.with_(skeleton=motion.skeleton.replace(names=names))


def _rigify(motion):
    """Rigify's names: the trunk ``DEF-spine`` .. ``DEF-spine.00k`` (the last
    one the head, no joint named so), limbs ``DEF-upper_arm.L`` ..."""
    trunk = [n for n in motion.skeleton.names if n[:4] not in ("Left", "Righ") and
             not n.endswith("_end")]
    spine = {n: f"DEF-spine.{k:03d}" if k else "DEF-spine" for k, n in enumerate(trunk)}
    return _renamed(motion, lambda n: spine.get(n) or "DEF-{}.{}".format(
        RIGIFY_LIMBS[n.replace("Left", "").replace("Right", "")], n[0]))


def _daz(motion):
    """Daz Genesis's names and hips: ``hip`` carries ``abdomenLower`` and
    ``pelvis``, which carries both thighs (no joint with three children
    below the chest)."""
    skel = motion.skeleton
    src = [0, 0] + list(range(1, skel.num_joints))  # joint 1 is the new pelvis
    parents = [-1, 0] + [1 if "UpLeg" in skel.names[j] else int(skel.parents[j]) + 1
                         for j in range(1, skel.num_joints)]
    offsets, rot, trans = skel.offsets[src], motion.rotations[:, src], motion.translations[:, src]
    offsets[1], rot[:, 1], trans[:, 1] = 0.0, np.eye(3), 0.0
    names = [skel.names[k] for k in src]
    names[1] = "pelvis"
    daz = Skeleton(names=names, parents=np.array(parents), offsets=offsets,
                   channels=[skel.channels[k] for k in src], end_site=skel.end_site[src])
    side = {"Left": "l", "Right": "r"}
    return _renamed(motion.with_(skeleton=daz, rotations=rot, translations=trans),
                    lambda n: n if n == "pelvis" else DAZ_NAMES.get(n) or next(
                        s + DAZ_NAMES[n[len(w):]] for w, s in side.items() if n.startswith(w)))


@pytest.mark.parametrize("unit, scale", [("cm", 0.01), ("m", 1.0), ("in", 0.0254)])
def test_rigify_and_daz_humans_are_read_as_humans(unit: str, scale: float) -> None:
    """A Rigify rig (no joint named head: ``DEF-spine.006`` is it) and a Daz
    Genesis rig (``hip`` with two children, ``pelvis`` and ``abdomenLower``)
    were "not a human": in cm or inches they kept the file's units (168
    units tall read as 168 m)."""
    clip = _clip("biped")
    daz = _daz(clip)
    assert np.allclose(daz.global_positions()[:, 2:], clip.global_positions()[:, 1:])
    for rig in (_rigify(clip), daz):
        units = read_rig(apply_dialect(rig, Dialect(up_axis="+Z", unit=unit))[0]).units
        assert (units.how, units.scale) == ("human", scale), units.summary()


def test_a_rigify_quadruped_bird_or_chain_is_no_human() -> None:
    """Reading the head and hips as the semantic reading does makes no
    quadruped (front paws on the ground), bird or bare chain a human."""
    dog = _rigify(generate_clip(zoo_rigs(["quadruped"], seed=3)[3], "walk", frames=60, seed=5))
    assert "DEF-spine.005" in dog.skeleton.names and "DEF-hand.L" in dog.skeleton.names
    chain = build_skeleton([("DEF-spine", None, (0.0, 90.0, 0.0)),
                            ("DEF-spine.001", "DEF-spine", (0.0, 40.0, 0.0)),
                            ("DEF-spine.002", "DEF-spine.001", (0.0, 40.0, 0.0))])
    still = Motion(chain, np.zeros((0, 3, 3, 3)), np.zeros((0, 3, 3)))
    for body in (apply_dialect(dog, Dialect(unit="cm"))[0],
                 apply_dialect(_clip("fowl"), Dialect(unit="cm"))[0], still):
        units = read_rig(body).units
        assert units.kept, units.summary()


def test_real_files_keep_their_readings(read_real) -> None:
    expect = {"bandai/dataset-1_walk_normal_001.bvh": ("+Y", "cm"),
              "cmu/01_01.bvh": ("+Y", "cmu"), "ccbase/007_01.bvh": ("+Y", "cm"),
              "fixtures/test3.bvh": ("+Y", "m"), "dog/D1_001_KAN01_001.bvh": ("+Y", "file")}
    for path, (axis, units) in expect.items():
        info = read_rig(read_real(path)).to_dict()
        assert (info["up_axis"], info["units"]) == (axis, units), path


def test_parse_units_and_errors() -> None:
    assert parse_units("inches") == 0.0254 and parse_units("0.5") == 0.5
    assert parse_units("file") == 1.0
    with pytest.raises(ValueError, match="units must be"):
        parse_units("parsecs")
    with pytest.raises(ValueError, match="positive"):
        parse_units(-1.0)
    with pytest.raises(ValueError, match="up_axis must be one of"):
        with_rig(_clip("crab", frames=4), up_axis="up")


def _crab_file(tmp_path: Path, axis: str = "-Z") -> Path:
    path = tmp_path / "crab.bvh"
    write_bvh(apply_dialect(_clip("crab"), Dialect(up_axis=axis, unit="cm"))[0], path)
    return path


def test_canonical_files_declare_themselves_and_are_never_reguessed(
        tmp_path: Path, capsys, monkeypatch) -> None:
    src, out = _crab_file(tmp_path), tmp_path / "canon.bvh"
    assert main(["convert", str(src), str(out), "--canonical", "--up-axis=-Z",
                 "--units", "cm"]) == 0
    assert out.read_text().splitlines()[0] == \
        "HIERARCHY # satagraph: canonical up_axis=+Y scale=1"
    motion = read_bvh(out)
    assert motion.rig.declared and motion.rig.up_axis == "+Y"

    def never(_motion):
        raise AssertionError("a declared file was re-guessed")
    monkeypatch.setattr(rr, "guess_up_axis", never)
    monkeypatch.setattr(rr, "guess_units", never)
    canon = canonicalize(motion, fps=None)
    assert canon.transform.up_axis == "+Y" and canon.transform.scale == 1.0
    capsys.readouterr()
    assert main(["inspect", "--json", str(out)]) == 0
    info = json.loads(capsys.readouterr().out)
    assert (info["rig"]["up_axis_how"], info["rig"]["units_how"]) == ("declared", "declared")
    # a user's override still wins over the declaration
    assert read_rig(with_rig(motion, up_axis="+X")).up.axis == "+X"
    # written again (e.g. round trip), the declaration stays
    write_bvh(motion, tmp_path / "again.bvh")
    assert read_bvh(tmp_path / "again.bvh").rig == motion.rig


def test_every_bvh_command_takes_the_overrides(tmp_path: Path) -> None:
    from satagraph.cli import build_parser
    parser = build_parser()
    f = str(_crab_file(tmp_path))
    for argv in (["inspect", f], ["convert", f, "o.bvh", "--canonical"], ["tags", f],
                 ["render", f, "o.gif"], ["reconstruct", "--ckpt", "c", f, "o.bvh"],
                 ["retarget", "--ckpt", "c", f, "--target", f, "o.bvh",
                  "--target-up-axis", "y", "--target-units", "m"],
                 ["eval", "--ckpt", "c"], ["train", "tiny"]):
        args = parser.parse_args(argv + ["--up-axis=-z", "--units", "cm"])
        assert (args.up_axis, args.units) == ("-Z", 0.01), argv


def test_manifest_columns_and_source_entries_set_the_rig(tmp_path: Path) -> None:
    crab = _crab_file(tmp_path, "+X")
    rows = [{"path": crab.name, "split": "train", "up_axis": "+X", "scale": "cm"}]
    with open(tmp_path / "manifest.tsv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]), delimiter="\t")
        w.writeheader(), w.writerows(rows)
    (f_manifest,) = resolve_sources([str(tmp_path / "manifest.tsv")])
    assert (f_manifest.up_axis, f_manifest.scale) == ("+X", 0.01)
    (f_entry,) = resolve_sources([{"path": str(tmp_path / "manifest.tsv"),
                                   "up_axis": "-Y", "units": "in"}])
    assert (f_entry.up_axis, f_entry.scale) == ("+X", 0.01)  # the row wins
    (feats,) = load_features([f_manifest], cache_dir=str(tmp_path / "cache"))
    truth = canonicalize(read_bvh(crab), fps=30.0, up_axis="+X", unit_scale=0.01)
    np.testing.assert_allclose(feats.x[0], truth.global_positions()[0]
                               - truth.global_positions()[0, :1] * [1, 0, 1], atol=1e-5)
    with pytest.raises(ValueError, match="manifest.tsv:2: up_axis must be"):
        rows[0]["up_axis"] = "sideways"
        with open(tmp_path / "manifest.tsv", "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]), delimiter="\t")
            w.writeheader(), w.writerows(rows)
        resolve_sources([str(tmp_path / "manifest.tsv")])


def test_no_warning_where_nothing_is_guessed() -> None:
    motion = apply_dialect(_clip("fowl"), Dialect(unit=28.0))[0]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        canonicalize(with_rig(motion, "+Y", "cm"))


@pytest.mark.parametrize("species", ["crab", "fowl", "spider"])
def test_zoo_body_plans_read_the_same_in_any_dialect(species: str, tmp_path: Path) -> None:
    from satagraph.semantics import describe_joints
    from satagraph.semantics.evidence import evidence_from_motion
    clip = _clip(species)
    clean = describe_joints(clip.skeleton, evidence=evidence_from_motion(clip))
    path = tmp_path / "x.bvh"
    write_bvh(apply_dialect(clip, Dialect(up_axis="-Z", unit="cm", noise="tag"))[0], path)
    exported = read_bvh(path)  # detected up axis, undecided units: same evidence
    assert describe_joints(exported.skeleton,
                           evidence=evidence_from_motion(exported)) == clean
    legs = [t for n, t in zip(clip.skeleton.names, clean)
            if n.lower().startswith("leg") or "thigh" in n.lower()]
    assert legs and len(set(legs)) == len(legs)  # distinct legs
    if species != "fowl":  # arthropods: legs, never arms
        assert not any(w in t for t in clean for w in ("forearm", "wrist", "elbow"))
    else:
        wings = [t for n, t in zip(clip.skeleton.names, clean) if "UpperArm" in n]
        assert all("front limb" in t for t in wings) and wings


def test_a_rig_without_frames_is_never_a_confident_up_axis():
    """Its rest pose is all there is, and exporters need not write it
    upright (CC_Base's lies along +Z): the guess always warns."""
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    from satagraph.transforms.rig_reading import guess_up_axis
    clip = generate_clip(zoo_rigs(["biped"])[0], "walk", frames=30, seed=3)
    rig = clip.slice(0, 0)
    assert not guess_up_axis(clip).low_confidence
    assert guess_up_axis(rig).low_confidence and guess_up_axis(rig).axis == "+Y"
