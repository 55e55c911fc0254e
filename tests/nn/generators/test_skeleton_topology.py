"""Hop distances and relation types of skeletons."""
from __future__ import annotations

import pytest
import torch

from satagraph.data import collate_clips
from satagraph.nn.generators import (parents_to_edge_index, skeleton_graph, skeleton_topology,
                                     stack_topologies)
from satagraph.nn.generators.skeleton_topology import (CHILD, END_EFFECTOR, NONE, PARENT, SELF,
                                                       SIBLING)
from tests.nn.generators.generator_helpers import TREE, relabel
from tests.nn.test_sata_modules import make_clips


def tables(parents, max_hops=5, both=False):
    edge_index, _ = parents_to_edge_index(torch.tensor(parents))
    if both:
        edge_index = torch.cat([edge_index, edge_index.flip(0)], 1)
    return skeleton_topology(edge_index, max_hops=max_hops)


def test_hand_made_tree_distances():
    expected = torch.tensor([
        [0, 1, 1, 2, 3, 2, 2],
        [1, 0, 2, 1, 2, 3, 3],
        [1, 2, 0, 3, 4, 1, 1],
        [2, 1, 3, 0, 1, 4, 4],
        [3, 2, 4, 1, 0, 5, 5],
        [2, 3, 1, 4, 5, 0, 2],
        [2, 3, 1, 4, 5, 2, 0]])
    assert torch.equal(tables(TREE, max_hops=6).distance[0], expected)
    assert torch.equal(tables(TREE, max_hops=3).distance[0], expected.clamp(max=3))
    assert torch.equal(tables(TREE).depth[0], torch.tensor([0, 1, 1, 2, 3, 2, 2]))


def test_hand_made_tree_relations():
    S, P, C, B, N, E = SELF, PARENT, CHILD, SIBLING, NONE, END_EFFECTOR
    expected = torch.tensor([   # row i (query), column j: relation of j to i
        [S, C, C, N, N, N, N],
        [P, S, B, C, N, N, N],
        [P, B, S, N, N, C, C],
        [N, P, N, S, C, N, N],
        [N, N, N, P, E, N, N],
        [N, N, P, N, N, E, B],
        [N, N, P, N, N, B, E]])
    assert torch.equal(tables(TREE).relation[0], expected)


def test_edge_direction_and_order_do_not_matter():
    one = tables(TREE)
    both = tables(TREE, both=True)
    edge_index, _ = parents_to_edge_index(torch.tensor(TREE))
    shuffled = edge_index.flip(0)[:, torch.randperm(edge_index.size(1))]
    other = skeleton_topology(shuffled)
    for a, b, c in zip(one, both, other):
        assert torch.equal(a, b) and torch.equal(a, c)


def test_relabelled_skeleton_permutes_the_tables():
    perm = [3, 6, 0, 5, 1, 4, 2]
    moved = relabel(TREE, perm)
    ref = tables(TREE)
    edge_index, _ = parents_to_edge_index(torch.tensor(moved))
    root = torch.tensor([perm.index(0)])
    got = skeleton_topology(edge_index, root=root)
    idx = torch.tensor(perm)
    assert torch.equal(got.distance[0], ref.distance[0][idx][:, idx])
    assert torch.equal(got.relation[0], ref.relation[0][idx][:, idx])
    assert torch.equal(got.depth[0], ref.depth[0][idx])


def test_batched_skeletons_match_single_ones():
    small = [-1, 0, 1]
    edge_a, _ = parents_to_edge_index(torch.tensor(TREE))
    edge_b, _ = parents_to_edge_index(torch.tensor(small))
    edge_index = torch.cat([edge_b, edge_a + len(small)], 1)
    batch = torch.tensor([0] * len(small) + [1] * len(TREE))
    got = skeleton_topology(edge_index, batch)
    assert got.mask.tolist() == [[True] * 3 + [False] * 4, [True] * 7]
    for field, ref_a, ref_b in zip(got, tables(TREE), tables(small)):
        assert torch.equal(field[1], ref_a[0])
        assert torch.equal(field[0][..., :3, :3] if field.dim() == 3 else field[0][:3], ref_b[0])


def test_cached_tables_stack_into_the_batched_ones():
    small = [-1, 0, 1]
    edge_a, _ = parents_to_edge_index(torch.tensor(TREE))
    edge_b, _ = parents_to_edge_index(torch.tensor(small))
    batched = skeleton_topology(torch.cat([edge_b, edge_a + 3, edge_b + 10], 1),
                                torch.tensor([0] * 3 + [1] * 7 + [2] * 3))
    stacked = stack_topologies([tables(small), tables(TREE), tables(small)])
    for got, ref in zip(stacked, batched):
        assert torch.equal(got, ref)


def test_disconnected_skeleton_is_refused():
    edge_index = torch.tensor([[0, 2], [1, 3]])
    with pytest.raises(ValueError, match="not connected"):
        skeleton_topology(edge_index, num_nodes=4)


def test_skeleton_graph_of_a_frame_batch():
    clips = make_clips([(3, 4), (2, 6)])
    frames = collate_clips(clips)
    graph = skeleton_graph(frames)
    assert graph.x.shape == (10, clips[0].static.shape[1] + clips[0].semantic.shape[1])
    assert graph.root.tolist() == [0, 4]
    assert graph.batch.tolist() == [0] * 4 + [1] * 6
    got = skeleton_topology(graph.edge_index, graph.batch, graph.root)
    ref = skeleton_topology(clips[1].edge_index)
    assert torch.equal(got.relation[1], ref.relation[0])
