r"""Semantic-aware feature modulation (SATA paper, section 3.2) and the plain
input projection used when the fusion block is ablated."""
from __future__ import annotations

import math
from typing import Optional

import torch
from torch import Tensor, nn
from torch_geometric.nn.resolver import activation_resolver


class SinusoidalEncoding(nn.Module):
    r"""Fourier features of continuous coordinates (NeRF-style):
    :math:`[x, \sin(2^k \pi x), \cos(2^k \pi x)]_{k < L}` per coordinate.

    Args:
        in_channels (int): Number of coordinates.
        num_frequencies (int, optional): :math:`L`, octaves per coordinate.
        include_input (bool, optional): Keep the raw coordinates too.

    Shapes:
        - **input**: :math:`(*, C_{in})`
        - **output**: :math:`(*, C_{in} (2L + 1))` (:math:`2 L C_{in}`
          without the input)
    """

    def __init__(self, in_channels: int, num_frequencies: int = 8,
                 include_input: bool = True) -> None:
        super().__init__()
        self.in_channels, self.include_input = in_channels, include_input
        freqs = math.pi * 2.0 ** torch.arange(num_frequencies, dtype=torch.float)
        self.register_buffer("freqs", freqs, persistent=False)

    @property
    def out_channels(self) -> int:
        return self.in_channels * (2 * self.freqs.numel() + int(self.include_input))

    def forward(self, x: Tensor) -> Tensor:
        angle = (x[..., None] * self.freqs).flatten(-2)
        parts = [x] if self.include_input else []
        return torch.cat(parts + [angle.sin(), angle.cos()], dim=-1)


def _check_semantic(semantic: Optional[Tensor], width: int) -> None:
    got = None if semantic is None else semantic.shape[-1]
    if got != width:
        raise ValueError(f"SemanticModulation: expected semantic features of width "
                         f"{width}, got {got}: build clips with the model's own, "
                         "to_clip(semantic=module.embed(skeleton)) as retarget does; "
                         "training: semantic_channels must be the data's width "
                         "(use_text=False trains without them)")


def _gather(value: Tensor, index: Optional[Tensor]) -> Tensor:
    return value if index is None else value[index]


class SemanticModulation(nn.Module):
    r"""Semantic-spatial modulation of motion features (paper eqs. 1-3).

    .. math::
        z_m = \phi_m(F_m), \; z_s = \mathrm{sin}([X_g; X_l]), \;
        z_t = \phi_t(X_t), \; c = \Phi([z_s; z_t]), \;
        [\gamma, \beta] = \Psi(c),

        \tilde F_m = z_m + \sigma(W_g c) \odot
        (\mathrm{LN}(z_m) \odot (1 + \gamma) + \beta)

    The condition :math:`c` depends only on static and semantic features, so
    it can be computed once per joint stream and gathered to the nodes with
    :obj:`index` (which the encoder and decoder do).

    Args:
        in_channels (int): Width of the motion features :math:`F_m`.
        hidden_channels (int): Output width (and width of :math:`z_t`).
        static_channels (int, optional): Width of the static coordinates
            (:math:`X_l, X_g`: 6).
        semantic_channels (int, optional): Width :math:`D_t` of :math:`X_t`
            (0: no semantic input).
        condition_channels (int, optional): Width of :math:`c` (default
            :obj:`hidden_channels`).
        num_frequencies (int, optional): Octaves of the sinusoidal encoder.
        use_text (bool, optional): Use :math:`X_t` in the condition
            (``False``: ablation "w/o text fusion", :math:`c = \Phi(z_s)`).
        act (str, optional): Activation of :math:`\Phi`.

    Shapes:
        - **x**: :math:`(N, C_{in})`
        - **static**: :math:`(S, 6)` (or :math:`(N, 6)` without index)
        - **semantic**: :math:`(S, D_t)`, optional
        - **index**: :math:`(N,)` row of :obj:`static` for every node, optional
        - **output**: :math:`(N, C_{hid})`
    """

    def __init__(self, in_channels: int, hidden_channels: int, static_channels: int = 6,
                 semantic_channels: int = 0, condition_channels: Optional[int] = None,
                 num_frequencies: int = 8, use_text: bool = True,
                 act: str = "relu") -> None:
        super().__init__()
        cond = condition_channels or hidden_channels
        self.phi_m = nn.Linear(in_channels, hidden_channels)
        self.phi_s = SinusoidalEncoding(static_channels, num_frequencies)
        self.use_text = bool(use_text and semantic_channels > 0)
        self.phi_t = nn.Linear(semantic_channels, hidden_channels) if self.use_text else None
        cond_in = self.phi_s.out_channels + (hidden_channels if self.use_text else 0)
        self.condition = nn.Sequential(nn.Linear(cond_in, cond), activation_resolver(act),
                                       nn.Linear(cond, cond))
        self.psi = nn.Linear(cond, 2 * hidden_channels)
        self.gate = nn.Linear(cond, hidden_channels)
        self.norm = nn.LayerNorm(hidden_channels)

    def condition_vector(self, static: Tensor, semantic: Optional[Tensor] = None) -> Tensor:
        r""":math:`c = \Phi([z_s; z_t])` per row of :obj:`static`."""
        parts = [self.phi_s(static)]
        if self.phi_t is not None:
            _check_semantic(semantic, self.phi_t.in_features)
            parts.append(self.phi_t(semantic))
        return self.condition(torch.cat(parts, dim=-1))

    def forward(self, x: Tensor, static: Tensor, semantic: Optional[Tensor] = None,
                index: Optional[Tensor] = None) -> Tensor:
        z_m = self.phi_m(x)
        c = _gather(self.condition_vector(static, semantic), index)
        gamma, beta = self.psi(c).chunk(2, dim=-1)
        h = self.norm(z_m) * (1 + gamma) + beta
        return z_m + torch.sigmoid(self.gate(c)) * h


class ConcatProjection(nn.Module):
    r"""Linear projection of ``[motion, static]`` features: the input layer
    of the "w/o fusion block" ablation (no semantic input). Same call as
    :class:`SemanticModulation`.

    Args:
        in_channels (int): Width of the motion features.
        hidden_channels (int): Output width.
        static_channels (int, optional): Width of the static features.

    Shapes:
        - **x**: :math:`(N, C_{in})`
        - **static**: :math:`(S, 6)` (or :math:`(N, 6)` without index)
        - **output**: :math:`(N, C_{hid})`
    """

    def __init__(self, in_channels: int, hidden_channels: int,
                 static_channels: int = 6) -> None:
        super().__init__()
        self.lin = nn.Linear(in_channels + static_channels, hidden_channels)

    def forward(self, x: Tensor, static: Tensor, semantic: Optional[Tensor] = None,
                index: Optional[Tensor] = None) -> Tensor:
        return self.lin(torch.cat([x, _gather(static, index)], dim=-1))


def build_input_layer(in_channels: int, hidden_channels: int, fusion: bool = True,
                      **kwargs) -> nn.Module:
    r""":class:`SemanticModulation` (with :obj:`kwargs`) if :obj:`fusion`,
    else :class:`ConcatProjection`."""
    if fusion:
        return SemanticModulation(in_channels, hidden_channels, **kwargs)
    return ConcatProjection(in_channels, hidden_channels,
                            kwargs.get("static_channels", 6))
