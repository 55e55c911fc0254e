"""What a trained model is used for, end to end: sliding-window
reconstruction and retargeting of whole motions (:mod:`.inference`), the
per-dataset evaluation (:mod:`.evaluation`) and the reference-free quality
of a retarget (:mod:`.quality`), text-to-motion generation
(:mod:`.generate`) and the skeleton-agnostic kinematic descriptor its
evaluation reads (:mod:`.motion_descriptor`).

The retargeting and reconstruction entry points are importable from here
(``from satagraph.pipelines import Retargeter``).

Pipelines use models through their public interface; they import no
network, loss or metric module (tests/test_layout.py).
"""
from satagraph._lazy import lazy_exports

_INFERENCE = ("Retargeter", "RigMemo", "reconstruct_motion", "retarget_motion")
__all__ = list(_INFERENCE)
__getattr__, __dir__ = lazy_exports(__name__, dict.fromkeys(_INFERENCE,
                                                            "satagraph.pipelines.inference"))
