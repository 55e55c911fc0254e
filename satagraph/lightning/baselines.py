"""LightningModules of the baselines: SAME and the zero-padding RVQ-VAE.

They are registered as ``module: same`` and
``module: padded_rvq`` by :mod:`satagraph.experiment.modules`.
Their configs inherit ``experiments/sata_vae.yaml``; model keys that only
SATA understands (``num_blocks``, ``local_conv``, ``semantic_channels``,
...) are dropped, any other unknown key is an error.
"""
from __future__ import annotations

import inspect
from typing import Any, Dict

import torch
from torch import Tensor, nn

from satagraph.lightning.autoencoder import MotionAutoencoderModule


def _sata_only_keys(model_cls: type) -> set:
    """Keyword arguments of :class:`~satagraph.nn.SATA` that
    :obj:`model_cls` does not take."""
    from satagraph.nn import SATA
    sata = set(inspect.signature(SATA).parameters)
    return sata - set(inspect.signature(model_cls).parameters)


def baseline_kwargs(model_cls: type, kwargs: Dict[str, Any]) -> Dict[str, Any]:
    """:obj:`kwargs` without the SATA-only keys inherited from the base config."""
    drop = _sata_only_keys(model_cls)
    return {k: v for k, v in kwargs.items() if k not in drop}


class SAMEModule(MotionAutoencoderModule):
    r"""SAME (:class:`~satagraph.nn.autoencoders.same.SAME`) with SATA's losses, metrics,
    schedule and inference. Deterministic latent: no KL or commitment
    term."""

    def build_model(self, **kwargs: Any) -> nn.Module:
        from satagraph.nn.autoencoders.same import SAME
        return SAME(**baseline_kwargs(SAME, kwargs))


class PaddedRVQModule(MotionAutoencoderModule):
    r"""The zero-padding MoMask RVQ-VAE (:class:`~satagraph.nn.autoencoders.padded.PaddedRVQ`,
    SATA paper appendix D.3.1). Its outputs are read back onto the real
    nodes only, so padded joints never enter the losses or metrics. Its
    latents are one per 4 frames (``z [K, D]``, ``codes [K, Q]``)."""

    def build_model(self, **kwargs: Any) -> nn.Module:
        from satagraph.nn.autoencoders.padded import PaddedRVQ
        return PaddedRVQ(**baseline_kwargs(PaddedRVQ, kwargs))

    @torch.no_grad()
    def codes(self, batch) -> Tensor:
        """Code indices per latent step, ``[K, Q]``."""
        return self.encode(self.normalize_batch(batch))["codes"]

