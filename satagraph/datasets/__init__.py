r"""Data sources and their captions for text-to-motion.

* :mod:`.captions`: :func:`captions_for` (the captions of any clip: user
  sidecars, templates from file names and the zoo generator's facts) and
  :func:`captioned_clips` (a manifest's captioned clips with their splits).
* :mod:`.sidecar`: user captions in ``clip.txt`` (HumanML3D lines) or
  ``clip.json``.
* :mod:`.mirror`: :func:`mirror_text`, the caption of a left/right mirrored
  motion.
"""
from satagraph.datasets.caption import Caption, CaptionError, choose, mirror_captions
from satagraph.datasets.captions import (CAPTIONERS, CaptionedClip, captioned_clips,
                                         captions_for, infer_dataset)
from satagraph.datasets.mirror import MIRROR_WORDS, mirror_text
from satagraph.datasets.sidecar import (parse_caption_json, parse_humanml3d,
                                        read_sidecar, read_sidecars, sidecar_paths)
from satagraph.datasets.zoo_captions import ZooClip, zoo_clip_of_row, zoo_phrasings

__all__ = ["Caption", "CaptionError", "CaptionedClip", "CAPTIONERS", "MIRROR_WORDS",
           "ZooClip", "captioned_clips", "captions_for", "choose", "infer_dataset",
           "mirror_captions", "mirror_text", "parse_caption_json", "parse_humanml3d",
           "read_sidecar", "read_sidecars", "sidecar_paths", "zoo_clip_of_row",
           "zoo_phrasings"]
