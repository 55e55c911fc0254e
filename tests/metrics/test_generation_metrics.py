"""Text-to-motion generation metrics (issue 19, item 8) on known values."""
from __future__ import annotations

import numpy as np
import pytest

from satagraph.metrics.generation import (diversity, distribution_metrics, fid, kid,
                                          matching_score, multimodality, r_precision,
                                          replicate, subsample)


def test_r_precision_perfect_and_shuffled():
    rng = np.random.default_rng(0)
    text = rng.normal(size=(64, 8))
    assert r_precision(text, text).tolist() == [1.0, 1.0, 1.0]
    shuffled = r_precision(text, text[rng.permutation(64)], top_k=3)
    assert shuffled[2] < 0.3  # chance: 3/32


def test_r_precision_counts_ranks():
    # motion 0 is nearest to text 1, then its own text 0: rank 2
    text = np.array([[0.0], [1.0]] + [[10.0 + i] for i in range(30)])
    motion = text.copy()
    motion[0] = [0.9]
    out = r_precision(text, motion, top_k=2)
    assert out[0] == pytest.approx(31 / 32) and out[1] == 1.0
    with pytest.raises(ValueError):
        r_precision(text[:10], motion[:10])


def test_r_precision_ties_rank_in_random_order():
    """A caption repeated in the pool ties with the motion's own: R@1 counts
    the expected 1/2 (it was 1); text embeddings that tell no text apart
    score chance k / 32 (they scored 1.0 at every k)."""
    text = np.array([[0.0], [0.0]] + [[10.0 + i] for i in range(30)])
    out = r_precision(text, text.copy(), top_k=3)
    # motions 0 and 1: own text tied with one other, none closer -> 1/2, 1, 1
    np.testing.assert_allclose(out, [31 / 32, 1.0, 1.0])
    motion = np.random.default_rng(0).normal(size=(64, 4))
    np.testing.assert_allclose(r_precision(np.ones((64, 4)), motion), [1 / 32, 2 / 32, 3 / 32])
    # texts 1 and 2 are one caption; motion 1 lies nearer text 0 (0.9) than
    # its own (1.1): c = 1, m = 1 -> 0, 1/2, 1; motion 2: c = 0, m = 1 ->
    # 1/2, 1, 1; the other 30 motions rank their own text first
    text = np.array([[0.0], [2.0], [2.0]] + [[10.0 + i] for i in range(29)])
    motion = text.copy()
    motion[1] = [0.9]
    np.testing.assert_allclose(r_precision(text, motion, top_k=3) * 32, [30.5, 31.5, 32.0])
    # motion 0 (at 0) ties texts 0 (at 1) and 1 (at -1): 1/2, 1, 1; motion 1
    # (at 10) has text 0 nearer than its own and ties with none: 0, 1, 1 (the
    # ties are a motion's, not a text's: text 1 is as near as their own to both)
    text = np.array([[1.0], [-1.0]] + [[100.0 + i] for i in range(30)])
    motion = text.copy()
    motion[0], motion[1] = [0.0], [10.0]
    np.testing.assert_allclose(r_precision(text, motion, top_k=3) * 32, [30.5, 32.0, 32.0])


def test_matching_score_and_diversity():
    text = np.zeros((4, 2))
    motion = np.array([[3.0, 4.0]] * 4)
    assert matching_score(text, motion) == 5.0
    assert matching_score(text + [1.0, 2.0], motion + [1.0, 2.0]) == 5.0  # a shift of both
    two = np.array([[0.0, 0.0], [3.0, 4.0]])
    assert diversity(two, pairs=50) == 5.0
    assert diversity(two + 1.0, pairs=50) == 5.0
    assert multimodality([two, two * 2], pairs=10) == 7.5


def test_fid_of_shifted_gaussians():
    rng = np.random.default_rng(0)
    a = rng.normal(size=(4000, 3))
    assert fid(a, a) == pytest.approx(0.0, abs=1e-6)
    assert fid(a, a + np.array([2.0, 0.0, 0.0])) == pytest.approx(4.0, abs=1e-6)
    b = rng.normal(size=(4000, 3)) * 2.0  # trace term: 3 (1 + 4 - 2 * 2) = 3
    assert fid(a, b) == pytest.approx(3.0, abs=0.3)


def test_kid_is_unbiased_and_grows_with_shift():
    rng = np.random.default_rng(0)
    same = [kid(rng.normal(size=(50, 4)), rng.normal(size=(50, 4))) for _ in range(40)]
    assert abs(np.mean(same)) < 3 * np.std(same) / np.sqrt(len(same))
    assert kid(rng.normal(size=(50, 4)), rng.normal(size=(50, 4)) + 1.0) > 0.1


def test_kid_hand_value():
    # D = 1, k(x, y) = (x y + 1)^3. real {0, 1}: off-diagonal k(0, 1) = 1
    # twice, / (2 * 1) -> 1. fake {0, 2, -1}: k(0, 2) = k(0, -1) = 1,
    # k(2, -1) = -1, twice each, / (3 * 2) -> 1/3. Cross: row 0 gives 1, 1, 1;
    # row 1 gives 1, 27, 0 -> mean 31/6. KID = 1 + 1/3 - 31/3 = -9.
    assert kid(np.array([[0.0], [1.0]]), np.array([[0.0], [2.0], [-1.0]])) == pytest.approx(-9.0)


def test_replicate_and_distribution_metrics():
    mean, half = replicate(lambda rng: 1.0, times=5)
    assert (mean, half) == (1.0, 0.0)
    values = iter([0.0, 1.0, 0.0, 1.0])  # mean 1/2, std 1/2: 1.96 * 0.5 / sqrt(4)
    assert replicate(lambda rng: next(values), times=4) == pytest.approx((0.5, 0.49))
    rng = np.random.default_rng(1)
    out = distribution_metrics(rng.normal(size=(100, 3)), rng.normal(size=(100, 3)) + 3,
                               times=3, size=64)
    assert out["fid"][0] > 20 and out["kid"][0] > 0.5 and out["fid"][1] >= 0


def test_subsample_draws_distinct_rows_or_keeps_all():
    x = np.arange(10.0)[:, None]
    rng = np.random.default_rng(0)
    part = subsample(x, 4, rng)
    assert part.shape == (4, 1) and len(set(part[:, 0])) == 4 and set(part[:, 0]) <= set(x[:, 0])
    for size in (10, 20):  # as many rows or fewer: all of them, in their order
        np.testing.assert_array_equal(subsample(x, size, rng), x)
