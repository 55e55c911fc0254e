"""Factory of the local message-passing layer of the spatial branch, and
its registry: :func:`register_local_conv` makes any PyG layer a
``model.local_conv`` name (a GNN-layer ablation of one's own)."""
from __future__ import annotations

import inspect
from typing import Callable, Dict, Optional, Tuple

import torch
from torch import nn
from torch_geometric.nn import (MLP, GATConv, GATv2Conv, GCNConv, GINConv, GINEConv,
                                MessagePassing, TransformerConv)

from satagraph.utils.registry import register_name


def _edge_mlp(channels: int, act: str) -> nn.Module:
    """The two-layer MLP of GIN(E) (paper section 4.1: two layers, ReLU)."""
    return MLP([channels, channels, channels], act=act, norm=None)


def _per_head(channels: int, heads: int) -> int:
    if channels % heads:
        raise ValueError(f"channels ({channels}) must be divisible by heads ({heads})")
    return channels // heads


def _attention(cls: type) -> Callable[..., MessagePassing]:
    def build(channels: int, heads: int, edge_dim: Optional[int], act: str) -> MessagePassing:
        return cls(channels, _per_head(channels, heads), heads=heads, edge_dim=edge_dim)
    return build


#: Builders ``(channels, heads, edge_dim, act) -> layer`` by name: the
#: built-in :data:`LOCAL_CONVS` and those :func:`register_local_conv` adds.
_BUILDERS: Dict[str, Callable[..., MessagePassing]] = {
    "gine": lambda channels, heads, edge_dim, act: GINEConv(_edge_mlp(channels, act),
                                                             edge_dim=edge_dim),
    "gin": lambda channels, heads, edge_dim, act: GINConv(_edge_mlp(channels, act)),
    "gcn": lambda channels, heads, edge_dim, act: GCNConv(channels, channels),
    "gat": _attention(GATConv), "gatv2": _attention(GATv2Conv),
    "transformer": _attention(TransformerConv),
}


#: Names of the built-in local layers (``None`` means "no GNN").
LOCAL_CONVS = tuple(_BUILDERS)
#: Names that mean no local layer.
NO_CONV = ("none", "null", "")


def register_local_conv(name: str, builder: Callable[..., MessagePassing]) -> None:
    r"""Make :obj:`builder` the local layer ``model.local_conv=name`` names.

    Example::

        from torch_geometric.nn import GraphConv
        from satagraph.nn import register_local_conv

        register_local_conv("graph", lambda channels, heads, edge_dim, act:
                            GraphConv(channels, channels))
        # satagraph train tiny model.local_conv=graph (with SATAGRAPH_PLUGINS
        # naming the file that registers it), or a sweep over it

    Args:
        name (str): The name (case-insensitive; not a built-in one).
        builder (callable): ``(channels, heads, edge_dim, act)`` -> a layer
            mapping :obj:`channels` to :obj:`channels` per node, called as
            ``layer(x, edge_index)`` or, when its ``forward`` takes one,
            ``layer(x, edge_index, edge_attr)`` (:obj:`edge_dim` wide).

    Raises:
        ValueError: The name is taken.
    """
    register_name(_BUILDERS, str(name).lower(), builder, "local conv", reserved=NO_CONV)


def local_conv_names() -> Tuple[str, ...]:
    """Every name :func:`build_local_conv` takes, registered ones included."""
    return tuple(_BUILDERS)


def build_local_conv(name: Optional[str], channels: int, heads: int = 4,
                     edge_dim: Optional[int] = None,
                     act: str = "relu") -> Optional[MessagePassing]:
    r"""A local message-passing layer mapping :obj:`channels` to :obj:`channels`.

    Args:
        name (str, optional): One of :data:`LOCAL_CONVS` (``"gine"``: the
            paper's GINEConv with a two-layer ReLU MLP; ``"gin"``;
            ``"gat"``; ``"gatv2"``; ``"gcn"``; ``"transformer"``:
            :class:`~torch_geometric.nn.conv.TransformerConv`), a name
            :func:`register_local_conv` added, or ``None`` (also ``"none"``)
            for no local layer.
        channels (int): Node feature width (input and output).
        heads (int, optional): Attention heads of the attention-based
            layers (their per-head width is ``channels // heads``).
        edge_dim (int, optional): Edge feature width for the layers that use
            edge features (GINE, GAT, GATv2, Transformer).
        act (str, optional): Activation of the GIN(E) MLP.

    Returns:
        The layer, or ``None``. Use :func:`accepts_edge_attr` to know whether
        it takes ``edge_attr``.

    Raises:
        ValueError: No layer has that name, or a registered layer's output
            is not :obj:`channels` wide.
    """
    key = check_local_conv(name)
    if key is None:
        return None
    conv = _BUILDERS[key](channels, heads, edge_dim, act)
    if key not in LOCAL_CONVS:
        _check_width(key, conv, channels, edge_dim)
    return conv


def _check_width(name: str, conv: nn.Module, channels: int, edge_dim: Optional[int]) -> None:
    """Refuse a registered layer that does not map :obj:`channels` to
    :obj:`channels`, probed once on a two-joint frame graph (in evaluation
    mode, the random state kept): one of another width, such as a
    ``GATConv(channels, channels, heads=heads)`` concatenating its heads,
    was a bare size mismatch in the block's residual sum at the first batch.
    A layer that cannot run on the probe is left to its first batch."""
    x, edge_index = torch.zeros(2, channels), torch.tensor([[0, 1], [1, 0]])
    args = (x, edge_index)
    if edge_dim and accepts_edge_attr(conv):
        args += (torch.zeros(2, edge_dim),)
    training = conv.training
    try:
        with torch.no_grad(), torch.random.fork_rng(devices=[]):
            out = conv.eval()(*args)
    except Exception:  # noqa: BLE001 - only the width is judged here
        return
    finally:
        conv.train(training)
    shape = tuple(out.shape) if isinstance(out, torch.Tensor) else None
    if shape != (2, channels):
        got = shape[1] if shape and len(shape) == 2 else shape or type(out).__name__
        raise ValueError(f"local conv {name!r} maps {channels} channels per node to {got}: "
                         "its register_local_conv builder must return a layer whose output "
                         "is channels wide (heads * (channels // heads) for one that "
                         "concatenates its heads)")


def check_local_conv(name: Optional[str]) -> Optional[str]:
    """The registered key of a local layer's name; ``None`` for no layer
    (``None``, ``"none"``).

    Raises:
        ValueError: No layer has that name (one line: the known ones).
    """
    key = None if name is None else str(name).lower()
    if key is None or key in NO_CONV:
        return None
    if key not in _BUILDERS:
        raise ValueError(f"unknown local conv {name!r}; known: {', '.join(_BUILDERS)} or "
                         "None (register_local_conv adds one)")
    return key


def accepts_edge_attr(conv: Optional[nn.Module]) -> bool:
    """Whether :obj:`conv`'s ``forward`` takes an ``edge_attr`` argument."""
    if conv is None:
        return False
    return "edge_attr" in inspect.signature(conv.forward).parameters
