"""The zero-padding RVQ-VAE baseline: MoMask's 1D-convolution RVQ-VAE on
frames flattened to a fixed joint count (SATA paper appendix D.3.1)."""
from __future__ import annotations

from typing import Dict, Tuple

import torch
from torch import Tensor, nn

from satagraph.nn.autoencoders.base import MotionAutoencoder
from satagraph.typing import DYNAMIC_CHANNELS, ROOT_CHANNELS
from satagraph.nn.bottlenecks.rvq import RVQBottleneck
from satagraph.nn.autoencoders.decoder import C_CHANNELS, Q_CHANNELS

#: Outputs per padded joint slot: 6D rotation and contact logit.
JOINT_OUT = Q_CHANNELS + C_CHANNELS


# ------------------------------------------------------------ padding
def padded_slots(frames, max_joints: int) -> Tuple[Tensor, int]:
    r"""Row of every node in a dense ``(B, T_pad, J_max)`` layout, and
    :math:`T_{pad}`, the longest clip rounded up to a multiple of 4 (so
    that two stride-2 convolutions divide it).

    Shapes:
        - **output**: :math:`(N,)` and an int
    """
    num_joints = frames.clip_num_joints
    if int(num_joints.max()) > max_joints:
        raise ValueError(f"a clip has {int(num_joints.max())} joints; this padded "
                         f"model holds at most max_joints={max_joints}")
    clip = frames.node_clip
    first_stream = num_joints.cumsum(0) - num_joints
    joint = frames.node_stream - first_stream[clip]
    time_pad = -(-frames.max_time // 4) * 4
    return (clip * time_pad + frames.node_time) * max_joints + joint, time_pad


def padding_mask(frames, max_joints: int) -> Tensor:
    r"""Real (joint, frame) slots of the dense layout (``True``); padded
    joints and frames after a clip's end are ``False``.

    Shapes:
        - **output**: :math:`(B, T_{pad}, J_{max})` bool
    """
    slot, time_pad = padded_slots(frames, max_joints)
    mask = torch.zeros(len(frames.meta) * time_pad * max_joints, dtype=torch.bool,
                       device=slot.device)
    return mask.index_fill(0, slot, True).view(-1, time_pad, max_joints)


def to_padded(x: Tensor, root: Tensor, frames, max_joints: int) -> Tensor:
    r"""Per-frame vectors ``[r; vec(X_pad)]`` (eq. 6 of the SATA paper):
    node features zero-padded to :obj:`max_joints`, flattened, after the
    root features; zeros after each clip's last frame.

    Shapes:
        - **x**: :math:`(N, F)`, **root**: :math:`(G, 4)`
        - **output**: :math:`(B, T_{pad}, 4 + J_{max} F)`
    """
    slot, time_pad = padded_slots(frames, max_joints)
    num_clips = len(frames.meta)
    dense = x.new_zeros(num_clips * time_pad * max_joints, x.shape[-1])
    dense = dense.index_copy(0, slot, x).view(num_clips, time_pad, -1)
    frame_slot = frames.frame_clip * time_pad + frames.frame_time
    dense_root = root.new_zeros(num_clips * time_pad, root.shape[-1])
    dense_root = dense_root.index_copy(0, frame_slot, root).view(num_clips, time_pad, -1)
    return torch.cat([dense_root, dense], dim=-1)


def from_padded(dense: Tensor, frames, max_joints: int) -> Dict[str, Tensor]:
    r"""Inverse of :func:`to_padded` for decoder outputs ``[r; vec(q, c)]``:
    only the real joints and frames of :obj:`frames` are read, so padded
    slots never reach a loss or a metric.

    Shapes:
        - **dense**: :math:`(B, T_{pad}, 4 + 7 J_{max})`
        - **output**: ``{"q": (N, 6), "r": (G, 4), "c": (N, 1)}``
    """
    slot, time_pad = padded_slots(frames, max_joints)
    root, joints = dense.split([ROOT_CHANNELS, JOINT_OUT * max_joints], dim=-1)
    joints = joints.reshape(-1, JOINT_OUT).index_select(0, slot)
    frame_slot = frames.frame_clip * time_pad + frames.frame_time
    q, c = joints.split([Q_CHANNELS, C_CHANNELS], dim=-1)
    return {"q": q, "r": root.reshape(-1, ROOT_CHANNELS).index_select(0, frame_slot),
            "c": c}


def latent_lengths(frames, down: int) -> Tensor:
    """Latent steps per clip, ``ceil(T_s / down)``, :math:`(B,)`."""
    return -(-frames.clip_num_frames // down)


def latent_mask(frames, down: int) -> Tensor:
    r"""Latent steps that cover at least one real frame.

    Shapes:
        - **output**: :math:`(B, T_{pad} / down)` bool
    """
    steps = -(-frames.max_time // 4) * 4 // down
    time = torch.arange(steps, device=frames.clip_num_frames.device)
    return time < latent_lengths(frames, down).unsqueeze(-1)


# --------------------------------------------------------- backbone
class ResConv1DBlock(nn.Module):
    r"""MoMask's residual block: act, dilated conv (kernel 3), act, conv
    (kernel 1), plus the input.

    Shapes:
        - **input**, **output**: :math:`(B, C, T)`
    """

    def __init__(self, channels: int, dilation: int = 1) -> None:
        super().__init__()
        self.block = nn.Sequential(
            nn.ReLU(), nn.Conv1d(channels, channels, 3, padding=dilation, dilation=dilation),
            nn.ReLU(), nn.Conv1d(channels, channels, 1))

    def forward(self, x: Tensor) -> Tensor:
        return x + self.block(x)


def resnet1d(channels: int, depth: int, dilation_growth: int) -> nn.Sequential:
    """:obj:`depth` residual blocks, dilations ``growth^d`` from the largest
    down (MoMask's ``reverse_dilation``)."""
    blocks = [ResConv1DBlock(channels, dilation_growth ** d) for d in range(depth)]
    return nn.Sequential(*blocks[::-1])


def conv_encoder(in_channels: int, channels: int, down_t: int, depth: int,
                 dilation_growth: int) -> nn.Sequential:
    """Conv + ReLU, :obj:`down_t` x [stride-2 conv, residual stack], conv."""
    layers = [nn.Conv1d(in_channels, channels, 3, padding=1), nn.ReLU()]
    for _ in range(down_t):
        layers += [nn.Conv1d(channels, channels, 4, stride=2, padding=1),
                   resnet1d(channels, depth, dilation_growth)]
    layers.append(nn.Conv1d(channels, channels, 3, padding=1))
    return nn.Sequential(*layers)


def conv_decoder(latent_channels: int, channels: int, out_channels: int, down_t: int,
                 depth: int, dilation_growth: int) -> nn.Sequential:
    """The mirror of :func:`conv_encoder` with nearest-neighbour upsampling."""
    layers = [nn.Conv1d(latent_channels, channels, 3, padding=1), nn.ReLU()]
    for _ in range(down_t):
        layers += [resnet1d(channels, depth, dilation_growth),
                   nn.Upsample(scale_factor=2, mode="nearest"),
                   nn.Conv1d(channels, channels, 3, padding=1)]
    layers += [nn.Conv1d(channels, channels, 3, padding=1), nn.ReLU(),
               nn.Conv1d(channels, out_channels, 3, padding=1)]
    return nn.Sequential(*layers)


class PaddedRVQ(MotionAutoencoder):
    r"""The padding baseline of the SATA paper (appendix D.3.1): MoMask's
    RVQ-VAE on per-frame vectors ``[r; vec(X_pad)]`` in which every
    skeleton's joint features are zero-padded to :obj:`max_joints`. The
    backbone never sees the skeleton topology.

    Encoder: 1D convolutions over time with :math:`2^{down_t}` temporal
    downsampling; residual quantisation with
    :class:`~satagraph.nn.RVQBottleneck` of the latent steps that cover real
    frames; the decoder upsamples and predicts ``[r; vec(q, c)]`` per
    frame, which is read back onto the target's nodes (real joints and
    frames only; :func:`padding_mask` is returned as ``mask``). The target
    must have the source's clip lengths; its joints take the slots of the
    same index (naive correspondence, as a padded model has no other).
    Clips are padded in time to the batch's longest, and the padding passes
    through the convolutions' biases: a clip's output depends a little on
    the clips batched with it (up to 7e-3 in normalised units, growing
    towards its end, for 9 frames beside 17), as in MoMask; SATA's do not.
    Like every RVQ here, its codebooks take their k-means start from the
    first batch it sees, in evaluation mode too (`vector_quantize_pytorch`).

    Args:
        max_joints (int): :math:`J_{max}`, joint slots per frame.
        in_channels (int, optional): Dynamic features per joint :math:`d_j`.
        hidden_channels (int, optional): Convolution width (MoMask: 512).
        latent_channels (int, optional): Code width (MoMask: 512).
        down_t (int, optional): Stride-2 stages (MoMask: 2, i.e. one latent
            per 4 frames).
        depth (int, optional): Residual blocks per stage (MoMask: 3).
        dilation_growth (int, optional): Dilation growth (MoMask: 3).
        num_quantizers (int, optional): Residual codebooks (MoMask: 6).
        codebook_size (int, optional): Codes per codebook (MoMask: 512).
        commitment_weight, quantize_dropout, codebook_decay, kmeans_init,
        threshold_ema_dead_code: see :class:`~satagraph.nn.RVQBottleneck`.

    Shapes:
        - **batch**, **target_batch**: :class:`~satagraph.data.FrameBatch`
          of :math:`B` clips with the same lengths, :math:`G` frames,
          :math:`N` target nodes
        - **output** of :meth:`forward`: ``q`` :math:`(N, 6)`, ``r``
          :math:`(G, 4)`, ``c`` :math:`(N, 1)` (logits), ``z``
          :math:`(K, C_{lat})` with :math:`K = \sum_s \lceil T_s / 4\rceil`
          latent steps, ``codes`` :math:`(K, Q)`, ``commit`` and ``mask``
          :math:`(B, T_{pad}, J_{max})`
    """

    def __init__(self, max_joints: int, in_channels: int = DYNAMIC_CHANNELS,
                 hidden_channels: int = 512, latent_channels: int = 512,
                 down_t: int = 2, depth: int = 3, dilation_growth: int = 3,
                 num_quantizers: int = 6, codebook_size: int = 512,
                 commitment_weight: float = 1.0, quantize_dropout: float = 0.2,
                 codebook_decay: float = 0.99, kmeans_init: bool = True,
                 threshold_ema_dead_code: float = 1.0) -> None:
        super().__init__()
        if down_t > 2:
            raise ValueError("down_t must be at most 2 (frames are padded to a multiple of 4)")
        self.max_joints, self.down = max_joints, 2 ** down_t
        self.latent_rate = self.down
        in_dim = ROOT_CHANNELS + max_joints * in_channels
        out_dim = ROOT_CHANNELS + max_joints * JOINT_OUT
        self.encoder = conv_encoder(in_dim, hidden_channels, down_t, depth, dilation_growth)
        self.bottleneck = RVQBottleneck(
            hidden_channels, latent_channels, num_quantizers, codebook_size,
            commitment_weight, quantize_dropout, codebook_decay, kmeans_init,
            threshold_ema_dead_code)
        self.decoder = conv_decoder(latent_channels, hidden_channels, out_dim, down_t,
                                    depth, dilation_growth)

    def encode(self, batch) -> Dict[str, Tensor]:
        """Quantised latents of the real latent steps, clip after clip:
        ``z``, ``codes``, ``commit``."""
        dense = to_padded(batch.x, batch.root, batch, self.max_joints)
        h = self.encoder(dense.transpose(1, 2)).transpose(1, 2)
        return self.bottleneck(h[latent_mask(batch, self.down)])._asdict()

    def decode_dense(self, z: Tensor, target_batch) -> Tensor:
        r"""Padded decoder output ``[r; vec(q, c)]`` per frame slot.

        Shapes:
            - **z**: :math:`(K, C_{lat})`
            - **output**: :math:`(B, T_{pad}, 4 + 7 J_{max})`
        """
        mask = latent_mask(target_batch, self.down)
        if z.shape[0] != int(mask.sum()):
            raise ValueError(f"PaddedRVQ: {z.shape[0]} latent steps for a target "
                             f"with {int(mask.sum())}")
        grid = z.new_zeros(mask.shape + (z.shape[-1],)).masked_scatter(mask[..., None], z)
        return self.decoder(grid.transpose(1, 2)).transpose(1, 2)

    def decode(self, z: Tensor, target_batch) -> Dict[str, Tensor]:
        """``q``, ``r``, ``c`` (logits) on the target's real nodes, and the
        padding ``mask``."""
        out = from_padded(self.decode_dense(z, target_batch), target_batch, self.max_joints)
        out["mask"] = padding_mask(target_batch, self.max_joints)
        return out
