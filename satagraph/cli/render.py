"""``satagraph render``: BVH files as 3D stick figures side by side.

Examples::

    satagraph render walk.bvh walk.gif
    satagraph render in.bvh out.bvh compare.mp4 --png sheet.png --max-frames 120

Motions are canonicalised first (Y up, facing +Z, root at the origin,
metres) unless ``--raw`` is given.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from typing import List, Sequence

from satagraph.cli.progress import ProgressLine
from satagraph.motion import Motion

OUTPUTS = (".gif", ".mp4")


def add_render_parser(subparsers: "argparse._SubParsersAction"
                      ) -> argparse.ArgumentParser:
    """Register ``satagraph render IN.bvh [MORE.bvh ...] OUT.gif|OUT.mp4
    [--png SHEET.png] [--fps N] [--max-frames N] [--raw]``.

    Args:
        subparsers: What :meth:`argparse.ArgumentParser.add_subparsers`
            returned.

    Returns:
        argparse.ArgumentParser: The ``render`` parser (``func`` is
        :func:`run_render`).
    """
    p = subparsers.add_parser(
        "render", help="render BVH files as 3D stick figures (GIF, MP4, PNG)",
        description="Render one or more BVH files side by side as 3D stick "
        "figures (shared axes and camera, ground grid, ground contacts in "
        "red, one titled panel per file) to an animated GIF or an MP4 "
        "(H.264, via the ffmpeg bundled with imageio-ffmpeg), optionally "
        "with a PNG contact sheet of six frames.",
        epilog="example: satagraph render a.bvh b.bvh out.gif --png sheet.png")
    p.add_argument("files", nargs="+", metavar="FILE",
                   help="input .bvh files, then the output .gif or .mp4")
    p.add_argument("--png", metavar="SHEET.png", default=None,
                   help="also write a PNG contact sheet")
    p.add_argument("--fps", type=float, default=None,
                   help="frames per second shown, every file resampled to it so that all "
                   "play in real time together (default: the first file's; a GIF's nearest "
                   "rate it plays exactly, at most 50)")
    p.add_argument("--max-frames", type=int, default=None, metavar="N",
                   help="render at most N frames (the clip is cut)")
    p.add_argument("--raw", action="store_true",
                   help="draw the files as they are (must be +Y up)")
    p.add_argument("--fit", action="store_true",
                   help="scale each panel to its own figure (default: one scale for all, "
                   "so that sizes compare: a crab beside a human is then a dot)")
    from satagraph.cli.arguments import add_rig_arguments
    add_rig_arguments(p, what="the inputs", per_input=True)
    p.set_defaults(func=run_render)
    return p


def own_scales(motions: Sequence[Motion], names: Sequence[str], fit: bool) -> bool:
    """Whether each panel is scaled to its own figure: when asked
    (``--fit``), or when several panels share a scale and the units of one
    are unknown (a dog in centimetres read as metres would dwarf a human
    beside it to a dot); one line names the files whose ``--units`` to give."""
    if fit or len(motions) < 2:
        return fit
    from satagraph.transforms.rig_reading import read_rig
    unknown = [name for motion, name in zip(motions, names) if read_rig(motion).units.kept]
    if unknown:
        print(f"satagraph: units unknown for {', '.join(unknown)} (pass --units): each panel "
              f"is scaled to its own figure", file=sys.stderr)
    return bool(unknown)


def _shown(motion: Motion, raw: bool) -> Motion:
    if raw:
        from satagraph.transforms.rig_reading import read_rig
        up = read_rig(motion).up
        if up.axis != "+Y" and not up.low_confidence:
            print(f"satagraph: warning: {motion.source}: --raw draws +Y up, and this rig "
                  f"reads {up.axis} up ({up.how}): it will lie on its side (drop --raw to "
                  "stand it up)", file=sys.stderr)
        return motion
    from satagraph.transforms.canonical import canonicalize
    return canonicalize(motion, fps=None)


def _split_files(files: List[str]) -> tuple:
    if len(files) < 2:
        raise ValueError("render needs at least one input .bvh and an "
                         "output .gif or .mp4")
    *inputs, output = files
    if os.path.splitext(output)[1].lower() not in OUTPUTS:
        raise ValueError(f"the last argument must be a .gif or .mp4 output, "
                         f"got {output!r}")
    return inputs, output


def run_render(args: argparse.Namespace) -> int:
    """Render the files and print what was written."""
    from satagraph.viz import render

    from satagraph.utils.files import check_output_path
    inputs, output = _split_files(args.files)
    if args.png is not None and os.path.splitext(args.png)[1].lower() != ".png":
        raise ValueError(f"--png {args.png}: the contact sheet is a .png file")
    for path in [output] + ([args.png] if args.png else []):
        check_output_path(path)  # before any frame is drawn: both or neither
    if args.fps is not None and not args.fps > 0:
        raise ValueError(f"--fps must be positive, got {args.fps}")
    if args.max_frames is not None and args.max_frames < 1:
        raise ValueError(f"--max-frames must be at least 1, got {args.max_frames}")
    from satagraph.cli.arguments import check_per_input
    check_per_input(args, len(inputs))
    from satagraph.cli.arguments import read_with_rig
    read = [read_with_rig(path, args, index=i) for i, path in enumerate(inputs)]
    titles = [os.path.basename(path) for path in inputs]
    fit = args.fit if args.raw else own_scales(read, titles, args.fit)
    motions = [_shown(motion, args.raw) for motion in read]
    start = time.perf_counter()
    progress = ProgressLine(sys.stderr, "frames drawn")
    try:
        count = render(motions, output, titles=titles, fps=args.fps,
                       max_frames=args.max_frames, sheet=args.png, fit=fit,
                       progress=progress)
    finally:
        progress.end()  # before an error too
    extra = f" and {args.png}" if args.png else ""
    print(f"wrote {output}{extra}: {len(motions)} panel(s), {count} frames "
          f"in {time.perf_counter() - start:.1f} s")
    return 0
