r"""MoMask's residual token transformer: RVQ layers :math:`q > 0` from the
layers below, conditioned on a text token and a skeleton token."""
from __future__ import annotations

from typing import NamedTuple, Optional, Tuple

import torch
from torch import Tensor, nn

from satagraph.nn.generators.codes import (check_codes, length_mask, pool_codes,
                                           unpool_codes, window_spans)
from satagraph.nn.generators.sampling import (check_guide, draw_logits, guided,
                                              residual_layer_schedule, sample_logits)
from satagraph.nn.generators.token_transformer import (TokenTransformer, evaluating,
                                                       init_token_model, masked_accuracy,
                                                       masked_cross_entropy, with_and_without_text)


class ResidualLoss(NamedTuple):
    """Output of :meth:`ResidualTransformer.loss`."""
    loss: Tensor
    accuracy: Tensor
    logits: Tensor
    targets: Tensor
    layer: Tensor
    drop_text: Tensor


class ResidualTransformer(nn.Module):
    r"""Predicts the codes of RVQ layer :math:`q \in [1, Q-1]` at every
    position, in parallel, from the sum of the code embeddings of layers
    :math:`< q`, a layer token, and the text and skeleton tokens (MoMask's
    residual transformer).

    Each layer :math:`l` has a code table :math:`E_l \in R^{K \times C}`;
    with :obj:`share_weights` the output head of layer :math:`q` scores codes
    against :math:`E_q` (its input table when layers above are predicted).
    :meth:`load_codebooks` copies the RVQ codebooks into the tables, so that
    the summed input is the partial quantised latent. Training draws
    :math:`q` with a :math:`1 - \cos` bias to low layers and drops the text
    with probability :obj:`cond_drop` (MoMask: 0.2). Token ids as
    :class:`~satagraph.nn.generators.MaskedTransformer`: codes ``0..K-1``,
    :attr:`pad_id` ``= K + 1``; positions past each length are ignored on
    input. Codes must be complete stacks (encode with the RVQ in eval mode:
    quantiser dropout writes ``-1``).

    Intended size for satagraph's data: 4 layers, 256 wide, 4 heads,
    :obj:`code_channels` = the RVQ latent width (256) when initialised from
    the codebooks.

    Args:
        num_codes (int): Codebook size :math:`K`.
        num_quantizers (int): RVQ layers :math:`Q \ge 2`.
        text_channels (int): Text embedding width.
        skel_channels (int): Skeleton embedding width.
        hidden_channels (int, optional): Width.
        heads (int, optional): Attention heads.
        num_layers (int, optional): Encoder layers.
        ff_channels (int, optional): Feed-forward width (default
            ``4 * hidden_channels``).
        dropout (float, optional): Dropout.
        cond_drop (float, optional): Text dropout probability.
        code_channels (int, optional): Code table width :math:`C` (default
            :obj:`hidden_channels`).
        share_weights (bool, optional): Tie output heads to code tables.
        positions (str, optional): ``"sine"`` or ``"learned"``.
        max_length (int, optional): Longest token sequence (learned
            positions).
        pool (int, optional): Frames per token.
        pool_reduce (str, optional): ``"mode"`` or ``"first"``.
        label_smoothing (float, optional): Cross-entropy label smoothing.
        position_jitter (int, optional): Training-time start positions
            (:class:`~satagraph.nn.generators.token_transformer.TokenTransformer`).

    Shapes:
        - **codes**: :math:`(B, T, Q)` (token rate in :meth:`forward`),
          **layer**: :math:`(B,)`, **lengths**: :math:`(B,)`
        - **output** of :meth:`forward`: :math:`(B, T, K)` logits of layer
          :obj:`layer`
    """

    def __init__(self, num_codes: int, num_quantizers: int, text_channels: int,
                 skel_channels: int, hidden_channels: int = 64, heads: int = 4,
                 num_layers: int = 2, ff_channels: Optional[int] = None, dropout: float = 0.1,
                 cond_drop: float = 0.2, code_channels: Optional[int] = None,
                 share_weights: bool = True, positions: str = "sine",
                 max_length: Optional[int] = None, pool: int = 1, pool_reduce: str = "mode",
                 label_smoothing: float = 0.0, position_jitter: int = 0) -> None:
        super().__init__()
        if num_quantizers < 2:
            raise ValueError("a residual transformer needs at least 2 quantizers")
        self.num_codes, self.num_quantizers = num_codes, num_quantizers
        self.mask_id, self.pad_id = num_codes, num_codes + 1
        self.pool, self.pool_reduce, self.label_smoothing = int(pool), pool_reduce, label_smoothing
        code_channels = code_channels or hidden_channels
        self.code_embed = nn.Parameter(torch.randn(num_quantizers, num_codes, code_channels) * 0.02)
        self.out_weight = None if share_weights else nn.Parameter(
            torch.randn(num_quantizers, num_codes, code_channels) * 0.02)
        self.out_bias = nn.Parameter(torch.zeros(num_quantizers, num_codes))
        self.in_proj = nn.Linear(code_channels, hidden_channels)
        self.layer_token = nn.Embedding(num_quantizers, hidden_channels)
        self.backbone = TokenTransformer(hidden_channels, heads, num_layers,
                                         ff_channels or 4 * hidden_channels, dropout,
                                         text_channels, skel_channels, cond_drop, positions,
                                         max_length, position_jitter)
        self.out_proj = nn.Linear(hidden_channels, code_channels)
        init_token_model(self)

    @torch.no_grad()
    def load_codebooks(self, codebooks: Tensor, freeze: bool = False) -> None:
        r"""Initialise the code tables from RVQ codebooks (e.g.
        ``SATA.bottleneck.rvq.codebooks``); :obj:`freeze` stops their
        training (the output heads then score against fixed codebooks unless
        :obj:`share_weights` is off).

        Shapes:
            - **codebooks**: :math:`(Q, K, C)`
        """
        if codebooks.shape != self.code_embed.shape:
            raise ValueError(f"codebooks of shape {tuple(codebooks.shape)}, expected "
                             f"{tuple(self.code_embed.shape)}")
        self.code_embed.copy_(codebooks)
        self.code_embed.requires_grad_(not freeze)

    # ------------------------------------------------------------ tokens
    def to_tokens(self, codes: Tensor, lengths: Tensor) -> Tuple[Tensor, Tensor]:
        """Per-frame code stacks to tokens (one real frame's stack per token)."""
        return pool_codes(codes, lengths, self.pool, self.pool_reduce, self.pad_id)

    def embed(self, codes: Tensor, layer: Tensor, valid: Tensor) -> Tensor:
        r"""Sum of the code embeddings of the layers below :obj:`layer`
        (zero at padding).

        Shapes:
            - **codes**: :math:`(B, T, Q')` with :math:`Q' \ge \max q`,
              **output**: :math:`(B, T, C)`
        """
        depth = codes.size(-1)
        safe = codes.clamp(0, self.num_codes - 1)
        rows = torch.arange(depth, device=codes.device)
        emb = self.code_embed[rows, safe]  # [B, T, Q', C]
        below = (rows < layer.view(-1, 1)).view(-1, 1, depth, 1) & valid[..., None, None]
        return (emb * below).sum(2)

    def forward(self, codes: Tensor, layer: Tensor, text_emb: Optional[Tensor],
                skel_emb: Tensor, lengths: Tensor, drop_text: Optional[Tensor] = None) -> Tensor:
        """Logits over the codes of :obj:`layer` (per sample) at every token."""
        valid = length_mask(lengths, codes.size(1))
        h = self.in_proj(self.embed(codes, layer, valid))
        extra = self.layer_token(layer).unsqueeze(1)
        h = self.out_proj(self.backbone(h, valid, text_emb, skel_emb, extra, drop_text))
        weight = self.code_embed if self.out_weight is None else self.out_weight
        return torch.einsum("btc,bkc->btk", h, weight[layer]) + self.out_bias[layer].unsqueeze(1)

    def guided_logits(self, codes: Tensor, layer: Tensor, text_emb: Optional[Tensor],
                      skel_emb: Tensor, lengths: Tensor, guidance: float = 1.0) -> Tensor:
        """Classifier-free guided logits; ``uncond`` drops the text only."""
        cond, uncond = self._logit_pair(codes, layer, text_emb, skel_emb, lengths, guidance)
        return cond if uncond is None else guided(cond, uncond, guidance)

    def _logit_pair(self, codes: Tensor, layer: Tensor, text_emb: Optional[Tensor],
                    skel_emb: Tensor, lengths: Tensor,
                    guidance: float) -> Tuple[Tensor, Optional[Tensor]]:
        """Conditional and text-dropped logits in one batch, or the plain
        logits and ``None`` where no guidance applies (no text, or
        :obj:`guidance` 1)."""
        return with_and_without_text(self, (codes, layer, text_emb, skel_emb, lengths),
                                     text_emb is not None, guidance)

    # ------------------------------------------------------------ training
    def loss(self, codes: Tensor, text_emb: Optional[Tensor], skel_emb: Tensor,
             lengths: Tensor, generator: Optional[torch.Generator] = None,
             layer: Optional[Tensor] = None) -> ResidualLoss:
        r"""Cross-entropy of one residual layer per sample (drawn with a
        :math:`1 - \cos` bias unless :obj:`layer` is given) over every real
        position; per-frame codes, :obj:`lengths` in frames."""
        tokens, tok_lengths = self.to_tokens(codes, lengths)
        check_codes(tokens, tok_lengths, self.num_codes)
        size = tokens.size(0)
        if layer is None:
            layer = residual_layer_schedule(size, codes.size(-1), generator, tokens.device)
        drop = self.backbone.draw_text_drop(size, generator, tokens.device)
        logits = self(tokens, layer, text_emb, skel_emb, tok_lengths, drop_text=drop)
        rows = torch.arange(size, device=tokens.device)
        targets = tokens[rows, :, layer]
        valid = length_mask(tok_lengths, tokens.size(1))
        loss = masked_cross_entropy(logits, targets, valid, self.label_smoothing)
        return ResidualLoss(loss, masked_accuracy(logits, targets, valid), logits, targets,
                            layer, drop)

    # ------------------------------------------------------------ generation
    @torch.no_grad()
    def generate(self, base_codes: Tensor, text_emb: Optional[Tensor], skel_emb: Tensor,
                 lengths: Tensor, guidance: float = 5.0, temperature: float = 1.0,
                 topk_ratio: Optional[float] = 0.1,
                 generator: Optional[torch.Generator] = None,
                 num_quantizers: Optional[int] = None, window: Optional[int] = None,
                 guide: str = "logits", draw_guidance: float = 1.0) -> Tensor:
        r"""Fills layers :math:`1..Q-1` one after the other given layer-0
        codes, with classifier-free guidance (MoMask: 5).

        Args:
            base_codes (Tensor): Per-frame layer-0 codes :math:`(B, T)` (e.g.
                from :meth:`MaskedTransformer.generate`).
            text_emb (Tensor, optional): Text embeddings (``None``:
                unconditional).
            skel_emb (Tensor): Skeleton embeddings.
            lengths (Tensor): Frames per sequence.
            guidance (float, optional): Guidance scale.
            temperature (float, optional): Sampling temperature (0: argmax).
            topk_ratio (float, optional): Share of codes kept by top-k.
            generator (torch.Generator, optional): Source of randomness.
            num_quantizers (int, optional): Layers to fill (default all).
            window (int, optional): Fill a sequence longer than this many
                frames in overlapping windows of it, each frame from the
                window centred nearest (:func:`~satagraph.nn.generators.codes.window_spans`;
                default: whole sequences). Guided over a whole sequence of
                three seconds or more, the shipped generator's walks speed
                up along it (``experiments/T2M.md`` section 57).
            guide (str, optional): How guidance enters each draw, as in
                :meth:`MaskedTransformer.generate`.
            draw_guidance (float, optional): The guidance of a draw among
                candidates, as in :meth:`MaskedTransformer.generate`.

        Returns:
            Tensor: Per-frame codes :math:`(B, T, Q)`, :attr:`pad_id` after
            each sequence's length.
        """
        args = (guidance, temperature, topk_ratio, generator, num_quantizers, check_guide(guide),
                draw_guidance)
        if window is None or int(lengths.max()) <= window:
            return self._fill(base_codes, text_emb, skel_emb, lengths, *args)
        depth = num_quantizers or self.num_quantizers
        out = base_codes.new_full((base_codes.size(0), int(lengths.max()), depth), self.pad_id)
        for b, length in enumerate(lengths.tolist()):
            text = None if text_emb is None else text_emb[b:b + 1]
            for start, stop, keep, end in window_spans(int(length), window, self.pool):
                part = self._fill(base_codes[b:b + 1, start:stop], text, skel_emb[b:b + 1],
                                  lengths.new_tensor([stop - start]), *args)
                out[b, keep:end] = part[0, keep - start:end - start]
        return out

    def _fill(self, base_codes: Tensor, text_emb: Optional[Tensor], skel_emb: Tensor,
              lengths: Tensor, guidance: float, temperature: float,
              topk_ratio: Optional[float], generator: Optional[torch.Generator],
              num_quantizers: Optional[int], guide: str, draw_guidance: float) -> Tensor:
        """:meth:`generate` over whole sequences (under its ``no_grad``)."""
        depth = num_quantizers or self.num_quantizers
        with evaluating(self):
            base, tok_lengths = pool_codes(base_codes, lengths, self.pool, self.pool_reduce,
                                           self.pad_id)
            valid = length_mask(tok_lengths, base.size(1))
            codes = base.new_full((*base.shape, depth), self.pad_id)
            codes[..., 0] = base
            for q in range(1, depth):
                layer = torch.full((base.size(0),), q, dtype=torch.long, device=base.device)
                logits, topk = draw_logits(*self._logit_pair(codes, layer, text_emb, skel_emb,
                                                             tok_lengths, guidance),
                                           guidance, guide, topk_ratio, draw_guidance)
                pred = sample_logits(logits, temperature, topk, generator)
                codes[..., q] = pred.masked_fill(~valid, self.pad_id)
            return unpool_codes(codes, lengths, self.pool, self.pad_id)
