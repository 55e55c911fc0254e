"""Masking schedule, corruption, sampling and guidance math."""
from __future__ import annotations

import math

import pytest
import torch

from satagraph.nn.generators import (corrupt_tokens, cosine_schedule, guided,
                                     guided_candidates, mask_ratio, random_mask,
                                     residual_layer_schedule, sample_logits, top_k_filter)
from satagraph.nn.generators.sampling import lowest_ranked, ranking_scores, spread_choice

K = 16


def draw_masks(floor=0.0, rows=4000, length=50, seed=0):
    gen = torch.Generator().manual_seed(seed)
    lengths = torch.randint(length // 2, length + 1, (rows,), generator=gen)
    valid = torch.arange(length) < lengths.unsqueeze(-1)
    ratio = mask_ratio(torch.rand(rows, generator=gen), floor)
    return random_mask(valid, ratio, gen), valid, ratio


def test_cosine_schedule_end_points():
    assert cosine_schedule(torch.tensor(0.0)) == 1.0
    assert abs(float(cosine_schedule(torch.tensor(1.0)))) < 1e-6


@pytest.mark.parametrize("floor", [0.0, 0.5])
def test_masked_fraction_follows_the_cosine_schedule(floor):
    mask, valid, ratio = draw_masks(floor)
    frac = mask.sum(-1) / valid.sum(-1)
    assert not (mask & ~valid).any()  # padding is never masked
    assert (mask.sum(-1) >= 1).all()
    count = torch.round(ratio * valid.sum(-1)).clamp(min=1)
    assert torch.equal(mask.sum(-1), count.long())  # round(ratio * length), at least one
    expected = floor + (1 - floor) * 2 / math.pi  # E[cos(pi u / 2)] = 2 / pi
    assert abs(float(frac.mean()) - expected) < 0.015
    assert float(frac.min()) >= floor - 0.02


def test_at_least_one_token_is_masked():
    valid = torch.ones(100, 5, dtype=torch.bool)
    mask = random_mask(valid, torch.zeros(100), torch.Generator().manual_seed(0))
    assert (mask.sum(-1) == 1).all()


def test_corruption_split_of_the_masked_tokens():
    gen = torch.Generator().manual_seed(0)
    codes = torch.randint(K, (400, 100), generator=gen)
    mask = torch.rand(400, 100, generator=gen) < 0.6
    out = corrupt_tokens(codes, mask, K, K, generator=gen)
    total = mask.sum().item()
    random_share = out.random.sum().item() / total
    masked_share = out.masked.sum().item() / total
    kept = mask & ~out.random & ~out.masked
    assert abs(random_share - 0.10) < 0.01
    assert abs(masked_share - 0.9 * 0.88) < 0.01  # 88 % of the non-random ones: 79.2 %
    assert abs(kept.sum().item() / total - 0.9 * 0.12) < 0.01
    assert not ((out.random | out.masked) & ~mask).any()
    assert torch.equal(out.inputs[~mask], codes[~mask])
    assert torch.equal(out.inputs[kept], codes[kept])
    assert out.inputs[out.masked].eq(K).all()
    assert out.inputs[out.random].lt(K).all() and out.inputs[out.random].ge(0).all()


def test_corruption_split_read_as_shares_of_all_masked_tokens():
    gen = torch.Generator().manual_seed(1)
    codes = torch.randint(K, (400, 100), generator=gen)
    mask = torch.ones(400, 100, dtype=torch.bool)
    out = corrupt_tokens(codes, mask, K, K, 0.1, 0.88 / 0.9, gen)  # 10 / 88 / 2
    assert abs(out.random.float().mean().item() - 0.10) < 0.01
    assert abs(out.masked.float().mean().item() - 0.88) < 0.01


def test_top_k_keeps_the_share_of_codes():
    logits = torch.randn(3, 20)
    kept = torch.isfinite(top_k_filter(logits, 0.1))
    assert kept.sum(-1).tolist() == [2, 2, 2]
    assert torch.equal(top_k_filter(logits, None), logits)
    assert kept.gather(-1, logits.argmax(-1, keepdim=True)).all()


def test_sampling_is_seeded_and_greedy_at_zero_temperature():
    logits = torch.randn(6, 8, K)
    draw = lambda seed: sample_logits(logits, 1.0, 0.5, torch.Generator().manual_seed(seed))
    assert torch.equal(draw(3), draw(3))
    assert not torch.equal(draw(3), draw(4))
    assert torch.equal(sample_logits(logits, 0.0), logits.argmax(-1))
    top = logits.topk(K // 2, -1).indices
    assert (top == draw(5).unsqueeze(-1)).any(-1).all()  # only top-k codes are drawn


def test_residual_layers_are_biased_to_low_layers():
    q = residual_layer_schedule(20000, 6, torch.Generator().manual_seed(0))
    assert q.min() == 1 and q.max() == 5
    counts = torch.bincount(q, minlength=6)[1:].float() / q.numel()
    # P(q = 1) = P(1 - cos(pi u / 2) < 1 / 8), u uniform
    expected_first = 2 / math.pi * math.acos(1 - 1 / 8)
    assert abs(float(counts[0]) - expected_first) < 0.01
    assert (counts[:-1] > counts[1:]).all()


def test_lowest_ranked_breaks_ties_by_position():
    scores = torch.tensor([[0.5, 0.1, 0.5, 0.5, float("inf")]])
    assert lowest_ranked(scores, torch.tensor([3])).tolist() == [[True, True, True, False, False]]


def test_guidance_math():
    cond, uncond = torch.randn(4, K), torch.randn(4, K)
    assert torch.equal(guided(cond, uncond, 1.0), cond)
    torch.testing.assert_close(guided(cond, uncond, 0.0), uncond)
    torch.testing.assert_close(guided(cond, uncond, 4.0), uncond + 4 * (cond - uncond))


def test_guided_candidates_draw_the_conditional_logits_among_the_guided_top_k():
    """The codes the guided logits rank in their top k keep their
    conditional logits, the others are ruled out; guidance can move the
    draw's favourite from the guided logits' extreme back to the
    conditional one's, and without guidance it is the conditional top k."""
    cond = torch.tensor([[3.0, 2.5, 0.0, -1.0, -2.0]])
    uncond = torch.tensor([[3.0, 1.0, 0.5, -1.0, -2.0]])
    out = guided_candidates(cond, uncond, 4.0, 0.4)  # two of five codes
    assert guided(cond, uncond, 4.0).argmax() == 1 and out.argmax() == 0
    assert torch.equal(out[0, :2], cond[0, :2]) and torch.isinf(out[0, 2:]).all()
    rows = torch.randn(6, K), torch.randn(6, K)
    assert torch.equal(guided_candidates(rows[0], rows[1], 1.0, 0.1),
                       top_k_filter(rows[0], 0.1))
    kept = guided_candidates(*rows, 3.0, 0.1) > float("-inf")
    assert torch.equal(kept, top_k_filter(guided(*rows, 3.0), 0.1) > float("-inf"))
    milder = guided_candidates(*rows, 3.0, 0.1, draw_scale=2.0)
    assert torch.equal(milder > float("-inf"), kept)
    torch.testing.assert_close(milder[kept], guided(*rows, 2.0)[kept])
    assert torch.equal(guided_candidates(*rows, 3.0, 0.1, draw_scale=3.0),
                       top_k_filter(guided(*rows, 3.0), 0.1))


def test_ranking_scores_noise_fades_with_the_steps():
    conf = torch.tensor([[0.9, 0.5, 0.1, 0.7]])
    assert torch.equal(ranking_scores(conf, 0.0, 0.3), conf)
    torch.testing.assert_close(ranking_scores(conf, 4.5, 1.0), conf.log())
    gen = lambda: torch.Generator().manual_seed(0)  # noqa: E731
    early = ranking_scores(conf, 4.5, 0.0, gen())
    assert torch.equal(early, ranking_scores(conf, 4.5, 0.0, gen()))  # seeded
    # noise of scale 4.5 reorders a ranking of log-probabilities a few nats apart
    orders = {tuple(ranking_scores(conf, 4.5, 0.0, torch.Generator().manual_seed(s))
                    .argsort().tolist()[0]) for s in range(20)}
    assert len(orders) > 3


def test_spread_choice_keeps_the_best_apart_and_fills_what_it_lacks():
    scores = torch.tensor([[0.9, 0.95, 0.8, 0.1, 0.2, 0.3, 0.85, 0.5]])
    every = torch.ones(1, 8, dtype=torch.bool)
    none = torch.zeros(1, 8, dtype=torch.bool)
    # gap 8 / 3 -> 2: 0.95 at 1, then its neighbours 0 and 2 are passed over for 6
    assert spread_choice(scores, every, none, torch.tensor([2]), 1.0)[0].nonzero().flatten().tolist() == [1, 6]
    # spread 0: by score alone, as lowest_ranked would keep them
    assert torch.equal(spread_choice(scores, every, none, torch.tensor([2]), 0.0),
                       lowest_ranked(-scores, torch.tensor([2])))
    # a locked token blocks its neighbours (gap 8 / 4 -> 2: 6 is passed over for 7)
    locked = none.clone()
    locked[0, 5] = True
    got = spread_choice(scores, ~locked, locked, torch.tensor([2]), 1.0)[0]
    assert got.nonzero().flatten().tolist() == [1, 7]
    # more wanted than fit apart: the rest by score, never a locked one
    got = spread_choice(scores, ~locked, locked, torch.tensor([7]), 1.0)[0]
    assert got.sum() == 7 and not got[5]


def test_spread_choice_rows_are_independent():
    gen = torch.Generator().manual_seed(0)
    scores = torch.rand(4, 30, generator=gen)
    cand = torch.rand(4, 30, generator=gen) > 0.3
    count = torch.tensor([0, 1, 5, 20]).clamp(max=cand.sum(-1))
    got = spread_choice(scores, cand, ~cand, count, 0.5)
    assert torch.equal(got.sum(-1), count) and not (got & ~cand).any()
    for b in range(4):
        assert torch.equal(spread_choice(scores[b:b + 1], cand[b:b + 1], ~cand[b:b + 1],
                                         count[b:b + 1], 0.5)[0], got[b])
