"""Residual vector quantiser bottleneck of SATA-RVQ (adapter around
:class:`vector_quantize_pytorch.ResidualVQ`)."""
from __future__ import annotations

from typing import NamedTuple

import torch
from torch import Tensor, nn
from vector_quantize_pytorch import ResidualVQ


class RVQOutput(NamedTuple):
    """Output of :class:`RVQBottleneck`: quantised latent, codes, commitment."""
    z: Tensor
    codes: Tensor
    commit: Tensor


class RVQBottleneck(nn.Module):
    r"""Projects each frame's feature to :obj:`latent_channels` and quantises
    it with :obj:`num_quantizers` residual codebooks (EMA updates, k-means
    initialisation on the first batch, dead-code reset, straight-through
    gradients and quantiser dropout, as MoMask).

    All frames of a batch are quantised as one sequence ``[1, G, D]`` (frames
    are quantised independently; only the EMA/k-means statistics are pooled).

    Args:
        in_channels (int): Width of the pooled encoder features.
        latent_channels (int, optional): Code width (paper: 256).
        num_quantizers (int, optional): Residual layers :math:`Q` (paper: 6).
        codebook_size (int, optional): Codes per layer (paper: 1024).
        commitment_weight (float, optional): Weight of the commitment loss
            inside the quantiser (the training loss applies its own weight
            on top).
        quantize_dropout (float, optional): Probability per training batch of
            dropping the layers after a random one (MoMask: 0.2); dropped
            codes are ``-1``.
        decay (float, optional): EMA decay of the codebooks (MoMask: 0.99).
        kmeans_init (bool, optional): Initialise codebooks by k-means on the
            first batch.
        threshold_ema_dead_code (float, optional): Codes whose EMA count falls
            below this are reset to random encoder outputs (0: never).
        rotation_trick (bool, optional): Rotation-trick gradients instead of
            the straight-through estimator.

    Shapes:
        - **input**: :math:`(G, C_{in})`
        - **output**: :class:`RVQOutput` with ``z`` :math:`(G, C_{lat})`,
          ``codes`` :math:`(G, Q)` (long) and the scalar ``commit``
    """

    def __init__(self, in_channels: int, latent_channels: int = 256,
                 num_quantizers: int = 6, codebook_size: int = 1024,
                 commitment_weight: float = 1.0, quantize_dropout: float = 0.2,
                 decay: float = 0.99, kmeans_init: bool = True,
                 threshold_ema_dead_code: float = 1.0,
                 rotation_trick: bool = False) -> None:
        super().__init__()
        self.latent_channels, self.codebook_size = latent_channels, codebook_size
        self.quantize_dropout = float(quantize_dropout)
        self.proj = nn.Linear(in_channels, latent_channels)
        self.rvq = ResidualVQ(
            dim=latent_channels, num_quantizers=num_quantizers,
            codebook_size=codebook_size, commitment_weight=commitment_weight,
            quantize_dropout=self.quantize_dropout > 0, decay=decay,
            kmeans_init=kmeans_init, threshold_ema_dead_code=threshold_ema_dead_code,
            rotation_trick=rotation_trick)

    def _drop_this_batch(self) -> bool:
        p = self.quantize_dropout
        return self.training and p > 0 and bool(torch.rand(()) < p)

    def forward(self, x: Tensor) -> RVQOutput:
        self.rvq.quantize_dropout = self._drop_this_batch()
        z, codes, losses = self.rvq(self.proj(x)[None])
        return RVQOutput(z[0], codes[0], losses.mean())

    def decode_codes(self, codes: Tensor) -> Tensor:
        r"""Latents from code indices (``-1`` = dropped layer).

        Shapes:
            - **codes**: :math:`(G, Q)`, **output**: :math:`(G, C_{lat})`
        """
        return self.rvq.get_output_from_indices(codes[None])[0]
