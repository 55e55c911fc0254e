"""``satagraph zoo``: write the procedural skeleton zoo as BVH files.

Examples::

    satagraph zoo zoo/                                # every species
    satagraph zoo zoo/ --species quadruped snake --clips 6 --seed 3
    satagraph zoo zoo/ --species crab --up-axes=+Z,-X --units cm 28 --rest-poses apose
    satagraph zoo zoo/ --dialect-variants           # every rig in all six up axes

The folder gets ``<species>/<skeleton>_<kind>.bvh`` files (exporter dialects
under ``<species>/<dialect>/``) and a ``manifest.tsv`` usable as a training
source, with the truth of each file's up axis, scale and height.
"""
from __future__ import annotations

import argparse
import itertools
import time
from typing import List

from satagraph.cli.arguments import Folder, ListThenFolder, one_of, positive_int, seed
from satagraph.datasets.zoo import (ALL_KINDS, CLIP_KINDS, GESTURE_KINDS, NOISE_STYLES,
                                    REST_POSES, SPECIES, UNITS, UP_AXES, Dialect,
                                    dialect_variants, unit_scale, write_dialect_zoo, write_zoo)

#: Every clip kind some species can do (:data:`ALL_KINDS`), in order.
_ALL_KIND_NAMES = tuple(dict.fromkeys(k for kinds in ALL_KINDS.values() for k in kinds))


def _axes(text: str) -> List[str]:
    """Up axes from ``+Z``, ``Z``, ``negX`` or a comma list ``+Z,-X``
    (``--up-axes +Z -X`` reaches it as ``+Z,-X``:
    :func:`~satagraph.cli._glued_axes`)."""
    out = []
    for item in text.split(","):
        word = item.strip().upper()
        sign = "-" if word.startswith(("-", "NEG")) else "+"
        axis = word.lstrip("+-").removeprefix("NEG").removeprefix("POS")
        if axis not in ("X", "Y", "Z"):
            raise argparse.ArgumentTypeError(
                f"not an up axis: {item!r} (choose from {', '.join(UP_AXES)})")
        out.append(sign + axis)
    return out


def _unit(text: str) -> str:
    try:
        unit_scale(text, 1.0)
    except ValueError as err:
        raise argparse.ArgumentTypeError(str(err)) from None
    return text


def add_zoo_parser(subparsers: "argparse._SubParsersAction"
                   ) -> argparse.ArgumentParser:
    """Register ``satagraph zoo OUT_DIR [--species ...] [--clips N]
    [--seed S] [--frames N] [--fps F] [--up-axes ...] [--units ...]
    [--rest-poses ...] [--name-noise ...] [--dialect-variants]``.

    Args:
        subparsers: What :meth:`argparse.ArgumentParser.add_subparsers`
            returned.

    Returns:
        argparse.ArgumentParser: The ``zoo`` parser (``func`` is
        :func:`run_zoo`).
    """
    kinds = "; ".join(f"{s}: {', '.join(k)}" for s, k in CLIP_KINDS.items())
    gestures = "; ".join(f"{s}: {', '.join(k)}" for s, k in GESTURE_KINDS.items())
    p = subparsers.add_parser(
        "zoo", help="write procedural skeletons and motions (BVH + manifest)",
        description="Generate skeletons of several body plans (bipeds, "
        "quadrupeds with and without tails, birds, hexapods, snakes, birds in "
        "the Bip01 and finger-named-wing dialects, crabs, spiders, long-tailed "
        "quadrupeds) with varied proportions and joint naming conventions, and "
        "physically sensible procedural motions (gaits with planted feet, "
        "turns, speed changes, idles, starts and stops, looking around, jumps, "
        "reaching), written as BVH files with a "
        "manifest.tsv. The same seed gives the same files. Clip kinds cycle "
        f"per skeleton: {kinds}; --kinds chooses among them and the gestures "
        f"({gestures}). Exporter dialects: every clip is written once "
        "per combination of --up-axes, --units, --rest-poses and --name-noise "
        "(default: once, +Y up in metres), each exactly the same motion; the "
        "manifest records up_axis, scale (metres per file unit), height_m, "
        "rest_pose and name_noise, and what each clip does (kind, turn_deg: "
        "positive to the left, speed_start and speed_end in leg lengths per "
        "second), the truth of its captions (satagraph.datasets).",
        epilog="examples: satagraph zoo zoo/ --species quadruped bird --clips 5; "
        "satagraph zoo zoo/ --species spider --up-axes=+Z,-Y --units cm in 28 "
        "--rest-poses native crouched --name-noise none tag")
    p.add_argument("out_dir", nargs="?", action=Folder,
                   help="output folder (created; also after a list option: --species hexapod DIR)")
    p.add_argument("--species", nargs="+", action=ListThenFolder,
                   read=one_of(SPECIES, "species"), default=None,
                   metavar="NAME", help=f"species to write (default: all of "
                   f"{', '.join(SPECIES)})")
    p.add_argument("--clips", type=positive_int, default=4,
                   help="clips per skeleton (default: 4)")
    p.add_argument("--seed", type=seed, default=0, help="random seed (default: 0)")
    p.add_argument("--frames", type=positive_int, default=120,
                   help="frames per clip, at least 2 (default: 120)")
    p.add_argument("--fps", type=float, default=30.0,
                   help="frames per second (default: 30)")
    p.add_argument("--kinds", nargs="+", action=ListThenFolder, default=None,
                   read=one_of(_ALL_KIND_NAMES, "clip kind"), metavar="KIND",
                   help="clip kinds to cycle through, of those each species can do "
                   "(default: every kind but the gestures; e.g. --species biped "
                   "--kinds bow wave, --species quadruped --kinds sit lie)")
    p.add_argument("--stance-bend", type=float, default=None, metavar="DEGREES",
                   help="the knee bend every rig stands at, 0 (upright) to under 90 "
                   "(default: the zoo's 36; a standing person's is 3-15); a "
                   "straighter-legged walker rises over each planted leg")
    d = p.add_argument_group("exporter dialects")
    d.add_argument("--up-axes", nargs="+", action=ListThenFolder, read=_axes, default=[["+Y"]],
                   metavar="AXIS", help=f"up axes to write ({', '.join(UP_AXES)}; a "
                   "proper rotation of the whole motion; default: +Y), as --up-axis "
                   "takes them: --up-axes +Z -X, --up-axes=+Z,-X or negX")
    d.add_argument("--units", nargs="+", action=ListThenFolder, read=_unit, default=["m"],
                   metavar="UNIT",
                   help=f"units to write: {', '.join(UNITS)}, or a number N for an "
                   "arbitrary unit in which the character is N units tall (default: m)")
    d.add_argument("--rest-poses", nargs="+", action=ListThenFolder,
                   read=one_of(REST_POSES, "rest pose"), default=["native"],
                   metavar="POSE", help=f"rest poses ({', '.join(REST_POSES)}; the "
                   "motion keeps its global positions; default: native)")
    d.add_argument("--name-noise", nargs="+", action=ListThenFolder,
                   read=one_of(("none",) + NOISE_STYLES, "name noise"),
                   default=["none"], metavar="STYLE",
                   help="exporter suffixes on joint names: none, tag (Tail_01__x7Q), "
                   "version (Tail_01_v2), hash (Tail_01_a1b2c3) (default: none)")
    d.add_argument("--dialect-variants", action="store_true",
                   help="instead: one clip per rig and up axis (all six unless "
                   "--up-axes is given), units, rest poses and name noise cycling "
                   "over rigs (a dialect benchmark; --clips is ignored)")
    p.set_defaults(func=run_zoo)
    return p


def run_zoo(args: argparse.Namespace) -> int:
    """Write the zoo and print a one-line summary per species."""
    if args.out_dir is None:
        raise ValueError("zoo: no output folder: satagraph zoo OUT_DIR [--species ...]")
    if not 1.0 <= args.fps <= 1000.0:  # also NaN
        raise ValueError(f"zoo: --fps must be between 1 and 1000, got {args.fps:g}")
    if args.frames < 2:
        raise ValueError(f"zoo: --frames must be at least 2 (a motion needs two frames "
                         f"for its velocities), got {args.frames}")
    start = time.perf_counter()
    if args.dialect_variants and args.stance_bend is not None:
        raise ValueError("zoo: --stance-bend is not drawn with --dialect-variants "
                         "(a dialect benchmark keeps the zoo's stance)")
    if args.dialect_variants:
        axes = _flat(args.up_axes)
        axes = UP_AXES if axes == ["+Y"] else axes
        variants = dialect_variants(args.seed, args.species, up_axes=axes)
        rows = write_dialect_zoo(args.out_dir, variants, seed=args.seed,
                                 fps=args.fps, frames=args.frames)
    else:
        rows = write_zoo(args.out_dir, species=args.species, clips=args.clips,
                         seed=args.seed, fps=args.fps, frames=args.frames,
                         dialects=_dialects(args), kinds=args.kinds,
                         stance_bend=args.stance_bend)
    for name in dict.fromkeys(r["species"] for r in rows):
        mine = [r for r in rows if r["species"] == name]
        skeletons = dict.fromkeys(f"{r['skeleton']} ({r['joints']} joints)"
                                  for r in mine)
        print(f"{name}: {len(mine)} clips on {', '.join(skeletons)}")
    print(f"wrote {len(rows)} BVH files and manifest.tsv to {args.out_dir} "
          f"in {time.perf_counter() - start:.1f} s")
    return 0


def _dialects(args: argparse.Namespace) -> List[Dialect]:
    """Every combination of the requested up axes, units, rest poses and
    name noises."""
    noises = [None if n == "none" else n for n in args.name_noise]
    combos = itertools.product(dict.fromkeys(_flat(args.up_axes)), dict.fromkeys(args.units),
                               dict.fromkeys(args.rest_poses), dict.fromkeys(noises))
    return [Dialect(*combo) for combo in combos]


def _flat(axes: List[List[str]]) -> List[str]:
    return [axis for group in axes for axis in group]
