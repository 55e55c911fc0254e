r"""Dropout whose mask is cheap to draw on a CPU.

On a CPU, :func:`torch.nn.functional.dropout` draws one random number per
element from the Mersenne twister (:meth:`~torch.Tensor.bernoulli_`): in a
SATA training step at the paper's sizes that took a fifth of the step. Here
one 64-bit draw gives the masks of four elements (one 16-bit lane each), so
the keep probability is :math:`1 - p` rounded to a multiple of
:math:`2^{-16}`. Draws come from torch's default generator, so runs stay
reproducible under :func:`torch.manual_seed`. On other devices (whose
generators are already fast) the functions fall back to torch's dropout.
"""
from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import Tensor, nn

_LANES = 4  # int16 lanes per int64 draw
_LOW = -(2 ** 15)


def fast_dropout(x: Tensor, p: float = 0.5, training: bool = True) -> Tensor:
    r"""Dropout of :obj:`x` with probability :obj:`p` (inverted scaling:
    kept elements are divided by :math:`1 - p`), differentiable.

    Args:
        x (Tensor): Input.
        p (float, optional): Probability of zeroing an element.
        training (bool, optional): Apply dropout (``False``: identity).

    Shapes:
        - **x**: :math:`(*)`, **output**: :math:`(*)`
    """
    if not training or p == 0.0:
        return x
    if x.device.type != "cpu" or not 0.0 < p < 1.0 or not x.is_floating_point():
        return F.dropout(x, p, training)
    count = x.numel()
    words = torch.empty(-(-count // _LANES), dtype=torch.int64).random_(-(2 ** 63), None)
    lanes = words.view(torch.int16)[:count].view(x.shape)
    threshold = _LOW + round(p * 2 ** 16)  # P(lane < threshold) = p
    mask = (lanes >= threshold).to(x.dtype).mul_(1.0 / (1.0 - p))
    return x * mask


class FastDropout(nn.Dropout):
    r""":class:`torch.nn.Dropout` through :func:`fast_dropout` (same
    argument, same state dict).

    Shapes:
        - **input**: :math:`(*)`, **output**: :math:`(*)`
    """

    def forward(self, input: Tensor) -> Tensor:
        if self.inplace:
            return F.dropout(input, self.p, self.training, inplace=True)
        return fast_dropout(input, self.p, self.training)


def use_fast_dropout(module: nn.Module) -> nn.Module:
    r"""Replaces every :class:`torch.nn.Dropout` inside :obj:`module`
    (e.g. those of :class:`torch.nn.TransformerEncoderLayer` and PyG's
    :class:`~torch_geometric.nn.conv.GPSConv`) by :class:`FastDropout`, in
    place. Returns :obj:`module`."""
    for name, child in module.named_children():
        if type(child) is nn.Dropout:
            setattr(module, name, FastDropout(child.p, child.inplace))
        else:
            use_fast_dropout(child)
    return module
