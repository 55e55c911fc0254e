"""Neural network modules, as plain :class:`torch.nn.Module` objects:

- :mod:`.layers`: modulation, local GNN convolutions, frame attention,
  spatio-temporal blocks, dropout;
- :mod:`.bottlenecks`: VAE and RVQ;
- :mod:`.autoencoders`: SATA (encoder, decoder) and the SAME and padded
  baselines;
- :mod:`.generators`: text-to-motion generators over SATA-RVQ codes.
"""
from satagraph.nn.autoencoders import (SAME, SATA, MotionAutoencoder, PaddedRVQ, SATADecoder, SATAEncoder,
                                       node_motion_features)
from satagraph.nn.bottlenecks import (RVQBottleneck, RVQOutput, VAEBottleneck, VAEOutput,
                                      gaussian_kl)
from satagraph.nn.layers import (LOCAL_CONVS, ConcatProjection, FastDropout, FrameGPSConv,
                                 LocalSpatialLayer, SemanticModulation, SinusoidalEncoding,
                                 SpatioTemporalBlock, accepts_edge_attr, build_input_layer,
                                 build_local_conv, fast_dropout, local_conv_names,
                                 make_blocks, register_local_conv, sinusoidal_positions,
                                 use_fast_dropout)

__all__ = [
    "MotionAutoencoder", "SATA", "SAME", "PaddedRVQ", "FrameGPSConv", "SATAEncoder", "SATADecoder", "SemanticModulation", "ConcatProjection",
    "SinusoidalEncoding", "SpatioTemporalBlock", "LocalSpatialLayer", "VAEBottleneck",
    "VAEOutput", "RVQBottleneck", "RVQOutput", "build_local_conv", "accepts_edge_attr",
    "build_input_layer", "make_blocks", "sinusoidal_positions", "node_motion_features",
    "gaussian_kl", "LOCAL_CONVS", "FastDropout", "fast_dropout", "use_fast_dropout",
    "register_local_conv", "local_conv_names",
]
