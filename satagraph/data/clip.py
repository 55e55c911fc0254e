"""A model-ready window of motion features for one skeleton."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict

import torch
from torch import Tensor


@dataclass
class MotionClip:
    r"""Motion features of one clip (or window) of one skeleton, as tensors.

    This is what datasets yield and what :func:`satagraph.data.collate_clips`
    batches. Feature layouts are described by :mod:`satagraph.data.features`.

    Args:
        dynamic (Tensor): Per-frame, per-joint features
            ``[q (6), x (3), x_rel (3), v_q (6), v_x (3), c (1)]``.
        root (Tensor): Per-frame root features ``r`` (yaw velocity, xz
            velocity in the facing frame, root height).
        static (Tensor): Per-joint static features ``[X_l (3), X_g (3)]``.
        semantic (Tensor): Per-joint semantic embedding ``X_t`` (may have
            zero columns).
        parents (Tensor): Parent index per joint, ``-1`` for the root.
        edge_attr (Tensor): (depth, reverse depth) per directed bone, in the
            order of :attr:`satagraph.Skeleton.edge_index`.
        meta (dict): Free-form information (skeleton id, dataset, source
            path, height, start frame) carried along, never batched.

    Shapes:
        - **dynamic**: :math:`(T, J, F_d)`
        - **root**: :math:`(T, 4)`
        - **static**: :math:`(J, F_s)`
        - **semantic**: :math:`(J, D_t)`
        - **parents**: :math:`(J,)`
        - **edge_attr**: :math:`(2(J-1), 2)`
    """

    dynamic: Tensor
    root: Tensor
    static: Tensor
    semantic: Tensor
    parents: Tensor
    edge_attr: Tensor
    meta: Dict[str, object] = field(default_factory=dict)

    @property
    def num_frames(self) -> int:
        return self.dynamic.shape[0]

    @property
    def num_joints(self) -> int:
        return self.dynamic.shape[1]

    @property
    def edge_index(self) -> Tensor:
        """Bones in both directions, parent -> child first, :math:`(2, 2(J-1))`."""
        child = torch.arange(1, self.num_joints)
        par = self.parents[1:].long()
        return torch.cat([torch.stack([par, child]), torch.stack([child, par])], 1)
