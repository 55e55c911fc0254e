"""What the SATA encoder and decoder share: an input layer that fuses
per-node inputs with the skeleton's static and semantic features, then
spatio-temporal blocks."""
from __future__ import annotations

from typing import Optional

from torch import Tensor, nn

from satagraph.typing import STATIC_CHANNELS
from satagraph.nn.layers.modulation import build_input_layer
from satagraph.nn.layers.spatio_temporal import make_blocks


class SATAStack(nn.Module):
    r"""Input layer (:class:`~satagraph.nn.SemanticModulation`, or a plain
    projection of ``[input, static]`` when :obj:`fusion` is off), then
    :obj:`num_blocks` :class:`~satagraph.nn.SpatioTemporalBlock` layers:
    the trunk of :class:`~satagraph.nn.SATAEncoder` (per-node motion in)
    and :class:`~satagraph.nn.SATADecoder` (each frame's latent on every
    node in).

    Args:
        in_channels (int): Per-node input width.
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
            projection of ``[input, static]``, no semantics).
        use_text (bool, optional): Semantic features in the modulation.
        num_frequencies (int, optional): Octaves of the static sinusoidal
            encoder.
        act (str, optional): Activation.

    Shapes:
        - **h**: :math:`(N, C_{in})` per-node input
        - **frames**: :class:`~satagraph.data.FrameBatch` with :math:`N` nodes
        - **output**: :math:`(N, C_{hid})`
    """

    def __init__(self, in_channels: int, hidden_channels: int = 256, heads: int = 4,
                 ff_channels: int = 512, num_blocks: int = 3, dropout: float = 0.1,
                 static_channels: int = STATIC_CHANNELS, semantic_channels: int = 0,
                 edge_channels: int = 2, local_conv: Optional[str] = "gine",
                 spatial_attention: bool = True, temporal: bool = True,
                 fusion: bool = True, use_text: bool = True, num_frequencies: int = 8,
                 act: str = "relu") -> None:
        super().__init__()
        self.hidden_channels = hidden_channels
        self.input = build_input_layer(
            in_channels, hidden_channels, fusion, static_channels=static_channels,
            semantic_channels=semantic_channels, num_frequencies=num_frequencies,
            use_text=use_text, act=act)
        self.blocks = make_blocks(
            num_blocks, hidden_channels, heads=heads, ff_channels=ff_channels,
            dropout=dropout, local_conv=local_conv, spatial_attention=spatial_attention,
            temporal=temporal, edge_channels=edge_channels, act=act)

    def stack(self, h: Tensor, frames) -> Tensor:
        """The per-node input :obj:`h` through the input layer and the blocks."""
        h = self.input(h, frames.joint_static, frames.joint_semantic, frames.node_stream)
        for block in self.blocks:
            h = block(h, frames)
        return h


__all__ = ["SATAStack"]
