"""Padding-free per-frame attention equals PyG's padded GPSConv."""
from __future__ import annotations

import pytest
import torch
from torch_geometric.nn import GINEConv, GPSConv

from satagraph.data import collate_clips
from satagraph.nn.layers.frame_gps import FrameGPSConv, frame_self_attention, joint_count_groups
from tests.nn.test_sata_modules import make_clips

MIXED = [(4, 5), (3, 9), (2, 5), (3, 2), (5, 9)]


def gps_pair(channels: int = 16, with_conv: bool = True):
    torch.manual_seed(0)
    conv = GINEConv(torch.nn.Linear(channels, channels), edge_dim=channels) if with_conv else None
    ours = FrameGPSConv(channels, conv, heads=4, norm="layer_norm",
                        norm_kwargs={"mode": "node"}).eval()
    ref = GPSConv(channels, conv, heads=4, norm="layer_norm",
                  norm_kwargs={"mode": "node"}).eval()
    ref.load_state_dict(ours.state_dict())
    return ours, ref


def test_groups_cover_every_node_once():
    frames = collate_clips(make_clips(MIXED))
    groups = joint_count_groups(frames)
    assert [count for count, _ in groups] == [2, 5, 9]
    nodes = torch.cat([index for _, index in groups])
    assert torch.equal(nodes.sort().values, torch.arange(frames.num_nodes))
    for count, index in groups:  # each block of `count` nodes is one frame graph
        graphs = frames.batch[index].view(-1, count)
        assert (graphs == graphs[:, :1]).all()


def test_single_skeleton_is_the_identity_grouping():
    frames = collate_clips(make_clips([(3, 6), (4, 6)]))
    assert joint_count_groups(frames) == [(6, None)]


@pytest.mark.parametrize("specs", [MIXED, [(3, 6), (4, 6)]])
@pytest.mark.parametrize("with_conv", [True, False])
def test_matches_padded_gpsconv(specs, with_conv):
    frames = collate_clips(make_clips(specs))
    ours, ref = gps_pair(with_conv=with_conv)
    x = torch.randn(frames.num_nodes, 16)
    kwargs = {"edge_attr": torch.randn(frames.edge_index.shape[1], 16)} if with_conv else {}
    expected = ref(x, frames.edge_index, frames.batch, **kwargs)
    got = ours(x, frames.edge_index, frames.batch, frames=frames, **kwargs)
    torch.testing.assert_close(got, expected, atol=1e-5, rtol=1e-5)
    assert torch.equal(ours(x, frames.edge_index, frames.batch, **kwargs), expected)


def test_attention_gradients_match():
    frames = collate_clips(make_clips(MIXED))
    ours, ref = gps_pair()
    x = torch.randn(frames.num_nodes, 16, requires_grad=True)
    grad_ours, = torch.autograd.grad(frame_self_attention(ours.attn, x, frames).square().sum(), x)
    from torch_geometric.utils import to_dense_batch
    h, mask = to_dense_batch(x, frames.batch)
    dense, _ = ref.attn(h, h, h, key_padding_mask=~mask, need_weights=False)
    grad_ref, = torch.autograd.grad(dense[mask].square().sum(), x)
    torch.testing.assert_close(grad_ours, grad_ref, atol=1e-4, rtol=1e-4)


def test_mixed_skeletons_under_autocast_keep_the_attention_dtype():
    # A float32 input whose attention autocast computes in bf16 (as CUDA's
    # autocast does after a float32 layer norm): the gathered output takes
    # the attention's dtype instead of failing in index_copy.
    frames = collate_clips(make_clips(MIXED))
    ours, _ = gps_pair()
    x = torch.randn(frames.num_nodes, 16)
    with torch.autocast("cpu", dtype=torch.bfloat16):
        got = frame_self_attention(ours.attn, x, frames)
    expected = frame_self_attention(ours.attn, x, frames)
    assert got.dtype == torch.bfloat16
    torch.testing.assert_close(got.float(), expected, atol=0.05, rtol=0.05)
