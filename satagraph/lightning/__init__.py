"""LightningModules for motion autoencoders."""
from satagraph.lightning.autoencoder import (MotionAutoencoderModule, SATARVQModule,
                                            SATAVAEModule, count_parameters, lr_factor)
from satagraph.lightning.baselines import PaddedRVQModule, SAMEModule
from satagraph.lightning.trailing_loss import TrailingLoss

__all__ = ["MotionAutoencoderModule", "SATAVAEModule", "SATARVQModule", "SAMEModule", "PaddedRVQModule",
           "TrailingLoss", "count_parameters", "lr_factor"]
