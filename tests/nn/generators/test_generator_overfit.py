"""Tiny generators memorise two code sequences on the CPU and generate them
back from their text condition."""
from __future__ import annotations

import pytest
import torch

from tests.nn.generators.generator_helpers import (NUM_CODES, SKEL, TEXT, tiny_masked,
                                                   tiny_residual)

STEPS = 300


@pytest.fixture(scope="module")
def data():
    gen = torch.Generator().manual_seed(0)
    codes = torch.randint(NUM_CODES, (2, 12, 3), generator=gen)
    text = torch.randn(2, TEXT, generator=gen)
    skel = torch.randn(1, SKEL, generator=gen).expand(2, -1)
    lengths = torch.tensor([12, 9])
    codes[1, 9:] = -1  # padding of the shorter clip
    return codes, text, skel, lengths


def fit(model, loss, steps=STEPS, lr=3e-3):
    gen = torch.Generator().manual_seed(0)
    opt = torch.optim.Adam(model.parameters(), lr=lr)
    for _ in range(steps):
        out = loss(gen)
        opt.zero_grad()
        out.loss.backward()
        opt.step()
    return out


def same_real(got, codes, lengths):
    return all(torch.equal(g[:n], c[:n]) for g, c, n in zip(got, codes, lengths.tolist()))


@pytest.fixture(scope="module")
def masked(data):
    codes, text, skel, lengths = data
    model = tiny_masked(cond_drop=0.2)
    fit(model, lambda gen: model.loss(codes, text, skel, lengths, generator=gen))
    return model


def test_masked_transformer_generates_what_it_memorised(masked, data):
    codes, text, skel, lengths = data
    for guidance in (1.0, 2.0):
        got = masked.generate(text, skel, lengths, guidance=guidance, temperature=0.0)
        assert same_real(got, codes[..., 0], lengths), guidance
        assert got[1, 9:].eq(masked.pad_id).all()
    hits = []
    for seed in range(3):  # sampling: mostly the memorised codes
        got = masked.generate(text, skel, lengths, generator=torch.Generator().manual_seed(seed))
        real = torch.arange(12) < lengths.unsqueeze(-1)
        hits.append((got == codes[..., 0])[real].float().mean())
    assert min(hits) > 0.8
    noisy = masked.generate(text, skel, lengths, temperature=0.0, choice_temperature=4.5,
                            generator=torch.Generator().manual_seed(0))
    assert same_real(noisy, codes[..., 0], lengths)  # any order of choice, the same codes
    spread = masked.generate(text, skel, lengths, temperature=0.0, spread=1.0)
    assert same_real(spread, codes[..., 0], lengths)
    swapped = masked.generate(text.flip(0), skel, lengths.flip(0), temperature=0.0)
    assert torch.equal(swapped[0, :9], codes[1, :9, 0])  # the text decides the sequence


@pytest.mark.slow
def test_residual_transformer_generates_what_it_memorised(data):
    codes, text, skel, lengths = data
    model = tiny_residual(num_quantizers=3, cond_drop=0.2)
    fit(model, lambda gen: model.loss(codes, text, skel, lengths, generator=gen))
    for guidance in (1.0, 2.0):
        got = model.generate(codes[..., 0], text, skel, lengths, guidance=guidance,
                             temperature=0.0)
        assert same_real(got, codes, lengths), guidance
        assert got[1, 9:].eq(model.pad_id).all()


def test_masked_transformer_infills_around_kept_tokens(masked, data):
    """Kept tokens stay as given, whatever they are; the others are filled
    in (here: the memorised ones back); keeping all returns them."""
    codes, text, skel, lengths = data
    known = codes[..., 0].clone()
    keep = torch.zeros_like(known, dtype=torch.bool)
    keep[:, ::3] = True
    foreign = known.masked_fill(keep, 0)  # kept tokens no training sequence has there
    got = masked.generate(text, skel, lengths, temperature=0.0, known=foreign, keep=keep)
    real = torch.arange(12) < lengths.unsqueeze(-1)
    assert got[keep & real].eq(0).all() and got[1, 9:].eq(masked.pad_id).all()
    back = masked.generate(text, skel, lengths, temperature=0.0, known=known, keep=keep)
    assert same_real(back, codes[..., 0], lengths)
    every = torch.ones_like(keep)
    assert same_real(masked.generate(text, skel, lengths, known=foreign, keep=every),
                     foreign, lengths)
