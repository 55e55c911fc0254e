"""Registers text-to-motion training (``module: t2m``) with the module
registry (:mod:`satagraph.experiment.registry`): the LightningModule, its
data module and the schema of its ``data`` section (the data module's
arguments and defaults)."""
from satagraph.data.caption_datamodule import CaptionDataModule
from satagraph.experiment.registry import register_module
from satagraph.experiment.schema import signature_schema
from satagraph.lightning.text_to_motion import DEFAULT_OPTIM, TextToMotionModule

#: The ``data`` section of ``module: t2m``; ``seed`` ``None`` is the run's.
CaptionDataConfig = signature_schema(CaptionDataModule, "CaptionDataConfig", seed=None)

register_module("t2m", TextToMotionModule, datamodule=CaptionDataModule,
                data=CaptionDataConfig, optim_keys=DEFAULT_OPTIM)
