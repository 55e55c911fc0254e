"""Language-model round trip: export the SATA Figure 6 prompt, import the
model's JSON answer as a dictionary.

satagraph never calls a model. :func:`build_prompt` writes the prompt of the
SATA paper (appendix C.3, Figure 6) for a skeleton; the user runs it in any
language model and saves the JSON answer; :func:`import_answer` checks that
the answer covers every joint of the skeleton, names no other joint and maps
each to a string, then stores it as a dictionary JSON usable with
``describe_joints(..., dictionary=...)``.

Two modes, as in the paper: ``"ALIGNMENT"`` when a reference vocabulary is
given (the model must reuse its exact strings for matching roles), and
``"GENERATION"`` without one (the paper names only the alignment mode; the
other name is ours).
"""
from __future__ import annotations

import json
import os
import re
from pathlib import Path
from typing import Dict, List, Mapping, Optional, Sequence, Union

from satagraph.semantics._files import (SemanticsError, read_json,
                                        write_json_atomic)
from satagraph.skeleton import Skeleton

PathLike = Union[str, "os.PathLike[str]"]

FIGURE6_TEMPLATE = """\
# Role
You are a Senior Technical Artist and Biomechanics Specialist specializing in \
Cross-Species Motion Retargeting. Your goal is to map raw 3D joint names from \
heterogeneous skeletons (Humans, Quadrupeds, etc.) into Universal Semantic \
Labels that serve as grounding for Text-to-Motion models (CLIP/T5).

# Context
Our framework uses these labels to build a "Topology-Agnostic" latent space. \
We need labels that describe the functional role of the joint, ensuring that \
a "Human Knee" and a "Dog Stifle" share the same semantic grounding.

# Task
Analyze the provided "Joint List" (often with parent-child hierarchy hints) \
and generate a JSON mapping: {"raw_name": "semantic_description"}.

# Rules for Universal Semantic Grounding
1. Taxonomic Neutrality:
- Use terms that apply to both bipeds and quadrupeds where possible.
- "UpLeg" -> "Upper Hind Leg / Thigh".
- "Arm" -> "Front Limb / Arm".
- "Hand/Foot" -> "Terminal End of Front/Hind Limb".
2. Hierarchy-Aware Interpretation:
- If the raw name is ambiguous (e.g., "Leg"), look at its position:
- Root -> Spine -> Leg (means Thigh/Upper Leg).
- Thigh -> Leg (means Calf/Shin).
3. Functional Role Expansion:
- Don't just clean the name; describe its locomotion role.
- "Hips/Pelvis" -> "Root / Pelvis Area (Center of Motion)".
- "ToeBase" -> "Toe Base (Support Pivot)".
4. Handle End Sites & Effectors:
- Joints ending in "_End", "Nub", or "Site" signify extremities.
- Map to "... Tip / Effector" (e.g., "Head Top Tip", "Front Left Paw Tip").
5. Standardize Orientation:
- Always expand: "L/l" -> "Left", "R/r" -> "Right", "Fr" -> "Front", \
"Bk" -> "Back".
6. Numerical Invariance (Aggregation) :
- Ignore numeric suffixes or indices that denote sequential segments of the \
same body part (e.g., "Spine1", "Spine_2", "Neck_3").
- Map these to the same core functional description (e.g., all map to \
"Spine segment").

# Mode: {{ MODE }}
{{ ALIGNMENT_BLOCK }}
# Input Data (Format: Raw Joint Name [Parent Name])
{{ RAW_JOINTS_LIST }}

# Output Format
Output ONLY a valid JSON object.
Example: {"root_joint": "The center of gravity of the body", \
"Spine2": "A spine bone segment"}

JSON:
"""

ALIGNMENT_BLOCK = """
# Alignment Constraints (Cross-Species Dictionary)
You must ensure these labels align with our Universal Motion Vocabulary.
Requirement:
1. Search the [Existing Vocabulary] below. If a joint plays the same \
functional role as an entry there, use that entry's exact string.
2. If the structure is unique to this species (e.g., "Tail", "Wing"), \
create a new clean label following the rules above.

[Existing Reference Vocabulary]:
{{ REFERENCE_VOCAB_LIST }}
"""


def joint_list(skeleton: Skeleton) -> str:
    """The prompt's input lines, ``Raw Joint Name [Parent Name]``.

    Args:
        skeleton: The skeleton (end sites included).

    Returns:
        One line per joint; the root's parent is ``None``.
    """
    names = skeleton.names
    return "\n".join(
        f"{name} [{names[p] if p >= 0 else 'None'}]"
        for name, p in zip(names, skeleton.parents.tolist()))


def build_prompt(skeleton: Skeleton,
                 reference_vocab: Optional[Sequence[str]] = None) -> str:
    """Render the Figure 6 prompt for :obj:`skeleton`.

    Args:
        skeleton: The skeleton to describe.
        reference_vocab: Existing descriptions the model must reuse
            (``"ALIGNMENT"`` mode); ``None`` for ``"GENERATION"`` mode.

    Returns:
        str: The prompt text.
    """
    block = ""
    if reference_vocab is not None:
        vocab = json.dumps(list(reference_vocab), indent=2, ensure_ascii=False)
        block = ALIGNMENT_BLOCK.replace("{{ REFERENCE_VOCAB_LIST }}", vocab)
    mode = "ALIGNMENT" if reference_vocab is not None else "GENERATION"
    return (FIGURE6_TEMPLATE.replace("{{ MODE }}", mode)
            .replace("{{ ALIGNMENT_BLOCK }}", block)
            .replace("{{ RAW_JOINTS_LIST }}", joint_list(skeleton)))


def validate_vocab(obj: object, source: str) -> List[str]:
    """A reference vocabulary: a JSON list of strings, a dictionary (its
    values are the vocabulary) or ``{"vocabulary": [...]}``.

    Args:
        obj: The decoded JSON value.
        source: File name for messages.

    Returns:
        list[str]: Unique entries in first-seen order.

    Raises:
        SemanticsError: Any other shape or a non-string entry.
    """
    if isinstance(obj, Mapping) and isinstance(obj.get("vocabulary"), list):
        obj = obj["vocabulary"]
    items = list(obj.values()) if isinstance(obj, Mapping) else obj
    if not isinstance(items, list):
        raise SemanticsError(f"{source}: expected a JSON list of descriptions "
                             f"or an object of name -> description")
    for i, item in enumerate(items):
        if not isinstance(item, str) or not item.strip():
            raise SemanticsError(f"{source}: entry {i} must be a non-empty "
                                 f"string, got {type(item).__name__}")
    return list(dict.fromkeys(" ".join(t.split()) for t in items))


def load_reference_vocab(path: PathLike) -> List[str]:
    """Read a reference vocabulary JSON file (see :func:`validate_vocab`).

    Args:
        path: The JSON file.

    Returns:
        list[str]: The vocabulary.
    """
    return validate_vocab(read_json(path, "reference vocabulary"),
                          os.fspath(path))


_FENCE = re.compile(r"^\s*(?:JSON:)?\s*```[a-zA-Z]*\s*(.*?)\s*```\s*$",
                    re.DOTALL)


def _decode_answer(text: str, source: str) -> Dict[str, object]:
    match = _FENCE.match(text)
    text = match.group(1) if match else text.strip()
    if text.startswith("JSON:"):
        text = text[5:]

    def pairs(items: list) -> dict:
        keys = [k for k, _ in items]
        dup = sorted({k for k in keys if keys.count(k) > 1})
        if dup:
            raise SemanticsError(f"{source}: duplicate joint(s) in answer: "
                                 f"{_names(dup)}")
        return dict(items)

    try:
        obj = json.loads(text, object_pairs_hook=pairs)
    except json.JSONDecodeError as err:
        raise SemanticsError(f"{source}: answer is not valid JSON: {err.msg} "
                             f"(line {err.lineno}, column {err.colno})"
                             ) from None
    if not isinstance(obj, dict):
        raise SemanticsError(f"{source}: answer must be a JSON object "
                             f"{{joint: description}}, got "
                             f"{type(obj).__name__}")
    return obj


def _names(names: Sequence[str], limit: int = 10) -> str:
    shown = ", ".join(repr(n) for n in names[:limit])
    return shown + (f" (+{len(names) - limit} more)" if len(names) > limit
                    else "")


def parse_answer(text: str, skeleton: Skeleton, source: str = "<answer>"
                 ) -> Dict[str, str]:
    """Validate a language model's JSON answer against a skeleton.

    A surrounding Markdown code fence is tolerated. Every joint must be
    covered, no unknown joint may appear, every value must be a non-empty
    string.

    Args:
        text: The answer text.
        skeleton: The skeleton the prompt was made for.
        source: File name for messages.

    Returns:
        dict[str, str]: raw name -> description, in skeleton order.

    Raises:
        SemanticsError: One line listing every problem found.
    """
    obj = _decode_answer(text, source)
    names = skeleton.names
    known = set(names)
    problems = []
    missing = [n for n in names if n not in obj]
    if missing:
        problems.append(f"missing {len(missing)} joint(s): {_names(missing)}")
    unknown = [k for k in obj if k not in known]
    if unknown:
        problems.append(f"unknown joint(s): {_names(unknown)}")
    bad = [k for k, v in obj.items()
           if k in known and (not isinstance(v, str) or not v.strip())]
    if bad:
        problems.append(f"non-string or empty description for {_names(bad)}")
    if problems:
        raise SemanticsError(f"{source}: answer does not match the skeleton: "
                             + "; ".join(problems))
    return {n: " ".join(obj[n].split()) for n in names}


def import_answer(answer: PathLike, skeleton: Skeleton, out: PathLike
                  ) -> Dict[str, str]:
    """Validate an answer file and store it as a dictionary JSON
    (written atomically).

    Args:
        answer: The saved language-model answer.
        skeleton: The skeleton the prompt was made for.
        out: Destination dictionary JSON.

    Returns:
        dict[str, str]: The stored dictionary.

    Raises:
        SemanticsError: Unreadable or invalid answer.
    """
    try:
        text = Path(answer).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise SemanticsError(f"{answer}: answer file not found") from None
    except (OSError, UnicodeDecodeError) as err:
        raise SemanticsError(f"{answer}: cannot read answer: {err}") from None
    dictionary = parse_answer(text, skeleton, os.fspath(answer))
    write_json_atomic(out, dictionary)
    return dictionary
