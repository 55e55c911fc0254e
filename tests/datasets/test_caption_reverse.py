"""Reversing captions together with motions played backwards."""
from __future__ import annotations

import numpy as np
import pytest

from satagraph.data.examples import example_motion
from satagraph.datasets import Caption, captions_for, reverse_text
from satagraph.datasets.reverse import REVERSIBLE_WORDS
from satagraph.transforms import reverse_time


@pytest.mark.parametrize("text, reversed_", [
    ("a person walks forward sadly", "a person walks backward sadly"),
    ("a person walks backwards", "a person walks forward"),
    ("someone walks", "someone walks backward"),
    ("a person walks like a huge, heavy giant", "a person walks backward like a huge, heavy giant"),
    ("an elderly person walks forward", "an elderly person walks backward"),
])
def test_walks_reverse_their_direction(text, reversed_):
    assert reverse_text(text) == reversed_


@pytest.mark.parametrize("text", [
    "a person jumps forward several times and turns around",  # not a walk
    "a person takes a walk",                                  # no walk verb
    "a person walks forward and to the left",                 # sides: not in the words
    "a person walks forward, then stops",                     # a stop played back is a start
    "a biped walks forward",                                   # the zoo's words: not known
    "",
])
def test_other_captions_have_no_known_reversal(text):
    assert reverse_text(text) is None


def test_reversing_a_reversed_walk_with_a_direction_gives_it_back():
    for text in ("a person walks forward angrily", "someone walks backward"):
        assert reverse_text(reverse_text(text)) == text


def test_templated_walk_captions_reverse_and_others_do_not():
    walk = captions_for("dataset-1_walk_sad_001.bvh")
    back = captions_for("dataset-1_walk-back_sad_001.bvh")
    for caption in walk:  # "walks forward" and "walks" both walk backward, nothing else changes
        text = caption.reversed().text
        assert text.count("walks backward") == 1
        assert text.replace(" backward", "") == caption.text.replace(" forward", "")
    for caption in back:
        assert "walks forward" in caption.reversed().text
    assert all(c.reversed() is None for c in captions_for("dataset-1_kick_sad_001.bvh"))
    assert Caption("someone walks", 1.0, 2.0).reversed() == \
        Caption("someone walks backward", 1.0, 2.0)
    assert {"walks", "forward", "backward", "person", "sadly"} <= REVERSIBLE_WORDS


def test_reverse_time_plays_the_motion_backwards():
    motion = example_motion(40, fps=30.0)
    back = reverse_time(motion)
    assert np.allclose(back.global_positions(), motion.global_positions()[::-1])
    root = motion.root_translation
    assert np.allclose(back.root_translation[-1] - back.root_translation[0],
                       -(root[-1] - root[0]))
    again = reverse_time(back)
    assert np.array_equal(again.rotations, motion.rotations)
    assert np.array_equal(again.translations, motion.translations)
