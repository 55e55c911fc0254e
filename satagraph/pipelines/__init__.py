"""What a trained model is used for, end to end: sliding-window
reconstruction and retargeting of whole motions (:mod:`.inference`), the
per-dataset evaluation (:mod:`.evaluation`) and the reference-free quality
of a retarget (:mod:`.quality`), text-to-motion generation
(:mod:`.generate`) and the skeleton-agnostic kinematic descriptor its
evaluation reads (:mod:`.motion_descriptor`).

Pipelines use models through their public interface; they import no
network, loss or metric module (tests/test_layout.py).
"""
