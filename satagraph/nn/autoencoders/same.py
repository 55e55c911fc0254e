"""SAME (Lee et al., 2023): a per-frame graph-attention autoencoder, the
topology-agnostic baseline of the SATA paper."""
from __future__ import annotations

from typing import Dict, List

import torch
from torch import Tensor, nn
from torch_geometric.nn import GATConv, GATv2Conv, global_max_pool
from torch_geometric.nn.resolver import activation_resolver

from satagraph.nn.autoencoders.base import MotionAutoencoder
from satagraph.typing import DYNAMIC_CHANNELS, ROOT_CHANNELS, STATIC_CHANNELS
from satagraph.nn.autoencoders.decoder import C_CHANNELS, Q_CHANNELS
from satagraph.nn.autoencoders.encoder import node_motion_features

#: Graph attention layers by name.
SAME_CONVS = {"gat": GATConv, "gatv2": GATv2Conv}


def _gat(conv: str, in_channels: int, out_channels: int, heads: int, edge_dim: int,
         dropout: float) -> nn.Module:
    """One attention layer; :obj:`out_channels` is the concatenated width."""
    if conv not in SAME_CONVS:
        raise ValueError(f"unknown SAME conv {conv!r}; known: {sorted(SAME_CONVS)}")
    if out_channels % heads:
        raise ValueError(f"channels ({out_channels}) must be divisible by heads ({heads})")
    return SAME_CONVS[conv](in_channels, out_channels // heads, heads=heads,
                            edge_dim=edge_dim, dropout=dropout, add_self_loops=True)


class SAMEEncoder(nn.Module):
    r"""Graph-attention encoder of SAME: per frame, :obj:`num_layers`
    attention layers over the skeleton graph (bones in both directions,
    edge features = (depth, reverse depth)), then
    :func:`~torch_geometric.nn.global_max_pool` over the frame's joints.

    The input per node is ``[motion, X_l, X_g]`` (22 dynamic + 4 root
    features on the root node + 6 static = 32, as SAME). Hidden layers
    have :obj:`heads` heads (concatenated); the last has one head and
    :obj:`latent_channels` outputs.

    Args:
        in_channels (int, optional): Motion features per node.
        hidden_channels (int, optional): Width of the hidden layers (SAME:
            256 = 16 heads x 16).
        latent_channels (int, optional): Latent width per frame (SAME: 32).
        num_layers (int, optional): Hidden attention layers (SAME: 3).
        heads (int, optional): Heads of the hidden layers (SAME: 16).
        static_channels (int, optional): ``[X_l, X_g]`` width.
        edge_channels (int, optional): Bone feature width.
        conv (str, optional): ``"gat"`` or ``"gatv2"``.
        dropout (float, optional): Attention dropout.
        act (str, optional): Activation between layers.

    Shapes:
        - **frames**: :class:`~satagraph.data.FrameBatch` with :math:`G`
          frame graphs
        - **output**: :math:`(G, C_{lat})`
    """

    def __init__(self, in_channels: int = DYNAMIC_CHANNELS + ROOT_CHANNELS,
                 hidden_channels: int = 256, latent_channels: int = 32,
                 num_layers: int = 3, heads: int = 16,
                 static_channels: int = STATIC_CHANNELS, edge_channels: int = 2,
                 conv: str = "gat", dropout: float = 0.0, act: str = "relu") -> None:
        super().__init__()
        widths = [in_channels + static_channels] + [hidden_channels] * num_layers
        self.convs = nn.ModuleList(
            _gat(conv, c_in, c_out, heads, edge_channels, dropout)
            for c_in, c_out in zip(widths[:-1], widths[1:]))
        self.convs.append(_gat(conv, widths[-1], latent_channels, 1, edge_channels, dropout))
        self.act = activation_resolver(act)

    def forward(self, frames) -> Tensor:
        static = frames.joint_static[frames.node_stream]
        h = torch.cat([node_motion_features(frames), static.to(frames.x.dtype)], dim=-1)
        edge_attr = frames.edge_attr.to(h.dtype)
        for i, conv in enumerate(self.convs):
            h = conv(h, frames.edge_index, edge_attr)
            if i < len(self.convs) - 1:
                h = self.act(h)
        return global_max_pool(h, frames.batch, size=frames.root.shape[0])


class SAMEDecoder(nn.Module):
    r"""Graph-attention decoder of SAME: every frame's latent is broadcast to
    the nodes of the target frame graph and concatenated with the target's
    static features ``[X_l, X_g]``; every later layer sees its input
    concatenated with ``[X_l, X_g]`` again (and the latent, when
    :obj:`latent_every_layer`). The last layer (one head) predicts
    ``[q (6), r (4), c (1)]`` per node; ``r`` is read at each frame's root.

    Args:
        latent_channels (int, optional): Latent width (SAME: 32).
        hidden_channels (int, optional): Width of the hidden layers.
        num_layers (int, optional): Hidden attention layers (SAME: 3).
        heads (int, optional): Heads of the hidden layers.
        static_channels (int, optional): ``[X_l, X_g]`` width.
        edge_channels (int, optional): Bone feature width.
        conv (str, optional): ``"gat"`` or ``"gatv2"``.
        dropout (float, optional): Attention dropout.
        latent_every_layer (bool, optional): Concatenate the latent at every
            layer too (SAME's code concatenates it at the input only).
        act (str, optional): Activation between layers.

    Shapes:
        - **z**: :math:`(G, C_{lat})`
        - **frames**: target :class:`~satagraph.data.FrameBatch` with
          :math:`G` frame graphs and :math:`N` nodes
        - **output**: ``{"q": (N, 6), "r": (G, 4), "c": (N, 1)}`` (contact
          logits)
    """

    def __init__(self, latent_channels: int = 32, hidden_channels: int = 256,
                 num_layers: int = 3, heads: int = 16,
                 static_channels: int = STATIC_CHANNELS, edge_channels: int = 2,
                 conv: str = "gat", dropout: float = 0.0,
                 latent_every_layer: bool = True, act: str = "relu") -> None:
        super().__init__()
        self.latent_every_layer = latent_every_layer
        extra = static_channels + (latent_channels if latent_every_layer else 0)
        widths = [latent_channels + static_channels] + [hidden_channels + extra] * num_layers
        outs = [hidden_channels] * num_layers
        self.convs = nn.ModuleList(
            _gat(conv, c_in, c_out, heads, edge_channels, dropout)
            for c_in, c_out in zip(widths[:-1], outs))
        out_channels = Q_CHANNELS + ROOT_CHANNELS + C_CHANNELS
        self.convs.append(_gat(conv, widths[-1], out_channels, 1, edge_channels, dropout))
        self.act = activation_resolver(act)

    def _skip(self, z_node: Tensor, static: Tensor) -> List[Tensor]:
        return [z_node, static] if self.latent_every_layer else [static]

    def forward(self, z: Tensor, frames) -> Dict[str, Tensor]:
        if z.shape[0] != frames.root.shape[0]:
            raise ValueError(f"SAMEDecoder: {z.shape[0]} latents for "
                             f"{frames.root.shape[0]} target frames")
        z_node = z[frames.batch]
        static = frames.joint_static[frames.node_stream].to(z.dtype)
        edge_attr = frames.edge_attr.to(z.dtype)
        h = torch.cat([z_node, static], dim=-1)
        for i, conv in enumerate(self.convs):
            if i > 0:
                h = torch.cat([self.act(h)] + self._skip(z_node, static), dim=-1)
            h = conv(h, frames.edge_index, edge_attr)
        q, r, c = h.split([Q_CHANNELS, ROOT_CHANNELS, C_CHANNELS], dim=-1)
        return {"q": q, "r": r[frames.root_node], "c": c}


class SAME(MotionAutoencoder):
    r"""The SAME autoencoder (Lee et al., 2023), re-implemented on frame
    graphs: :class:`SAMEEncoder` (one deterministic latent per frame, no
    temporal layers) and :class:`SAMEDecoder` onto any target skeleton.
    It has the interface of :class:`~satagraph.nn.SATA`, so the same
    losses, metrics and inference apply; temporal losses act over the
    training windows. There is no bottleneck term (no ``kl`` or
    ``commit``).

    Defaults are SAME's own widths (``config/mycfg.yml``: 16 heads x 16,
    three hidden layers, 32-D latent; about 0.3 M parameters). The SATA
    paper widens it to 5.98 M parameters (``experiments/same_wide.yaml``).

    Args:
        hidden_channels (int, optional): Width of the hidden layers.
        latent_channels (int, optional): Latent width per frame.
        num_layers (int, optional): Hidden layers of the encoder and of the
            decoder.
        heads (int, optional): Heads of the hidden layers.
        conv (str, optional): ``"gat"`` (SAME) or ``"gatv2"``.
        dropout (float, optional): Attention dropout.
        latent_every_layer (bool, optional): See :class:`SAMEDecoder`.
        act (str, optional): Activation.

    Shapes:
        - **batch**, **target_batch**: :class:`~satagraph.data.FrameBatch`
          with the same frame graphs (clip lengths) :math:`G`; :math:`N` is
          the number of nodes of the target
        - **output** of :meth:`forward`: ``q`` :math:`(N, 6)`, ``r``
          :math:`(G, 4)`, ``c`` :math:`(N, 1)` (logits), ``z``
          :math:`(G, C_{lat})`
    """

    def __init__(self, hidden_channels: int = 256, latent_channels: int = 32,
                 num_layers: int = 3, heads: int = 16, conv: str = "gat",
                 dropout: float = 0.0, latent_every_layer: bool = True,
                 act: str = "relu") -> None:
        super().__init__()
        shared = dict(hidden_channels=hidden_channels, latent_channels=latent_channels,
                      num_layers=num_layers, heads=heads, conv=conv, dropout=dropout,
                      act=act)
        self.encoder = SAMEEncoder(**shared)
        self.decoder = SAMEDecoder(latent_every_layer=latent_every_layer, **shared)

    def encode(self, batch) -> Dict[str, Tensor]:
        """Latent per frame, ``{"z": (G, C_lat)}``."""
        return {"z": self.encoder(batch)}

    def decode(self, z: Tensor, target_batch) -> Dict[str, Tensor]:
        """``q``, ``r``, ``c`` (logits) on the target frame graphs."""
        return self.decoder(z, target_batch)
