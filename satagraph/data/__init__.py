"""Model-ready motion: features, normalisation, frame graphs, datasets and
batching of motion clips (imported lazily, so that numpy-only submodules
load without torch)."""
from satagraph._lazy import lazy_exports

_FEATURES = ("MotionFeatures", "motion_to_features", "features_to_motion")
_EXPORTS = {**dict.fromkeys(_FEATURES, "satagraph.data.features"),
            "MotionClip": "satagraph.data.clip",
            "FrameBatch": "satagraph.data.collate",
            "collate_clips": "satagraph.data.collate",
            "ClipLoader": "satagraph.data.loader",
            "FrameGraph": "satagraph.data.frame_graph",
            "FeatureNormalizer": "satagraph.data.normalizer",
            "MotionDataset": "satagraph.data.dataset",
            "MotionDataModule": "satagraph.data.datamodule",
            "CaptionDataModule": "satagraph.data.caption_datamodule",
            "register_window_transform": "satagraph.data.window_transform"}
__all__ = ["MotionClip", "FrameGraph", "FrameBatch", "collate_clips", "ClipLoader",
           "FeatureNormalizer", "MotionDataset", "MotionDataModule", "CaptionDataModule",
           "register_window_transform", *_FEATURES]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
