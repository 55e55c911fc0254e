"""benchmarks/t2m_directions.py: which way a generated person walks."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import t2m  # noqa: E402
import t2m_directions  # noqa: E402
from tests.conftest import data_dir  # noqa: E402


def test_the_built_in_generator_walks_a_zoo_biped_the_asked_way(tmp_path):
    from satagraph.io import read_bvh, write_bvh
    from satagraph.pipelines.generate import GenerationSettings, load_generator
    item = [it for it in t2m.zoo_items("val", 8, seed=0, keep=True) if it.label == "walk"][0]
    rig = tmp_path / "biped.bvh"
    write_bvh(item.motion, rig)
    target = read_bvh(str(rig))
    model, settings = load_generator("builtin"), GenerationSettings()
    assert t2m_directions.walked(model, target, "a person walks forward", "walk", 1,
                                 settings) == 1
    assert t2m_directions.walked(model, target, "a person walks backward", "walk-back", 1,
                                 settings) == 1
    row = {"rig": "biped", "sampling": "logits", "seeds": 2, "walk": 2, "walk-back": 1,
           "walk-left": 0, "walk-right": 2}
    assert t2m_directions._row(row) == "| biped | logits | 2 / 2 | 1 / 2 | 0 / 2 | 2 / 2 |"


@pytest.mark.skipif(data_dir() is None, reason="../shared/data not found: the manifest's "
                    "human rigs are needed")
def test_human_rigs_are_the_splits_cmu_and_ccbase_files(monkeypatch):
    monkeypatch.setattr(t2m_directions, "MANIFEST", data_dir() / "manifest.tsv")
    val = [Path(p).name for p in t2m_directions.human_rigs("val")]
    assert val == ["depressed_13_000.bvh", "old_13_000.bvh", "007_07.bvh", "007_08.bvh",
                   "007_09.bvh"]
    assert not set(val) & {Path(p).name for p in t2m_directions.human_rigs("test")}


@pytest.mark.skipif(data_dir() is None, reason="../shared/data not found: a CMU test rig is "
                    "needed")
def test_the_built_in_generator_walks_a_person_backward_on_a_cmu_rig():
    """The CMU skeleton has one captioned training clip (jumps); the default
    sampling keeps the residual transformer's guided logits, which walk a
    person backward there (``experiments/T2M.md`` sections 64-66; both
    transformers drawing among candidates walked forward)."""
    from satagraph.pipelines.generate import GenerationSettings, load_generator
    from satagraph.io import read_bvh
    rig = read_bvh(str(data_dir() / "cmu" / "neutral_16_000.bvh"))
    model = load_generator("builtin")
    back = ("a person walks backward", "walk-back")
    assert t2m_directions.walked(model, rig, *back, 2, GenerationSettings()) == 2


def test_overrides_apply_on_top_of_every_sampling(tmp_path, monkeypatch):
    """``--smooth``/``--output-smooth``/``--residual-guidance`` reach each
    sampling's :class:`GenerationSettings`, its own fields kept."""
    from satagraph.io import write_bvh
    item = t2m.zoo_items("val", 2, seed=0, keep=True)[0]
    rig = tmp_path / "rig.bvh"
    write_bvh(item.motion, rig)
    seen = []
    monkeypatch.setattr(t2m_directions, "walked",
                        lambda model, target, prompt, label, seeds, settings:
                        seen.append(settings) or seeds)
    rows = t2m_directions.table(None, [str(rig)], ["logits", "masked-candidates"], 3,
                                {"smooth": 0.0, "output_smooth": 2.0,
                                 "residual_guidance": 3.0})
    assert [r["walk"] for r in rows] == [3, 3]
    assert {(s.guide, s.residual_guide) for s in seen} == {("logits", "logits"),
                                                          ("candidates", "logits")}
    assert all(s.smooth == 0.0 and s.output_smooth == 2.0 and s.residual_guidance == 3.0
               for s in seen)
    assert all(s.draw_guidance == t2m_directions.GenerationSettings().draw_guidance
               for s in seen)
