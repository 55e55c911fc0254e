"""Joint names in Japanese (MikuMikuDance) and Chinese read as their English
counterparts (:mod:`satagraph.semantics.foreign`): the same descriptions,
sides, up-axis evidence and units as the same rig named in English."""
from __future__ import annotations

from typing import Dict

import numpy as np
import pytest

from satagraph.motion import Motion
from satagraph.semantics import describe_joints
from satagraph.semantics.foreign import english_name
from satagraph.semantics.lexicon import parse_name
from satagraph.transforms.augment import mirror_pairs
from satagraph.transforms.rig_reading import guess_units, guess_up_axis

BANDAI = "bandai/dataset-1_walk_normal_001.bvh"
#: Bandai's joints by their MikuMikuDance names (the left side; the right
#: side swaps 左 for 右).
MMD: Dict[str, str] = {
    "joint_Root": "全ての親", "Hips": "下半身", "Spine": "上半身", "Chest": "上半身2",
    "Neck": "首", "Head": "頭", "Shoulder_L": "左肩", "UpperArm_L": "左腕",
    "LowerArm_L": "左ひじ", "Hand_L": "左手首", "UpperLeg_L": "左足",
    "LowerLeg_L": "左ひざ", "Foot_L": "左足首", "Toes_L": "左つま先"}
MMD.update({k.replace("_L", "_R"): v.replace("左", "右") for k, v in MMD.items() if "左" in v})


@pytest.mark.parametrize("name,english", [
    ("左ひざ", "Left Knee"), ("右足ＩＫ", "Right Leg IK"), ("上半身2", "Chest"),
    ("上半身", "Spine"), ("左人指１", "Left Index Finger 1"), ("左足首", "Left Ankle"),
    ("右腕捩", "Right Arm Twist"), ("腰キャンセル左", "Waist Helper Left"),
    ("左大腿", "Left Thigh"), ("头", "Head"), ("Épaule_G", "Epaule_G"),
    ("センター", "Hips"), ("ｾﾝﾀｰ", "Hips"), ("左ひじ補助", "Left Elbow Helper"),
    ("左ダミー", "Left ダミー"),  # a kana keeps its voicing mark (ダ is not タ)
    ("LeftUpLeg", "LeftUpLeg"), ("mixamorig:Hips", "mixamorig:Hips")])
def test_english_name(name, english):
    assert english_name(name) == english


@pytest.mark.parametrize("name,limb,side", [
    ("左ひざ", 2, "left"), ("右足首", 3, "right"), ("左腕", 1, "left"),
    ("右ひじ", 2, "right"), ("左つま先", 4, "left"), ("左小腿", 2, "left")])
def test_limb_segments_and_sides(name, limb, side):
    info = parse_name(name)
    assert info.limb is not None and info.limb[2] == limb
    assert info.side == side


def test_helpers_and_trunk():
    assert parse_name("右足ＩＫ").helper == "ik"
    assert parse_name("左腕捩").helper == "twist"
    assert parse_name("下半身").trunk == "pelvis"
    assert parse_name("頭").trunk == "head"
    assert parse_name("尻尾").tail


def _renamed(motion: Motion) -> Motion:
    names = [MMD[n[:-4]] + "_end" if n.endswith("_end") else MMD[n]
             for n in motion.skeleton.names]
    return motion.with_(skeleton=motion.skeleton.replace(names=names))


def test_an_mmd_rig_reads_as_its_english_twin(read_real):
    english = read_real(BANDAI)
    mmd = _renamed(english)
    assert describe_joints(mmd.skeleton) == describe_joints(english.skeleton)
    np.testing.assert_array_equal(mirror_pairs(mmd.skeleton), mirror_pairs(english.skeleton))
    a, b = guess_up_axis(english), guess_up_axis(mmd)
    assert (a.axis, a.confidence) == (b.axis, b.confidence)
    assert a.evidence == b.evidence


def test_mmd_units(read_real):
    """An MMD human about 20 units tall reads in MMD's units (8 cm); in
    centimetres it is too tall for them and reads by its height, as any
    human."""
    english = read_real(BANDAI)
    mmd = _renamed(english)
    assert guess_units(mmd, "+Y").scale == guess_units(english, "+Y").scale == 0.01
    small = mmd.with_(skeleton=mmd.skeleton.replace(offsets=mmd.skeleton.offsets / 8),
                      translations=mmd.translations / 8)
    units = guess_units(small, "+Y")
    assert (units.scale, units.how) == (0.08, "dialect")
    assert 1.2 < units.height * units.scale < 2.0


#: A Reallusion CC_Base rig's joints by the MMD bones in their places (its
#: ``Hip`` carries ``Pelvis``, with the legs, and ``Waist``, with the spine,
#: as MMD's センター carries 下半身 and 上半身), helper bones included.
CC_MMD = {"Hip": "センター", "Pelvis": "下半身", "Waist": "上半身", "Spine01": "上半身2",
          "Spine02": "上半身3", "NeckTwist01": "首", "Head": "頭", "JawRoot": "あご",
          "L_Thigh": "左足", "L_Calf": "左ひざ", "L_Foot": "左足首", "L_ToeBase": "左足先EX",
          "L_KneeShareBone": "左ひざ補助", "L_Eye": "左目", "L_Clavicle": "左肩",
          "L_Upperarm": "左腕", "L_UpperarmTwist01": "左腕捩1", "L_Forearm": "左ひじ",
          "L_ForearmTwist01": "左手捩1", "L_ElbowShareBone": "左ひじ補助", "L_Hand": "左手首"}
CC_MMD.update({"R_" + k[2:]: v.replace("左", "右") for k, v in CC_MMD.items()
               if k.startswith("L_")})


def test_an_mmd_hierarchy_reads_as_its_english_twin(read_real):
    """The centre of motion (センター, a cog-like name that read as the
    ground reference), the legs under 下半身, twist and helper bones (捩,
    補助): each as its CC_Base twin; the three trunk joints the two
    conventions cut differently are spine segments both ways."""
    english = read_real("ccbase/006_01.bvh")

    def mmd(name: str) -> str:
        bare = name.split("CC_Base_", 1)[-1]
        if bare.endswith("_end") and bare[:-4] in CC_MMD:
            return CC_MMD[bare[:-4]] + "_end"
        return CC_MMD.get(bare, name)

    names = [mmd(n) for n in english.skeleton.names]
    renamed = english.with_(skeleton=english.skeleton.replace(names=names))
    ours, theirs = describe_joints(renamed.skeleton), describe_joints(english.skeleton)
    changed = [j for j, n in enumerate(names) if n != english.skeleton.names[j]]
    assert len(changed) == 40
    trunk = {names.index(n) for n in ("上半身", "上半身2", "上半身3")}
    assert [j for j in changed if ours[j] != theirs[j]] == sorted(trunk)
    assert all(ours[j].startswith("spine segment") for j in trunk)
    assert ours[0] == theirs[0] == "pelvis, hips root (center of motion)"
