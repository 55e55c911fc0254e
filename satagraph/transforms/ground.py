r"""Putting a decoded motion on the ground its source stands on.

A decoder predicts the root's height; decoded onto another body plan it can
carry the source's hip height over (a quadruped's hips at 0.7 of its height
decoded onto a biped leave the biped's feet 16 % of its height above the
floor). :func:`ground_like` moves the whole motion up or down by one
constant, so its vertical dynamics (bobbing, jumps) stay the decoder's and
only the offset is set: the median height of its lowest joint, in its own
character heights, becomes the source's.
"""
from __future__ import annotations

import numpy as np

from satagraph.motion import Motion


def lowest_heights(motion: Motion) -> np.ndarray:
    r"""Height of the lowest joint per frame (+Y up).

    Shapes:
        - **output**: :math:`(T,)`
    """
    return motion.global_positions()[..., 1].min(axis=1)


def ground_like(motion: Motion, reference: Motion) -> Motion:
    r""":obj:`motion` shifted along +Y by one constant so that the median
    height of its lowest joint over its frames, over its character height,
    is :obj:`reference`'s (both +Y up, floor at 0: canonical motions).

    Args:
        motion (Motion): A decoded motion (a retarget or reconstruction).
        reference (Motion): The motion it was decoded from.
    """
    if motion.num_frames == 0 or reference.num_frames == 0:
        return motion
    want = float(np.median(lowest_heights(reference))) / max(reference.height(), 1e-9)
    shift = want * motion.height() - float(np.median(lowest_heights(motion)))
    translations = motion.translations.copy()
    translations[:, 0, 1] += shift
    return motion.with_(translations=translations)


__all__ = ["lowest_heights", "ground_like"]
