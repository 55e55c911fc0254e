"""Registers text-to-motion training (``module: t2m``) with
:mod:`satagraph.train`: the LightningModule and its data module."""
from satagraph.datasets.datamodule import CaptionDataModule
from satagraph.lightning.text_to_motion import TextToMotionModule
from satagraph.train import DATAMODULES, register_module

register_module("t2m", TextToMotionModule)
DATAMODULES["t2m"] = CaptionDataModule
