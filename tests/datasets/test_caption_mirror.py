"""Mirroring captions together with mirrored motions."""
from __future__ import annotations

import pytest

from satagraph.sides import swap_side
from satagraph.datasets.zoo import ClipFacts
from satagraph.datasets import Caption, captions_for, mirror_captions, mirror_text

CANONICAL = [
    "a person turns left and raises the right hand",
    "Left foot forward, RIGHT arm back; Right knee bends",
    "someone spins clockwise, then counterclockwise",
    "walks leftwards along the rightmost wall, leftward then rightwards",
    "a left-handed throw to the far-right",
    "raises the left_hand, then RIGHT_FOOT",
    "nothing sided here: bright copyright leftover wrights",
    "",
]


@pytest.mark.parametrize("text", CANONICAL)
def test_mirror_is_an_involution(text):
    assert mirror_text(mirror_text(text)) == text


def test_mirror_swaps_whole_words_keeping_case():
    assert mirror_text(CANONICAL[0]) == "a person turns right and raises the left hand"
    assert mirror_text(CANONICAL[1]) == "Right foot forward, LEFT arm back; Left knee bends"
    assert mirror_text(CANONICAL[2]) == "someone spins counterclockwise, then clockwise"
    assert mirror_text(CANONICAL[3]) == \
        "walks rightwards along the leftmost wall, rightward then leftwards"
    assert mirror_text(CANONICAL[4]) == "a right-handed throw to the far-left"
    assert mirror_text(CANONICAL[5]) == "raises the right_hand, then LEFT_FOOT"
    assert mirror_text(CANONICAL[6]) == CANONICAL[6]  # no word boundary, no swap
    assert mirror_text("Clockwise") == "Counterclockwise"


def test_other_spellings_of_counterclockwise():
    for text in ("anticlockwise", "anti-clockwise", "counter-clockwise",
                 "counter clockwise", "anti clockwise"):
        assert mirror_text(f"turns {text}") == "turns clockwise"
    assert mirror_text("Turns Anti-Clockwise") == "Turns Clockwise"
    # HumanML3D's spelling, once "counter counterclockwise"
    assert mirror_text("walks a Counter Clockwise circle then clockwise") == \
        "walks a Clockwise circle then counterclockwise"


def test_caption_words_follow_the_joint_name_rule():
    for word in ("Left", "Right", "left", "right", "LEFT", "RIGHT"):
        assert mirror_text(word) == swap_side(word) != word


def test_mirrored_captions_of_sided_clips():
    left = captions_for("dataset-1_walk-left_sad_001.bvh")
    right = captions_for("dataset-1_walk-right_sad_001.bvh")
    assert [c.text for c in mirror_captions(left)] == [c.text for c in right]
    turn = captions_for(ClipFacts("biped", "turn", 4.0, 1.3, 1.3, 80.0))
    back = captions_for(ClipFacts("biped", "turn", 4.0, 1.3, 1.3, -80.0))
    assert [c.text for c in mirror_captions(turn)] == [c.text for c in back]
    part = Caption("steps to the left", 1.0, 2.5, "user").mirrored()
    assert part == Caption("steps to the right", 1.0, 2.5, "user")
