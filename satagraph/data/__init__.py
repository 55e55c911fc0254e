"""Model-ready motion: features, normalisation, frame graphs, datasets and
batching of motion clips (imported lazily, so that numpy-only submodules
load without torch)."""
from satagraph._lazy import lazy_exports

_FEATURES = ("MotionFeatures", "motion_to_features", "features_to_motion")
_EXPORTS = {**dict.fromkeys(_FEATURES, "satagraph.data.features"),
            "MotionClip": "satagraph.data.clip",
            "FrameBatch": "satagraph.data.collate",
            "collate_clips": "satagraph.data.collate",
            "FrameGraph": "satagraph.data.frame_graph"}
__all__ = ["MotionClip", "FrameGraph", "FrameBatch", "collate_clips", *_FEATURES]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
