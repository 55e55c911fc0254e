"""Semantic alignment benchmark: do joint-description embeddings find the
functionally corresponding joint in another skeleton?

For every pair of skeletons among the human rigs of ``../shared/data``
(bandai, cmu, ccbase, and the three fixture rigs: Mixamo, a MocapBank-style
rig named by joints -- Collar/Shoulder/Elbow/Wrist, Hip/Knee/Ankle -- and a
Blender rig) and the dog, and for every joint of a hand-made correspondence
table (pelvis, spine, neck, head, and each limb's girdle / upper / lower /
terminal segment and toes, where both skeletons have it), the nearest joint by
cosine similarity in the other skeleton must be one of the table's acceptable
answers. Both directions are
scored. The dog's tail has no counterpart and is not scored (its best match is
reported). Encoders: the default offline pipeline (rules + OfflineTextEncoder),
a baseline that embeds the raw names without rules, and a local T5 with
``--t5 PATH``.

Body plans beyond mammals (issue 15): the hand-built rigs of
:mod:`satagraph.semantics.reference_rigs` (a 3ds Max biped bird, also
with exporter noise in every name, a bird with finger-named wings, a crab, a
spider, a long-tailed quadruped) against the real humans and the dog:
bird <-> human (legs to legs, wings to arms), arthropod <-> quadruped (legs to
legs: a leg segment to the same side's leg segment of the same rank, front
or hind, any leg pair) and tail / neck / head; and the zoo's crab and
spider, written +X up in inches with an A rest pose and read back, whose leg
pairs must be told front to back (the first pair to a quadruped's front leg,
the last to its hind leg). Scored with the rules and the geometry / motion
evidence (real files and zoo files: their motion; reference rigs: their rest
pose), the rules on names alone, and the raw-name baseline.

It also times describing and embedding every joint of every skeleton in the
data with a warm embedding cache (target < 1 s).

Usage::

    .venv/bin/python benchmarks/semantic_alignment.py [--data DIR] [--t5 PATH]
"""
from __future__ import annotations

import argparse
import itertools
import re
import sys
import tempfile
import time
from pathlib import Path
from typing import Dict, List, Sequence, Tuple

import torch

from satagraph.semantics import (OfflineTextEncoder, T5TextEncoder,
                                 TextEncoder, clear_memory,
                                 describe_joints, embed_skeleton,
                                 embed_texts, evidence_from_motion)
from satagraph.semantics.reference_rigs import (REFERENCE_RIGS,
                                                rest_evidence,
                                                with_exporter_noise)
from satagraph.semantics.lexicon import split_words, strip_prefixes
from satagraph.semantics.lexicon import parse_name
from satagraph.semantics.rules import describe_structure
from satagraph.datasets.zoo import Dialect, apply_dialect, generate_clip, zoo_rigs
from satagraph.io import read_bvh, write_bvh
from satagraph.sides import swap_side
from satagraph.utils.files import atomic_write_text
from results_io import SHARED_DATA

REPO = Path(__file__).resolve().parents[1]
RESULTS = REPO / "benchmarks" / "results" / "semantic_alignment.md"
FILES = {"bandai": "bandai/dataset-1_bow_active_001.bvh",
         "cmu": "cmu/01_01.bvh", "ccbase": "ccbase/006_01.bvh",
         "mixamo": "fixtures/test_freebvh.bvh",
         "mocapbank": "fixtures/test_mocapbank.bvh",
         "blender": "fixtures/test3.bvh",
         "dog": "dog/D1_001_KAN01_001.bvh"}
HUMANS = ("bandai", "cmu", "ccbase", "mixamo", "mocapbank", "blender")
_M = "mixamorig:"

# concept -> skeleton -> acceptable joints, "|"-separated (absent: none).
# Limb concepts are written for the left side; the right side is mirrored.
CENTRAL = {
    "pelvis": {"bandai": "Hips", "cmu": "Hips", "dog": "Hips",
               "ccbase": "CC_Base_Hip|CC_Base_Pelvis", "mixamo": _M + "Hips",
               "mocapbank": "Hips", "blender": "pelvis"},
    "spine": {"bandai": "Spine|Chest", "cmu": "LowerBack|Spine|Spine1",
              "ccbase": "CC_Base_Waist|CC_Base_Spine01|CC_Base_Spine02",
              "dog": "Spine|Spine1",
              "mixamo": f"{_M}Spine|{_M}Spine1|{_M}Spine2",
              "mocapbank": "Chest|Chest2", "blender": "spine|spine.001"},
    "neck": {"bandai": "Neck", "cmu": "Neck|Neck1",
             "ccbase": "CC_Base_NeckTwist01|CC_Base_NeckTwist02",
             "dog": "Neck", "mixamo": _M + "Neck", "mocapbank": "Neck",
             "blender": "neck"},
    "head": {"bandai": "Head", "cmu": "Head", "ccbase": "CC_Base_Head",
             "dog": "Head", "mixamo": _M + "Head", "mocapbank": "Head",
             "blender": "face"},
}
LIMBS = {
    "front girdle": {"bandai": "Shoulder_L", "cmu": "LeftShoulder",
                     "ccbase": "CC_Base_L_Clavicle", "dog": "LeftShoulder",
                     "mixamo": _M + "LeftShoulder", "mocapbank": "LeftCollar",
                     "blender": "shoulder.L"},
    "front upper": {"bandai": "UpperArm_L", "cmu": "LeftArm",
                    "ccbase": "CC_Base_L_Upperarm", "dog": "LeftArm",
                    "mixamo": _M + "LeftArm", "mocapbank": "LeftShoulder",
                    "blender": "upper_arm.L"},
    "front lower": {"bandai": "LowerArm_L", "cmu": "LeftForeArm",
                    "ccbase": "CC_Base_L_Forearm", "dog": "LeftForeArm",
                    "mixamo": _M + "LeftForeArm", "mocapbank": "LeftElbow",
                    "blender": "forearm.L"},
    "front terminal": {"bandai": "Hand_L", "cmu": "LeftHand",
                       "ccbase": "CC_Base_L_Hand", "dog": "LeftHand",
                       "mixamo": _M + "LeftHand", "mocapbank": "LeftWrist"},
    "hind girdle": {"cmu": "LHipJoint", "blender": "pelvis.L"},
    "hind upper": {"bandai": "UpperLeg_L", "cmu": "LeftUpLeg",
                   "ccbase": "CC_Base_L_Thigh", "dog": "LeftUpLeg",
                   "mixamo": _M + "LeftUpLeg", "mocapbank": "LeftHip",
                   "blender": "thigh.L"},
    "hind lower": {"bandai": "LowerLeg_L", "cmu": "LeftLeg",
                   "ccbase": "CC_Base_L_Calf", "dog": "LeftLeg",
                   "mixamo": _M + "LeftLeg", "mocapbank": "LeftKnee",
                   "blender": "shin.L"},
    "hind terminal": {"bandai": "Foot_L", "cmu": "LeftFoot",
                      "ccbase": "CC_Base_L_Foot", "dog": "LeftFoot",
                      "mixamo": _M + "LeftFoot", "mocapbank": "LeftAnkle",
                      "blender": "foot.L"},
    "hind toes": {"bandai": "Toes_L", "cmu": "LeftToeBase",
                  "ccbase": "CC_Base_L_ToeBase", "mixamo": _M + "LeftToeBase"},
}
def mirror(name: str) -> str:
    """Right-side name of a left-side joint name (:func:`satagraph.sides.swap_side`)."""
    return swap_side(name)


def build_table() -> List[Tuple[str, Dict[str, Tuple[str, ...]]]]:
    """Rows (concept, skeleton -> acceptable joint names)."""
    table = [(c, {k: tuple(v.split("|")) for k, v in cols.items()})
             for c, cols in CENTRAL.items()]
    for concept, cols in LIMBS.items():
        table.append((f"left {concept}", {k: (v,) for k, v in cols.items()}))
        table.append((f"right {concept}",
                      {k: (mirror(v),) for k, v in cols.items()}))
    return table


TABLE = build_table()

# ------------------------------------------------- body plans beyond mammals
BIRDS = ("bird_bip01", "bird_bip01_noise", "bird_fingerwing")
ARTHROPODS = ("crab", "spider")
#: Zoo arthropods read from a dialect file with their motion as evidence.
ZOO_ARTHROPODS = ("zoo_crab", "zoo_spider")
QUADRUPEDS = ("dog", "quadruped_longtail")
_B = "Bip01_L_"
_CRAB = [f"leg_L_0{n}" for n in (1, 2, 3)]
_SPIDER = [f"Leg_L_0{n}" for n in (1, 2, 3, 4)]
# group -> concept -> skeleton -> acceptable joints (left side; mirrored).
BODYPLAN = {
    "wings to arms": {
        "front girdle": {"bird_bip01": _B + "Clavicle"},
        "front upper": {"bird_bip01": _B + "UpperArm", "bird_fingerwing": "L_Finger_01"},
        "front lower": {"bird_bip01": _B + "Forearm", "bird_fingerwing": "L_Finger_02"},
        "front terminal": {"bird_bip01": _B + "Hand", "bird_fingerwing": "L_Finger_03"},
    },
    "legs to legs": {
        "hind upper": {"bird_bip01": _B + "Thigh", "bird_fingerwing": "thigh_L"},
        "hind lower": {"bird_bip01": _B + "Calf", "bird_fingerwing": "shin_L"},
        "hind terminal": {"bird_bip01": _B + "Foot", "bird_fingerwing": "tarsus_L"},
        "hind toes": {"bird_bip01": _B + "Toe0", "bird_fingerwing": "toe_L"},
        "leg upper": {"crab": "|".join(_CRAB), "spider": "|".join(_SPIDER),
                      "dog": "LeftArm|LeftUpLeg",
                      "quadruped_longtail": "LeftArm|LeftUpLeg"},
        "leg lower": {"crab": "|".join(f"{c}_02" for c in _CRAB),
                      "spider": "|".join(f"{c}_1" for c in _SPIDER),
                      "dog": "LeftForeArm|LeftLeg",
                      "quadruped_longtail": "LeftForeArm|LeftLeg"},
        "leg terminal": {"crab": "|".join(f"{c}_03" for c in _CRAB),
                         "spider": "|".join(f"{c}_2" for c in _SPIDER),
                         "dog": "LeftHand|LeftFoot",
                         "quadruped_longtail": "LeftHand|LeftFoot"},
    },
    "leg pairs front to back": {
        f"{end} leg {seg}": {
            "zoo_crab": f"leg_L_0{1 if end == 'front' else 3}{crab}",
            "zoo_spider": f"Leg_L_0{1 if end == 'front' else 4}{spider}",
            "dog": quad[end == "hind"], "quadruped_longtail": quad[end == "hind"]}
        for seg, crab, spider, quad in (
            ("upper", "", "", ("LeftArm", "LeftUpLeg")),
            ("lower", "_02", "_1", ("LeftForeArm", "LeftLeg")),
            ("terminal", "_03", "_2", ("LeftHand", "LeftFoot")))
        for end in ("front", "hind")},
    "tail / neck / head": {
        "tail": {"bird_bip01": "Bip01_Tail|Bip01_Tail1", "dog": "Tail|Tail1",
                 "quadruped_longtail": "|".join(f"Tail_{i:02d}" for i in range(1, 33))},
        "neck": {"bird_bip01": "Bip01_Neck|Bip01_Neck1", "bird_fingerwing": "neck_01|neck_02",
                 "quadruped_longtail": "Neck|Neck1", "dog": "Neck"},
        "head": {"bird_bip01": "Bip01_Head", "bird_fingerwing": "head",
                 "quadruped_longtail": "Head", "dog": "Head"},
    },
}
# (pair kind, groups scored, pairs)
BODYPLAN_PAIRS = [
    ("bird<->human", ("wings to arms", "legs to legs", "tail / neck / head"),
     [(b, h) for b in BIRDS for h in HUMANS]),
    ("arthropod<->quadruped", ("legs to legs",),
     [(a, q) for a in ARTHROPODS for q in QUADRUPEDS]),
    ("arthropod<->quadruped, pairs in order", ("leg pairs front to back",),
     [(a, q) for a in ZOO_ARTHROPODS for q in QUADRUPEDS]),
    ("tail/neck", ("tail / neck / head",),
     [("bird_bip01", "dog"), ("bird_bip01", "quadruped_longtail"),
      ("bird_bip01_noise", "dog"), ("quadruped_longtail", "dog"),
      ("bird_fingerwing", "dog")]),
]
_HUMAN_ROWS = {"front girdle", "front upper", "front lower", "front terminal",
               "hind upper", "hind lower", "hind terminal", "hind toes"}


def _mirror_in(key: str, name: str) -> str:
    """Right-side joint of a left-side joint in skeleton :obj:`key` (the
    spider numbers its right legs 05 .. 08)."""
    if key.endswith("spider"):
        return re.sub(r"Leg_L_0(\d)", lambda m: f"Leg_R_0{int(m.group(1)) + 4}", name)
    return mirror(name)


def build_bodyplan_table(noise: Dict[str, str]) -> Dict[str, list]:
    """Group -> rows (concept, skeleton -> acceptable names), both sides;
    human columns from :data:`LIMBS` / :data:`CENTRAL`, the noisy bird's
    from the clean bird's through :obj:`noise` (clean -> noisy name)."""
    out: Dict[str, list] = {}
    for group, concepts in BODYPLAN.items():
        rows = []
        for concept, cols in concepts.items():
            cols = dict(cols)
            if concept in _HUMAN_ROWS:
                cols.update({h: LIMBS[concept][h] for h in HUMANS
                             if h in LIMBS[concept]})
            if concept in CENTRAL:
                cols.update({h: CENTRAL[concept][h] for h in HUMANS})
            if "bird_bip01" in cols:  # clean names, made noisy after mirroring
                cols["bird_bip01_noise"] = cols["bird_bip01"]
            paired = concept not in ("tail", "neck", "head")
            sides = (("left", lambda k, n: n), ("right", _mirror_in)) if paired \
                else (("", lambda k, n: n),)
            for side, fn in sides:
                rows.append((f"{side} {concept}".strip(), {
                    k: tuple(noise.get(fn(k, n), fn(k, n)) if k.endswith("_noise")
                             else fn(k, n) for n in v.split("|"))
                    for k, v in cols.items()}))
        out[group] = rows
    return out

# Free-text tags (paper Table 11 "Variant A" style labels and user anchor
# tags) -> acceptable joints. Not identical to any rule description, so this
# measures the encoder's graded similarity, not the rules.
QUERIES = {
    "Pelvis": {"cmu": "Hips", "dog": "Hips"},
    "Lower Back": {"cmu": "LowerBack", "dog": "Spine|Spine1"},
    "Head Crown": {"cmu": "Head|Head_end", "dog": "Head|Head_end"},
    "Neck": {"cmu": "Neck|Neck1", "dog": "Neck"},
    "Left Clavicle": {"cmu": "LeftShoulder", "dog": "LeftShoulder"},
    "Left Upper Arm": {"cmu": "LeftArm", "dog": "LeftArm"},
    "Right Forearm": {"cmu": "RightForeArm", "dog": "RightForeArm"},
    "Left Hand": {"cmu": "LeftHand", "dog": "LeftHand"},
    "front right paw": {"cmu": "RightHand", "dog": "RightHand"},
    "Left Thigh": {"cmu": "LeftUpLeg", "dog": "LeftUpLeg"},
    "Right Calf": {"cmu": "RightLeg", "dog": "RightLeg"},
    "Right Shin": {"cmu": "RightLeg", "dog": "RightLeg"},
    "left hind paw": {"cmu": "LeftFoot", "dog": "LeftFoot"},
    "Left Foot": {"cmu": "LeftFoot", "dog": "LeftFoot"},
    "Left Toe Tip": {"cmu": "LeftToeBase_end", "dog": "LeftFoot_end"},
    "tail base": {"dog": "Tail|Tail1"},
}


def evaluate_bodyplans(label: str, texts_of, encoder: TextEncoder,
                       skels: dict, cache_dir: Path, table: Dict[str, list]
                       ) -> Tuple[List[str], List[str]]:
    """Markdown rows of the body-plan correspondences for one encoder (one
    row per rig and kind, over its partners), and the misses."""
    embs = {k: embed_texts(texts_of(k, s), encoder, cache_dir)
            for k, s in skels.items()}
    rows, misses = [], []
    for kind, groups, pairs in BODYPLAN_PAIRS:
        rows_of = [r for g in groups for r in table[g]]
        per_rig: Dict[str, List[int]] = {}
        for a, b in pairs:
            c, t, m = score_pair(a, b, skels, embs, rows_of)
            per_rig.setdefault(a, [0, 0, []])
            per_rig[a][0] += c
            per_rig[a][1] += t
            per_rig[a][2].append(b)
            misses += [f"[{label}] {x}" for x in m]
        for rig, (c, t, partners) in per_rig.items():
            who = partners[0] if len(partners) == 1 else \
                f"{{{', '.join(partners)}}}"
            rows.append(f"| {label} | {rig}<->{who} | {kind} | {c}/{t} | "
                        f"{100 * c / t:.1f}% |")
        c = sum(v[0] for v in per_rig.values())
        t = sum(v[1] for v in per_rig.values())
        rows.append(f"| {label} | **all {kind}** | {kind} | {c}/{t} | "
                    f"**{100 * c / t:.1f}%** |")
    return rows, misses


def raw_name_texts(skeleton) -> List[str]:
    """Baseline texts: the raw names split into words, no rules."""
    return [" ".join(split_words(strip_prefixes(n))) or n
            for n in skeleton.names]


def nearest(emb_a: torch.Tensor, emb_b: torch.Tensor) -> torch.Tensor:
    """Index in B of the most cosine-similar joint for every joint of A."""
    a = torch.nn.functional.normalize(emb_a, dim=1)
    b = torch.nn.functional.normalize(emb_b, dim=1)
    return (a @ b.T).argmax(dim=1)


def score_pair(a: str, b: str, skels: dict, embs: dict, table=None
               ) -> Tuple[int, int, List[str]]:
    """Correct / total queries in both directions, and the misses."""
    correct, total, misses = 0, 0, []
    for src, dst in ((a, b), (b, a)):
        names_s, names_d = skels[src].names, skels[dst].names
        nn_idx = nearest(embs[src], embs[dst])
        for concept, cols in (TABLE if table is None else table):
            if src not in cols or dst not in cols:
                continue
            for query in cols[src]:
                got = names_d[int(nn_idx[names_s.index(query)])]
                total += 1
                if got in cols[dst]:
                    correct += 1
                else:
                    misses.append(f"{src}:{query} -> {dst}:{got} "
                                  f"(want {'/'.join(cols[dst])})")
    return correct, total, misses


def evaluate(label: str, texts_of, encoder: TextEncoder, skels: dict,
             cache_dir: Path) -> Tuple[List[str], List[str]]:
    """Markdown rows for one encoder, and its misses."""
    embs = {k: embed_texts(texts_of(s), encoder, cache_dir)
            for k, s in skels.items()}
    rows, misses, groups = [], [], {"human<->dog": [0, 0],
                                    "human<->human": [0, 0]}
    for a, b in itertools.combinations(list(skels), 2):
        kind = "human<->dog" if "dog" in (a, b) else "human<->human"
        c, t, m = score_pair(a, b, skels, embs)
        groups[kind][0] += c
        groups[kind][1] += t
        misses += [f"[{label}] {x}" for x in m]
        rows.append(f"| {label} | {a}<->{b} | {kind} | {c}/{t} | "
                    f"{100 * c / t:.1f}% |")
    for kind, (c, t) in groups.items():
        rows.append(f"| {label} | **all {kind}** | {kind} | {c}/{t} | "
                    f"**{100 * c / t:.1f}%** |")
    tail = skels["dog"].names.index("Tail")
    for h in HUMANS:
        sims = torch.nn.functional.normalize(embs["dog"][tail:tail + 1], dim=1) \
            @ torch.nn.functional.normalize(embs[h], dim=1).T
        j = int(sims.argmax())
        misses.append(f"[{label}] (unscored) dog:Tail best match {h}:"
                      f"{skels[h].names[j]} cos={float(sims[0, j]):.2f}")
    return rows, misses


def evaluate_queries(label: str, texts_of, encoder: TextEncoder,
                     skels: dict, cache_dir: Path) -> Tuple[str, List[str]]:
    """One markdown row: free-text queries matched against rule texts."""
    texts = list(QUERIES)
    q = torch.nn.functional.normalize(
        embed_texts(texts, encoder, cache_dir), dim=1)
    correct, total, misses = 0, 0, []
    for key in ("cmu", "dog"):
        emb = torch.nn.functional.normalize(
            embed_texts(texts_of(skels[key]), encoder, cache_dir), dim=1)
        best = (q @ emb.T).argmax(dim=1)
        for i, text in enumerate(texts):
            if key not in QUERIES[text]:
                continue
            got = skels[key].names[int(best[i])]
            total += 1
            if got in QUERIES[text][key].split("|"):
                correct += 1
            else:
                misses.append(f"[{label}] query {text!r} -> {key}:{got} "
                              f"(want {QUERIES[text][key]})")
    return (f"| {label} | free-text queries -> cmu, dog | paraphrase | "
            f"{correct}/{total} | {100 * correct / total:.1f}% |", misses)


def load_all(data: Path) -> List:
    """Every skeleton of every BVH file in the data folder."""
    return [read_bvh(p).skeleton for p in sorted(data.glob("*/*.bvh"))]


def time_all(skeletons: Sequence, cache_dir: Path) -> Tuple[float, float, int]:
    """Seconds to describe + embed all joints with a warm disk cache:
    (rule memos and in-memory cache cleared, everything warm), joints."""
    for s in skeletons:  # warm the disk cache
        embed_skeleton(s, cache_dir=cache_dir)
    describe_structure.cache_clear()
    parse_name.cache_clear()
    clear_memory()
    t0 = time.perf_counter()
    for s in skeletons:
        embed_skeleton(s, cache_dir=cache_dir)
    cold = time.perf_counter() - t0
    t0 = time.perf_counter()
    joints = sum(embed_skeleton(s, cache_dir=cache_dir).shape[0]
                 for s in skeletons)
    return cold, time.perf_counter() - t0, joints


def _parse_args(argv: Sequence[str] = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path,
                        default=SHARED_DATA,
                        help="shared BVH data folder (default ../shared/data)")
    parser.add_argument("--t5", type=Path, default=None,
                        help="local T5 folder (optional)")
    parser.add_argument("--out", type=Path, default=RESULTS,
                        help="markdown results file")
    return parser.parse_args(argv)


def _encoders(t5_path: Path = None) -> list:
    """(label, texts of a skeleton, encoder) to evaluate."""
    offline = OfflineTextEncoder()
    out = [("offline (rules)", describe_joints, offline),
           ("offline (raw names, no rules)", raw_name_texts, offline)]
    if t5_path is not None:
        t5 = T5TextEncoder(t5_path)
        out += [("t5 (rules)", describe_joints, t5),
                ("t5 (raw names, no rules)", raw_name_texts, t5)]
    return out


def _check_table(skels: dict, table=None) -> None:
    for concept, cols in (TABLE if table is None else table):
        for key, names in cols.items():
            bad = [n for n in names if n not in skels[key].names]
            assert not bad, f"table row {concept!r}: {key} has no {bad}"


def _timing_lines(data: Path, cache_dir: Path) -> List[str]:
    t_load = time.perf_counter()
    every = load_all(data)
    t_load = time.perf_counter() - t_load
    cold, warm, joints = time_all(every, cache_dir)
    verdict = "meets" if max(cold, warm) < 1.0 else "MISSES"
    return ["", "## Timing (describe + embed, warm embedding cache)", "",
            f"- {len(every)} files, {joints} joints (reading the BVH files "
            f"is not timed: {t_load:.1f} s)",
            f"- fresh rule memos, cache file read from disk: {cold:.3f} s",
            f"- everything warm: {warm:.3f} s",
            f"- target < 1 s: {verdict}", ""]


def bodyplan_skeletons(motions: dict) -> Tuple[dict, dict, Dict[str, str]]:
    """Skeletons and evidence of the real files and the reference rigs, and
    the noisy bird's clean -> noisy joint names."""
    skels = {k: m.skeleton for k, m in motions.items()}
    evidence = {k: evidence_from_motion(m) for k, m in motions.items()}
    refs = {"bird_bip01": REFERENCE_RIGS["bird_bip01"](),
            "bird_fingerwing": REFERENCE_RIGS["bird_fingerwing"](),
            "crab": REFERENCE_RIGS["crab"](), "spider": REFERENCE_RIGS["spider"](),
            "quadruped_longtail": REFERENCE_RIGS["quadruped_longtail"]()}
    refs["bird_bip01_noise"] = with_exporter_noise(refs["bird_bip01"])
    noise = dict(zip(refs["bird_bip01"].names, refs["bird_bip01_noise"].names))
    for k, sk in refs.items():
        skels[k], evidence[k] = sk, rest_evidence(sk)
    for k in ZOO_ARTHROPODS:
        motion = zoo_file_motion(k[len("zoo_"):])
        skels[k], evidence[k] = motion.skeleton, evidence_from_motion(motion)
    return skels, evidence, noise


def zoo_file_motion(species: str):
    """A zoo rig's walk written +X up in inches with an A rest pose, read
    back from the file (up axis detected, units the file's own)."""
    clip = generate_clip(zoo_rigs([species], seed=0)[0], "walk", frames=90, seed=1)
    motion = apply_dialect(clip, Dialect(up_axis="+X", unit="in", rest="apose"))[0]
    with tempfile.TemporaryDirectory() as tmp:
        write_bvh(motion, Path(tmp) / f"{species}.bvh")
        return read_bvh(Path(tmp) / f"{species}.bvh")


def _bodyplan_lines(motions: dict, t5_path: Path, cache_dir: Path
                    ) -> Tuple[List[str], List[str]]:
    """The body-plan section of the results and its misses."""
    skels, evidence, noise = bodyplan_skeletons(motions)
    table = build_bodyplan_table(noise)
    for rows in table.values():
        _check_table(skels, rows)
    lines = ["", "## Body plans beyond mammals", "",
             "Reference rigs (`satagraph/semantics/reference_rigs.py`, the "
             "issue 15 rig spec) against the real humans (bandai, cmu, ccbase, "
             "mixamo, mocapbank, blender) and the dog; `bird_bip01_noise` has an "
             "exporter suffix on every name (`__x7Q`, `_v2`, `_a1b2c3`). "
             "`zoo_crab` / `zoo_spider`: the zoo's rigs written +X up in inches "
             "with an A rest pose and read back; their first leg pair must meet a "
             "quadruped's front leg and their last its hind leg. Evidence: real "
             "and zoo files their motion, reference rigs their rest pose. Both "
             "directions; a row sums a rig over its partners.", "",
             "| encoder | pairs | kind | correct | accuracy |",
             "|---|---|---|---|---|"]
    notes: List[str] = []
    for label, texts_of, enc in _encoders(t5_path):
        variants = ([(f"{label[:-1]} + evidence)", lambda k, s, f=texts_of:
                      f(s, evidence=evidence[k])),
                     (f"{label[:-1]}, names only)", lambda k, s, f=texts_of: f(s))]
                    if "no rules" not in label else
                    [(label, lambda k, s, f=texts_of: f(s))])
        for name, fn in variants:
            rows, misses = evaluate_bodyplans(name, fn, enc, skels, cache_dir, table)
            lines += rows
            if "no rules" not in name:
                notes += misses
    return lines, notes


def main(argv: Sequence[str] = None) -> int:
    """Run the benchmark, print the table, write the results file."""
    args = _parse_args(argv)
    if not args.data.is_dir():
        print(f"no data folder {args.data}; pass --data", file=sys.stderr)
        return 2
    motions = {k: read_bvh(args.data / f) for k, f in FILES.items()}
    skels = {k: m.skeleton for k, m in motions.items()}
    _check_table(skels)
    lines = ["# Semantic alignment", "",
             "Nearest joint by cosine of description embeddings, both "
             "directions, hand-made correspondence table "
             "(`benchmarks/semantic_alignment.py`).", "",
             "| encoder | pair | kind | correct | accuracy |",
             "|---|---|---|---|---|"]
    notes: List[str] = []
    with tempfile.TemporaryDirectory() as tmp:
        for label, texts_of, enc in _encoders(args.t5):
            rows, misses = evaluate(label, texts_of, enc, skels, Path(tmp))
            row, more = evaluate_queries(label, texts_of, enc, skels,
                                         Path(tmp))
            lines += rows + [row]
            if "no rules" not in label:  # baselines: too many to list
                notes += misses + more
        body, more = _bodyplan_lines(motions, args.t5, Path(tmp))
        notes += more
        timing = _timing_lines(args.data, Path(tmp) / "timing")
    lines += body
    lines += ["", "## Misses and notes (rule-based rows)", ""]
    lines += [f"- {n}" for n in notes] + timing
    text = "\n".join(lines)
    print(text)
    atomic_write_text(args.out, text, create_parent=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
