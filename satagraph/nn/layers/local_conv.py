"""Factory of the local message-passing layer of the spatial branch."""
from __future__ import annotations

import inspect
from typing import Optional

from torch import nn
from torch_geometric.nn import (MLP, GATConv, GATv2Conv, GCNConv, GINConv, GINEConv,
                                MessagePassing, TransformerConv)

#: Names accepted by :func:`build_local_conv` (``None`` means "no GNN").
LOCAL_CONVS = ("gine", "gin", "gat", "gatv2", "gcn", "transformer")


def _edge_mlp(channels: int, act: str) -> nn.Module:
    """The two-layer MLP of GIN(E) (paper section 4.1: two layers, ReLU)."""
    return MLP([channels, channels, channels], act=act, norm=None)


def _per_head(channels: int, heads: int) -> int:
    if channels % heads:
        raise ValueError(f"channels ({channels}) must be divisible by heads ({heads})")
    return channels // heads


def build_local_conv(name: Optional[str], channels: int, heads: int = 4,
                     edge_dim: Optional[int] = None,
                     act: str = "relu") -> Optional[MessagePassing]:
    r"""A local message-passing layer mapping :obj:`channels` to :obj:`channels`.

    Args:
        name (str, optional): One of :data:`LOCAL_CONVS` (``"gine"``: the
            paper's GINEConv with a two-layer ReLU MLP; ``"gin"``;
            ``"gat"``; ``"gatv2"``; ``"gcn"``; ``"transformer"``:
            :class:`~torch_geometric.nn.conv.TransformerConv`), or ``None``
            (also ``"none"``) for no local layer.
        channels (int): Node feature width (input and output).
        heads (int, optional): Attention heads of the attention-based
            layers (their per-head width is ``channels // heads``).
        edge_dim (int, optional): Edge feature width for the layers that use
            edge features (GINE, GAT, GATv2, Transformer).
        act (str, optional): Activation of the GIN(E) MLP.

    Returns:
        The layer, or ``None``. Use :func:`accepts_edge_attr` to know whether
        it takes ``edge_attr``.
    """
    if name is None or str(name).lower() in ("none", "null", ""):
        return None
    key = str(name).lower()
    if key == "gine":
        return GINEConv(_edge_mlp(channels, act), edge_dim=edge_dim)
    if key == "gin":
        return GINConv(_edge_mlp(channels, act))
    if key == "gcn":
        return GCNConv(channels, channels)
    builders = {"gat": GATConv, "gatv2": GATv2Conv, "transformer": TransformerConv}
    if key in builders:
        return builders[key](channels, _per_head(channels, heads), heads=heads,
                             edge_dim=edge_dim)
    raise ValueError(f"unknown local conv {name!r}; known: {LOCAL_CONVS} or None")


def accepts_edge_attr(conv: Optional[nn.Module]) -> bool:
    """Whether :obj:`conv`'s ``forward`` takes an ``edge_attr`` argument."""
    if conv is None:
        return False
    return "edge_attr" in inspect.signature(conv.forward).parameters
