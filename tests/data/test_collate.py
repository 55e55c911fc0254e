"""collate_clips: frame graphs of mixed skeletons and lengths."""
from __future__ import annotations

import copy
import pickle
from typing import List, Sequence, Tuple

import pytest
import torch
from torch_geometric.data import Batch

from satagraph.data import FrameBatch, FrameGraph, collate_clips
from satagraph.data.clip import MotionClip
from satagraph.ops.fk import fk_levels, forward_kinematics
from satagraph.ops.rotation import rotation_6d_to_matrix

SPECS = ((5, 3), (12, 7), (5, 4), (1, 2))  # (joints, frames); 1-joint has no bones


def random_parents(num_joints: int, gen: torch.Generator) -> torch.Tensor:
    """A random tree: parents[j] uniform in [0, j), root -1."""
    par = [-1] + [int(torch.randint(0, j, (1,), generator=gen)) for j in range(1, num_joints)]
    return torch.tensor(par)


def random_clip(num_joints: int, num_frames: int, gen: torch.Generator,
                parents: torch.Tensor = None, dtype=torch.float32) -> MotionClip:
    parents = random_parents(num_joints, gen) if parents is None else parents
    return MotionClip(
        dynamic=torch.randn(num_frames, num_joints, 7, generator=gen, dtype=dtype),
        root=torch.randn(num_frames, 4, generator=gen, dtype=dtype),
        static=torch.randn(num_joints, 6, generator=gen, dtype=dtype),
        semantic=torch.randn(num_joints, 3, generator=gen, dtype=dtype),
        parents=parents,
        edge_attr=torch.randn(2 * (num_joints - 1), 2, generator=gen, dtype=dtype),
        meta={"id": f"{num_joints}x{num_frames}"})


def make_clips(specs: Sequence[Tuple[int, int]] = SPECS, seed: int = 0) -> List[MotionClip]:
    gen = torch.Generator().manual_seed(seed)
    clips = [random_clip(j, t, gen) for j, t in specs]
    # A second clip on the first skeleton (shared template).
    clips.append(random_clip(specs[0][0], 2, gen, parents=clips[0].parents.clone()))
    return clips


def frame_graphs(clips: List[MotionClip]) -> List[FrameGraph]:
    return [FrameGraph.from_clip(c, t) for c in clips for t in range(c.num_frames)]


def depth_of(parents: torch.Tensor) -> torch.Tensor:
    depth = torch.zeros(parents.numel(), dtype=torch.long)
    for j in range(1, parents.numel()):
        depth[j] = depth[parents[j]] + 1
    return depth


@pytest.fixture
def clips() -> List[MotionClip]:
    return make_clips()


def test_shapes(clips):
    batch = collate_clips(clips)
    frames = [c.num_frames for c in clips]
    joints = [c.num_joints for c in clips]
    num_nodes = sum(t * j for t, j in zip(frames, joints))
    num_edges = sum(2 * t * (j - 1) for t, j in zip(frames, joints))
    num_graphs, num_streams = sum(frames), sum(joints)
    assert isinstance(batch, FrameBatch) and isinstance(batch, Batch)
    assert batch.num_graphs == num_graphs and batch.num_nodes == num_nodes
    assert batch.num_streams == num_streams and isinstance(batch.num_streams, int)
    assert batch.max_time == max(frames) and isinstance(batch.max_time, int)
    assert batch.meta == [c.meta for c in clips]
    expected = {
        "x": (num_nodes, 7), "edge_index": (2, num_edges), "edge_attr": (num_edges, 2),
        "batch": (num_nodes,), "ptr": (num_graphs + 1,), "root": (num_graphs, 4),
        "root_node": (num_graphs,), "frame_clip": (num_graphs,),
        "frame_time": (num_graphs,), "node_stream": (num_nodes,),
        "node_time": (num_nodes,), "node_parent": (num_nodes,),
        "node_depth": (num_nodes,), "joint_static": (num_streams, 6),
        "joint_semantic": (num_streams, 3), "stream_parent": (num_streams,),
        "stream_depth": (num_streams,), "stream_clip": (num_streams,),
        "clip_num_frames": (len(clips),), "clip_num_joints": (len(clips),),
    }
    for key, shape in expected.items():
        assert tuple(batch[key].shape) == shape, key
        if key not in ("x", "edge_attr", "root", "joint_static", "joint_semantic"):
            assert batch[key].dtype == torch.long, key


def test_matches_from_data_list(clips):
    batch = collate_clips(clips)
    graphs = frame_graphs(clips)
    ref = Batch.from_data_list(graphs)
    for key in ref.keys():
        assert torch.equal(batch[key], ref[key]), key
    assert batch._slice_dict.keys() == ref._slice_dict.keys()
    for key, value in ref._slice_dict.items():
        assert torch.equal(batch._slice_dict[key], value), key
    examples = batch.to_data_list()
    assert len(examples) == len(graphs)
    for got, want in zip(examples, graphs):
        assert isinstance(got, FrameGraph)
        assert sorted(got.keys()) == sorted(want.keys())
        for key in want.keys():
            assert torch.equal(got[key], want[key]), key
    assert torch.equal(batch[3].edge_index, graphs[3].edge_index)


def test_frame_graph_batching_increments(clips):
    ref = Batch.from_data_list(frame_graphs(clips))
    assert torch.equal(ref.root_node, ref.ptr[:-1])
    assert torch.equal(ref.x[ref.root_node], torch.stack([c.dynamic[t, 0] for c in clips
                                                          for t in range(c.num_frames)]))
    assert torch.equal(ref.frame_time, torch.cat([torch.arange(c.num_frames) for c in clips]))


def test_node_layout(clips):
    batch = collate_clips(clips)
    node = stream = graph = 0
    for s, clip in enumerate(clips):
        num_frames, num_joints = clip.num_frames, clip.num_joints
        depth = depth_of(clip.parents)
        sl = slice(stream, stream + num_joints)
        assert torch.equal(batch.joint_static[sl], clip.static)
        assert torch.equal(batch.joint_semantic[sl], clip.semantic)
        assert torch.equal(batch.stream_depth[sl], depth)
        assert (batch.stream_clip[sl] == s).all()
        par = torch.where(clip.parents < 0, -1, clip.parents + stream)
        assert torch.equal(batch.stream_parent[sl], par)
        gl = slice(graph, graph + num_frames)
        assert (batch.frame_clip[gl] == s).all()
        assert torch.equal(batch.frame_time[gl], torch.arange(num_frames))
        assert torch.equal(batch.root[gl], clip.root)
        for t in range(num_frames):
            ids = node + t * num_joints + torch.arange(num_joints)
            assert torch.equal(batch.x[ids], clip.dynamic[t])
            assert torch.equal(batch.node_stream[ids], stream + torch.arange(num_joints))
            assert (batch.node_time[ids] == t).all()
            assert (batch.batch[ids] == graph + t).all()
            assert torch.equal(batch.node_depth[ids], depth)
            expected = torch.where(clip.parents < 0, -1, clip.parents + ids[0])
            assert torch.equal(batch.node_parent[ids], expected)
            assert int(batch.root_node[graph + t]) == ids[0]
        node += num_frames * num_joints
        stream += num_joints
        graph += num_frames
    assert torch.equal(batch.clip_num_frames, torch.tensor([c.num_frames for c in clips]))
    assert torch.equal(batch.clip_num_joints, torch.tensor([c.num_joints for c in clips]))


def test_edges_within_frames_between_parent_and_child(clips):
    batch = collate_clips(clips)
    src, dst = batch.edge_index
    assert torch.equal(batch.batch[src], batch.batch[dst])
    parent_of_dst = batch.node_parent[dst] == src
    parent_of_src = batch.node_parent[src] == dst
    assert (parent_of_dst ^ parent_of_src).all()
    # Every bone appears in both directions, once each.
    bones = set(zip(src.tolist(), dst.tolist()))
    assert len(bones) == src.numel() and all((d, s) in bones for s, d in bones)
    child = torch.nonzero(batch.node_parent >= 0).view(-1)
    assert src.numel() == 2 * child.numel()
    # edge_attr follows the clip's bone order in every frame.
    edge = 0
    for clip in clips:
        for _ in range(clip.num_frames):
            num = clip.edge_attr.shape[0]
            assert torch.equal(batch.edge_attr[edge:edge + num], clip.edge_attr)
            edge += num


def test_device_copy_and_pickle(clips):
    batch = collate_clips(clips)
    moved = batch.to("cpu")
    assert moved.num_streams == batch.num_streams and moved.max_time == batch.max_time
    assert torch.equal(moved.node_parent, batch.node_parent)
    shallow = copy.copy(batch)
    shallow.x = shallow.x * 2
    assert torch.equal(batch.x * 2, shallow.x)
    assert torch.equal(shallow.joint_static, batch.joint_static)
    loaded = pickle.loads(pickle.dumps(batch))
    assert isinstance(loaded, FrameBatch) and loaded.num_graphs == batch.num_graphs
    assert loaded.meta == batch.meta and loaded.max_time == batch.max_time
    assert torch.equal(loaded[2].x, batch[2].x)


def test_dataloader_collate_fn(clips):
    loader = torch.utils.data.DataLoader(clips, batch_size=3, collate_fn=collate_clips)
    sizes = [b.num_graphs for b in loader]
    assert sizes == [sum(c.num_frames for c in clips[i:i + 3]) for i in range(0, len(clips), 3)]


def test_forward_kinematics_over_batch(clips):
    batch = collate_clips(clips)
    gen = torch.Generator().manual_seed(1)
    rotation = rotation_6d_to_matrix(torch.randn(batch.num_nodes, 6, generator=gen,
                                                 dtype=torch.float64))
    offset = batch.joint_static[batch.node_stream, :3].double()
    levels = fk_levels(batch.node_parent, batch.node_depth)
    rot, pos = forward_kinematics(rotation, offset, batch.node_parent, levels)
    node = 0
    for clip in clips:
        num = clip.num_frames * clip.num_joints
        local = rotation[node:node + num].view(clip.num_frames, clip.num_joints, 3, 3)
        ref_rot, ref_pos = forward_kinematics(local, clip.static[:, :3].double(), clip.parents)
        torch.testing.assert_close(rot[node:node + num], ref_rot.reshape(num, 3, 3))
        torch.testing.assert_close(pos[node:node + num], ref_pos.reshape(num, 3))
        node += num


def test_to_clip_list_gives_back_the_clips(clips):
    """Every clip's tensors and meta come back; collated again, the batch
    is the same batch (single-joint clips included)."""
    gen = torch.Generator().manual_seed(3)
    clips = clips + [random_clip(1, 4, gen)]
    batch = collate_clips(clips)
    back = batch.to_clip_list()
    assert len(back) == len(clips)
    for ours, theirs in zip(back, clips):
        for key in ("dynamic", "root", "static", "semantic", "parents", "edge_attr"):
            assert torch.equal(getattr(ours, key), getattr(theirs, key).to(getattr(ours, key)))
        assert ours.meta == theirs.meta
    again = collate_clips(back)
    for key in batch.keys():
        if isinstance(batch[key], torch.Tensor):
            assert torch.equal(again[key], batch[key]), key


def test_empty_raises():
    with pytest.raises(ValueError):
        collate_clips([])


def test_batch_owns_its_index_structure(clips):
    """Clip of every node, the same joint one frame earlier, inner joints,
    heights and limb ends are collated once, with values that follow from
    the definition of the node order."""
    for k, clip in enumerate(clips):
        clip.meta.update(height=1.0 + k, limb_ends=[1, 2] if k == 0 else [])
    batch = collate_clips(clips)
    offset = 0
    for k, clip in enumerate(clips):
        t, j = clip.num_frames, clip.num_joints
        nodes = torch.arange(offset, offset + t * j)
        assert bool((batch.node_clip[nodes] == k).all())
        prev = batch.node_prev[nodes].view(t, j)
        assert torch.equal(prev[0], nodes[:j])  # frame 0: itself
        assert torch.equal(prev[1:], nodes.view(t, j)[:-1])
        inner = torch.zeros(j, dtype=torch.bool)
        inner[clip.parents[clip.parents >= 0].long()] = True
        assert torch.equal(batch.node_inner[nodes].view(t, j), inner.expand(t, j))
        offset += t * j
    assert batch.clip_height.tolist() == [1.0 + k for k in range(len(clips))]
    assert batch.clip_limb_ends[0].tolist() == [1, 2, -1, -1]
    assert bool((batch.clip_limb_ends[1:] == -1).all())
    assert torch.equal(batch.heights("node"), batch.clip_height[batch.node_clip])
    assert torch.equal(batch.heights("frame"), batch.clip_height[batch.frame_clip])
    with pytest.raises(ValueError, match="unknown level"):
        batch.heights("edge")


def test_batch_knows_its_frame_rate(clips):
    assert collate_clips(clips).fps == 30.0  # clips that do not say
    for clip in clips:
        clip.meta["fps"] = 60.0
    assert collate_clips(clips).fps == 60.0
    clips[0].meta["fps"] = 24.0
    with pytest.raises(ValueError, match="different frame rates"):
        collate_clips(clips)


def test_losses_and_metrics_read_the_batch_frame_rate(clips):
    """Root integration (losses, metrics) at the batch's rate unless told."""
    from satagraph.losses import to_global
    for clip in clips:
        clip.meta["fps"] = 60.0
    batch = collate_clips(clips)
    gen = torch.Generator().manual_seed(0)
    pos = torch.randn(batch.num_nodes, 3, generator=gen)
    root = torch.randn(batch.root.shape, generator=gen)
    torch.testing.assert_close(to_global(pos, root, batch), to_global(pos, root, batch, 60.0))
    assert not torch.allclose(to_global(pos, root, batch), to_global(pos, root, batch, 30.0))


def test_a_clip_whose_arrays_disagree_is_named():
    """Arrays of the wrong length used to batch silently and fail later in
    the model; a features object instead of a clip failed on an attribute."""
    from dataclasses import replace
    good = make_clips(((5, 3),))[0]
    with pytest.raises(TypeError, match="clip 1 is a dict, not a MotionClip"):
        collate_clips([good, {}])
    for bad, said in ((replace(good, root=good.root[:2]), "root has 2 rows for its 3 frames"),
                      (replace(good, static=good.static[:4]), "static has 4 rows"),
                      (replace(good, semantic=torch.zeros(2, 0)), "semantic has 2 rows"),
                      (replace(good, dynamic=good.dynamic[:0]), "with T, J >= 1"),
                      (replace(good, edge_attr=good.edge_attr[:3]), "edge_attr has 3 rows")):
        with pytest.raises(ValueError, match=f"clip 0: .*{said}"):
            collate_clips([bad])


@pytest.mark.parametrize("parents", [[-1, 0, -1, 2, 3], [0, -1, 1, 2, 3], [-1, 2, 0, 2, 3]])
def test_parents_that_are_not_a_tree_from_joint_0_are_refused(parents):
    """A second root, a root that is not joint 0, or a child before its
    parent made edges between clips and frames: the next clip's output
    changed with its neighbour."""
    from dataclasses import replace
    good = make_clips(((5, 3),))[0]
    bad = replace(good, parents=torch.tensor(parents))
    with pytest.raises(ValueError, match="clip 1: parents .* are not a tree rooted at joint 0"):
        collate_clips([good, bad])


def test_clips_of_other_feature_widths_are_named():
    from dataclasses import replace
    good = make_clips(((5, 3),))[0]
    wide = replace(good, semantic=torch.zeros(5, 7))
    with pytest.raises(ValueError, match=r"clip 1: feature widths differ: semantic 7 \(clip 0: "):
        collate_clips([good, wide])


def test_frame_batch_is_built_from_clips_not_frame_graphs(clips):
    """``FrameBatch.from_data_list`` of frame graphs failed later, deep in a
    model, on an attribute only clips give."""
    with pytest.raises(TypeError, match="collate_clips"):
        FrameBatch.from_data_list(frame_graphs(clips))
    batch = collate_clips(clips)
    assert len(batch.index_select([0, 1])) == 2 and batch.get_example(0).num_nodes > 0


def test_height_and_leg_default_where_a_clip_does_not_say():
    clips = make_clips(SPECS[:2])  # their meta holds an id only
    clips[1].meta["height"] = 1.6  # its leg: half of that
    clips[2].meta.update(height=1.6, leg=0.7)
    batch = collate_clips(clips)
    assert batch.clip_height.tolist() == pytest.approx([1.0, 1.6, 1.6])
    assert batch.clip_leg.tolist() == pytest.approx([0.5, 0.8, 0.7])
