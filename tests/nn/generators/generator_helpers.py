"""Tiny skeletons and generator networks shared by the generator tests."""
from __future__ import annotations

from typing import List, Tuple

import torch
from torch import Tensor

from satagraph.nn.generators import (MaskedTransformer, ResidualTransformer, SkeletonEmbedding,
                                     parents_to_edge_index)

#: A hand-made tree: 0 root; 1, 2 children of 0; 3 child of 1; 4 child of 3;
#: 5 child of 2; 6 child of 2.
TREE = [-1, 0, 0, 1, 3, 2, 2]
NUM_CODES, TEXT, SKEL = 16, 12, 8


def skeleton(parents: List[int], features: int = 6, seed: int = 0) -> Tuple[Tensor, Tensor]:
    """Random joint features and bones (parent -> child) of a tree."""
    gen = torch.Generator().manual_seed(seed)
    edge_index, _ = parents_to_edge_index(torch.tensor(parents))
    return torch.randn(len(parents), features, generator=gen), edge_index


def relabel(parents: List[int], perm: List[int]) -> List[int]:
    """The same tree with old joint ``perm[k]`` as new joint ``k``."""
    new_of = {old: new for new, old in enumerate(perm)}
    return [-1 if parents[old] < 0 else new_of[parents[old]] for old in perm]


def tiny_masked(**kwargs) -> MaskedTransformer:
    torch.manual_seed(0)
    args = dict(hidden_channels=32, heads=2, num_layers=2, dropout=0.0)
    return MaskedTransformer(NUM_CODES, TEXT, SKEL, **dict(args, **kwargs))


def tiny_residual(num_quantizers: int = 4, **kwargs) -> ResidualTransformer:
    torch.manual_seed(0)
    args = dict(hidden_channels=32, heads=2, num_layers=2, dropout=0.0)
    return ResidualTransformer(NUM_CODES, num_quantizers, TEXT, SKEL, **dict(args, **kwargs))


def tiny_skeleton_net(in_channels: int = 6, randomize: bool = True) -> SkeletonEmbedding:
    torch.manual_seed(0)
    net = SkeletonEmbedding(in_channels, hidden_channels=16, out_channels=SKEL, heads=2,
                            num_layers=2)
    if randomize:  # topology biases start at zero: make them matter
        torch.nn.init.normal_(net.dist_emb.weight)
        torch.nn.init.normal_(net.rel_emb.weight)
    return net
