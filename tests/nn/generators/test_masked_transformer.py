"""Masked token transformer over layer-0 codes (MoMask)."""
from __future__ import annotations

import pytest
import torch

from satagraph.nn.generators import MaskedTransformer, masked_cross_entropy, top_k_filter
from tests.nn.generators.generator_helpers import (NUM_CODES, SKEL, TEXT, TREE, skeleton,
                                                   tiny_masked, tiny_skeleton_net)


def random_codes(lengths, seed=0):
    gen = torch.Generator().manual_seed(seed)
    return torch.randint(NUM_CODES, (lengths.numel(), int(lengths.max())), generator=gen)


def test_forward_shape_and_ids():
    model = tiny_masked()
    assert (model.mask_id, model.pad_id) == (NUM_CODES, NUM_CODES + 1)
    assert model.token_emb.num_embeddings == NUM_CODES + 2
    logits = model(random_codes(torch.tensor([5, 3])), torch.randn(2, TEXT), torch.randn(2, SKEL),
                   torch.tensor([5, 3]))
    assert logits.shape == (2, 5, NUM_CODES)


def test_padding_content_is_ignored(conditions):
    text, skel, lengths = conditions
    model = tiny_masked().eval()
    codes = random_codes(lengths)
    garbage = codes.clone()
    garbage[1, 7:] = 3
    garbage[2, 3:] = model.mask_id
    real = torch.arange(codes.size(1)) < lengths.unsqueeze(-1)
    a, b = model(codes, text, skel, lengths), model(garbage, text, skel, lengths)
    torch.testing.assert_close(a[real], b[real])


def test_masked_cross_entropy_reads_masked_targets_only():
    logits = torch.randn(2, 6, NUM_CODES)
    targets = torch.randint(NUM_CODES, (2, 6))
    mask = torch.tensor([[1, 0, 1, 0, 0, 1], [0, 1, 1, 0, 0, 0]], dtype=torch.bool)
    ref = masked_cross_entropy(logits, targets, mask)
    changed = targets.clone()
    changed[~mask] = (changed[~mask] + 1) % NUM_CODES
    assert torch.equal(masked_cross_entropy(logits, changed, mask), ref)
    changed[0, 0] = (targets[0, 0] + 1) % NUM_CODES
    assert not torch.equal(masked_cross_entropy(logits, changed, mask), ref)
    manual = torch.nn.functional.cross_entropy(logits[mask], targets[mask])
    torch.testing.assert_close(ref, manual)


def test_loss_scores_the_masked_positions_only(conditions):
    text, skel, lengths = conditions
    model = tiny_masked()
    codes = random_codes(lengths)
    out = model.loss(codes, text, skel, lengths, generator=torch.Generator().manual_seed(0))
    valid = torch.arange(codes.size(1)) < lengths.unsqueeze(-1)
    assert not (out.corruption.mask & ~valid).any()
    assert out.corruption.inputs[~valid].eq(model.pad_id).all()
    manual = masked_cross_entropy(out.logits, codes, out.corruption.mask)
    torch.testing.assert_close(out.loss, manual)
    # the same draws give the same loss
    again = model.loss(codes, text, skel, lengths, generator=torch.Generator().manual_seed(0))
    assert torch.equal(again.corruption.inputs, out.corruption.inputs)
    torch.testing.assert_close(again.loss, out.loss)


def test_loss_accepts_code_stacks_and_pooling(conditions):
    text, skel, lengths = conditions
    model = tiny_masked(pool=4)
    stack = torch.stack([random_codes(lengths), random_codes(lengths, 1)], -1)
    out = model.loss(stack, text, skel, lengths)
    assert out.targets.shape == (3, 3)  # ceil(10 / 4) tokens
    assert out.targets[2, 1:].eq(model.pad_id).all()  # 3 frames: one token


def test_mask_floor_raises_the_masked_share():
    model = tiny_masked(mask_floor=0.6)
    lengths = torch.full((300,), 40)
    tokens = torch.randint(NUM_CODES, (300, 40))
    mask = model.corrupt(tokens, lengths, torch.Generator().manual_seed(0)).mask
    share = mask.float().mean(-1)
    assert share.min() >= 0.6 - 1e-6
    with pytest.raises(ValueError, match="mask_floor"):
        tiny_masked(mask_floor=1.0)


def test_text_dropout_only_in_training():
    model = tiny_masked(cond_drop=0.3)
    drop = model.backbone.draw_text_drop(5000, torch.Generator().manual_seed(0))
    assert abs(drop.float().mean().item() - 0.3) < 0.03
    assert not model.eval().backbone.draw_text_drop(100).any()


def test_dropping_text_never_changes_the_skeleton_token(conditions):
    text, skel, lengths = conditions
    model = tiny_masked(cond_drop=1.0)
    seen = []
    model.backbone.condition.register_forward_hook(lambda mod, args, out: seen.append(out))
    codes = random_codes(lengths)
    model(codes, text, skel, lengths)
    model.loss(codes, text, skel, lengths)  # cond_drop 1: every text dropped
    model(codes, None, skel, lengths)
    model.eval().generate(text, skel, lengths, steps=2, guidance=3.0)
    kept, dropped, absent, guided = seen[0], seen[1], seen[2], seen[3]
    same = lambda a, b: torch.testing.assert_close(a, b, atol=1e-6, rtol=0)  # batched matmul
    for other in (dropped, absent):
        assert torch.equal(other[:, 1], kept[:, 1])
    same(guided[:3, 1], kept[:, 1])
    same(guided[3:, 1], kept[:, 1])
    null = model.backbone.condition.null_text.expand(3, -1)
    for other in (dropped, absent, guided[3:]):
        assert torch.equal(other[:, 0], null)
    same(guided[:3, 0], kept[:, 0])
    assert not torch.allclose(kept[:, 0], null)


def test_no_text_equals_dropped_text(conditions):
    text, skel, lengths = conditions
    model = tiny_masked().eval()
    codes = random_codes(lengths)
    drop = torch.ones(3, dtype=torch.bool)
    torch.testing.assert_close(model(codes, None, skel, lengths),
                               model(codes, text, skel, lengths, drop_text=drop))


def test_guidance(conditions):
    text, skel, lengths = conditions
    model = tiny_masked().eval()
    tokens = random_codes(lengths)
    cond = model(tokens, text, skel, lengths)
    uncond = model(tokens, None, skel, lengths)
    assert torch.equal(model.guided_logits(tokens, text, skel, lengths, 1.0), cond)
    torch.testing.assert_close(model.guided_logits(tokens, text, skel, lengths, 3.0),
                               uncond + 3.0 * (cond - uncond), atol=1e-5, rtol=1e-5)
    assert torch.equal(model.guided_logits(tokens, None, skel, lengths, 3.0), uncond)


@pytest.mark.parametrize("pool", [1, 3])
def test_generate_fills_every_position_and_keeps_padding(conditions, pool):
    text, skel, lengths = conditions
    model = tiny_masked(pool=pool).train()
    out = model.generate(text, skel, lengths, steps=4, generator=torch.Generator().manual_seed(0))
    assert model.training  # the mode is restored
    real = torch.arange(int(lengths.max())) < lengths.unsqueeze(-1)
    assert out.shape == (3, 10) and out.dtype == torch.long
    assert out[real].ge(0).all() and out[real].lt(NUM_CODES).all()
    assert out[~real].eq(model.pad_id).all()
    if pool > 1:  # one code per token: constant over each window of frames
        assert torch.equal(out[0, :9].view(3, 3), out[0, :9:3].unsqueeze(-1).expand(3, 3))


def test_generate_is_seeded(conditions):
    text, skel, lengths = conditions
    model = tiny_masked()
    run = lambda seed, text=text: model.generate(text, skel, lengths,
                                                 generator=torch.Generator().manual_seed(seed))
    assert torch.equal(run(0), run(0))
    assert not torch.equal(run(0), run(1))
    assert torch.equal(run(2, None), run(2, None))


def test_greedy_single_step_is_the_argmax_of_all_masked(conditions):
    text, skel, lengths = conditions
    model = tiny_masked().eval()
    out = model.generate(text, skel, lengths, steps=1, guidance=1.0, temperature=0.0)
    masked = torch.full((3, 10), model.mask_id)
    expected = model(masked, text, skel, lengths).argmax(-1)
    real = torch.arange(10) < lengths.unsqueeze(-1)
    assert torch.equal(out[real], expected[real])


def test_learned_positions_have_a_maximum_length(conditions):
    text, skel, lengths = conditions
    model = tiny_masked(positions="learned", max_length=8)
    with pytest.raises(ValueError, match="max_length"):
        model(random_codes(lengths), text, skel, lengths)
    assert model(random_codes(lengths)[:, :8], text, skel, lengths.clamp(max=8)).shape == (3, 8, 16)
    with pytest.raises(ValueError):
        MaskedTransformer(NUM_CODES, TEXT, SKEL, positions="learned")


def test_gradients_reach_the_skeleton_embedding():
    net = tiny_skeleton_net()
    model = tiny_masked()
    x, edge_index = skeleton(TREE)
    f_skel = net(x, edge_index).expand(2, -1)
    lengths = torch.tensor([6, 4])
    out = model.loss(random_codes(lengths), torch.randn(2, TEXT), f_skel, lengths)
    out.loss.backward()
    for name, param in net.named_parameters():
        assert param.grad is not None and param.grad.abs().sum() > 0, name
    assert model.backbone.condition.skel_proj.weight.grad.abs().sum() > 0


@pytest.mark.parametrize("floor, spread", [(0.0, 0.0), (0.5, 0.0), (0.0, 1.0)])
def test_decoding_steps_remask_on_the_training_schedule(conditions, floor, spread):
    text, skel, lengths = conditions
    model = tiny_masked(mask_floor=floor)
    masked_counts = []
    model.token_emb.register_forward_hook(
        lambda mod, args, out: masked_counts.append(args[0].eq(model.mask_id).sum(-1)))
    model.generate(text, skel, lengths, steps=5, guidance=1.0, spread=spread)
    assert len(masked_counts) == 5
    assert torch.equal(masked_counts[0], lengths)  # all masked at first
    for count in masked_counts:
        assert (count >= torch.round(floor * lengths).clamp(min=1)).all()
    if floor == 0.0:
        assert masked_counts[-1].tolist() == [1, 1, 1]


def test_incomplete_code_stacks_are_refused(conditions):
    text, skel, lengths = conditions
    model = tiny_masked()
    codes = random_codes(lengths)
    codes[0, 2] = -1
    with pytest.raises(ValueError, match="dropped RVQ layers"):
        model.loss(codes, text, skel, lengths)
    codes[0, 2] = 0
    codes[1, 8:] = -1  # padding may hold anything
    model.loss(codes, text, skel, lengths)


def test_generate_in_windows_continues_each_window_from_the_one_before(conditions):
    """With a window, a longer sequence is generated window after window:
    the first window is what a sequence of that length alone gives, each
    later window is the infilling of its own length after the tokens of the
    window before that it overlaps (greedy, so exactly), a kept token stays
    in every window, sequences no longer than the window are generated whole
    (the same draws as without a window) and the padding stays."""
    from satagraph.nn.generators.codes import continuation_spans
    text, skel, _ = conditions
    model = tiny_masked(pool=2).eval()
    lengths = torch.tensor([30, 12, 21])
    greedy = dict(steps=3, guidance=2.0, temperature=0.0)
    known = torch.zeros(3, 15, dtype=torch.long)
    keep = torch.zeros(3, 15, dtype=torch.bool)
    known[0, 11], keep[0, 11] = 5, True
    out = model.generate(text, skel, lengths, window=12, known=known, keep=keep, **greedy)
    assert out.shape == (3, 30) and out[0, 22] == 5
    tokens = out[:, ::2]
    for b in (0, 2):
        spans = continuation_spans(int(lengths[b] + 1) // 2, 6)
        assert len(spans) >= 3
        for start, stop, context in spans:
            held = keep[b:b + 1, start:stop].clone()
            held[:, :context] = True
            alone = model.generate(text[b:b + 1], skel[b:b + 1],
                                   torch.tensor([min(2 * stop, int(lengths[b])) - 2 * start]),
                                   known=tokens[b:b + 1, start:stop], keep=held, **greedy)
            assert torch.equal(alone[0, ::2], tokens[b, start:stop])
    short = model.generate(text[1:2], skel[1:2], lengths[1:2], **greedy)
    assert torch.equal(out[1, :12], short[0])
    assert out[1, 12:].eq(model.pad_id).all() and out[2, 21:].eq(model.pad_id).all()
    assert not torch.equal(out, model.generate(text, skel, lengths, known=known, keep=keep,
                                               **greedy))
    seeded = lambda window: model.generate(text, skel, lengths, window=window,
                                           generator=torch.Generator().manual_seed(3))
    assert torch.equal(seeded(30), seeded(None))


def test_candidates_guide_draws_the_conditional_choice_among_the_guided_top_k(conditions):
    """With ``guide="candidates"`` a greedy single step takes, at every
    position, the conditional logits' best code among the guided logits'
    top k; an unknown guide is refused."""
    text, skel, lengths = conditions
    model = tiny_masked().eval()
    out = model.generate(text, skel, lengths, steps=1, guidance=8.0, temperature=0.0,
                         topk_ratio=0.25, guide="candidates")
    masked = torch.full((3, 10), model.mask_id)
    cond, uncond = model(masked, text, skel, lengths), model(masked, None, skel, lengths)
    allowed = top_k_filter(uncond + 8.0 * (cond - uncond), 0.25) > float("-inf")
    expected = cond.masked_fill(~allowed, float("-inf")).argmax(-1)
    real = torch.arange(10) < lengths.unsqueeze(-1)
    assert torch.equal(out[real], expected[real])
    greedy = model.generate(text, skel, lengths, steps=1, guidance=8.0, temperature=0.0)
    assert not torch.equal(out, greedy)
    with pytest.raises(ValueError, match="unknown guide"):
        model.generate(text, skel, lengths, guide="guided")


def test_text_score_is_the_masked_tokens_mean_log_ratio_with_and_without_text(conditions):
    """One round: the mean, over the masked tokens, of the log-probability
    of each true token with the text minus without it, on one random
    pattern shared by every row; equal rows score equally."""
    text, skel, lengths = conditions
    model = tiny_masked(pool=1).eval()
    codes = random_codes(lengths)
    codes[1] = codes[0]
    same = torch.cat([text[:1], text[:1], text[2:]])
    got = model.text_score(codes, same, skel[[0, 0, 2]], torch.tensor([10, 10, 3]), rounds=1,
                           generator=torch.Generator().manual_seed(4))
    assert got.shape == (3,) and got[0] == got[1]
    pattern = torch.rand((1, codes.size(1)), generator=torch.Generator().manual_seed(4))
    for row, length in ((0, 10), (2, 3)):
        masked = pattern[0, :length].argsort()[:round(0.5 * length)]
        inputs = codes[row:row + 1, :length].clone()
        inputs[0, masked] = model.mask_id
        args = (inputs, same[row:row + 1], skel[[0, 0, 2]][row:row + 1], torch.tensor([length]))
        cond = model(*args).log_softmax(-1)[0]
        uncond = model(*args, drop_text=torch.tensor([True])).log_softmax(-1)[0]
        true = codes[row, :length]
        gain = (cond - uncond).gather(-1, true[:, None])[:, 0]
        torch.testing.assert_close(got[row], gain[masked].mean())


def test_text_score_prefers_codes_the_text_was_trained_to_predict():
    """A model taught to emit code 3 under one text and code 5 under
    another scores each text's own codes higher (gradient descent on the
    masked loss, seeded)."""
    torch.manual_seed(0)
    model = tiny_masked(pool=1, cond_drop=0.3)
    texts = torch.randn(2, TEXT)
    skel = torch.randn(1, SKEL).expand(2, -1)
    lengths = torch.tensor([8, 8])
    codes = torch.tensor([[3] * 8, [5] * 8])
    opt = torch.optim.Adam(model.parameters(), lr=3e-3)
    gen = torch.Generator().manual_seed(0)
    for _ in range(150):
        opt.zero_grad()
        model.loss(codes, texts, skel, lengths, generator=gen).loss.backward()
        opt.step()
    own = model.text_score(codes, texts, skel, lengths, generator=torch.Generator().manual_seed(1))
    swapped = model.text_score(codes.flip(0), texts, skel, lengths,
                               generator=torch.Generator().manual_seed(1))
    assert (own > swapped).all() and (own > 0).all()
