"""Registers text-to-motion training (``module: t2m``) with
:mod:`satagraph.experiment.train`: the LightningModule and its data module."""
from satagraph.data.caption_datamodule import CaptionDataModule
from satagraph.lightning.text_to_motion import TextToMotionModule
from satagraph.experiment.train import DATAMODULES, register_module

register_module("t2m", TextToMotionModule)
DATAMODULES["t2m"] = CaptionDataModule
