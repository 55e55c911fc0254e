r"""Masking schedules, token corruption and sampling for masked and residual
token transformers (MoMask's recipe), all driven by an optional
:class:`torch.Generator` so that training draws and generation are
reproducible."""
from __future__ import annotations

import math
from typing import List, NamedTuple, Optional, Tuple

import torch
from torch import Tensor


def _device_of(generator: Optional[torch.Generator], device) -> torch.device:
    return generator.device if generator is not None else torch.device(device or "cpu")


def uniform(shape, generator: Optional[torch.Generator] = None, device=None) -> Tensor:
    """:func:`torch.rand` on :obj:`generator`'s device, moved to :obj:`device`
    (the same draws wherever the model runs)."""
    return torch.rand(shape, generator=generator,
                      device=_device_of(generator, device)).to(device)


def integers(high: int, shape, generator: Optional[torch.Generator] = None,
             device=None) -> Tensor:
    """:func:`torch.randint` on :obj:`generator`'s device, moved to :obj:`device`."""
    return torch.randint(high, shape, generator=generator,
                         device=_device_of(generator, device)).to(device)


def cosine_schedule(u: Tensor) -> Tensor:
    r"""Masked fraction :math:`\cos(\pi u / 2)` for :math:`u \in [0, 1]`."""
    return torch.cos(u * math.pi / 2)


def mask_ratio(u: Tensor, floor: float = 0.0) -> Tensor:
    r"""Training mask ratio: :math:`f + (1 - f)\cos(\pi u / 2)` (MoMask:
    :math:`f = 0`). A floor :math:`f > 0` keeps the task from being a copy
    of neighbouring tokens when tokens are per frame."""
    return floor + (1.0 - floor) * cosine_schedule(u)


def lowest_ranked(scores: Tensor, count: Tensor) -> Tensor:
    r"""``True`` at the :obj:`count` lowest :obj:`scores` of every row (ties
    broken by position).

    Shapes:
        - **scores**: :math:`(B, T)`, **count**: :math:`(B,)`,
          **output**: :math:`(B, T)`
    """
    ranks = scores.argsort(dim=-1, stable=True).argsort(dim=-1)
    return ranks < count.unsqueeze(-1)


def ranking_scores(confidence: Tensor, temperature: float, progress: float,
                   generator: Optional[torch.Generator] = None) -> Tensor:
    r"""What iterative decoding ranks tokens by to re-mask the lowest: the
    confidence itself (:obj:`temperature` 0), or MaskGIT's noised log
    confidence :math:`\log p + \tau (1 - s)\,g` with Gumbel noise
    :math:`g`, :math:`\tau` = :obj:`temperature` and :math:`s` =
    :obj:`progress` (the share of steps done, so the noise fades out).
    Without noise, the positions next to a kept token are the most
    confident (a copy of it) and are kept next: runs of one code grow over
    the sequence (``experiments/T2M.md`` section 20).

    Shapes:
        - **confidence**: :math:`(B, T)` probabilities, **output**: :math:`(B, T)`
    """
    if temperature <= 0:
        return confidence
    u = uniform(confidence.shape, generator, confidence.device).clamp(1e-20, 1 - 1e-7)
    gumbel = -torch.log(-torch.log(u))
    return confidence.clamp_min(1e-30).log() + temperature * (1.0 - progress) * gumbel


def spread_choice(scores: Tensor, candidates: Tensor, locked: Tensor, count: Tensor,
                  spread: float) -> Tensor:
    r"""``True`` at :obj:`count` of the :obj:`candidates` of every row,
    chosen by highest :obj:`scores` but spread over time: a candidate is
    passed over while it lies closer than
    :math:`d = \lfloor s\,T_b / (k_b + 1) \rfloor` tokens to a
    :obj:`locked` or already chosen position (:math:`s` = :obj:`spread`,
    :math:`T_b` the row's candidates and locked positions, :math:`k_b` the
    locked ones after the choice); what that leaves short is filled by score.
    Iterative decoding that keeps the most confident tokens keeps copies of
    their neighbours first (``experiments/T2M.md`` section 20); kept tokens
    spread apart make the transformer predict the phases between them.

    Shapes:
        - **scores**, **candidates**, **locked**: :math:`(B, T)`,
          **count**: :math:`(B,)`, **output**: :math:`(B, T)`
    """
    chosen = torch.zeros_like(candidates)
    order = scores.masked_fill(~candidates, float("-inf")).argsort(dim=-1, descending=True)
    for b in range(scores.size(0)):
        picks = order[b, :int(candidates[b].sum())].tolist()
        taken = _spread_row(picks, locked[b].nonzero().flatten().tolist(), int(count[b]),
                            spread, scores.size(1))
        chosen[b, taken] = True
    return chosen


def _spread_row(picks: List[int], locked: List[int], want: int, spread: float,
                length: int) -> List[int]:
    """:func:`spread_choice` of one row: :obj:`want` of :obj:`picks` (best
    first), apart from each other and from :obj:`locked` where they can be."""
    if want <= 0 or not picks:
        return []
    gap = int(spread * (len(picks) + len(locked)) / (len(locked) + want + 1))
    blocked = [False] * length
    for t in locked:
        _block(blocked, t, gap)
    taken = []
    for t in picks:
        if len(taken) < want and not blocked[t]:
            taken.append(t)
            _block(blocked, t, gap)
    seen = set(taken)
    return taken + [t for t in picks if t not in seen][:want - len(taken)]


def _block(blocked: List[bool], t: int, gap: int) -> None:
    """Marks the positions closer than :obj:`gap` to :obj:`t`."""
    for u in range(max(t - gap + 1, 0), min(t + gap, len(blocked))):
        blocked[u] = True


def random_mask(valid: Tensor, ratio: Tensor,
                generator: Optional[torch.Generator] = None) -> Tensor:
    r"""A uniformly random subset of :math:`\mathrm{round}(r_b\,n_b)` (at
    least one) of the real positions of every row.

    Shapes:
        - **valid**: :math:`(B, T)`, **ratio**: :math:`(B,)`,
          **output**: :math:`(B, T)`
    """
    length = valid.sum(-1)
    count = torch.round(ratio * length).clamp(min=1)
    count = torch.minimum(count, length).long()
    scores = uniform(valid.shape, generator, valid.device)
    return lowest_ranked(scores.masked_fill(~valid, 2.0), count) & valid


def bernoulli_subset(mask: Tensor, prob: float,
                     generator: Optional[torch.Generator] = None) -> Tensor:
    """Each ``True`` of :obj:`mask` kept with probability :obj:`prob`."""
    draw = uniform(mask.shape, generator, mask.device)
    return mask & (draw < prob)


class Corruption(NamedTuple):
    """Inputs of a masked-token training step and where they differ from
    the targets' role: ``mask`` (loss positions), ``random`` (replaced by a
    random code), ``masked`` (replaced by [MASK]); the rest of ``mask``
    keeps its true code."""
    inputs: Tensor
    mask: Tensor
    random: Tensor
    masked: Tensor


def corrupt_tokens(codes: Tensor, mask: Tensor, mask_id: int, num_codes: int,
                   random_prob: float = 0.1, mask_prob: float = 0.88,
                   generator: Optional[torch.Generator] = None) -> Corruption:
    r"""MoMask's corruption of the masked positions: :obj:`random_prob` of
    them get a uniformly random code; of the others, :obj:`mask_prob` get
    [MASK] and the rest keep the true code (defaults: 10 % random, 79.2 %
    [MASK], 10.8 % kept).

    Shapes:
        - **codes**, **mask**: :math:`(B, T)`; outputs alike
    """
    random = bernoulli_subset(mask, random_prob, generator)
    masked = bernoulli_subset(mask & ~random, mask_prob, generator)
    noise = integers(num_codes, codes.shape, generator, codes.device)
    inputs = torch.where(random, noise, codes)
    inputs = inputs.masked_fill(masked, mask_id)
    return Corruption(inputs, mask, random, masked)


def top_k_filter(logits: Tensor, ratio: Optional[float]) -> Tensor:
    r"""Logits outside the :math:`\lceil r K \rceil` largest of every row set
    to ``-inf`` (MoMask keeps 10 %: :obj:`ratio` 0.1; ``None`` or 1: none
    filtered).

    Shapes:
        - **logits**: :math:`(\ldots, K)`, **output**: alike
    """
    if ratio is None or ratio >= 1.0:
        return logits
    k = max(1, math.ceil(ratio * logits.size(-1)))
    kth = logits.topk(k, dim=-1).values[..., -1:]
    return logits.masked_fill(logits < kth, float("-inf"))


def sample_logits(logits: Tensor, temperature: float = 1.0, topk_ratio: Optional[float] = 0.1,
                  generator: Optional[torch.Generator] = None) -> Tensor:
    r"""Codes drawn from ``softmax(top_k(logits) / temperature)``
    (:obj:`temperature` 0: the argmax).

    Shapes:
        - **logits**: :math:`(\ldots, K)`, **output**: :math:`(\ldots)` long
    """
    if temperature <= 0:
        return logits.argmax(-1)
    probs = torch.softmax(top_k_filter(logits, topk_ratio) / temperature, dim=-1)
    flat = probs.reshape(-1, probs.size(-1)).to(_device_of(generator, probs.device))
    draw = torch.multinomial(flat, 1, generator=generator)
    return draw.to(probs.device).view(probs.shape[:-1])


def residual_layer_schedule(size: int, num_quantizers: int,
                            generator: Optional[torch.Generator] = None,
                            device=None) -> Tensor:
    r"""Residual layer :math:`q \in [1, Q-1]` per sample, biased to low
    layers: :math:`q = 1 + \mathrm{round}((1 - \cos(\pi u / 2))(Q - 2))`
    (MoMask's ``q_schedule``).

    Shapes:
        - **output**: :math:`(B,)` long
    """
    u = uniform((size,), generator, device)
    return 1 + torch.round((1 - cosine_schedule(u)) * (num_quantizers - 2)).long()


def guided(cond: Tensor, uncond: Tensor, scale: float) -> Tensor:
    r"""Classifier-free guidance on logits:
    :math:`u + s\,(c - u)` (:math:`s = 1`: exactly the conditional logits)."""
    if scale == 1.0:
        return cond
    return uncond + scale * (cond - uncond)


#: How guidance enters a draw: ``"logits"``, codes drawn from the guided
#: logits (MoMask); ``"candidates"``, the guided logits choose which codes may
#: be drawn (their top k) and logits guided less draw among them
#: (:func:`guided_candidates`).
GUIDES = ("logits", "candidates")


def guided_candidates(cond: Tensor, uncond: Tensor, scale: float,
                      topk_ratio: Optional[float], draw_scale: float = 1.0) -> Tensor:
    r"""The logits guided by :obj:`draw_scale` (1: the conditional ones)
    over the codes that the logits guided by :obj:`scale` rank in their top
    :obj:`topk_ratio`, the others ``-inf``: full guidance rules out the codes
    the text does not ask for, and a milder one draws among the rest
    instead of logits pushed far past the conditional ones (drawn from the
    guided logits, the built-in generator's walks, runs and dashes are
    30-45 % faster than real ones; ``experiments/T2M.md`` sections 63-64).

    Shapes:
        - **cond**, **uncond**: :math:`(\ldots, K)`, **output**: alike
    """
    allowed = top_k_filter(guided(cond, uncond, scale), topk_ratio) > float("-inf")
    return guided(cond, uncond, draw_scale).masked_fill(~allowed, float("-inf"))


def draw_logits(cond: Tensor, uncond: Optional[Tensor], guidance: float, guide: str,
                topk_ratio: Optional[float], draw_guidance: float = 1.0
                ) -> Tuple[Tensor, Optional[float]]:
    r"""The logits one draw samples from, as :obj:`guide` says
    (:data:`GUIDES`), and the top-k ratio still to apply to them (``None``
    where they are the candidates already).

    Args:
        cond (Tensor): Text-conditioned logits (the plain ones where no
            guidance applies).
        uncond (Tensor, optional): Text-dropped logits; ``None``: no guidance.
        guidance (float): Guidance scale of the guided logits.
        guide (str): ``"logits"`` (:func:`guided`) or ``"candidates"``
            (:func:`guided_candidates`).
        topk_ratio (float, optional): MoMask's top-k share.
        draw_guidance (float): Guidance of the draw among the candidates.

    Shapes:
        - **cond**, **uncond**: :math:`(\ldots, K)`, **output**: alike
    """
    if guide == "candidates":
        if uncond is None:
            return top_k_filter(cond, topk_ratio), None
        return guided_candidates(cond, uncond, guidance, topk_ratio, draw_guidance), None
    return (cond if uncond is None else guided(cond, uncond, guidance)), topk_ratio


def check_guide(guide: str) -> str:
    """:obj:`guide` if it is one of :data:`GUIDES`, else a ``ValueError``."""
    if guide not in GUIDES:
        raise ValueError(f"unknown guide {guide!r}: use one of {GUIDES}")
    return guide
