"""Differentiable operators: rotations, forward kinematics and temporal
streams (imported lazily: the numpy forward kinematics loads without
torch). The index structure of a frame-graph batch (clip of each node, the
same joint one frame earlier, inner joints, clip heights) is collated with
it: see :class:`~satagraph.data.collate.FrameBatch`."""
from satagraph._lazy import lazy_exports

_FK = ("fk_levels", "forward_kinematics", "forward_kinematics_numpy")
_ROTATION = (
    "axis_angle_matrix", "euler_to_matrix", "euler_to_quaternion", "geodesic_angle",
    "matrix_to_euler", "matrix_to_quaternion", "matrix_to_rotation_6d",
    "quaternion_slerp", "quaternion_to_euler", "quaternion_to_matrix",
    "rotation_6d_to_matrix", "unit_quaternion_to_euler", "yaw_matrix")
_ROTATION_NUMPY = ("axis_angle_matrix_numpy", "matrix_to_quaternion_numpy",
                   "quaternion_to_matrix_numpy", "yaw_matrix_numpy", "yaw_of")
_TEMPORAL = ("to_temporal_streams", "from_temporal_streams")
_EXPORTS = {**dict.fromkeys(_FK, "satagraph.ops.fk"),
            **dict.fromkeys(_ROTATION, "satagraph.ops.rotation"),
            **dict.fromkeys(_ROTATION_NUMPY, "satagraph.ops.rotation_numpy"),
            **dict.fromkeys(_TEMPORAL, "satagraph.ops.temporal")}
__all__ = [*_FK, *_ROTATION, *_ROTATION_NUMPY, *_TEMPORAL]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
