"""User control over descriptions: JSON dictionaries and sparse anchor tags.

Precedence, from strongest to weakest:

1. **Anchor tags** (``{"raw joint name": "tag"}``): the tagged joint gets its
   tag verbatim.
2. **Dictionary** entries (``{"raw joint name": "description"}``, e.g. an
   imported language-model answer): replace the rule description of every
   joint with that exact raw name. Entries for joints the skeleton does not
   have are ignored, so one dictionary can serve many skeletons.
3. **Propagated tags**: a tag spreads along its chain to joints whose names
   the rules did not understand (those with a structural fallback
   description) and that have no dictionary entry:

   * *down*: a joint below a tagged joint ``A``, reached through joints that
     each have a single child (end sites not counted) and are themselves
     not understood, gets ``"<tag>, <k-th> segment down the chain"`` where
     ``k`` is the number of bones from ``A``; ``A`` itself may branch (a
     tagged paw passes its tag to each toe chain);
   * *up*: otherwise, a joint with a single child from which a tagged joint
     ``B`` is reached down a single-child chain of not-understood joints gets
     ``"<tag>, <k-th> segment up the chain"``;
   * an end site of a tagged or propagated joint gets ``"<tag> tip"``.

   Joints the rules understood keep their rule description; tag them
   explicitly (or use a dictionary) to change them.
4. **Rules** (:mod:`.rules`).
"""
from __future__ import annotations

import os
from typing import Dict, Iterable, List, Mapping, Optional, Sequence, Union

from satagraph.semantics._files import SemanticsError, read_json
from satagraph.semantics.rules import RuleResult, ordinal

DictionaryLike = Union[None, Mapping[str, str], str, "os.PathLike[str]"]
AnchorsLike = Union[None, Mapping[str, str], Iterable[str]]


def validate_dictionary(obj: object, source: str = "<dictionary>"
                        ) -> Dict[str, str]:
    """Check a raw-name -> description mapping.

    Args:
        obj: The decoded JSON value.
        source: File name (or other origin) used in error messages.

    Returns:
        dict[str, str]: The mapping, descriptions stripped.

    Raises:
        SemanticsError: Not an object, or a key / value that is not a
            non-empty string (the message names the file and the key).
    """
    if not isinstance(obj, Mapping):
        raise SemanticsError(
            f"{source}: expected a JSON object mapping raw joint names to "
            f"descriptions, got {type(obj).__name__}")
    out: Dict[str, str] = {}
    for key, value in obj.items():
        if not isinstance(key, str) or not key.strip():
            raise SemanticsError(f"{source}: joint name {key!r} must be a "
                                 f"non-empty string")
        if not isinstance(value, str) or not value.strip():
            raise SemanticsError(
                f"{source}: key {key!r}: description must be a non-empty "
                f"string, got {type(value).__name__} {value!r}")
        out[key] = " ".join(value.split())
    return out


def load_dictionary(dictionary: DictionaryLike) -> Dict[str, str]:
    """Load and validate a dictionary given as a mapping or a JSON file.

    Args:
        dictionary: ``None``, a mapping, or the path of a JSON file.

    Returns:
        dict[str, str]: The validated mapping (empty for ``None``).

    Raises:
        SemanticsError: Unreadable file, bad JSON or bad entries.
    """
    if dictionary is None:
        return {}
    if isinstance(dictionary, Mapping):
        return validate_dictionary(dictionary)
    path = os.fspath(dictionary)
    return validate_dictionary(read_json(path, "dictionary"), path)


def parse_anchor(text: str) -> tuple:
    """Parse one ``NAME=TAG`` anchor (split at the first ``=``).

    Args:
        text: For example ``"LeftFoot=left hind paw"``.

    Returns:
        tuple[str, str]: ``(name, tag)``.

    Raises:
        SemanticsError: No ``=``, or an empty name or tag.
    """
    name, sep, tag = text.partition("=")
    if not sep or not name.strip() or not tag.strip():
        raise SemanticsError(f"anchor {text!r}: expected NAME=TAG, e.g. "
                             f"'LeftFoot=left hind paw'")
    return name.strip(), " ".join(tag.split())


def normalize_anchors(anchors: AnchorsLike) -> Dict[str, str]:
    """Anchors as a ``{name: tag}`` dict.

    Args:
        anchors: ``None``, a mapping, or an iterable of ``"NAME=TAG"``.

    Returns:
        dict[str, str]: name -> tag.

    Raises:
        SemanticsError: A malformed anchor.
    """
    if anchors is None:
        return {}
    if isinstance(anchors, Mapping):
        pairs = [parse_anchor(f"{k}={v}") if isinstance(v, str)
                 else _bad_anchor(k, v) for k, v in anchors.items()]
    elif isinstance(anchors, str):
        pairs = [parse_anchor(anchors)]
    else:
        pairs = [parse_anchor(a) for a in anchors]
    return dict(pairs)


def _bad_anchor(name: object, tag: object) -> tuple:
    raise SemanticsError(f"anchor {name!r}: tag must be a string, got "
                         f"{type(tag).__name__}")


def check_anchor_names(anchors: Mapping[str, str], names: Sequence[str]
                       ) -> None:
    """Every anchor must name a joint of the skeleton.

    Args:
        anchors: name -> tag.
        names: The skeleton's joint names.

    Raises:
        SemanticsError: An anchor names no joint.
    """
    known = set(names)
    for name in anchors:
        if name not in known:
            sample = ", ".join(list(names)[:8])
            raise SemanticsError(
                f"anchor {name!r}: the skeleton has no joint of that name "
                f"(joints: {sample}{', ...' if len(names) > 8 else ''})")


class _Propagation:
    """Spreads anchor tags along chains (see the module docstring)."""

    def __init__(self, names: Sequence[str], parents: Sequence[int],
                 end_site: Sequence[bool], free: List[bool]) -> None:
        self.names, self.parents, self.end_site = names, parents, end_site
        self.free = free
        self.kids: List[List[int]] = [[] for _ in names]
        for j, p in enumerate(parents):
            if p >= 0 and not end_site[j]:
                self.kids[p].append(j)

    def down(self, j: int, tags: Mapping[int, str]) -> Optional[tuple]:
        p, k = self.parents[j], 1
        while p >= 0:
            if p in tags:
                return tags[p], f"{ordinal(k)} segment down the chain"
            if not self.free[p] or len(self.kids[p]) != 1:
                return None
            p, k = self.parents[p], k + 1
        return None

    def up(self, j: int, tags: Mapping[int, str]) -> Optional[tuple]:
        c, k = j, 1
        while len(self.kids[c]) == 1:
            c = self.kids[c][0]
            if c in tags:
                return tags[c], f"{ordinal(k)} segment up the chain"
            if not self.free[c]:
                return None
            k += 1
        return None


def apply_user(names: Sequence[str], parents: Sequence[int],
               end_site: Sequence[bool], rules: RuleResult,
               dictionary: Mapping[str, str], anchors: Mapping[str, str]
               ) -> List[str]:
    """Combine rule descriptions, a dictionary and anchor tags.

    Args:
        names: Raw joint names.
        parents: Parent index per joint.
        end_site: End-site flags.
        rules: Rule output for these joints.
        dictionary: Validated raw name -> description.
        anchors: Validated raw name -> tag (names must exist).

    Returns:
        list[str]: The final description per joint.
    """
    out = [dictionary.get(n, d) for n, d in zip(names, rules.descriptions)]
    if not anchors:
        return out
    tags = {j: anchors[n] for j, n in enumerate(names) if n in anchors}
    free = [rules.fallback[j] and n not in dictionary and j not in tags
            for j, n in enumerate(names)]
    prop = _Propagation(names, parents, end_site, free)
    source: Dict[int, str] = dict(tags)
    for j in range(len(names)):
        if j in tags:
            out[j] = tags[j]
        elif free[j] and not end_site[j]:
            found = prop.down(j, tags) or prop.up(j, tags)
            if found:
                source[j] = found[0]
                out[j] = f"{found[0]}, {found[1]}"
    for j, p in enumerate(parents):
        if end_site[j] and p in source and names[j] not in dictionary \
                and j not in tags:
            out[j] = f"{source[p]} tip"
    return out
