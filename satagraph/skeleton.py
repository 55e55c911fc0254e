"""Kinematic skeleton: joints, hierarchy, rest offsets and channel layout."""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import List, Optional, Sequence, Tuple

import numpy as np

# Relation types between two joints (row i, column j), as in AnyTop/OmniZoo.
REL_SELF = 0
REL_PARENT = 1  # j is the parent of i
REL_CHILD = 2  # j is a child of i
REL_SIBLING = 3  # i and j share a parent
REL_NONE = 4
REL_END_EFFECTOR = 5  # written on the diagonal for leaves


@dataclass(frozen=True, eq=False)
class Skeleton:
    r"""A tree of joints, stored in topological order (parents before children).

    End sites of a BVH file are kept as leaf joints (``end_site[j] = True``)
    with their offsets and no channels.

    Args:
        names (list[str]): Unique joint names.
        parents (np.ndarray): Parent index per joint, ``-1`` for the root.
        offsets (np.ndarray): Rest offset of each joint from its parent, in
            the file's units.
        channels (list[tuple[str, ...]]): BVH channel names per joint, e.g.
            ``("Xposition", "Yposition", "Zposition", "Zrotation", ...)``.
        end_site (np.ndarray, optional): Leaf flags for BVH end sites.

    Shapes:
        - **parents**: :math:`(J,)`
        - **offsets**: :math:`(J, 3)`
    """

    names: List[str]
    parents: np.ndarray
    offsets: np.ndarray
    channels: List[Tuple[str, ...]] = field(default_factory=list)
    end_site: Optional[np.ndarray] = None

    def __post_init__(self) -> None:
        parents = np.asarray(self.parents, dtype=np.int64)
        offsets = np.asarray(self.offsets, dtype=np.float64).reshape(-1, 3)
        num = len(self.names)
        if parents.shape != (num,) or offsets.shape != (num, 3):
            raise ValueError(
                f"Skeleton: {num} names but parents {parents.shape} and "
                f"offsets {offsets.shape}")
        if num == 0 or parents[0] != -1 or (parents[1:] < 0).any():
            raise ValueError("Skeleton: joint 0 must be the only root (-1)")
        if (parents[1:] >= np.arange(1, num)).any():
            raise ValueError("Skeleton: parents must come before children")
        if len(set(self.names)) != num:
            raise ValueError("Skeleton: joint names must be unique")
        channels = list(self.channels) or [()] * num
        end_site = (np.zeros(num, dtype=bool) if self.end_site is None else
                    np.asarray(self.end_site, dtype=bool))
        object.__setattr__(self, "parents", parents)
        object.__setattr__(self, "offsets", offsets)
        object.__setattr__(self, "channels", [tuple(c) for c in channels])
        object.__setattr__(self, "end_site", end_site)

    # ------------------------------------------------------------------ basic
    @property
    def num_joints(self) -> int:
        """Number of joints, end sites included."""
        return len(self.names)

    def __len__(self) -> int:
        return self.num_joints

    def describe(self) -> str:
        """``"31-joint skeleton (and 7 end sites)"``: the joints a file's
        tool counts, its end sites apart."""
        ends = int(np.count_nonzero(self.end_site))
        tail = f" (and {ends} end site{'s' if ends != 1 else ''})" if ends else ""
        return f"{self.num_joints - ends}-joint skeleton{tail}"

    def __repr__(self) -> str:
        return (f"Skeleton(joints={self.num_joints}, "
                f"end_sites={int(self.end_site.sum())}, root={self.names[0]!r})")

    def index(self, name: str) -> int:
        """Index of the joint called :obj:`name`."""
        try:
            return self.names.index(name)
        except ValueError:
            raise KeyError(f"no joint named {name!r}") from None

    def replace(self, **changes) -> "Skeleton":
        """A copy with some fields replaced."""
        return replace(self, **changes)

    @cached_property
    def children(self) -> List[List[int]]:
        """Child indices per joint."""
        out: List[List[int]] = [[] for _ in range(self.num_joints)]
        for j, p in enumerate(self.parents[1:], start=1):
            out[p].append(j)
        return out

    def subtree(self, joint: int) -> np.ndarray:
        """:obj:`joint` and all its descendants, in joint order."""
        inside = np.zeros(self.num_joints, dtype=bool)
        inside[joint] = True
        for j in range(int(joint) + 1, self.num_joints):
            inside[j] = inside[self.parents[j]]
        return np.flatnonzero(inside)

    @cached_property
    def is_leaf(self) -> np.ndarray:
        """``True`` for joints without children."""
        leaf = np.ones(self.num_joints, dtype=bool)
        leaf[self.parents[1:]] = False
        return leaf

    @cached_property
    def rotation_orders(self) -> List[str]:
        """Euler order per joint (e.g. ``"ZXY"``), ``""`` for joints without
        rotation channels."""
        return [
            "".join(c[0].upper() for c in ch if c.lower().endswith("rotation"))
            for ch in self.channels
        ]

    @cached_property
    def has_position_channels(self) -> np.ndarray:
        """``True`` for joints with position channels."""
        return np.array([
            any(c.lower().endswith("position") for c in ch)
            for ch in self.channels
        ], dtype=bool)

    @property
    def num_channels(self) -> int:
        """Number of BVH channels per frame."""
        return sum(len(c) for c in self.channels)

    # -------------------------------------------------------------- topology
    @cached_property
    def depth(self) -> np.ndarray:
        """Number of bones between each joint and the root."""
        depth = np.zeros(self.num_joints, dtype=np.int64)
        for j in range(1, self.num_joints):
            depth[j] = depth[self.parents[j]] + 1
        return depth

    @cached_property
    def reverse_depth(self) -> np.ndarray:
        """Number of bones to the deepest leaf below each joint."""
        rev = np.zeros(self.num_joints, dtype=np.int64)
        for j in range(self.num_joints - 1, 0, -1):
            p = self.parents[j]
            rev[p] = max(rev[p], rev[j] + 1)
        return rev

    @cached_property
    def hop_distance(self) -> np.ndarray:
        """Number of bones on the tree path between every pair of joints.

        Shapes:
            - **output**: :math:`(J, J)`
        """
        num = self.num_joints
        # Ancestor-or-self matrix: anc[i, k] = 1 if k is on i's root path.
        anc = np.zeros((num, num), dtype=bool)
        for j in range(num):
            p = self.parents[j]
            if p >= 0:
                anc[j] = anc[p]
            anc[j, j] = True
        depth = self.depth
        common = anc.astype(np.int64) @ anc.T.astype(np.int64)  # shared ancestors
        lca_depth = common - 1
        return depth[:, None] + depth[None, :] - 2 * lca_depth

    @cached_property
    def relation_types(self) -> np.ndarray:
        """Relation of joint ``j`` to joint ``i`` at ``[i, j]``: self (0),
        parent (1), child (2), sibling (3), none (4), end effector (5, on the
        diagonal for leaves).

        Shapes:
            - **output**: :math:`(J, J)`
        """
        num = self.num_joints
        rel = np.full((num, num), REL_NONE, dtype=np.int64)
        par = self.parents
        same_parent = (par[:, None] == par[None, :]) & (par[:, None] >= 0)
        rel[same_parent] = REL_SIBLING
        child = np.arange(1, num)
        rel[child, par[1:]] = REL_PARENT
        rel[par[1:], child] = REL_CHILD
        diag = np.where(self.is_leaf, REL_END_EFFECTOR, REL_SELF)
        rel[np.arange(num), np.arange(num)] = diag
        return rel

    @cached_property
    def edge_index(self) -> np.ndarray:
        """Bones as undirected edges (both directions), parent -> child first.

        Shapes:
            - **output**: :math:`(2, 2(J-1))`
        """
        child = np.arange(1, self.num_joints)
        par = self.parents[1:]
        return np.concatenate(
            [np.stack([par, child]), np.stack([child, par])], axis=1)

    @cached_property
    def edge_attr(self) -> np.ndarray:
        """(depth, reverse depth) of each edge's child joint.

        Shapes:
            - **output**: :math:`(2(J-1), 2)`
        """
        child = np.arange(1, self.num_joints)
        feat = np.stack([self.depth[child], self.reverse_depth[child]], axis=1)
        return np.concatenate([feat, feat], axis=0).astype(np.float32)

    # ------------------------------------------------------------------ rest
    def rest_positions(self) -> np.ndarray:
        """Joint positions of the rest pose (offsets only, no rotation),
        relative to the root.

        Shapes:
            - **output**: :math:`(J, 3)`
        """
        pos = np.zeros((self.num_joints, 3))
        for j in range(1, self.num_joints):
            pos[j] = pos[self.parents[j]] + self.offsets[j]
        return pos

    def subset(self, keep: Sequence[int]) -> "Skeleton":
        """Skeleton restricted to the joints in :obj:`keep` (sorted indices,
        closed under taking parents except for the new root)."""
        keep = list(keep)
        remap = {old: new for new, old in enumerate(keep)}
        parents = [remap.get(int(self.parents[j]), -1) for j in keep]
        return Skeleton(
            names=[self.names[j] for j in keep],
            parents=np.array(parents),
            offsets=self.offsets[keep],
            channels=[self.channels[j] for j in keep],
            end_site=self.end_site[keep],
        )
