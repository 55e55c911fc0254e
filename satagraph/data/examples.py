"""Built-in example motions, generated procedurally (no files, no downloads)."""
from __future__ import annotations

import numpy as np
import torch

from satagraph.motion import Motion
from satagraph.ops.rotation import euler_to_matrix
from satagraph.skeleton import Skeleton

_POS = ("Xposition", "Yposition", "Zposition")
_ROT = ("Zrotation", "Xrotation", "Yrotation")

# name, parent, offset (metres, +Y up, facing +Z), end site
_BIPED = [
    ("Hips", -1, (0.0, 0.0, 0.0), False),
    ("Spine", 0, (0.0, 0.1, 0.0), False),
    ("Head", 1, (0.0, 0.55, 0.0), False),
    ("Head_end", 2, (0.0, 0.2, 0.0), True),
    ("LeftUpLeg", 0, (0.1, -0.05, 0.0), False),
    ("LeftFoot", 4, (0.0, -0.8, 0.0), False),
    ("LeftFoot_end", 5, (0.0, -0.05, 0.15), True),
    ("RightUpLeg", 0, (-0.1, -0.05, 0.0), False),
    ("RightFoot", 7, (0.0, -0.8, 0.0), False),
    ("RightFoot_end", 8, (0.0, -0.05, 0.15), True),
]
_LEG = 0.8  # hip to ankle
_HIP_HEIGHT = 0.05 + 0.05 + _LEG  # toe at y = 0 when the leg is vertical


def example_skeleton() -> Skeleton:
    r"""A small biped: hips, spine, head and two one-bone legs with feet
    (7 joints and 3 end sites), in metres, +Y up, facing +Z. The root has 6
    channels, the other joints 3 (``ZXY`` rotations, as in many BVH files).
    """
    names = [n for n, _, _, _ in _BIPED]
    end_site = np.array([e for _, _, _, e in _BIPED])
    channels = [() if e else (_POS + _ROT if p < 0 else _ROT)
                for _, p, _, e in _BIPED]
    return Skeleton(names=names, parents=np.array([p for _, p, _, _ in _BIPED]),
                    offsets=np.array([o for _, _, o, _ in _BIPED]),
                    channels=channels, end_site=end_site)


def example_motion(num_frames: int = 60, fps: float = 30.0,
                   speed: float = 1.2, stride: float = 1.1) -> Motion:
    r"""A procedurally generated walk of :func:`example_skeleton` along +Z.

    The legs swing in opposite phase, the feet stay level, the hips bob so
    that the lower foot touches the ground (y = 0), and the spine and head
    counter-rotate a little. The motion is periodic in :obj:`stride` metres.

    Args:
        num_frames (int, optional): Number of frames.
        fps (float, optional): Frames per second.
        speed (float, optional): Walking speed in metres per second.
        stride (float, optional): Length of one step cycle (two steps) in
            metres.

    Returns:
        Motion: rotations and translations, no raw channels.
    """
    skel = example_skeleton()
    time = np.arange(num_frames) / fps
    phase = 2 * np.pi * speed * time / stride
    swing = np.radians(25.0) * np.sin(phase)  # left leg; the right is -swing
    euler = np.zeros((num_frames, skel.num_joints, 3))  # ZXY, radians
    euler[:, 0, 2] = np.radians(5.0) * np.sin(phase)  # hips yaw
    euler[:, 1, 2] = -np.radians(8.0) * np.sin(phase)  # spine counter-yaw
    euler[:, 2, 2] = np.radians(3.0) * np.sin(phase)
    euler[:, 4, 1], euler[:, 5, 1] = -swing, swing  # leg forward, foot level
    euler[:, 7, 1], euler[:, 8, 1] = swing, -swing
    rot = euler_to_matrix(torch.from_numpy(euler), "ZXY").numpy()
    rot[:, skel.end_site] = np.eye(3)
    trans = np.broadcast_to(skel.offsets, (num_frames, skel.num_joints, 3)).copy()
    trans[:, 0, 1] = _HIP_HEIGHT - _LEG * (1 - np.cos(swing))
    trans[:, 0, 2] = speed * time
    return Motion(skel, rot, trans, fps=fps, source="<satagraph example walk>")
