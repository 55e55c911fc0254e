"""When a retarget is carried as its character (``carriage``): never, where
it already lands its limbs, where the target shows no frames, a
reconstruction; and where a limb it stands on never comes down, or always.
Bad settings are refused in one line."""
from __future__ import annotations

import numpy as np
import pytest

from satagraph.pipelines import inference
from satagraph.pipelines.inference import (CARRIAGE_LANDS, RigMemo, carried_as_character,
                                           check_settings, once_per_motion)
from satagraph.pipelines.quality import lands
from satagraph.transforms.ground import ground_level, ground_retarget
from tests.pipelines.test_quality import _forelegs_up, _walk


@pytest.fixture(scope="module")
def walk():
    return _walk("quadruped")


def _carried(out, target, mode: str, memo=None):
    """:obj:`out` carried as :obj:`target`'s character, checked on the
    floor as a retarget is (:func:`ground_retarget` at the target's level)."""
    level = ground_level(target) if target.num_frames else None
    return carried_as_character(out, target, mode,
                                lambda m: ground_retarget(m, out, target, level), memo)


def test_never_and_a_retarget_that_lands_its_limbs_are_kept(walk) -> None:
    lifted = _forelegs_up(walk)
    assert _carried(lifted, walk, "never") is lifted
    assert _carried(walk, walk, "auto") is walk  # lands 1.0
    assert _carried(lifted, walk.slice(0, 0), "auto") is lifted  # no frames, no carriage
    assert _carried(lifted, walk.slice(0, 0), "always") is lifted


def test_auto_carries_a_retarget_whose_forepaws_never_come_down(walk) -> None:
    """Forelegs swung up 65 degrees (lands 0): carried, the paws land as
    the character's own clip lands them; the memo keeps the character's
    carriage, and the output is the same with or without it."""
    lifted = _forelegs_up(walk)
    memo = RigMemo()
    carried = _carried(lifted, walk, "auto", memo)
    assert carried is not lifted and lands(carried, walk) > 0.9
    assert (id(walk), "carriage") in memo.kept
    again = _carried(lifted, walk, "auto", memo)
    np.testing.assert_array_equal(again.rotations, carried.rotations)


def test_always_carries_even_a_retarget_that_lands(walk) -> None:
    """Forelegs swung up only 10 degrees still land (auto keeps them);
    ``always`` turns every joint's mean rotation back to the clip's own."""
    from satagraph.transforms.carriage import mean_carriage
    slightly = _forelegs_up(walk, 10.0)
    assert lands(slightly, walk) > 0.5
    assert _carried(slightly, walk, "auto") is slightly
    turned = _carried(slightly, walk, "always")
    assert np.abs(mean_carriage(slightly) - mean_carriage(walk)).max() > 0.1
    np.testing.assert_allclose(mean_carriage(turned), mean_carriage(walk), atol=1e-9)


def test_a_carriage_setting_that_is_none_of_the_modes_is_refused() -> None:
    class Module:
        window, fps = 64, 30.0
        meta = {"window": 64}

    with pytest.raises(ValueError, match=r"carriage must be one of \['auto', 'always', "
                                         r"'never'\], got 'sometimes'"):
        check_settings(Module(), 64, 16, "auto", False, "sometimes")


def test_auto_reads_a_target_clip_from_the_floor_it_stands_on(walk) -> None:
    """A target clip whose lowest point is no paw's (the dog's clips that
    lie with the tail tip on the floor, the paws 4-11 cm above it where
    they stand): raised 6 % of its height, its paws still land where it
    stands, and forepaws held up are carried down as onto the clip itself."""
    from satagraph.transforms.ground import raise_root
    lifted = _forelegs_up(walk)
    raised = raise_root(walk, 0.06 * walk.height())
    carried = _carried(lifted, raised, "auto")
    assert carried is not lifted and lands(carried, walk) > 0.9


@pytest.mark.parametrize("degrees, carried", [(15.0, False), (35.0, True)])
def test_auto_carries_only_a_retarget_landing_less_than_half_as_often(walk, degrees: float,
                                                                       carried: bool) -> None:
    """Forelegs swung up 15 degrees still land their paws 0.73 as often as
    the clip does (kept); swung up 35 degrees, 0.35 as often (carried)."""
    lifted = _forelegs_up(walk, degrees)
    assert lands(lifted, walk) == pytest.approx(0.35 if carried else 0.73, abs=0.01)
    assert (_carried(lifted, walk, "auto") is not lifted) == carried


@pytest.mark.parametrize("landing, carried", [(CARRIAGE_LANDS, False),
                                              (np.nextafter(CARRIAGE_LANDS, 0.0), True),
                                              (None, False), (0.0, True)])
def test_auto_carries_below_carriage_lands_and_never_where_lands_says_nothing(
        walk, monkeypatch, landing, carried: bool) -> None:
    """The gate's edge: a retarget that ``lands`` exactly
    ``CARRIAGE_LANDS`` is kept, one a hair below carried; one ``lands``
    cannot read (``None``: its character stands on no limb in the clip) is
    not asked to stand."""
    monkeypatch.setattr(inference, "lands_against", lambda motion, own: landing)
    lifted = _forelegs_up(walk)
    assert (_carried(lifted, walk, "auto") is not lifted) == carried


def test_once_per_motion_gives_its_last_result_again_for_the_same_motion(walk) -> None:
    """Called again on the same motion object, the wrapped function is not
    run again; on another motion it is, and only its last result is kept."""
    runs = []
    first5 = once_per_motion(lambda m: runs.append(m) or m.slice(0, 5))
    short = first5(walk)
    assert first5(walk) is short and runs == [walk]
    other = walk.slice(0, 10)
    assert first5(other).num_frames == 5 and runs == [walk, other]
    assert first5(walk) is not short and len(runs) == 3
