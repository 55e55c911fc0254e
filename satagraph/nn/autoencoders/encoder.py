"""The SATA encoder: modulation, spatio-temporal blocks, max-pool per frame."""
from __future__ import annotations

from typing import Any

import torch
from torch import Tensor
from torch_geometric.nn import global_max_pool

from satagraph.typing import DYNAMIC_CHANNELS, ROOT_CHANNELS
from satagraph.nn.autoencoders.stack import SATAStack


def node_motion_features(frames) -> Tensor:
    r"""Per-node encoder input: the dynamic features with each frame's root
    features ``r`` on its root node (zeros on the other nodes).

    Shapes:
        - **output**: :math:`(N, 22 + 4)`
    """
    root = frames.x.new_zeros(frames.x.shape[0], frames.root.shape[-1])
    root = root.index_copy(0, frames.root_node, frames.root.to(root.dtype))
    return torch.cat([frames.x, root], dim=-1)


class SATAEncoder(SATAStack):
    r"""Encodes a batch of frame graphs into one latent per frame: each
    node's motion features (:func:`node_motion_features`) through a
    :class:`~satagraph.nn.autoencoders.stack.SATAStack` (semantic
    modulation, spatio-temporal blocks), then
    :func:`~torch_geometric.nn.global_max_pool` over each frame's joints.

    Args:
        in_channels (int, optional): Motion features per node (22 dynamic +
            4 root).
        **kwargs: The :class:`~satagraph.nn.autoencoders.stack.SATAStack`
            arguments (``hidden_channels``, ``heads``, ``ff_channels``,
            ``num_blocks``, ``dropout``, ``static_channels``,
            ``semantic_channels``, ``edge_channels``, ``local_conv``,
            ``spatial_attention``, ``temporal``, ``fusion``, ``use_text``,
            ``num_frequencies``, ``act``).

    Shapes:
        - **frames**: :class:`~satagraph.data.FrameBatch` with :math:`N`
          nodes and :math:`G` frame graphs
        - **output**: :math:`(G, C_{hid})`
    """

    def __init__(self, in_channels: int = DYNAMIC_CHANNELS + ROOT_CHANNELS,
                 **kwargs: Any) -> None:
        super().__init__(in_channels, **kwargs)

    def node_embeddings(self, frames) -> Tensor:
        """Node features after the last block, :math:`(N, C_{hid})`."""
        return self.stack(node_motion_features(frames), frames)

    def forward(self, frames) -> Tensor:
        num_frames = frames.root.shape[0]
        return global_max_pool(self.node_embeddings(frames), frames.batch, size=num_frames)
