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
        :obj:`batch` itself), whose clips must be as long as the source's, in
        the same order: the frame count alone can match while a clip's
        latents are decoded with its neighbour's.

        Raises:
            ValueError: The target's clip lengths are not the source's.
        """
        target = batch if target_batch is None else target_batch
        if target is not batch:  # a training step decodes its own batch: no sync
            check_clip_lengths(batch, target)
        enc = self.encode(batch)
        return dict(enc, **self.decode(enc["z"], target))


def check_clip_lengths(batch, target) -> None:
    """One line when :obj:`target`'s clips are not as long as
    :obj:`batch`'s, clip by clip."""
    source, wanted = batch.clip_num_frames.tolist(), target.clip_num_frames.tolist()
    if source != wanted:
        raise ValueError(f"decoding onto clips of {wanted[:8]} frames from clips of "
                         f"{source[:8]}: the target's clips must be the source's lengths, "
                         "in its order")


__all__ = ["MotionAutoencoder", "check_clip_lengths"]
