"""The SATA encoder: modulation, spatio-temporal blocks, max-pool per frame."""
from __future__ import annotations

from typing import Optional

import torch
from torch import Tensor, nn
from torch_geometric.nn import global_max_pool

from satagraph.typing import DYNAMIC_CHANNELS, ROOT_CHANNELS, STATIC_CHANNELS
from satagraph.nn.layers.modulation import build_input_layer
from satagraph.nn.layers.spatio_temporal import make_blocks


def node_motion_features(frames) -> Tensor:
    r"""Per-node encoder input: the dynamic features with each frame's root
    features ``r`` on its root node (zeros on the other nodes).

    Shapes:
        - **output**: :math:`(N, 22 + 4)`
    """
    root = frames.x.new_zeros(frames.x.shape[0], frames.root.shape[-1])
    root = root.index_copy(0, frames.root_node, frames.root.to(root.dtype))
    return torch.cat([frames.x, root], dim=-1)


class SATAEncoder(nn.Module):
    r"""Encodes a batch of frame graphs into one latent per frame.

    Input layer (:class:`~satagraph.nn.SemanticModulation`, or a plain
    projection of ``[motion, static]`` when :obj:`fusion` is off), then
    :obj:`num_blocks` :class:`~satagraph.nn.SpatioTemporalBlock` layers, then
    :func:`~torch_geometric.nn.global_max_pool` over each frame's joints.

    Args:
        in_channels (int, optional): Motion features per node (22 dynamic +
            4 root).
        hidden_channels (int, optional): Width of the blocks (paper: 256).
        heads (int, optional): Attention heads (paper: 4).
        ff_channels (int, optional): Temporal feed-forward width (paper: 512).
        num_blocks (int, optional): Spatio-temporal blocks (paper: 3).
        dropout (float, optional): Dropout probability (paper: 0.1).
        static_channels (int, optional): ``[X_l, X_g]`` width (6).
        semantic_channels (int, optional): :math:`D_t` (0: none).
        edge_channels (int, optional): Bone feature width (2).
        local_conv (str, optional): Local GNN (``None``: no GNN).
        spatial_attention (bool, optional): Per-frame self-attention.
        temporal (bool, optional): Temporal Transformer.
        fusion (bool, optional): Semantic modulation (``False``: plain
            projection of ``[motion, static]``, no semantics).
        use_text (bool, optional): Semantic features in the modulation.
        num_frequencies (int, optional): Octaves of the static sinusoidal
            encoder.
        act (str, optional): Activation.

    Shapes:
        - **frames**: :class:`~satagraph.data.FrameBatch` with :math:`N`
          nodes and :math:`G` frame graphs
        - **output**: :math:`(G, C_{hid})`
    """

    def __init__(self, in_channels: int = DYNAMIC_CHANNELS + ROOT_CHANNELS,
                 hidden_channels: int = 256, heads: int = 4, ff_channels: int = 512,
                 num_blocks: int = 3, dropout: float = 0.1,
                 static_channels: int = STATIC_CHANNELS, semantic_channels: int = 0,
                 edge_channels: int = 2, local_conv: Optional[str] = "gine",
                 spatial_attention: bool = True, temporal: bool = True,
                 fusion: bool = True, use_text: bool = True, num_frequencies: int = 8,
                 act: str = "relu") -> None:
        super().__init__()
        self.input = build_input_layer(
            in_channels, hidden_channels, fusion, static_channels=static_channels,
            semantic_channels=semantic_channels, num_frequencies=num_frequencies,
            use_text=use_text, act=act)
        self.blocks = make_blocks(
            num_blocks, hidden_channels, heads=heads, ff_channels=ff_channels,
            dropout=dropout, local_conv=local_conv, spatial_attention=spatial_attention,
            temporal=temporal, edge_channels=edge_channels, act=act)

    def node_embeddings(self, frames) -> Tensor:
        """Node features after the last block, :math:`(N, C_{hid})`."""
        h = self.input(node_motion_features(frames), frames.joint_static,
                       frames.joint_semantic, frames.node_stream)
        for block in self.blocks:
            h = block(h, frames)
        return h

    def forward(self, frames) -> Tensor:
        num_frames = frames.root.shape[0]
        return global_max_pool(self.node_embeddings(frames), frames.batch, size=num_frames)
