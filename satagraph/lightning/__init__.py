"""LightningModules for motion autoencoders."""
from satagraph.lightning.autoencoder import (MotionAutoencoderModule, SATARVQModule,
                                            SATAVAEModule, count_parameters, lr_factor)
from satagraph.lightning.baselines import PaddedRVQModule, SAMEModule

__all__ = ["MotionAutoencoderModule", "SATAVAEModule", "SATARVQModule", "SAMEModule", "PaddedRVQModule",
           "count_parameters", "lr_factor"]
