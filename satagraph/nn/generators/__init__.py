r"""Generator networks for text-to-motion on any skeleton (issue 19), as
plain :class:`torch.nn.Module` objects over SATA-RVQ codes:

- :class:`SkeletonEmbedding`: :math:`f_{skel}` of a skeleton (OmniZoo 4.2.1);
- :class:`MaskedTransformer`: layer-0 codes by masked modelling (MoMask);
- :class:`ResidualTransformer`: RVQ layers :math:`1..Q-1` (MoMask);
- :class:`LengthModel`: a duration distribution when no length is given;
- helpers for topology tables, code sequences and the token rate.

Generation end to end (the lead's pipeline wires the pieces)::

    f_skel = skel_net(*skeleton_graph(frames))              # [B, D_s]
    base = masked.generate(text_emb, f_skel, num_frames, generator=g)
    codes = residual.generate(base, text_emb, f_skel, num_frames, generator=g)
    z = sata.bottleneck.decode_codes(merge_codes(codes, num_frames))
"""
from satagraph.nn.generators.codes import (code_run_lengths, length_mask, merge_codes,
                                           pool_codes, split_codes, token_lengths,
                                           unpool_codes)
from satagraph.nn.generators.length_model import LengthModel
from satagraph.nn.generators.masked_transformer import MaskedLoss, MaskedTransformer
from satagraph.nn.generators.residual_transformer import ResidualLoss, ResidualTransformer
from satagraph.nn.generators.sampling import (GUIDES, corrupt_tokens, cosine_schedule,
                                              draw_logits, guided, guided_candidates,
                                              mask_ratio, random_mask,
                                              residual_layer_schedule, sample_logits,
                                              top_k_filter)
from satagraph.nn.generators.skeleton_embedding import (SkeletonEmbedding, SkeletonGraph,
                                                        TopologyAttentionLayer,
                                                        skeleton_graph)
from satagraph.nn.generators.skeleton_topology import (NUM_RELATIONS, SkeletonTopology,
                                                       parents_to_edge_index,
                                                       skeleton_topology, stack_topologies)
from satagraph.nn.generators.token_transformer import (ConditionTokens, TokenTransformer,
                                                       masked_cross_entropy)

__all__ = [
    "SkeletonEmbedding", "SkeletonGraph", "TopologyAttentionLayer", "skeleton_graph",
    "SkeletonTopology", "skeleton_topology", "stack_topologies", "parents_to_edge_index", "NUM_RELATIONS",
    "MaskedTransformer", "MaskedLoss", "ResidualTransformer", "ResidualLoss", "LengthModel",
    "ConditionTokens", "TokenTransformer", "masked_cross_entropy",
    "split_codes", "merge_codes", "pool_codes", "unpool_codes", "token_lengths",
    "length_mask", "code_run_lengths",
    "cosine_schedule", "mask_ratio", "random_mask", "corrupt_tokens", "top_k_filter",
    "sample_logits", "residual_layer_schedule", "guided", "guided_candidates", "draw_logits",
    "GUIDES",
]
