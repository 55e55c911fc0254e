"""Duration distribution from text and skeleton."""
from __future__ import annotations

import torch

from satagraph.nn.generators import LengthModel
from tests.nn.generators.generator_helpers import SKEL, TEXT


def tiny_length(**kwargs) -> LengthModel:
    torch.manual_seed(0)
    return LengthModel(TEXT, SKEL, hidden_channels=32, dropout=0.0, **kwargs)


def test_bins():
    model = tiny_length(bin_seconds=0.25, max_seconds=10.0)
    assert model.num_bins == 40
    seconds = torch.tensor([0.0, 0.25, 0.3, 0.4, 2.0, 9.9, 30.0])
    bins = model.seconds_to_bins(seconds)
    assert bins.tolist() == [0, 0, 0, 1, 7, 39, 39]
    assert model.bins_to_seconds(torch.tensor([0, 7, 39])).tolist() == [0.25, 2.0, 10.0]
    assert LengthModel.seconds_to_frames(torch.tensor([2.0, 0.01]), 30).tolist() == [60, 1]


def test_logits_shape_and_text_dropout():
    model = tiny_length(cond_drop=1.0).eval()
    text, skel = torch.randn(3, TEXT), torch.randn(3, SKEL)
    assert model(text, skel).shape == (3, model.num_bins)
    torch.testing.assert_close(model(None, skel),
                               model(text, skel, drop_text=torch.ones(3, dtype=torch.bool)))


def test_learns_durations_from_text_and_skeleton():
    model = tiny_length(cond_drop=0.1)
    gen = torch.Generator().manual_seed(0)
    text, skel = torch.randn(3, TEXT, generator=gen), torch.randn(3, SKEL, generator=gen)
    skel[1] = skel[0]  # same skeleton, other text; the third: same text, other skeleton
    text[2] = text[0]
    seconds = torch.tensor([2.0, 5.0, 7.5])
    opt = torch.optim.Adam(model.parameters(), lr=1e-2)
    for _ in range(150):
        loss = model.loss(seconds, text, skel, generator=gen)
        opt.zero_grad()
        loss.backward()
        opt.step()
    assert torch.equal(model.mode(text, skel), seconds)
    assert model.training  # the mode is restored


def test_sampling_is_seeded_and_on_the_bins():
    model = tiny_length()
    text, skel = torch.randn(64, TEXT), torch.randn(64, SKEL)
    draw = lambda seed: model.sample(text, skel, generator=torch.Generator().manual_seed(seed))
    assert torch.equal(draw(0), draw(0))
    assert not torch.equal(draw(0), draw(1))
    bins = draw(2) / model.bin_seconds
    assert torch.equal(bins, bins.round()) and bins.min() >= 1 and bins.max() <= model.num_bins
    assert model.sample(None, skel[:2]).shape == (2,)


def test_gradients_reach_both_conditions():
    model = tiny_length()
    text = torch.randn(2, TEXT, requires_grad=True)
    skel = torch.randn(2, SKEL, requires_grad=True)
    model.eval().loss(torch.tensor([1.0, 3.0]), text, skel).backward()
    assert text.grad.abs().sum() > 0 and skel.grad.abs().sum() > 0


def test_a_lower_bound_scores_every_longer_bin():
    model = tiny_length(bin_seconds=0.5, max_seconds=4.0, cond_drop=0.0).eval()
    text, skel = torch.randn(3, TEXT), torch.randn(3, SKEL)
    seconds = torch.tensor([0.5, 2.0, 4.0])
    logp = model(text, skel).log_softmax(-1)
    censored = torch.ones(3, dtype=torch.bool)
    want = -torch.stack([logp[0].exp().sum().log(),  # at least the first bin: certain
                         logp[1, 3:].logsumexp(-1), logp[2, 7]]).mean()
    torch.testing.assert_close(model.loss(seconds, text, skel, censored=censored), want)
    mixed = torch.tensor([False, True, False])
    want = -torch.stack([logp[0, 0], logp[1, 3:].logsumexp(-1), logp[2, 7]]).mean()
    torch.testing.assert_close(model.loss(seconds, text, skel, censored=mixed), want)
    torch.testing.assert_close(model.loss(seconds, text, skel, censored=~censored),
                               model.loss(seconds, text, skel))


def test_drawn_lengths_teach_at_least_not_a_spread():
    """Clips of lengths drawn uniformly for one caption: read as known
    durations they teach a spread over the range, read as lower bounds the
    longest bin."""
    gen = torch.Generator().manual_seed(0)
    text, skel = torch.randn(1, TEXT, generator=gen), torch.randn(1, SKEL, generator=gen)
    seconds = torch.rand(64, generator=gen) * 3.0 + 1.0  # 1-4 s
    modes = {}
    for censored in (False, True):
        model = tiny_length(bin_seconds=0.5, max_seconds=4.0, cond_drop=0.0)
        opt = torch.optim.Adam(model.parameters(), lr=1e-2)
        flag = torch.full((64,), censored)
        for _ in range(150):
            loss = model.loss(seconds, text.expand(64, -1), skel.expand(64, -1),
                              censored=flag)
            opt.zero_grad()
            loss.backward()
            opt.step()
        p = model.eval()(text, skel).softmax(-1)[0]
        modes[censored] = (float(p[-1]), float(p[:-1].max()))
    top, rest = modes[True]
    assert top > 0.9 > rest
    top, rest = modes[False]
    assert top < 0.3 and rest < 0.3
