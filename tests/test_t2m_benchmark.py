"""benchmarks/t2m.py --quick (issue 19, item 8): zoo only, no shared data."""
from __future__ import annotations

import pytest

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import t2m  # noqa: E402


def test_probes_read_direction_speed_and_stillness():
    labels = ["walk", "walk-back", "walk-left", "walk-right", "run", "dash", "bow"]
    travels = [np.array(v) for v in ([0, 3], [0.2, -3], [1, 2], [-1, 2], [0, 5], [0, 9],
                                     [0, 0])]
    out = t2m.probes(labels, travels, [0.3, 0.3, 0.3, 0.3, 0.6, 0.9, 0.01])
    assert out["direction"] == (1.0, 4) and out["ordering"] and out["still"] == (1.0, 1)


def test_sideways_reads_travel_against_the_body_facing():
    """A zoo walk travels the way its hips face (a few degrees); its root
    velocity turned 60 degrees in the facing frame walks crabwise, and the
    probe reads 60 more; the forward actions' median goes in the probes."""
    from dataclasses import replace
    from satagraph.data.features import motion_to_features
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    from satagraph.transforms.canonical import canonicalize
    rig = [r for r in zoo_rigs(seed=1) if r.species == "quadruped"][0]
    feats = motion_to_features(canonicalize(generate_clip(rig, "walk", frames=90, seed=0),
                                            fps=30.0))
    walk = t2m.measure(feats, [], "walk", "zoo", "quadruped")
    c, s = np.cos(np.radians(60)), np.sin(np.radians(60))
    r = feats.r.copy()
    r[:, 1], r[:, 2] = c * feats.r[:, 1] + s * feats.r[:, 2], -s * feats.r[:, 1] + c * feats.r[:, 2]
    crab = t2m.measure(replace(feats, r=r), [], "walk", "zoo", "quadruped")
    assert walk.sideways < 8.0 and abs(crab.sideways - walk.sideways - 60.0) < 8.0
    out = t2m.probes(["walk", "bow", "run"], [walk.travel, crab.travel, crab.travel],
                     [0.3, 0.0, 0.6], [walk.sideways, crab.sideways, crab.sideways])
    assert out["sideways"] == (np.median([walk.sideways, crab.sideways]), 2)


def test_turn_reads_how_fast_the_facing_turns():
    """A zoo walk keeps its facing (a few degrees a second); the same root
    features with 20 degrees a second of yaw rate added read exactly 20
    more; the forward actions' median magnitude goes in the probes."""
    from dataclasses import replace
    from satagraph.data.features import motion_to_features
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    from satagraph.transforms.canonical import canonicalize
    rig = [r for r in zoo_rigs(seed=1) if r.species == "biped"][0]
    feats = motion_to_features(canonicalize(generate_clip(rig, "walk", frames=90, seed=0),
                                            fps=30.0))
    walk = t2m.measure(feats, [], "walk", "zoo", "biped")
    r = feats.r.copy()
    r[:, 0] += np.radians(20.0)
    turned = t2m.measure(replace(feats, r=r), [], "walk", "zoo", "biped")
    assert abs(walk.turn) < 5.0
    assert turned.turn - walk.turn == pytest.approx(20.0, abs=1e-6)
    out = t2m.probes(["walk", "bow", "run"], [walk.travel] * 3, [0.3, 0.0, 0.6],
                     turns=[walk.turn, turned.turn, -turned.turn])
    assert out["turn"] == (np.median([abs(walk.turn), abs(turned.turn)]), 2)
    assert out["turn_left"] == np.mean([walk.turn > 0, -turned.turn > 0])
    assert t2m.probe_cell(out).endswith(
        f"; turn {out['turn'][0]:.1f} deg/s (n=2, {out['turn_left']:.0%} left)")



def test_pace_drift_reads_a_walk_that_speeds_up():
    """A zoo walk keeps its pace; the same root features whose speed ramps
    from 0.7 to 1.3 times along the clip read about +0.5 (the last third's
    mean over the first's); the forward actions' signed median goes in the
    probes and in the probe cell."""
    from dataclasses import replace
    from satagraph.data.features import motion_to_features
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    from satagraph.transforms.canonical import canonicalize
    rig = [r for r in zoo_rigs(seed=1) if r.species == "quadruped"][0]
    feats = motion_to_features(canonicalize(generate_clip(rig, "walk", frames=90, seed=0),
                                            fps=30.0))
    walk = t2m.measure(feats, [], "walk", "zoo", "quadruped")
    r = feats.r.copy()
    r[:, 1:3] *= np.linspace(0.7, 1.3, len(r))[:, None]  # horizontal root velocity
    faster = t2m.measure(replace(feats, r=r), [], "walk", "zoo", "quadruped")
    assert abs(walk.drift) < 0.1 and faster.drift - walk.drift == pytest.approx(0.5, abs=0.08)
    out = t2m.probes(["walk", "bow", "run"], [walk.travel] * 3, [0.3, 0.0, 0.6],
                     drifts=[walk.drift, -0.9, faster.drift])
    assert out["drift"] == (np.median([walk.drift, faster.drift]), 2)
    assert t2m.probe_cell(out).endswith(f"pace drift {out['drift'][0]:+.0%} (n=2)")

@pytest.mark.slow
def test_quick_table_has_rows_and_real_beats_shuffled(tmp_path):
    torch.set_num_threads(1)
    assert t2m.main(["--quick", "--out", str(tmp_path), "--save", str(tmp_path)]) == 0
    result = json.loads((tmp_path / "t2m_quick.json").read_text())
    rows = {r["row"]: r for r in result["rows"] if r["group"] == "zoo"}
    assert {"real", "shuffled captions", "retrieval (own rig)"} <= set(rows)
    assert result["facts"]["pool_size"] == 32
    assert rows["real"]["R@3"][0] > rows["shuffled captions"]["R@3"][0] + 0.3
    text = (tmp_path / "t2m_quick.md").read_text()
    assert "| zoo | real |" in text and "Action accuracy per asked action, zoo" in text
    by_label = rows["real"]["action_by_label"]
    n = sum(c["n"] for c in by_label.values())
    share, half = rows["real"]["action"]
    assert share == pytest.approx(sum(c["n"] * c["accuracy"] for c in by_label.values()) / n)
    assert half == pytest.approx(1.96 * (share * (1 - share) / n) ** 0.5)


def test_recogniser_reports_accuracy_per_asked_action():
    """A recogniser that always answers ``walk``: right on every walk, wrong
    on every run (recognised as a walk instead), and labels it does not know
    are left out."""
    model = t2m.Recogniser(2, ["run", "walk"])
    with torch.no_grad():
        for p in model.parameters():
            p.zero_()
        model.net[-1].bias.copy_(torch.tensor([0.0, 1.0]))
    descs = [np.zeros(2)] * 5
    labels = ["walk", "walk", "run", "run", "bow"]
    assert model.accuracy(descs, labels) == 0.5
    share, half = model.accuracy_interval(descs, labels)
    assert share == 0.5 and half == pytest.approx(1.96 * 0.5 / 2)  # 4 known motions
    assert model.by_label(descs, labels) == {
        "run": {"n": 2, "accuracy": 0.0, "instead": "walk"},
        "walk": {"n": 2, "accuracy": 1.0, "instead": None}}
    rows = [{"group": "zoo", "row": "real", "action_by_label": model.by_label(descs, labels)}]
    assert "| run | 2 | 0.00 (walk) |" in t2m.action_table(rows)


def test_validation_prompts_and_sampling_settings():
    """``--prompts val`` draws the zoo's validation seeds (other rigs than the
    test prompts'); the sampling flags become GenerationSettings."""
    val = t2m.zoo_items("val", 3)
    test = t2m.zoo_items("test", 3)
    assert all(not np.allclose(a.desc, b.desc) for a, b in zip(val, test))
    unset = dict(guidance=None, residual_guidance=None, temperature=None, topk_ratio=None,
                 residual_temperature=None, layers=None, smooth=None)
    settings = t2m.sampling(argparse.Namespace(**dict(unset, guidance=2.5, temperature=0.7)))
    assert (settings.guidance, settings.temperature, settings.steps) == (2.5, 0.7, 10)
    assert t2m.sampling(argparse.Namespace(**unset)) is None


def test_bandai_validation_takes_are_neither_learnt_nor_test_prompts(shared_data, monkeypatch):
    """``--bandai-val`` scores Bandai's validation takes: none is among the
    files the evaluator learns from or the test prompts, and the evaluator
    learns from the same files as the test table's."""
    monkeypatch.setattr(t2m, "MANIFEST", shared_data / "manifest.tsv")  # SATAGRAPH_DATA's
    split = t2m.file_splits(t2m.captioned_files())
    paths = {role: {f.path for f in files} for role, files in split.items()}
    assert paths["val"] and all("bandai/" in p for p in paths["val"])
    for role in ("fit", "seen", "test"):
        assert not paths["val"] & paths[role], role
    assert not paths["fit"] & paths["seen"] and not paths["test"] & paths["fit"]
    assert {f.dataset for f in split["fit"]} == {"bandai", "cmu", "ccbase"}
    with pytest.raises(SystemExit):
        t2m.main(["--bandai-val"])  # with the test prompts: refused before any work


def test_a_full_run_without_the_real_files_is_refused_before_any_work(tmp_path, monkeypatch,
                                                                      capsys):
    # a clone without ../shared ran the full evaluation on the zoo alone and
    # wrote t2m.md without its Bandai groups and real-rig probes, saying nothing
    monkeypatch.setattr(t2m, "MANIFEST", tmp_path / "shared" / "data" / "manifest.tsv")

    def evaluate(*args, **kwargs):
        raise AssertionError("evaluated without the real files")
    monkeypatch.setattr(t2m, "evaluate", evaluate)
    with pytest.raises(SystemExit) as exit_:
        t2m.main(["--out", str(tmp_path), "--save", str(tmp_path)])
    assert exit_.value.code == 2
    assert f"{tmp_path / 'shared' / 'data'}: no manifest.tsv there" in capsys.readouterr().err
    assert not list(tmp_path.glob("t2m*"))


def _captioned_folder(root: Path, splits: dict, captions: bool = True) -> Path:
    """A folder of 60-frame zoo biped walks (one 96-frame window each) with a
    manifest of :obj:`splits` (file stem -> split) and, with
    :obj:`captions`, a HumanML3D sidecar beside each."""
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    from satagraph.io import write_bvh
    rig = [r for r in zoo_rigs(seed=1) if r.species == "biped"][0]
    folder = root / "mine"
    folder.mkdir(parents=True)
    for i, stem in enumerate(splits):
        write_bvh(generate_clip(rig, "walk", frames=60, seed=i), folder / f"{stem}.bvh")
        if captions:
            (folder / f"{stem}.txt").write_text(f"a person walks {stem}#x#0.0#0.0\n")
    (folder / "manifest.tsv").write_text(
        "path\tsplit\n" + "".join(f"{s}.bvh\t{v}\n" for s, v in splits.items()))
    return folder


def _refused(tmp_path, monkeypatch, capsys, argv) -> str:
    """The one error line of a --data run refused before any evaluation."""
    def evaluate(*args, **kwargs):
        raise AssertionError("evaluated a folder it should refuse")
    monkeypatch.setattr(t2m, "evaluate", evaluate)
    with pytest.raises(SystemExit) as exit_:
        t2m.main(argv + ["--out", str(tmp_path), "--save", str(tmp_path)])
    assert exit_.value.code == 2 and not list(tmp_path.glob("t2m*"))
    return capsys.readouterr().err.strip().splitlines()[-1]


SPLITS = {"a": "train", "b": "train", "c": "test", "d": "test", "e": "test", "f": "test"}


def test_data_scores_a_users_held_out_clips_with_the_pool_size_stated(tmp_path, monkeypatch):
    # a user who fine-tuned on their own captioned folder had no way to score
    # it: t2m.py took no --data ("unrecognized arguments: --data")
    folder = _captioned_folder(tmp_path, SPLITS)
    zoo_items = t2m.zoo_items
    monkeypatch.setattr(t2m, "zoo_items", lambda stream, count, seed=0, keep=False:
                        zoo_items(stream, 16, seed, keep))
    out = tmp_path / "out"
    assert t2m.main(["--quick", "--data", str(folder), "--pool-size", "4", "--steps", "5",
                     "--out", str(out), "--save", str(out)]) == 0
    result = json.loads((out / "t2m_quick_data.json").read_text())
    facts = result["facts"]
    assert (facts["pool_size"], facts["split"], facts["test_items"]) == (4, "test", 4)
    assert (facts["fit_files"], facts["fit_windows"], facts["train_items"]) == (2, 2, 18)
    assert {r["group"] for r in result["rows"]} == {"mine (test)"}  # no zoo group
    real = next(r for r in result["rows"] if r["row"] == "real")
    assert real["n"] == 4 and "R@3" in real and real["action"] is None
    text = (out / "t2m_quick_data.md").read_text()
    assert (f"Scored on {folder}, split 'test': 4 captioned windows of at most 96 frames "
            "from 4 files (0 more without a caption left out); the evaluator learnt from 16 "
            "zoo training clips and 2 windows of 2 captioned files of the 'train' split; "
            "R@1-3 in pools of 4;") in text
    assert not (out / "t2m_quick.md").exists()  # the project's quick table is left alone


def test_data_refuses_a_split_without_captions(tmp_path, monkeypatch, capsys):
    folder = _captioned_folder(tmp_path, SPLITS, captions=False)
    line = _refused(tmp_path, monkeypatch, capsys, ["--data", str(folder), "--pool-size", "4"])
    assert line.endswith(f"error: {folder}: none of the 4 files of the 'test' split has a "
                         "caption (a sidecar CLIP.txt of HumanML3D lines caption#tokens#from#to, "
                         "or CLIP.json, beside CLIP.bvh)")


def test_data_refuses_fewer_held_out_windows_than_the_pool(tmp_path, monkeypatch, capsys):
    folder = _captioned_folder(tmp_path, SPLITS)
    line = _refused(tmp_path, monkeypatch, capsys, ["--data", str(folder)])
    assert line.endswith(f"error: {folder}: 4 captioned windows of 96 frames in the 'test' "
                         "split (4 files), fewer than the pool size 32 R-precision ranks each "
                         "caption in: hold out more clips or pass --pool-size 4 or less")
    two = _captioned_folder(tmp_path / "two", {"a": "train", "c": "test", "d": "test"})
    line = _refused(tmp_path, monkeypatch, capsys, ["--data", str(two), "--pool-size", "4"])
    assert line.endswith("fewer than the pool size 4 R-precision ranks each caption in: hold "
                         "out more clips (4 windows at least)")  # not --pool-size 2 or less


def test_data_refuses_a_rig_the_evaluator_cannot_read(tmp_path, monkeypatch, capsys):
    """A rope of three joints has no limb the descriptor reads: scored, every
    motion of it would look alike to the evaluator."""
    folder = _captioned_folder(tmp_path, SPLITS)
    rope = "".join(f"JOINT j{i}\n{{\nOFFSET 0 10 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n"
                   for i in range(2))
    frames = "".join(f"{i * 0.5} 90 0 {i} 0 0 0 {i} 0 0 0 {i}\n" for i in range(40))
    (folder / "rope.bvh").write_text(
        "HIERARCHY\nROOT r\n{\nOFFSET 0 0 0\nCHANNELS 6 Xposition Yposition Zposition "
        "Zrotation Xrotation Yrotation\n" + rope + "End Site\n{\nOFFSET 0 10 0\n}\n"
        + "}\n" * 3 + f"MOTION\nFrames: 40\nFrame Time: 0.0333333\n{frames}")
    (folder / "rope.txt").write_text("a rope swings#x#0.0#0.0\n")
    with open(folder / "manifest.tsv", "a") as f:
        f.write("rope.bvh\ttest\n")
    line = _refused(tmp_path, monkeypatch, capsys, ["--data", str(folder), "--pool-size", "4"])
    assert line.endswith(f"error: {folder / 'rope.bvh'}: the evaluator finds no limb on its "
                         "rig (3 joints; it reads motion by the ends of the legs and arms its "
                         "joint names show, see satagraph tags), so it cannot score it: leave "
                         "it out or name its joints")



def test_skeleton_probes_read_whether_the_limbs_come_down(monkeypatch):
    """``lands`` per skeleton: a generator that gives back the target's own
    walk for every prompt reads 1.00 over the six travelling prompts; one
    that gives it back with the forelegs swung up (the forepaws never
    within 5 % of the height of the floor) reads 0.00; the cell says so."""
    from tests.pipelines.test_quality import _forelegs_up, _walk
    walk = _walk("quadruped")
    for given, down in ((walk, 1.0), (_forelegs_up(walk), 0.0)):
        monkeypatch.setattr(t2m, "generate_on", lambda *args, given=given: given)
        rows = t2m.skeleton_probes(None, {"zoo quadruped": ("a quadruped", walk)}, seeds=1)
        assert rows[0]["probes"]["lands"] == (pytest.approx(down), 6)
        assert f"down {down:.2f} (n=6)" in t2m.probe_cell(rows[0]["probes"])
