"""Skeleton: topology (depth, hop distance, relations), edges and validation."""
from __future__ import annotations

from collections import deque
from itertools import product

import numpy as np
import pytest

from satagraph.skeleton import (REL_CHILD, REL_END_EFFECTOR, REL_NONE,
                                REL_PARENT, REL_SELF, REL_SIBLING, Skeleton)


def bfs_distances(parents: np.ndarray) -> np.ndarray:
    """Hop distances by breadth-first search over the undirected tree."""
    num = len(parents)
    adj = [[] for _ in range(num)]
    for j, p in enumerate(parents):
        if p >= 0:
            adj[j].append(int(p))
            adj[int(p)].append(j)
    out = np.full((num, num), -1, dtype=np.int64)
    for src in range(num):
        out[src, src] = 0
        queue = deque([src])
        while queue:
            u = queue.popleft()
            for v in adj[u]:
                if out[src, v] < 0:
                    out[src, v] = out[src, u] + 1
                    queue.append(v)
    return out


def random_tree(num: int, seed: int) -> Skeleton:
    gen = np.random.default_rng(seed)
    parents = np.array([-1] + [int(gen.integers(0, j)) for j in range(1, num)])
    return Skeleton([f"j{j}" for j in range(num)], parents,
                    gen.normal(size=(num, 3)))


def test_basic_properties(tiny_skeleton):
    skel = tiny_skeleton
    assert skel.num_joints == len(skel) == 10
    assert skel.index("LeftFoot") == 5
    with pytest.raises(KeyError, match="Tail"):
        skel.index("Tail")
    assert skel.children[0] == [1, 4, 7]
    assert skel.is_leaf.tolist() == [False, False, False, True, False, False,
                                     True, False, False, True]
    assert skel.rotation_orders == ["ZXY", "XYZ", "XZY", "", "YXZ", "YZX", "",
                                    "ZYX", "ZXY", ""]
    assert np.flatnonzero(skel.has_position_channels).tolist() == [0, 4]
    assert skel.num_channels == 6 + 3 + 3 + 6 + 3 + 3 + 3
    assert repr(skel) == "Skeleton(joints=10, end_sites=3, root='Hips')"


def test_a_root_with_one_child_is_no_leaf():
    # 0 - 1 - 2: only joint 1 names the root as its parent
    skel = Skeleton(list("abc"), np.array([-1, 0, 1]), np.zeros((3, 3)))
    assert skel.is_leaf.tolist() == [False, False, True]
    assert np.diag(skel.relation_types).tolist() == [REL_SELF, REL_SELF, REL_END_EFFECTOR]


def test_depth_and_reverse_depth(tiny_skeleton):
    assert tiny_skeleton.depth.tolist() == [0, 1, 2, 3, 1, 2, 3, 1, 2, 3]
    assert tiny_skeleton.reverse_depth.tolist() == [3, 2, 1, 0, 2, 1, 0, 2, 1, 0]


def test_subtree_is_a_joint_and_everything_below_it(tiny_skeleton):
    assert tiny_skeleton.subtree(4).tolist() == [4, 5, 6]
    assert tiny_skeleton.subtree(0).tolist() == list(range(10))
    assert tiny_skeleton.subtree(9).tolist() == [9]
    # joints listed breadth first: a subtree need not be contiguous
    skel = Skeleton(list("abcde"), np.array([-1, 0, 0, 1, 2]), np.zeros((5, 3)))
    assert skel.subtree(1).tolist() == [1, 3]


def test_reverse_depth_uneven_branches():
    #   0 - 1 - 2 - 3
    #   +-- 4
    skel = Skeleton(list("abcde"), np.array([-1, 0, 1, 2, 0]), np.zeros((5, 3)))
    assert skel.depth.tolist() == [0, 1, 2, 3, 1]
    assert skel.reverse_depth.tolist() == [3, 2, 1, 0, 0]


def test_hop_distance_hand_values(tiny_skeleton):
    hop = tiny_skeleton.hop_distance
    assert hop.shape == (10, 10)
    assert hop[0, 3] == 3 and hop[3, 6] == 6 and hop[5, 8] == 4
    assert hop[4, 7] == 2 and hop[1, 4] == 2 and hop[2, 2] == 0


@pytest.mark.parametrize("seed", range(5))
def test_hop_distance_is_tree_metric(seed, tiny_skeleton):
    skel = tiny_skeleton if seed == 0 else random_tree(12 + 3 * seed, seed)
    hop = skel.hop_distance
    np.testing.assert_array_equal(hop, bfs_distances(skel.parents))
    np.testing.assert_array_equal(hop, hop.T)
    assert (np.diag(hop) == 0).all()
    off = ~np.eye(skel.num_joints, dtype=bool)
    assert (hop[off] > 0).all()
    # Triangle inequality and the four-point condition of tree metrics.
    assert (hop[:, None, :] <= hop[:, :, None] + hop[None, :, :]).all()
    # d(x,y)+d(z,w), d(x,z)+d(y,w), d(x,w)+d(y,z): the two largest are equal.
    sums = np.sort(np.stack([
        hop[:, :, None, None] + hop[None, None, :, :],
        hop[:, None, :, None] + hop[None, :, None, :],
        hop[:, None, None, :] + hop[None, :, :, None]]), axis=0)
    assert (sums[1] == sums[2]).all()
    # Bones are exactly the pairs at distance 1.
    ones = np.argwhere(hop == 1)
    bones = {(int(p), j) for j, p in enumerate(skel.parents) if p >= 0}
    assert {tuple(sorted(map(int, e))) for e in ones} == bones


def test_hop_distance_real_skeleton(read_real):
    skel = read_real("ccbase/007_01.bvh").skeleton  # 142 joints
    np.testing.assert_array_equal(skel.hop_distance, bfs_distances(skel.parents))


def test_relation_types(tiny_skeleton):
    rel = tiny_skeleton.relation_types
    assert rel.shape == (10, 10)
    diag = np.diag(rel)
    assert diag.tolist() == [REL_SELF, REL_SELF, REL_SELF, REL_END_EFFECTOR,
                             REL_SELF, REL_SELF, REL_END_EFFECTOR, REL_SELF,
                             REL_SELF, REL_END_EFFECTOR]
    assert rel[1, 0] == REL_PARENT and rel[0, 1] == REL_CHILD
    assert rel[3, 2] == REL_PARENT and rel[2, 3] == REL_CHILD
    assert rel[1, 4] == rel[4, 7] == rel[7, 1] == REL_SIBLING
    assert rel[2, 5] == REL_NONE  # cousins are not siblings
    assert rel[0, 2] == REL_NONE and rel[2, 0] == REL_NONE  # grandparent
    assert rel[3, 6] == REL_NONE


@pytest.mark.parametrize("seed", range(3))
def test_relation_types_match_definition(seed):
    skel = random_tree(15, seed)
    par = skel.parents
    rel = skel.relation_types
    for i, j in product(range(skel.num_joints), repeat=2):
        if i == j:
            want = REL_END_EFFECTOR if skel.is_leaf[i] else REL_SELF
        elif par[i] == j:
            want = REL_PARENT
        elif par[j] == i:
            want = REL_CHILD
        elif par[i] == par[j]:
            want = REL_SIBLING
        else:
            want = REL_NONE
        assert rel[i, j] == want, (i, j)


def test_edges(tiny_skeleton):
    skel = tiny_skeleton
    ei, ea = skel.edge_index, skel.edge_attr
    assert ei.shape == (2, 18) and ea.shape == (18, 2)
    assert ea.dtype == np.float32
    half = ei[:, :9]
    np.testing.assert_array_equal(half[0], skel.parents[1:])
    np.testing.assert_array_equal(half[1], np.arange(1, 10))
    np.testing.assert_array_equal(ei[:, 9:], half[::-1])
    child = np.arange(1, 10)
    np.testing.assert_array_equal(ea[:9, 0], skel.depth[child])
    np.testing.assert_array_equal(ea[:9, 1], skel.reverse_depth[child])
    np.testing.assert_array_equal(ea[9:], ea[:9])


def test_rest_positions(tiny_skeleton):
    pos = tiny_skeleton.rest_positions()
    np.testing.assert_allclose(pos[0], 0)
    np.testing.assert_allclose(pos[3], [0, 60, 1])
    np.testing.assert_allclose(pos[6], [10, -90, 12])


def test_subset(tiny_skeleton):
    sub = tiny_skeleton.subset([0, 1, 2, 3])
    assert sub.names == ["Hips", "Spine", "Head", "Head_end"]
    assert sub.parents.tolist() == [-1, 0, 1, 2]
    assert sub.end_site.tolist() == [False, False, False, True]
    legs = tiny_skeleton.subset([4, 5, 6])  # new root
    assert legs.parents.tolist() == [-1, 0, 1]


def test_defaults():
    skel = Skeleton(["a", "b"], [-1, 0], [[0, 0, 0], [0, 1, 0]])
    assert skel.channels == [(), ()]
    assert skel.end_site.tolist() == [False, False]
    assert skel.parents.dtype == np.int64 and skel.offsets.dtype == np.float64


@pytest.mark.parametrize("names, parents, offsets, match", [
    (["a", "b"], [-1], np.zeros((2, 3)), "parents"),
    (["a", "b"], [-1, 0], np.zeros((3, 3)), "offsets"),
    ([], [], np.zeros((0, 3)), "root"),
    (["a", "b"], [0, -1], np.zeros((2, 3)), "root"),
    (["a", "b", "c"], [-1, 0, -1], np.zeros((3, 3)), "root"),
    (["a", "b", "c"], [-1, 2, 0], np.zeros((3, 3)), "before children"),
    (["a", "b", "b"], [-1, 0, 0], np.zeros((3, 3)), "unique"),
])
def test_validation(names, parents, offsets, match):
    with pytest.raises(ValueError, match=match):
        Skeleton(names, np.array(parents), offsets)


def test_replace_revalidates(tiny_skeleton):
    with pytest.raises(ValueError, match="unique"):
        tiny_skeleton.replace(names=["x"] * 10)
    moved = tiny_skeleton.replace(offsets=tiny_skeleton.offsets * 2)
    np.testing.assert_allclose(moved.rest_positions(),
                               2 * tiny_skeleton.rest_positions())
    assert moved.names == tiny_skeleton.names


def test_a_skeleton_is_described_by_the_joints_a_tool_counts():
    """Messages said "38-joint skeleton" of a CMU file of 31 joints: its 7
    end sites were counted as joints."""
    import numpy as np
    from satagraph.skeleton import Skeleton
    skel = Skeleton(names=["Hips", "Spine", "Head", "Head_end"], parents=np.array([-1, 0, 1, 2]),
                    offsets=np.zeros((4, 3)), end_site=np.array([False, False, False, True]))
    assert skel.describe() == "3-joint skeleton (and 1 end site)"
    assert skel.subset([0, 1, 2]).describe() == "3-joint skeleton"
