"""LightningModules for motion autoencoders."""
from satagraph.lightning.autoencoder import (MotionAutoencoderModule, SATARVQModule,
                                            SATAVAEModule, count_parameters, lr_factor)
from satagraph.lightning.baselines import PaddedRVQModule, SAMEModule
from satagraph.lightning.trailing_loss import TrailingLoss

__all__ = ["MotionAutoencoderModule", "SATAVAEModule", "SATARVQModule", "SAMEModule", "PaddedRVQModule",
           "TrailingLoss", "TextToMotionModule", "count_parameters", "lr_factor"]


def __getattr__(name: str):
    """``TextToMotionModule`` on first use: it imports the text encoders."""
    if name == "TextToMotionModule":
        from satagraph.lightning.text_to_motion import TextToMotionModule
        return TextToMotionModule
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
