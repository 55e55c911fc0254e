"""satagraph: topology-agnostic character motion on PyTorch Geometric.

The public names are imported lazily (:mod:`satagraph._lazy`), so that the
command line starts without loading torch.
"""
from satagraph._lazy import lazy_exports

__version__ = "0.1.0"
_EXPORTS = {"Skeleton": "satagraph.skeleton", "Motion": "satagraph.motion",
            "CanonicalTransform": "satagraph.motion"}
__all__ = ["Skeleton", "Motion", "CanonicalTransform", "__version__"]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
