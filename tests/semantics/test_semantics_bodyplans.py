"""Semantic tags for body plans beyond mammals (issue 15, item 4): birds,
arthropods, tails and heads, exporter noise, and geometry / motion evidence
through the data pipeline, inference and ``satagraph tags``."""
from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Dict

import numpy as np
import pytest
import torch

from satagraph import Skeleton
from satagraph.semantics import (JointEvidence, as_evidence, call_semantic,
                                 describe_joints, evidence_from_motion,
                                 joint_evidence, limb_ends, remap_evidence)
from satagraph.semantics.lexicon import (drop_noise_tokens, is_noise_token,
                                         parse_name)
from satagraph.semantics.reference_rigs import (REFERENCE_RIGS, bip01_bird,
                                                build_skeleton, crab,
                                                fingerwing_bird,
                                                long_tailed_quadruped,
                                                rest_evidence, spider,
                                                with_exporter_noise)
from satagraph.semantics.rules import describe_structure
from satagraph.motion import Motion

REPO_ROOT = Path(__file__).resolve().parents[2]
READINGS = Path(__file__).with_name("semantic_readings.json")
FORBIDDEN_FOR_ARTHROPODS = ("upper arm", "forearm", "wrist", "elbow", "hand")


def table(skeleton: Skeleton, evidence=None) -> Dict[str, str]:
    return dict(zip(skeleton.names, describe_joints(skeleton, evidence=evidence)))


def both(skeleton: Skeleton):
    """Descriptions without and with the rest pose as evidence."""
    return [table(skeleton), table(skeleton, rest_evidence(skeleton))]


# ------------------------------------------------------------ readings kept
def _data_dir():
    path = Path(os.environ.get("SATAGRAPH_DATA")
                or REPO_ROOT.parent / "shared" / "data")
    return path if (path / "manifest.tsv").is_file() else None


_STORED = json.loads(READINGS.read_text(encoding="utf-8"))
_FILES = sorted(k for k in _STORED if "/" in k)
_ZOO = sorted(k for k in _STORED if "/" not in k)


@pytest.mark.parametrize("rel", _FILES)
def test_real_files_keep_their_readings_with_and_without_motion(rel):
    root = _data_dir()
    if root is None:
        pytest.skip("shared BVH data not found")
    from satagraph.io import read_bvh
    motion = read_bvh(root / rel)
    want = _STORED[rel]["descriptions"]
    assert describe_joints(motion.skeleton) == want
    assert describe_joints(motion.skeleton,
                           evidence=evidence_from_motion(motion)) == want


def test_zoo_rigs_keep_their_readings():
    from satagraph.datasets.zoo import zoo_rigs
    rigs = {r.name: r.skeleton for r in zoo_rigs()}
    checked = 0
    for name in _ZOO:
        sk, stored = rigs.get(name), _STORED[name]
        if sk is None or list(sk.names) != stored["names"] or \
                sk.parents.tolist() != stored["parents"]:
            continue  # a rig the zoo has changed since: not comparable
        assert describe_joints(sk) == stored["descriptions"], name
        checked += 1
    assert checked >= 10


# ------------------------------------------------------------------- birds
def test_bip01_bird_legs_are_hind_limbs_and_wings_front_limbs():
    for d in both(bip01_bird()):
        for s, side in (("L", "left"), ("R", "right")):
            p = f"Bip01_{s}_"
            assert d[p + "Thigh"] == f"{side} hind limb upper segment (thigh)"
            assert d[p + "Calf"].startswith(f"{side} hind limb lower segment")
            assert d[p + "HorseLink"].startswith(
                f"{side} hind limb digitigrade segment (tarsometatarsus")
            assert d[p + "Foot"].startswith(f"{side} hind limb terminal segment")
            assert d[p + "Toe0"].startswith(f"{side} hind limb digit segment")
            assert d[p + "Clavicle"].startswith(f"{side} front limb girdle")
            assert d[p + "UpperArm"].startswith(f"{side} front limb upper")
            assert d[p + "Hand"].startswith(f"{side} front limb terminal")
        assert d["Bip01_Beak"].startswith("beak")
        assert d["Bip01_Tail1"] == "tail segment"
        assert d["Bip01_Neck1"] == "neck segment"
    ends = limb_ends(bip01_bird())
    names = bip01_bird().names
    assert names[ends["left hind"]] == "Bip01_L_Foot"
    assert names[ends["right front"]] == "Bip01_R_Hand"


def test_fingerwing_bird_wings_are_whole_front_limbs():
    for d in both(fingerwing_bird()):
        for s, side in (("L", "left"), ("R", "right")):
            assert d[f"{s}_Finger_01"].startswith(f"{side} front limb upper segment")
            assert d[f"{s}_Finger_02"].startswith(f"{side} front limb lower segment")
            assert d[f"{s}_Finger_03"].startswith(f"{side} front limb terminal segment")
            assert d[f"thigh_{s}"].startswith(f"{side} hind limb upper segment")
            assert d[f"toe_{s}"].startswith(f"{side} hind limb digit segment")
        assert not any("digit segment (fingers" in t for t in d.values())


def test_digitigrade_segment_keeps_the_foot_terminal():
    sk = build_skeleton([("Hips", None, (0, 1, 0)),
                         ("Thigh_L", "Hips", (0.1, 0, 0)),
                         ("Leg_L", "Thigh_L", (0, -0.3, 0)),
                         ("HorseLink_L", "Leg_L", (0, -0.3, 0)),
                         ("Cannon_R", "Hips", (-0.1, -0.5, 0)),
                         ("Foot_L", "HorseLink_L", (0, -0.3, 0)),
                         ("Foot_L_end", "Foot_L", (0, -0.1, 0))])
    d = table(sk)
    assert d["Leg_L"].startswith("left hind limb lower segment")
    assert "digitigrade segment" in d["HorseLink_L"]
    assert d["Foot_L"].startswith("left hind limb terminal segment")
    assert d["Foot_L_end"].startswith("left hind limb terminal tip")
    assert parse_name("Bip01 R HorseLink").digitigrade


# -------------------------------------------------------------- arthropods
def _legs(d: Dict[str, str], prefix: str) -> Dict[str, str]:
    return {n: t for n, t in d.items() if n.startswith(prefix)}


def test_crab_legs_are_distinct_leg_pairs_claws_and_eye_stalks():
    for d in both(crab()):
        for s, side in (("L", "left"), ("R", "right")):
            for n, (limb, k) in enumerate((("front", "first"), ("middle", "second"),
                                          ("hind", "third")), start=1):
                leg = f"leg_{s}_0{n}"
                assert d[leg] == (f"{side} {limb} limb upper segment, {k} leg pair "
                                  "(femur / thigh)")
                assert d[f"{leg}_02"].startswith(f"{side} {limb} limb lower segment")
                assert d[f"{leg}_03"].startswith(f"{side} {limb} limb terminal segment")
            assert d[f"Claw_{s}_01"].startswith(f"{side} claw limb upper segment")
            assert d[f"Claw_{s}_Pincer"] == f"{side} claw limb terminal segment (pincer)"
            assert d[f"EyeStalk_{s}"].startswith(f"{side} eye stalk")
        legs = _legs(d, "leg_")
        assert len(set(legs.values())) == len(legs) == 24  # every joint distinct
        text = " ".join(d.values())
        assert not any(w in text for w in FORBIDDEN_FOR_ARTHROPODS)
        assert d["Body"].startswith("main body")


def test_leg_pairs_follow_geometry_over_name_numbers():
    sk = crab(reverse_numbers=True)  # leg_*_03 is the front leg
    names_only, with_geometry = table(sk), table(sk, rest_evidence(sk))
    assert "first leg pair" in names_only["leg_L_01"]
    assert "first leg pair" in with_geometry["leg_L_03"]
    assert with_geometry["leg_L_03"].startswith("left front limb")
    assert "third leg pair" in with_geometry["leg_R_01"]


@pytest.mark.parametrize("species", ["crab", "spider", "hexapod"])
def test_zoo_arthropods_walk_with_leg_pairs_front_to_back(species, tmp_path):
    # pairs are numbered by where legs join the body, then by their feet:
    # the zoo's hexapod splays its front legs backwards across the hind ones
    # (as the crab and spider once did), which read the first pair as last
    from satagraph.datasets.zoo import Dialect, apply_dialect, generate_clip, zoo_rigs
    from satagraph.io import read_bvh, write_bvh
    rig = zoo_rigs([species], seed=0)[0]
    clip = generate_clip(rig, "walk", frames=40, seed=1)
    write_bvh(apply_dialect(clip, Dialect(up_axis="+X", unit="in", rest="apose"))[0],
              tmp_path / "a.bvh")
    motion = read_bvh(tmp_path / "a.bvh")
    d = table(motion.skeleton, evidence_from_motion(motion, up_axis="+X"))
    pairs = {"crab": ("leg_L_01", "leg_L_03"), "spider": ("Leg_L_01", "Leg_R_08"),
             "hexapod": ("LeftFrontFemur", "RightHindFemur")}
    front, hind = pairs[species]
    assert d[front].endswith("first leg pair (femur / thigh)") and "front limb" in d[front]
    assert "hind limb" in d[hind]


def test_spider_four_leg_pairs_mirrored_by_side():
    for d in both(spider()):
        assert d["Leg_L_01"].replace("left", "right") == d["Leg_R_05"]
        assert "first leg pair" in d["Leg_L_01"]
        assert "fourth leg pair" in d["Leg_R_08_2"]
        assert len({d[f"Leg_L_0{i}"] for i in range(1, 5)}) == 4
        assert d["Fang_L"].startswith("left fang")
        assert d["Abdomen_02"].startswith("spine segment")
        assert not any(w in " ".join(d.values()) for w in FORBIDDEN_FOR_ARTHROPODS)


def test_insect_leg_pairs_by_front_center_hind_words():
    from satagraph.datasets.zoo import zoo_rigs
    rig = next(r for r in zoo_rigs(["hexapod"]))
    d = table(rig.skeleton)
    assert "first leg pair" in d["LeftFrontFemur"]
    assert "second leg pair" in d["LeftCenterFemur"]
    assert "third leg pair" in d["LeftHindFemur"]
    assert d["LeftAntenna"].startswith("left antenna")
    assert set(limb_ends(rig.skeleton)) == {"left front", "right front",
                                            "left hind", "right hind"}


def test_claw_under_a_foot_is_a_digit():
    sk = build_skeleton([("Hips", None, (0, 1, 0)), ("LeftUpLeg", "Hips", (0.1, 0, 0)),
                         ("LeftLeg", "LeftUpLeg", (0, -0.4, 0)),
                         ("LeftFoot", "LeftLeg", (0, -0.4, 0)),
                         ("LeftClaw", "LeftFoot", (0, -0.1, 0.1))])
    assert table(sk)["LeftClaw"].startswith("left hind limb digit segment")


# ------------------------------------------------------- tails and heads
def test_long_tailed_quadruped_tail_head_and_paws():
    d = table(long_tailed_quadruped())
    assert len(d) > 100
    assert {d[f"Tail_{i:02d}"] for i in range(1, 33)} == {"tail segment"}
    assert d["Jaw"] == "lower jaw" and d["Snout"].startswith("snout")
    assert d["Tongue"] == "tongue segment" and d["Ear_L"] == "left ear"
    assert d["LeftHandToe1_1"].startswith("left front limb digit segment")
    assert d["RightFootToe4_2"].startswith("right hind limb digit segment")
    assert d["LeftArm"].startswith("left front limb upper segment")


def test_fins_and_snake_bodies():
    sk = build_skeleton([("Root", None, (0, 0.2, 0)), ("Body", "Root", (0, 0, 0)),
                         ("Fin_L", "Body", (0.1, 0, 0)), ("DorsalFin", "Body", (0, 0.1, 0)),
                         ("Spine01", "Body", (0, 0, -0.1)), ("Spine02", "Spine01", (0, 0, -0.1)),
                         ("Tail", "Spine02", (0, 0, -0.1))])
    d = table(sk)
    assert d["Fin_L"] == "left fin" and d["DorsalFin"].startswith("fin")
    assert d["Spine02"] == "spine segment (back)" and d["Tail"] == "tail segment"


# ---------------------------------------------------------- exporter noise
@pytest.mark.parametrize("rig", sorted(REFERENCE_RIGS))
def test_exporter_noise_is_dropped(rig):
    sk = REFERENCE_RIGS[rig]()
    clean = describe_joints(sk)
    for seed in range(12):
        noisy = with_exporter_noise(sk, seed)
        assert noisy.names != sk.names
        assert describe_joints(noisy) == clean, seed
        assert describe_joints(noisy, evidence=rest_evidence(noisy)) == \
            describe_joints(sk, evidence=rest_evidence(sk))


@pytest.mark.parametrize("name,clean", [
    ("Tail_01__x7Q", "Tail_01"), ("Spine_02__k3Z", "Spine_02"),
    ("Hand_v2", "Hand"), ("Foot_a1b2c3", "Foot"), ("Foot_aadbfa", "Foot"),
    ("Toe0__abc_end", "Toe0_end"), ("Bip01__lg2", "Bip01"),
    ("mixamorig:LeftArm__x7Q", "mixamorig:LeftArm"),
    ("Bip01 L Finger0Nub", "Bip01 L Finger0Nub"), ("Face01", "Face01"),
    ("DEF-spine.003", "DEF-spine.003"), ("CC_Base_L_Pinky1", "CC_Base_L_Pinky1"),
    ("LeftHandIndex1", "LeftHandIndex1"), ("Leg_R_05_1", "Leg_R_05_1"),
    ("Model::LeftHand", "Model::LeftHand"), ("Rig__LeftUpLeg", "Rig__LeftUpLeg"),
])
def test_noise_tokens(name, clean):
    assert drop_noise_tokens(name) == clean


def test_noise_tokens_are_cached_per_name():
    """Every mirror and rig read asks again for the same names: the second
    call is a cache hit, equal to a fresh reading; the cache is bounded."""
    names = ["Tail_01__x7Q", "Foot_a1b2c3", "Bip01__lg2", "LeftHandIndex1", "Toe0__abc_end"]
    first = [drop_noise_tokens(n) for n in names]
    hits = drop_noise_tokens.cache_info().hits
    assert [drop_noise_tokens(n) for n in names] == first
    assert drop_noise_tokens.cache_info().hits == hits + len(names)
    assert first == [drop_noise_tokens.__wrapped__(n) for n in names]
    assert drop_noise_tokens.cache_info().maxsize == 16384


def test_noise_never_becomes_a_side_or_a_word():
    assert is_noise_token("x7L") and is_noise_token("r4T") and is_noise_token("v12")
    assert not is_noise_token("L") and not is_noise_token("Finger0Nub")
    d = table(build_skeleton([("Hips__x7L", None, (0, 1, 0)),
                              ("Bone__r4T", "Hips__x7L", (0, 0, -0.1))]))
    assert d["Bone__r4T"] == "unnamed joint, first segment of a chain from the pelvis"


# ------------------------------------------------------------- evidence
def _unnamed_bird() -> Skeleton:
    """A bird whose limbs have no body words: only geometry tells."""
    rows = [("Hips", None, (0, 0.3, 0)), ("Spine", "Hips", (0, 0.05, 0.05)),
            ("Head", "Spine", (0, 0.1, 0.05))]
    for s, k in (("L", 1.0), ("R", -1.0)):
        rows += [(f"Bone_{s}_a", "Spine", (0.05 * k, -0.05, 0)),
                 (f"Bone_{s}_b", f"Bone_{s}_a", (0, -0.15, 0.03)),
                 (f"Bone_{s}_c", f"Bone_{s}_b", (0, -0.15, 0.0)),
                 (f"Bone_{s}_x", "Spine", (0.05 * k, 0.02, 0)),
                 (f"Bone_{s}_y", f"Bone_{s}_x", (0.15 * k, 0, 0)),
                 (f"Bone_{s}_z", f"Bone_{s}_y", (0.15 * k, 0, 0))]
    return build_skeleton(rows)


def test_weight_bearing_chains_are_legs_spread_chains_wings():
    sk = _unnamed_bird()
    d = table(sk, rest_evidence(sk))
    assert d["Bone_L_a"].startswith("left hind limb upper segment")
    assert d["Bone_R_c"].startswith("right hind limb terminal segment")
    assert d["Bone_L_x"].startswith("left front limb upper segment")
    assert d["Bone_R_z"].startswith("right front limb terminal segment")
    assert "segment of a chain" in table(sk)["Bone_L_a"]  # names only: unknown


def test_weight_groups_split_front_and_hind_legs():
    rows = [("Root", None, (0, 0.5, 0)), ("Pelvis", "Root", (0, 0, 0)),
            ("Spine", "Pelvis", (0, 0, 0.3)), ("Neck", "Spine", (0, 0.1, 0.1)),
            ("Head", "Neck", (0, 0.1, 0.1))]
    for s, k in (("L", 1.0), ("R", -1.0)):  # leg words only, all off the pelvis
        rows += [(f"Leg_{s}_A", "Pelvis", (0.1 * k, 0, 0.3)),
                 (f"Knee_{s}_A", f"Leg_{s}_A", (0, -0.25, 0)),
                 (f"Foot_{s}_A", f"Knee_{s}_A", (0, -0.25, 0)),
                 (f"Leg_{s}_B", "Pelvis", (0.1 * k, 0, 0)),
                 (f"Knee_{s}_B", f"Leg_{s}_B", (0, -0.25, 0)),
                 (f"Foot_{s}_B", f"Knee_{s}_B", (0, -0.25, 0))]
    sk = build_skeleton(rows)
    assert "hind limb" in table(sk)["Leg_L_A"]  # names: all hang off the pelvis
    d = table(sk, rest_evidence(sk))
    assert d["Leg_L_A"].startswith("left front limb upper")
    assert d["Foot_R_B"].startswith("right hind limb terminal")


def test_evidence_in_a_wrong_frame_is_ignored():
    sk = crab(reverse_numbers=True)
    pos = sk.rest_positions() * np.array([-1.0, 1.0, 1.0])  # left and right swapped
    assert table(sk, pos) == table(sk)


def test_evidence_is_part_of_the_rule_cache_key():
    sk = crab(reverse_numbers=True)
    key = (tuple(sk.names), tuple(sk.parents.tolist()), tuple(sk.end_site.tolist()))
    a = describe_structure(*key)
    b = describe_structure(*key, rest_evidence(sk))
    assert a.descriptions != b.descriptions
    assert describe_structure(*key) is a
    assert describe_structure(*key, rest_evidence(sk)) is b


def test_joint_evidence_inputs_and_errors():
    sk = bip01_bird()
    pos = sk.rest_positions()
    ev = joint_evidence(pos)
    assert isinstance(ev, JointEvidence) and ev.num_joints == sk.num_joints
    assert joint_evidence(np.repeat(pos[None], 3, axis=0)) == ev
    assert as_evidence(torch.from_numpy(pos), sk.num_joints) == ev
    toe = sk.names.index("Bip01_L_Toe0")
    assert ev.contact[toe] == 1.0 and ev.lateral[toe] > 0
    with pytest.raises(ValueError):
        describe_joints(sk, evidence=pos[:-1])
    with pytest.raises(ValueError):
        joint_evidence(np.zeros((2, 3, 4)))
    hash(ev)


def test_evidence_from_motion_any_up_axis_and_unit():
    sk = bip01_bird()
    frames = 4
    rot = np.broadcast_to(np.eye(3), (frames, sk.num_joints, 3, 3)).copy()
    motion = Motion(sk, rot, np.broadcast_to(sk.offsets, (frames,) + sk.offsets.shape).copy())
    want = table(sk, rest_evidence(sk))
    assert table(sk, evidence_from_motion(motion, up_axis="+Y")) == want
    z_up = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])  # +Y -> +Z, in cm
    sk_z = sk.replace(offsets=sk.offsets @ z_up.T * 100.0)
    moved = Motion(sk_z, rot, np.broadcast_to(sk_z.offsets, (frames,) + sk.offsets.shape).copy())
    assert table(sk_z, evidence_from_motion(moved, up_axis="+Z")) == want


def test_remap_evidence_by_name():
    sk = bip01_bird()
    ev = rest_evidence(sk)
    keep = [j for j, n in enumerate(sk.names) if "Tail" not in n]
    sub = sk.subset(keep)
    assert remap_evidence(ev, sk.names, sub) == ev.subset(keep)
    assert remap_evidence(None, sk.names, sub) is None


def test_call_semantic_passes_evidence_only_where_accepted():
    sk, ev = bip01_bird(), rest_evidence(bip01_bird())
    seen = []
    assert call_semantic(lambda s: 1, sk, ev) == 1
    assert call_semantic(lambda s, evidence=None: seen.append(evidence) or 2, sk, ev) == 2
    assert seen == [ev]


# -------------------------------------------------------------- pipeline
def test_dataset_embeds_each_file_with_its_evidence():
    from satagraph.data.dataset import MotionDataset
    from satagraph.data.features import motion_to_features
    from satagraph.datasets.sources import MotionFile
    from satagraph.transforms.canonical import canonicalize
    sk = crab(reverse_numbers=True)
    frames = 8
    rot = np.broadcast_to(np.eye(3), (frames, sk.num_joints, 3, 3)).copy()
    motion = Motion(sk, rot, np.broadcast_to(sk.offsets, (frames,) + sk.offsets.shape).copy())
    feats = motion_to_features(canonicalize(motion, up_axis="+Y", unit_scale=1.0))  # flat body
    sk = feats.skeleton  # the motionless root is removed
    calls = []

    def embed(skeleton, evidence=None):
        calls.append(evidence)
        texts = describe_joints(skeleton, evidence=evidence)
        return torch.tensor([[float("first leg pair" in t)] for t in texts])

    files = [MotionFile(path="a.bvh", dataset="d", skeleton="crab", split="train")]
    ds = MotionDataset(files, [feats], embed, window=4, stride=4)
    clip = ds[0]
    ds[1]
    assert len(calls) == 1 and calls[0] is not None  # once per skeleton + evidence
    first = [n for n, v in zip(sk.names, clip.semantic[:, 0].tolist()) if v]
    assert "leg_L_03" in first and "leg_L_01" not in first  # geometry, not numbers
    assert clip.meta["limb_ends"] == tuple(
        sk.names.index(n) for n in ("leg_L_03_03", "leg_R_03_03", "leg_L_01_03",
                                    "leg_R_01_03"))


def test_inference_embeds_target_with_its_evidence():
    from satagraph.pipelines.inference import _embed, static_features
    from satagraph.transforms.canonical import canonicalize
    sk = crab(reverse_numbers=True)
    motion = Motion(sk, np.broadcast_to(np.eye(3), (2, sk.num_joints, 3, 3)).copy(),
                    np.broadcast_to(sk.offsets, (2,) + sk.offsets.shape).copy())
    feats = static_features(canonicalize(motion, up_axis="+Y", unit_scale=1.0))
    sk = feats.skeleton
    got = _embed(lambda s, evidence=None: describe_joints(s, evidence=evidence), feats)
    assert "first leg pair" in got[sk.names.index("leg_L_03")]
    assert _embed(lambda s: "plain", feats) == "plain"
    assert _embed(None, feats) is None


def test_tags_cli_reads_the_motion(tmp_path, capsys):
    from satagraph.cli.tags import main
    from satagraph.io import write_bvh
    sk = crab(reverse_numbers=True)
    channels = [("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation",
                 "Yrotation") if p < 0 else ("Zrotation", "Xrotation", "Yrotation")
                for p in sk.parents.tolist()]
    sk = sk.replace(channels=channels)
    motion = Motion(sk, np.broadcast_to(np.eye(3), (3, sk.num_joints, 3, 3)).copy(),
                    np.broadcast_to(sk.offsets, (3,) + sk.offsets.shape).copy())
    write_bvh(motion, tmp_path / "crab.bvh")
    assert main([str(tmp_path / "crab.bvh"), "--json", "--up-axis", "+Y"]) == 0
    rows = {r["name"]: r["description"] for r in json.loads(capsys.readouterr().out)}
    assert "first leg pair" in rows["leg_L_03"]
    assert main([str(tmp_path / "crab.bvh"), "--json", "--names-only"]) == 0
    rows = {r["name"]: r["description"] for r in json.loads(capsys.readouterr().out)}
    assert "first leg pair" in rows["leg_L_01"]


def _regenerate() -> None:  # pragma: no cover - maintenance helper
    """Rewrite semantic_readings.json (run only after a reviewed change)."""
    import csv
    from satagraph.datasets.zoo import zoo_rigs
    from satagraph.io import read_bvh
    root, out = _data_dir(), {}
    rows = list(csv.DictReader(open(root / "manifest.tsv"), delimiter="\t"))
    best: Dict[str, dict] = {}
    for r in rows:
        key = r["skeleton"] if r["dataset"] != "fixtures" else r["path"]
        if key not in best or int(r["frames"]) < int(best[key]["frames"]):
            best[key] = r
    skels = {r["path"]: read_bvh(root / r["path"]).skeleton for r in best.values()}
    skels.update({r.name: r.skeleton for r in zoo_rigs()})
    for key, sk in skels.items():
        out[key] = {"names": list(sk.names), "parents": sk.parents.tolist(),
                    "descriptions": describe_joints(sk)}
    READINGS.write_text(json.dumps(out, indent=1, ensure_ascii=False), encoding="utf-8")


if __name__ == "__main__" and "--regenerate" in sys.argv:  # pragma: no cover
    _regenerate()
