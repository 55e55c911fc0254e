"""SATA: topology-agnostic motion autoencoder (encoder, bottleneck, decoder)."""
from __future__ import annotations

from typing import Dict, Optional

from torch import Tensor

from satagraph.nn.autoencoders.base import MotionAutoencoder
from satagraph.nn.bottlenecks.rvq import RVQBottleneck
from satagraph.nn.bottlenecks.vae import VAEBottleneck
from satagraph.nn.autoencoders.decoder import SATADecoder
from satagraph.nn.autoencoders.encoder import SATAEncoder
from satagraph.ops.frame_pool import frame_groups, pool_frames
from satagraph.ops.smoothing import gaussian_smooth

#: Default latent width per bottleneck (paper section 4.1).
DEFAULT_LATENT = {"vae": 128, "rvq": 256}


class SATA(MotionAutoencoder):
    r"""The SATA autoencoder: :class:`~satagraph.nn.SATAEncoder` (one latent
    per frame), a VAE or RVQ bottleneck, and
    :class:`~satagraph.nn.SATADecoder` onto any target skeleton.

    Args:
        hidden_channels (int, optional): Block width (paper: 256).
        heads (int, optional): Attention heads (paper: 4).
        ff_channels (int, optional): Temporal feed-forward width (paper: 512).
        num_blocks (int, optional): Blocks in the encoder and in the decoder
            (paper: 3 each).
        dropout (float, optional): Dropout (paper: 0.1).
        semantic_channels (int, optional): Width :math:`D_t` of the joint
            semantic embedding (0 or ``None``: none).
        bottleneck (str, optional): ``"vae"`` or ``"rvq"``.
        latent_channels (int, optional): Latent width (default 128 for the
            VAE, 256 for the RVQ).
        local_conv (str, optional): Local GNN of the spatial layers (see
            :func:`~satagraph.nn.build_local_conv`; ``None``: no GNN).
        spatial_attention (bool, optional): Per-frame spatial attention.
        temporal (bool, optional): Temporal Transformer.
        fusion (bool, optional): Semantic modulation block.
        use_text (bool, optional): Semantic features in the modulation.
        num_frequencies (int, optional): Octaves of the static sinusoidal
            encoder.
        num_quantizers, codebook_size, commitment_weight, quantize_dropout,
        codebook_decay, kmeans_init, threshold_ema_dead_code: RVQ options
            (see :class:`~satagraph.nn.RVQBottleneck`).
        act (str, optional): Activation.
        latent_smooth (float, optional): Standard deviation in frames of a
            Gaussian smoothing of the latents along each clip before the
            decoder (:func:`~satagraph.ops.smoothing.gaussian_smooth`; 0:
            none). Generation decodes code sequences with smoothed latents;
            a decoder trained with the same smoothing reads them as the
            motion they were encoded from instead of as a damped copy.
        code_pool (int, optional): Frames per code of the RVQ: the
            encoder's features averaged over each run of this many frames
            of a clip (:func:`~satagraph.ops.frame_pool.frame_groups`)
            before the quantiser, and the codes and latents repeated over
            those frames after it, so that the decoder learns from latents
            that hold for :obj:`code_pool` frames, as a generator pooling
            its tokens over that many frames gives them (1: a code per
            frame, as the paper).

    Shapes:
        - **batch**, **target_batch**: :class:`~satagraph.data.FrameBatch`
          with the same frame graphs (clip lengths) :math:`G`; :math:`N` is
          the number of nodes of the target
        - **output** of :meth:`forward`: ``q`` :math:`(N, 6)`, ``r``
          :math:`(G, 4)`, ``c`` :math:`(N, 1)` (logits), ``z`` :math:`(G, D)`
          and the bottleneck terms (VAE: ``kl``, ``mu``, ``logvar``; RVQ:
          ``commit``, ``codes`` :math:`(G, Q)`)
    """

    def __init__(self, hidden_channels: int = 256, heads: int = 4, ff_channels: int = 512,
                 num_blocks: int = 3, dropout: float = 0.1,
                 semantic_channels: Optional[int] = 0, bottleneck: str = "vae",
                 latent_channels: Optional[int] = None, local_conv: Optional[str] = "gine",
                 spatial_attention: bool = True, temporal: bool = True,
                 fusion: bool = True, use_text: bool = True, num_frequencies: int = 8,
                 num_quantizers: int = 6, codebook_size: int = 1024,
                 commitment_weight: float = 1.0, quantize_dropout: float = 0.2,
                 codebook_decay: float = 0.99, kmeans_init: bool = True,
                 threshold_ema_dead_code: float = 1.0, act: str = "relu",
                 latent_smooth: float = 0.0, code_pool: int = 1) -> None:
        super().__init__()
        self.latent_smooth = float(latent_smooth)
        if bottleneck not in DEFAULT_LATENT:
            raise ValueError(f"unknown bottleneck {bottleneck!r}: use 'vae' or 'rvq'")
        self.code_pool = int(code_pool)
        if self.code_pool < 1 or (self.code_pool > 1 and bottleneck != "rvq"):
            raise ValueError(f"code_pool={code_pool}: a positive number of frames, above 1 "
                             "for the RVQ only")
        self.bottleneck_type = bottleneck
        latent = latent_channels or DEFAULT_LATENT[bottleneck]
        shared = dict(hidden_channels=hidden_channels, heads=heads, ff_channels=ff_channels,
                      num_blocks=num_blocks, dropout=dropout,
                      semantic_channels=int(semantic_channels or 0), local_conv=local_conv,
                      spatial_attention=spatial_attention, temporal=temporal,
                      fusion=fusion, use_text=use_text, num_frequencies=num_frequencies,
                      act=act)
        self.encoder = SATAEncoder(**shared)
        if bottleneck == "vae":
            self.bottleneck = VAEBottleneck(hidden_channels, latent)
        else:
            self.bottleneck = RVQBottleneck(
                hidden_channels, latent, num_quantizers, codebook_size, commitment_weight,
                quantize_dropout, codebook_decay, kmeans_init, threshold_ema_dead_code)
        self.decoder = SATADecoder(latent_channels=latent, **shared)

    def encode(self, batch) -> Dict[str, Tensor]:
        """Latent per frame ``z`` and the bottleneck terms (RVQ codes per
        frame, the same over each :attr:`code_pool` frames)."""
        h = self.encoder(batch)
        if self.code_pool == 1:
            return self.bottleneck(h)._asdict()
        group = frame_groups(batch, self.code_pool)
        out = self.bottleneck(pool_frames(h, group))._asdict()
        return {**out, "z": out["z"][group], "codes": out["codes"][group]}

    def decode(self, z: Tensor, target_batch) -> Dict[str, Tensor]:
        """``q``, ``r``, ``c`` (logits) on the target frame graphs, from the
        latents smoothed over :attr:`latent_smooth` frames."""
        z = gaussian_smooth(z, target_batch.clip_num_frames, self.latent_smooth)
        return self.decoder(z, target_batch)
