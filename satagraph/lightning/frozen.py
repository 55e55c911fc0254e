r"""Parts of a module left out of training (``optim.frozen``), one rule for
every LightningModule: a frozen part is not optimised and stays in
evaluation mode while the rest trains (no dropout, and a frozen quantiser's
codebooks do not move)."""
from __future__ import annotations

from typing import List, Sequence

from torch import nn


def named_parts(module: nn.Module, names: Sequence[str], known: Sequence[str]) -> List[nn.Module]:
    r"""The submodules of :obj:`module` at the paths :obj:`names`
    (e.g. ``model.encoder``).

    Args:
        module: The module.
        names: Paths below :obj:`module` (``optim.frozen``).
        known: The parts a user may name, listed by the error.

    Raises:
        ValueError: A name that is not a part of :obj:`module` (one line,
            naming the known parts).
    """
    parts = []
    for name in names or ():
        try:
            parts.append(module.get_submodule(str(name)))
        except AttributeError:
            raise ValueError(f"optim.frozen: {name!r} is not a part of "
                             f"{type(module).__name__}; its parts: {', '.join(known)}") from None
    return parts


def freeze(parts: Sequence[nn.Module]) -> None:
    """Leave :obj:`parts` out of the optimiser (no gradients) and in
    evaluation mode; a module's ``train()`` keeps them there with
    :func:`keep_frozen`."""
    for part in parts:
        part.requires_grad_(False).eval()


def keep_frozen(parts: Sequence[nn.Module]) -> None:
    """Put frozen :obj:`parts` back in evaluation mode (after ``train()``)."""
    for part in parts:
        part.eval()


__all__ = ["named_parts", "freeze", "keep_frozen"]
