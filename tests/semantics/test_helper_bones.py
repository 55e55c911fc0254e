"""Helper bones (twist, share, inverse-kinematics) on an Unreal-style rig:
read as helpers, never as the limbs they ride along or aim at."""
from __future__ import annotations

import numpy as np
import pytest

from satagraph.semantics import helper_joints, hip_bones, limb_ends
from satagraph.skeleton import Skeleton
from satagraph.transforms.canonical import facing_pairs

#: Unreal's mannequin (+Y up, cm): a floor root, the body below the pelvis,
#: twist bones on the limbs, and the IK targets' chains under the root.
BODY = [("pelvis", "root", (0, 97, 0)), ("spine_01", "pelvis", (0, 10, 0)),
        ("spine_02", "spine_01", (0, 14, 0)), ("spine_03", "spine_02", (0, 13, 0)),
        ("neck_01", "spine_03", (0, 17, 0)), ("head", "neck_01", (0, 10, 0))]
SIDE = [("clavicle_{s}", "spine_03", (4, 12, 0)), ("upperarm_{s}", "clavicle_{s}", (15, 0, 0)),
        ("lowerarm_{s}", "upperarm_{s}", (30, 0, 0)), ("hand_{s}", "lowerarm_{s}", (26, 0, 0)),
        ("lowerarm_twist_01_{s}", "lowerarm_{s}", (13, 0, 0)),
        ("upperarm_twist_01_{s}", "upperarm_{s}", (0.5, 0, 0)),
        ("thigh_{s}", "pelvis", (9, -2, 0)), ("calf_{s}", "thigh_{s}", (0, -43, 0)),
        ("foot_{s}", "calf_{s}", (0, -41, 0)), ("ball_{s}", "foot_{s}", (0, -9, 13)),
        ("calf_twist_01_{s}", "calf_{s}", (0, -20, 0)),
        ("thigh_twist_01_{s}", "thigh_{s}", (0, -1, 0))]
IK = [("ik_foot_root", "root", (0, 0, 0)), ("ik_foot_l", "ik_foot_root", (9, 8, 0)),
      ("ik_foot_r", "ik_foot_root", (-9, 8, 0)), ("ik_hand_root", "root", (0, 0, 0)),
      ("ik_hand_gun", "ik_hand_root", (-56, 110, 0)), ("ik_hand_l", "ik_hand_gun", (112, 0, 0)),
      ("ik_hand_r", "ik_hand_gun", (0, 0, 0))]


def unreal(ik_first: bool) -> Skeleton:
    sides = [(n.format(s=s), p.format(s=s), (x if s == "l" else -x, y, z))
             for s in "lr" for n, p, (x, y, z) in SIDE]
    joints = [("root", None, (0, 0, 0))] + (IK + BODY + sides if ik_first else BODY + sides + IK)
    names = [n for n, _, _ in joints]
    parents = [-1] + [names.index(p) for _, p, _ in joints[1:]]
    return Skeleton(names=names, parents=np.array(parents),
                    offsets=np.array([o for _, _, o in joints], dtype=float))


@pytest.mark.parametrize("ik_first", [False, True])
def test_unreal_helpers_are_not_limbs(ik_first: bool) -> None:
    skeleton = unreal(ik_first)
    names = np.array(skeleton.names)
    assert {k: skeleton.names[j] for k, j in limb_ends(skeleton).items()} == {
        "left front": "hand_l", "right front": "hand_r", "left hind": "foot_l",
        "right hind": "foot_r"}
    helpers = set(names[helper_joints(skeleton)])
    assert {n for n in names if "twist" in n or n.startswith("ik_")} <= helpers
    assert not helpers & {"hand_l", "foot_r", "calf_l", "pelvis"}
    assert not hip_bones(skeleton).any()
    left, right = facing_pairs(skeleton, skeleton.rest_positions())
    assert (list(names[left]), list(names[right])) == (["thigh_l"], ["thigh_r"])


@pytest.mark.parametrize("prefix", ["Character1_Ctrl_", "Rig_IK_", "Hero_Target_", "Model::"])
def test_a_helper_word_every_joint_shares_is_a_prefix_not_a_helper(prefix: str) -> None:
    """MotionBuilder's HumanIK control rig names every joint
    ``Character1_Ctrl_...``: read per name, ``Ctrl`` made every joint a
    helper, so the rig had no limbs and no facing. A prefix all names share
    is read as a prefix."""
    from satagraph.datasets.zoo import zoo_rigs
    plain = zoo_rigs(["biped"])[0].skeleton
    rig = plain.replace(names=[prefix + n for n in plain.names])
    assert not helper_joints(rig).any()
    assert {k: rig.names[j][len(prefix):] for k, j in limb_ends(rig).items()} == {
        k: plain.names[j] for k, j in limb_ends(plain).items()}
    pose = plain.rest_positions()
    assert facing_pairs(rig, pose) == facing_pairs(plain, pose)


def test_shared_prefix_ends_at_a_separator_and_leaves_letters() -> None:
    from satagraph.semantics.lexicon import shared_prefix
    assert shared_prefix(["Character1_Ctrl_Hips", "Character1_Ctrl_LeftUpLeg"]) == "Character1_Ctrl_"
    assert shared_prefix(["Bip01", "Bip01 Pelvis"]) == ""      # the root is the prefix itself
    assert shared_prefix(["Bone_001", "Bone_002"]) == ""       # nothing but numbers left
    assert shared_prefix(["LeftArm", "LeftLeg"]) == ""         # no separator
    assert shared_prefix(["Hips"]) == ""
