"""Evaluation metrics, per clip of a batch of frame graphs: the motion
metrics of SAME (:mod:`.motion`: JR, RT, JP, FS, GP and the retarget
error) and the text-to-motion generation metrics (:mod:`.generation`:
R-precision, matching score, FID, KID, diversity, multimodality)."""
from satagraph.metrics.generation import (POOL_SIZE, diversity, fid, kid, matching_score,
                                          multimodality, r_precision)
from satagraph.metrics.motion import (SLIDE_HEIGHT, foot_sliding, ground_penetration,
                                      joint_position_error, joint_rotation_error,
                                      motion_metrics, retarget_error,
                                      root_trajectory_error)

__all__ = ["POOL_SIZE", "diversity", "fid", "kid", "matching_score", "multimodality",
           "r_precision", "SLIDE_HEIGHT", "foot_sliding", "ground_penetration",
           "joint_position_error", "joint_rotation_error", "motion_metrics",
           "retarget_error", "root_trajectory_error"]
