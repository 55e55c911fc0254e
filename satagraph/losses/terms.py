"""The loss terms on frame-graph batches, each a function of predictions,
ground truth and the batch (see :mod:`satagraph.losses` for units)."""
from __future__ import annotations

from typing import Optional

import torch
import torch.nn.functional as F
from torch import Tensor

from satagraph.losses.positions import POSITION_SCALE, time_difference
from satagraph.ops.rotation import rotation_6d_to_matrix

def _masked_mean(value: Tensor, mask: Tensor) -> Tensor:
    """Mean of ``value`` rows where ``mask`` (zero when nothing is selected)."""
    value = value.reshape(mask.shape[0], -1)[mask]
    return value.mean() if value.numel() else value.sum()


def rotation_loss(q_pred: Tensor, q_true: Tensor, batch) -> Tensor:
    r"""MSE of rotation matrices (from 6D) over joints with children.

    Shapes:
        - **q_pred**, **q_true**: :math:`(N, 6)`
    """
    diff = rotation_6d_to_matrix(q_pred) - rotation_6d_to_matrix(q_true)
    return _masked_mean(diff.pow(2), batch.node_inner)


def velocity_loss(pos_pred: Tensor, pos_true: Tensor, batch) -> Tensor:
    r"""MSE of per-frame displacements (consecutive frames of a clip).

    Shapes:
        - **pos_pred**, **pos_true**: :math:`(N, 3)` global positions
    """
    prev = batch.node_prev
    diff = (pos_pred - pos_pred[prev]) - (pos_true - pos_true[prev])
    return _masked_mean(diff.pow(2), batch.node_time > 0)


def limb_velocity_loss(pos_source: Tensor, pos_target: Tensor, pairing,
                       scale: float = POSITION_SCALE) -> Tensor:
    r"""Mean squared difference of the paired limb ends' per-frame
    displacements in the facing frame, relative to the root, each in
    :obj:`scale` units per its character's height (unpaired retargeting
    across skeletons; zero when no limb is paired).

    Args:
        pos_source (Tensor): Source positions relative to the root's ground
            projection in the facing frame (the ``x`` features).
        pos_target (Tensor): The same for the motion decoded on the partner
            skeletons (:func:`facing_positions`).
        pairing (Pairing): From :func:`satagraph.data.pairing.partner_batch`.
        scale (float, optional): Units per character height
            (:data:`~satagraph.losses.POSITION_SCALE`).

    Shapes:
        - **pos_source**: :math:`(N, 3)`, **pos_target**: :math:`(N', 3)`
        - **output**: scalar
    """
    if not pairing.source_nodes.numel():
        return pos_target.sum() * 0.0
    src = pos_source[pairing.source_nodes] - pos_source[pairing.source_prev]
    tgt = pos_target[pairing.target_nodes] - pos_target[pairing.target_prev]
    src = src.to(tgt.dtype) * (scale / pairing.source_height)[:, None]
    tgt = tgt * (scale / pairing.target_height)[:, None]
    return (tgt - src).pow(2).sum(-1).mean()


#: Weight of the lowest joint's height inside :func:`root_transfer_loss`
#: (heights x 10: a tenth of the height off the ground costs as much as a
#: root moving one height per second too fast).
LOWEST_SCALE = 10.0


def root_transfer_loss(r_source: Tensor, r_target: Tensor, h_source: Tensor,
                       h_target: Tensor, low_source: Tensor, low_target: Tensor,
                       leg_source: Tensor, leg_target: Tensor) -> Tensor:
    r"""Unpaired cross-skeleton root term: a motion decoded onto another
    skeleton turns at the source's yaw rate (rad/s), moves its root over
    the ground as many of its own leg lengths per second as the source
    (the unit in which a cat and a horse that walk alike travel alike:
    :func:`satagraph.motion.leg_length`), and keeps its lowest joint as
    many of its heights above the ground (x :data:`LOWEST_SCALE`). The limb
    term (:func:`limb_velocity_loss`) sees positions relative to the root
    only, so without this the partner's root may drift, float or sink.

    Shapes:
        - **r_source**, **r_target**: :math:`(G', 4)` root features (yaw
          rate, x/z velocity in the facing frame, height) of the source
          frames and of their decoding on the partner
        - **h_source**, **h_target**, **low_source**, **low_target**,
          **leg_source**, **leg_target**: :math:`(G',)` heights of the two
          characters, each frame's lowest joint height and the two leg
          lengths
        - **output**: scalar
    """
    r_source = r_source.to(r_target.dtype)
    turn = (r_target[:, 0] - r_source[:, 0]).pow(2)
    speed = (r_target[:, 1:3] / leg_target[:, None]
             - r_source[:, 1:3] / leg_source[:, None].to(r_target.dtype)).pow(2).sum(-1)
    low = (LOWEST_SCALE * (low_target / h_target - low_source.to(low_target.dtype) / h_source)
           ).pow(2)
    return (turn + speed + low).mean()


def carried_heights(pos: Tensor, batch) -> Tensor:
    r"""Every stream's (clip joint's) height above its frame's root,
    averaged over the clip's frames, in heights of its clip's character
    (how a body carries its joints; the mean that
    :func:`~satagraph.pipelines.quality.posture` reads as a median).

    Shapes:
        - **pos**: :math:`(N, 3)` facing-frame (or global) positions
        - **output**: :math:`(S,)`
    """
    from torch_geometric.utils import scatter
    above = pos[:, 1] - pos[batch.root_node[batch.batch], 1]
    return scatter(above / batch.heights("node").to(pos.dtype), batch.node_stream, 0,
                   int(batch.num_streams), "mean")


def carriage_loss(pos_target: Tensor, pos_partner: Tensor, target, partner,
                  partners: Tensor) -> Tensor:
    r"""Unpaired cross-skeleton carriage term: a motion decoded onto another
    skeleton carries each joint as high above the root, on average over
    the window, as that skeleton's own clip does (:func:`carried_heights`),
    both in the partner's heights: the squared gap averaged over each
    pair's joints, then over the pairs. The limb and root terms
    (:func:`limb_velocity_loss`, :func:`root_transfer_loss`) see the
    source's motion only, so without this a human's upright carriage is
    copied onto a quadruped (walking on its hind legs, forepaws up).
    Every frame of the partner's clip counts, standing or not.

    Args:
        pos_target (Tensor): Positions of the motion decoded on the partner
            skeletons (:func:`facing_positions`), nodes of :obj:`target`.
        pos_partner (Tensor): The partners' own positions (the ``x``
            features), nodes of :obj:`partner`.
        target (FrameBatch): The partner skeletons' frame graphs
            (``Pairing.target``).
        partner (FrameBatch): The batch holding the partners' own clips.
        partners (Tensor): Each :obj:`target` clip's partner clip in
            :obj:`partner` (``Pairing.partners``).

    Shapes:
        - **pos_target**: :math:`(N', 3)`, **pos_partner**: :math:`(N, 3)`
        - **partners**: :math:`(B',)`
        - **output**: scalar
    """
    from torch_geometric.utils import scatter
    pred = carried_heights(pos_target, target)
    true = carried_heights(pos_partner.to(pos_target.dtype), partner)
    first_t = target.clip_num_joints.cumsum(0) - target.clip_num_joints
    first_p = partner.clip_num_joints.cumsum(0) - partner.clip_num_joints
    clip = target.stream_clip
    stream = torch.arange(clip.numel(), device=clip.device)
    same = stream - first_t[clip] + first_p[partners[clip]]
    gap = (pred - true[same]).pow(2)
    return scatter(gap, clip, 0, partners.numel(), "mean").mean()


def contact_loss(c_logits: Tensor, c_true: Tensor) -> Tensor:
    r"""Binary cross-entropy of contact logits.

    Shapes:
        - **c_logits**, **c_true**: :math:`(N, 1)`
    """
    return F.binary_cross_entropy_with_logits(c_logits, c_true.to(c_logits.dtype))


def foot_sliding_loss(pos_pred: Tensor, c_true: Tensor, batch) -> Tensor:
    r"""Mean horizontal displacement per frame of the predicted global
    positions, weighted by the true contact (SAME's ``cv``).

    Shapes:
        - **pos_pred**: :math:`(N, 3)`, **c_true**: :math:`(N, 1)`
    """
    step = (pos_pred - pos_pred[batch.node_prev])[:, [0, 2]].norm(dim=-1)
    return _masked_mean(step * c_true.reshape(-1), batch.node_time > 0)


def stance_loss(local_pred: Tensor, local_true: Tensor, c_true: Tensor, batch) -> Tensor:
    r"""Mean squared error of the per-frame horizontal displacement of the
    joints in contact, relative to the root in the facing frame, weighted
    by the true contact. A planted foot moves back under the body as fast as
    the root moves forward; :func:`foot_sliding_loss` (global frame) can be
    lowered by slowing the root, this term only by the stride.

    Shapes:
        - **local_pred**, **local_true**: :math:`(N, 3)` facing-frame
          positions
        - **c_true**: :math:`(N, 1)`
    """
    prev = batch.node_prev
    diff = (local_pred - local_pred[prev]) - (local_true - local_true[prev])
    value = diff[:, [0, 2]].pow(2).sum(-1) * c_true.reshape(-1).to(diff.dtype)
    return _masked_mean(value, batch.node_time > 0)


def amplitude_loss(local_pred: Tensor, local_true: Tensor, batch,
                   streams: Optional[Tensor] = None) -> Tensor:
    r"""Mean squared difference of every joint's spread over its clip: the
    standard deviation over time of each axis of the facing-frame position
    (relative to the root's ground projection), predicted against true.
    The mean squared position error is lowest, for a decoder unsure of a
    limb's phase, at a motion of smaller swing; this term scores the swing
    itself (how far a foot reaches fore and aft, how high it lifts), not
    where in it each frame is. :obj:`streams` keeps some joints only
    (e.g. :func:`limb_end_streams`; zero when it is empty).

    Shapes:
        - **local_pred**, **local_true**: :math:`(N, 3)` facing-frame
          positions
        - **streams**: :math:`(S',)` stream (clip joint) indices
        - **output**: scalar
    """
    return stream_mean(spread_error(local_pred, local_true, batch), streams)


def spread_error(local_pred: Tensor, local_true: Tensor, batch) -> Tensor:
    r"""Squared difference of every stream's (clip joint's) spread over its
    clip, predicted against true, summed over the axes (what
    :func:`amplitude_loss` averages).

    Shapes:
        - **local_pred**, **local_true**: :math:`(N, 3)`
        - **output**: :math:`(S,)`
    """
    return (_spread(local_pred, batch) - _spread(local_true, batch)).pow(2).sum(-1)


def stream_mean(values: Tensor, streams: Optional[Tensor] = None) -> Tensor:
    """Mean of per-stream :obj:`values` over :obj:`streams` (all when
    ``None``; zero when empty)."""
    if streams is not None:
        values = values[streams]
    return values.mean() if values.numel() else values.sum()


def limb_end_streams(batch) -> Tensor:
    r"""Streams (clip joints) of every clip's limb ends
    (:attr:`~satagraph.data.FrameBatch.clip_limb_ends`).

    Shapes:
        - **output**: :math:`(S',)`
    """
    first = batch.clip_num_joints.cumsum(0) - batch.clip_num_joints
    ends = batch.clip_limb_ends.to(first.device)
    return (first[:, None] + ends)[ends >= 0]


def _spread(pos: Tensor, batch) -> Tensor:
    """Standard deviation over time of each stream's (clip joint's)
    positions, :math:`(S, 3)`."""
    from torch_geometric.utils import scatter
    size = int(batch.num_streams)
    mean = scatter(pos, batch.node_stream, 0, size, "mean")
    var = scatter((pos - mean[batch.node_stream]).pow(2), batch.node_stream, 0, size, "mean")
    return (var + 1e-6).sqrt()


def penetration_loss(pos_pred: Tensor) -> Tensor:
    r"""Mean of :math:`\min(y, 0)^2` (the ground is at :math:`y = 0`).

    Shapes:
        - **pos_pred**: :math:`(N, 3)`
    """
    return pos_pred[:, 1].clamp(max=0).pow(2).mean()


def smoothness_loss(pos_pred: Tensor, batch, pos_true: Optional[Tensor] = None,
                    order: int = 2) -> Tensor:
    r"""Mean squared :obj:`order`-th time difference of the predicted
    positions, or of its deviation from the target's when :obj:`pos_true`
    is given.

    Shapes:
        - **pos_pred**, **pos_true**: :math:`(N, 3)`
    """
    diff, valid = time_difference(pos_pred, batch, order)
    if pos_true is not None:
        diff = diff - time_difference(pos_true, batch, order)[0]
    return _masked_mean(diff.pow(2).sum(-1), valid)


__all__ = ["rotation_loss", "velocity_loss", "limb_velocity_loss", "carried_heights",
           "carriage_loss", "contact_loss",
           "foot_sliding_loss", "amplitude_loss", "spread_error", "stream_mean",
           "limb_end_streams", "penetration_loss", "smoothness_loss"]
