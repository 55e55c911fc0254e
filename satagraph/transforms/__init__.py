"""Motion-to-motion transforms: reading a rig (up axis, units),
canonicalisation (+Y up, facing +Z, metres, one frame rate), skeleton
augmentation (bone scaling, mirroring, time reversal, restructuring), the rest pose a rig
is shown to a model in, a leading bind-pose frame, and planting a decoded
motion's feet and settling its root where it stands still. Imported lazily:
numpy only."""
from satagraph._lazy import lazy_exports

_CANONICAL = ("canonicalize", "decanonicalize", "detect_up_axis", "resample")
_EXPORTS = {**dict.fromkeys(_CANONICAL, "satagraph.transforms.canonical"),
            **dict.fromkeys(("read_rig", "with_rig"), "satagraph.transforms.rig_reading"),
            **dict.fromkeys(("SkeletonAugment", "mirror", "reverse_time", "scale_bones"),
                            "satagraph.transforms.augment"),
            "plant_feet": "satagraph.transforms.foot_plant",
            **dict.fromkeys(("has_bind_frame", "replace_bind_frame"),
                            "satagraph.transforms.bind_frame"),
            **dict.fromkeys(("settle_root", "hold_still_source"),
                            "satagraph.transforms.still_root"),
            **dict.fromkeys(("shown_rest", "needs_rest"), "satagraph.transforms.rest")}
__all__ = [*_CANONICAL, "read_rig", "with_rig", "SkeletonAugment", "mirror",
           "reverse_time", "scale_bones", "plant_feet", "settle_root", "hold_still_source",
           "shown_rest", "needs_rest", "has_bind_frame", "replace_bind_frame"]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
