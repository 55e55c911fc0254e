"""SATA modules: shapes, gradients, ablation switches, batch invariances,
overfitting, bottlenecks and the paper-size parameter count."""
from __future__ import annotations

from typing import List, Sequence, Tuple

import pytest
import roma
import torch

from satagraph.data import collate_clips
from satagraph.data.clip import MotionClip
from satagraph.losses import MotionLoss
from satagraph.nn import (LOCAL_CONVS, SATA, local_conv_names, register_local_conv, ConcatProjection, RVQBottleneck,
                          SATADecoder, SATAEncoder, SemanticModulation, SinusoidalEncoding,
                          SpatioTemporalBlock, VAEBottleneck, build_local_conv,
                          gaussian_kl, sinusoidal_positions)
from satagraph.ops.rotation import matrix_to_rotation_6d

D_T = 8
TINY = dict(hidden_channels=16, heads=2, ff_channels=32, num_blocks=1, dropout=0.0,
            semantic_channels=D_T, latent_channels=8)
ABLATIONS = [dict(), dict(local_conv=None), dict(spatial_attention=False),
             dict(temporal=False), dict(fusion=False), dict(use_text=False),
             dict(semantic_channels=0),
             dict(local_conv=None, spatial_attention=False, temporal=False, fusion=False)]


# ------------------------------------------------------------------ helpers
def random_parents(num_joints: int, gen: torch.Generator) -> torch.Tensor:
    parents = [-1] + [int(torch.randint(0, j, (1,), generator=gen)) for j in range(1, num_joints)]
    return torch.tensor(parents)


def edge_features(parents: torch.Tensor) -> torch.Tensor:
    """(depth, reverse depth) of each bone's child, both directions."""
    num = parents.numel()
    depth, height = [0] * num, [0] * num
    for j in range(1, num):
        depth[j] = depth[int(parents[j])] + 1
    for j in range(num - 1, 0, -1):
        p = int(parents[j])
        height[p] = max(height[p], height[j] + 1)
    feat = torch.tensor([[depth[j], height[j]] for j in range(1, num)], dtype=torch.float)
    return torch.cat([feat, feat])


def random_clip(frames: int, joints: int, seed: int, semantic: int = D_T) -> MotionClip:
    gen = torch.Generator().manual_seed(seed)
    parents = random_parents(joints, gen)
    dyn = torch.randn(frames, joints, 22, generator=gen)
    dyn[..., :6] = matrix_to_rotation_6d(roma.rotvec_to_rotmat(
        0.5 * torch.randn(frames, joints, 3, generator=gen)))
    dyn[..., 21] = (torch.rand(frames, joints, generator=gen) > 0.5).float()
    return MotionClip(dynamic=dyn, root=torch.randn(frames, 4, generator=gen),
                      static=0.3 * torch.randn(joints, 6, generator=gen),
                      semantic=torch.randn(joints, semantic, generator=gen),
                      parents=parents, edge_attr=edge_features(parents),
                      meta={"height": 1.0, "seed": seed})


def make_clips(specs: Sequence[Tuple[int, int]], seed: int = 0,
               semantic: int = D_T) -> List[MotionClip]:
    return [random_clip(t, j, seed + i, semantic) for i, (t, j) in enumerate(specs)]


SPECS = [(5, 4), (3, 7), (6, 5)]


@pytest.fixture
def batch():
    return collate_clips(make_clips(SPECS))


def node_slices(clips: Sequence[MotionClip]) -> List[slice]:
    out, start = [], 0
    for c in clips:
        out.append(slice(start, start + c.num_frames * c.num_joints))
        start += c.num_frames * c.num_joints
    return out


def frame_slices(clips: Sequence[MotionClip]) -> List[slice]:
    out, start = [], 0
    for c in clips:
        out.append(slice(start, start + c.num_frames))
        start += c.num_frames
    return out


def per_clip(out, clips, idx: int):
    nodes, frames = node_slices(clips)[idx], frame_slices(clips)[idx]
    return {"q": out["q"][nodes], "c": out["c"][nodes], "r": out["r"][frames],
            "z": out["z"][frames]}


def assert_finite_grads(module: torch.nn.Module) -> None:
    for name, p in module.named_parameters():
        if p.requires_grad:
            assert p.grad is not None, f"no gradient for {name}"
            assert torch.isfinite(p.grad).all(), f"non-finite gradient for {name}"


def output_sum(out) -> torch.Tensor:
    total = out["q"].sum() + out["r"].sum() + out["c"].sum()
    return total + sum(out[k] for k in ("kl", "commit") if k in out)


# ------------------------------------------------------------- modulation
def test_sinusoidal_encoding():
    enc = SinusoidalEncoding(6, num_frequencies=4)
    x = torch.randn(5, 6)
    y = enc(x)
    assert y.shape == (5, enc.out_channels) == (5, 6 * 9)
    assert torch.equal(y[:, :6], x)
    assert SinusoidalEncoding(6, 4, include_input=False)(x).shape == (5, 48)


@pytest.mark.parametrize("use_text", [True, False])
def test_semantic_modulation_shapes_and_grads(use_text):
    mod = SemanticModulation(10, 16, semantic_channels=D_T, use_text=use_text)
    x = torch.randn(12, 10, requires_grad=True)
    static, semantic = torch.randn(4, 6), torch.randn(4, D_T)
    index = torch.arange(12) % 4
    out = mod(x, static, semantic, index)
    assert out.shape == (12, 16)
    out.pow(2).sum().backward()
    assert_finite_grads(mod)
    assert (mod.phi_t is not None) == use_text
    per_node = mod(x, static[index], semantic[index])
    torch.testing.assert_close(per_node, out)


def test_semantic_modulation_rejects_wrong_semantic_width():
    mod = SemanticModulation(10, 16, semantic_channels=D_T)
    with pytest.raises(ValueError, match="semantic"):
        mod(torch.randn(3, 10), torch.randn(3, 6), torch.randn(3, D_T + 1))


def test_modulation_gate_closed_returns_projection():
    mod = SemanticModulation(10, 16, semantic_channels=D_T)
    torch.nn.init.zeros_(mod.gate.weight)
    torch.nn.init.constant_(mod.gate.bias, -1e4)
    x, static, sem = torch.randn(5, 10), torch.randn(5, 6), torch.randn(5, D_T)
    torch.testing.assert_close(mod(x, static, sem), mod.phi_m(x))


def test_concat_projection():
    proj = ConcatProjection(10, 16)
    out = proj(torch.randn(12, 10), torch.randn(4, 6), None, torch.arange(12) % 4)
    assert out.shape == (12, 16)


# ----------------------------------------------------------------- blocks
def test_sinusoidal_positions():
    pe = sinusoidal_positions(7, 6)
    assert pe.shape == (7, 6)
    torch.testing.assert_close(pe[0], torch.tensor([0.0, 1.0] * 3))
    assert sinusoidal_positions(3, 5).shape == (3, 5)


@pytest.mark.parametrize("name", list(LOCAL_CONVS) + [None])
def test_local_conv_names(name, batch):
    conv = build_local_conv(name, 16, heads=2, edge_dim=16)
    assert (conv is None) == (name is None)
    block = SpatioTemporalBlock(16, heads=2, ff_channels=32, dropout=0.0, local_conv=name)
    x = torch.randn(batch.num_nodes, 16)
    out = block(x, batch)
    assert out.shape == x.shape and torch.isfinite(out).all()
    out.pow(2).sum().backward()
    assert_finite_grads(block)


def test_unknown_local_conv():
    with pytest.raises(ValueError, match="unknown local conv .*register_local_conv"):
        build_local_conv("sage", 16)


def test_a_registered_local_conv_is_a_layer_name(batch, monkeypatch):
    """Any PyG layer becomes a ``model.local_conv`` name; one whose forward
    takes edge features gets them."""
    from torch_geometric.nn import GraphConv, ResGatedGraphConv
    from satagraph.nn.layers import local_conv
    monkeypatch.setattr(local_conv, "_BUILDERS", dict(local_conv._BUILDERS))
    register_local_conv("graph_t", lambda channels, heads, edge_dim, act:
                        GraphConv(channels, channels))
    register_local_conv("resgated_t", lambda channels, heads, edge_dim, act:
                        ResGatedGraphConv(channels, channels, edge_dim=edge_dim))
    assert {"graph_t", "resgated_t"} <= set(local_conv_names())
    with pytest.raises(ValueError, match="registered already"):
        register_local_conv("GINE", lambda *args: None)
    for name, cls in (("graph_t", GraphConv), ("resgated_t", ResGatedGraphConv)):
        block = SpatioTemporalBlock(16, heads=2, ff_channels=32, dropout=0.0, local_conv=name)
        assert any(isinstance(m, cls) for m in block.modules())
        out = block(torch.randn(batch.num_nodes, 16), batch)
        assert torch.isfinite(out).all()
        out.pow(2).sum().backward()
        assert_finite_grads(block)


def test_a_registered_local_conv_of_another_width_is_refused(monkeypatch):
    """A registered layer concatenating its heads (``GATConv(channels,
    channels, heads=heads)``) was a bare 'The size of tensor a (64) must
    match the size of tensor b (32)' traceback from the block's residual sum
    at the first batch (``satagraph train``: exit code 1, after the data was
    read); it is one line naming the layer when the model is built. The probe
    draws no random numbers and leaves the layer in training mode."""
    from torch_geometric.nn import GATConv
    from satagraph.nn.layers import local_conv
    monkeypatch.setattr(local_conv, "_BUILDERS", dict(local_conv._BUILDERS))
    register_local_conv("wide_t", lambda channels, heads, edge_dim, act:
                        GATConv(channels, channels, heads=heads, edge_dim=edge_dim))
    with pytest.raises(ValueError, match=r"^local conv 'wide_t' maps 16 channels per node "
                       r"to 32: its register_local_conv builder must return"):
        SpatioTemporalBlock(16, heads=2, ff_channels=32, local_conv="wide_t")
    register_local_conv("gat_t", lambda channels, heads, edge_dim, act:
                        GATConv(channels, channels // heads, heads=heads,
                                edge_dim=edge_dim, dropout=0.5))
    torch.manual_seed(0)
    conv = build_local_conv("gat_t", 16, heads=2, edge_dim=16)
    after = torch.rand(3)
    torch.manual_seed(0)
    GATConv(16, 8, heads=2, edge_dim=16, dropout=0.5)
    assert torch.equal(torch.rand(3), after) and conv.training


@pytest.mark.parametrize("local_conv", ["gine", None])
@pytest.mark.parametrize("attention", [True, False])
@pytest.mark.parametrize("temporal", [True, False])
def test_block_switches(local_conv, attention, temporal, batch):
    block = SpatioTemporalBlock(16, heads=2, ff_channels=32, dropout=0.0,
                                local_conv=local_conv, spatial_attention=attention,
                                temporal=temporal)
    x = torch.randn(batch.num_nodes, 16, requires_grad=True)
    out = block(x, batch)
    assert out.shape == x.shape
    if local_conv is None and not attention and not temporal:
        assert torch.equal(out, x)  # everything off: identity
        return
    out.pow(2).sum().backward()
    assert_finite_grads(block)
    assert (block.temporal is None) != temporal


# -------------------------------------------------------- encoder/decoder
def test_encoder_decoder_shapes(batch):
    enc = SATAEncoder(hidden_channels=16, heads=2, ff_channels=32, num_blocks=2,
                      dropout=0.0, semantic_channels=D_T)
    dec = SATADecoder(latent_channels=16, hidden_channels=16, heads=2, ff_channels=32,
                      num_blocks=2, dropout=0.0, semantic_channels=D_T)
    z = enc(batch)
    assert z.shape == (batch.root.shape[0], 16)
    out = dec(z, batch)
    assert out["q"].shape == (batch.num_nodes, 6)
    assert out["r"].shape == (batch.root.shape[0], 4)
    assert out["c"].shape == (batch.num_nodes, 1)
    with pytest.raises(ValueError, match="latents"):
        dec(z[:-1], batch)


# ------------------------------------------------------------------- SATA
@pytest.mark.parametrize("bottleneck", ["vae", "rvq"])
def test_sata_forward_shapes(bottleneck, batch):
    model = SATA(bottleneck=bottleneck, codebook_size=16, **TINY)
    out = model(batch)
    num_frames = batch.root.shape[0]
    assert out["q"].shape == (batch.num_nodes, 6)
    assert out["r"].shape == (num_frames, 4)
    assert out["c"].shape == (batch.num_nodes, 1)
    assert out["z"].shape == (num_frames, 8)
    if bottleneck == "vae":
        assert {"kl", "mu", "logvar"} <= set(out)
    else:
        assert out["codes"].shape == (num_frames, 6) and out["commit"].ndim == 0


@pytest.mark.parametrize("options", ABLATIONS, ids=lambda o: ",".join(o) or "full")
@pytest.mark.parametrize("bottleneck", ["vae", "rvq"])
def test_sata_gradients(options, bottleneck):
    clips = make_clips(SPECS, semantic=0 if options.get("semantic_channels") == 0 else D_T)
    batch = collate_clips(clips)
    model = SATA(bottleneck=bottleneck, codebook_size=16, quantize_dropout=0.0,
                 **dict(TINY, **options)).train()
    out = model(batch)
    output_sum(out).backward()
    assert_finite_grads(model)


def test_code_pool_holds_each_code_over_its_frames_within_each_clip():
    """``code_pool=2``: codes and latents the same over each pair of a
    clip's frames (the last frame of an odd clip alone), never across two
    clips; a pooled model's gradients reach its encoder; the VAE refuses it."""
    clips = make_clips(SPECS)
    batch = collate_clips(clips)
    model = SATA(bottleneck="rvq", codebook_size=16, quantize_dropout=0.0, code_pool=2,
                 **TINY).train()
    out = model(batch)
    group = torch.tensor([0, 0, 1, 1, 2, 3, 3, 4, 5, 5, 6, 6, 7, 7])  # clips of 5, 3, 6 frames
    for key in ("codes", "z"):
        for g in group.unique():
            rows = out[key][group == g]
            assert (rows == rows[0]).all()
    output_sum(out).backward()
    assert_finite_grads(model)
    with pytest.raises(ValueError, match="code_pool=2"):
        SATA(bottleneck="vae", code_pool=2, **TINY)


def test_decode_on_another_skeleton():
    source = collate_clips(make_clips([(5, 4), (3, 7)]))
    target = collate_clips(make_clips([(5, 9), (3, 3)], seed=10))
    model = SATA(**TINY).eval()
    out = model(source, target)
    assert out["q"].shape == (target.num_nodes, 6)
    assert out["r"].shape == (8, 4)


@pytest.mark.parametrize("bottleneck", ["vae", "rvq"])
def test_clip_order_invariance(bottleneck):
    clips = make_clips(SPECS)
    model = SATA(bottleneck=bottleneck, codebook_size=16, **TINY)
    model.train()
    model(collate_clips(clips))  # RVQ: k-means init of the codebooks
    model.eval()
    order = [2, 0, 1]
    permuted = [clips[i] for i in order]
    with torch.no_grad():
        out = model(collate_clips(clips))
        out_p = model(collate_clips(permuted))
    for new, old in enumerate(order):
        a, b = per_clip(out, clips, old), per_clip(out_p, permuted, new)
        for key in a:
            torch.testing.assert_close(a[key], b[key], atol=1e-5, rtol=1e-5)


def test_clip_independence():
    clips = make_clips(SPECS)
    model = SATA(**TINY).eval()
    changed = list(clips)
    changed[1] = random_clip(9, 7, seed=99)  # other features, longer clip
    changed[2] = random_clip(2, 3, seed=98)
    with torch.no_grad():
        out = model(collate_clips(clips))
        out_c = model(collate_clips(changed))
    a, b = per_clip(out, clips, 0), per_clip(out_c, changed, 0)
    for key in a:
        torch.testing.assert_close(a[key], b[key], atol=1e-5, rtol=1e-5)


@pytest.mark.slow
def test_tiny_model_overfits_one_batch():
    torch.manual_seed(0)
    batch = collate_clips(make_clips([(6, 4), (4, 5)]))
    model = SATA(hidden_channels=32, heads=2, ff_channels=64, num_blocks=1, dropout=0.0,
                 semantic_channels=D_T, latent_channels=16).train()
    criterion = MotionLoss(kl=0.0)
    opt = torch.optim.Adam(model.parameters(), lr=3e-3)
    threads = torch.get_num_threads()
    torch.set_num_threads(1)  # tiny tensors: threads only contend
    try:
        losses = []
        for _ in range(300):
            loss = criterion(model(batch), batch)["loss"]
            opt.zero_grad()
            loss.backward()
            opt.step()
            losses.append(loss.item())
            if losses[-1] < losses[0] / 10:
                break
    finally:
        torch.set_num_threads(threads)
    assert losses[-1] < losses[0] / 10, (losses[0], losses[-10:])


# ------------------------------------------------------------ bottlenecks
def test_vae_kl_zero_at_prior():
    mu, logvar = torch.zeros(5, 8), torch.zeros(5, 8)
    assert gaussian_kl(mu, logvar).item() == 0.0
    assert gaussian_kl(torch.ones(5, 8), logvar).item() == pytest.approx(4.0)


def test_vae_bottleneck_sample_and_mean():
    vae = VAEBottleneck(16, 8)
    x = torch.randn(10, 16)
    vae.eval()
    out = vae(x)
    assert out.z.shape == out.mu.shape == out.logvar.shape == (10, 8)
    assert torch.equal(out.z, out.mu) and out.kl.ndim == 0 and out.kl >= 0
    vae.train()
    assert not torch.equal(vae(x).z, out.mu)
    torch.nn.init.zeros_(vae.lin.weight)
    torch.nn.init.zeros_(vae.lin.bias)
    assert vae(x).kl.item() == 0.0


@pytest.mark.parametrize("training", [True, False])
def test_rvq_codes(training):
    torch.manual_seed(0)
    rvq = RVQBottleneck(16, latent_channels=8, num_quantizers=3, codebook_size=32,
                        quantize_dropout=0.0).train(training)
    x = torch.randn(40, 16)
    out = rvq(x)
    assert out.z.shape == (40, 8)
    assert out.codes.shape == (40, 3) and out.codes.dtype == torch.long
    assert ((out.codes >= 0) & (out.codes < 32)).all()
    assert out.commit.ndim == 0 and torch.isfinite(out.commit)
    rvq.eval()
    out = rvq(x)
    torch.testing.assert_close(rvq.decode_codes(out.codes), out.z)


def test_rvq_quantize_dropout_marks_dropped_layers():
    torch.manual_seed(0)
    rvq = RVQBottleneck(16, latent_channels=8, num_quantizers=4, codebook_size=16,
                        quantize_dropout=1.0).train()
    dropped = [(rvq(torch.randn(20, 16)).codes == -1).any().item() for _ in range(20)]
    assert any(dropped)
    assert (rvq.eval()(torch.randn(20, 16)).codes >= 0).all()


# --------------------------------------------------------- paper sizes
def count(module: torch.nn.Module) -> int:
    return sum(p.numel() for p in module.parameters() if p.requires_grad)


def test_paper_size_parameter_count():
    model = SATA(semantic_channels=256, bottleneck="vae")
    assert abs(count(model) - 8.41e6) / 8.41e6 < 0.05, count(model)


def test_a_target_of_other_clip_lengths_is_refused():
    """Target clips of 5 and 10 frames under source clips of 10 and 5: the
    frame count matches, and the temporal transformer decoded each target
    clip from latents of both source clips."""
    model = SATA(bottleneck="vae", **TINY).eval()
    source = collate_clips(make_clips([(10, 4), (5, 6)]))
    target = collate_clips(make_clips([(5, 4), (10, 6)], seed=7))
    with pytest.raises(ValueError, match=r"clips of \[5, 10\] frames from clips of \[10, 5\]"):
        model(source, target)
    same = collate_clips(make_clips([(10, 5), (5, 3)], seed=9))
    assert model(source, same)["q"].shape[0] == same.num_nodes
