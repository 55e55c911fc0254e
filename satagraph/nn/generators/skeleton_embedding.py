r"""Topology-aware skeleton embedding (OmniZoo section 4.2.1): one vector
:math:`f_{skel}` per skeleton from its joints' static features and its
topology."""
from __future__ import annotations

from typing import Any, NamedTuple, Optional

import torch
import torch.nn.functional as F
from torch import Tensor, nn
from torch_geometric.utils import to_dense_batch

from satagraph.nn.generators.skeleton_topology import (NUM_RELATIONS, SkeletonTopology,
                                                       parents_to_edge_index,
                                                       skeleton_topology)


class SkeletonGraph(NamedTuple):
    """Skeletons in PyG form: joint features, bones, skeleton of every joint
    and the root of every skeleton."""
    x: Tensor
    edge_index: Tensor
    batch: Tensor
    root: Tensor


def skeleton_graph(frames: Any) -> SkeletonGraph:
    r"""The skeleton of every clip of a :class:`~satagraph.data.FrameBatch`
    (one graph per clip, its streams as nodes): node features
    ``[X_l, X_g, X_t]`` (``joint_static`` then ``joint_semantic``).

    Shapes:
        - **output**: ``x`` :math:`(S, F_s + D_t)`, ``edge_index``
          :math:`(2, S - B)`, ``batch`` :math:`(S,)`, ``root`` :math:`(B,)`
    """
    x = torch.cat([frames.joint_static, frames.joint_semantic], dim=-1)
    edge_index, root = parents_to_edge_index(frames.stream_parent)
    return SkeletonGraph(x, edge_index, frames.stream_clip, root)


class TopologyAttentionLayer(nn.Module):
    r"""Pre-norm Transformer layer whose attention logits get an additive
    per-head bias (OmniZoo eq. 6-7).

    Args:
        channels (int): Token width.
        heads (int): Attention heads.
        ff_channels (int): Feed-forward width.
        dropout (float, optional): Dropout on attention weights and branches.

    Shapes:
        - **h**: :math:`(B, L, C)`, **bias**: :math:`(B, H, L, L)`,
          **output**: :math:`(B, L, C)`
    """

    def __init__(self, channels: int, heads: int, ff_channels: int, dropout: float = 0.0) -> None:
        super().__init__()
        if channels % heads:
            raise ValueError(f"channels ({channels}) must be divisible by heads ({heads})")
        self.heads, self.dropout = heads, dropout
        self.norm1, self.norm2 = nn.LayerNorm(channels), nn.LayerNorm(channels)
        self.qkv = nn.Linear(channels, 3 * channels)
        self.out = nn.Linear(channels, channels)
        self.ffn = nn.Sequential(nn.Linear(channels, ff_channels), nn.GELU(),
                                 nn.Dropout(dropout), nn.Linear(ff_channels, channels))

    def attention(self, h: Tensor, bias: Tensor) -> Tensor:
        size, length, channels = h.shape
        qkv = self.qkv(h).view(size, length, 3, self.heads, channels // self.heads)
        q, k, v = qkv.permute(2, 0, 3, 1, 4)
        p = self.dropout if self.training else 0.0
        out = F.scaled_dot_product_attention(q, k, v, attn_mask=bias.to(q.dtype), dropout_p=p)
        return self.out(out.transpose(1, 2).reshape(size, length, channels))

    def forward(self, h: Tensor, bias: Tensor) -> Tensor:
        h = h + F.dropout(self.attention(self.norm1(h), bias), self.dropout, self.training)
        return h + F.dropout(self.ffn(self.norm2(h)), self.dropout, self.training)


class SkeletonEmbedding(nn.Module):
    r"""Topology-aware skeleton embedding (OmniZoo section 4.2.1).

    A per-joint MLP over satagraph's static joint features (``X_l``, ``X_g``
    and the semantic embedding ``X_t``, concatenated), a learned CLS token,
    :obj:`num_layers` Transformer layers whose attention logits get the
    per-head bias ``Emb_dist(hop distance) + Emb_rel(relation)`` plus the key
    padding mask, and :math:`f_{skel} = W\,\mathrm{LN}(h_{CLS}) + b`.

    Skeletons come as one padding-free PyG batch; they are densified (padded
    to the largest) only inside this module. No joint index enters the
    computation, so :math:`f_{skel}` does not depend on the joint order, nor
    on the other skeletons of the batch. Pairs involving the CLS token get a
    distance and a relation id of their own.

    Intended size for satagraph's data (about 18 min of captioned motion plus
    the procedural zoo; a few hundred distinct skeletons): 2-4 layers, 128
    wide, 4 heads; OmniZoo's 140 species would afford more.

    Args:
        in_channels (int): Joint feature width :math:`F_s + D_t`.
        hidden_channels (int, optional): Token width.
        out_channels (int, optional): Width :math:`D_s` of :math:`f_{skel}`.
        heads (int, optional): Attention heads.
        num_layers (int, optional): Transformer layers :math:`L`.
        ff_channels (int, optional): Feed-forward width (default
            ``2 * hidden_channels``).
        dropout (float, optional): Dropout.
        max_hops (int, optional): Hop distances are clipped to this.

    Shapes:
        - **x**: :math:`(N, F_s + D_t)`, **edge_index**: :math:`(2, E)`,
          **batch**: :math:`(N,)`, **root**: :math:`(B,)`
        - **output**: :math:`(B, D_s)`
    """

    def __init__(self, in_channels: int, hidden_channels: int = 64, out_channels: int = 64,
                 heads: int = 4, num_layers: int = 2, ff_channels: Optional[int] = None,
                 dropout: float = 0.0, max_hops: int = 5) -> None:
        super().__init__()
        self.heads, self.max_hops = heads, max_hops
        self.joint_mlp = nn.Sequential(nn.Linear(in_channels, hidden_channels), nn.GELU(),
                                       nn.Linear(hidden_channels, hidden_channels))
        self.cls = nn.Parameter(torch.randn(hidden_channels) * 0.02)
        self.dist_emb = nn.Embedding(max_hops + 2, heads)  # last id: pairs with CLS
        self.rel_emb = nn.Embedding(NUM_RELATIONS + 1, heads)
        nn.init.zeros_(self.dist_emb.weight)
        nn.init.zeros_(self.rel_emb.weight)
        ff = ff_channels or 2 * hidden_channels
        self.layers = nn.ModuleList(TopologyAttentionLayer(hidden_channels, heads, ff, dropout)
                                    for _ in range(num_layers))
        self.norm = nn.LayerNorm(hidden_channels)
        self.lin = nn.Linear(hidden_channels, out_channels)

    def attention_bias(self, topology: SkeletonTopology) -> Tensor:
        r"""Per-head additive bias with the CLS row and column and the key
        padding mask (``-inf``).

        Shapes:
            - **output**: :math:`(B, H, J_{max} + 1, J_{max} + 1)`
        """
        dist = F.pad(topology.distance, (1, 0, 1, 0), value=self.max_hops + 1)
        rel = F.pad(topology.relation, (1, 0, 1, 0), value=NUM_RELATIONS)
        bias = (self.dist_emb(dist) + self.rel_emb(rel)).permute(0, 3, 1, 2)
        keys = F.pad(topology.mask, (1, 0), value=True)
        return bias.masked_fill(~keys[:, None, None, :], float("-inf"))

    def forward(self, x: Tensor, edge_index: Tensor, batch: Optional[Tensor] = None,
                root: Optional[Tensor] = None,
                topology: Optional[SkeletonTopology] = None) -> Tensor:
        """:obj:`topology` may be given to reuse precomputed tables."""
        if batch is None:
            batch = x.new_zeros(x.size(0), dtype=torch.long)
        if topology is None:
            topology = skeleton_topology(edge_index, batch, root, x.size(0), self.max_hops)
        h, _ = to_dense_batch(self.joint_mlp(x), batch)
        h = torch.cat([self.cls.expand(h.size(0), 1, -1), h], dim=1)
        bias = self.attention_bias(topology)
        for layer in self.layers:
            h = layer(h, bias)
        return self.lin(self.norm(h[:, 0]))
