r"""Training losses of the motion autoencoders (SAME's terms, SATA paper
section 3.4), on a :class:`~satagraph.data.FrameBatch`.

Inputs are PHYSICAL (unnormalised) features: predicted ``q`` (6D local
rotations, the root's relative to its facing frame), ``r`` (yaw velocity,
xz velocity in the facing frame, root height; per second) and contact
logits ``c``; targets come from the batch (``x``, ``root``). Positions come
from forward kinematics with each joint's rest offset ``X_l`` and the root
at ``(0, h, 0)`` in the facing frame :math:`F_t`; global positions apply
:math:`F_t` (root yaw and ground origin integrated from ``r`` within each
clip).

Units. Positions are divided by the character height (``meta["height"]``
of each clip, 1 if missing) and multiplied by :obj:`position_scale` = 175,
i.e. every character is measured in "centimetres of a 1.75 m human". This
makes the position terms independent of the species' size and lets SAME's
weights (which are in cm for humans) apply unchanged.

Terms and default weights (:data:`DEFAULT_WEIGHTS`), after SAME's
``config/mycfg.yml`` (see ``ANCHORS.md`` 1.5) unless noted:

======================  ======  ==============================================
term                    weight  definition
======================  ======  ==============================================
``rotation``            5       MSE of rotation matrices, joints with children
``position``            0.01    MSE of positions in the facing frame
``velocity``            1       MSE of per-frame global displacements
``root``                10      MSE of ``r`` (normalised when a normaliser is
                                given, as SAME; physical otherwise)
``contact``             1       BCE with logits (SAME: MSE on the contact
                                output; the decoder here predicts logits)
``foot_sliding``        6       mean of true contact x horizontal global
                                displacement per frame (SAME's ``cv``)
``penetration``         0.1     mean of ``min(y, 0)^2`` of predicted positions
``smoothness``          0.015   mean squared norm of the deviation of the
                                second time differences of global positions
                                from the target's. SAME penalises the
                                predicted third difference itself with 0.2 on
                                ``(|d3 p| * 30^3 * 1e-5)^2``, i.e. 0.2 * 0.27^2
                                = 0.015 on ``|d3 p|^2`` per frame: the same
                                coefficient is used here
                                (``smooth_match_target=False`` and
                                ``smooth_order=3`` give SAME's term)
``kl``                  1e-4    KL of the VAE bottleneck (no value in the
                                papers; a small beta as in motion VAEs)
``commit``              0.02    RVQ commitment loss (MoMask's weight)
``retarget``            0       unpaired cross-skeleton term (off by default):
                                each clip's latents are also decoded onto
                                another skeleton of the batch, and the limb
                                ends' velocities relative to the root (in
                                heights per frame, x 175) must match the
                                source's (:func:`limb_velocity_loss`; the
                                end-effector loss of Aberman et al.'s
                                skeleton-aware networks across species).
                                Computed by the LightningModule, which holds
                                the decoder
======================  ======  ==============================================
"""
from __future__ import annotations

from typing import Dict, Optional, Tuple

import torch
import torch.nn.functional as F
from torch import Tensor, nn

from satagraph.typing import DYNAMIC_LAYOUT
from satagraph.ops.fk import fk_levels, forward_kinematics
from satagraph.ops.motion_batch import integrate_root_batch
from satagraph.ops.rotation import rotation_6d_to_matrix, yaw_matrix

DEFAULT_WEIGHTS: Dict[str, float] = {
    "rotation": 5.0, "position": 0.01, "velocity": 1.0, "root": 10.0, "contact": 1.0,
    "foot_sliding": 6.0, "penetration": 0.1, "smoothness": 0.015, "kl": 1e-4,
    "commit": 0.02, "retarget": 0.0,
}
#: Units per character height of the position terms (SAME's cm, 1.75 m human).
POSITION_SCALE = 175.0


def _masked_mean(value: Tensor, mask: Tensor) -> Tensor:
    """Mean of ``value`` rows where ``mask`` (zero when nothing is selected)."""
    value = value.reshape(mask.shape[0], -1)[mask]
    return value.mean() if value.numel() else value.sum()


def inner_joints(batch) -> Tensor:
    """Nodes with at least one child, :math:`(N,)` bool."""
    mask = torch.zeros(batch.num_nodes, dtype=torch.bool, device=batch.node_parent.device)
    mask[batch.node_parent[batch.node_parent >= 0]] = True
    return mask


def rotation_loss(q_pred: Tensor, q_true: Tensor, batch) -> Tensor:
    r"""MSE of rotation matrices (from 6D) over joints with children.

    Shapes:
        - **q_pred**, **q_true**: :math:`(N, 6)`
    """
    diff = rotation_6d_to_matrix(q_pred) - rotation_6d_to_matrix(q_true)
    return _masked_mean(diff.pow(2), inner_joints(batch))


def facing_positions(q: Tensor, r: Tensor, batch) -> Tensor:
    r"""Joint positions in each frame's facing frame by forward kinematics
    (rest offsets ``X_l``, root at ``(0, h, 0)``), physical units.

    Shapes:
        - **q**: :math:`(N, 6)`, **r**: :math:`(G, 4)`
        - **output**: :math:`(N, 3)`
    """
    offsets = batch.joint_static[batch.node_stream, :3].to(q.dtype)
    height = F.pad(r[:, 3:4], (1, 1))  # (0, h, 0)
    offsets = offsets.index_copy(0, batch.root_node, height.to(q.dtype))
    levels = fk_levels(batch.node_parent, batch.node_depth)
    return forward_kinematics(rotation_6d_to_matrix(q), offsets, batch.node_parent,
                              levels)[1]


def to_global(pos: Tensor, r: Tensor, batch, fps: Optional[float] = None) -> Tensor:
    r"""Facing-frame positions to global ones: :math:`F_t` (yaw and ground
    origin integrated from ``r`` at :obj:`fps`, by default the batch's;
    every clip starting at the origin).

    Shapes:
        - **pos**: :math:`(N, 3)`, **r**: :math:`(G, 4)`
        - **output**: :math:`(N, 3)`
    """
    fps = batch.fps if fps is None else fps
    theta, origin = integrate_root_batch(r, batch.clip_num_frames, fps)
    frame = batch.batch
    return (yaw_matrix(theta)[frame] @ pos[..., None])[..., 0] + origin[frame]


def position_scale(batch, scale: float = POSITION_SCALE) -> Tensor:
    """Factor per node turning physical lengths into :obj:`scale` units per
    character height, :math:`(N, 1)`."""
    return (scale / batch.clip_height)[batch.node_clip][:, None]


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


def penetration_loss(pos_pred: Tensor) -> Tensor:
    r"""Mean of :math:`\min(y, 0)^2` (the ground is at :math:`y = 0`).

    Shapes:
        - **pos_pred**: :math:`(N, 3)`
    """
    return pos_pred[:, 1].clamp(max=0).pow(2).mean()


def time_difference(pos: Tensor, batch, order: int = 2) -> Tuple[Tensor, Tensor]:
    r"""Finite difference of :obj:`order` over time within each clip, and
    the nodes where it is defined (``node_time >= order``).

    Shapes:
        - **pos**: :math:`(N, F)`
        - **output**: :math:`(N, F)` and :math:`(N,)` bool
    """
    prev = batch.node_prev
    diff = pos
    for _ in range(order):  # loop over the order (2 or 3), not over frames
        diff = diff - diff[prev]
    return diff, batch.node_time >= order


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


class MotionLoss(nn.Module):
    r"""Weighted sum of the motion losses (see the module docstring).

    Args:
        weights (dict, optional): Weights by term name (overrides).
        position_scale (float, optional): Units per character height of the
            position terms.
        smooth_order (int, optional): Order of the smoothness differences.
        smooth_match_target (bool, optional): Penalise the difference to the
            target's time differences (``False``: the predicted ones, SAME).
        **kwargs (float): Weights by term name, e.g. ``rotation=5.0``.

    Call with ``(out, batch, normalizer=None, fps=None)`` (``fps``: the
    batch's frame rate unless given): :obj:`out` holds
    physical ``q`` :math:`(N, 6)`, ``r`` :math:`(G, 4)`, contact logits
    ``c`` :math:`(N, 1)`, optionally ``r_norm`` (normalised ``r``, used for
    the root term with :obj:`normalizer`, as SAME), ``kl`` and ``commit``.
    Returns every term (unweighted) and their weighted sum under ``"loss"``.
    """

    def __init__(self, weights: Optional[Dict[str, float]] = None,
                 position_scale: float = POSITION_SCALE, smooth_order: int = 2,
                 smooth_match_target: bool = True, **kwargs: float) -> None:
        super().__init__()
        self.weights = dict(DEFAULT_WEIGHTS, **(weights or {}), **kwargs)
        unknown = set(self.weights) - set(DEFAULT_WEIGHTS)
        if unknown:
            raise ValueError(f"MotionLoss: unknown terms {sorted(unknown)}; "
                             f"known: {sorted(DEFAULT_WEIGHTS)}")
        self.position_scale, self.smooth_order = position_scale, smooth_order
        self.smooth_match_target = smooth_match_target

    def _root(self, out: Dict[str, Tensor], batch, normalizer) -> Tensor:
        if normalizer is not None and "r_norm" in out:
            return F.mse_loss(out["r_norm"], normalizer.normalize(
                batch.root, "root", batch.heights("frame")))
        return F.mse_loss(out["r"], batch.root.to(out["r"].dtype))

    def _positions(self, q: Tensor, r: Tensor, batch, fps: Optional[float]):
        scale = position_scale(batch, self.position_scale)
        local = facing_positions(q, r, batch)
        return local * scale, to_global(local, r, batch, fps) * scale

    def terms(self, out: Dict[str, Tensor], batch, normalizer=None,
              fps: Optional[float] = None) -> Dict[str, Tensor]:
        """Every unweighted term."""
        q_true = batch.x[:, DYNAMIC_LAYOUT["q"]].to(out["q"].dtype)
        c_true = batch.x[:, DYNAMIC_LAYOUT["c"]]
        local_p, glob_p = self._positions(out["q"], out["r"], batch, fps)
        local_t, glob_t = self._positions(q_true, batch.root.to(out["r"].dtype), batch, fps)
        smooth_ref = glob_t if self.smooth_match_target else None
        terms = {
            "rotation": rotation_loss(out["q"], q_true, batch),
            "position": F.mse_loss(local_p, local_t),
            "velocity": velocity_loss(glob_p, glob_t, batch),
            "root": self._root(out, batch, normalizer),
            "contact": contact_loss(out["c"], c_true),
            "foot_sliding": foot_sliding_loss(glob_p, c_true, batch),
            "penetration": penetration_loss(local_p),
            "smoothness": smoothness_loss(glob_p, batch, smooth_ref, self.smooth_order),
        }
        terms.update({k: out[k] for k in ("kl", "commit") if k in out})
        return terms

    def forward(self, out: Dict[str, Tensor], batch, normalizer=None,
                fps: Optional[float] = None) -> Dict[str, Tensor]:
        terms = self.terms(out, batch, normalizer, fps)
        terms["loss"] = sum(self.weights[k] * v for k, v in terms.items())
        return terms
