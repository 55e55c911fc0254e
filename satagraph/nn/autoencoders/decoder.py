"""The SATA decoder: per-frame latents broadcast onto a target skeleton."""
from __future__ import annotations

from typing import Any, Dict

from torch import Tensor, nn

from satagraph.typing import ROOT_CHANNELS
from satagraph.nn.autoencoders.stack import SATAStack

#: Output widths: 6D rotation per node, root features per frame, contact logit.
Q_CHANNELS, C_CHANNELS = 6, 1


class SATADecoder(SATAStack):
    r"""Decodes one latent per frame onto the nodes of a target batch.

    Every frame's latent is broadcast to all nodes of the target frame graph
    (``z[target.batch]``) and fused with the target's static and semantic
    features by the input layer (the latent plays the role of the motion
    features :math:`F_m`); after :obj:`num_blocks` spatio-temporal blocks a
    linear head predicts ``[q (6), r (4), c (1)]`` per node; ``r`` is read at
    each frame's root node.

    Args:
        latent_channels (int, optional): Latent width.
        **kwargs: The :class:`~satagraph.nn.autoencoders.stack.SATAStack`
            arguments, as in :class:`~satagraph.nn.SATAEncoder`.

    Shapes:
        - **z**: :math:`(G, C_{lat})`, frames in the order of the target's
          frame graphs
        - **frames**: target :class:`~satagraph.data.FrameBatch` with
          :math:`G` frame graphs and :math:`N` nodes
        - **output**: ``{"q": (N, 6), "r": (G, 4), "c": (N, 1)}`` (contact
          logits)
    """

    def __init__(self, latent_channels: int = 128, **kwargs: Any) -> None:
        super().__init__(latent_channels, **kwargs)
        self.head = nn.Linear(self.hidden_channels, Q_CHANNELS + ROOT_CHANNELS + C_CHANNELS)

    def forward(self, z: Tensor, frames) -> Dict[str, Tensor]:
        if z.shape[0] != frames.root.shape[0]:
            raise ValueError(f"SATADecoder: {z.shape[0]} latents for "
                             f"{frames.root.shape[0]} target frames")
        out = self.head(self.stack(z[frames.batch], frames))
        q, r, c = out.split([Q_CHANNELS, ROOT_CHANNELS, C_CHANNELS], dim=-1)
        return {"q": q, "r": r[frames.root_node], "c": c}
