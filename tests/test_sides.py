"""The one left/right rule (:mod:`satagraph.sides`), pinned on real-world
joint names and shared by canonicalisation, mirroring and the lexicon."""
from __future__ import annotations

from pathlib import Path

import pytest

from satagraph.sides import _side_markers, side_markers, side_of, side_pairs, swap_side
from satagraph.semantics.lexicon import parse_name
from satagraph.transforms.augment import mirror_pairs
from satagraph.transforms.canonical import lateral_pairs

#: name, side, mirror image.
TABLE = [
    ("mixamorig:LeftUpLeg", "left", "mixamorig:RightUpLeg"),
    ("thigh.L", "left", "thigh.R"),
    ("l_hip", "left", "r_hip"),
    ("HipL", "left", "HipR"),  # once: canonical none, augment and lexicon left
    ("Bip01 L Thigh", "left", "Bip01 R Thigh"),
    ("LeftHand", "left", "RightHand"),
    ("lShldr", "left", "rShldr"),
    ("RightFoot_End", "right", "LeftFoot_End"),
    ("Left_Wing", "left", "Right_Wing"),
    ("LHipJoint", "left", "RHipJoint"),
    ("L_Fr_UpLeg", "left", "R_Fr_UpLeg"),  # Fr beside a side word: front
    ("FL_Foot", "left", "FR_Foot"),  # a leg code alone: front left
    ("antenna_r", "right", "antenna_l"),
    ("Lt_Arm", "left", "Rt_Arm"),
    ("LEFTARM", "left", "RIGHTARM"),
    ("lefthand", "left", "righthand"),
    ("Finger1L", "left", "Finger1R"),
    ("RightArm__k8L", "right", "LeftArm__k8L"),  # an exporter tag has no side
    ("左ひざ", "left", "右ひざ"), ("右足ＩＫ", "right", "左足ＩＫ"),  # MMD
    ("腰キャンセル左", "left", "腰キャンセル右"), ("左大腿", "left", "右大腿"),
    ("Hips", None, "Hips"), ("Spine", None, "Spine"), ("Spine1", None, "Spine1"),
    ("Lower", None, "Lower"), ("LowerBack", None, "LowerBack"),
    ("Leg", None, "Leg"), ("Tail", None, "Tail"), ("Root", None, "Root"),
    ("Ladder", None, "Ladder"), ("Rib", None, "Rib"),
    ("RL_BoneRoot", None, "RL_BoneRoot"),  # once: augment swapped to LL_
    ("Tail_09__f8R", None, "Tail_09__f8R"), ("spine_01_a1b2c3", None, "spine_01_a1b2c3"),
    # CMU ASF names as converters write them: a side letter glued to the bone
    ("lfemur", "left", "rfemur"), ("rclavicle", "right", "lclavicle"),
    ("ltibia", "left", "rtibia"), ("lhumerus", "left", "rhumerus"), ("lhand", "left", "rhand"),
    ("rfoot", "right", "lfoot"), ("ltoes", "left", "rtoes"), ("lhipjoint", "left", "rhipjoint"),
    ("rthumb", "right", "lthumb"), ("lradius", "left", "rradius"), ("rwrist", "right", "lwrist"),
    ("lupperarm", "left", "rupperarm"), ("Lhand_end", "left", "Rhand_end"),
    # a side word glued after the bone
    ("upperarmleft", "left", "upperarmright"), ("Bip01_footright", "right", "Bip01_footleft"),
    *((word, None, word) for word in (
        "lowerback", "upperback", "lowerneck", "label", "lower", "length", "rib", "radius",
        "leg", "root", "rear", "ring", "lips", "lid", "reference", "roll", "rotation", "rump",
        "lace", "release", "rest", "lung", "ribs", "rigging", "lumbar", "leaf")),
]


@pytest.mark.parametrize("name,side,other", TABLE)
def test_side_of_and_swap_side(name, side, other):
    assert side_of(name) == side
    assert swap_side(name) == other
    assert swap_side(other) == name
    assert side_of(other) == {"left": "right", "right": "left", None: None}[side]


def test_side_markers_are_cached_and_returned_as_new_lists():
    """Every mirror, canonicalisation and rig read asks again for the same
    names: the markers are cached (bounded), equal to a fresh reading, and
    a caller that edits the list it got does not change the next answer."""
    names = [name for name, _, _ in TABLE]
    fresh = [list(_side_markers.__wrapped__(n)) for n in names]
    assert [side_markers(n) for n in names] == fresh
    hits = _side_markers.cache_info().hits
    got = side_markers("Bip01 L Thigh")
    assert got == [(6, 7, "l")] and _side_markers.cache_info().hits == hits + 1
    got.append((0, 1, "r"))
    got[0] = (0, 0, "right")
    assert side_markers("Bip01 L Thigh") == [(6, 7, "l")]
    assert swap_side("Bip01 L Thigh") == "Bip01 R Thigh"
    assert _side_markers.cache_info().maxsize == 16384


@pytest.mark.parametrize("name,side,other", TABLE)
def test_the_lexicon_reads_the_same_side(name, side, other):
    assert parse_name(name).side == side


def _real_names(root: Path):
    names = set()
    for path in sorted(root.rglob("*.bvh"))[:400]:
        with open(path, encoding="utf-8", errors="replace") as f:
            for line in f:
                words = line.split()
                if words[:1] == ["MOTION"]:
                    break
                if words[:1] in (["ROOT"], ["JOINT"]) and len(words) > 1:
                    names.add(" ".join(words[1:]))
    return sorted(names)


def _zoo_names():
    from satagraph.datasets.zoo import zoo_rigs
    return sorted({n for rig in zoo_rigs(seed=0) for n in rig.skeleton.names})


def _one_rule(names):
    for name in names:
        side = side_of(name)
        assert parse_name(name).side == side, name
        assert swap_side(swap_side(name)) == name, name
        assert (swap_side(name) == name) == (side is None), name


def test_one_rule_on_every_zoo_name():
    _one_rule(_zoo_names())


def test_one_rule_on_every_real_name(shared_data: Path):
    """The real rigs' names (``$SATAGRAPH_DATA`` or ``../shared/data``; it
    read ``../shared/data`` alone, and where that was missing checked no
    real name without saying so)."""
    names = _real_names(shared_data)
    assert len(names) > 100
    _one_rule(names)


def test_pairs_follow_the_rule():
    names = ["Hips", "LeftUpLeg", "RightUpLeg", "thigh.L", "thigh.R", "HipL",
             "HipR", "Tail", "LeftHand"]
    assert side_pairs(names) == ([1, 3, 5], [2, 4, 6])
    assert list(mirror_pairs_of(names)) == [0, 2, 1, 4, 3, 6, 5, 7, 8]
    noisy = ["Hips", "LeftArm__x7Q", "rightarm__k3Z", "LHipJoint", "RHipJoint"]
    assert lateral_pairs(noisy) == ([1, 3], [2, 4])
    mmd = ["センター", "左足", "右足", "左ひざ", "右ひざ", "上半身"]
    assert lateral_pairs(mmd) == ([1, 3], [2, 4])
    assert list(mirror_pairs_of(mmd)) == [0, 2, 1, 4, 3, 5]


def test_glued_cmu_asf_sides_pair_and_mirror():
    """``lfemur`` / ``rfemur`` (CMU ASF names) had no side: mirroring left
    the legs in place and the rig had no left/right pairs to face by."""
    names = ["root", "lhipjoint", "lfemur", "ltibia", "rhipjoint", "rfemur", "rtibia",
             "lowerback", "lclavicle", "lhumerus", "rclavicle", "rhumerus"]
    assert lateral_pairs(names) == ([1, 2, 3, 8, 9], [4, 5, 6, 10, 11])
    assert list(mirror_pairs_of(names)) == [0, 4, 5, 6, 1, 2, 3, 7, 10, 11, 8, 9]


def mirror_pairs_of(names):
    import numpy as np
    from satagraph.skeleton import Skeleton
    skel = Skeleton(names=names, parents=np.array([-1] + [0] * (len(names) - 1)),
                    offsets=np.zeros((len(names), 3)),
                    channels=[("Xrotation",)] * len(names),
                    end_site=np.zeros(len(names), bool))
    return mirror_pairs(skel)
