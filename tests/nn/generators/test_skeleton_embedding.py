"""Topology-aware skeleton embedding (OmniZoo 4.2.1)."""
from __future__ import annotations

import torch

from satagraph.data import collate_clips
from satagraph.nn.generators import (parents_to_edge_index, skeleton_graph,
                                     skeleton_topology)
from tests.nn.generators.generator_helpers import SKEL, TREE, relabel, skeleton, tiny_skeleton_net
from tests.nn.test_sata_modules import make_clips

BIG = [-1, 0, 1, 2, 3, 0, 5, 6, 0, 8, 9, 9, 4]


def embed_alone(net, parents, x, root=0):
    edge_index, _ = parents_to_edge_index(torch.tensor(parents))
    return net(x, edge_index, root=torch.tensor([root]))


def test_output_shape_one_per_skeleton():
    net = tiny_skeleton_net().eval()
    x_a, e_a = skeleton(TREE)
    x_b, e_b = skeleton(BIG, seed=1)
    out = net(torch.cat([x_a, x_b]), torch.cat([e_a, e_b + len(TREE)], 1),
              torch.tensor([0] * len(TREE) + [1] * len(BIG)))
    assert out.shape == (2, SKEL)
    assert torch.isfinite(out).all()


def test_joint_order_does_not_matter():
    net = tiny_skeleton_net().eval()
    x, _ = skeleton(TREE)
    perm = [3, 6, 0, 5, 1, 4, 2]
    ref = embed_alone(net, TREE, x)
    got = embed_alone(net, relabel(TREE, perm), x[torch.tensor(perm)], root=perm.index(0))
    torch.testing.assert_close(got, ref, atol=1e-5, rtol=1e-5)


def test_padding_and_batch_neighbours_do_not_matter():
    net = tiny_skeleton_net().eval()
    x_a, e_a = skeleton(TREE)
    x_b, e_b = skeleton(BIG, seed=1)
    alone = net(x_a, e_a)
    first = net(torch.cat([x_a, x_b]), torch.cat([e_a, e_b + len(TREE)], 1),
                torch.tensor([0] * len(TREE) + [1] * len(BIG)))
    last = net(torch.cat([x_b, x_a]), torch.cat([e_b, e_a + len(BIG)], 1),
               torch.tensor([0] * len(BIG) + [1] * len(TREE)))
    torch.testing.assert_close(first[0], alone[0], atol=1e-5, rtol=1e-5)
    torch.testing.assert_close(last[1], alone[0], atol=1e-5, rtol=1e-5)
    torch.testing.assert_close(first[1], last[0], atol=1e-5, rtol=1e-5)


def test_topology_changes_the_embedding():
    net = tiny_skeleton_net().eval()
    x, _ = skeleton(TREE)
    chain = list(range(-1, len(TREE) - 1))
    assert not torch.allclose(embed_alone(net, TREE, x), embed_alone(net, chain, x), atol=1e-4)


def test_precomputed_topology_gives_the_same_output():
    net = tiny_skeleton_net().eval()
    x, edge_index = skeleton(TREE)
    tables = skeleton_topology(edge_index, max_hops=net.max_hops)
    assert torch.equal(net(x, edge_index, topology=tables), net(x, edge_index))


def test_gradients_reach_every_parameter():
    net = tiny_skeleton_net()
    x, edge_index = skeleton(TREE)
    x.requires_grad_(True)
    net(x, edge_index).square().sum().backward()
    assert x.grad is not None and x.grad.abs().sum() > 0
    for name, param in net.named_parameters():
        assert param.grad is not None and param.grad.abs().sum() > 0, name


def test_frame_batch_clips_of_one_skeleton_share_their_embedding():
    clips = make_clips([(3, 5), (2, 7), (4, 5)])
    clips[2].static, clips[2].semantic = clips[0].static, clips[0].semantic
    clips[2].parents, clips[2].edge_attr = clips[0].parents, clips[0].edge_attr
    graph = skeleton_graph(collate_clips(clips))
    net = tiny_skeleton_net(graph.x.size(1)).eval()
    out = net(*graph)
    assert out.shape == (3, SKEL)
    torch.testing.assert_close(out[2], out[0], atol=1e-5, rtol=1e-5)
