"""Datasets, canonicalisation, features and batching of motion clips."""
from satagraph.data.canonical import canonicalize, decanonicalize, detect_up_axis, resample
from satagraph.data.clip import MotionClip
from satagraph.data.collate import FrameBatch, collate_clips
from satagraph.data.features import MotionFeatures, features_to_motion, motion_to_features
from satagraph.data.frame_graph import FrameGraph

__all__ = ["canonicalize", "decanonicalize", "detect_up_axis", "resample", "MotionClip",
           "FrameGraph", "FrameBatch", "collate_clips", "MotionFeatures",
           "motion_to_features", "features_to_motion"]
