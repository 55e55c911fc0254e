"""Batching clips of any skeletons and lengths into frame graphs."""
from __future__ import annotations

from typing import Dict, List, NamedTuple, Tuple

import torch
from torch import Tensor
from torch_geometric.data import Batch

from satagraph.data.clip import MotionClip
from satagraph.data.frame_graph import FrameGraph, joint_depth

#: Frame rate of clips that do not say theirs (``meta["fps"]``).
DEFAULT_FPS = 30.0

#: Limb ends per clip (left front, right front, left hind, right hind).
NUM_LIMBS = 4


class FrameBatch(Batch):
    r"""Frame graphs of several clips (mixed skeletons and lengths, no
    padding), as one disconnected graph, with the context that temporal
    layers, forward kinematics and losses need.

    Built by :func:`collate_clips`. Nodes are ordered clip after clip, then
    frame, then joint: node ``= clip_offset + t * J_s + j``. A *stream* is one
    joint of one clip over time (``stream = stream_offset_s + j``). Every
    frame of every clip is one graph, so :obj:`batch`, :obj:`ptr`,
    :obj:`num_graphs` refer to frames, and :meth:`get_example` /
    :meth:`to_data_list` give back :class:`~satagraph.data.FrameGraph`
    objects (keys ``x, edge_index, edge_attr, root, root_node, node_depth,
    frame_time``) equal to those of
    :meth:`~torch_geometric.data.Batch.from_data_list`. Index-valued keys
    hold global indices into this batch (``-1`` where none).

    With :math:`B` clips of :math:`T_s` frames and :math:`J_s` joints:
    :math:`N = \sum_s T_s J_s` nodes, :math:`E = \sum_s 2 T_s (J_s - 1)`
    edges, :math:`G = \sum_s T_s` frame graphs, :math:`S = \sum_s J_s`
    streams.

    Attributes:
        fps (float): The clips' frame rate (``meta["fps"]``; they must
            agree), :data:`DEFAULT_FPS` for clips that do not say.
        num_streams (int): :math:`S`, a Python int (no device sync).
        max_time (int): :math:`\max_s T_s`, a Python int.
        meta (list[dict]): The clips' :attr:`MotionClip.meta`.

    Shapes:
        - **x**: :math:`(N, F_d)` dynamic features
        - **edge_index**: :math:`(2, E)` bones within each frame
        - **edge_attr**: :math:`(E, 2)` (depth, reverse depth)
        - **batch**: :math:`(N,)` frame graph of each node
        - **ptr**: :math:`(G + 1,)` first node of each frame graph
        - **root**: :math:`(G, 4)` root features per frame
        - **root_node**: :math:`(G,)` node of each frame's root
        - **frame_clip**: :math:`(G,)` clip of each frame graph
        - **frame_time**: :math:`(G,)` frame index within its clip
        - **node_stream**: :math:`(N,)` stream of each node
        - **node_time**: :math:`(N,)` frame index within its clip
        - **node_parent**: :math:`(N,)` parent node in the same frame
          (``-1`` for roots)
        - **node_depth**: :math:`(N,)` bones to the root
        - **joint_static**: :math:`(S, F_s)` ``[X_l, X_g]`` per stream
        - **joint_semantic**: :math:`(S, D_t)` ``X_t`` per stream
        - **stream_parent**: :math:`(S,)` parent stream (``-1`` for roots)
        - **stream_depth**: :math:`(S,)` bones to the root
        - **stream_clip**: :math:`(S,)` clip of each stream
        - **clip_num_frames**: :math:`(B,)` :math:`T_s`
        - **clip_num_joints**: :math:`(B,)` :math:`J_s`
        - **node_clip**: :math:`(N,)` clip of each node
        - **node_prev**: :math:`(N,)` the same joint one frame earlier
          (itself at frame 0)
        - **node_inner**: :math:`(N,)` whether the joint has children
        - **clip_height**: :math:`(B,)` character height of each clip
          (``meta["height"]``, 1 where the clip does not say)
        - **clip_leg**: :math:`(B,)` leg length of each clip's character
          (``meta["leg"]``, :func:`satagraph.motion.leg_length`; half the
          height where the clip does not say)
        - **clip_limb_ends**: :math:`(B, 4)` each clip's limb-end joints
          (``meta["limb_ends"]`` in the order of
          :data:`~satagraph.semantics.LIMBS`, ``-1`` where missing)
    """

    @classmethod
    def from_data_list(cls, data_list, follow_batch=None, exclude_keys=None):
        """Refused: frame graphs alone do not hold the clips' context (their
        streams, heights, limb ends) that a :class:`FrameBatch` carries;
        :func:`collate_clips` builds one from clips, and
        :meth:`Batch.from_data_list <torch_geometric.data.Batch.from_data_list>`
        of :class:`~satagraph.data.FrameGraph` objects gives the plain PyG
        batch (an ``AttributeError`` deep in a model before)."""
        raise TypeError("FrameBatch.from_data_list: build a FrameBatch from clips with "
                        "satagraph.data.collate_clips(clips) (MotionFeatures.to_clip makes "
                        "them); torch_geometric.data.Batch.from_data_list(frame_graphs) "
                        "gives the plain PyG batch")

    def heights(self, level: str) -> Tensor:
        r"""The clip height of every row of a feature tensor: ``"node"``
        (:math:`N`, rows of :obj:`x`), ``"frame"`` (:math:`G`, rows of
        :obj:`root`) or ``"stream"`` (:math:`S`, rows of
        :obj:`joint_static`)."""
        return self._per_clip(self.clip_height, level, "heights")

    def legs(self, level: str) -> Tensor:
        r"""The clip leg length of every row, as :meth:`heights`."""
        return self._per_clip(self.clip_leg, level, "legs")

    def to_clip_list(self) -> List[MotionClip]:
        r"""The batch's clips back as :class:`MotionClip` objects on the CPU
        (what :func:`collate_clips` takes): ``collate_clips(b.to_clip_list())``
        rebuilds :obj:`b`. :meth:`to_data_list` gives frame graphs instead."""
        frames, joints = self.clip_num_frames.tolist(), self.clip_num_joints.tolist()
        nodes = [t * j for t, j in zip(frames, joints)]
        bones = [t * 2 * (j - 1) for t, j in zip(frames, joints)]
        offsets = [_exclusive_cumsum(v).tolist() for v in (nodes, frames, joints, bones)]
        return [self._clip(i, frames[i], joints[i], *spans)
                for i, spans in enumerate(zip(*offsets))]

    def _clip(self, i: int, num_frames: int, num_joints: int, node: int, frame: int,
              stream: int, edge: int) -> MotionClip:
        """Clip :obj:`i` of :obj:`num_frames` frames and :obj:`num_joints`
        joints, whose nodes, frames, streams and edges start at the given
        offsets."""
        streams = slice(stream, stream + num_joints)
        parents = self.stream_parent[streams]
        return MotionClip(
            dynamic=self.x[node:node + num_frames * num_joints].view(
                num_frames, num_joints, -1).cpu(),
            root=self.root[frame:frame + num_frames].cpu(),
            static=self.joint_static[streams].cpu(),
            semantic=self.joint_semantic[streams].cpu(),
            parents=torch.where(parents < 0, -1, parents - stream).cpu(),
            edge_attr=self.edge_attr[edge:edge + 2 * (num_joints - 1)].cpu(),
            meta=self.meta[i])

    def _per_clip(self, values: Tensor, level: str, name: str) -> Tensor:
        index = {"node": "node_clip", "frame": "frame_clip", "stream": "stream_clip"}
        if level not in index:
            raise ValueError(f"FrameBatch.{name}: unknown level {level!r} "
                             "(node, frame or stream)")
        return values[getattr(self, index[level])]


class _Group(NamedTuple):
    """Clips sharing a skeleton and a length."""
    members: List[int]
    num_frames: int
    parents: Tensor
    edge_index: Tensor
    depth: Tensor


def _groups(clips: List[MotionClip]) -> List[_Group]:
    """Clips grouped by (skeleton, length), in order of first appearance."""
    groups: Dict[Tuple, _Group] = {}
    for i, clip in enumerate(clips):
        key = (clip.num_frames, tuple(clip.parents.tolist()))
        if key not in groups:
            parents = clip.parents.long()
            groups[key] = _Group([], clip.num_frames, parents, clip.edge_index,
                                 joint_depth(parents))
        groups[key].members.append(i)
    return list(groups.values())


def _exclusive_cumsum(values: List[int]) -> Tensor:
    out = torch.tensor([0] + values[:-1])
    return out.cumsum(0)


def _group_blocks(group: _Group, node_offset: Tensor, frame_offset: Tensor,
                  stream_offset: Tensor) -> Dict[str, Tensor]:
    """Node and edge attributes of every clip of a group, one row per clip.

    Templates cover one clip (frame after frame); offsets (one per member)
    make them global."""
    num_joints, num_frames = group.parents.numel(), group.num_frames
    time = torch.arange(num_frames).repeat_interleave(num_joints)
    joint = torch.arange(num_joints).repeat(num_frames)
    first = time * num_joints  # first node of the frame, within the clip
    parent = group.parents[joint]
    bones = group.edge_index.view(2, 1, -1 if num_joints > 1 else 0)
    edges = bones + first[::num_joints].view(1, -1, 1)
    size = len(group.members)
    return {
        "batch": frame_offset.view(-1, 1) + time,
        "node_stream": stream_offset.view(-1, 1) + joint,
        "node_time": time.expand(size, -1),
        "node_parent": torch.where(parent < 0, -1, node_offset.view(-1, 1)
                                   + (first + parent)),
        "node_depth": group.depth[joint].expand(size, -1),
        "edge_index": node_offset.view(-1, 1, 1) + edges.reshape(1, 2, -1),
        "stream_depth": group.depth.expand(size, -1),
    }


def _node_edge_attrs(out: FrameBatch, clips: List[MotionClip], frames: List[int],
                     joints: List[int]) -> None:
    """Per-node attributes and bones, built per group and put in clip order."""
    offsets = {
        "node": _exclusive_cumsum([t * j for t, j in zip(frames, joints)]),
        "frame": _exclusive_cumsum(frames), "stream": _exclusive_cumsum(joints),
    }
    pieces: Dict[str, List[Tensor]] = {}
    for group in _groups(clips):
        idx = torch.tensor(group.members)
        blocks = _group_blocks(group, offsets["node"][idx], offsets["frame"][idx],
                               offsets["stream"][idx])
        for key, block in blocks.items():
            rows = pieces.setdefault(key, [None] * len(clips))
            for i, row in zip(group.members, block.unbind(0)):
                rows[i] = row
    for key, rows in pieces.items():
        setattr(out, key, torch.cat(rows, dim=-1))
    out.edge_attr = torch.cat([c.edge_attr.repeat(t, 1) for c, t in zip(clips, frames)])


def _frame_stream_attrs(out: FrameBatch, clips: List[MotionClip],
                        num_frames: Tensor, num_joints: Tensor) -> None:
    """Per-frame-graph and per-stream attributes."""
    clip = torch.arange(len(clips))
    out.frame_clip = clip.repeat_interleave(num_frames)
    out.frame_time = (torch.arange(out.frame_clip.numel())
                      - (num_frames.cumsum(0) - num_frames)[out.frame_clip])
    sizes = num_joints[out.frame_clip]
    out.ptr = torch.cat([sizes.new_zeros(1), sizes.cumsum(0)])
    out.root_node = out.ptr[:-1]
    out.stream_clip = clip.repeat_interleave(num_joints)
    local = torch.cat([c.parents for c in clips]).long()
    offset = (num_joints.cumsum(0) - num_joints)[out.stream_clip]
    out.stream_parent = torch.where(local < 0, -1, local + offset)
    out.joint_static = torch.cat([c.static for c in clips])
    out.joint_semantic = torch.cat([c.semantic for c in clips])


def _structure(out: FrameBatch, clips: List[MotionClip]) -> None:
    """What losses and metrics ask of every batch, computed once."""
    out.node_clip = out.stream_clip[out.node_stream]
    index = torch.arange(out.node_clip.numel())
    out.node_prev = torch.where(out.node_time > 0,
                                index - out.clip_num_joints[out.node_clip], index)
    out.node_inner = torch.zeros(index.numel(), dtype=torch.bool)
    out.node_inner[out.node_parent[out.node_parent >= 0]] = True
    out.clip_height = torch.tensor([float(c.meta.get("height", 1.0)) for c in clips])
    out.clip_leg = torch.tensor([float(c.meta.get("leg", 0.5 * float(c.meta.get("height", 1.0))))
                                 for c in clips])
    ends = [list(c.meta.get("limb_ends", ()))[:NUM_LIMBS] for c in clips]
    out.clip_limb_ends = torch.tensor([e + [-1] * (NUM_LIMBS - len(e)) for e in ends],
                                      dtype=torch.long).view(len(clips), NUM_LIMBS)


def _frame_rate(clips: List[MotionClip]) -> float:
    """The one frame rate of :obj:`clips`."""
    rates = {float(c.meta["fps"]) for c in clips if "fps" in c.meta}
    if len(rates) > 1:
        raise ValueError(f"collate_clips: clips at different frame rates {sorted(rates)}; "
                         "resample them to one rate first")
    return rates.pop() if rates else DEFAULT_FPS


def _separation(out: FrameBatch, num_graphs: int) -> None:
    """What :meth:`Batch.get_example` needs to give back frame graphs."""
    graphs = torch.arange(num_graphs + 1)
    bones = (out.ptr[1:] - out.ptr[:-1] - 1) * 2
    edge_ptr = torch.cat([bones.new_zeros(1), bones.cumsum(0)])
    out._num_graphs = num_graphs
    out._slice_dict = {
        "x": out.ptr, "edge_index": edge_ptr, "edge_attr": edge_ptr,
        "root": graphs, "root_node": graphs, "node_depth": out.ptr,
        "frame_time": graphs,
    }
    out._inc_dict = {key: None for key in out._slice_dict}
    out._inc_dict["edge_index"] = out._inc_dict["root_node"] = out.ptr[:-1]


def _check_clip(index: int, clip: MotionClip) -> None:
    """One line naming the clip whose arrays disagree with its
    :math:`(T, J, F_d)` dynamic features (:class:`MotionClip`'s Shapes)."""
    if not isinstance(clip, MotionClip):
        raise TypeError(f"collate_clips: clip {index} is a {type(clip).__name__}, not a "
                        "MotionClip (MotionFeatures.to_clip(start, stop) makes one)")
    if clip.dynamic.dim() != 3 or clip.num_frames < 1 or clip.num_joints < 1:
        raise ValueError(f"collate_clips: clip {index}: dynamic features must be (T, J, F) "
                         f"with T, J >= 1, got {tuple(clip.dynamic.shape)}")
    frames, joints = clip.num_frames, clip.num_joints
    for name, rows, want in (("root", clip.root.shape[0], frames),
                             ("static", clip.static.shape[0], joints),
                             ("semantic", clip.semantic.shape[0], joints),
                             ("parents", clip.parents.shape[0], joints)):
        if rows != want:
            raise ValueError(f"collate_clips: clip {index}: {name} has {rows} rows for its "
                             f"{frames} frames and {joints} joints")
    if clip.edge_attr.shape[0] != 2 * (joints - 1):
        raise ValueError(f"collate_clips: clip {index}: edge_attr has {clip.edge_attr.shape[0]} "
                         f"rows; {joints} joints have {2 * (joints - 1)} directed bones")
    parents = clip.parents.tolist()
    if parents[0] != -1 or any(not 0 <= p < j for j, p in enumerate(parents[1:], start=1)):
        raise ValueError(f"collate_clips: clip {index}: parents {parents[:12]}"
                         f"{'...' if len(parents) > 12 else ''} are not a tree rooted at joint "
                         "0 with each parent before its child (its edges would join other "
                         "frames and clips)")


def _check_widths(clips: List[MotionClip]) -> None:
    """One line naming the first clip whose feature widths differ from
    clip 0's (the widths every clip of a batch shares)."""
    def widths(clip: MotionClip) -> tuple:
        return tuple(getattr(clip, name).shape[-1] for name in _WIDTHS)
    first = widths(clips[0])
    for i, clip in enumerate(clips[1:], start=1):
        if widths(clip) != first:
            got = ", ".join(f"{n} {a} (clip 0: {b})" for n, a, b in
                            zip(_WIDTHS, widths(clip), first) if a != b)
            raise ValueError(f"collate_clips: clip {i}: feature widths differ: {got}")


#: The per-clip arrays whose last dimension every clip of a batch shares.
_WIDTHS = ("dynamic", "root", "static", "semantic", "edge_attr")


def collate_clips(clips: List[MotionClip]) -> FrameBatch:
    r"""Batches clips of any skeletons and lengths into frame graphs,
    vectorised (no loop over frames, no padding).

    Args:
        clips (list[MotionClip]): Clips on the CPU; joint 0 is the root of
            each skeleton.

    Returns:
        FrameBatch: see :class:`FrameBatch` for the attributes.
    """
    if isinstance(clips, MotionClip):  # a loader with batch_size=None hands each over alone
        raise TypeError("collate_clips: a list of clips, not one MotionClip (ClipLoader("
                        "batch_size=None) hands over each item as it is: batch_size=1)")
    if not clips:
        raise ValueError("collate_clips: no clips")
    for i, clip in enumerate(clips):
        _check_clip(i, clip)
    _check_widths(clips)
    frames = [c.num_frames for c in clips]
    joints = [c.num_joints for c in clips]
    num_frames, num_joints = torch.tensor(frames), torch.tensor(joints)

    out = FrameBatch(_base_cls=FrameGraph)
    out.x = torch.cat([c.dynamic.reshape(-1, c.dynamic.shape[-1]) for c in clips])
    out.root = torch.cat([c.root for c in clips])
    out.num_streams, out.max_time = sum(joints), max(frames)
    out.clip_num_frames, out.clip_num_joints = num_frames, num_joints
    out.meta = [c.meta for c in clips]
    out.fps = _frame_rate(clips)
    _frame_stream_attrs(out, clips, num_frames, num_joints)
    _node_edge_attrs(out, clips, frames, joints)
    _structure(out, clips)
    _separation(out, sum(frames))
    return out
