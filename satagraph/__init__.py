"""satagraph: topology-agnostic character motion on PyTorch Geometric."""
from satagraph.motion import CanonicalTransform, Motion
from satagraph.skeleton import Skeleton

__version__ = "0.1.0"
__all__ = ["Skeleton", "Motion", "CanonicalTransform", "__version__"]
