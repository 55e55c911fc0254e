"""Evaluation metrics, per clip of a batch of frame graphs: the motion
metrics of SAME (:mod:`.motion`: JR, RT, JP, FS, GP and the retarget
error). Later: generation metrics."""
from satagraph.metrics.motion import (SLIDE_HEIGHT, foot_sliding, ground_penetration,
                                      joint_position_error, joint_rotation_error,
                                      motion_metrics, retarget_error,
                                      root_trajectory_error)

__all__ = ["SLIDE_HEIGHT", "foot_sliding", "ground_penetration", "joint_position_error",
           "joint_rotation_error", "motion_metrics", "retarget_error",
           "root_trajectory_error"]
