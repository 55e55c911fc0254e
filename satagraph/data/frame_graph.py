"""One frame of one motion clip as a PyG graph."""
from __future__ import annotations

from typing import Any, Optional

import torch
from torch import Tensor
from torch_geometric.data import Data

from satagraph.data.clip import MotionClip

# Custom keys: how they are concatenated and incremented when batching.
_CAT_DIM = {"root": 0, "root_node": 0, "node_depth": 0, "frame_time": 0}
_INC_NODES = {"root_node"}


class FrameGraph(Data):
    r"""One frame of one clip: joints are nodes, bones are undirected edges
    (both directions, parent -> child first) carrying (depth, reverse depth)
    of their child joint.

    :class:`~torch_geometric.data.Batch` of frame graphs is correct for every
    key: :obj:`root_node` is incremented by the number of nodes, the other
    custom keys are not (none of them contains ``"index"`` or ``"batch"``).
    :func:`~satagraph.data.collate_clips` builds the same batch (plus
    per-stream and per-clip context) without materialising frame graphs.

    Args:
        x (Tensor, optional): Dynamic node features.
        edge_index (Tensor, optional): Bones, both directions.
        edge_attr (Tensor, optional): (depth, reverse depth) per bone.
        root (Tensor, optional): Root features ``r`` of the frame.
        root_node (Tensor, optional): Node index of the root joint.
        node_depth (Tensor, optional): Number of bones to the root.
        frame_time (Tensor, optional): Frame index within its clip.
        **kwargs (optional): Further attributes.

    Shapes:
        - **x**: :math:`(J, F_d)`
        - **edge_index**: :math:`(2, 2(J-1))`
        - **edge_attr**: :math:`(2(J-1), 2)`
        - **root**: :math:`(1, 4)`
        - **root_node**: :math:`(1,)`
        - **node_depth**: :math:`(J,)`
        - **frame_time**: :math:`(1,)`
    """

    def __init__(self, x: Optional[Tensor] = None,
                 edge_index: Optional[Tensor] = None,
                 edge_attr: Optional[Tensor] = None,
                 root: Optional[Tensor] = None,
                 root_node: Optional[Tensor] = None,
                 node_depth: Optional[Tensor] = None,
                 frame_time: Optional[Tensor] = None, **kwargs: Any) -> None:
        super().__init__(x=x, edge_index=edge_index, edge_attr=edge_attr,
                         root=root, root_node=root_node, node_depth=node_depth,
                         frame_time=frame_time, **kwargs)

    def __inc__(self, key: str, value: Any, *args: Any, **kwargs: Any) -> Any:
        if key in _INC_NODES:
            return self.num_nodes
        if key in _CAT_DIM:
            return 0
        return super().__inc__(key, value, *args, **kwargs)

    def __cat_dim__(self, key: str, value: Any, *args: Any, **kwargs: Any) -> Any:
        if key in _CAT_DIM:
            return _CAT_DIM[key]
        return super().__cat_dim__(key, value, *args, **kwargs)

    @classmethod
    def from_clip(cls, clip: MotionClip, t: int) -> "FrameGraph":
        r"""Frame :obj:`t` of :obj:`clip` (joint 0 is the root)."""
        return cls(x=clip.dynamic[t], edge_index=clip.edge_index,
                   edge_attr=clip.edge_attr, root=clip.root[t:t + 1],
                   root_node=torch.zeros(1, dtype=torch.long),
                   node_depth=joint_depth(clip.parents),
                   frame_time=torch.tensor([t]))


def joint_depth(parents: Tensor) -> Tensor:
    r"""Number of bones between every joint and the root (parents before
    children, ``-1`` for the root).

    Shapes:
        - **parents**: :math:`(J,)`
        - **output**: :math:`(J,)`
    """
    depth = [0] * parents.numel()
    for j, p in enumerate(parents.tolist()):
        depth[j] = depth[p] + 1 if p >= 0 else 0
    return torch.tensor(depth, dtype=torch.long)
