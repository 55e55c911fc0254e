"""Neural network modules: SATA (modulation, spatio-temporal blocks, encoder,
decoder, VAE / RVQ bottlenecks) and the local GNN factory."""
from satagraph.nn.bottleneck_rvq import RVQBottleneck, RVQOutput
from satagraph.nn.bottleneck_vae import VAEBottleneck, VAEOutput, gaussian_kl
from satagraph.nn.decoder import SATADecoder
from satagraph.nn.dropout import FastDropout, fast_dropout, use_fast_dropout
from satagraph.nn.encoder import SATAEncoder, node_motion_features
from satagraph.nn.local_conv import LOCAL_CONVS, accepts_edge_attr, build_local_conv
from satagraph.nn.modulation import (ConcatProjection, SemanticModulation,
                                     SinusoidalEncoding, build_input_layer)
from satagraph.nn.frame_gps import FrameGPSConv
from satagraph.nn.padded import PaddedRVQ
from satagraph.nn.same import SAME
from satagraph.nn.sata import SATA
from satagraph.nn.spatio_temporal import (LocalSpatialLayer, SpatioTemporalBlock,
                                          make_blocks, sinusoidal_positions)

__all__ = [
    "SATA", "SAME", "PaddedRVQ", "FrameGPSConv", "SATAEncoder", "SATADecoder", "SemanticModulation", "ConcatProjection",
    "SinusoidalEncoding", "SpatioTemporalBlock", "LocalSpatialLayer", "VAEBottleneck",
    "VAEOutput", "RVQBottleneck", "RVQOutput", "build_local_conv", "accepts_edge_attr",
    "build_input_layer", "make_blocks", "sinusoidal_positions", "node_motion_features",
    "gaussian_kl", "LOCAL_CONVS", "FastDropout", "fast_dropout", "use_fast_dropout",
]
