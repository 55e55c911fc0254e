"""The zoo's dialect body plans (issue 15): names exactly as in the rig spec,
BVH round trips, walking gaits with planted feet, and existing species'
files unchanged."""
from __future__ import annotations

import hashlib
import re
from pathlib import Path

import numpy as np
import pytest

from satagraph.datasets.zoo import SPECIES, generate_clip, write_zoo, zoo_rigs
from satagraph.io import read_bvh, write_bvh

OLD_SPECIES = ("biped", "quadruped", "bird", "hexapod", "snake")
NEW_SPECIES = ("fowl", "crab", "spider", "longtail")
RIGS = {r.name: r for r in zoo_rigs(NEW_SPECIES, seed=0)}


def _rig(name: str):
    return RIGS[f"zoo0-{name}"]


def _assert_chain(skel, names, parent=None):
    """``names`` exist and each hangs off the one before (the first off
    :obj:`parent` when given)."""
    index = [skel.index(n) for n in names]
    if parent is not None:
        assert skel.parents[index[0]] == skel.index(parent), names[0]
    for a, b in zip(index, index[1:]):
        assert skel.parents[b] == a, (skel.names[a], skel.names[b])


_NUMBER = re.compile(r"-?\d+\.\d+")


def _fingerprint(text: str) -> bytes:
    """A BVH file's words and its numbers to 4 decimals: the same on every
    machine, where the file's bytes are not (a rotation that is zero up to
    the last bit prints as ``-0.000000`` on one CPU and ``0.000000`` on
    another)."""
    numbers = np.round(np.array(_NUMBER.findall(text), dtype=np.float64), 4) + 0.0
    return _NUMBER.sub("#", text).encode() + numbers.tobytes()


@pytest.mark.slow
def test_existing_species_unchanged():
    """The full zoo (new species included) writes the same files for the
    existing species as the main branch before issue 15 did (to 4
    decimals), but for the quadrupeds, changed on purpose on 26 Nov (drawn
    carriage, galloping runs): the other four plans' files are those of
    that day's main."""
    import tempfile

    digest = hashlib.sha1()
    with tempfile.TemporaryDirectory() as tmp:
        rows = write_zoo(tmp, clips=2, seed=3, frames=12)
        for r in rows:
            if r["species"] in OLD_SPECIES and r["species"] != "quadruped":
                digest.update(_fingerprint((Path(tmp) / r["path"]).read_text()))
    assert digest.hexdigest() == "ba08e365079c622c6fc38546212d87b13b7e88c1"
    assert any(r["species"] == "quadruped" for r in rows)
    assert SPECIES[:5] == OLD_SPECIES and set(NEW_SPECIES) <= set(SPECIES)


def test_bip01_names():
    skel = _rig("fowl-bip01").skeleton
    _assert_chain(skel, ["Bip01", "Bip01_Pelvis", "Bip01_Spine", "Bip01_Spine1", "Bip01_Neck",
                         "Bip01_Neck1", "Bip01_Head", "Bip01_Beak", "Bip01_Beak_end"])
    _assert_chain(skel, ["Bip01_Tail", "Bip01_Tail1"], parent="Bip01_Pelvis")
    for s in "LR":
        _assert_chain(skel, [f"Bip01_{s}_{p}" for p in ("Thigh", "Calf", "HorseLink", "Foot",
                                                        "Toe0")] + [f"Bip01_{s}_Toe0_end"],
                      parent="Bip01_Spine")
        _assert_chain(skel, [f"Bip01_{s}_{p}" for p in ("Clavicle", "UpperArm", "Forearm",
                                                        "Hand", "Finger0")]
                      + [f"Bip01_{s}_Finger0_end"], parent="Bip01_Spine")


def test_fingerwing_names():
    skel = _rig("fowl-fingerwing").skeleton
    _assert_chain(skel, ["root", "pelvis", "spine_01", "spine_02", "neck_01", "neck_02",
                         "head", "beak", "beak_end"])
    for s in "LR":
        _assert_chain(skel, [f"thigh_{s}", f"shin_{s}", f"tarsus_{s}", f"toe_{s}",
                             f"toe_{s}_end"], parent="pelvis")
        _assert_chain(skel, [f"{s}_Finger_01", f"{s}_Finger_02", f"{s}_Finger_03",
                             f"{s}_Finger_03_end"], parent="spine_02")


@pytest.mark.parametrize("variant", ["plain", "abdomen"])
def test_crab_names_and_legs(variant):
    rig = _rig(f"crab-{variant}")
    skel = rig.skeleton
    _assert_chain(skel, ["Root", "Body"])
    rest = skel.rest_positions()
    for s in "LR":
        for n in (1, 2, 3):
            leg = f"leg_{s}_{n:02d}"
            _assert_chain(skel, [leg, f"{leg}_02", f"{leg}_03", f"{leg}_04"], parent="Body")
        _assert_chain(skel, [f"Claw_{s}_01", f"Claw_{s}_02", f"Claw_{s}_Pincer"], parent="Body")
        assert skel.parents[skel.index(f"EyeStalk_{s}")] == skel.index("Body")
        z = [rest[skel.index(f"leg_{s}_{n:02d}"), 2] for n in (1, 2, 3)]
        assert z[0] > z[1] > z[2]  # numbered front to back
        assert rest[skel.index(f"Claw_{s}_01"), 2] > z[0]  # claws in front
    walking = {skel.names[leg.upper] for leg in rig.legs}
    assert walking == {f"leg_{s}_{n:02d}" for s in "LR" for n in (1, 2, 3)}  # claws don't walk
    assert ("Abdomen" in skel.names) == (variant == "abdomen")


def test_spider_names():
    rig = _rig("spider-plain")
    skel = rig.skeleton
    _assert_chain(skel, ["Cephalothorax", "Abdomen_01", "Abdomen_02"])
    rest = skel.rest_positions()
    for s, numbers in (("L", range(1, 5)), ("R", range(5, 9))):
        for n in numbers:
            leg = f"Leg_{s}_{n:02d}"
            _assert_chain(skel, [leg, f"{leg}_1", f"{leg}_2", f"{leg}_3"], parent="Cephalothorax")
        z = [rest[skel.index(f"Leg_{s}_{n:02d}"), 2] for n in numbers]
        assert np.all(np.diff(z) < 0)  # front to back
        assert skel.parents[skel.index(f"Fang_{s}")] == 0
    first = rest[[skel.index("Leg_L_01"), skel.index("Leg_R_05")]]
    np.testing.assert_allclose(first[0] * [-1, 1, 1], first[1])  # one mirrored pair
    assert len(rig.legs) == 8


@pytest.mark.parametrize("variant,tail", [("tail32", 32), ("tail36", 36)])
def test_longtail_names(variant, tail):
    skel = _rig(f"longtail-{variant}").skeleton
    assert 90 <= skel.num_joints <= 110
    _assert_chain(skel, [f"Tail_{i:02d}" for i in range(1, tail + 1)], parent="Hips")
    for name in ("Ear_L", "Ear_R", "Jaw", "Snout"):
        assert skel.parents[skel.index(name)] == skel.index("Head"), name
    _assert_chain(skel, ["Tongue_01", "Tongue_02"], parent="Jaw")
    for side in ("Left", "Right"):
        _assert_chain(skel, [f"{side}UpLeg", f"{side}Leg", f"{side}Foot", f"{side}ToeBase"],
                      parent="Hips")
        _assert_chain(skel, [f"{side}Shoulder", f"{side}Arm", f"{side}ForeArm", f"{side}Hand"],
                      parent="Spine2")
        for digit in ("Index1", "Middle1", "Ring1", "Pinky1"):
            assert skel.parents[skel.index(f"{side}Foot{digit}")] == skel.index(f"{side}ToeBase")
            assert skel.parents[skel.index(f"{side}Hand{digit}")] == skel.index(f"{side}Hand")


@pytest.mark.parametrize("name", sorted(RIGS))
def test_round_trip(tmp_path, name):
    motion = generate_clip(RIGS[name], "walk", frames=12, seed=1)
    write_bvh(motion, tmp_path / "a.bvh")
    back = read_bvh(tmp_path / "a.bvh")
    assert back.skeleton.names == motion.skeleton.names
    assert np.array_equal(back.skeleton.parents, motion.skeleton.parents)
    err = np.abs(back.global_positions() - motion.global_positions()).max()
    assert err < 1e-4 * motion.height()


@pytest.mark.parametrize("name", ["crab-plain", "spider-plain", "fowl-bip01",
                                  "longtail-tail32"])
def test_gait_travels_in_step(name):
    """Stance tips stay planted (height 0, no sliding), the body travels,
    and the gait keeps a statically stable support (a tripod / tetrapod /
    one foot) at every frame."""
    rig = _rig(name)
    motion = generate_clip(rig, "walk", frames=60, seed=3)
    pos, height = motion.global_positions(), motion.height()
    tips = [leg.tips for leg in rig.legs]
    feet = pos[:, [t for group in tips for t in group]]
    stance = feet[..., 1] < 1e-6 * height
    slide = np.linalg.norm(np.diff(feet[..., [0, 2]], axis=0), axis=-1)
    assert slide[stance[1:] & stance[:-1]].max() < 1e-5 * height
    assert pos[..., 1].min() > -1e-6 * height
    root = motion.root_translation[:, [0, 2]]
    travel = np.linalg.norm(root[-1] - root[0])
    assert travel > 0.5 * height
    down = np.array([[pos[t, group, 1].max() < 1e-6 * height for group in tips]
                     for t in range(motion.num_frames)])
    support = {2: 1, 4: 2, 6: 3, 8: 4}[len(tips)]
    assert down.sum(axis=1).min() >= support
    assert 0.0 < down.mean() < 1.0  # and every leg steps
    assert (down.mean(axis=0) < 1.0).all()
