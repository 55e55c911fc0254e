"""Semantic joint tags: canonical functional descriptions and their embeddings.

The pipeline of SATA (paper section 3.2, appendix C.3), offline:

1. :func:`describe_joints` turns raw joint names into canonical,
   taxonomy-neutral descriptions by rules (:mod:`.rules`), optionally
   helped by geometry / motion evidence (:mod:`.evidence`: which chains
   bear weight, spread sideways, lie in front), then applies a user
   dictionary and sparse anchor tags (:mod:`.user`).
2. :func:`build_prompt` / :func:`import_answer` (:mod:`.prompt`) let a user
   run the paper's Figure 6 prompt in any language model and import the JSON
   answer as a dictionary.
3. :func:`embed_skeleton` embeds the descriptions with a
   :class:`TextEncoder` (:class:`OfflineTextEncoder` by default, or a local
   :class:`T5TextEncoder`) through a disk cache (:mod:`.cache`): the
   semantic features X_t, one row per joint. The same encoders embed
   captions for text-to-motion, with :class:`SentenceEncoder` (a local
   MiniLM) and :class:`GloVeEncoder` (local word vectors);
   :func:`build_text_encoder` builds any of them from a spec string.

Example::

    from satagraph.io import read_bvh
    from satagraph.semantics import describe_joints, embed_skeleton, evidence_from_motion

    motion = read_bvh("walk.bvh")
    describe_joints(motion.skeleton)   # ["pelvis, hips root ...", ...]
    evidence = evidence_from_motion(motion)  # what the body does
    x_t = embed_skeleton(motion.skeleton, evidence=evidence)  # [J, 256]
"""
from __future__ import annotations

import os
from typing import TYPE_CHECKING, List, Optional, Sequence, Union

from satagraph._lazy import lazy_exports
from satagraph.semantics._files import SemanticsError, write_json_atomic
from satagraph.semantics.evidence import (EvidenceLike, JointEvidence,
                                          as_evidence, call_semantic,
                                          evidence_from_features,
                                          evidence_from_motion,
                                          joint_evidence, remap_evidence)
from satagraph.semantics.limbs import (LIMBS, helper_joints, hip_bones, limb_end_index,
                                        limb_ends, paired_legs)
from satagraph.semantics.prompt import (build_prompt, import_answer,
                                        load_reference_vocab,
                                        parse_answer)
from satagraph.semantics.rules import describe_structure
from satagraph.semantics.user import (AnchorsLike, DictionaryLike,
                                      apply_user, check_anchor_names,
                                      load_dictionary, normalize_anchors,
                                      parse_anchor, validate_dictionary)
from satagraph.skeleton import Skeleton

if TYPE_CHECKING:
    from torch import Tensor

    from satagraph.semantics.encoders import TextEncoder

# The encoders and the embedding cache need torch: they load on first use, so
# that reading a rig (describe_joints, evidence, limbs) stays numpy-only.
_ENCODERS = ("TextEncoder", "OfflineTextEncoder", "T5TextEncoder")
_FACTORY = ("TextEncoderMismatch", "build_text_encoder", "check_text_encoder",
            "check_text_encoder_state", "text_encoder_state", "register_text_encoder")
__getattr__, __dir__ = lazy_exports(__name__, {
    **dict.fromkeys(_ENCODERS, "satagraph.semantics.encoders"),
    **dict.fromkeys(_FACTORY, "satagraph.semantics.factory"),
    "GloVeEncoder": "satagraph.semantics.glove",
    "SentenceEncoder": "satagraph.semantics.sentence",
    **dict.fromkeys(("EmbeddingCache", "clear_memory", "default_cache_dir"),
                    "satagraph.semantics.cache")})

PathLike = Union[str, "os.PathLike[str]"]
_DEFAULT_ENCODER: Optional["TextEncoder"] = None


def describe_joints(skeleton: Skeleton, dictionary: DictionaryLike = None,
                    anchors: AnchorsLike = None,
                    evidence: EvidenceLike = None) -> List[str]:
    """One canonical functional description per joint (end sites included).

    Rules first (see :mod:`satagraph.semantics.rules`), then the
    dictionary, then anchor tags and their propagation along chains (see
    :mod:`satagraph.semantics.user` for the exact precedence and
    propagation rule). Never returns an empty string; unknown names get a
    cleaned form plus their structural role.

    Args:
        skeleton: The skeleton.
        dictionary: Raw name -> description, as a mapping or a JSON file.
        anchors: Sparse tags, as ``{name: tag}`` or ``["NAME=TAG", ...]``.
        evidence: Optional geometry / motion evidence: a
            :class:`JointEvidence`, motion features, or canonical joint
            positions ``[T, J, 3]`` / ``[J, 3]`` (+Y up, facing +Z, see
            :mod:`satagraph.semantics.evidence`). ``None``: names and
            hierarchy only.

    Returns:
        list[str]: ``skeleton.num_joints`` descriptions.

    Raises:
        SemanticsError: Invalid dictionary or anchors (the message names the
            file or key).
        ValueError: Evidence for another number of joints.
    """
    names = tuple(skeleton.names)
    parents = tuple(int(p) for p in skeleton.parents.tolist())
    end_site = tuple(bool(e) for e in skeleton.end_site.tolist())
    rules = describe_structure(names, parents, end_site,
                               as_evidence(evidence, len(names)))
    table = load_dictionary(dictionary)
    tags = normalize_anchors(anchors)
    check_anchor_names(tags, names)
    if not table and not tags:
        return list(rules.descriptions)
    return apply_user(names, parents, end_site, rules, table, tags)


def default_encoder() -> "TextEncoder":
    """The shared default encoder, ``OfflineTextEncoder(256)``.

    Returns:
        TextEncoder: The encoder.
    """
    from satagraph.semantics.encoders import OfflineTextEncoder

    global _DEFAULT_ENCODER
    if _DEFAULT_ENCODER is None:
        _DEFAULT_ENCODER = OfflineTextEncoder()
    return _DEFAULT_ENCODER


def embed_texts(texts: Sequence[str], encoder: Optional[TextEncoder] = None,
                cache_dir: Optional[PathLike] = None, use_cache: bool = True
                ) -> Tensor:
    """Embed texts through the disk cache.

    Args:
        texts: N texts.
        encoder: Text encoder (default :func:`default_encoder`).
        cache_dir: Cache directory (default ``$SATAGRAPH_CACHE`` or
            ``~/.cache/satagraph/embeddings``).
        use_cache: ``False`` to call the encoder directly.

    Returns:
        Tensor: float32 ``[N, D]``.
    """
    from satagraph.semantics.cache import EmbeddingCache

    encoder = encoder or default_encoder()
    if not use_cache:
        return encoder.encode(list(texts)).float().cpu()
    return EmbeddingCache(cache_dir).embed(encoder, list(texts))


def embed_skeleton(skeleton: Skeleton, encoder: Optional[TextEncoder] = None,
                   cache_dir: Optional[PathLike] = None,
                   dictionary: DictionaryLike = None,
                   anchors: AnchorsLike = None, use_cache: bool = True,
                   evidence: EvidenceLike = None) -> Tensor:
    """Semantic features X_t of a skeleton: embedded joint descriptions.

    Args:
        skeleton: The skeleton.
        encoder: Text encoder (default ``OfflineTextEncoder(256)``).
        cache_dir: Embedding cache directory (see :func:`embed_texts`).
        dictionary: Raw name -> description overrides (mapping or JSON file).
        anchors: Sparse anchor tags (``{name: tag}`` or ``["NAME=TAG"]``).
        use_cache: ``False`` to bypass the disk cache.
        evidence: Geometry / motion evidence (see :func:`describe_joints`).
            The cache is keyed by the description texts, so evidence that
            changes a description gets its own embedding.

    Returns:
        Tensor: float32 ``[J, D]``, one row per joint (end sites included).
    """
    texts = describe_joints(skeleton, dictionary=dictionary, anchors=anchors,
                            evidence=evidence)
    return embed_texts(texts, encoder, cache_dir, use_cache)


__all__ = [
    "describe_joints", "embed_skeleton", "embed_texts", "default_encoder",
    "TextEncoder", "OfflineTextEncoder", "T5TextEncoder", "SentenceEncoder",
    "GloVeEncoder", "build_text_encoder", "check_text_encoder",
    "check_text_encoder_state", "text_encoder_state", "TextEncoderMismatch",
    "register_text_encoder", "EmbeddingCache",
    "default_cache_dir", "clear_memory", "build_prompt", "parse_answer",
    "import_answer", "load_reference_vocab", "load_dictionary",
    "validate_dictionary", "normalize_anchors", "parse_anchor",
    "write_json_atomic", "SemanticsError", "LIMBS", "limb_ends", "limb_end_index",
    "paired_legs", "helper_joints", "hip_bones",
    "JointEvidence", "joint_evidence", "evidence_from_features",
    "evidence_from_motion", "remap_evidence", "call_semantic", "as_evidence",
]
