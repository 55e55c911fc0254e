"""``satagraph zoo``: write the procedural skeleton zoo as BVH files.

Examples::

    satagraph zoo zoo/                                # every species
    satagraph zoo zoo/ --species quadruped snake --clips 6 --seed 3

The folder gets ``<species>/<skeleton>_<kind>.bvh`` files and a
``manifest.tsv`` usable as a training source.
"""
from __future__ import annotations

import argparse
import time

from satagraph.data.zoo import CLIP_KINDS, SPECIES, write_zoo


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1: {text!r}")
    return value


def add_zoo_parser(subparsers: "argparse._SubParsersAction"
                   ) -> argparse.ArgumentParser:
    """Register ``satagraph zoo OUT_DIR [--species ...] [--clips N]
    [--seed S] [--frames N] [--fps F]``.

    Args:
        subparsers: What :meth:`argparse.ArgumentParser.add_subparsers`
            returned.

    Returns:
        argparse.ArgumentParser: The ``zoo`` parser (``func`` is
        :func:`run_zoo`).
    """
    kinds = "; ".join(f"{s}: {', '.join(k)}" for s, k in CLIP_KINDS.items())
    p = subparsers.add_parser(
        "zoo", help="write procedural skeletons and motions (BVH + manifest)",
        description="Generate skeletons of several body plans (bipeds, "
        "quadrupeds with and without tails, birds, hexapods, snakes) with "
        "varied proportions and joint naming conventions, and physically "
        "sensible procedural motions (gaits with planted feet, turns, speed "
        "changes, idles), written as BVH files with a manifest.tsv. The same "
        f"seed gives the same files. Clip kinds cycle per skeleton: {kinds}.",
        epilog="example: satagraph zoo zoo/ --species quadruped bird --clips 5")
    p.add_argument("out_dir", help="output folder (created)")
    p.add_argument("--species", nargs="+", choices=SPECIES, default=None,
                   metavar="NAME", help=f"species to write (default: all of "
                   f"{', '.join(SPECIES)})")
    p.add_argument("--clips", type=_positive_int, default=4,
                   help="clips per skeleton (default: 4)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    p.add_argument("--frames", type=_positive_int, default=120,
                   help="frames per clip (default: 120)")
    p.add_argument("--fps", type=float, default=30.0,
                   help="frames per second (default: 30)")
    p.set_defaults(func=run_zoo)
    return p


def run_zoo(args: argparse.Namespace) -> int:
    """Write the zoo and print a one-line summary per species."""
    start = time.perf_counter()
    rows = write_zoo(args.out_dir, species=args.species, clips=args.clips,
                     seed=args.seed, fps=args.fps, frames=max(args.frames, 2))
    for name in dict.fromkeys(r["species"] for r in rows):
        mine = [r for r in rows if r["species"] == name]
        skeletons = dict.fromkeys(f"{r['skeleton']} ({r['joints']} joints)"
                                  for r in mine)
        print(f"{name}: {len(mine)} clips on {', '.join(skeletons)}")
    print(f"wrote {len(rows)} BVH files and manifest.tsv to {args.out_dir} "
          f"in {time.perf_counter() - start:.1f} s")
    return 0
