"""Differentiable operators: rotations, forward kinematics, temporal streams."""
from satagraph.ops.fk import fk_levels, forward_kinematics, forward_kinematics_numpy
from satagraph.ops.rotation import (
    axis_angle_matrix,
    euler_to_matrix,
    euler_to_quaternion,
    geodesic_angle,
    matrix_to_euler,
    matrix_to_quaternion,
    matrix_to_rotation_6d,
    quaternion_slerp,
    quaternion_to_euler,
    quaternion_to_matrix,
    rotation_6d_to_matrix,
    yaw_matrix,
)
from satagraph.ops.temporal import from_temporal_streams, to_temporal_streams

__all__ = [
    "fk_levels", "forward_kinematics", "forward_kinematics_numpy", "axis_angle_matrix", "euler_to_matrix",
    "euler_to_quaternion", "geodesic_angle", "matrix_to_euler",
    "matrix_to_quaternion", "matrix_to_rotation_6d", "quaternion_slerp",
    "quaternion_to_euler", "quaternion_to_matrix", "rotation_6d_to_matrix",
    "yaw_matrix", "to_temporal_streams", "from_temporal_streams",
]
