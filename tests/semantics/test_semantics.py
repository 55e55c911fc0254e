"""Semantic tags: rule descriptions, dictionaries, anchors, prompt round trip."""
from __future__ import annotations

import csv
import json
import os
from pathlib import Path
from typing import Dict, List

import numpy as np
import pytest

from satagraph import Skeleton
from satagraph.semantics import (SemanticsError, build_prompt,
                                 describe_joints, import_answer,
                                 load_dictionary, load_reference_vocab,
                                 normalize_anchors, parse_answer)
from satagraph.semantics.lexicon import parse_name
from satagraph.semantics.rules import describe_structure, ordinal
from satagraph.io import read_bvh

REPO_ROOT = Path(__file__).resolve().parents[2]
SKIP = ("shared BVH data not found (../shared/data next to the repository, "
        "or set SATAGRAPH_DATA)")


def _data_dir():
    path = Path(os.environ.get("SATAGRAPH_DATA")
                or REPO_ROOT.parent / "shared" / "data")
    return path if (path / "manifest.tsv").is_file() else None


def _one_file_per_skeleton() -> List[str]:
    root = _data_dir()
    if root is None:
        return []
    with open(root / "manifest.tsv", newline="") as f:
        rows = list(csv.DictReader(f, delimiter="\t"))
    best: Dict[str, dict] = {}
    for row in rows:
        key = row["skeleton"] if row["dataset"] != "fixtures" else row["path"]
        if key not in best or int(row["frames"]) < int(best[key]["frames"]):
            best[key] = row
    return sorted(r["path"] for r in best.values())


_SKELETONS: Dict[str, Skeleton] = {}


def real(rel: str) -> Skeleton:
    """Skeleton of a shared data file (cached; skips without data)."""
    root = _data_dir()
    if root is None:
        pytest.skip(SKIP)
    if rel not in _SKELETONS:
        _SKELETONS[rel] = read_bvh(root / rel).skeleton
    return _SKELETONS[rel]


def build(spec: str) -> Skeleton:
    """Skeleton from an indented list of names (one space per level);
    names ending in ``_end`` are end sites."""
    names, parents, stack = [], [], []
    for line in spec.strip("\n").splitlines():
        depth = len(line) - len(line.lstrip(" "))
        del stack[depth:]
        parents.append(stack[-1] if stack else -1)
        names.append(line.strip())
        stack.append(len(names) - 1)
    return Skeleton(names=names, parents=np.array(parents),
                    offsets=np.zeros((len(names), 3)),
                    end_site=np.array([n.endswith("_end") for n in names]))


def desc(skeleton: Skeleton, **kw) -> Dict[str, str]:
    return dict(zip(skeleton.names, describe_joints(skeleton, **kw)))


BANDAI = "bandai/dataset-1_bow_active_001.bvh"
CMU = "cmu/01_01.bvh"
CC100 = "ccbase/006_01.bvh"
CC101 = "ccbase/007_01.bvh"
DOG = "dog/D1_001_KAN01_001.bvh"
MIXAMO = "fixtures/test_freebvh.bvh"
MOCAPBANK = "fixtures/test_mocapbank.bvh"
BLENDER = "fixtures/test3.bvh"


# ------------------------------------------------------------- real data
@pytest.mark.parametrize("rel", _one_file_per_skeleton() or [
    pytest.param(None, marks=pytest.mark.skip(reason=SKIP))])
def test_every_joint_of_every_skeleton_is_understood(rel):
    sk = real(rel)
    texts = describe_joints(sk)
    assert len(texts) == sk.num_joints
    assert all(isinstance(t, str) and t.strip() for t in texts)
    assert describe_joints(sk) == texts  # deterministic
    rules = describe_structure(tuple(sk.names), tuple(sk.parents.tolist()),
                               tuple(sk.end_site.tolist()))
    unknown = [n for n, f in zip(sk.names, rules.fallback) if f]
    assert not unknown, f"{rel}: names not understood: {unknown}"


REAL_EXPECTED = [
    # taxonomic neutrality: human thigh == dog hind thigh, arm == foreleg
    (DOG, "LeftUpLeg", "left hind limb upper segment"),
    (CMU, "LeftUpLeg", "left hind limb upper segment"),
    (BANDAI, "UpperLeg_L", "left hind limb upper segment"),
    (CC100, "CC_Base_L_Thigh", "left hind limb upper segment"),
    (MIXAMO, "mixamorig:RightUpLeg", "right hind limb upper segment"),
    (MOCAPBANK, "LeftHip", "left hind limb upper segment"),
    (BLENDER, "thigh.R", "right hind limb upper segment"),
    (DOG, "LeftArm", "left front limb upper segment"),
    (CMU, "RightArm", "right front limb upper segment"),
    (BANDAI, "UpperArm_L", "left front limb upper segment"),
    (CC100, "CC_Base_R_Upperarm", "right front limb upper segment"),
    (MOCAPBANK, "LeftShoulder", "left front limb upper segment"),
    (BLENDER, "upper_arm.L", "left front limb upper segment"),
    # hierarchy-aware: Leg under UpLeg is the lower segment
    (DOG, "LeftLeg", "left hind limb lower segment"),
    (CMU, "RightLeg", "right hind limb lower segment"),
    (MOCAPBANK, "LeftKnee", "left hind limb lower segment"),
    (BANDAI, "LowerArm_R", "right front limb lower segment"),
    (MOCAPBANK, "RightElbow", "right front limb lower segment"),
    (DOG, "LeftHand", "left front limb terminal segment"),
    (DOG, "RightFoot", "right hind limb terminal segment"),
    (MOCAPBANK, "LeftAnkle", "left hind limb terminal segment"),
    (MOCAPBANK, "LeftWrist", "left front limb terminal segment"),
    (CMU, "LHipJoint", "left hind limb girdle segment"),
    (BLENDER, "pelvis.L", "left hind limb girdle segment"),
    (DOG, "LeftShoulder", "left front limb girdle segment"),
    (CC100, "CC_Base_L_Clavicle", "left front limb girdle segment"),
    (MOCAPBANK, "RightCollar", "right front limb girdle segment"),
    (BANDAI, "Toes_L", "left hind limb digit segment"),
    (CMU, "LThumb", "left front limb first digit segment"),
    (MIXAMO, "mixamorig:LeftHandIndex1", "left front limb second digit"),
    (CC100, "CC_Base_L_Mid2", "left front limb third digit segment"),
    (CC100, "CC_Base_R_BigToe1", "right hind limb first digit segment"),
    (CC100, "CC_Base_L_PinkyToe1", "left hind limb fifth digit segment"),
    # trunk
    (BANDAI, "joint_Root", "skeleton root"),
    (BANDAI, "Hips", "pelvis"),
    (CC101, "RL_BoneRoot", "skeleton root"),
    (CC101, "CC_Base_Hip", "pelvis"),
    (CC100, "CC_Base_Pelvis", "pelvis"),
    (CMU, "LowerBack", "spine segment"),
    (BANDAI, "Chest", "spine segment"),
    (MOCAPBANK, "Chest2", "spine segment"),
    (CC100, "CC_Base_Waist", "spine segment"),
    (CC100, "CC_Base_NeckTwist01", "neck segment"),
    (CMU, "Neck1", "neck segment"),
    (BLENDER, "face", "head"),
    # tips, helpers, face parts, tail
    (DOG, "Head_end", "head top tip"),
    (MIXAMO, "mixamorig:HeadTop_End", "head top tip"),
    (BANDAI, "Hand_L_end", "left front limb terminal tip"),
    (CMU, "LeftToeBase_end", "left hind limb digit tip"),
    (BLENDER, "forearm.L_end", "left front limb lower segment tip"),
    (CC100, "CC_Base_L_ThighTwist01", "left hind limb upper segment twist "
                                      "helper"),
    (CC100, "CC_Base_R_KneeShareBone", "right hind limb lower segment helper"),
    (CC100, "CC_Base_JawRoot", "jaw"),
    (CC100, "CC_Base_L_Eye", "left eye"),
    (MIXAMO, "mixamorig:RightEye", "right eye"),
    (CC100, "CC_Base_Tongue02", "tongue segment"),
    (DOG, "Tail", "tail segment"),
    (DOG, "Tail1_end", "tail tip"),
]


@pytest.mark.parametrize("rel,name,expected", REAL_EXPECTED,
                         ids=[f"{r.split('/')[0]}:{n}"
                              for r, n, _ in REAL_EXPECTED])
def test_real_names(rel, name, expected):
    assert expected in desc(real(rel))[name]


def test_human_and_dog_share_descriptions():
    human, dog = desc(real(CMU)), desc(real(DOG))
    for name in ("Hips", "LeftUpLeg", "LeftLeg", "LeftFoot", "LeftArm",
                 "LeftForeArm", "LeftHand", "LeftShoulder", "Neck", "Head"):
        assert human[name] == dog[name]
    assert desc(real(BANDAI))["UpperLeg_L"] == dog["LeftUpLeg"]
    assert desc(real(CC100))["CC_Base_L_Upperarm"] == dog["LeftArm"]
    assert "tail" not in " ".join(human.values())


# ------------------------------------------------------------ common rigs
SMPL = """
pelvis
 left_hip
  left_knee
   left_ankle
    left_foot
 spine1
  spine2
   spine3
    neck
     head
    left_collar
     left_shoulder
      left_elbow
       left_wrist
        left_hand
"""
UNREAL = """
root
 pelvis
  spine_01
   spine_02
    spine_03
     clavicle_l
      upperarm_l
       lowerarm_l
        hand_l
         index_01_l
        lowerarm_twist_01_l
     neck_01
      head
  thigh_r
   calf_r
    foot_r
     ball_r
   thigh_twist_01_r
 ik_foot_root
  ik_foot_l
"""
BIPED = """
Bip01
 Bip01 Pelvis
  Bip01 Spine
   Bip01 L Thigh
    Bip01 L Calf
     Bip01 L Foot
      Bip01 L Toe0
       Bip01 L Toe0Nub
   Bip01 Spine1
    Bip01 Neck
     Bip01 Head
      Bip01 HeadNub
     Bip01 R Clavicle
      Bip01 R UpperArm
       Bip01 R Forearm
        Bip01 R Hand
         Bip01 R Finger0
          Bip01 R Finger0Nub
"""
RIGIFY = """
DEF-spine
 DEF-thigh.L
  DEF-thigh.L.001
   DEF-shin.L
    DEF-foot.L
     DEF-toe.L
 DEF-spine.001
  DEF-spine.002
   DEF-spine.003
    DEF-shoulder.R
     DEF-upper_arm.R
      DEF-forearm.R
       DEF-hand.R
        DEF-f_index.01.R
    DEF-spine.004
     DEF-spine.005
      DEF-spine.006
"""
QUADRUPED = """
Root
 Pelvis
  Spine1
   Spine2
    Neck
     Head
    Leg_FL
     Leg_FL1
      Paw_FL
  BackLeftThigh
   BackLeftShin
    BackLeftPaw
  Tail1
   Tail2
"""

RIG_EXPECTED = [
    (SMPL, "left_hip", "left hind limb upper segment"),
    (SMPL, "left_knee", "left hind limb lower segment"),
    (SMPL, "left_ankle", "left hind limb terminal segment"),
    (SMPL, "left_foot", "left hind limb digit segment"),
    (SMPL, "left_collar", "left front limb girdle segment"),
    (SMPL, "left_shoulder", "left front limb upper segment"),
    (SMPL, "left_elbow", "left front limb lower segment"),
    (SMPL, "left_wrist", "left front limb terminal segment"),
    (SMPL, "left_hand", "left front limb digit segment"),
    (SMPL, "pelvis", "pelvis"),
    (UNREAL, "root", "skeleton root"),
    (UNREAL, "thigh_r", "right hind limb upper segment"),
    (UNREAL, "calf_r", "right hind limb lower segment"),
    (UNREAL, "ball_r", "right hind limb digit segment"),
    (UNREAL, "clavicle_l", "left front limb girdle segment"),
    (UNREAL, "lowerarm_l", "left front limb lower segment"),
    (UNREAL, "index_01_l", "left front limb second digit segment"),
    (UNREAL, "lowerarm_twist_01_l", "twist helper"),
    (UNREAL, "thigh_twist_01_r", "right hind limb upper segment twist"),
    (UNREAL, "ik_foot_l", "inverse kinematics helper"),
    (UNREAL, "neck_01", "neck segment"),
    (BIPED, "Bip01", "skeleton root"),
    (BIPED, "Bip01 Pelvis", "pelvis"),
    (BIPED, "Bip01 L Thigh", "left hind limb upper segment"),
    (BIPED, "Bip01 L Toe0Nub", "left hind limb digit tip"),
    (BIPED, "Bip01 HeadNub", "head top tip"),
    (BIPED, "Bip01 R Clavicle", "right front limb girdle segment"),
    (BIPED, "Bip01 R Forearm", "right front limb lower segment"),
    (BIPED, "Bip01 R Finger0", "right front limb digit segment"),
    (RIGIFY, "DEF-spine", "pelvis"),
    (RIGIFY, "DEF-thigh.L.001", "left hind limb upper segment"),
    (RIGIFY, "DEF-shin.L", "left hind limb lower segment"),
    (RIGIFY, "DEF-spine.003", "spine segment"),
    (RIGIFY, "DEF-shoulder.R", "right front limb girdle segment"),
    (RIGIFY, "DEF-f_index.01.R", "right front limb second digit"),
    (RIGIFY, "DEF-spine.005", "neck segment"),
    (RIGIFY, "DEF-spine.006", "head"),
    (QUADRUPED, "Leg_FL", "left front limb upper segment"),
    (QUADRUPED, "Leg_FL1", "left front limb lower segment"),
    (QUADRUPED, "Paw_FL", "left front limb terminal segment"),
    (QUADRUPED, "BackLeftThigh", "left hind limb upper segment"),
    (QUADRUPED, "BackLeftPaw", "left hind limb terminal segment"),
    (QUADRUPED, "Tail2", "tail segment"),
]


@pytest.mark.parametrize("spec,name,expected", RIG_EXPECTED,
                         ids=[n for _, n, _ in RIG_EXPECTED])
def test_common_rigs(spec, name, expected):
    assert expected in desc(build(spec))[name]


@pytest.mark.parametrize("name", [
    "RightUpLeg", "R_UpLeg", "r_thigh", "thigh_r", "thigh.R", "RThigh",
    "Bip01 R Thigh", "Bip001_R_Thigh", "DEF-thigh.R", "ORG-thigh.R",
    "CC_Base_R_Thigh", "mixamorig:RightUpLeg", "RightUpperLeg", "RIGHTUPLEG",
    "Right_Leg_Upper"])
def test_abbreviations_and_prefixes(name):
    sk = build(f"Hips\n {name}\n Spine\n  Neck\n   Head")
    assert desc(sk)[name] == "right hind limb upper segment (thigh)"


@pytest.mark.parametrize("name,expected", [
    ("Fr_L_UpLeg", "left front limb upper segment"),
    ("Bk_L_UpLeg", "left hind limb upper segment"),
    ("FrontLeftThigh", "left front limb upper segment"),
    ("HindRightLeg", "right hind limb upper segment"),
    ("Left_ForeLeg", "left front limb upper segment"),
])
def test_front_hind_words(name, expected):
    sk = build(f"Hips\n {name}\n Spine\n  Neck\n   Head")
    assert expected in desc(sk)[name]


def test_hierarchy_resolves_ambiguous_names():
    sk = build("""
Hips
 Leg_L
  Knee_L
 UpLeg_R
  Leg_R
   Ankle_R
    Foot_R
 Spine
  Collar_L
   Shoulder_L
  Shoulder_R
   Arm_R
""")
    d = desc(sk)
    assert "left hind limb upper segment" in d["Leg_L"]  # Root -> Leg
    assert "right hind limb lower segment" in d["Leg_R"]  # UpLeg -> Leg
    assert "right hind limb digit segment" in d["Foot_R"]  # Ankle -> Foot
    assert "left front limb upper segment" in d["Shoulder_L"]  # under Collar
    assert "right front limb girdle segment" in d["Shoulder_R"]  # above Arm


def test_leg_chains_front_or_hind_by_attachment():
    sk = build("""
Hips
 LeftLeg
  LeftKnee
   LeftFoot
 Spine
  Spine1
   Neck
    Head
   LeftLegB
    LeftKneeB
     LeftFootB
""")
    d = desc(sk)
    assert "left hind limb upper segment" in d["LeftLeg"]
    assert "left front limb upper segment" in d["LeftLegB"]
    assert "left front limb terminal segment" in d["LeftFootB"]


def test_numeric_invariance():
    sk = build("""
Hips
 Spine
  Spine1
   Spine_2
    spine.003
     Spine04
      Neck
       Neck_1
        Head
""")
    d = desc(sk)
    assert len({d[n] for n in ("Spine", "Spine1", "Spine_2", "spine.003",
                               "Spine04")}) == 1
    assert "spine segment" in d["Spine_2"]
    assert d["Neck"] == d["Neck_1"] == "neck segment"
    fingers = build("Hand_L\n Index1_L\n  Index2_L\n   Index3_L\n    Index3_L_end")
    f = desc(fingers)
    assert f["Index1_L"] == f["Index2_L"] == f["Index3_L"]


@pytest.mark.parametrize("names", [
    ["Body", "Bone", "Bone.001", "Bone.002"],
    ["", "???", "日本語", "123"],
    ["a", "b", "c", "d"],
    ["x:", "|", "__", "Bip01"],
])
def test_unknown_names_fall_back_to_structure(names):
    sk = Skeleton(names=names, parents=np.array([-1, 0, 1, 1]),
                  offsets=np.zeros((4, 3)))
    texts = describe_joints(sk)
    assert all(t.strip() for t in texts)
    assert "root of the skeleton" in texts[0] or "skeleton root" in texts[0]


def test_unknown_joint_role_names_the_chain():
    sk = build("Hips\n Spine\n  Frob\n   Widget3\n    Widget3_end")
    d = desc(sk)
    assert d["Frob"] == "frob joint, first segment of a chain from the spine"
    assert d["Widget3"] == \
        "widget joint, second segment of a chain from the spine"
    assert d["Widget3_end"].startswith("tip of widget joint")
    sk = build("Root\n Thing\n  Bone.001")
    assert desc(sk)["Bone.001"] == ("unnamed joint, second segment of a "
                                    "chain from the skeleton root")


def test_parse_name_and_ordinal():
    info = parse_name("mixamorig:LeftHandThumb2")
    assert info.side == "left" and info.digit == "first"
    assert parse_name("CC_Base_L_Thigh").side == "left"
    assert parse_name("LowerBack").trunk == "spine_lower"
    assert parse_name("HeadTop_End").tip
    assert ordinal(2) == "second" and ordinal(12) == "12th" and \
        ordinal(23) == "23rd"


# -------------------------------------------------- dictionary and anchors
def test_dictionary_overrides_rules(tmp_path):
    sk = build("Hips\n Spine\n  Head")
    d = desc(sk, dictionary={"Spine": "my  spine", "Missing": "x"})
    assert d["Spine"] == "my spine"
    assert d["Hips"].startswith("pelvis")
    path = tmp_path / "dict.json"
    path.write_text(json.dumps({"Head": "the skull"}))
    assert desc(sk, dictionary=path)["Head"] == "the skull"
    assert desc(sk, dictionary=str(path))["Head"] == "the skull"


@pytest.mark.parametrize("content,needle", [
    ("{not json", "not valid JSON"),
    ("[1, 2]", "expected a JSON object"),
    ('{"Hips": 3}', "key 'Hips'"),
    ('{"Hips": "  "}', "key 'Hips'"),
    ('{"Hips": null}', "key 'Hips'"),
])
def test_bad_dictionary_errors_name_file_and_key(tmp_path, content, needle):
    path = tmp_path / "bad_dict.json"
    path.write_text(content)
    with pytest.raises(SemanticsError) as err:
        load_dictionary(path)
    assert needle in str(err.value) and "bad_dict.json" in str(err.value)
    assert "\n" not in str(err.value)
    with pytest.raises(SemanticsError, match="not found"):
        load_dictionary(tmp_path / "absent.json")


ODD = """
Hips
 Spine
  Neck
   Head
 Bone
  Bone.001
   Bone.002
    Bone.002_end
 Thing
  Thing.001
   Thing.002
"""


def test_anchor_tags_and_propagation():
    sk = build(ODD)
    d = desc(sk, anchors={"Bone": "tail base", "Thing.002": "left hind paw",
                          "Spine": "lower back"})
    assert d["Bone"] == "tail base"
    assert d["Bone.001"] == "tail base, first segment down the chain"
    assert d["Bone.002"] == "tail base, second segment down the chain"
    assert d["Bone.002_end"] == "tail base tip"
    assert d["Thing.002"] == "left hind paw"
    assert d["Thing.001"] == "left hind paw, first segment up the chain"
    assert d["Thing"] == "left hind paw, second segment up the chain"
    assert d["Spine"] == "lower back"  # a tag always wins on its own joint
    assert d["Neck"] == "neck segment"  # understood joints keep their rules
    assert d == desc(sk, anchors=["Bone=tail base", "Thing.002=left hind paw",
                                  "Spine=lower back"])


def test_anchors_stop_at_branches_and_dictionary_wins():
    sk = build("Root\n A\n  B\n   C\n   D")
    d = desc(sk, anchors={"A": "tag"}, dictionary={"B": "from dict"})
    assert d["B"] == "from dict"
    assert "tag" not in d["C"] and "tag" not in d["D"]
    d = desc(sk, anchors={"A": "tag"})
    assert d["B"] == "tag, first segment down the chain"
    assert "tag" not in d["C"]  # B branches: propagation stops


@pytest.mark.parametrize("anchors,needle", [
    (["NoEquals"], "NAME=TAG"), (["=tag"], "NAME=TAG"), (["Hips="], "NAME=TAG"),
    ({"Hips": 3}, "must be a string"), (["Nope=tag"], "no joint"),
])
def test_bad_anchors(anchors, needle):
    with pytest.raises(SemanticsError, match=needle):
        describe_joints(build("Hips\n Spine"), anchors=anchors)


def test_normalize_anchors_splits_at_first_equals():
    assert normalize_anchors(["a:b=x = y"]) == {"a:b": "x = y"}
    assert normalize_anchors(None) == {}


# ------------------------------------------------------ prompt round trip
def test_prompt_generation_mode():
    sk = build("Hips\n LeftUpLeg\n  LeftLeg\n   LeftLeg_end")
    text = build_prompt(sk)
    assert "# Mode: GENERATION" in text
    assert "Existing Reference Vocabulary" not in text
    assert "{{" not in text and "{%" not in text
    for line in ("Hips [None]", "LeftUpLeg [Hips]", "LeftLeg [LeftUpLeg]",
                 "LeftLeg_end [LeftLeg]"):
        assert line in text.splitlines()
    assert "Taxonomic Neutrality" in text and "Numerical Invariance" in text
    assert text.rstrip().endswith("JSON:")


def test_prompt_alignment_mode(tmp_path):
    sk = build("Hips\n Tail")
    vocab = tmp_path / "vocab.json"
    vocab.write_text(json.dumps({"Hips": "pelvis root", "X": "tail segment",
                                 "Y": "pelvis root"}))
    words = load_reference_vocab(vocab)
    assert words == ["pelvis root", "tail segment"]
    text = build_prompt(sk, words)
    assert "# Mode: ALIGNMENT" in text
    assert "[Existing Reference Vocabulary]:" in text
    assert '"tail segment"' in text
    vocab.write_text(json.dumps(["a", "b"]))
    assert load_reference_vocab(vocab) == ["a", "b"]
    vocab.write_text(json.dumps({"vocabulary": ["c"]}))
    assert load_reference_vocab(vocab) == ["c"]
    vocab.write_text(json.dumps([1]))
    with pytest.raises(SemanticsError, match="vocab.json"):
        load_reference_vocab(vocab)


def test_import_answer_roundtrip(tmp_path):
    sk = build("Hips\n Spine\n  Spine_end")
    answer = tmp_path / "answer.json"
    answer.write_text('```json\n{"Hips": "Root / Pelvis Area", '
                      '"Spine": "Spine segment", "Spine_end": "Spine Tip"}\n```')
    out = tmp_path / "sub" / "dict.json"
    stored = import_answer(answer, sk, out)
    assert json.loads(out.read_text()) == stored
    assert list(stored) == sk.names
    assert desc(sk, dictionary=out)["Spine"] == "Spine segment"
    assert [p.name for p in out.parent.iterdir()] == ["dict.json"]


@pytest.mark.parametrize("content,needle", [
    ('{"Hips": "a", "Spine": "b"}', "missing 1 joint(s): 'Spine_end'"),
    ('{"Hips": "a", "Spine": "b", "Spine_end": "c", "Tail": "d"}',
     "unknown joint(s): 'Tail'"),
    ('{"Hips": "a", "Spine": 5, "Spine_end": "c"}', "non-string"),
    ('{"Hips": "a", "Spine": "", "Spine_end": "c"}', "non-string or empty"),
    ('Sure! Here is the JSON: {"Hips"', "not valid JSON"),
    ('["Hips", "Spine"]', "must be a JSON object"),
    ('{"Hips": "a", "Hips": "b", "Spine": "b", "Spine_end": "c"}',
     "duplicate"),
])
def test_import_answer_rejects_malformed(tmp_path, content, needle):
    sk = build("Hips\n Spine\n  Spine_end")
    answer = tmp_path / "answer.json"
    answer.write_text(content)
    out = tmp_path / "dict.json"
    with pytest.raises(SemanticsError) as err:
        import_answer(answer, sk, out)
    assert needle in str(err.value) and "answer.json" in str(err.value)
    assert not out.exists()
    with pytest.raises(SemanticsError, match="not found"):
        import_answer(tmp_path / "none.json", sk, out)


def test_parse_answer_lists_every_problem():
    sk = build("Hips\n Spine")
    with pytest.raises(SemanticsError) as err:
        parse_answer('{"Spine": 1, "Foo": "x"}', sk, "a.json")
    msg = str(err.value)
    assert "missing" in msg and "unknown" in msg and "non-string" in msg
