r"""Where motion comes from, and its captions for text-to-motion
(imported lazily).

* :mod:`.sources`: BVH folders and manifests resolved into
  :class:`~satagraph.datasets.sources.MotionFile` entries with splits.
* :mod:`.zoo`: the procedural zoo (rigs, motions, exporter dialects and
  the writer).
* :mod:`.captions`: :func:`captions_for` (the captions of any clip: user
  sidecars, templates from file names and the zoo generator's facts) and
  :func:`captioned_clips` (a manifest's captioned clips with their splits).
* :mod:`.sidecar`: user captions in ``clip.txt`` (HumanML3D lines) or
  ``clip.json``.
* :mod:`.mirror`: :func:`mirror_text`, the caption of a left/right mirrored
  motion.
* :mod:`.reverse`: :func:`reverse_text`, the caption of a motion played
  backwards (walks only).
"""
from satagraph._lazy import lazy_exports

_EXPORTS = {
    **dict.fromkeys(("Caption", "CaptionError", "choose", "mirror_captions"),
                    "satagraph.datasets.caption"),
    **dict.fromkeys(("CAPTIONERS", "CaptionedClip", "captioned_clips", "captions_for",
                     "infer_dataset"), "satagraph.datasets.captions"),
    **dict.fromkeys(("MIRROR_WORDS", "mirror_text"), "satagraph.datasets.mirror"),
    **dict.fromkeys(("REVERSIBLE_WORDS", "reverse_text"), "satagraph.datasets.reverse"),
    **dict.fromkeys(("parse_caption_json", "parse_humanml3d", "read_sidecar",
                     "read_sidecars", "sidecar_paths"), "satagraph.datasets.sidecar"),
    **dict.fromkeys(("ZooClip", "zoo_clip_of_row", "zoo_phrasings"),
                    "satagraph.datasets.zoo_captions")}
__all__ = ["Caption", "CaptionError", "CaptionedClip", "CAPTIONERS", "MIRROR_WORDS",
           "REVERSIBLE_WORDS", "ZooClip", "captioned_clips", "captions_for", "choose",
           "infer_dataset", "mirror_captions", "mirror_text", "parse_caption_json",
           "parse_humanml3d", "read_sidecar", "read_sidecars", "reverse_text", "sidecar_paths",
           "zoo_clip_of_row", "zoo_phrasings"]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
