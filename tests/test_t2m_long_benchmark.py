"""benchmarks/t2m_long.py: clips longer than the generator's training window."""
from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import t2m  # noqa: E402
import t2m_long  # noqa: E402


def test_pace_ratio_is_the_median_over_moving_prompts_of_their_own_length_clips():
    item = t2m.zoo_items("val", 1, seed=0)[0]
    own = [replace(item, label=l, froude=f) for l, f in
           (("walk", 0.5), ("run", 1.0), ("idle", 0.01), ("dash", 2.0))]
    long = [replace(it, froude=f) for it, f in zip(own, (0.25, 1.0, 0.5, 3.0))]
    assert t2m_long.pace_ratio(long, own) == 1.0  # median of 0.5, 1, 1.5: idle left out


@pytest.mark.slow
def test_stretches_are_the_prompts_length_at_either_end_of_the_long_clip():
    """Both stretches last as long as the prompt's own clip; the first is
    the start of the long generation and the last its end."""
    from satagraph.data.dataset import _frames
    from satagraph.data.features import motion_to_features
    from satagraph.pipelines.generate import GenerationSettings, generate_on, load_generator
    from satagraph.transforms.canonical import canonicalize
    item = [it for it in t2m.zoo_items("val", 8, seed=0, keep=True) if it.label == "walk"][0]
    module = load_generator("builtin")
    parts = t2m_long.stretches(module, item, 4.4, 0, GenerationSettings())
    size = int(round(item.seconds * t2m.FPS))
    full = motion_to_features(canonicalize(
        generate_on(module, item.captions[0], item.motion, 4.4, 0, GenerationSettings()),
        fps=t2m.FPS, up_axis="+Y", unit_scale=1.0))
    for name, part in (("first", slice(0, size)), ("last", slice(132 - size, 132))):
        assert parts[name].seconds == size / t2m.FPS
        expected = t2m.measure(_frames(full, part), item.captions, "walk", "zoo", item.skeleton)
        np.testing.assert_allclose(parts[name].desc, expected.desc)
    assert not np.allclose(parts["first"].desc, parts["last"].desc)


def test_table_gives_the_stretches_lengths_this_run_measured():
    # the table printed "(1.1-3.2 s)" whatever prompts the run scored
    facts = {"seconds": 12.0, "prompts": "val", "seed": 3, "items": 2,
             "labels": {"walk": 1, "idle": 1}, "ckpt": "builtin",
             "trained_window_frames": 120, "stretch_seconds": [1.3, 2.5],
             "seconds_total": 5.0}
    rows = [{"row": "real", "R@3": None, "fid": None, "action": None,
             "direction": (1.0, 1), "pace": 1.0}]
    text = t2m_long.table({"facts": facts, "rows": rows})
    assert "the prompt's own length (1.3-2.5 s)" in text
