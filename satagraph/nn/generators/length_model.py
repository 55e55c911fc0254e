r"""A categorical distribution over motion durations from the text and the
skeleton, for generation when the user gives no length (MoMask's
``LengthEstimator`` takes the text only; a skeleton changes how long an
action takes).

A training duration is either known (a captioned clip or segment, whose
caption describes all of it) or only a lower bound (*censored*: a clip
whose length was drawn while its motion could have gone on, as the
endless zoo's, :class:`~satagraph.data.captioned.ZooCaptionWindows`). A
known duration is scored by the cross-entropy of its bin; a lower bound by
the probability of its bin or any longer one, as survival analysis scores
censored observations, so that drawn lengths teach the model "at least
this long" rather than a uniform spread of durations."""
from __future__ import annotations

from typing import Optional

import torch
import torch.nn.functional as F
from torch import Tensor, nn

from satagraph.nn.generators.sampling import sample_logits, uniform
from satagraph.nn.generators.token_transformer import evaluating


class LengthModel(nn.Module):
    r"""Duration classifier: bin :math:`i` stands for
    :math:`(i + 1)\,w` seconds (:math:`w` = :obj:`bin_seconds`), up to
    :obj:`max_seconds`; durations are rounded to the nearest bin and clipped
    to the range. An MLP reads the projected text embedding (a learned
    null-text vector where the text is absent or dropped) plus the projected
    skeleton embedding.

    Intended size for satagraph's data: 128 wide, 0.25 s bins up to 10 s
    (the longest training windows; AnyTop generates at most 9.8 s).

    Args:
        text_channels (int): Text embedding width.
        skel_channels (int): Skeleton embedding width.
        hidden_channels (int, optional): MLP width.
        bin_seconds (float, optional): Bin width :math:`w` in seconds.
        max_seconds (float, optional): Longest duration.
        dropout (float, optional): Dropout.
        cond_drop (float, optional): Text dropout probability in training
            (so that a skeleton alone gives a length distribution).
        label_smoothing (float, optional): Cross-entropy label smoothing.

    Shapes:
        - **text_emb**: :math:`(B, D_{text})` or ``None``,
          **skel_emb**: :math:`(B, D_s)`, **seconds**: :math:`(B,)`
        - **output** of :meth:`forward`: :math:`(B, n_{bins})` logits
    """

    def __init__(self, text_channels: int, skel_channels: int, hidden_channels: int = 64,
                 bin_seconds: float = 0.25, max_seconds: float = 10.0, dropout: float = 0.1,
                 cond_drop: float = 0.1, label_smoothing: float = 0.0) -> None:
        super().__init__()
        self.bin_seconds, self.cond_drop = float(bin_seconds), float(cond_drop)
        self.label_smoothing = label_smoothing
        self.num_bins = max(1, round(max_seconds / bin_seconds))
        self.text_proj = nn.Linear(text_channels, hidden_channels)
        self.skel_proj = nn.Linear(skel_channels, hidden_channels)
        self.null_text = nn.Parameter(torch.randn(hidden_channels) * 0.02)
        self.mlp = nn.Sequential(nn.GELU(), nn.Dropout(dropout),
                                 nn.Linear(hidden_channels, hidden_channels), nn.GELU(),
                                 nn.Linear(hidden_channels, self.num_bins))

    def seconds_to_bins(self, seconds: Tensor) -> Tensor:
        """Nearest bin of every duration (clipped to the range)."""
        bins = torch.round(seconds / self.bin_seconds).long() - 1
        return bins.clamp(0, self.num_bins - 1)

    def bins_to_seconds(self, bins: Tensor) -> Tensor:
        """Duration of every bin."""
        return (bins + 1).to(torch.float) * self.bin_seconds

    @staticmethod
    def seconds_to_frames(seconds: Tensor, fps: float) -> Tensor:
        """Whole frames (at least one) of every duration."""
        return torch.round(seconds * fps).long().clamp(min=1)

    def forward(self, text_emb: Optional[Tensor], skel_emb: Tensor,
                drop_text: Optional[Tensor] = None) -> Tensor:
        skel = self.skel_proj(skel_emb)
        text = self.null_text.expand_as(skel)
        if text_emb is not None:
            cond = self.text_proj(text_emb)
            text = cond if drop_text is None else torch.where(drop_text.unsqueeze(-1), text, cond)
        return self.mlp(text + skel)

    def loss(self, seconds: Tensor, text_emb: Optional[Tensor], skel_emb: Tensor,
             generator: Optional[torch.Generator] = None,
             censored: Optional[Tensor] = None) -> Tensor:
        """Mean negative log-likelihood of the durations (text dropped with
        probability :obj:`cond_drop` in training): the cross-entropy of a
        known duration's bin, :math:`-\\log P(\\text{bin} \\ge b)` of a
        lower bound's (:obj:`censored`, default: none).

        Shapes:
            - **seconds**, **censored**: :math:`(B,)`
        """
        drop = None
        if self.training and self.cond_drop > 0:
            drop = uniform((skel_emb.size(0),), generator, skel_emb.device) < self.cond_drop
        logits = self(text_emb, skel_emb, drop)
        bins = self.seconds_to_bins(seconds)
        known = F.cross_entropy(logits, bins, label_smoothing=self.label_smoothing,
                                reduction="none")
        if censored is None or not bool(censored.any()):
            return known.mean()
        later = torch.arange(self.num_bins, device=logits.device) >= bins.unsqueeze(-1)
        bound = (logits.logsumexp(-1)
                 - logits.masked_fill(~later, float("-inf")).logsumexp(-1))
        return torch.where(censored.to(logits.device).bool(), bound, known).mean()

    @torch.no_grad()
    def sample(self, text_emb: Optional[Tensor], skel_emb: Tensor, temperature: float = 1.0,
               generator: Optional[torch.Generator] = None) -> Tensor:
        """Durations (seconds) drawn from the predicted distribution."""
        with evaluating(self):
            logits = self(text_emb, skel_emb)
        return self.bins_to_seconds(sample_logits(logits, temperature, None, generator))

    @torch.no_grad()
    def mode(self, text_emb: Optional[Tensor], skel_emb: Tensor) -> Tensor:
        """Most likely duration (seconds)."""
        with evaluating(self):
            logits = self(text_emb, skel_emb)
        return self.bins_to_seconds(logits.argmax(-1))
