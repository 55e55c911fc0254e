"""BVH reading and writing (imported lazily: reading needs numpy only)."""
from satagraph._lazy import lazy_exports

_EXPORTS = {"read_bvh": "satagraph.io.bvh_reader",
            "channel_values": "satagraph.io.bvh_writer",
            "write_bvh": "satagraph.io.bvh_writer",
            "BVHError": "satagraph.io.errors"}
__all__ = ["read_bvh", "write_bvh", "channel_values", "BVHError"]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
