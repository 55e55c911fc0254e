"""Layers of the autoencoders and generators: semantic modulation, local
GNN convolutions, frame attention (GPS), spatio-temporal blocks and a fast
dropout."""
from satagraph.nn.layers.dropout import FastDropout, fast_dropout, use_fast_dropout
from satagraph.nn.layers.frame_gps import FrameGPSConv
from satagraph.nn.layers.local_conv import (LOCAL_CONVS, accepts_edge_attr, build_local_conv,
                                            local_conv_names, register_local_conv)
from satagraph.nn.layers.modulation import (ConcatProjection, SemanticModulation,
                                            SinusoidalEncoding, build_input_layer)
from satagraph.nn.layers.spatio_temporal import (LocalSpatialLayer, SpatioTemporalBlock,
                                                 make_blocks, sinusoidal_positions)

__all__ = ["FastDropout", "fast_dropout", "use_fast_dropout", "FrameGPSConv",
           "LOCAL_CONVS", "accepts_edge_attr", "build_local_conv", "local_conv_names",
           "register_local_conv", "ConcatProjection",
           "SemanticModulation", "SinusoidalEncoding", "build_input_layer",
           "LocalSpatialLayer", "SpatioTemporalBlock", "make_blocks",
           "sinusoidal_positions"]
