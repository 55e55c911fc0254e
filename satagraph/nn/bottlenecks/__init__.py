"""Latent bottlenecks of the autoencoders: a Gaussian VAE and a residual
vector quantiser (RVQ)."""
from satagraph.nn.bottlenecks.rvq import RVQBottleneck, RVQOutput
from satagraph.nn.bottlenecks.vae import VAEBottleneck, VAEOutput, gaussian_kl

__all__ = ["RVQBottleneck", "RVQOutput", "VAEBottleneck", "VAEOutput", "gaussian_kl"]
