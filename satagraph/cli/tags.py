"""``satagraph tags``: inspect and control the semantic joint tags of a BVH file.

Examples::

    satagraph tags walk.bvh                        # table of descriptions
    satagraph tags walk.bvh --names-only           # names and hierarchy only
    satagraph tags walk.bvh --json                 # the same as JSON
    satagraph tags walk.bvh --anchor "Bone.003=tail base" --dictionary d.json
    satagraph tags walk.bvh --prompt --out prompt.txt
    satagraph tags walk.bvh --prompt --reference-vocab vocab.json
    satagraph tags walk.bvh --import answer.json --out dict.json

The descriptions use the file's motion as evidence (which chains bear
weight, spread sideways, lie in front; see
:mod:`satagraph.semantics.evidence`), as training and inference do;
``--names-only`` reads names and hierarchy alone.

Errors print one line to stderr and return exit code 2.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import List, Optional, Sequence

from satagraph.utils.files import OutputPathError, atomic_write_text, check_output_path
from satagraph.skeleton import Skeleton


def add_tags_parser(subparsers: "argparse._SubParsersAction"
                    ) -> argparse.ArgumentParser:
    """Register the ``tags`` subcommand.

    Args:
        subparsers: The object returned by
            :meth:`argparse.ArgumentParser.add_subparsers`.

    Returns:
        argparse.ArgumentParser: The ``tags`` parser (its default ``func``
        is :func:`run_tags`).
    """
    p = subparsers.add_parser(
        "tags", help="show, override or LM-generate semantic joint tags",
        description="Canonical functional descriptions of a BVH file's "
                    "joints (semantic tags), user overrides, and the SATA "
                    "Figure 6 prompt round trip for your own language model.")
    p.add_argument("file", type=Path, help="BVH file")
    mode = p.add_mutually_exclusive_group()
    mode.add_argument("--prompt", action="store_true",
                      help="write the Figure 6 prompt for a language model")
    mode.add_argument("--import", dest="import_answer", type=Path,
                      metavar="ANSWER.json",
                      help="validate a language model's JSON answer and "
                           "store it as a dictionary (needs --out)")
    p.add_argument("--reference-vocab", type=Path, metavar="V.json",
                   help="with --prompt: reference vocabulary (alignment mode)")
    p.add_argument("--out", "--output", type=Path, metavar="FILE",
                   help="output file (prompt, dictionary, or table/JSON)")
    p.add_argument("--dictionary", type=Path, metavar="D.json",
                   help="JSON raw name -> description overrides")
    p.add_argument("--anchor", action="append", default=[],
                   metavar="NAME=TAG", help="anchor tag (repeatable)")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.add_argument("--names-only", action="store_true",
                   help="ignore the motion: names and hierarchy only")
    from satagraph.cli.arguments import add_rig_arguments
    add_rig_arguments(p, what="the file (for the motion evidence)")
    p.set_defaults(func=run_tags)
    return p


def _rows(skeleton: Skeleton, descriptions: List[str]) -> List[dict]:
    names = skeleton.names
    return [{"index": j, "name": name,
             "parent": names[p] if p >= 0 else None,
             "description": text}
            for j, (name, p, text) in enumerate(
                zip(names, skeleton.parents.tolist(), descriptions))]


def format_table(rows: Sequence[dict]) -> str:
    """Aligned text table: index, joint name, parent, description.

    Args:
        rows: Output of the joint rows (``index``, ``name``, ``parent``,
            ``description``).

    Returns:
        str: The table.
    """
    head = ("#", "joint", "parent", "description")
    cells = [head] + [(str(r["index"]), r["name"], r["parent"] or "-",
                       r["description"]) for r in rows]
    widths = [max(len(c[i]) for c in cells) for i in range(3)]
    lines = ["  ".join([c[0].rjust(widths[0]), c[1].ljust(widths[1]),
                        c[2].ljust(widths[2]), c[3]]).rstrip() for c in cells]
    return "\n".join(lines)


def _evidence(motion):
    """Evidence of the file's motion, canonicalised as the features are
    (with the ``--up-axis`` / ``--units`` attached to it). ``None`` (names
    only) where the motion cannot be canonicalised or its up axis is a
    low-confidence guess, said on stderr: evidence read on the wrong axis
    would mislead."""
    from satagraph.transforms.rig_reading import read_rig
    from satagraph.semantics import evidence_from_motion
    up = read_rig(motion).up
    if up.low_confidence:
        print(f"satagraph: note: {motion.source}: the up axis is uncertain "
              f"({up.summary()}); descriptions from names only (pass --up-axis "
              "to use the motion)", file=sys.stderr)
        return None
    try:
        return evidence_from_motion(motion)
    except ValueError:
        return None


def _emit(text: str, out: Optional[Path]) -> None:
    if out is None:
        print(text)
    else:
        atomic_write_text(out, text + ("" if text.endswith("\n") else "\n"),
                          create_parent=True)


def _run(args: argparse.Namespace) -> int:
    from satagraph.semantics import (SemanticsError, build_prompt,
                                     describe_joints, import_answer,
                                     load_reference_vocab)
    if args.reference_vocab and not args.prompt:
        raise SemanticsError("--reference-vocab needs --prompt")
    if args.import_answer and args.out is None:
        raise SemanticsError("--import needs --out DICT.json")
    if args.out is not None:  # before any work, said as every command says it
        check_output_path(args.out, create_parent=True)
    from satagraph.cli.arguments import read_with_rig
    motion = read_with_rig(str(args.file), args)
    skeleton = motion.skeleton
    if args.prompt:
        vocab = (load_reference_vocab(args.reference_vocab)
                 if args.reference_vocab else None)
        _emit(build_prompt(skeleton, vocab), args.out)
        return 0
    if args.import_answer:
        stored = import_answer(args.import_answer, skeleton, args.out)
        print(f"stored {len(stored)} joint descriptions in {args.out}")
        return 0
    evidence = None if args.names_only else _evidence(motion)
    texts = describe_joints(skeleton, dictionary=args.dictionary,
                            anchors=args.anchor, evidence=evidence)
    rows = _rows(skeleton, texts)
    text = (json.dumps(rows, indent=2, ensure_ascii=False) if args.json
            else format_table(rows))
    _emit(text, args.out)
    return 0


def run_tags(args: argparse.Namespace) -> int:
    """Run ``satagraph tags`` with parsed arguments.

    Args:
        args: Namespace from the ``tags`` parser.

    Returns:
        int: 0 on success, 2 on any user error (one line on stderr).
    """
    from satagraph.semantics import SemanticsError  # torch: only here
    from satagraph.io import BVHError
    from satagraph.cli import _message
    try:
        return _run(args)
    except (SemanticsError, BVHError, OSError, OutputPathError) as err:
        message = _message(err).splitlines()[0] if str(err) else repr(err)
        print(f"satagraph: error: {message}", file=sys.stderr)
        return 2


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Stand-alone entry point: ``python -m satagraph.cli.tags FILE ...``.

    Args:
        argv: Arguments after the program name (default ``sys.argv[1:]``).

    Returns:
        int: The exit code.
    """
    parser = argparse.ArgumentParser(prog="satagraph")
    add_tags_parser(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(["tags", *(sys.argv[1:] if argv is None
                                        else argv)])
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
