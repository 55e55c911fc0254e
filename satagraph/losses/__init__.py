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
``global_position``     0       MSE of global positions (the root's path
                                and yaw integrated over the window from
                                ``r``, so a biased yaw rate or speed counts
                                as the drift it causes; off by default)
``velocity``            1       MSE of per-frame global displacements
``root``                10      MSE of ``r`` (normalised when a normaliser is
                                given, as SAME; physical otherwise)
``contact``             1       BCE with logits (SAME: MSE on the contact
                                output; the decoder here predicts logits)
``foot_sliding``        6       mean of true contact x horizontal global
                                displacement per frame (SAME's ``cv``)
``stance``              0       MSE of the horizontal per-frame displacement
                                of joints in true contact relative to the root
                                (facing frame), weighted by the contact: the
                                stride, which ``foot_sliding`` leaves to the
                                root as well (not in SAME; off by default)
``amplitude``           0       MSE of every joint's standard deviation over
                                its clip, per axis, in the facing frame: the
                                swing of the limbs, which the mean squared
                                errors shrink where the phase is unsure (not
                                in SAME; off by default)
``limb_amplitude``      0       the same over the limb ends only
                                (``FrameBatch.clip_limb_ends``): the stride
                                and the feet's lift, not the wings' or the
                                tail's swing (off by default)
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
``retarget_root``       0       the root of the same cross-skeleton decoding
                                (off by default): yaw rate, ground speed in
                                heights per second and the lowest joint's
                                height over the character's, as the source's
                                (:func:`root_transfer_loss`)
``retarget_carriage``   0       the carriage of the same cross-skeleton
                                decoding (off by default): each joint's
                                height above the root, averaged over the
                                window, in the partner's heights, as the
                                partner's own clip carries it
                                (:func:`carriage_loss`)
======================  ======  ==============================================
"""
from satagraph.losses.motion_loss import DEFAULT_WEIGHTS, MotionLoss
from satagraph.losses.positions import (POSITION_SCALE, facing_positions, position_scale,
                                        time_difference, to_global)
from satagraph.losses.terms import (amplitude_loss, carriage_loss, carried_heights,
                                    contact_loss, foot_sliding_loss,
                                    limb_end_streams, limb_velocity_loss,
                                    penetration_loss, root_transfer_loss, rotation_loss,
                                    smoothness_loss, stance_loss, velocity_loss)

__all__ = ["DEFAULT_WEIGHTS", "MotionLoss", "POSITION_SCALE", "facing_positions",
           "position_scale", "time_difference", "to_global", "amplitude_loss", "carriage_loss",
           "carried_heights", "contact_loss",
           "limb_end_streams",
           "foot_sliding_loss", "limb_velocity_loss", "penetration_loss", "root_transfer_loss",
           "rotation_loss", "smoothness_loss", "stance_loss", "velocity_loss"]
