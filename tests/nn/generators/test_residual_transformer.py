"""Residual token transformer over RVQ layers 1..Q-1 (MoMask)."""
from __future__ import annotations

import pytest
import torch

from satagraph.nn import RVQBottleneck
from satagraph.nn.generators import ResidualTransformer, top_k_filter
from tests.nn.generators.generator_helpers import (NUM_CODES, SKEL, TEXT, TREE, skeleton,
                                                   tiny_residual, tiny_skeleton_net)

Q = 4


def random_stack(lengths, seed=0):
    gen = torch.Generator().manual_seed(seed)
    return torch.randint(NUM_CODES, (lengths.numel(), int(lengths.max()), Q), generator=gen)


def test_forward_shape():
    model = tiny_residual(Q)
    lengths = torch.tensor([5, 2])
    logits = model(random_stack(lengths), torch.tensor([1, 3]), torch.randn(2, TEXT),
                   torch.randn(2, SKEL), lengths)
    assert logits.shape == (2, 5, NUM_CODES)
    with pytest.raises(ValueError, match="2 quantizers"):
        tiny_residual(1)


def test_logits_depend_only_on_the_layers_below(conditions):
    text, skel, lengths = conditions
    model = tiny_residual(Q).eval()
    codes = random_stack(lengths)
    layer = torch.tensor([1, 2, 3])
    ref = model(codes, layer, text, skel, lengths)
    above = codes.clone()
    for b, q in enumerate(layer.tolist()):
        above[b, :, q:] = (above[b, :, q:] + 5) % NUM_CODES
    assert torch.equal(model(above, layer, text, skel, lengths), ref)
    below = codes.clone()
    below[:, :, 0] = (below[:, :, 0] + 5) % NUM_CODES
    assert not torch.allclose(model(below, layer, text, skel, lengths), ref)


def test_loss_targets_the_drawn_layer(conditions):
    text, skel, lengths = conditions
    model = tiny_residual(Q)
    codes = random_stack(lengths)
    out = model.loss(codes, text, skel, lengths, generator=torch.Generator().manual_seed(0))
    assert out.layer.min() >= 1 and out.layer.max() <= Q - 1
    for b, q in enumerate(out.layer.tolist()):
        n = int(lengths[b])
        assert torch.equal(out.targets[b, :n], codes[b, :n, q])
    forced = model.loss(codes, text, skel, lengths, layer=torch.tensor([3, 3, 3]))
    assert forced.layer.tolist() == [3, 3, 3]
    # padding never counts: changing codes past the lengths keeps the loss
    model.eval()
    layer = torch.tensor([2, 1, 3])
    ref = model.loss(codes, text, skel, lengths, layer=layer).loss
    garbage = codes.clone()
    garbage[1, 7:] = 0
    garbage[2, 3:] = 1
    torch.testing.assert_close(model.loss(garbage, text, skel, lengths, layer=layer).loss, ref)


def test_generate_fills_the_layers_above_the_base(conditions):
    text, skel, lengths = conditions
    model = tiny_residual(Q).train()
    base = random_stack(lengths)[..., 0]
    out = model.generate(base, text, skel, lengths, generator=torch.Generator().manual_seed(0))
    assert model.training
    real = torch.arange(10) < lengths.unsqueeze(-1)
    assert out.shape == (3, 10, Q)
    assert torch.equal(out[..., 0][real], base[real])
    assert out[real].ge(0).all() and out[real].lt(NUM_CODES).all()
    assert out[~real].eq(model.pad_id).all()
    assert model.generate(base, text, skel, lengths, num_quantizers=2).shape == (3, 10, 2)


def test_generate_is_seeded_and_accepts_no_text(conditions):
    text, skel, lengths = conditions
    model = tiny_residual(Q)
    base = random_stack(lengths)[..., 0]
    run = lambda seed, text=text: model.generate(base, text, skel, lengths,
                                                 generator=torch.Generator().manual_seed(seed))
    assert torch.equal(run(0), run(0))
    assert not torch.equal(run(0), run(1))
    assert torch.equal(run(3, None), run(3, None))


def test_generate_with_pooled_tokens(conditions):
    text, skel, lengths = conditions
    model = tiny_residual(Q, pool=2)
    base = random_stack(lengths)[..., 0].repeat_interleave(2, 1)[:, :10]  # constant pairs
    out = model.generate(base, text, skel, lengths)
    real = torch.arange(10) < lengths.unsqueeze(-1)
    assert torch.equal(out[..., 0][real], base[real])
    assert torch.equal(out[0, 0::2], out[0, 1::2])  # one stack per token of two frames


def test_guidance(conditions):
    text, skel, lengths = conditions
    model = tiny_residual(Q).eval()
    codes, layer = random_stack(lengths), torch.tensor([1, 2, 3])
    cond = model(codes, layer, text, skel, lengths)
    uncond = model(codes, layer, None, skel, lengths)
    assert torch.equal(model.guided_logits(codes, layer, text, skel, lengths, 1.0), cond)
    torch.testing.assert_close(model.guided_logits(codes, layer, text, skel, lengths, 5.0),
                               uncond + 5.0 * (cond - uncond), atol=1e-5, rtol=1e-5)


def test_dropping_text_never_changes_the_skeleton_token(conditions):
    text, skel, lengths = conditions
    model = tiny_residual(Q, cond_drop=1.0)
    seen = []
    model.backbone.condition.skel_proj.register_forward_hook(lambda m, a, out: seen.append(out))
    codes = random_stack(lengths)
    model(codes, torch.tensor([1, 1, 1]), text, skel, lengths)
    out = model.loss(codes, text, skel, lengths)
    assert out.drop_text.all()
    assert torch.equal(seen[1], seen[0])


def test_codebooks_initialise_the_code_tables():
    torch.manual_seed(0)
    rvq = RVQBottleneck(8, 32, num_quantizers=Q, codebook_size=NUM_CODES, kmeans_init=False)
    assert rvq.rvq.codebooks.abs().sum() > 0
    model = tiny_residual(Q)
    model.load_codebooks(rvq.rvq.codebooks, freeze=True)
    assert torch.equal(model.code_embed, rvq.rvq.codebooks)
    assert not model.code_embed.requires_grad
    # the summed input of layer q is the partial quantised latent
    codes = torch.randint(NUM_CODES, (1, 5, Q))
    partial = model.embed(codes, torch.tensor([2]), torch.ones(1, 5, dtype=torch.bool))
    expected = rvq.rvq.codebooks[0][codes[0, :, 0]] + rvq.rvq.codebooks[1][codes[0, :, 1]]
    torch.testing.assert_close(partial[0], expected)
    with pytest.raises(ValueError, match="codebooks"):
        model.load_codebooks(torch.zeros(Q, NUM_CODES, 7))


def test_unshared_output_heads():
    model = ResidualTransformer(NUM_CODES, Q, TEXT, SKEL, hidden_channels=16, heads=2,
                                num_layers=1, share_weights=False)
    assert model.out_weight is not None and model.out_weight.shape == model.code_embed.shape


def test_gradients_reach_the_skeleton_embedding():
    net = tiny_skeleton_net()
    model = tiny_residual(Q)
    x, edge_index = skeleton(TREE)
    lengths = torch.tensor([6, 4])
    out = model.loss(random_stack(lengths), torch.randn(2, TEXT),
                     net(x, edge_index).expand(2, -1), lengths)
    out.loss.backward()
    for name, param in net.named_parameters():
        assert param.grad is not None and param.grad.abs().sum() > 0, name


def test_generate_in_windows_takes_each_span_from_its_windows_own_fill(conditions):
    """With a window, each sequence's kept span of every window holds the
    codes a whole-sequence fill of that window alone gives (argmax, so
    exactly); sequences no longer than the window are filled whole, the
    padding stays, and a window as long as the batch changes nothing."""
    from satagraph.nn.generators.codes import window_spans
    text, skel, _ = conditions
    model = tiny_residual(Q, pool=2).eval()
    lengths = torch.tensor([30, 12, 21])
    base = random_stack(lengths)[..., 0].repeat_interleave(2, 1)[:, :30]
    fill = dict(guidance=3.0, temperature=0.0)
    out = model.generate(base, text, skel, lengths, window=12, **fill)
    assert out.shape == (3, 30, Q)
    assert torch.equal(out[1, :12], model.generate(base[1:2, :12], text[1:2], skel[1:2],
                                                   torch.tensor([12]), **fill)[0])
    for b in (0, 2):
        n = int(lengths[b])
        assert len(window_spans(n, 12, 2)) >= 2
        for start, stop, keep, end in window_spans(n, 12, 2):
            alone = model.generate(base[b:b + 1, start:stop], text[b:b + 1], skel[b:b + 1],
                                   torch.tensor([stop - start]), **fill)[0]
            assert torch.equal(out[b, keep:end], alone[keep - start:end - start])
    real = torch.arange(30) < lengths.unsqueeze(-1)
    assert out[~real].eq(model.pad_id).all() and torch.equal(out[..., 0][real], base[real])
    assert torch.equal(model.generate(base, text, skel, lengths, window=30, **fill),
                       model.generate(base, text, skel, lengths, **fill))
    assert not torch.equal(out, model.generate(base, text, skel, lengths, **fill))


def test_position_jitter_starts_each_training_sequence_at_a_drawn_position(conditions):
    """In training, each sequence's tokens read the sinusoids from a start
    drawn in ``0..position_jitter`` (the same draw again gives the same
    positions); in eval mode, and with no jitter, they start at 0."""
    from satagraph.nn.layers.spatio_temporal import sinusoidal_positions
    model = tiny_residual(Q, position_jitter=7)
    backbone = model.backbone
    h = torch.zeros(3, 10, backbone.hidden_channels)
    table = sinusoidal_positions(17, backbone.hidden_channels)
    torch.manual_seed(4)
    drawn = backbone.token_positions(h)
    torch.manual_seed(4)
    start = torch.randint(8, (3, 1))
    assert drawn.shape == (3, 10, backbone.hidden_channels)
    for b in range(3):
        assert torch.equal(drawn[b], table[int(start[b]):int(start[b]) + 10])
    starts = set()
    for seed in range(20):
        torch.manual_seed(seed)
        positions = backbone.token_positions(h)
        starts |= {int(torch.cdist(positions[b, :1], table).argmin()) for b in range(3)}
    assert starts == set(range(8))
    model.eval()
    assert torch.equal(backbone.token_positions(h), table[:10])
    assert torch.equal(tiny_residual(Q).train().backbone.token_positions(h), table[:10])
    with pytest.raises(ValueError, match="position_jitter"):
        tiny_residual(Q, position_jitter=-1)


def test_candidates_guide_takes_the_conditional_best_among_the_guided_top_k(conditions):
    """Greedy residual filling with ``guide="candidates"``: each layer's code
    is the conditional logits' best among the guided logits' top k, given
    the layers below it."""
    text, skel, _ = conditions
    model = tiny_residual(3).eval()
    lengths = torch.tensor([6, 4, 5])
    base = random_stack(lengths)[..., 0]
    fill = dict(guidance=4.0, temperature=0.0, topk_ratio=0.25)
    out = model.generate(base, text, skel, lengths, guide="candidates", **fill)
    layer = torch.ones(3, dtype=torch.long)
    codes = torch.full((3, 6, 3), model.pad_id)
    codes[..., 0] = base.masked_fill(~(torch.arange(6) < lengths.unsqueeze(-1)), model.pad_id)
    cond = model(codes, layer, text, skel, lengths)
    uncond = model(codes, layer, None, skel, lengths)
    allowed = top_k_filter(uncond + 4.0 * (cond - uncond), 0.25) > float("-inf")
    expected = cond.masked_fill(~allowed, float("-inf")).argmax(-1)
    real = torch.arange(6) < lengths.unsqueeze(-1)
    assert torch.equal(out[..., 1][real], expected[real])
    assert not torch.equal(out, model.generate(base, text, skel, lengths, **fill))
