"""Sliding-window plan and learning-rate schedule."""
import pytest

from satagraph.data.dataset import window_starts
from satagraph.pipelines.inference import window_plan
from satagraph.lightning import lr_factor


def test_window_plan_covers_every_frame_once():
    for num in (1, 30, 64, 65, 100, 113, 500):
        plan = window_plan(num, 64, 16)
        kept = [f for a, b, keep in plan for f in range(keep, b)]
        assert kept == list(range(num))
        assert all(b - a == min(64, num) for a, b, _ in plan)
        assert all(keep - a in (0, 16) or a == plan[-1][0] for a, _, keep in plan)


def test_window_plan_starts_are_the_training_windows():
    """One windowing rule: inference windows start where training windows
    of stride ``window - overlap`` do."""
    for num in (1, 30, 64, 65, 100, 113, 500):
        for window, overlap in ((64, 16), (16, 0), (10, 9)):
            plan = window_plan(num, window, overlap)
            assert [a for a, _, _ in plan] == window_starts(num, window, window - overlap)


@pytest.mark.parametrize("window,overlap", [(16, 16), (16, 20), (16, -1), (0, 0), (-5, -2)])
def test_window_plan_rejects_windows_that_cover_nothing(window, overlap):
    with pytest.raises(ValueError, match=f"windows of {window} frames sharing {overlap}: "):
        window_plan(100, window, overlap)


def test_lr_schedule():
    assert lr_factor(0, 30, 0.99, 0.01) == pytest.approx(1 / 30)
    assert lr_factor(29, 30, 0.99, 0.01) == 1.0
    assert lr_factor(40, 30, 0.99, 0.01) == pytest.approx(0.99 ** 10)
    assert lr_factor(10_000, 30, 0.99, 0.01) == 0.01
