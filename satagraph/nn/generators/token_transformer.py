r"""The backbone shared by the masked and residual token transformers: two
separate condition tokens (text, skeleton), positions, a bidirectional
Transformer encoder over code tokens with a key padding mask."""
from __future__ import annotations

from contextlib import contextmanager
from typing import Callable, Iterator, Optional, Sequence, Tuple

import torch
import torch.nn.functional as F
from torch import Tensor, nn

from satagraph.nn.generators.sampling import uniform
from satagraph.nn.layers.spatio_temporal import sinusoidal_positions

POSITIONS = ("sine", "learned")


class ConditionTokens(nn.Module):
    r"""The text token (projected text embedding, or a learned null-text
    token where the text is dropped or absent) and the skeleton token
    (projected :math:`f_{skel}`, never dropped), kept as two tokens.

    Args:
        text_channels (int): Width :math:`D_{text}` of the text embedding.
        skel_channels (int): Width :math:`D_s` of the skeleton embedding.
        hidden_channels (int): Token width.

    Shapes:
        - **text_emb**: :math:`(B, D_{text})` or ``None``,
          **skel_emb**: :math:`(B, D_s)`, **drop_text**: :math:`(B,)` bool
        - **output**: :math:`(B, 2, C)` (text token first)
    """

    def __init__(self, text_channels: int, skel_channels: int, hidden_channels: int) -> None:
        super().__init__()
        self.text_proj = nn.Linear(text_channels, hidden_channels)
        self.skel_proj = nn.Linear(skel_channels, hidden_channels)
        self.null_text = nn.Parameter(torch.randn(hidden_channels) * 0.02)

    def forward(self, text_emb: Optional[Tensor], skel_emb: Tensor,
                drop_text: Optional[Tensor] = None) -> Tensor:
        skel = self.skel_proj(skel_emb)
        text = self.null_text.to(skel.dtype).expand_as(skel)
        if text_emb is not None:
            cond = self.text_proj(text_emb)
            text = cond if drop_text is None else torch.where(drop_text.unsqueeze(-1), text, cond)
        return torch.stack([text, skel], dim=1)


class TokenTransformer(nn.Module):
    r"""Pre-norm bidirectional Transformer encoder over ``[text, skeleton,
    extra..., tokens...]``; returns the outputs at the token positions.

    Args:
        hidden_channels (int): Width.
        heads (int): Attention heads.
        num_layers (int): Encoder layers.
        ff_channels (int): Feed-forward width.
        dropout (float): Dropout.
        text_channels (int): Text embedding width.
        skel_channels (int): Skeleton embedding width.
        cond_drop (float): Probability of dropping the text in training
            (drawn by :meth:`draw_text_drop`).
        positions (str): ``"sine"`` (any length) or ``"learned"`` (at most
            :obj:`max_length` tokens).
        max_length (int, optional): Longest token sequence (learned
            positions).
        position_jitter (int, optional): In training, each sequence's first
            token sits at a position drawn from ``0..position_jitter``
            instead of 0, so that no motion is tied to the first positions
            (``experiments/T2M.md`` section 59: the shipped generator's
            residual layers write slow motion there); 0, the default, as
            every model before it. Inference always starts at 0.

    Shapes:
        - **h**: :math:`(B, T, C)` token embeddings, **valid**: :math:`(B, T)`,
          **extra**: :math:`(B, E, C)`
        - **output**: :math:`(B, T, C)`
    """

    def __init__(self, hidden_channels: int, heads: int, num_layers: int, ff_channels: int,
                 dropout: float, text_channels: int, skel_channels: int, cond_drop: float,
                 positions: str = "sine", max_length: Optional[int] = None,
                 position_jitter: int = 0) -> None:
        super().__init__()
        if positions not in POSITIONS:
            raise ValueError(f"unknown positions {positions!r}: use one of {POSITIONS}")
        if positions == "learned" and not max_length:
            raise ValueError("learned positions need max_length")
        if position_jitter < 0:
            raise ValueError(f"position_jitter must be >= 0, got {position_jitter}")
        self.cond_drop, self.hidden_channels = cond_drop, hidden_channels
        self.position_jitter = int(position_jitter)
        self.condition = ConditionTokens(text_channels, skel_channels, hidden_channels)
        self.pos = nn.Embedding(max_length, hidden_channels) if positions == "learned" else None
        layer = nn.TransformerEncoderLayer(hidden_channels, heads, ff_channels, dropout,
                                           activation="gelu", batch_first=True,
                                           norm_first=True)
        self.encoder = nn.TransformerEncoder(layer, num_layers, norm=nn.LayerNorm(hidden_channels),
                                             enable_nested_tensor=False)

    def positions(self, length: int, device, dtype) -> Tensor:
        """Position embeddings :math:`(T, C)`."""
        if self.pos is None:
            return sinusoidal_positions(length, self.hidden_channels, device, dtype)
        if length > self.pos.num_embeddings:
            raise ValueError(f"{length} tokens exceed max_length {self.pos.num_embeddings}")
        return self.pos.weight[:length]

    def token_positions(self, h: Tensor) -> Tensor:
        r"""The position embeddings of :obj:`h`'s tokens: :math:`(T, C)`
        from 0, or in training with :attr:`position_jitter` :math:`(B, T, C)`
        from a start drawn per sequence."""
        length = h.size(1)
        if not self.training or self.position_jitter <= 0:
            return self.positions(length, h.device, h.dtype)
        table = self.positions(length + self.position_jitter, h.device, h.dtype)
        start = torch.randint(self.position_jitter + 1, (h.size(0), 1), device=h.device)
        return table[start + torch.arange(length, device=h.device)]

    def draw_text_drop(self, size: int, generator: Optional[torch.Generator] = None,
                       device=None) -> Tensor:
        """Which samples lose their text (training only; :math:`(B,)` bool)."""
        if not self.training or self.cond_drop <= 0:
            return torch.zeros(size, dtype=torch.bool, device=device)
        return uniform((size,), generator, device) < self.cond_drop

    def forward(self, h: Tensor, valid: Tensor, text_emb: Optional[Tensor], skel_emb: Tensor,
                extra: Optional[Tensor] = None, drop_text: Optional[Tensor] = None) -> Tensor:
        cond = self.condition(text_emb, skel_emb, drop_text)
        if extra is not None:
            cond = torch.cat([cond, extra], dim=1)
        h = h + self.token_positions(h)
        keep = F.pad(valid, (cond.size(1), 0), value=True)
        out = self.encoder(torch.cat([cond, h], dim=1), src_key_padding_mask=~keep)
        return out[:, cond.size(1):]


def masked_cross_entropy(logits: Tensor, targets: Tensor, mask: Tensor,
                         label_smoothing: float = 0.0) -> Tensor:
    r"""Mean cross-entropy over the ``True`` positions of :obj:`mask` only
    (targets elsewhere are never read).

    Shapes:
        - **logits**: :math:`(B, T, K)`, **targets**, **mask**: :math:`(B, T)`
        - **output**: scalar
    """
    if not bool(mask.any()):
        return logits.sum() * 0.0
    return F.cross_entropy(logits[mask], targets[mask], label_smoothing=label_smoothing)


def masked_accuracy(logits: Tensor, targets: Tensor, mask: Tensor) -> Tensor:
    """Share of the ``True`` positions of :obj:`mask` whose argmax is right."""
    hit = (logits.argmax(-1) == targets) & mask
    return hit.sum() / mask.sum().clamp(min=1)


def with_and_without_text(forward: Callable[..., Tensor], inputs: Sequence[Tensor],
                          has_text: bool, guidance: float) -> Tuple[Tensor, Optional[Tensor]]:
    r"""The text-conditioned and text-dropped outputs of :obj:`forward` on
    :obj:`inputs` (its positional arguments, batch first) in one batch of
    twice the size, the second half with ``drop_text``; the plain output and
    ``None`` where no guidance applies (no text, or :obj:`guidance` 1).

    Shapes:
        - **inputs**: each :math:`(B, \ldots)`
        - **output**: two :math:`(B, \ldots, K)`
    """
    if not has_text or guidance == 1.0:
        return forward(*inputs), None
    size = inputs[0].size(0)
    drop = torch.arange(2 * size, device=inputs[0].device) >= size
    both = forward(*(x.repeat(2, *[1] * (x.dim() - 1)) for x in inputs), drop_text=drop)
    return both[:size], both[size:]


@contextmanager
def evaluating(module: nn.Module) -> Iterator[None]:
    """:obj:`module` in eval mode inside the block, its mode restored after."""
    mode = module.training
    module.eval()
    try:
        yield
    finally:
        module.train(mode)


def init_token_model(module: nn.Module) -> None:
    """MoMask's (BERT's) initialisation: linear and embedding weights
    :math:`N(0, 0.02)`, zero biases, unit layer norms."""
    for sub in module.modules():
        if isinstance(sub, (nn.Linear, nn.Embedding)):
            nn.init.normal_(sub.weight, std=0.02)
        if isinstance(sub, nn.Linear) and sub.bias is not None:
            nn.init.zeros_(sub.bias)
        if isinstance(sub, nn.LayerNorm):
            nn.init.ones_(sub.weight)
            nn.init.zeros_(sub.bias)
