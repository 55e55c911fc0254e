"""The SATA decoder: per-frame latents broadcast onto a target skeleton."""
from __future__ import annotations

from typing import Dict, Optional

from torch import Tensor, nn

from satagraph.typing import ROOT_CHANNELS, STATIC_CHANNELS
from satagraph.nn.layers.modulation import build_input_layer
from satagraph.nn.layers.spatio_temporal import make_blocks

#: Output widths: 6D rotation per node, root features per frame, contact logit.
Q_CHANNELS, C_CHANNELS = 6, 1


class SATADecoder(nn.Module):
    r"""Decodes one latent per frame onto the nodes of a target batch.

    Every frame's latent is broadcast to all nodes of the target frame graph
    (``z[target.batch]``) and fused with the target's static and semantic
    features by the input layer (the latent plays the role of the motion
    features :math:`F_m`); after :obj:`num_blocks` spatio-temporal blocks a
    linear head predicts ``[q (6), r (4), c (1)]`` per node; ``r`` is read at
    each frame's root node.

    Args:
        latent_channels (int, optional): Latent width.
        hidden_channels, heads, ff_channels, num_blocks, dropout,
        static_channels, semantic_channels, edge_channels, local_conv,
        spatial_attention, temporal, fusion, use_text, num_frequencies, act:
            As in :class:`~satagraph.nn.SATAEncoder`.

    Shapes:
        - **z**: :math:`(G, C_{lat})`, frames in the order of the target's
          frame graphs
        - **frames**: target :class:`~satagraph.data.FrameBatch` with
          :math:`G` frame graphs and :math:`N` nodes
        - **output**: ``{"q": (N, 6), "r": (G, 4), "c": (N, 1)}`` (contact
          logits)
    """

    def __init__(self, latent_channels: int = 128, hidden_channels: int = 256,
                 heads: int = 4, ff_channels: int = 512, num_blocks: int = 3,
                 dropout: float = 0.1, static_channels: int = STATIC_CHANNELS,
                 semantic_channels: int = 0, edge_channels: int = 2,
                 local_conv: Optional[str] = "gine", spatial_attention: bool = True,
                 temporal: bool = True, fusion: bool = True, use_text: bool = True,
                 num_frequencies: int = 8, act: str = "relu") -> None:
        super().__init__()
        self.input = build_input_layer(
            latent_channels, hidden_channels, fusion, static_channels=static_channels,
            semantic_channels=semantic_channels, num_frequencies=num_frequencies,
            use_text=use_text, act=act)
        self.blocks = make_blocks(
            num_blocks, hidden_channels, heads=heads, ff_channels=ff_channels,
            dropout=dropout, local_conv=local_conv, spatial_attention=spatial_attention,
            temporal=temporal, edge_channels=edge_channels, act=act)
        self.head = nn.Linear(hidden_channels, Q_CHANNELS + ROOT_CHANNELS + C_CHANNELS)

    def forward(self, z: Tensor, frames) -> Dict[str, Tensor]:
        if z.shape[0] != frames.root.shape[0]:
            raise ValueError(f"SATADecoder: {z.shape[0]} latents for "
                             f"{frames.root.shape[0]} target frames")
        h = self.input(z[frames.batch], frames.joint_static, frames.joint_semantic,
                       frames.node_stream)
        for block in self.blocks:
            h = block(h, frames)
        out = self.head(h)
        q, r, c = out.split([Q_CHANNELS, ROOT_CHANNELS, C_CHANNELS], dim=-1)
        return {"q": q, "r": r[frames.root_node], "c": c}
