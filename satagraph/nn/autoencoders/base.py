"""The contract every motion autoencoder keeps (what Lightning modules,
inference and generators consume)."""
from __future__ import annotations

from typing import Dict

from torch import Tensor, nn


class MotionAutoencoder(nn.Module):
    r"""Base class of the motion autoencoders: :meth:`encode` a (normalised)
    :class:`~satagraph.data.FrameBatch` into latents, :meth:`decode` them
    onto the frame graphs of any target batch, :meth:`forward` both.

    Latents come at :attr:`latent_rate` frames per latent step: with rate 1
    (SATA, SAME) ``z`` has one row per frame graph, in the batch's frame
    order, so the latents of some frames can be decoded onto another
    skeleton's frames (what the unpaired retargeting term does); with rate
    :math:`k > 1` (the padded baseline) every clip has
    :math:`\lceil T_s / k \rceil` rows, clip after clip.

    Subclasses implement :meth:`encode` and :meth:`decode`.

    Shapes:
        - **encode** output: ``{"z": (L, C_lat), ...}`` with :math:`L = G`
          at rate 1, plus bottleneck terms (``kl``, ``commit``, ``codes``)
        - **decode** output: ``{"q": (N, 6), "r": (G, 4), "c": (N, 1)}``
          (normalised rotations, root features, contact logits) on the
          target's :math:`N` nodes and :math:`G` frames
    """

    #: Frames per latent step.
    latent_rate: int = 1

    def encode(self, batch) -> Dict[str, Tensor]:
        """Latents ``z`` of :obj:`batch` and the bottleneck's terms."""
        raise NotImplementedError

    def decode(self, z: Tensor, target_batch) -> Dict[str, Tensor]:
        """``q``, ``r``, ``c`` (logits) of :obj:`z` on the target's frame graphs."""
        raise NotImplementedError

    def forward(self, batch, target_batch=None) -> Dict[str, Tensor]:
        """Encode :obj:`batch` and decode onto :obj:`target_batch` (default:
        :obj:`batch` itself)."""
        enc = self.encode(batch)
        target = batch if target_batch is None else target_batch
        return dict(enc, **self.decode(enc["z"], target))


__all__ = ["MotionAutoencoder"]
