"""benchmarks/t2m_paired.py: paired differences of two samplings over seeds."""
from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import t2m_paired  # noqa: E402


def _run(path: Path, seed: int, r3: float, fid: float, bandai: float) -> str:
    facts = {"seed": seed, "prompts": "val", "bandai_val": True, "evaluator_steps": 3000}
    rows = [{"group": "zoo", "row": "generator (GT length)", "R@3": [r3, 0.005],
             "fid": [fid, 0.007], "diversity": 1.3},
            {"group": "bandai (val)", "row": "generator (GT length)", "R@3": [bandai, 0.01]}]
    path.write_text(json.dumps({"facts": facts, "rows": rows, "skeletons": []}))
    return str(path)


def test_paired_differences_mean_sd_and_t_interval(tmp_path, capsys):
    base = [_run(tmp_path / f"b{s}.json", s, 0.80, 0.22, b)
            for s, b in ((1, 0.40), (2, 0.30), (3, 0.50))]
    cand = [_run(tmp_path / f"c{s}.json", s, 0.81, fid, b)
            for s, fid, b in ((1, 0.20, 0.42), (2, 0.21, 0.28), (3, 0.19, 0.53))]
    cells = ["zoo|generator (GT length)|fid", "bandai (val)|generator (GT length)|R@3",
             "zoo|generator (GT length)|diversity"]
    cell_args = [a for c in cells for a in ("--cell", c)]
    assert t2m_paired.main(["--baseline", *base, "--candidate", *cand, "--out",
                            str(tmp_path / "t.md")] + cell_args) == 0
    text = (tmp_path / "t.md").read_text()
    assert text in capsys.readouterr().out
    mean, sd, half = t2m_paired.summary([0.02, -0.02, 0.03])
    assert mean == pytest.approx(0.01) and sd == pytest.approx(math.sqrt(0.0014 / 2))
    assert half == pytest.approx(4.303 * sd / math.sqrt(3))
    bandai = next(line for line in text.splitlines()
                  if line.startswith("| bandai (val) / generator (GT length) / R@3 |"))
    assert "0.400 -> 0.420 (+0.020)" in bandai and "0.300 -> 0.280 (-0.020)" in bandai
    assert f"| {mean:+.3f} | {sd:.3f} | {mean - half:+.3f} to {mean + half:+.3f} |" in bandai
    fid = next(line for line in text.splitlines() if "/ fid |" in line)
    assert "| -0.020 | 0.010 |" in fid
    assert "| +0.000 | 0.000 | +0.000 to +0.000 |" in text  # diversity: no change


def test_one_pair_has_no_spread():
    mean, sd, half = t2m_paired.summary([0.5])
    assert mean == 0.5 and math.isnan(sd) and math.isnan(half)


def test_unpaired_or_unreadable_runs_are_refused_naming_the_files(tmp_path):
    b = _run(tmp_path / "b.json", 19, 0.8, 0.2, 0.4)
    c = _run(tmp_path / "c.json", 20, 0.8, 0.2, 0.4)
    with pytest.raises(SystemExit,
                       match=r"b\.json and .*c\.json: not a pair \(seed 19 against 20\)"):
        t2m_paired.pair_runs([b], [c])
    with pytest.raises(SystemExit, match="1 baseline and 2 candidate files"):
        t2m_paired.pair_runs([b], [c, c])
    (tmp_path / "bad.json").write_text("{not json")
    with pytest.raises(SystemExit, match=r"bad\.json: not a readable t2m\.py JSON file"):
        t2m_paired.load_run(str(tmp_path / "bad.json"))
    with pytest.raises(SystemExit, match=r"b\.json: no cell 'zoo\|real\|fid'"):
        t2m_paired.cell_value(t2m_paired.load_run(b), "zoo|real|fid")
    with pytest.raises(SystemExit, match="not GROUP\\|ROW\\|METRIC"):
        t2m_paired.cell_value(t2m_paired.load_run(b), "zoo-fid")


def test_action_of_one_asked_label_is_a_cell():
    """``action:LABEL`` reads the accuracy on the prompts asking for LABEL;
    a label the row never asked for is no cell."""
    run = {"path": "r.json", "rows": [{"group": "zoo", "row": "reconstruction (SATA-RVQ)",
                                       "action": [0.5, 0.06],
                                       "action_by_label": {"jump": {"n": 23, "accuracy": 0.35,
                                                                    "instead": "look"}}}]}
    assert t2m_paired.cell_value(run, "zoo|reconstruction (SATA-RVQ)|action:jump") == 0.35
    assert t2m_paired.cell_value(run, "zoo|reconstruction (SATA-RVQ)|action") == 0.5
    with pytest.raises(SystemExit, match="r.json: no cell 'zoo|reconstruction"):
        t2m_paired.cell_value(run, "zoo|reconstruction (SATA-RVQ)|action:idle")


def test_a_failed_write_leaves_the_previous_table(tmp_path, file_size_limit):
    # --out was written in place: a full disk left half a table (the
    # previous one gone); every benchmark now writes through atomic_write
    base = [_run(tmp_path / f"b{s}.json", s, 0.80, 0.22, 0.4) for s in (1, 2)]
    cand = [_run(tmp_path / f"c{s}.json", s, 0.81, 0.20, 0.4) for s in (1, 2)]
    out = tmp_path / "t.md"
    args = ["--baseline", *base, "--candidate", *cand, "--out", str(out),
            "--cell", "zoo|generator (GT length)|fid"]
    assert t2m_paired.main(args) == 0
    before = out.read_text()
    with file_size_limit(len(before) // 2), pytest.raises(OSError):
        t2m_paired.main(args + ["--cell", "zoo|generator (GT length)|R@3"])
    assert out.read_text() == before
