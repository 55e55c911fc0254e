"""Temporal smoothing of per-frame values of batched clips."""
from __future__ import annotations

import torch
from torch import Tensor


def gaussian_smooth(x: Tensor, num_frames: Tensor, sigma: float) -> Tensor:
    r"""Each clip's frames smoothed along time by a Gaussian of standard
    deviation :obj:`sigma` frames (edges replicated; ``sigma <= 0``: as
    is). Clips never mix.

    Args:
        x (Tensor): Per-frame values of consecutive clips.
        num_frames (Tensor): Frames per clip, summing to :math:`G`.
        sigma (float): Standard deviation in frames.

    Shapes:
        - **x**: :math:`(G, C)`; **num_frames**: :math:`(B,)`
        - **output**: :math:`(G, C)`
    """
    if sigma <= 0 or x.size(0) == 0:
        return x
    radius = max(1, int(round(3 * sigma)))
    offsets = torch.arange(-radius, radius + 1, dtype=x.dtype, device=x.device)
    kernel = torch.exp(-0.5 * (offsets / sigma) ** 2)
    kernel = (kernel / kernel.sum()).view(1, 1, -1).repeat(x.size(1), 1, 1)
    out = []
    for clip in torch.split(x, [int(n) for n in num_frames]):
        padded = torch.nn.functional.pad(clip.t()[None], (radius, radius), mode="replicate")
        out.append(torch.nn.functional.conv1d(padded, kernel, groups=x.size(1))[0].t())
    return torch.cat(out)


__all__ = ["gaussian_smooth"]
