r"""Topology tables of skeletons for attention biases: hop distances and
relation types (self, parent, child, sibling, none, end effector), as AnyTop
defines them and OmniZoo's skeleton embedding uses them."""
from __future__ import annotations

from typing import NamedTuple, Optional, Sequence, Tuple

import torch
import torch.nn.functional as F
from torch import Tensor
from torch_geometric.utils import to_dense_adj

#: Relation type ids (AnyTop's order; ``END_EFFECTOR`` replaces ``SELF`` on
#: the diagonal for leaves).
SELF, PARENT, CHILD, SIBLING, NONE, END_EFFECTOR = range(6)
NUM_RELATIONS = 6


class SkeletonTopology(NamedTuple):
    r"""Dense per-skeleton tables (padded to the largest skeleton).

    Attributes:
        distance (Tensor): Hops between joints, clipped to ``max_hops``
            (0 at padding), :math:`(B, J_{max}, J_{max})` long.
        relation (Tensor): Relation of key joint ``j`` to query joint ``i``
            (ids above; ``NONE`` at padding), :math:`(B, J_{max}, J_{max})`.
        mask (Tensor): Real joints (``True``), :math:`(B, J_{max})`.
        depth (Tensor): Bones to the root (0 at padding), :math:`(B, J_{max})`.
    """
    distance: Tensor
    relation: Tensor
    mask: Tensor
    depth: Tensor


def default_roots(batch: Tensor, num_graphs: Optional[int] = None) -> Tensor:
    r"""The first node of every graph (satagraph's convention: joint 0 is
    the root).

    Shapes:
        - **batch**: :math:`(N,)`, **output**: :math:`(B,)` node indices
    """
    num_graphs = int(batch.max()) + 1 if num_graphs is None else num_graphs
    counts = torch.bincount(batch, minlength=num_graphs)
    return counts.cumsum(0) - counts


def _hop_distance(adj: Tensor, max_hops: int) -> Tensor:
    """Hops clipped to ``max_hops`` by boolean reachability powers."""
    eye = torch.eye(adj.size(-1), dtype=torch.bool, device=adj.device)
    reach = eye.expand_as(adj).clone()
    dist = torch.full(adj.shape, max_hops, dtype=torch.long, device=adj.device)
    dist.masked_fill_(reach, 0)
    step = adj.float()
    for hop in range(1, max_hops):
        new = (torch.bmm(reach.float(), step) > 0) & ~reach
        if not bool(new.any()):
            break
        dist.masked_fill_(new, hop)
        reach |= new
    return dist


def _depth(adj: Tensor, root_local: Tensor, mask: Tensor) -> Tensor:
    """Bones to the root of every joint, by breadth-first frontiers."""
    size, num = mask.shape
    depth = torch.full((size, num), -1, dtype=torch.long, device=adj.device)
    rows = torch.arange(size, device=adj.device)
    depth[rows, root_local] = 0
    frontier = torch.zeros(size, num, device=adj.device)
    frontier[rows, root_local] = 1.0
    for level in range(1, num):
        nxt = (torch.bmm(adj.float(), frontier.unsqueeze(-1)).squeeze(-1) > 0) & (depth < 0)
        if not bool(nxt.any()):
            break
        depth.masked_fill_(nxt, level)
        frontier = nxt.float()
    if bool((mask & (depth < 0)).any()):
        raise ValueError("skeleton_topology: a skeleton is not connected to its root")
    return depth.clamp(min=0)


def _relations(adj: Tensor, depth: Tensor, mask: Tensor) -> Tensor:
    """Relation ids from adjacency and depth."""
    is_parent = adj & (depth.unsqueeze(1) == depth.unsqueeze(2) - 1)  # [i, j]: j parent of i
    is_child = is_parent.transpose(1, 2)
    par = is_parent.float()
    sibling = (torch.bmm(par, par.transpose(1, 2)) > 0)
    eye = torch.eye(adj.size(-1), dtype=torch.bool, device=adj.device)
    leaf = ~is_child.any(-1) & mask
    rel = torch.full(adj.shape, NONE, dtype=torch.long, device=adj.device)
    rel.masked_fill_(sibling & ~eye, SIBLING)
    rel.masked_fill_(is_child, CHILD)
    rel.masked_fill_(is_parent, PARENT)
    rel.masked_fill_(eye & mask.unsqueeze(-1), SELF)
    rel.masked_fill_(eye & leaf.unsqueeze(-1), END_EFFECTOR)
    return rel


def skeleton_topology(edge_index: Tensor, batch: Optional[Tensor] = None,
                      root: Optional[Tensor] = None, num_nodes: Optional[int] = None,
                      max_hops: int = 5) -> SkeletonTopology:
    r"""Hop distances and relation types of every skeleton of a batch,
    vectorised over skeletons (dense :math:`J_{max} \times J_{max}` tables).

    Edges may be given in one or both directions: parent and child are told
    apart by the depth from :obj:`root`, so the tables do not depend on the
    order of the joints or of the edges.

    Args:
        edge_index (Tensor): Bones (global node indices).
        batch (Tensor, optional): Skeleton of every node (sorted; default:
            one skeleton).
        root (Tensor, optional): Global node index of every skeleton's root
            (default: its first node).
        num_nodes (int, optional): :math:`N` (default: from :obj:`batch`).
        max_hops (int, optional): Distances are clipped to this (AnyTop: 5).

    Returns:
        SkeletonTopology: ``distance``, ``relation``, ``mask``, ``depth``.

    Shapes:
        - **edge_index**: :math:`(2, E)`, **batch**: :math:`(N,)`,
          **root**: :math:`(B,)`
    """
    if batch is None:
        size = num_nodes if num_nodes is not None else int(edge_index.max()) + 1
        batch = torch.zeros(size, dtype=torch.long, device=edge_index.device)
    num_graphs = int(batch.max()) + 1
    counts = torch.bincount(batch, minlength=num_graphs)
    start = counts.cumsum(0) - counts
    root = default_roots(batch, num_graphs) if root is None else root
    adj = to_dense_adj(edge_index, batch, batch_size=num_graphs) > 0
    adj = adj | adj.transpose(1, 2)
    mask = torch.arange(adj.size(-1), device=adj.device) < counts.unsqueeze(-1)
    depth = _depth(adj, root - start, mask)
    dist = _hop_distance(adj, max_hops).masked_fill(~(mask.unsqueeze(1) & mask.unsqueeze(2)), 0)
    return SkeletonTopology(dist, _relations(adj, depth, mask), mask, depth)


def stack_topologies(tables: Sequence[SkeletonTopology]) -> SkeletonTopology:
    r"""One padded batch from per-skeleton tables (e.g. computed once per
    skeleton and cached by a dataset), equal to computing them together.

    Shapes:
        - **tables**: each of batch size 1 (or more)
        - **output**: tables of :math:`\sum B` skeletons padded to the largest
    """
    size = max(t.mask.size(-1) for t in tables)
    pads = {"distance": 0, "relation": NONE, "mask": False, "depth": 0}
    fields = {}
    for name, value in pads.items():
        parts = []
        for t in tables:
            part = getattr(t, name)
            extra = size - part.size(-1)
            spec = (0, extra, 0, extra) if part.dim() == 3 else (0, extra)
            parts.append(F.pad(part, spec, value=value))
        fields[name] = torch.cat(parts)
    return SkeletonTopology(**fields)


def parents_to_edge_index(parents: Tensor) -> Tuple[Tensor, Tensor]:
    r"""Bones (parent -> child) and roots from global parent indices
    (``-1`` for roots), e.g. a :class:`~satagraph.data.FrameBatch`'s
    :obj:`stream_parent`.

    Returns:
        (Tensor, Tensor): ``edge_index`` :math:`(2, N - B)` and the roots
        :math:`(B,)` in node order.
    """
    child = torch.nonzero(parents >= 0).view(-1)
    roots = torch.nonzero(parents < 0).view(-1)
    return torch.stack([parents[child], child]), roots
