r"""RVQ code sequences for generators: per-frame codes of a
:class:`~satagraph.data.FrameBatch` <-> padded per-clip sequences, and the
token rate (pooling codes every :obj:`stride` frames and back).

SATA-RVQ gives one code stack per frame (``[G, Q]``, frames of all clips
concatenated). At 30 fps that is 300 tokens for 10 s; neighbouring frames
often share a layer-0 code, which makes masked modelling of single tokens
easy to copy from neighbours. Pooling every ``stride`` frames keeps one
*real* frame's whole stack per window (the residual structure stays
valid) and repeats it on unpooling. Whether to pool, and by how much, is
left to measurements of code run lengths (:func:`code_run_lengths`).
"""
from __future__ import annotations

from typing import List, Optional, Tuple

import torch
from torch import Tensor

POOL_REDUCTIONS = ("first", "mode")


def length_mask(lengths: Tensor, max_length: int) -> Tensor:
    r"""``True`` at real positions.

    Shapes:
        - **lengths**: :math:`(B,)`, **output**: :math:`(B, T)`
    """
    return torch.arange(max_length, device=lengths.device) < lengths.unsqueeze(-1)


def token_lengths(num_frames: Tensor, stride: int) -> Tensor:
    r"""Tokens per clip at one token every :obj:`stride` frames
    (:math:`\lceil T / stride \rceil`)."""
    return torch.div(num_frames + stride - 1, stride, rounding_mode="floor")


def split_codes(codes: Tensor, num_frames: Tensor, pad_value: int = -1) -> Tensor:
    r"""Per-frame codes of concatenated clips (as
    :meth:`~satagraph.lightning.SATARVQModule.codes` gives them) to one
    padded sequence per clip.

    Shapes:
        - **codes**: :math:`(G, \ldots)` with :math:`G = \sum_b T_b`,
          **num_frames**: :math:`(B,)`
        - **output**: :math:`(B, T_{max}, \ldots)`
    """
    mask = length_mask(num_frames, int(num_frames.max()))
    out = codes.new_full((*mask.shape, *codes.shape[1:]), pad_value)
    out[mask] = codes
    return out


def merge_codes(codes: Tensor, lengths: Tensor) -> Tensor:
    r"""Inverse of :func:`split_codes`: the real positions, clip after clip.

    Shapes:
        - **codes**: :math:`(B, T, \ldots)`, **output**: :math:`(G, \ldots)`
    """
    return codes[length_mask(lengths, codes.size(1))]


def check_codes(codes: Tensor, lengths: Tensor, num_codes: int) -> None:
    r"""Refuses codes outside ``0..num_codes-1`` at real positions (e.g.
    the ``-1`` of RVQ quantiser dropout: encode in eval mode).

    Shapes:
        - **codes**: :math:`(B, T[, Q])`, **lengths**: :math:`(B,)`
    """
    real = codes[length_mask(lengths, codes.size(1))]
    if real.numel() and (bool(real.min() < 0) or bool(real.max() >= num_codes)):
        raise ValueError(f"codes must lie in [0, {num_codes}) before each length, got "
                         f"[{int(real.min())}, {int(real.max())}] (dropped RVQ layers?)")


def _window_choice(base: Tensor, valid: Tensor, reduce: str) -> Tensor:
    """Frame chosen in every window ``[B, W, stride]`` of layer-0 codes."""
    if reduce == "first":
        return base.new_zeros(base.shape[:2])
    same = (base.unsqueeze(-1) == base.unsqueeze(-2)) & valid.unsqueeze(-2)
    count = same.sum(-1).masked_fill(~valid, -1)
    return count.argmax(-1)  # first frame of the most frequent code


def pool_codes(codes: Tensor, lengths: Tensor, stride: int, reduce: str = "mode",
               pad_value: int = -1) -> Tuple[Tensor, Tensor]:
    r"""One token every :obj:`stride` frames: the whole code stack of one
    frame of each window, the first (``"first"``) or the first frame whose
    layer-0 code is the window's most frequent (``"mode"``).

    Args:
        codes (Tensor): Per-frame codes (layer 0 first when stacked).
        lengths (Tensor): Frames per clip.
        stride (int): Frames per token (1: unchanged).
        reduce (str, optional): ``"mode"`` or ``"first"``.
        pad_value (int, optional): Value after each clip's last token.

    Returns:
        (Tensor, Tensor): Tokens and tokens per clip.

    Shapes:
        - **codes**: :math:`(B, T)` or :math:`(B, T, Q)`
        - **output**: :math:`(B, \lceil T / s \rceil[, Q])` and :math:`(B,)`
    """
    if reduce not in POOL_REDUCTIONS:
        raise ValueError(f"unknown reduce {reduce!r}: use one of {POOL_REDUCTIONS}")
    out_lengths = token_lengths(lengths, stride)
    if stride == 1:
        return codes.masked_fill(~_mask_like(codes, lengths), pad_value), out_lengths
    size, frames = codes.shape[:2]
    windows = -(-frames // stride)
    pad = windows * stride - frames
    stack = codes if codes.dim() == 3 else codes.unsqueeze(-1)
    stack = torch.cat([stack, stack.new_full((size, pad, stack.size(-1)), pad_value)], 1)
    stack = stack.view(size, windows, stride, -1)
    valid = length_mask(lengths, windows * stride).view(size, windows, stride)
    pick = _window_choice(stack[..., 0], valid, reduce)
    index = pick[..., None, None].expand(-1, -1, 1, stack.size(-1))
    out = stack.gather(2, index).squeeze(2)
    out = out if codes.dim() == 3 else out.squeeze(-1)
    return out.masked_fill(~_mask_like(out, out_lengths), pad_value), out_lengths


def unpool_codes(tokens: Tensor, lengths: Tensor, stride: int, pad_value: int = -1,
                 num_frames: Optional[int] = None) -> Tensor:
    r"""Inverse of :func:`pool_codes`: every token repeated over its
    :obj:`stride` frames, cut at each clip's :obj:`lengths` (frames).

    Shapes:
        - **tokens**: :math:`(B, W[, Q])`, **lengths**: :math:`(B,)`
        - **output**: :math:`(B, T[, Q])` with :math:`T` = :obj:`num_frames`
          or :math:`\max` :obj:`lengths`
    """
    frames = int(lengths.max()) if num_frames is None else num_frames
    out = tokens.repeat_interleave(stride, dim=1)[:, :frames]
    if out.size(1) < frames:
        extra = out.new_full((out.size(0), frames - out.size(1), *out.shape[2:]), pad_value)
        out = torch.cat([out, extra], 1)
    return out.masked_fill(~_mask_like(out, lengths), pad_value)


def _mask_like(codes: Tensor, lengths: Tensor) -> Tensor:
    mask = length_mask(lengths, codes.size(1))
    return mask if codes.dim() == 2 else mask.unsqueeze(-1)


def code_run_lengths(codes: Tensor, lengths: Tensor) -> Tensor:
    r"""Lengths of the runs of equal consecutive codes in every clip (to
    choose the token stride).

    Shapes:
        - **codes**: :math:`(B, T)` (e.g. layer 0), **lengths**: :math:`(B,)`
        - **output**: :math:`(R,)` run lengths, clip after clip
    """
    runs = []
    for row, length in zip(codes, lengths.tolist()):
        _, counts = torch.unique_consecutive(row[:length], return_counts=True)
        runs.append(counts)
    return torch.cat(runs) if runs else codes.new_zeros(0)


def window_spans(length: int, window: int, align: int = 1) -> List[Tuple[int, int, int, int]]:
    r"""Overlapping windows over a sequence of :obj:`length` frames, each
    frame taken from the window whose centre is nearest: ``(start, stop,
    keep_from, keep_to)``, windows of :obj:`window` frames every half window
    (the last one ending at the sequence's end), every start and kept
    boundary a multiple of :obj:`align` (the frames of a token). Each window
    but the first and last keeps about its central half; a sequence no
    longer than a window is one span.

    Example:
        >>> window_spans(120, 60, 2)
        [(0, 60, 0, 46), (30, 90, 46, 76), (60, 120, 76, 120)]
    """
    if window < 2 * align:
        raise ValueError(f"a window of {window} frames is under two tokens of {align}")
    if length <= window:
        return [(0, length, 0, length)]
    hop = max(align, window // 2 // align * align)
    last = (length - window) // align * align
    starts = list(range(0, last, hop)) + [last]
    stops = [s + window for s in starts[:-1]] + [length]
    centres = [(a + b) / 2 for a, b in zip(starts, stops)]
    cuts = [int((c + d) / 2 / align + 0.5) * align for c, d in zip(centres, centres[1:])]
    bounds = [0] + cuts + [length]
    return [(a, b, k, m) for a, b, k, m in zip(starts, stops, bounds, bounds[1:])]


def continuation_spans(length: int, window: int) -> List[Tuple[int, int, int]]:
    r"""Windows of :obj:`window` tokens that generate a sequence of
    :obj:`length` tokens one after the other: ``(start, stop, context)``,
    the first at 0, each later one starting half a window before the end of
    the one before it (the last one ending at the sequence's end), its first
    :obj:`context` tokens (those already generated) kept as given. A
    sequence no longer than a window is one span.

    Example:
        >>> continuation_spans(150, 60)
        [(0, 60, 0), (30, 90, 30), (60, 120, 30), (90, 150, 30)]
        >>> continuation_spans(75, 60)
        [(0, 60, 0), (15, 75, 45)]
    """
    if window < 2:
        raise ValueError(f"a window of {window} tokens is under two tokens")
    if length <= window:
        return [(0, length, 0)]
    spans = [(0, window, 0)]
    while spans[-1][1] < length:
        end = spans[-1][1]
        start = min(end - window // 2, length - window)
        spans.append((start, start + window, end - start))
    return spans
