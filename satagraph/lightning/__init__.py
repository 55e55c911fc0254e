"""LightningModules for motion autoencoders."""
from satagraph.lightning.autoencoder import (MotionAutoencoderModule, SATARVQModule,
                                            SATAVAEModule, count_parameters, lr_factor)

__all__ = ["MotionAutoencoderModule", "SATAVAEModule", "SATARVQModule",
           "count_parameters", "lr_factor"]
