"""Templated captions of the motion-capture datasets and the zoo, and the
captioned clips of manifests."""
from __future__ import annotations

import collections
from pathlib import Path

import numpy as np
import pytest

from satagraph.datasets.sources import MotionFile
from satagraph.datasets.zoo import MOTION_COLUMNS, ClipFacts, generate_clip_with_facts, write_zoo
from satagraph.datasets.zoo.endless import EndlessZoo
from satagraph.datasets import (CAPTIONERS, Caption, CaptionError, captioned_clips,
                                captions_for, choose, infer_dataset, zoo_clip_of_row)
from satagraph.datasets.mocap_captions import BANDAI_ACTIONS, BANDAI_STYLES
from satagraph.datasets.zoo_captions import UNTOLD_TURN


def texts(path, **kwargs):
    return [c.text for c in captions_for(path, **kwargs)]


# ------------------------------------------------------------- mocap names
def test_bandai_exact_captions():
    assert set(texts("bandai/dataset-1_walk_normal_002.bvh")) == {
        "a person walks forward", "someone walks forward", "a person walks",
        "someone walks"}
    assert texts("bandai/dataset-1_bye_chimpira_001.bvh") == [
        "a person waves goodbye with one hand like a thug",
        "someone waves goodbye with one hand like a thug",
        "a person waves goodbye with one hand like a street punk",
        "someone waves goodbye with one hand like a street punk",
        "a thuggish person waves goodbye with one hand",
        "a person waves a hand to say goodbye like a thug",
        "someone waves a hand to say goodbye like a thug",
        "a person waves a hand to say goodbye like a street punk",
        "someone waves a hand to say goodbye like a street punk",
        "a thuggish person waves a hand to say goodbye"]
    timid = texts("dataset-1_walk-back_not-confident_001.bvh")
    assert "a timid person walks backward" in timid
    assert "someone walks backwards without confidence" in timid
    assert "an elderly person dashes forward" in texts("dataset-1_dash_old_001.bvh")
    captions = captions_for("dataset-1_kick_normal_001.bvh")
    assert {c.source for c in captions} == {"bandai"}
    assert all(c.whole for c in captions)


def test_bandai_tables_cover_the_manifest_tokens():
    # The 16 action and 15 style tokens of the shared manifest.
    assert sorted(BANDAI_ACTIONS) == sorted(
        "bow bye byebye call dance-short dash guide kick punch respond run slash walk "
        "walk-back walk-left walk-right".split())
    assert sorted(BANDAI_STYLES) == sorted(
        "active angry childish chimpira feminine giant happy masculinity musical normal "
        "not-confident old proud sad tired".split())
    # Unknown tokens give no caption rather than a guess.
    assert captions_for("dataset-1_dance-long_normal_001.bvh") == []
    assert captions_for("dataset-1_walk_sleepy_001.bvh") == []


def test_cmu_xia_and_ccbase_captions():
    assert texts("cmu/01_01.bvh")[0] == \
        "a person jumps forward several times and turns around"
    assert set(texts("cmu/neutral_16_000.bvh")) == {
        "a person jumps", "someone jumps", "a person makes a jump", "someone makes a jump"}
    assert "a depressed person throws a punch" in texts("cmu/depressed_18_000.bvh")
    assert "someone runs forward angrily" in texts("cmu/angry_13_000.bvh")
    assert "a person walks forward with a strut" in texts("cmu/strutting_01_000.bvh")
    assert captions_for("cmu/angry_99_000.bvh") == []  # unknown content
    dribble = texts("ccbase/006_04.bvh")
    assert dribble == texts("ccbase/006_15.bvh")  # subject level: trials alike
    assert "a person dribbles a basketball" in dribble
    assert texts("ccbase/007_01.bvh") == ["a person walks", "someone walks",
                                          "a person takes a walk"]
    assert captions_for("ccbase/009_01.bvh") == []


def test_dog_and_fixtures_have_no_captions_by_design():
    assert CAPTIONERS["dog"] is None and CAPTIONERS["fixtures"] is None
    assert captions_for("dog/D1_010_KAN01_002.bvh") == []
    assert captions_for({"path": "dog/D1_001_KAN01_001.bvh", "dataset": "dog"}) == []
    assert captions_for("fixtures/test3.bvh") == []


def test_dataset_inference_and_clip_forms():
    assert infer_dataset("x/dataset-1_bow_sad_001.bvh") == "bandai"
    assert infer_dataset("somewhere/006_01.bvh") == "ccbase"
    assert infer_dataset("somewhere/01_01.bvh") == "cmu"
    assert infer_dataset("somewhere/old_13_000.bvh") == "cmu"
    assert infer_dataset("dog/anything.bvh") == "dog"
    assert infer_dataset("elsewhere/clip.bvh") is None
    path = "data/bandai/dataset-1_bow_sad_001.bvh"
    by_path = texts(path)
    assert texts(Path(path)) == by_path
    assert texts({"path": "bandai/dataset-1_bow_sad_001.bvh", "dataset": "bandai"}) == by_path
    assert texts(MotionFile(path, "bandai", "bandai22", "test")) == by_path
    # An explicit dataset wins over the name.
    assert captions_for(path, dataset="dog") == []


def test_choice_of_phrasings_is_seeded():
    path = "dataset-1_walk_angry_001.bvh"
    every = texts(path)
    assert len(every) == 10
    a, b = texts(path, count=3, seed=1), texts(path, count=3, seed=1)
    assert a == b and len(a) == 3 and set(a) <= set(every)
    assert [t for t in every if t in a] == a  # canonical order kept
    picks = {tuple(texts(path, count=3, seed=s)) for s in range(8)}
    assert len(picks) > 1
    assert texts(path, count=0) == [] and texts(path, count=99) == every
    assert choose(["x", "y", "x"], "k") == ["x", "y"]
    with pytest.raises(CaptionError, match="count"):
        choose(["x", "y"], "k", count=-1)


# -------------------------------------------------------------------- zoo
def _heading_change(root: np.ndarray, span: int = 8) -> float:
    """Signed angle (degrees, positive to the left = +X of +Z) between the
    root's first and last displacement."""
    d0, d1 = root[span] - root[0], root[-1] - root[-1 - span]
    cross = d0[2] * d1[0] - d0[0] * d1[2]
    return float(np.degrees(np.arctan2(cross, d0[0] * d1[0] + d0[2] * d1[2])))


def test_zoo_turn_side_is_the_side_of_the_left_joints():
    from satagraph.datasets.zoo import zoo_rigs
    rig = zoo_rigs(["biped"])[0]
    for seed in range(4):
        motion, facts = generate_clip_with_facts(rig, "turn", 60, 30.0, seed)
        pos = motion.global_positions()
        root = pos[:, 0]
        measured = _heading_change(root)
        assert np.sign(measured) == np.sign(facts.turn) and abs(facts.turn) > 30
        # "left" is the side of the joints named Left at the start
        forward = (root[8] - root[0]) / np.linalg.norm(root[8] - root[0])
        left_dir = np.array([forward[2], 0.0, -forward[0]])
        left = [j for j, n in enumerate(motion.skeleton.names) if "left" in n.lower()]
        assert left and float(np.mean((pos[0, left] - root[0]) @ left_dir)) > 0
        side = "left" if facts.turn > 0 else "right"
        words = " ".join(texts(facts))
        assert f" {side}" in words and ({"left", "right"} - {side}).pop() not in words


def test_endless_zoo_captions_match_the_generated_motion():
    zoo = EndlessZoo(species=["biped", "quadruped", "crab"], noise=0.0, seed=3)
    kinds = collections.Counter()
    for index in range(48):
        sample = zoo.sample(0, index, 65)
        facts = sample.facts
        assert facts is not None and facts.kind == sample.kind
        assert facts.species == sample.species
        captions = captions_for(sample)
        assert captions and {c.source for c in captions} == {"zoo"}
        words = " ".join(c.text for c in captions)
        root = sample.motion.global_positions()[:, 0]
        speed = np.linalg.norm(np.diff(root[:, [0, 2]], axis=0), axis=1) * 30.0
        kinds[sample.kind] += 1
        if sample.kind == "turn":
            side = "left" if _heading_change(root) > 0 else "right"
            assert f"to the {side}" in words or f" {side} while" in words, words
        elif sample.kind == "speed":
            faster = speed[-5:].mean() > speed[:5].mean()
            assert ("speeding up" in words) == faster, words
            assert ("slowing down" in words) == (not faster), words
        elif sample.kind in ("idle", "look"):
            assert speed.max() < 0.05 * speed.mean() + 0.2 and "stands" in words
            assert ("looking around" in words) == (sample.kind == "look"), words
        elif sample.kind == "jump":
            assert "jumps" in words and "walks" not in words, words
        elif sample.kind == "reach":
            assert speed.max() < 0.2 and "arm" in words and "walks" not in words, words
        elif sample.kind in ("start", "stop"):
            moving_at_end = speed[-5:].mean() > speed[:5].mean()
            assert moving_at_end == (sample.kind == "start"), (sample.kind, speed)
            assert min(speed[:5].mean(), speed[-5:].mean()) < 0.02, speed
            assert ("starts walking" in words or "sets off" in words) == moving_at_end, words
            assert ("halt" in words or "stop" in words) == (not moving_at_end), words
        elif sample.kind == "back":
            assert "backward" in words and "forward" not in words, words
        elif sample.kind == "side":
            side = "left" if facts.travel > 0 else "right"
            assert f" {side}" in words and ({"left", "right"} - {side}).pop() not in words
        elif sample.kind == "run":
            assert ("runs" in words or "dashes" in words) and "walks" not in words, words
        else:
            assert "forward" in words and " left" not in words and "right" not in words
    assert set(kinds) >= {"walk", "turn", "speed", "idle", "start", "stop", "look", "back",
                          "side", "run"}


def test_zoo_phrasings_by_kind_and_species():
    snake = ClipFacts("snake", "turn", 3.0, 0.25, 0.25, -20.0)
    assert set(texts(snake)) == {
        "a snake slithers forward and veers to the right",
        "a long snake slithers forward and veers to the right",
        "a snake veers right while slithering",
        "a long snake veers right while slithering"}
    big = texts(ClipFacts("biped", "turn", 4.0, 1.3, 1.3, 190.0))
    assert "a person walks forward and turns around to the left" in big
    slow = texts(ClipFacts("quadruped", "speed", 4.0, 1.3, 0.7, 0.0))
    assert "a quadruped walks forward, slowing down" in slow
    assert "a four-legged animal trots forward" in texts(
        ClipFacts("quadruped", "trot", 4.0, 2.4, 2.4, 1.0))
    assert "a snake lies in place, swaying the front of its body" in texts(
        ClipFacts("snake", "idle", 4.0, 0.0, 0.0, 0.0))
    # A turn too small to tell is walking forward; a long drift is veering.
    assert texts(ClipFacts("crab", "turn", 0.5, 1.2, 1.2, -6.0)) == texts(
        ClipFacts("crab", "walk", 0.5, 1.2, 1.2, 0.0))
    assert "a crab walks forward, veering to the right" in texts(
        ClipFacts("crab", "walk", 10.0, 1.2, 1.2, -35.0))
    assert "a bird walks forward, speeding up, veering to the left" in texts(
        ClipFacts("bird", "speed", 10.0, 0.7, 1.4, 31.0))
    assert all("veer" not in t for t in texts(ClipFacts("bird", "walk", 4, 1, 1, 29.0)))


def test_fixed_zoo_manifest_records_the_facts(tmp_path):
    rows = write_zoo(tmp_path, species=["biped", "snake"], clips=4, frames=40, seed=2)
    assert set(MOTION_COLUMNS) <= set(rows[0])
    clips = captioned_clips(tmp_path / "manifest.tsv")
    assert len(clips) == len(rows) and {c.dataset for c in clips} == {"zoo"}
    assert [c.split for c in clips] == [r["split"] for r in rows]
    for row, clip in zip(rows, clips):
        words = " ".join(c.text for c in clip.captions)
        if row["kind"] == "turn" and abs(float(row["turn_deg"])) >= UNTOLD_TURN:
            side = "left" if float(row["turn_deg"]) > 0 else "right"
            assert side in words, words
        elif row["kind"] == "turn":  # too small to tell (a 40-frame snake)
            assert "forward" in words and "left" not in words and "right" not in words
        if row["kind"] == "speed":
            faster = float(row["speed_end"]) > float(row["speed_start"])
            assert ("speeding up" in words) == faster
    # Without the facts columns (an older zoo), the file name still tells
    # the kind, and the captions do not guess a side.
    turn = next(r for r in rows if r["kind"] == "turn")
    bare = {k: v for k, v in turn.items() if k not in MOTION_COLUMNS}
    assert zoo_clip_of_row(bare).turn is None
    words = texts(bare)
    assert words and all("left" not in t and "right" not in t for t in words)
    assert "turns" in " ".join(words)
    assert texts(turn["path"], dataset="zoo")  # species and kind from the name


# ------------------------------------------------------------- real data
def test_captioned_clips_of_the_shared_manifest(shared_data):
    clips = captioned_clips(shared_data / "manifest.tsv")
    count = collections.Counter((c.dataset, c.split) for c in clips)
    assert count == {("bandai", "train"): 130, ("bandai", "val"): 22,
                     ("bandai", "test"): 22, ("cmu", "train"): 6, ("cmu", "val"): 2,
                     ("cmu", "test"): 2, ("ccbase", "train"): 20, ("ccbase", "val"): 3,
                     ("ccbase", "test"): 3}
    assert all(Path(c.path).is_file() for c in clips)
    test = captioned_clips(shared_data / "manifest.tsv", split="test", count=2, seed=0)
    assert len(test) == 27 and all(len(c.captions) == 2 for c in test)
    # Held-out Bandai styles (giant, sad) have style words training never has.
    train_words = {w for c in clips if c.split == "train" for cap in c.captions
                   for w in cap.text.split()}
    assert "sadly" not in train_words and "giant" not in train_words
    assert isinstance(clips[0].captions[0], Caption)
