"""Helpers of benchmarks/throughput.py, scaling.py and compare.py (fast: no
training or timing runs)."""
from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import compare  # noqa: E402
import scaling  # noqa: E402
import throughput  # noqa: E402
from satagraph.experiment.sweep import SweepRow  # noqa: E402


def test_synthetic_tree_batch():
    feats = scaling.synthetic_features(30, 8, 2)
    batch = scaling.batch_of(feats, 8)
    assert batch.clip_num_joints.tolist() == [30, 30]
    assert int(batch.root.shape[0]) == 16
    parents = scaling.synthetic_motion(30, 4).skeleton.parents
    assert parents[0] == -1 and all(0 <= p < j for j, p in enumerate(parents) if j)


def test_tiled_motion_and_replace_row():
    motion = scaling.synthetic_motion(5, 10)
    tiled = throughput.tiled_motion(motion, 3)
    assert tiled.num_frames == 30
    np.testing.assert_allclose(tiled.rotations[10:20], motion.rotations)
    rows = [{"model": "a", "device": "cpu", "v": 1}, {"model": "b", "device": "cpu"}]
    out = throughput.replace_row(rows, {"model": "a", "device": "cpu", "v": 2},
                                 ("model", "device"))
    assert len(out) == 2 and out[-1]["v"] == 2


def test_scaling_table_ratio():
    rows = [dict(model=m, input={"kind": "synthetic"}, joints=[20, 20], frames=32,
                 ms_per_frame=t, mb_per_frame=1.0) for m, t in (("SATA", 2.0),
                                                                ("padded RVQ", 5.0))]
    text = scaling.table(rows)
    assert "| 2.50 | 1.00 |" in text


def test_scaling_every_frame_padded_runs_each_clip_on_the_largest_rig():
    feats = [scaling.synthetic_features(j, 8, 1)[0] for j in (12, 30, 20)]
    padded = scaling.batch_of(scaling.padded_to_largest(feats), 8)
    assert padded.clip_num_joints.tolist() == [30, 30, 30]
    assert int(padded.root.shape[0]) == int(scaling.batch_of(feats, 8).root.shape[0])
    rows = [dict(model=m, input={"kind": "mixed"}, joints=[27, 26, 141], frames=48,
                 ms_per_frame=t, mb_per_frame=1.0)
            for m, t in (("SATA", 2.0), ("padded RVQ", 1.0),
                         ("SATA, every frame padded", 4.4))]
    text = scaling.table(rows)
    assert "time SATA, every frame padded / SATA" in text
    assert text.splitlines()[-1].endswith("| 0.50 | 1.00 | 2.20 |")


def test_compare_tables():
    metrics = {n: 0.1 for n in ("JR", "RT", "JP", "FS", "GP")}
    row = SweepRow("SATA-VAE", "sata_vae", params=10, steps=3,
                   metrics={"dog": dict(metrics, clips=2), "all": dict(metrics, clips=2),
                            "zero-shot": dict(metrics, clips=4)},
                   retarget={"internal": {"test": 1.5, "test:dog": 1.5, "zero-shot": 2.0},
                             "cross": {"test": 3.0, "test:dog": 3.0, "zero-shot": 4.0}})
    t1 = compare.table1([row])
    assert "| dog | SATA-VAE | 2 |" in t1 and "| zero-shot | SATA-VAE | 4 |" in t1
    t3 = compare.table3([row]).splitlines()
    assert t3[0] == "| model | setting | dog | all (test) | zero-shot |"
    assert t3[2:] == ["| SATA-VAE | internal | 1.500 | 1.500 | 2.000 |",
                      "| SATA-VAE | cross | 3.000 | 3.000 | 4.000 |"]


def test_matmul_peak_is_best_over_sizes(monkeypatch):
    import torch
    cpu = torch.device("cpu")
    assert throughput._matmul_rate(cpu, 64, 1) > 0
    rates = {32: 5.0, 64: 9.0, 128: 7.0}
    monkeypatch.setattr(throughput, "_matmul_rate", lambda dev, size, rep: rates[size])
    assert throughput.matmul_peak(cpu, (32, 64, 128), repeats=1) == 9.0


def test_compile_table_reports_speedup_against_eager():
    import compile_step
    rows = [dict(variant="eager", first_s=2.0, best_s=1.0, median_s=1.1, first_loss=3.0,
                 other_first_s=2.5, scatter_ops=0),
            dict(variant="compile", first_s=40.0, best_s=0.8, median_s=0.9,
                 first_loss=3.0 + 1e-6, other_first_s=30.0, scatter_ops=0),
            dict(variant="torch-scatter", first_s=2.0, best_s=1.1, median_s=1.1,
                 first_loss=3.0, other_first_s=2.5, scatter_ops=7)]
    lines = compile_step.table(rows).splitlines()
    assert "| 1.00x |" in lines[2] and "| 1.25x |" in lines[3] and "+1.00e-06" in lines[3]
    assert lines[4].startswith("| torch-scatter |") and lines[4].endswith("| 0.91x | +0.00e+00 | 2.50 | 7 |")
    assert set(compile_step.VARIANTS) == {"eager", "compile", "compile-dynamic", "torch-scatter"}


def test_pyg_scatter_switch_is_restored_and_counted_ops_are_real():
    """The torch-scatter variant flips PyG's call-time switch only inside
    its block (and refuses when torch-scatter is missing); the op counter
    counts the operators a step really calls."""
    import compile_step
    import torch
    import torch_geometric.typing as pyg_typing
    before = pyg_typing.WITH_TORCH_SCATTER
    with compile_step.pyg_scatter(False):
        assert pyg_typing.WITH_TORCH_SCATTER is False
    assert pyg_typing.WITH_TORCH_SCATTER == before
    if not compile_step.SCATTER_INSTALLED:
        with pytest.raises(RuntimeError, match="torch-scatter is not installed"):
            with compile_step.pyg_scatter(True):
                pass
    index = torch.tensor([0, 1, 1])

    def step():
        for _ in range(3):
            torch.zeros(2).scatter_add_(0, index, torch.ones(3))
    assert compile_step.op_calls(step, "aten::scatter_add_") == 3
    assert compile_step.op_calls(step, "torch_scatter::") == 0


def test_retarget_sanity_shuffled_control_and_conditioned_summary():
    """The shuffled control scores each retarget against the next source
    clip: retargets that copy their own source score 1 paired and about 0
    shuffled; the summary's last column averages the trained rows over the
    clips whose reconstruction is in step only."""
    import retarget_sanity as rs
    rng = np.random.default_rng(0)
    sources = [{limb: np.cumsum(rng.normal(size=200)) for limb in rs.LIMBS} for _ in range(4)]
    outs = {"bandai/walk.bvh": [{k: v.copy() for k, v in s.items()} for s in sources]}
    control = rs.shuffled(sources, outs)[(rs.SHUFFLED, "bandai/walk.bvh")]
    assert len(control) == 4 and max(abs(c) for c in control) < 0.25
    assert rs.shuffled(sources[:1], {"t": outs["bandai/walk.bvh"][:1]}) == {}
    means = {(rs.TRAINED, "bandai/walk.bvh"): [0.8, 0.6, -0.2, 0.0],
             (rs.RECONSTRUCTION, "dog"): [0.9, 0.5, 0.1, 0.3],
             (rs.SHUFFLED, "bandai/walk.bvh"): control}
    lines = rs.summary(means).splitlines()
    trained = next(line for line in lines if line.startswith(f"| {rs.TRAINED} |"))
    assert trained.endswith("| +0.30 | -0.20 | +0.80 | 2 | +0.70 (2 clips) |")
    shuffled_row = next(line for line in lines if line.startswith(f"| {rs.SHUFFLED} |"))
    assert shuffled_row.endswith("| - |")


def test_op_counter_sees_torch_scatter_kernels():
    """Where torch-scatter is installed, the counter sees its operators (so
    a zero in the table means the step never calls them)."""
    torch_scatter = pytest.importorskip("torch_scatter",
                                        reason="torch-scatter not installed (make scatter)")
    import compile_step
    import torch
    from torch_geometric.utils import softmax
    src, ptr = torch.randn(6, 4, requires_grad=True), torch.tensor([0, 2, 6])
    assert compile_step.op_calls(lambda: torch_scatter.segment_csr(src, ptr, reduce="max"),
                                 "torch_scatter::") == 1
    with compile_step.pyg_scatter(True):
        assert compile_step.op_calls(lambda: softmax(src, ptr=ptr), "torch_scatter::") >= 1
    with compile_step.pyg_scatter(False):
        assert compile_step.op_calls(lambda: softmax(src, ptr=ptr), "torch_scatter::") == 0


def test_semantic_alignment_bodyplans_without_data():
    import semantic_alignment as sa
    from satagraph.semantics import OfflineTextEncoder, describe_joints
    skels, evidence, noise = sa.bodyplan_skeletons({})
    table = sa.build_bodyplan_table(noise)
    refs = {k: s for k, s in skels.items() if k in sa.BIRDS + sa.ARTHROPODS
            + ("quadruped_longtail",)}
    for rows in table.values():
        sa._check_table(refs, [(c, {k: v for k, v in cols.items() if k in refs})
                               for c, cols in rows])
    assert set(table["wings to arms"][0][1]["bird_bip01_noise"]) == {
        noise["Bip01_L_Clavicle"]}
    enc = OfflineTextEncoder()
    legs = [r for r in table["legs to legs"] if r[0].endswith(("leg upper", "leg lower"))]
    for fn, want in ((lambda k: describe_joints(skels[k], evidence=evidence[k]), 1.0),
                     (lambda k: sa.raw_name_texts(skels[k]), 0.5)):
        embs = {k: enc.encode(fn(k)) for k in ("crab", "quadruped_longtail")}
        c, t, _ = sa.score_pair("crab", "quadruped_longtail", skels, embs, legs)
        assert t == 20 and (c == t if want == 1.0 else c < want * t)


def test_semantic_alignment_zoo_leg_pairs_in_order():
    # zoo arthropods read from a dialect file: first pair front, last hind
    import semantic_alignment as sa
    from satagraph.semantics import OfflineTextEncoder, describe_joints
    skels, evidence, noise = sa.bodyplan_skeletons({})
    rows = sa.build_bodyplan_table(noise)["leg pairs front to back"]
    enc = OfflineTextEncoder()
    embs = {k: enc.encode(describe_joints(skels[k], evidence=evidence[k]))
            for k in sa.ZOO_ARTHROPODS + ("quadruped_longtail",)}
    for a in sa.ZOO_ARTHROPODS:
        c, t, misses = sa.score_pair(a, "quadruped_longtail", skels, embs, rows)
        assert t == 24 and c == t, misses


@pytest.mark.slow
def test_rig_reading_every_zoo_variant(tmp_path):
    # every zoo rig in all six up axes, in m, cm, inches and arbitrary units
    import rig_reading
    rows = rig_reading.zoo_rows(0, 40, tmp_path)
    assert {r["up_true"] for r in rows} == {"+X", "-X", "+Y", "-Y", "+Z", "-Z"}
    assert {r["species"] for r in rows} >= {"biped", "fowl", "crab", "spider", "longtail"}
    # jump clips included: a 40-frame jump's moving frames are mostly its
    # flight (experiments/PRETRAIN.md sections 6 and 8)
    assert any(r["kind"] == "jump" for r in rows)
    wrong = [r for r in rows if r["up_read"] != r["up_true"] and not r["flagged"]]
    assert not wrong, wrong
    assert all(r["units_ok"] for r in rows), [r for r in rows if not r["units_ok"]]


def test_rest_modes_table_counts_what_auto_changes():
    import rest_modes
    rows = [{"rest": "random", "file": 0.08, "first-frame": 0.04, "line only": 0.08,
             "auto": 0.04, "re-rested by auto": True},
            {"rest": "native", "file": 0.03, "first-frame": 0.05, "line only": 0.03,
             "auto": 0.03, "re-rested by auto": False}]
    text = rest_modes.table(rows)
    assert "| random | 1 | 8.0 | 4.0 | 8.0 | 4.0 | 100% | 1 / 0 |" in text
    assert "| native | 1 | 3.0 | 5.0 | 3.0 | 3.0 | 0% | 0 / 0 |" in text
    assert "| all (median; mean) | 2 |" in text


@pytest.mark.slow
def test_rest_modes_auto_is_the_file_rest_where_it_does_not_re_rest():
    """``auto`` reads designed rests as the file has them and re-rests
    lines and arbitrary poses on their mean standing pose, which is
    neither the file's rest nor the first frame's."""
    import rest_modes
    from satagraph.experiment.train import load_module
    rows = rest_modes.validation_rows(load_module("builtin").eval(), per_rest=1, frames=40)
    assert {r["rest"] for r in rows} == {"native", "apose", "flat", "crouched", "random",
                                          "frame", "axis"}
    for r in rows:
        if r["re-rested by auto"]:
            assert r["auto"] != pytest.approx(r["first-frame"], abs=1e-6), r
            assert r["auto"] != pytest.approx(r["file"], abs=1e-6), r
        else:
            assert r["auto"] == pytest.approx(r["file"], abs=1e-9), r
    assert all(r["re-rested by auto"] for r in rows if r["rest"] in ("random", "axis"))


def test_pretrained_pose_error_leaves_out_the_root_path(tiny_motion):
    """``joint_error(..., relative=True)`` is the pose's error alone: a
    whole motion shifted by a constant has no pose error and a JP of the
    shift over the height; the reconstruction table prints both."""
    import pretrained
    shift = tiny_motion.translations.copy()
    shift[:, 0] += np.array([0.3, 0.0, 0.0])
    moved = tiny_motion.with_(translations=shift)
    height = tiny_motion.height()
    assert pretrained.joint_error(tiny_motion, moved) == pytest.approx(0.3 / height)
    assert pretrained.joint_error(tiny_motion, moved, relative=True) == pytest.approx(0.0, abs=1e-9)
    row = dict(group="real, never trained", case="dog/x.bvh", jp=0.58, grounded_jp=0.58,
               pose=0.41, local=0.12, height=0.46, steps=0.5, stride=0.75, slide=0.37,
               source_slide=0.07)
    text = pretrained.table({"retarget": [], "reconstruction": [row]}, "builtin", 1.0)
    assert ("| real, never trained | dog/x.bvh | 58.0 | no | 58.0 | 41.0 | 12.0 | +0.50 "
            "| 0.75 | 0.37 (0.07) |") in text
    del row["local"], row["stride"]  # results measured before the columns
    text = pretrained.table({"retarget": [], "reconstruction": [row]}, "builtin", 1.0)
    assert "| 58.0 | 41.0 | - | +0.50 | - |" in text


def test_pretrained_reconstruction_rows_load_the_kind_they_name(monkeypatch):
    """Each held-out zoo row reads a clip of the species, kind and plan it
    names: the loaders' lambdas bound the kind late, and "quadruped trot"
    reconstructed a quadruped walk."""
    import pretrained
    asked = []
    monkeypatch.setattr(pretrained, "zoo_clip",
                        lambda *args: asked.append(args) or (None, ""))
    for group, case, load in pretrained.recon_cases():
        if group == "held-out zoo":
            load()
            species, kind, holdout = asked[-1]
            named, kind_named = case.split()[:2]
            assert (named.split("/")[0], kind_named) == (species, kind), case
            assert holdout == case.endswith("(unseen plan)"), (case, asked[-1])
    assert ("quadruped", "trot", False) in asked


def test_pretrained_heading_free_pose_error_leaves_out_the_facing_drift(tiny_motion):
    """``joint_error(..., heading=True)``: an output whose whole body turns
    about +Y by a growing angle (a drifting decoded facing) has a root-
    relative error but no heading-free one; a changed pose keeps its error."""
    import pretrained
    from satagraph.transforms.canonical import canonicalize
    motion = canonicalize(tiny_motion, fps=30.0)
    pos = motion.global_positions()
    yaw = np.linspace(0.0, 0.8, motion.num_frames)[:, None]
    rel = pos - pos[:, :1]
    turned = rel.copy()
    turned[..., 0] = np.cos(yaw) * rel[..., 0] + np.sin(yaw) * rel[..., 2]
    turned[..., 2] = np.cos(yaw) * rel[..., 2] - np.sin(yaw) * rel[..., 0]
    np.testing.assert_allclose(pretrained.turned_onto(rel, turned), rel, atol=1e-9)
    rotations = motion.rotations.copy()
    c, s = np.cos(yaw[:, 0]), np.sin(yaw[:, 0])
    spin = np.zeros((motion.num_frames, 3, 3))
    spin[:, 0, 0], spin[:, 0, 2], spin[:, 1, 1], spin[:, 2, 0], spin[:, 2, 2] = c, s, 1, -s, c
    rotations[:, 0] = spin @ rotations[:, 0]
    drifted = motion.with_(rotations=rotations)
    assert pretrained.joint_error(motion, drifted, relative=True) > 0.01
    assert pretrained.joint_error(motion, drifted, heading=True) == pytest.approx(0.0, abs=1e-9)
    bent = motion.rotations.copy()
    bent[:, 1:] = np.swapaxes(bent[:, 1:], -1, -2)  # every joint's rotation inverted
    changed = motion.with_(rotations=bent)
    assert pretrained.joint_error(motion, changed, heading=True) > 0.01


def test_pretrained_retarget_rows_give_the_lands_column():
    """The retarget table gives ``lands`` beside posture (a human -> dog
    retarget whose forepaws never come down reads 0.00 where posture reads
    0.80), "-" in results measured before it; pretrained_val's retarget
    cell gives the lowest lands of a pair."""
    import pretrained
    import pretrained_val
    row = dict(group="real, never trained", case="bandai human -> dog", source="a.bvh",
               target="dog/b.bvh", steps=0.88, travel=0.85, stride=0.56, posture=0.8,
               lands=0.0, ground=0.018, decoder_ground=-0.18, upright=1.0,
               source_upright=1.0, slide=0.5, source_slide=0.11, hover=0.026,
               source_hover=0.0, sideways=4.0)
    header = "| posture (diagnostic) | lands (diagnostic) | ground, % height (<= 3) |"
    text = pretrained.table({"retarget": [row], "reconstruction": []}, "builtin", 1.0)
    assert header in text
    assert "| +0.88 | 0.85 | 0.56 | 0.80 | 0.00 | +1.8 | -18.0 |" in text
    del row["lands"]
    text = pretrained.table({"retarget": [row], "reconstruction": []}, "builtin", 1.0)
    assert "| 0.56 | 0.80 | - | +1.8 |" in text
    rt = {"a.ckpt": {"bandai -> dog": dict(n=2, steps=0.9, travel=0.88, travel_ok=0.5,
                                           posture=0.8, lands=0.25)}}
    s = pretrained_val.summarise([dict(jp=0.1, pose=0.05, local=0.02, drift=None)])
    text = pretrained_val.table({"a.ckpt": {"zoo biped": s}}, 1.0, rt)
    assert "| bandai -> dog | 2 | +0.90, 0.88 (50%), posture 0.80, lands 0.25 |" in text


def test_pretrained_val_summary_gives_drift_only_where_most_clips_have_one():
    import pretrained_val
    clips = [dict(jp=0.1, pose=0.05, local=0.02, drift=10.0),
             dict(jp=0.3, pose=0.07, local=0.04, drift=None),
             dict(jp=0.2, pose=0.06, local=0.03, drift=20.0)]
    s = pretrained_val.summarise(clips)
    assert s["median"] == pytest.approx(0.2) and s["mean"] == pytest.approx(0.2)
    assert s["jp_clips"] == pytest.approx([0.1, 0.3, 0.2])  # per clip, in clip order
    assert s["pose_clips"] == pytest.approx([0.05, 0.07, 0.06])
    assert s["pose"] == pytest.approx(0.06) and s["drift"] == pytest.approx(15.0)
    assert pretrained_val.summarise(clips[1:2] + clips[:1])["drift"] is None
    text = pretrained_val.table({"a.ckpt": {"zoo biped": s, "dog (not test)": s}}, 1.0)
    assert "| zoo biped | 3 | 20.0 (20.0) |" in text
    assert "| dog (not test) | 3 | 20.0 (20.0), pose 6.0 (3.0), drift 15 |" in text
    rt = {"a.ckpt": {"zoo biped -> bird": dict(n=2, steps=0.935, travel=0.88, travel_ok=0.5)}}
    text = pretrained_val.table({"a.ckpt": {"zoo biped": s}}, 1.0, rt)
    assert "| zoo biped -> bird | 2 | +0.94, 0.88 (50%) |" in text
    strides = [dict(c, stride=v) for c, v in zip(clips, (0.7, None, 0.8))]
    s = pretrained_val.summarise(strides)
    assert s["stride"] == pytest.approx(0.75)
    rt["a.ckpt"]["zoo biped -> bird"]["stride"] = 0.66
    text = pretrained_val.table({"a.ckpt": {"zoo biped": s}}, 1.0, rt)
    assert "| zoo biped | 3 | 20.0 (20.0), stride 0.75 |" in text
    assert "| zoo biped -> bird | 2 | +0.94, 0.88 (50%), stride 0.66 |" in text


def test_t2m_gait_reads_a_real_walk_as_a_straight_gait():
    """benchmarks/t2m_gait.py's row of a real zoo walk: it travels where it
    faces (heading gap about 0), its limbs swing at a walk's cadence, and
    the table gives every plan its cell."""
    import t2m_gait
    froude, swing, cadence, gap = t2m_gait.gait(t2m_gait.real_walk("biped", 911))
    assert 0.1 < froude < 1.0 and swing > 0.2 and 0.8 < cadence < 2.0
    assert abs(gap) < 2.0
    text = t2m_gait.walk_table({"real": {"biped": [froude, swing, cadence, gap]}}, ["biped"])
    assert text.splitlines()[0].endswith("heading gap, deg |")
    assert text.splitlines()[-1] == (f"| real | {froude:.2f} | {swing:.2f} | {cadence:.2f} "
                                     f"| {gap:+.1f} |")


def test_pretrained_rule_gives_section_31s_verdict_from_its_stored_table():
    """The rule computed from the stored JSON of PRETRAIN.md section 31
    fails both candidates on the parts that section reports, and a
    candidate equal to the base fails part 1 only."""
    import json
    import pretrained_rule
    root = Path(__file__).resolve().parents[1] / "benchmarks" / "results"
    results = json.loads((root / "pretrained_val_sitlie.json").read_text())
    fails, chosen = pretrained_rule.verdict(results)
    assert chosen is None
    lie = next(c for c in fails if "s43_lie" in c)
    starts = ("part 2: zoo biped JP 3.32 against 3.15", "part 2: zoo bird JP 3.41",
              "part 3: bandai -> dog travel in band 75% against 100%")
    assert len(fails[lie]) == 3 and all(map(str.startswith, fails[lie], starts))
    for part in ("reconstruction", "retarget"):
        results[part]["same"] = results[part]["builtin"]
    assert [f[:7] for f in pretrained_rule.failures(results, "same")] == ["part 1:"]


def test_pretrained_rule_posture_is_judged_against_the_base_below_its_floor():
    """Part 3's posture: below 0.9 fails where the base holds 0.9 or more;
    on a row where the base is below 0.9 already (the human -> quadruped
    rows since posture stopped being a correlation), only a fall of more
    than 0.03 below the base's fails."""
    import json
    import pretrained_rule
    root = Path(__file__).resolve().parents[1] / "benchmarks" / "results"
    results = json.loads((root / "pretrained_val_sitlie.json").read_text())
    for part in ("reconstruction", "retarget"):
        results[part] = {name: json.loads(json.dumps(results[part]["builtin"]))
                         for name in ("builtin", "same")}
    base, same = results["retarget"]["builtin"], results["retarget"]["same"]
    high, low = list(base)[:2]
    base[high]["posture"], same[high]["posture"] = 0.95, 0.89
    base[low]["posture"], same[low]["posture"] = 0.80, 0.78

    def posture_fails():
        return [f for f in pretrained_rule.failures(results, "same") if "posture" in f]
    assert posture_fails() == [f"part 3: {high} lowest posture 0.89 against 0.95"]
    same[high]["posture"], same[low]["posture"] = 0.91, 0.76
    assert posture_fails() == [f"part 3: {low} lowest posture 0.76 against 0.80"]


def test_pretrained_rule_carriage_aim_asks_the_quadruped_rows_postures_up() -> None:
    """``--aim carriage``: part 1 asks each of the two human -> quadruped
    rows' lowest posture 0.05 over the base's (the dog's error is kept
    in part 2 instead of being the aim), and the passing candidate whose
    smaller gain is largest is chosen."""
    import json
    import pretrained_rule
    root = Path(__file__).resolve().parents[1] / "benchmarks" / "results"
    results = json.loads((root / "pretrained_val_sitlie.json").read_text())
    for part in ("reconstruction", "retarget"):
        results[part] = {name: json.loads(json.dumps(results[part]["builtin"]))
                         for name in ("builtin", "small", "large")}
    ret = results["retarget"]
    for row in pretrained_rule.CARRIAGE_ROWS:
        ret["builtin"][row]["posture"] = 0.80
    ret["small"]["zoo biped -> quadruped"]["posture"] = 0.90
    ret["small"]["bandai -> dog"]["posture"] = 0.86
    ret["large"]["zoo biped -> quadruped"]["posture"] = 0.87
    ret["large"]["bandai -> dog"]["posture"] = 0.84
    fails, chosen = pretrained_rule.verdict(results, aim="carriage")
    assert fails == {"small": [], "large": ["part 1: bandai -> dog lowest posture 0.84 "
                                            "against 0.80"]} and chosen == "small"
    ret["large"]["bandai -> dog"]["posture"] = 0.88  # its smaller gain 0.07 > 0.06
    assert pretrained_rule.verdict(results, aim="carriage") == ({"small": [], "large": []},
                                                                "large")
    dog = results["reconstruction"]["large"][pretrained_rule.AIM]
    dog["median"] *= 1.2  # the dog is kept, not aimed at
    assert pretrained_rule.failures(results, "large", aim="carriage")[0].startswith(
        "part 2: dog (not test) JP")


def test_pretrained_rule_paired_compares_each_clip_with_itself():
    """``--paired``: a candidate 10 % worse on every clip fails part 2 even
    where the group's median does not move, one worse on a single clip of
    five passes; part 1 asks the dog's pose 5 % better clip by clip; the
    choice among passing candidates is by that ratio; results without
    per-clip values are refused by name."""
    import json
    import pretrained_rule
    root = Path(__file__).resolve().parents[1] / "benchmarks" / "results"
    results = json.loads((root / "pretrained_val_sitlie.json").read_text())
    for part in ("reconstruction", "retarget"):  # builtin and two copies of it
        results[part] = {name: json.loads(json.dumps(results[part]["builtin"]))
                         for name in ("builtin", "same", "other")}
    rec = results["reconstruction"]
    base, same = rec["builtin"], rec["same"]
    for group in pretrained_rule.KEPT:
        base[group]["jp_clips"] = [0.02, 0.03, 0.04, 0.05, 0.06]
        same[group]["jp_clips"] = [0.05, 0.033, 0.044, 0.055, 0.066]  # 10 % worse, the first 2.5x
        same[group]["median"] = base[group]["median"]  # unpaired medians equal
    base[pretrained_rule.AIM]["pose_clips"] = [0.2, 0.2, 0.2]
    same[pretrained_rule.AIM]["pose_clips"] = [0.1, 0.2, 0.2]  # one clip better: ratio 1
    fails = pretrained_rule.failures(results, "same", paired=True)
    assert fails[0] == "part 1: dog (not test) paired pose ratio +0.0% over 3 clips"
    part2 = [f for f in fails if f.startswith("part 2")]
    assert len(part2) == len(pretrained_rule.KEPT)
    assert part2[0] == "part 2: zoo biped paired JP ratio +10.0% over 5 clips"
    assert not [f for f in pretrained_rule.failures(results, "same") if f.startswith("part 2")]
    for group in pretrained_rule.KEPT:
        same[group]["jp_clips"] = [0.03, 0.03, 0.04, 0.05, 0.06]
        rec["other"][group]["jp_clips"] = same[group]["jp_clips"]
    same[pretrained_rule.AIM]["pose_clips"] = [0.1, 0.18, 0.19]
    rec["other"][pretrained_rule.AIM]["pose_clips"] = [0.3, 0.15, 0.15]
    assert pretrained_rule.failures(results, "same", paired=True) == []
    assert pretrained_rule.verdict(results, paired=True) == ({"same": [], "other": []}, "other")
    del base["zoo biped"]["jp_clips"]
    with pytest.raises(ValueError, match="lack per-clip jp_clips"):
        pretrained_rule.failures(results, "same", paired=True)


def test_pretrained_rule_human_aim_asks_bandai_better_and_keeps_the_dog():
    """``--aim human`` (section 58): part 1 asks Bandai's clips 5 % better
    clip by clip, the zoo groups stay in part 2 and the dog's pose error is
    kept there (paired, 1.05); the passing candidate with the lowest Bandai
    ratio is chosen; without ``--paired`` it is refused."""
    import json
    import pretrained_rule
    root = Path(__file__).resolve().parents[1] / "benchmarks" / "results"
    results = json.loads((root / "pretrained_val_s35.json").read_text())
    for part in ("reconstruction", "retarget"):
        results[part] = {name: json.loads(json.dumps(results[part]["builtin"]))
                         for name in ("builtin", "small", "large")}
    rec = results["reconstruction"]
    bandai = rec["builtin"][pretrained_rule.HUMAN]["jp_clips"]
    rec["small"][pretrained_rule.HUMAN]["jp_clips"] = [0.94 * v for v in bandai]
    rec["large"][pretrained_rule.HUMAN]["jp_clips"] = [0.80 * v for v in bandai]
    dog = rec["builtin"][pretrained_rule.AIM]["pose_clips"]
    rec["large"][pretrained_rule.AIM]["pose_clips"] = [1.06 * v for v in dog]
    fails, chosen = pretrained_rule.verdict(results, paired=True, aim="human")
    assert fails == {"small": [], "large": [
        f"part 2: dog (not test) paired pose ratio +6.0% over {len(dog)} clips"]}
    assert chosen == "small"
    rec["large"][pretrained_rule.AIM]["pose_clips"] = dog
    assert pretrained_rule.verdict(results, paired=True, aim="human")[1] == "large"
    assert pretrained_rule.failures(results, "builtin", paired=True, aim="human") == [
        f"part 1: bandai (val) paired JP ratio +0.0% over {len(bandai)} clips"]
    with pytest.raises(ValueError, match="add --paired"):
        pretrained_rule.failures(results, "small", aim="human")


def test_pretrained_rule_gives_section_35s_verdicts_from_its_stored_table():
    """Section 35's six epochs all fail the paired rule as registered; with
    the still-source rows' steps left out (the amendment that section
    states), epoch 20 alone passes and is chosen."""
    import json
    import pretrained_rule
    root = Path(__file__).resolve().parents[1] / "benchmarks" / "results"
    results = json.loads((root / "pretrained_val_s35.json").read_text())
    fails, chosen = pretrained_rule.verdict(results, paired=True)
    assert chosen is None and len(fails) == 6
    epoch20 = next(c for c in fails if "epoch_20" in c)
    assert fails[epoch20] == ["part 3: still source: dog -> bandai steps +0.02 against +0.06"]
    fails, chosen = pretrained_rule.verdict(results, paired=True, still_steps=False)
    assert chosen == epoch20 and [c for c, f in fails.items() if not f] == [epoch20]


def test_mirror_val_gives_section_37bs_verdict_from_its_stored_table():
    """Section 37b's stored figures fail on builtin-wide's spider alone; a
    group the run did not measure (Bandai with --no-bandai) is not judged,
    and builtin's mean counts the groups measured."""
    import json
    import mirror_val
    root = Path(__file__).resolve().parents[1] / "benchmarks" / "results"
    results = json.loads((root / "mirror_val_37b.json").read_text())
    ok, failures = mirror_val.verdict(results)
    assert not ok and len(failures) == 1 and failures[0].startswith("builtin-wide zoo spider: 1.117")
    results["builtin-wide"]["zoo spider"]["mirror"] = results["builtin-wide"]["zoo spider"]["single"]
    del results["builtin"]["bandai (val)"]
    assert mirror_val.verdict(results) == (True, [])
    results["builtin"]["zoo bird"]["mirror"] = [2 * v for v in results["builtin"]["zoo bird"]["single"]]
    ok, failures = mirror_val.verdict(results)
    assert failures == ["builtin zoo bird: 2.000 > 1.02", "builtin mean 1.167 > 0.95"]


def test_rest_val_gives_section_39s_verdict_from_its_stored_table():
    """Section 39's stored figures fail on the quadruped, Bandai and the
    mean; a candidate at 0.9 of the baseline on every clip passes."""
    import json
    import rest_val
    root = Path(__file__).resolve().parents[1] / "benchmarks" / "results"
    results = json.loads((root / "rest_val.json").read_text())
    ok, failures = rest_val.verdict(results)
    assert not ok and failures == ["builtin zoo quadruped: 1.022 > 1.02",
                                   "builtin bandai (val): 1.053 > 1.02", "mean 0.987 > 0.97"]
    for groups in results.values():
        for cell in groups.values():
            cell["two"] = [0.9 * v for v in cell["one"]]
    assert rest_val.verdict(results) == (True, [])


def test_unmirrored_val_gives_section_40s_verdict_from_its_stored_table():
    """Section 40's stored figures pass; a hexapod reading that moved at
    all, or a spider gaining less than 5 %, would fail it."""
    import json
    import unmirrored_val
    root = Path(__file__).resolve().parents[1] / "benchmarks" / "results"
    results = json.loads((root / "unmirrored_val.json").read_text())
    assert unmirrored_val.verdict(results) == (True, [])
    cells = results["builtin-wide"]
    cells["zoo hexapod"]["two"] = [v * 1.001 for v in cells["zoo hexapod"]["one"]]
    cells["zoo spider"]["two"] = [v * 0.97 for v in cells["zoo spider"]["one"]]
    ok, failures = unmirrored_val.verdict(results)
    assert not ok and sorted(failures) == ["zoo hexapod: 1.001 > 1.0",
                                           "zoo hexapod: a mirrored reading changed",
                                           "zoo spider: 0.970 > 0.95"]


def test_pipeline_writes_its_tables_to_out_and_leaves_the_committed_ones(tmp_path,
                                                                         shared_data):
    # a quick run (--repeat 1, one file) overwrote benchmarks/results/pipeline.md
    # with no way to send it elsewhere (no --out), the .md and .json written
    # one after the other in place
    import pipeline
    data = tmp_path / "data"
    data.mkdir()
    (data / "manifest.tsv").write_text("path\n")
    (data / "walk.bvh").symlink_to(shared_data / "bandai" / "dataset-1_walk_normal_002.bvh")
    committed = Path(pipeline.ROOT) / "benchmarks" / "results" / "pipeline.md"
    before = committed.read_bytes()
    pipeline.main(["--data", str(data), "--repeat", "1", "--out", str(tmp_path / "p")])
    assert "| satagraph parse+FK | 1 |" in (tmp_path / "p.md").read_text()
    assert (tmp_path / "p.json").is_file()
    assert committed.read_bytes() == before


def test_collate_writes_its_tables_to_out_and_leaves_the_committed_ones(tmp_path,
                                                                        shared_data,
                                                                        monkeypatch):
    import collate
    monkeypatch.setattr(collate, "retain_freed_memory", lambda: False)  # process-wide
    committed = Path(collate.ROOT) / "benchmarks" / "results" / "collate.md"
    before = committed.read_bytes()
    collate.main(["--data", str(shared_data), "--clips", "2", "--frames", "8",
                  "--repeat", "1", "--out", str(tmp_path / "c")])
    assert "2 clips x 8 frames" in (tmp_path / "c.md").read_text()
    assert (tmp_path / "c.json").is_file()
    assert committed.read_bytes() == before


def test_benchmarks_read_the_data_satagraph_data_names(tmp_path):
    """Every benchmark read ../shared/data beside the checkout, whatever
    SATAGRAPH_DATA (the tests' data) named."""
    import subprocess
    code = "import results_io; print(results_io.SHARED_DATA)"
    folder = Path(__file__).resolve().parents[1] / "benchmarks"
    env = dict(os.environ, SATAGRAPH_DATA=str(tmp_path / "mine"))
    out = subprocess.run([sys.executable, "-c", code], cwd=folder, env=env, text=True,
                         capture_output=True, check=True).stdout.strip()
    assert out == str(tmp_path / "mine")


def test_rig_reading_says_where_the_real_files_are_left_out(tmp_path, monkeypatch):
    # without ../shared (a clone of its own) the run wrote a zoo-only table
    # over benchmarks/results/rig_reading.md, saying nothing of the real files
    import rig_reading
    missing = tmp_path / "shared" / "data"  # a clone of its own: no ../shared beside it
    monkeypatch.setattr(rig_reading, "SHARED_DATA", missing)
    row = {"species": "biped", "up_true": "+Y", "up_read": "+Y", "flagged": False,
           "decidable": True, "looks_like": None, "units_how": "height",
           "units_ok": True, "within_20": True}
    monkeypatch.setattr(rig_reading, "zoo_rows", lambda seed, frames, tmp: [row])
    committed = rig_reading.RESULTS.with_suffix(".md")
    before = committed.read_bytes()
    assert rig_reading.main(["--seeds", "0", "--out", str(tmp_path / "r")]) == 0
    text = (tmp_path / "r.md").read_text()
    assert f"{missing}: no manifest.tsv there" in text
    assert committed.read_bytes() == before
    with pytest.raises(SystemExit):  # a --data folder without the files: refused
        rig_reading.main(["--data", str(tmp_path), "--out", str(tmp_path / "r")])


BENCHMARKS = sorted(p.stem for p in (Path(__file__).resolve().parents[1] / "benchmarks")
                    .glob("*.py") if p.stem != "results_io")


@pytest.mark.parametrize("name", BENCHMARKS)
def test_benchmark_help_shows_its_whole_docstring(name, monkeypatch, capsys):
    # --help showed the docstring's first line alone, often cut mid-sentence
    # ("Wall time of ``satagraph --help`` and ``satagraph inspect FILE``, each
    # in a"), without the usage, the default output path or the run's length
    import importlib
    module = importlib.import_module(name)
    monkeypatch.setattr(sys, "argv", [f"{name}.py", "--help"])
    with pytest.raises(SystemExit) as exit_:
        module.main()
    assert exit_.value.code == 0
    assert " ".join(module.__doc__.split()) in " ".join(capsys.readouterr().out.split())


def test_retarget_sanity_without_the_shared_data_says_so_in_one_line(tmp_path, monkeypatch,
                                                                    capsys):
    # a clone without ../shared: a FileNotFoundError traceback on manifest.tsv
    import retarget_sanity as rs
    monkeypatch.setattr(rs, "DATA", tmp_path / "shared" / "data")
    assert rs.main(["--ckpt", "builtin", "--out", str(tmp_path / "r.md")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "not found" in err and "--source and --target" in err
    assert not (tmp_path / "r.md").exists()


def test_cli_start_writes_its_table_to_out_and_leaves_the_committed_one(tmp_path):
    # a quick check (--repeat 1) overwrote benchmarks/results/cli_start.md;
    # --file spares the `satagraph demo --quick` process writing its walk
    # (test_cli.py runs that command)
    import cli_start
    from satagraph.data.examples import example_motion
    from satagraph.io import write_bvh
    write_bvh(example_motion(), tmp_path / "walk.bvh")
    before = cli_start.OUT.read_bytes()
    cli_start.main(["--repeat", "1", "--out", str(tmp_path / "c.md"),
                    "--file", str(tmp_path / "walk.bvh"), "--command", "retarget --help"])
    assert "satagraph --help" in (tmp_path / "c.md").read_text()
    assert "| satagraph inspect walk.bvh |" in (tmp_path / "c.md").read_text()
    assert "| satagraph retarget --help |" in (tmp_path / "c.md").read_text()
    assert cli_start.OUT.read_bytes() == before


def test_stitch_val_seam_reads_a_jump_where_a_window_begins():
    """``seam`` is about 1 on a smooth take and far above where the pose
    jumps at a window's first kept frame (what the cut rule left)."""
    from dataclasses import replace
    import stitch_val
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    from satagraph.pipelines.inference import window_plan
    walk = generate_clip(zoo_rigs(["biped"])[0], "walk", frames=90, seed=1)
    smooth = stitch_val.seam(walk, 32, 8)
    trans = walk.translations.copy()
    cut = window_plan(90, 32, 8)[0][1]  # the first window's stop: where the cut rule cut
    trans[cut:, 0, 0] += 0.05 * walk.height()
    jumped = replace(walk, translations=trans)
    assert 0.5 < smooth < 2.0 and stitch_val.seam(jumped, 32, 8) > 3 * smooth


def test_benchmarks_of_the_real_files_stop_in_one_line_without_them(tmp_path, monkeypatch,
                                                                     capsys):
    """pretrained, pretrained_val, mirror_val and stitch_val each said it
    in their own words; one check now, naming the script and the folder,
    before any model loads."""
    import mirror_val
    import pretrained
    import pretrained_val
    import stitch_val
    from results_io import missing_data
    missing = tmp_path / "shared" / "data"
    assert missing_data("x.py", tmp_path) == (
        f"x.py: {tmp_path}: no manifest.tsv there: the real rows need the real BVH files of "
        "../shared/data (or $SATAGRAPH_DATA)")
    (tmp_path / "manifest.tsv").write_text("")
    assert missing_data("x.py", tmp_path) is None
    for module in (pretrained, pretrained_val):
        monkeypatch.setattr(module, "DATA", missing)
    monkeypatch.setattr(mirror_val.val, "DATA", missing)
    monkeypatch.setattr(stitch_val, "missing_data", lambda script, what: missing_data(
        script, missing, what))
    out = tmp_path / "out"
    assert pretrained.main(["--out", str(out)]) == 2
    assert pretrained_val.main(["--out", str(out)]) == 2
    with pytest.raises(SystemExit):
        stitch_val.main(["--out", str(out)])
    assert mirror_val.main(["--out", str(out)]) == 2
    err = capsys.readouterr().err
    for script in ("pretrained.py", "pretrained_val.py", "stitch_val.py", "mirror_val.py"):
        assert f"{script}: {missing}: no manifest.tsv there" in err, script
    assert not out.exists()


def test_inference_stages_counts_each_stage_s_own_time(tmp_path, capsys):
    """A stage called inside another counts for itself only; without the
    real files the benchmark says so in one line."""
    import time
    import inference_stages
    clock = inference_stages.StageClock()
    inner = clock.timed("model", lambda: time.sleep(0.02))
    outer = clock.timed("post", lambda: (time.sleep(0.01), inner()))
    outer()
    assert 0.02 <= clock.totals["model"] < 0.2 and 0.01 <= clock.totals["post"] < 0.02 + 0.1
    assert not clock.stack
    assert inference_stages.main(["--data", str(tmp_path)]) == 2
    printed = capsys.readouterr()
    assert printed.out == "" and printed.err.count("\n") == 1
    assert printed.err.startswith(f"inference_stages.py: {tmp_path}: no manifest.tsv there")


def test_retarget_many_says_in_one_line_that_it_needs_the_real_files(tmp_path, capsys):
    import retarget_many
    assert retarget_many.main(["--data", str(tmp_path), "--out", str(tmp_path / "r")]) == 2
    printed = capsys.readouterr()
    assert printed.out == "" and printed.err.count("\n") == 1
    assert printed.err.startswith(f"retarget_many.py: {tmp_path}: no manifest.tsv there")
    assert not (tmp_path / "r.md").exists()


def test_resume_benchmark_draws_the_same_kill_points_unless_told(tmp_path, monkeypatch):
    """``benchmarks/resume.py`` without ``--seed`` kills at the same steps
    each time (it drew them unseeded: no two tables alike)."""
    import resume
    seeds = []

    def run(root, kills, count, every, epochs, seed):
        seeds.append(seed)
        return "| killed |\n"

    monkeypatch.setattr(resume, "run", run)
    for _ in range(2):
        assert resume.main(["--out", str(tmp_path / "resume.md")]) == 0
    assert seeds == [resume.DEFAULT_SEED] * 2
    points = resume.kill_points(36, 5, 3, seeds[0])
    assert points == resume.kill_points(36, 5, 3, seeds[1]) == sorted(set(points))
    assert all(5 < k < 35 for k in points)


def test_interop_needs_blender_and_says_so(monkeypatch, capsys) -> None:
    """Without Blender, benchmarks/interop.py says in one line what it
    needs and exits 0; its comparison of two readings gives the largest
    joint distance as a fraction of the character's size, by joint name."""
    import interop
    monkeypatch.setattr(interop.shutil, "which", lambda name: None)
    assert interop.main([]) == 0
    out = capsys.readouterr().out
    assert out.count("\n") == 1 and "needs Blender" in out
    pos = np.zeros((2, 2, 3))
    pos[:, 1, 1] = 2.0  # a joint 2 above the root: size 2
    ref = {"names": ["Hips", "Left_Head"], "frames": 2, "fps": 24.0, "positions": pos}
    other = dict(ref, names=["Left_Head", "Hips"], positions=pos[:, ::-1].copy(),
                 fps=1 / 0.041667)
    other["positions"][1, 0, 0] = 0.002  # Left_Head off by 1e-3 of the size
    assert interop.compare(ref, other) == {"same_header": True, "error": pytest.approx(1e-3)}
    assert interop.compare(ref, dict(other, frames=3))["same_header"] is False
    assert interop.blender_name("Left Head") == "Left_Head"


def test_demo_record_tables_a_demo_summary_and_refuses_one_without_retargets(tmp_path, capsys):
    """The README's demo table comes from a committed record of the run
    (``benchmarks/results/demo.md``), not from figures copied by hand."""
    import json
    import demo_record
    quality = {"steps": 0.9904, "travel": 0.9458, "stride": 0.7001, "lands": 0.78125}
    summary = {"seconds": 251.2, "steps": [
        {"name": "retarget", "quality": {"quadruped": quality,
                                         "bird": dict(quality, steps=-0.25, lands=None)}},
        {"name": "train", "seconds": 242.6, "note": "13 epochs, 341 steps"},
        {"name": "fine-tuned", "quality": {"quadruped": dict(quality, travel=1.2)}}]}
    path = tmp_path / "summary.json"
    path.write_text(json.dumps(summary))
    assert demo_record.main([str(path), "--out", str(tmp_path / "demo")]) == 0
    text = (tmp_path / "demo.md").read_text()
    assert "| biped -> quadruped | +0.99 | 0.95x | 0.70x | 0.78 | +0.99 | 1.20x | 0.70x | 0.78 |" in text
    assert "| biped -> bird | -0.25 | 0.95x | 0.70x | - | - | - | - | - |" in text
    assert "251 s in all; training: 13 epochs, 341 steps (243 s)" in text
    assert json.loads((tmp_path / "demo.json").read_text()) == summary
    path.write_text(json.dumps({"seconds": 1.0, "steps": [{"name": "zoo"}]}))
    capsys.readouterr()
    assert demo_record.main([str(path), "--out", str(tmp_path / "quick")]) == 2
    assert "no 'retarget' step" in capsys.readouterr().err
    assert not (tmp_path / "quick.md").exists()
    # demo --from-scratch (or --data): its one 'retarget' step is the trained model's, after it
    scratch = [summary["steps"][1], dict(summary["steps"][0])]
    path.write_text(json.dumps(dict(summary, steps=scratch)))
    assert demo_record.main([str(path), "--out", str(tmp_path / "scratch")]) == 2
    assert "a model trained from scratch" in capsys.readouterr().err
    assert not (tmp_path / "scratch.md").exists()
