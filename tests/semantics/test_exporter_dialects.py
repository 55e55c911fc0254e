"""Joint names of exporters and rigs people use (Daz Genesis, VRoid,
insects named by leg segment, quadrupeds and dragons that name the whole leg
in every joint): each read as the joint it is, with and without the rest
pose as evidence."""
from __future__ import annotations

from typing import Dict, List, Sequence, Tuple

import pytest

from satagraph import Skeleton
from satagraph.semantics import describe_joints, limb_ends
from satagraph.semantics.reference_rigs import build_skeleton, rest_evidence
from satagraph.sides import side_of, swap_side

Row = Tuple[str, object, Tuple[float, float, float]]


def readings(rows: Sequence[Row]) -> List[Dict[str, str]]:
    """Joint name -> description, names only and with the rest pose."""
    skeleton: Skeleton = build_skeleton(rows)
    return [dict(zip(skeleton.names, describe_joints(skeleton, evidence=evidence)))
            for evidence in (None, rest_evidence(skeleton))]


def mirrored(rows: Sequence[Row]) -> List[Row]:
    """The other side of :obj:`rows`: side markers swapped, x mirrored."""
    other = lambda n: n if n is None or side_of(n) is None else swap_side(n)  # noqa: E731
    return [(other(n), other(p), (-x, y, z)) for n, p, (x, y, z) in rows]


#: Daz Genesis 8: ``Shldr`` (shoulder) is the upper arm, ``Bend`` / ``Twist``
#: split each long bone in two.
DAZ_TRUNK: List[Row] = [
    ("hip", None, (0.0, 1.0, 0.0)), ("pelvis", "hip", (0.0, 0.0, 0.0)),
    ("abdomenLower", "hip", (0.0, 0.1, 0.0)), ("chestUpper", "abdomenLower", (0.0, 0.3, 0.0)),
    ("neckLower", "chestUpper", (0.0, 0.15, 0.0)), ("head", "neckLower", (0.0, 0.1, 0.0)),
    ("head_end", "head", (0.0, 0.2, 0.0))]
DAZ_LEFT: List[Row] = [
    ("lCollar", "chestUpper", (0.03, 0.1, 0.0)), ("lShldrBend", "lCollar", (0.15, 0.0, 0.0)),
    ("lShldrTwist", "lShldrBend", (0.12, 0.0, 0.0)), ("lForearmBend", "lShldrTwist", (0.13, 0.0, 0.0)),
    ("lForearmTwist", "lForearmBend", (0.12, 0.0, 0.0)), ("lHand", "lForearmTwist", (0.12, 0.0, 0.0)),
    ("lHand_end", "lHand", (0.1, 0.0, 0.0)),
    ("lThighBend", "pelvis", (0.09, -0.05, 0.0)), ("lThighTwist", "lThighBend", (0.0, -0.2, 0.0)),
    ("lShin", "lThighTwist", (0.0, -0.2, 0.0)), ("lFoot", "lShin", (0.0, -0.45, 0.0)),
    ("lToe", "lFoot", (0.0, -0.08, 0.12)), ("lToe_end", "lToe", (0.0, 0.0, 0.05))]


def test_daz_genesis_shoulder_is_the_upper_arm() -> None:
    """``lShldrBend`` / ``lShldrTwist`` were unknown words ("left shldr bend
    joint, first segment of a chain from ..."): the rig had no upper arm."""
    rows = DAZ_TRUNK + DAZ_LEFT + mirrored(DAZ_LEFT)
    for table in readings(rows):
        for s, side in (("l", "left"), ("r", "right")):
            assert table[f"{s}ShldrBend"] == f"{side} front limb upper segment (upper arm)"
            assert table[f"{s}ShldrTwist"] == f"{side} front limb upper segment (upper arm)"
            assert table[f"{s}ForearmBend"] == f"{side} front limb lower segment (forearm)"
            assert table[f"{s}Collar"].startswith(f"{side} front limb girdle segment")


def _insect_leg(side: str, pair: int, z: float) -> List[Row]:
    x = 0.05 if side == "L" else -0.05
    leg = f"{side}{pair}"
    return [(f"{leg}_coxa", "thorax", (x, 0.0, z)), (f"{leg}_femur", f"{leg}_coxa", (x, 0.03, 0.0)),
            (f"{leg}_tibia", f"{leg}_femur", (x, -0.08, 0.0)),
            (f"{leg}_tarsus", f"{leg}_tibia", (x / 2, -0.05, 0.0)),
            (f"{leg}_tarsus_end", f"{leg}_tarsus", (x / 2, -0.01, 0.0))]


def test_an_insect_coxa_is_the_first_leg_segment() -> None:
    """``L1_coxa`` (side and pair number in one token) was an unknown word:
    "left coxa joint, first segment of a chain from the spine" while the
    femur below it read as the leg's upper segment."""
    rows: List[Row] = [("thorax", None, (0.0, 0.1, 0.0)), ("head", "thorax", (0.0, 0.0, 0.1)),
                       ("head_end", "head", (0.0, 0.0, 0.03))]
    for side in "LR":
        for pair, z in ((1, 0.05), (2, 0.0), (3, -0.05)):
            rows += _insect_leg(side, pair, z)
    for table in readings(rows):
        for side, word in (("L", "left"), ("R", "right")):
            for pair, (where, nth) in enumerate((("front", "first"), ("middle", "second"),
                                                 ("hind", "third")), start=1):
                assert table[f"{side}{pair}_coxa"] == (
                    f"{word} {where} limb girdle segment, {nth} leg pair (coxa / hip)")
                assert table[f"{side}{pair}_femur"].startswith(
                    f"{word} {where} limb upper segment, {nth} leg pair")


def test_a_sided_back_joint_is_not_the_spine() -> None:
    """VRoid's skirt bones behind the left and right hip
    (``J_Sec_L_SkirtBack_01``) read as "spine segment (back)", their side
    lost; the spine has no side."""
    rows: List[Row] = [("J_Bip_C_Hips", None, (0.0, 1.0, 0.0)),
                       ("J_Bip_C_Spine", "J_Bip_C_Hips", (0.0, 0.1, 0.0)),
                       ("J_Bip_C_Head", "J_Bip_C_Spine", (0.0, 0.5, 0.0)),
                       ("J_Bip_C_Head_end", "J_Bip_C_Head", (0.0, 0.2, 0.0)),
                       ("J_Bip_C_LowerBack", "J_Bip_C_Hips", (0.0, 0.05, -0.05))]
    for side, x in (("L", 0.1), ("R", -0.1)):
        rows += [(f"J_Sec_{side}_SkirtBack_01", "J_Bip_C_Hips", (x, -0.05, -0.1)),
                 (f"J_Sec_{side}_SkirtBack_02", f"J_Sec_{side}_SkirtBack_01", (x / 5, -0.15, 0.0))]
    for table in readings(rows):
        assert table["J_Bip_C_LowerBack"].startswith("spine segment")
        for side, word in (("L", "left"), ("R", "right")):
            for k in ("01", "02"):
                text = table[f"J_Sec_{side}_SkirtBack_{k}"]
                assert "spine" not in text and text.startswith(f"{word} "), text


#: A quadruped (or a dragon's legs) naming the whole leg in every joint.
QUADRUPED_TRUNK: List[Row] = [
    ("Pelvis", None, (0.0, 0.6, 0.0)), ("Spine_01", "Pelvis", (0.0, 0.0, 0.25)),
    ("Spine_02", "Spine_01", (0.0, 0.0, 0.25)), ("Neck_01", "Spine_02", (0.0, 0.1, 0.1)),
    ("Head", "Neck_01", (0.0, 0.1, 0.1)), ("Head_end", "Head", (0.0, 0.0, 0.15))]
QUADRUPED_LEFT: List[Row] = [
    ("FrontLeg_Scapula_L", "Spine_02", (0.08, 0.0, 0.0)),
    ("FrontLeg_Upper_L", "FrontLeg_Scapula_L", (0.02, -0.15, 0.0)),
    ("FrontLeg_Lower_L", "FrontLeg_Upper_L", (0.0, -0.2, 0.0)),
    ("FrontLeg_Foot_L", "FrontLeg_Lower_L", (0.0, -0.23, 0.0)),
    ("FrontLeg_Foot_L_end", "FrontLeg_Foot_L", (0.0, -0.02, 0.05)),
    ("HindLeg_Hip_L", "Pelvis", (0.08, 0.0, 0.0)),
    ("HindLeg_Thigh_L", "HindLeg_Hip_L", (0.02, -0.1, 0.0)),
    ("HindLeg_Shin_L", "HindLeg_Thigh_L", (0.0, -0.22, -0.05)),
    ("HindLeg_Foot_L", "HindLeg_Shin_L", (0.0, -0.26, 0.05)),
    ("HindLeg_Foot_L_end", "HindLeg_Foot_L", (0.0, -0.02, 0.05))]


def test_a_limb_word_before_the_segment_word_names_the_limb() -> None:
    """``FrontLeg_Scapula_L`` and ``HindLeg_Hip_L`` read as the leg's upper
    segment (two thighs, two upper arms in a row): ``Leg`` was taken for the
    segment because it ranks below the shoulder blade and the hip bone."""
    rows = QUADRUPED_TRUNK + QUADRUPED_LEFT + mirrored(QUADRUPED_LEFT)
    for table in readings(rows):
        for side, word in (("L", "left"), ("R", "right")):
            assert table[f"FrontLeg_Scapula_{side}"].startswith(f"{word} front limb girdle segment")
            assert table[f"FrontLeg_Upper_{side}"].startswith(f"{word} front limb upper segment")
            assert table[f"HindLeg_Hip_{side}"] == f"{word} hind limb girdle segment (hip bone)"
            assert table[f"HindLeg_Thigh_{side}"] == f"{word} hind limb upper segment (thigh)"
            assert table[f"HindLeg_Shin_{side}"] == f"{word} hind limb lower segment (shin / calf)"


#: Daz Genesis 8 hand and foot: ``Carpal`` and ``Metatarsals`` bones
#: between the hand / foot and the fingers / toes.
DAZ_LEFT_ENDS: List[Row] = [
    ("lCarpal1", "lHand", (0.03, 0.0, 0.01)), ("lIndex1", "lCarpal1", (0.05, 0.0, 0.0)),
    ("lIndex1_end", "lIndex1", (0.03, 0.0, 0.0)),
    ("lMetatarsals", "lFoot", (0.0, -0.05, 0.06)), ("lToe", "lMetatarsals", (0.0, -0.02, 0.06)),
    ("lToe_end", "lToe", (0.0, 0.0, 0.03))]


def test_daz_genesis_carpal_and_metatarsals_are_hand_and_foot() -> None:
    """``lCarpal1`` / ``lMetatarsals`` were unknown words ("left metatarsals
    joint, first segment of a chain from the left hind limb terminal
    segment")."""
    left = [r for r in DAZ_LEFT if r[0] not in ("lToe", "lToe_end")] + DAZ_LEFT_ENDS
    rows = DAZ_TRUNK + left + mirrored(left)
    for table in readings(rows):
        for s, side in (("l", "left"), ("r", "right")):
            assert table[f"{s}Carpal1"] == f"{side} front limb terminal segment (hand / front paw)"
            assert table[f"{s}Index1"] == f"{side} front limb second digit segment (index finger)"
            assert table[f"{s}Metatarsals"] == f"{side} hind limb terminal segment (foot / hind paw)"
            assert table[f"{s}Toe"] == f"{side} hind limb digit segment (toes)"


def test_max_biped_fore_twist_is_a_forearm_twist_helper() -> None:
    """3ds Max biped's forearm twist links (``Bip01 L ForeTwist``) read as
    an unknown joint ("left front twist joint, first segment of a chain
    from the left front limb lower segment")."""
    left: List[Row] = [
        ("Bip01 L Clavicle", "Bip01 Spine1", (0.03, 0.1, 0.0)),
        ("Bip01 L UpperArm", "Bip01 L Clavicle", (0.15, 0.0, 0.0)),
        ("Bip01 L Forearm", "Bip01 L UpperArm", (0.25, 0.0, 0.0)),
        ("Bip01 L Hand", "Bip01 L Forearm", (0.25, 0.0, 0.0)),
        ("Bip01 L Hand_end", "Bip01 L Hand", (0.1, 0.0, 0.0)),
        ("Bip01 L ForeTwist", "Bip01 L Forearm", (0.0, 0.0, 0.0)),
        ("Bip01 L ForeTwist1", "Bip01 L Forearm", (0.12, 0.0, 0.0))]
    rows: List[Row] = [("Bip01", None, (0.0, 1.0, 0.0)), ("Bip01 Pelvis", "Bip01", (0.0, 0.0, 0.0)),
                       ("Bip01 Spine", "Bip01 Pelvis", (0.0, 0.1, 0.0)),
                       ("Bip01 Spine1", "Bip01 Spine", (0.0, 0.3, 0.0)),
                       ("Bip01 Head", "Bip01 Spine1", (0.0, 0.2, 0.0)),
                       ("Bip01 Head_end", "Bip01 Head", (0.0, 0.2, 0.0))]
    for table in readings(rows + left + mirrored(left)):
        for s, side in (("L", "left"), ("R", "right")):
            for twist in ("ForeTwist", "ForeTwist1"):
                assert table[f"Bip01 {s} {twist}"] == f"{side} front limb lower segment twist helper"
            assert table[f"Bip01 {s} Hand"] == f"{side} front limb terminal segment (hand / front paw)"


#: A dragon's wing off the same spine joint as its forelegs.
DRAGON_WING_LEFT: List[Row] = [
    ("Wing_L_01", "Spine_02", (0.1, 0.1, 0.05)), ("Wing_L_02", "Wing_L_01", (0.4, 0.05, 0.0)),
    ("Wing_L_03", "Wing_L_02", (0.4, 0.05, 0.0)), ("Wing_L_04", "Wing_L_03", (0.4, 0.05, 0.0)),
    ("Wing_L_04_end", "Wing_L_04", (0.3, 0.0, -0.1))]


def test_a_dragon_s_wings_are_not_a_second_pair_of_forelegs() -> None:
    """Four legs and two wings: ``Wing_L_01`` read "left front limb upper
    segment (upper arm)", the very text of ``FrontLeg_Upper_L``, so the
    embedding could not tell the wings from the forelegs."""
    left = QUADRUPED_LEFT + DRAGON_WING_LEFT
    rows = QUADRUPED_TRUNK + left + mirrored(left)
    skeleton = build_skeleton(rows)
    for table in readings(rows):
        for s, side in (("L", "left"), ("R", "right")):
            wing = [table[f"Wing_{s}_0{k}"] for k in range(1, 5)] + [table[f"Wing_{s}_04_end"]]
            assert wing == [f"{side} wing limb upper segment (wing upper arm)",
                            f"{side} wing limb lower segment (wing forearm)",
                            f"{side} wing limb terminal segment (wing hand)",
                            f"{side} wing limb digit segment (wing fingers)",
                            f"{side} wing limb digit tip (wing fingertip)"]
            assert table[f"FrontLeg_Upper_{s}"] == f"{side} front limb upper segment (upper arm)"
            legs = {table[n] for n, _, _ in rows if n.startswith("FrontLeg")}
            assert legs.isdisjoint(wing)
    ends = limb_ends(skeleton)
    assert skeleton.names[ends["left front"]] == "FrontLeg_Foot_L"


def test_a_bird_s_wings_stay_its_front_limbs() -> None:
    """Without forelegs beside them, wings are the front limbs (a bird's
    wing reads as a human's arm)."""
    hind = [r for r in QUADRUPED_LEFT if r[0].startswith("HindLeg")]
    left = hind + DRAGON_WING_LEFT
    for table in readings(QUADRUPED_TRUNK + left + mirrored(left)):
        assert table["Wing_L_01"] == "left front limb upper segment (upper arm)"
        assert table["Wing_R_03"] == "right front limb terminal segment (hand / front paw)"
