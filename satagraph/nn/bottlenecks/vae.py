"""Diagonal-Gaussian bottleneck of SATA-VAE."""
from __future__ import annotations

from typing import NamedTuple

import torch
from torch import Tensor, nn

#: Bounds of the log-variance (numerical safety of ``exp``).
LOGVAR_MIN, LOGVAR_MAX = -30.0, 20.0


class VAEOutput(NamedTuple):
    """Output of :class:`VAEBottleneck`: latent, KL, mean, log-variance."""
    z: Tensor
    kl: Tensor
    mu: Tensor
    logvar: Tensor


def gaussian_kl(mu: Tensor, logvar: Tensor) -> Tensor:
    r""":math:`KL(\mathcal N(\mu, \sigma^2) \| \mathcal N(0, I))`, summed
    over latent channels and averaged over rows (frames).

    Shapes:
        - **mu**, **logvar**: :math:`(G, D)`
        - **output**: scalar
    """
    kl = 0.5 * (mu.pow(2) + logvar.exp() - 1.0 - logvar).sum(-1)
    return kl.mean() if kl.numel() else kl.sum()


class VAEBottleneck(nn.Module):
    r"""A linear layer maps each frame's feature to the mean and log-variance
    of a diagonal Gaussian (paper section 4.1); the latent is a
    reparameterised sample in training and the mean in evaluation.

    Args:
        in_channels (int): Width of the pooled encoder features.
        latent_channels (int, optional): Latent width (paper: 128).

    Shapes:
        - **input**: :math:`(G, C_{in})`
        - **output**: :class:`VAEOutput` with ``z``, ``mu``, ``logvar``
          :math:`(G, C_{lat})` and the scalar ``kl``
    """

    def __init__(self, in_channels: int, latent_channels: int = 128) -> None:
        super().__init__()
        self.latent_channels = latent_channels
        self.lin = nn.Linear(in_channels, 2 * latent_channels)

    def forward(self, x: Tensor) -> VAEOutput:
        mu, logvar = self.lin(x).chunk(2, dim=-1)
        logvar = logvar.clamp(LOGVAR_MIN, LOGVAR_MAX)
        z = mu
        if self.training:
            z = mu + torch.randn_like(mu) * torch.exp(0.5 * logvar)
        return VAEOutput(z, gaussian_kl(mu, logvar), mu, logvar)
