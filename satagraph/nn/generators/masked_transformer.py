r"""MoMask's masked token transformer over the first RVQ layer's codes,
conditioned on a text token and a skeleton token."""
from __future__ import annotations

import math
from typing import NamedTuple, Optional, Tuple

import torch
from torch import Tensor, nn

from satagraph.nn.generators.codes import (check_codes, continuation_spans, length_mask,
                                           pool_codes, token_lengths, unpool_codes)
from satagraph.nn.generators.sampling import (Corruption, check_guide, corrupt_tokens,
                                              draw_logits, guided, lowest_ranked, mask_ratio,
                                              random_mask, ranking_scores, sample_logits,
                                              spread_choice, uniform)
from satagraph.nn.generators.token_transformer import (TokenTransformer, evaluating,
                                                       init_token_model, masked_accuracy,
                                                       masked_cross_entropy, with_and_without_text)


class MaskedLoss(NamedTuple):
    """Output of :meth:`MaskedTransformer.loss`."""
    loss: Tensor
    accuracy: Tensor
    logits: Tensor
    targets: Tensor
    corruption: Corruption
    drop_text: Tensor


class MaskedTransformer(nn.Module):
    r"""Masked token model over layer-0 RVQ codes (MoMask), with two
    separate condition tokens: the text (projected text embedding; a learned
    null-text token when dropped) and the skeleton (projected
    :math:`f_{skel}`, never dropped).

    Vocabulary: codes ``0..K-1``, :attr:`mask_id` ``= K``, :attr:`pad_id`
    ``= K + 1``. Training (:meth:`loss`) masks a fraction
    :math:`f + (1 - f)\cos(\pi u / 2)` of each sequence (:obj:`mask_floor`
    :math:`f`), corrupts the masked positions (10 % random code, 88 % of the
    rest [MASK], the others kept) and scores them only; the text is dropped
    with probability :obj:`cond_drop`. :meth:`generate` decodes iteratively
    with cosine re-masking of the least confident tokens and classifier-free
    guidance ``uncond + s (cond - uncond)`` where ``uncond`` drops the text
    only.

    Token rate: with :obj:`pool` :math:`s > 1` one token stands for
    :math:`s` frames (:func:`~satagraph.nn.generators.pool_codes`).
    :meth:`forward` works on tokens; :meth:`loss` takes per-frame codes and
    :meth:`generate` returns per-frame codes, lengths in frames for both.

    Intended size for satagraph's data (about 18 min of captioned real
    motion plus the procedural zoo): 4 layers, 256 wide, 4 heads,
    feed-forward 1024, dropout 0.2 (MoMask on HumanML3D: 8 layers, 384
    wide, 6 heads).

    Args:
        num_codes (int): Codebook size :math:`K`.
        text_channels (int): Text embedding width :math:`D_{text}`.
        skel_channels (int): Skeleton embedding width :math:`D_s`.
        hidden_channels (int, optional): Width.
        heads (int, optional): Attention heads.
        num_layers (int, optional): Encoder layers.
        ff_channels (int, optional): Feed-forward width (default
            ``4 * hidden_channels``).
        dropout (float, optional): Dropout.
        cond_drop (float, optional): Text dropout probability (MoMask: 0.1).
        positions (str, optional): ``"sine"`` or ``"learned"``.
        max_length (int, optional): Longest token sequence (learned
            positions).
        pool (int, optional): Frames per token (1: per-frame tokens).
        pool_reduce (str, optional): ``"mode"`` or ``"first"`` (see
            :func:`~satagraph.nn.generators.pool_codes`).
        mask_floor (float, optional): Smallest training mask ratio.
        random_prob (float, optional): Share of masked tokens given a random
            code.
        mask_prob (float, optional): Share of the other masked tokens given
            [MASK].
        label_smoothing (float, optional): Cross-entropy label smoothing.
        position_jitter (int, optional): Training-time start positions
            (:class:`~satagraph.nn.generators.token_transformer.TokenTransformer`).

    Shapes:
        - **tokens**: :math:`(B, T)` (token rate), **text_emb**:
          :math:`(B, D_{text})` or ``None``, **skel_emb**: :math:`(B, D_s)`,
          **lengths**: :math:`(B,)` tokens (:meth:`forward`) or frames
        - **output** of :meth:`forward`: :math:`(B, T, K)` logits
    """

    def __init__(self, num_codes: int, text_channels: int, skel_channels: int,
                 hidden_channels: int = 64, heads: int = 4, num_layers: int = 2,
                 ff_channels: Optional[int] = None, dropout: float = 0.1,
                 cond_drop: float = 0.1, positions: str = "sine",
                 max_length: Optional[int] = None, pool: int = 1, pool_reduce: str = "mode",
                 mask_floor: float = 0.0, random_prob: float = 0.1, mask_prob: float = 0.88,
                 label_smoothing: float = 0.0, position_jitter: int = 0) -> None:
        super().__init__()
        if not 0.0 <= mask_floor < 1.0:
            raise ValueError(f"mask_floor must be in [0, 1), got {mask_floor}")
        self.num_codes, self.mask_id, self.pad_id = num_codes, num_codes, num_codes + 1
        self.pool, self.pool_reduce, self.mask_floor = int(pool), pool_reduce, float(mask_floor)
        self.random_prob, self.mask_prob = random_prob, mask_prob
        self.label_smoothing = label_smoothing
        self.token_emb = nn.Embedding(num_codes + 2, hidden_channels)
        self.backbone = TokenTransformer(hidden_channels, heads, num_layers,
                                         ff_channels or 4 * hidden_channels, dropout,
                                         text_channels, skel_channels, cond_drop, positions,
                                         max_length, position_jitter)
        self.head = nn.Linear(hidden_channels, num_codes)
        init_token_model(self)

    # ------------------------------------------------------------ tokens
    def to_tokens(self, codes: Tensor, lengths: Tensor) -> Tuple[Tensor, Tensor]:
        r"""Per-frame layer-0 codes to tokens (pooled by :attr:`pool`, [PAD]
        after each sequence) and tokens per sequence.

        Shapes:
            - **codes**: :math:`(B, T_f)` or :math:`(B, T_f, Q)`,
              **lengths**: :math:`(B,)` frames
        """
        base = codes[..., 0] if codes.dim() == 3 else codes
        return pool_codes(base, lengths, self.pool, self.pool_reduce, self.pad_id)

    def to_frames(self, tokens: Tensor, lengths: Tensor) -> Tensor:
        """Tokens back to per-frame codes (:attr:`pad_id` after each clip)."""
        return unpool_codes(tokens, lengths, self.pool, self.pad_id)

    # ------------------------------------------------------------ model
    def forward(self, tokens: Tensor, text_emb: Optional[Tensor], skel_emb: Tensor,
                lengths: Tensor, drop_text: Optional[Tensor] = None) -> Tensor:
        """Logits over codes at every token position (positions from
        :obj:`lengths` on are [PAD] whatever :obj:`tokens` holds there)."""
        valid = length_mask(lengths, tokens.size(1))
        tokens = tokens.masked_fill(~valid, self.pad_id)
        h = self.backbone(self.token_emb(tokens), valid, text_emb, skel_emb,
                          drop_text=drop_text)
        return self.head(h)

    def guided_logits(self, tokens: Tensor, text_emb: Optional[Tensor], skel_emb: Tensor,
                      lengths: Tensor, guidance: float = 1.0) -> Tensor:
        r"""Classifier-free guided logits ``uncond + s (cond - uncond)``;
        ``uncond`` drops the text only. ``text_emb=None``: the unconditional
        logits; :math:`s = 1`: the conditional ones (one pass each)."""
        cond, uncond = self._logit_pair(tokens, text_emb, skel_emb, lengths, guidance)
        return cond if uncond is None else guided(cond, uncond, guidance)

    def _logit_pair(self, tokens: Tensor, text_emb: Optional[Tensor], skel_emb: Tensor,
                    lengths: Tensor, guidance: float) -> Tuple[Tensor, Optional[Tensor]]:
        """Conditional and text-dropped logits in one batch, or the plain
        logits and ``None`` where no guidance applies (no text, or
        :obj:`guidance` 1)."""
        return with_and_without_text(self, (tokens, text_emb, skel_emb, lengths),
                                     text_emb is not None, guidance)

    # ------------------------------------------------------------ training
    def corrupt(self, tokens: Tensor, lengths: Tensor,
                generator: Optional[torch.Generator] = None) -> Corruption:
        """Training masks and corrupted inputs for token sequences."""
        valid = length_mask(lengths, tokens.size(1))
        ratio = mask_ratio(uniform((tokens.size(0),), generator, tokens.device), self.mask_floor)
        mask = random_mask(valid, ratio, generator)
        out = corrupt_tokens(tokens, mask, self.mask_id, self.num_codes, self.random_prob,
                             self.mask_prob, generator)
        return out._replace(inputs=out.inputs.masked_fill(~valid, self.pad_id))

    def loss(self, codes: Tensor, text_emb: Optional[Tensor], skel_emb: Tensor,
             lengths: Tensor, generator: Optional[torch.Generator] = None) -> MaskedLoss:
        r"""Masked-token cross-entropy on per-frame codes (:obj:`lengths` in
        frames), on the masked positions only; the text is dropped with
        probability :obj:`cond_drop` in training."""
        targets, tok_lengths = self.to_tokens(codes, lengths)
        check_codes(targets, tok_lengths, self.num_codes)
        corruption = self.corrupt(targets, tok_lengths, generator)
        drop = self.backbone.draw_text_drop(targets.size(0), generator, targets.device)
        logits = self(corruption.inputs, text_emb, skel_emb, tok_lengths, drop_text=drop)
        loss = masked_cross_entropy(logits, targets, corruption.mask, self.label_smoothing)
        return MaskedLoss(loss, masked_accuracy(logits, targets, corruption.mask), logits,
                          targets, corruption, drop)

    # ------------------------------------------------------------ generation
    @staticmethod
    def _remask(scores: Tensor, fixed: Tensor, valid: Tensor, count: Tensor,
                spread: float) -> Tensor:
        """The :obj:`count` tokens drawn last to draw again: the lowest
        ranked, or (:obj:`spread` > 0) all but those
        :func:`~satagraph.nn.generators.sampling.spread_choice` keeps."""
        if spread <= 0:
            return lowest_ranked(scores, count) & ~fixed
        fresh = (scores < 1e5) & ~fixed
        kept = spread_choice(scores, fresh, valid & ~fresh, fresh.sum(-1) - count, spread)
        return fresh & ~kept

    @torch.no_grad()
    def generate(self, text_emb: Optional[Tensor], skel_emb: Tensor, lengths: Tensor,
                 steps: int = 10, guidance: float = 4.0, temperature: float = 1.0,
                 topk_ratio: Optional[float] = 0.1,
                 generator: Optional[torch.Generator] = None,
                 known: Optional[Tensor] = None, keep: Optional[Tensor] = None,
                 choice_temperature: float = 0.0, spread: float = 0.0,
                 window: Optional[int] = None, guide: str = "logits",
                 draw_guidance: float = 1.0) -> Tensor:
        r"""Layer-0 codes by iterative decoding (MoMask): all tokens start
        as [MASK] (but the :obj:`keep` positions of :obj:`known`, which stay
        as given: infilling); at step :math:`i` of :obj:`steps` (:math:`n`) the
        :math:`\mathrm{round}(r_i L)` least confident free tokens (at least one),
        :math:`r_i = f + (1 - f)\cos(\pi i / (2(n-1)))` with :math:`f` =
        :obj:`mask_floor` (as in training), are re-masked and re-drawn from
        the guided logits (top-k keeping :obj:`topk_ratio` of the codes,
        :obj:`temperature`; 0: argmax). Every step fills all the masked
        tokens, so the output has no [MASK].

        Args:
            text_emb (Tensor, optional): Text embeddings (``None``:
                unconditional on the skeleton).
            skel_emb (Tensor): Skeleton embeddings.
            lengths (Tensor): Frames to generate per sequence.
            steps (int, optional): Decoding steps (MoMask: 10).
            guidance (float, optional): Guidance scale (MoMask: 4).
            temperature (float, optional): Sampling temperature.
            topk_ratio (float, optional): Share of codes kept by top-k.
            generator (torch.Generator, optional): Source of randomness.
            known (Tensor, optional): Tokens :math:`(B, T)` at the token
                rate (:meth:`to_tokens`), read where :obj:`keep` is set.
            keep (Tensor, optional): :math:`(B, T)` bool, the tokens of
                :obj:`known` to keep (:math:`L` counts the others).
            choice_temperature (float, optional): Gumbel noise on the
                ranking of which tokens to re-mask, fading over the steps
                (MaskGIT: 4.5; 0: by confidence alone, see
                :func:`~satagraph.nn.generators.sampling.ranking_scores`).
            spread (float, optional): Keep the tokens of each step spread
                over time, :obj:`spread` of the mean gap apart where the
                ranking allows (0: by rank alone, see
                :func:`~satagraph.nn.generators.sampling.spread_choice`).
            window (int, optional): Generate a sequence longer than this many
                frames window after window
                (:func:`~satagraph.nn.generators.codes.continuation_spans`),
                each window infilling after the tokens of the window before
                that it overlaps, so that a transformer trained on windows of
                this length reads no position it never learnt (default: whole
                sequences at once).
            guide (str, optional): ``"logits"`` (MoMask: draw from the guided
                logits) or ``"candidates"`` (draw from the logits guided by
                :obj:`draw_guidance` among the guided logits' top k,
                :func:`~satagraph.nn.generators.sampling.guided_candidates`).
            draw_guidance (float, optional): Guidance of the draw among the
                candidates (1: the conditional logits).

        Returns:
            Tensor: Per-frame codes :math:`(B, T_{max})`, :attr:`pad_id`
            after each sequence's length.
        """
        args = (steps, guidance, temperature, topk_ratio, generator, choice_temperature, spread,
                check_guide(guide), draw_guidance)
        with evaluating(self):
            tok_lengths = token_lengths(lengths, self.pool)
            valid = length_mask(tok_lengths, int(tok_lengths.max()))
            ids = torch.full(valid.shape, self.mask_id, dtype=torch.long, device=valid.device)
            keep = torch.zeros_like(valid) if keep is None else keep[:, :valid.size(1)] & valid
            if known is not None:
                ids = torch.where(keep, known[:, :valid.size(1)], ids)
            span = None if window is None else window // self.pool
            if span is None or valid.size(1) <= span:
                return self.to_frames(self._decode(ids, keep, text_emb, skel_emb, tok_lengths,
                                                   *args), lengths)
            for b, length in enumerate(tok_lengths.tolist()):
                text = None if text_emb is None else text_emb[b:b + 1]
                for start, stop, context in continuation_spans(length, span):
                    held = keep[b:b + 1, start:stop].clone()
                    held[:, :context] = True
                    ids[b, start:stop] = self._decode(ids[b:b + 1, start:stop], held, text,
                                                      skel_emb[b:b + 1],
                                                      tok_lengths.new_tensor([stop - start]),
                                                      *args)[0]
            return self.to_frames(ids, lengths)

    @torch.no_grad()
    def text_score(self, codes: Tensor, text_emb: Tensor, skel_emb: Tensor, lengths: Tensor,
                   rounds: int = 4, ratio: float = 0.5,
                   generator: Optional[torch.Generator] = None) -> Tensor:
        r"""How much the text explains each sequence of layer-0 codes: the
        pointwise mutual information of text and tokens as this model reads
        it, :math:`\log p(x_i \mid \text{context}, \text{text}) - \log
        p(x_i \mid \text{context})` (the skeleton kept in both), averaged
        over the tokens of :obj:`rounds` random maskings of :obj:`ratio` of
        each sequence. Every sequence of a call is masked alike where their
        lengths agree, so that candidates of one prompt compare on the same
        positions (:func:`~satagraph.pipelines.generate.generate_on`'s
        ``rerank``).

        Shapes:
            - **codes**: :math:`(B, T_f)` or :math:`(B, T_f, Q)` per-frame
              codes, **lengths**: :math:`(B,)` frames
            - **output**: :math:`(B,)`
        """
        tokens, tok_lengths = self.to_tokens(codes, lengths)
        valid = length_mask(tok_lengths, tokens.size(1))
        count = torch.round(ratio * tok_lengths).clamp(min=1).long()
        total = torch.zeros(tokens.size(0), device=tokens.device)
        with evaluating(self):
            for _ in range(rounds):
                pattern = uniform((1, tokens.size(1)), generator, tokens.device)
                mask = lowest_ranked(pattern.expand_as(valid).masked_fill(~valid, 2.0),
                                     count) & valid
                inputs = tokens.masked_fill(mask, self.mask_id)
                cond, uncond = with_and_without_text(  # any guidance but 1 gives both
                    self, (inputs, text_emb, skel_emb, tok_lengths), True, 0.0)
                gain = (cond.log_softmax(-1) - uncond.log_softmax(-1)).gather(
                    -1, tokens.clamp(max=self.num_codes - 1).unsqueeze(-1)).squeeze(-1)
                total += (gain * mask).sum(-1) / mask.sum(-1).clamp(min=1)
        return total / max(rounds, 1)

    def _draw(self, ids: Tensor, text_emb: Optional[Tensor], skel_emb: Tensor,
              tok_lengths: Tensor, guidance: float, temperature: float,
              topk_ratio: Optional[float], generator: Optional[torch.Generator], guide: str,
              draw_guidance: float) -> Tuple[Tensor, Tensor]:
        """One decoding step's logits (their softmax ranks the draws) and the
        codes drawn, as :obj:`guide` says
        (:func:`~satagraph.nn.generators.sampling.draw_logits`)."""
        logits, topk = draw_logits(*self._logit_pair(ids, text_emb, skel_emb, tok_lengths,
                                                     guidance),
                                   guidance, guide, topk_ratio, draw_guidance)
        return logits, sample_logits(logits, temperature, topk, generator)

    def _decode(self, ids: Tensor, keep: Tensor, text_emb: Optional[Tensor], skel_emb: Tensor,
                tok_lengths: Tensor, steps: int, guidance: float, temperature: float,
                topk_ratio: Optional[float], generator: Optional[torch.Generator],
                choice_temperature: float, spread: float, guide: str,
                draw_guidance: float) -> Tensor:
        """:meth:`generate`'s iterative decoding of whole token sequences
        (:obj:`ids` hold the kept tokens where :obj:`keep` is set); tokens,
        :attr:`pad_id` after each length."""
        valid = length_mask(tok_lengths, ids.size(1))
        keep = keep & valid
        ids = torch.where(keep, ids, torch.full_like(ids, self.mask_id))
        ids = ids.masked_fill(~valid, self.pad_id)
        fixed = ~valid | keep
        scores = torch.zeros(valid.shape, device=valid.device).masked_fill(fixed, float("inf"))
        free = (~fixed).sum(-1)
        for step in range(steps):
            ratio = self.mask_floor + (1 - self.mask_floor) * math.cos(
                math.pi / 2 * step / max(steps - 1, 1))
            count = torch.round(ratio * free).clamp(min=1).long()
            remask = self._remask(scores, fixed, valid, count, spread)
            ids = ids.masked_fill(remask, self.mask_id)
            logits, pred = self._draw(ids, text_emb, skel_emb, tok_lengths, guidance,
                                      temperature, topk_ratio, generator, guide, draw_guidance)
            ids = torch.where(remask, pred, ids)
            conf = logits.softmax(-1).gather(-1, pred.unsqueeze(-1)).squeeze(-1)
            conf = ranking_scores(conf, choice_temperature, (step + 1) / steps, generator)
            scores = conf.masked_fill(~remask, 1e5).masked_fill(fixed, float("inf"))
        return ids
