r"""The spatio-temporal interleaved block (SATA paper, section 3.3): a
GPS-style spatial layer over each frame graph, then a Transformer over each
joint's temporal stream."""
from __future__ import annotations

import math
from typing import Optional

import torch
from torch import Tensor, nn
from torch_geometric.nn.resolver import activation_resolver

from satagraph.nn.layers.dropout import fast_dropout, use_fast_dropout
from satagraph.nn.layers.frame_gps import FrameGPSConv
from satagraph.nn.layers.local_conv import accepts_edge_attr, build_local_conv
from satagraph.ops.temporal import from_temporal_streams, to_temporal_streams


def sinusoidal_positions(length: int, channels: int, device=None,
                         dtype=torch.float) -> Tensor:
    r"""Transformer sinusoidal position encodings :math:`(T, C)`
    (``sin`` on even, ``cos`` on odd channels)."""
    pos = torch.arange(length, device=device, dtype=dtype)[:, None]
    rate = torch.exp(torch.arange(0, channels, 2, device=device, dtype=dtype)
                     * (-math.log(10000.0) / channels))
    out = torch.zeros(length, channels, device=device, dtype=dtype)
    out[:, 0::2] = torch.sin(pos * rate)
    out[:, 1::2] = torch.cos(pos * rate)[:, : channels // 2]
    return out


class LocalSpatialLayer(nn.Module):
    r"""GPSConv without its attention path: local conv, dropout, residual and
    norm, then a residual MLP and norm (the "w/o spatial Transformer" layer).

    Args:
        channels (int): Node feature width.
        conv (nn.Module): The local message-passing layer.
        dropout (float, optional): Dropout probability.
        act (str, optional): MLP activation.

    Shapes:
        - **x**: :math:`(N, C)`, **output**: :math:`(N, C)`
    """

    def __init__(self, channels: int, conv: nn.Module, dropout: float = 0.0,
                 act: str = "relu") -> None:
        super().__init__()
        self.conv, self.dropout = conv, dropout
        self.mlp = nn.Sequential(nn.Linear(channels, 2 * channels), activation_resolver(act),
                                 nn.Dropout(dropout), nn.Linear(2 * channels, channels),
                                 nn.Dropout(dropout))
        self.norm1, self.norm2 = nn.LayerNorm(channels), nn.LayerNorm(channels)

    def forward(self, x: Tensor, edge_index: Tensor, batch: Optional[Tensor] = None,
                **kwargs) -> Tensor:
        h = fast_dropout(self.conv(x, edge_index, **kwargs), self.dropout, self.training)
        h = self.norm1(h + x)
        return self.norm2(h + self.mlp(h))


class SpatioTemporalBlock(nn.Module):
    r"""One spatio-temporal interleaved block.

    Spatial part: :class:`~torch_geometric.nn.conv.GPSConv` (local conv +
    multi-head self-attention within each frame graph, summed, MLP,
    residuals, node-wise layer norm), as
    :class:`~satagraph.nn.layers.frame_gps.FrameGPSConv` so that the attention runs
    per skeleton without padding; bone features (depth, reverse depth)
    are embedded to :obj:`channels` by a linear layer for the local convs that
    take edge features. Temporal part: every joint stream is gathered with
    :func:`~satagraph.ops.temporal.to_temporal_streams`, sinusoidal position
    encodings are added, a :class:`torch.nn.TransformerEncoderLayer` runs with
    the padding mask, and the stream is scattered back.

    Args:
        channels (int): Node feature width.
        heads (int, optional): Attention heads (spatial and temporal).
        ff_channels (int, optional): Feed-forward width of the temporal
            Transformer layer.
        dropout (float, optional): Dropout probability.
        local_conv (str, optional): See
            :func:`~satagraph.nn.layers.local_conv.build_local_conv`; ``None``: no GNN.
        spatial_attention (bool, optional): Per-frame self-attention
            (``False``: ablation "w/o spatial TF").
        temporal (bool, optional): Temporal Transformer (``False``: ablation
            "w/o temporal TF").
        edge_channels (int, optional): Width of the bone features.
        act (str, optional): Activation of the MLPs.

    Shapes:
        - **x**: :math:`(N, C)` node features, in the node order of
          :obj:`frames`
        - **frames**: a :class:`~satagraph.data.FrameBatch` (``edge_index``,
          ``edge_attr``, ``batch`` and the stream attributes)
        - **output**: :math:`(N, C)`
    """

    def __init__(self, channels: int, heads: int = 4, ff_channels: int = 512,
                 dropout: float = 0.1, local_conv: Optional[str] = "gine",
                 spatial_attention: bool = True, temporal: bool = True,
                 edge_channels: int = 2, act: str = "relu") -> None:
        super().__init__()
        if heads < 1 or channels % heads:
            raise ValueError(f"model.hidden_channels={channels} must be a multiple of "
                             f"model.heads={heads} (each head attends over an equal share)")
        conv = build_local_conv(local_conv, channels, heads, edge_dim=channels, act=act)
        self.use_edge_attr = accepts_edge_attr(conv)
        self.edge_lin = nn.Linear(edge_channels, channels) if self.use_edge_attr else None
        self.spatial = self._spatial(channels, conv, heads, dropout, spatial_attention, act)
        self.temporal = nn.TransformerEncoderLayer(
            channels, heads, ff_channels, dropout, batch_first=True) if temporal else None
        use_fast_dropout(self)  # torch's CPU dropout draws one number per element

    @staticmethod
    def _spatial(channels: int, conv: Optional[nn.Module], heads: int, dropout: float,
                 attention: bool, act: str) -> Optional[nn.Module]:
        if attention:
            gps = FrameGPSConv(channels, conv, heads=heads, dropout=dropout, act=act,
                          norm="layer_norm", norm_kwargs={"mode": "node"},
                          attn_type="multihead")
            if conv is None:  # norm1 follows the local conv only: drop the unused
                gps.norm1 = None  # parameters (DDP rejects unused parameters)
            return gps
        return LocalSpatialLayer(channels, conv, dropout, act) if conv is not None else None

    def spatial_forward(self, x: Tensor, frames) -> Tensor:
        """The spatial part alone (identity when it is disabled)."""
        if self.spatial is None:
            return x
        kwargs = {}
        if self.use_edge_attr:
            kwargs["edge_attr"] = self.edge_lin(frames.edge_attr.to(x.dtype))
        if isinstance(self.spatial, FrameGPSConv):
            kwargs["frames"] = frames  # attention per skeleton, without padding
        return self.spatial(x, frames.edge_index, frames.batch, **kwargs)

    def temporal_forward(self, x: Tensor, frames) -> Tensor:
        """The temporal part alone (identity when it is disabled)."""
        if self.temporal is None:
            return x
        streams, mask = to_temporal_streams(x, frames)
        pos = sinusoidal_positions(streams.shape[1], streams.shape[2], x.device, x.dtype)
        streams = self.temporal(streams + pos, src_key_padding_mask=~mask)
        return from_temporal_streams(streams, frames)

    def forward(self, x: Tensor, frames) -> Tensor:
        return self.temporal_forward(self.spatial_forward(x, frames), frames)


def make_blocks(num_blocks: int, channels: int, **kwargs) -> nn.ModuleList:
    """:obj:`num_blocks` :class:`SpatioTemporalBlock` layers of width
    :obj:`channels` (:obj:`kwargs` go to each)."""
    return nn.ModuleList(SpatioTemporalBlock(channels, **kwargs) for _ in range(num_blocks))
