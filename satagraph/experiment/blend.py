r"""Weight-space blends of a fine-tune with the weights it started from.

A fine-tune that learns something new tends to drift on what its starting
point already did well. Interpolating the two in weight space (WiSE-FT,
Wortsman et al., 2022),

.. math::
    \theta_\alpha = (1 - \alpha)\, \theta_{\text{base}} + \alpha\, \theta_{\text{tuned}},

keeps much of the new skill with less of the drift, without training. Both
ends must be the same network reading the same features: one was started
from the other with its normaliser kept (``--init-from CKPT
--init-normalizer checkpoint``), so they share every key, shape and
normaliser statistic.

``satagraph export-weights CKPT OUT.safetensors --blend builtin --alpha 0.5``
writes such a blend.
"""
from __future__ import annotations

from typing import Any, Dict, Mapping

import torch
from torch import Tensor

from satagraph.data.dataset import data_facing_smooth
from satagraph.io.weights import NORMALIZER_PREFIX


def blend_state(base: Mapping[str, Tensor], tuned: Mapping[str, Tensor], alpha: float,
                base_name: str = "base", tuned_name: str = "tuned") -> Dict[str, Tensor]:
    r"""The state dict :math:`(1 - \alpha)\,` :obj:`base` :math:`+ \alpha\,`
    :obj:`tuned`.

    Every floating-point weight is interpolated. The normaliser (its
    statistics and flags) and every other tensor that is not a float must
    be equal in both: they say what the features mean, and a network can be
    far more sensitive to them than to its weights (`builtin` reads zoo
    bipeds at 3.1 % of their height with its own normaliser and at 16.9 %
    with one refitted on a fine-tune's data; blending the statistics too
    gave 6-10 % at every share in between, ``experiments/PRETRAIN.md``
    section 32). A fine-tune meant to be blended keeps its starting
    point's normaliser (``--init-normalizer checkpoint``).

    Args:
        base (Mapping[str, Tensor]): The starting point's state dict.
        tuned (Mapping[str, Tensor]): The fine-tune's state dict.
        alpha (float): Share of :obj:`tuned`, in :math:`[0, 1]` (0 gives
            :obj:`base`, 1 gives :obj:`tuned`).
        base_name (str): :obj:`base`'s name in error messages.
        tuned_name (str): :obj:`tuned`'s name in error messages.

    Returns:
        Dict[str, Tensor]: The blend, each tensor in :obj:`tuned`'s dtype.

    Raises:
        ValueError: :obj:`alpha` outside :math:`[0, 1]`, or the two are not
            the same network (one line naming both and the first mismatch).
    """
    alpha = float(alpha)
    if not 0.0 <= alpha <= 1.0:
        raise ValueError(f"--alpha must be in [0, 1] (the fine-tune's share), got {alpha:g}")
    _check_same_network(base, tuned, base_name, tuned_name)
    return {key: _mix(base[key], value, alpha, key, base_name, tuned_name)
            for key, value in tuned.items()}


def check_blend_meta(base: Mapping[str, Any], tuned: Mapping[str, Any],
                     base_name: str = "base", tuned_name: str = "tuned") -> None:
    """Refuses to blend two models that read their input otherwise: another
    module kind, semantic encoder or facing smoothing.

    Args:
        base (Mapping[str, Any]): The starting point's ``hyper_parameters``.
        tuned (Mapping[str, Any]): The fine-tune's ``hyper_parameters``.
        base_name (str): :obj:`base`'s name in error messages.
        tuned_name (str): :obj:`tuned`'s name in error messages.

    Raises:
        ValueError: One line naming both and what differs.
    """
    ours, theirs = tuned.get("meta") or {}, base.get("meta") or {}
    read = {"module": lambda m: m.get("module", "vae"),
            "semantic encoder": lambda m: m.get("semantic_encoder"),
            "data.preprocessing.facing_smooth": lambda m: data_facing_smooth(m.get("data"))}
    for what, get in read.items():
        if get(ours) != get(theirs):
            raise ValueError(f"cannot blend {tuned_name} with {base_name}: {what} "
                             f"{get(ours)!r} in one and {get(theirs)!r} in the other")


def _check_same_network(base: Mapping[str, Tensor], tuned: Mapping[str, Tensor],
                        base_name: str, tuned_name: str) -> None:
    """Refuses two state dicts of different keys or shapes."""
    only = sorted(set(base) ^ set(tuned))
    if only:
        owner = base_name if only[0] in base else tuned_name
        raise ValueError(f"cannot blend {tuned_name} with {base_name}: not the same network "
                         f"({len(only)} weights only in one, e.g. {only[0]!r} in {owner})")
    for key, value in tuned.items():
        if tuple(base[key].shape) != tuple(value.shape):
            raise ValueError(f"cannot blend {tuned_name} with {base_name}: {key!r} is "
                             f"{tuple(value.shape)} in one and {tuple(base[key].shape)} "
                             "in the other")


def _mix(a: Tensor, b: Tensor, alpha: float, key: str, base_name: str,
         tuned_name: str) -> Tensor:
    """One tensor of the blend."""
    if b.is_floating_point() and not key.startswith(NORMALIZER_PREFIX):
        return ((1.0 - alpha) * a.float() + alpha * b.float()).to(b.dtype)
    if not torch.allclose(a.to(b.dtype), b, rtol=1e-5, atol=1e-7):
        hint = (": fine-tune with --init-normalizer checkpoint to blend"
                if key.startswith(NORMALIZER_PREFIX) else "")
        raise ValueError(f"cannot blend {tuned_name} with {base_name}: {key!r} differs "
                         f"and is not a weight (the two read their features otherwise{hint})")
    return b.clone()


__all__ = ["blend_state", "check_blend_meta"]
