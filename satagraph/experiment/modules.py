r"""The built-in modules, registered on import (see
:mod:`satagraph.experiment.registry`): ``vae`` and ``rvq`` (SATA),
``same`` and ``padded_rvq`` (the baselines, which drop the SATA-only keys
their configs inherit from ``sata_vae.yaml``)."""
from __future__ import annotations

import inspect
from typing import Set

from satagraph.experiment.registry import register_module
from satagraph.lightning import PaddedRVQModule, SAMEModule, SATARVQModule, SATAVAEModule
from satagraph.lightning.autoencoder import DEFAULT_OPTIM


def _parameters(*classes: type) -> Set[str]:
    """The keyword arguments of :obj:`classes` together."""
    return {name for cls in classes for name in inspect.signature(cls).parameters}


def sata_keys() -> Set[str]:
    """``model`` keys of the SATA modules: :class:`~satagraph.nn.SATA`'s arguments."""
    from satagraph.nn import SATA
    return _parameters(SATA)


def same_keys() -> Set[str]:
    """``model`` keys of ``same``: SAME's and the inherited SATA ones."""
    from satagraph.nn import SATA
    from satagraph.nn.autoencoders.same import SAME
    return _parameters(SATA, SAME)


def padded_keys() -> Set[str]:
    """``model`` keys of ``padded_rvq``: PaddedRVQ's and the inherited SATA ones."""
    from satagraph.nn import SATA
    from satagraph.nn.autoencoders.padded import PaddedRVQ
    return _parameters(SATA, PaddedRVQ)


for _name, _cls, _keys in (("vae", SATAVAEModule, sata_keys),
                           ("rvq", SATARVQModule, sata_keys),
                           ("same", SAMEModule, same_keys),
                           ("padded_rvq", PaddedRVQModule, padded_keys)):
    register_module(_name, _cls, model_keys=_keys, optim_keys=DEFAULT_OPTIM)

__all__ = ["sata_keys", "same_keys", "padded_keys"]
