r"""The ``satagraph`` command line.

Every subcommand is registered by a small ``add_<name>_parser(subparsers)``
function that sets ``func`` (a function of the parsed arguments returning
an exit code or ``None``) with :meth:`~argparse.ArgumentParser.set_defaults`.
Subcommands living in other modules are listed in :data:`OPTIONAL_COMMANDS`
and registered when their module imports.

Exit codes: 0 on success, 2 on bad usage or bad input (a malformed BVH file,
a missing file, an unwritable output): one line ``satagraph: error: ...`` on
stderr, no traceback (``--traceback`` shows it).
"""
from __future__ import annotations

import argparse
import codecs
import contextlib
import gc
import importlib
import json
import os
import re
import signal
import sys
import tempfile
import threading
import warnings
from collections import Counter
from pathlib import Path
from typing import Any, Callable, Dict, Iterator, List, Optional, Sequence, Tuple

from satagraph import __version__
from satagraph.cli.arguments import (add_rig_arguments, positive_float, positive_int,
                                     read_with_rig, rig_overrides, seed)
from satagraph.io import BVHError
from satagraph.memory import retain_freed_memory
from satagraph.motion import Motion
from satagraph.utils.files import check_output_path

PROG = "satagraph"

#: Subcommands defined in other modules: ``(module, parser function)``.
#: A module that does not exist (yet) is skipped silently.
OPTIONAL_COMMANDS: Tuple[Tuple[str, str], ...] = (
    ("satagraph.cli.tags", "add_tags_parser"),
    ("satagraph.cli.train", "add_train_parsers"),
    ("satagraph.cli.zoo", "add_zoo_parser"),
    ("satagraph.cli.render", "add_render_parser"),
    ("satagraph.cli.sweep", "add_sweep_parser"),
    ("satagraph.cli.generate", "add_generate_parser"),
    ("satagraph.cli.cache", "add_cache_parser"),
)

Subparsers = argparse._SubParsersAction  # what add_subparsers() returns


class CommandError(Exception):
    """A user-facing failure: printed as one line, exit code 2."""


# ------------------------------------------------------------------ helpers
def _write(motion: Motion, path: str) -> None:
    from satagraph.io import write_bvh  # torch: loaded for the commands that write

    try:
        write_bvh(motion, path)
    except OSError as err:
        raise CommandError(f"cannot write {path}: "
                           f"{err.strerror or err}") from err


def describe(motion: Motion, path: str) -> Dict[str, Any]:
    """Summary of a motion as plain Python values (what ``inspect`` shows).

    ``rig`` is how the rig is read (:func:`~satagraph.transforms.rig_reading.read_rig`:
    up axis and units, each given, declared or guessed, with the confidence
    and the evidence); ``height`` is the character height in file units
    along that up axis and ``height_m`` in metres; ``bind_frame`` whether
    frame 0 is the rig's bind pose rather than motion
    (:func:`~satagraph.transforms.bind_frame.has_bind_frame`: it is read as
    frame 1's pose).
    """
    from satagraph.data.validate import DEFAULT_LIMITS
    from satagraph.transforms.bind_frame import has_bind_frame
    from satagraph.transforms.rig_reading import read_rig
    skel = motion.skeleton
    reading = read_rig(motion)
    rig = reading.to_dict()
    if motion.num_frames < DEFAULT_LIMITS.min_frames:
        rig["warnings"] = [*rig["warnings"], (
            f"{motion.num_frames} frame(s): a rig without motion; it serves as a target "
            f"skeleton, but motions need at least {DEFAULT_LIMITS.min_frames}")]
    layout = Counter(len(c) for c in skel.channels)
    return {
        "file": path,
        "root": skel.names[0],
        "joints": skel.num_joints,
        "joints_without_end_sites": int((~skel.end_site).sum()),
        "end_sites": int(skel.end_site.sum()),
        "frames": motion.num_frames,
        "fps": float(motion.fps),
        "duration": float(motion.duration),
        "up_axis": reading.up.axis,
        "height": reading.units.height,
        "height_m": reading.units.height * reading.units.scale,
        "rig": rig,
        "max_depth": int(skel.depth.max()),
        "rotation_orders": dict(sorted(Counter(
            o for o in skel.rotation_orders if o).items())),
        "channel_layout": {str(k): layout[k] for k in sorted(layout)},
        "position_channel_joints": int(skel.has_position_channels.sum()),
        "channels_per_frame": skel.num_channels,
        "bind_frame": has_bind_frame(motion),
    }


def _rig_rows(rig: Dict[str, Any]) -> List[Tuple[str, str]]:
    """The up-axis and unit rows of the ``inspect`` table."""
    how = rig["up_axis_how"]
    up = f"{rig['up_axis']} ({how}"
    if how == "detected":
        up += f", confidence {rig['up_axis_confidence']:.2f}"
    rows = [("up axis", up + ")")]
    for cue, scores in rig["up_axis_evidence"].items():
        ranked = sorted(scores, key=scores.get, reverse=True)[:3]
        rows.append((f"  {cue}", ", ".join(f"{a} {scores[a]:.2f}" for a in ranked)))
    units = ("file units kept (undecided)" if rig["units_how"] == "kept" else
             f"{rig['units']} ({rig['units_how']}, confidence "
             f"{rig['units_confidence']:.2f})")
    rows.append(("units", units if rig["units_how"] == "kept"
                  else f"{units}: {rig['units_reason']}"))
    rows += [("WARNING", w) for w in rig["warnings"]]
    return rows


def format_table(info: Dict[str, Any]) -> str:
    """The human-readable form of :func:`describe`."""
    orders = ", ".join(f"{o} x{n}" for o, n in info["rotation_orders"].items())
    layout = info["channel_layout"]
    channels = ", ".join(
        f"{n} joint{'s' * (n != 1)} with {k}" for k, n in layout.items())
    rows = [
        ("file", info["file"]),
        ("root", info["root"]),
        ("joints", f"{info['joints']} ({info['joints_without_end_sites']} "
                   f"without end sites)"),
        ("end sites", info["end_sites"]),
        ("frames", info["frames"]),
        ("fps", f"{info['fps']:g}"),
        ("duration", f"{info['duration']:.3f} s"),
        *_rig_rows(info["rig"]),
        ("height", f"{info['height']:.4g} file units, {info['height_m']:.4g} m"
                   + (" if the file units were metres" if info["rig"]["units_how"]
                      == "kept" else "")),
        ("depth", info["max_depth"]),
        ("rotation orders", orders or "none"),
        ("channels", f"{info['channels_per_frame']} per frame: {channels}"),
        ("position channels", f"on {info['position_channel_joints']} joint(s)"),
        ("frame 0", "none" if not info["frames"] else
         "the rig's bind pose, not motion: read as frame 1's pose"
         if info["bind_frame"] else "motion"),
    ]
    width = max(len(k) for k, _ in rows)
    return "\n".join(f"{k:<{width}}  {v}" for k, v in rows)


# ------------------------------------------------------------------ inspect
def run_inspect(args: argparse.Namespace) -> int:
    """Print the summary of a BVH file, or a line per file of a folder
    (:mod:`satagraph.cli.inspect_folder`)."""
    if Path(args.file).is_dir():
        from satagraph.cli.inspect_folder import run_inspect_folder
        return run_inspect_folder(args, lambda path, up_axis, scale: describe(
            read_with_rig(path, args, manifest=(up_axis, scale)), path))
    info = describe(read_with_rig(args.file, args), str(args.file))
    print(json.dumps(info, indent=2) if args.json else format_table(info))
    return 0


def add_inspect_parser(subparsers: Subparsers) -> argparse.ArgumentParser:
    """Register ``satagraph inspect FILE [--json]``."""
    parser = subparsers.add_parser(
        "inspect", help="summarise a BVH file, or every one of a folder",
        description="Summarise a BVH file: joints and end sites, frames, "
        "frame rate, duration, the up axis (with the confidence and evidence "
        "of its detection), the units and height, Euler rotation orders and "
        "channel layout, and whether frame 0 is the rig's bind pose rather than "
        "motion. Doubtful readings are flagged WARNING. Given a folder: "
        "one line per .bvh below it and a summary of their up axes, units and "
        "warnings (a dataset checked before training; a file that does not read "
        "is one error line, exit code 2).",
        epilog="examples: satagraph inspect walk.bvh --json; satagraph inspect mocap/")
    parser.add_argument("file", help="the .bvh file, or a folder of them")
    parser.add_argument("--json", action="store_true",
                        help="print a JSON object instead of a table")
    add_rig_arguments(parser)
    parser.set_defaults(func=run_inspect)
    return parser


# ------------------------------------------------------------------ convert
def run_convert(args: argparse.Namespace) -> int:
    """Re-write a BVH file, optionally resampled and/or canonicalised."""
    if (args.up_axis or args.units) and not args.canonical:
        raise CommandError("--up-axis and --units need --canonical")
    check_output_path(args.output)
    from satagraph.data.validate import (DEFAULT_LIMITS, check_resample, check_skeleton,
                                         check_writable)
    low, high = DEFAULT_LIMITS.min_fps, DEFAULT_LIMITS.max_fps
    if args.fps is not None and not low <= args.fps <= high:  # else written, then refused
        raise CommandError(f"--fps {args.fps:g}: satagraph reads {low:g} to {high:g} fps; "
                           "a file at this rate would be refused by its other commands")
    motion = read_with_rig(args.input, args)
    check_writable(motion, args.input)
    if args.canonical or args.fps:  # resampling: bounded memory, a sane skeleton
        check_resample(motion, args.input, args.fps)
        if args.canonical:
            check_skeleton(motion, args.input)
    notes = []
    if args.canonical:
        from satagraph.transforms.canonical import canonicalize
        motion = canonicalize(motion, fps=args.fps)
        tf = motion.transform
        if tf.source_rig.scale is None:  # the file's own units kept, undecided
            raise CommandError(f"{args.input}: its units are unknown, and a canonical file "
                               "declares metres: pass --units (cm, in, m, ... or a factor)")
        notes.append(f"canonical: source up axis {tf.up_axis}, scale {tf.scale:g} "
                     "to metres; the file declares itself +Y up in metres")
    elif args.fps:
        from satagraph.transforms.canonical import resample
        motion = resample(motion, args.fps)
    _write(motion, args.output)
    note = f" ({'; '.join(notes)})" if notes else ""
    print(f"wrote {args.output}: {motion.num_frames} frames at "
          f"{motion.fps:g} fps, {motion.num_joints} joints{note}")
    return 0


def add_convert_parser(subparsers: Subparsers) -> argparse.ArgumentParser:
    """Register ``satagraph convert IN OUT [--fps N] [--canonical]``."""
    parser = subparsers.add_parser(
        "convert", help="re-write a BVH file (resample, canonicalise)",
        description="Read a BVH file and write it again in a standard "
        "layout. Without options the channel values are kept exactly. "
        "--fps resamples (slerp for rotations); --canonical brings the "
        "motion to +Y up, facing +Z, root at the origin, metres (and "
        "folds an extra root joint above the hips into them, still or "
        "travelling) and the output declares "
        "itself canonical in a comment on its HIERARCHY line, so that satagraph never "
        "re-guesses its up axis or units. The output is replaced "
        "atomically, so IN and OUT may be the same file.",
        epilog="example: satagraph convert in.bvh out.bvh --fps 30 --canonical")
    parser.add_argument("input", help="the .bvh file to read")
    parser.add_argument("output", help="the .bvh file to write")
    from satagraph.data.validate import DEFAULT_LIMITS  # numpy alone
    parser.add_argument("--fps", type=positive_float, default=None,
                        help=f"resample to this frame rate ({DEFAULT_LIMITS.min_fps:g} "
                        f"to {DEFAULT_LIMITS.max_fps:g})")
    parser.add_argument("--canonical", action="store_true",
                        help="canonicalise (Y up, facing +Z, metres)")
    add_rig_arguments(parser, what="the input (with --canonical)")
    parser.set_defaults(func=run_convert)
    return parser


# --------------------------------------------------------------------- demo
def _quick_demo_path(output: Optional[str], tmp: str) -> str:
    """Where ``demo --quick`` writes the example: :obj:`output` when it
    names a ``.bvh`` file, ``example_walk.bvh`` in it when it is a folder,
    else in :obj:`tmp`."""
    if output is None:
        return str(Path(tmp) / "example_walk.bvh")
    if output.lower().endswith(".bvh"):
        return output
    Path(output).mkdir(parents=True, exist_ok=True)
    return str(Path(output) / "example_walk.bvh")


def _write_example(motion: Motion, path: str, tmp: str) -> None:
    """Write the example walk to :obj:`path`, refusing to replace a file
    that holds anything else (a motion the user named by mistake)."""
    draft = str(Path(tmp) / "draft.bvh")
    _write(motion, draft)
    target = Path(path)
    if target.exists() and (not target.is_file()
                            or target.read_bytes() != Path(draft).read_bytes()):
        raise CommandError(f"{path}: exists and is not the example walk (a motion of "
                           "yours?); give --output a new name or delete it first")
    _write(motion, path)


def run_quick_demo(args: argparse.Namespace) -> int:
    """Write the built-in example walk and inspect it (``demo --quick``)."""
    from satagraph.data.examples import example_motion

    motion = example_motion()
    with tempfile.TemporaryDirectory(prefix="satagraph-demo-") as tmp:
        path = _quick_demo_path(args.output, tmp)
        _write_example(motion, path, tmp)
        kept = "" if args.output else " (removed when the demo ends: --output PATH keeps it)"
        print(f"satagraph demo: wrote the built-in example walk, {motion.num_frames} "
              f"frames at {motion.fps:g} fps on a {motion.skeleton.describe()}, "
              f"to {path}{kept}")
        print(f"$ satagraph inspect {path}")
        return run_inspect(argparse.Namespace(file=path, json=args.json))


def run_demo(args: argparse.Namespace) -> int:
    """The whole pipeline on the procedural zoo (see :mod:`satagraph.experiment.demo`),
    or the built-in example with ``--quick``; exit code 1 (one line on stderr)
    when another live demo writes to the same output folder."""
    if args.quick:
        return run_quick_demo(args)
    from satagraph.experiment.demo import DemoOptions, format_summary
    from satagraph.experiment.demo import run_demo as run_full_demo
    from satagraph.lightning.reliability import RunLockedError

    options = DemoOptions(
        output=args.output or "demo_output", minutes=args.minutes, data=args.data,
        species=args.species, clips=args.clips, frames=args.frames, seed=args.seed,
        config=args.config, overrides=list(args.overrides) + rig_overrides(args),
        from_scratch=args.from_scratch)
    try:
        result = run_full_demo(options)
    except RunLockedError as err:  # another demo writes there
        print(f"{PROG}: error: {err}", file=sys.stderr)
        return 1
    print(json.dumps(result.to_dict(), indent=2) if args.json
          else format_summary(result))
    return 0


def add_demo_parser(subparsers: Subparsers) -> argparse.ArgumentParser:
    """Register ``satagraph demo [--quick] [--output DIR] [--minutes M]
    [--data PATH ...] [overrides ...]``."""
    from satagraph.datasets.zoo import SPECIES

    parser = subparsers.add_parser(
        "demo", help="the whole pipeline on built-in data (no data needed)",
        description="Run the whole pipeline on built-in data, with no data "
        "files and no network, in under 10 minutes on a CPU: (1) write the "
        "procedural zoo (bipeds, quadrupeds, birds, fowl) to "
        "OUTPUT/zoo; (2) retarget a biped walk onto a quadruped, a bird and a "
        "differently proportioned human with the built-in model "
        "(OUTPUT/retarget/*.bvh), scoring each (limbs in step with the source, "
        "root travel and stride against the source's); (3) render them side by side "
        "(OUTPUT/demo.gif, OUTPUT/demo_sheet.png); (4) fine-tune the built-in "
        "model on the zoo (the named config demo, 4 minutes; --minutes changes "
        "it) into OUTPUT/run and score the same retargets with it "
        "(OUTPUT/retarget_finetuned); (5) print what was written where, how "
        "long each step took and the scores. --from-scratch (or --data with "
        "your own BVH folders and manifests, or a version without built-in "
        "weights) trains a new model first and retargets with it. --quick "
        "only writes the built-in example walk (7 joints, 3 end sites, 60 "
        "frames at 30 fps) and inspects it, in seconds.",
        epilog="examples: satagraph demo --minutes 2 | satagraph demo --data "
        "my_bvh_folder --output runs/demo | satagraph demo --quick")
    parser.add_argument("overrides", nargs="*", metavar="KEY=VALUE",
                        help="dotted overrides of the training config, e.g. "
                        "data.batch_size=8 data.augment.scale=0.5")
    parser.add_argument("--quick", action="store_true",
                        help="only write and inspect the built-in example walk")
    parser.add_argument("--output", default=None, metavar="PATH",
                        help="output folder (default: demo_output); with "
                        "--quick, where to keep the example BVH file")
    parser.add_argument("--minutes", type=positive_float, default=None,
                        help="training time in minutes (default: the "
                        "config's, 4)")
    parser.add_argument("--data", nargs="+", action="extend", default=None, metavar="PATH",
                        help="train on these BVH folders / manifests instead "
                        "of the zoo (a folder without a manifest.tsv is split "
                        "80/10/10 by file name; NAME=PATH names its dataset)")
    parser.add_argument("--config", default="demo",
                        help="training config (default: demo)")
    parser.add_argument("--from-scratch", action="store_true",
                        help="train a new model instead of fine-tuning the "
                        "built-in one")
    parser.add_argument("--species", nargs="+", choices=SPECIES, default=None,
                        metavar="NAME", help="zoo species (default: biped, "
                        "quadruped, bird, fowl; biped, quadruped and "
                        "bird are always written)")
    parser.add_argument("--clips", type=positive_int, default=4,
                        help="zoo clips per skeleton (default: 4)")
    parser.add_argument("--frames", type=positive_int, default=120,
                        help="frames per zoo clip (default: 120)")
    parser.add_argument("--seed", type=seed, default=0,
                        help="zoo and bone-scaling seed (default: 0)")
    parser.add_argument("--json", action="store_true",
                        help="print the summary as JSON")
    add_rig_arguments(parser, what="every --data file without its own setting (a "
                      "manifest's up_axis / scale column), as train reads them")
    parser.set_defaults(func=run_demo)
    return parser


# ------------------------------------------------------------------- parser
def _warn(message: str) -> None:
    print(f"{PROG}: warning: {message}", file=sys.stderr)


def _add_optional_parsers(subparsers: Subparsers) -> None:
    """Register the subcommands of :data:`OPTIONAL_COMMANDS` whose module
    imports. A parser left without ``func`` gets the module's
    ``run_<name>`` function."""
    for module_name, function in OPTIONAL_COMMANDS:
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as err:
            if err.name != module_name:
                _warn(f"{module_name} unavailable ({err})")
            continue
        except Exception as err:  # a broken plugin must not break the rest
            _warn(f"{module_name} failed to import ({type(err).__name__}: {err})")
            continue
        before = set(subparsers.choices)
        getattr(module, function)(subparsers)
        for name in sorted(set(subparsers.choices) - before):
            parser = subparsers.choices[name]
            run = getattr(module, f"run_{name.replace('-', '_')}", None)
            if parser.get_default("func") is None and run is not None:
                parser.set_defaults(func=run)


PARSERS: List[Callable[[Subparsers], Any]] = [
    add_inspect_parser, add_convert_parser, add_demo_parser]


def build_parser() -> argparse.ArgumentParser:
    """The top-level parser with every available subcommand."""
    parser = argparse.ArgumentParser(
        prog=PROG, description="Topology-agnostic character motion: BVH "
        "tools for any skeleton. Run 'satagraph COMMAND --help' for details.")
    parser.add_argument("-V", "--version", action="version",
                        version=f"{PROG} {__version__}")
    parser.add_argument("--traceback", action="store_true",
                        help="show the full traceback on errors")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    subparsers.required = True
    for add in PARSERS:
        add(subparsers)
    _add_optional_parsers(subparsers)
    return parser


def _message(err: BaseException) -> str:
    if isinstance(err, OSError) and err.filename is not None:
        return f"{err.filename}: {err.strerror or err}"
    return _out_of_memory(err) or str(err)


#: How torch's CPU allocator says that it failed (a RuntimeError, not a MemoryError).
_CPU_ALLOCATION = re.compile(r"can't allocate memory: you tried to allocate (\d+) bytes")
#: How torch's GPU allocators (CUDA, MPS) say the size that failed, in a
#: message of several sentences about the device's memory.
_GPU_ALLOCATION = re.compile(r"Tried to allocate ([\d.]+ (?:[KMGT]i?B|bytes))")
#: A RuntimeError of a CUDA library (cuBLAS, cuDNN, a kernel launch) out of
#: GPU memory: ``CUDA error: out of memory``, then advice about debugging.
_GPU_LIBRARY_OUT = re.compile(r"CUDA error: out of memory|CUBLAS_STATUS_ALLOC_FAILED|"
                              r"CUDNN_STATUS_ALLOC_FAILED")


def _out_of_memory(err: BaseException) -> Optional[str]:
    """One line for an allocation that failed (Python's :class:`MemoryError`,
    torch's on the CPU or a GPU), ``None`` for any other error."""
    asked = _CPU_ALLOCATION.search(str(err))
    if asked:
        return f"out of memory: {int(asked.group(1)) / 2 ** 30:.1f} GiB asked for at once"
    if isinstance(err, MemoryError) or type(err).__name__ == "OutOfMemoryError":
        asked = _GPU_ALLOCATION.search(str(err))
        if asked:
            return f"out of memory on the GPU: {asked.group(1)} asked for at once"
        return f"out of memory: {' '.join(str(err).split()[:12]) or type(err).__name__}"
    if _GPU_LIBRARY_OUT.search(str(err)):  # a CUDA library's own allocation, no size said
        return "out of memory on the GPU (in a CUDA library, which says no size)"
    return None


def _format_warning(message, category, filename, lineno, line=None) -> str:
    """Warnings as one line: ``satagraph: warning: ...``."""
    return f"{PROG}: warning: {message}\n"


#: Options whose value may be a negative axis (``-Y``), which argparse
#: would take for an option.
_AXIS_OPTIONS = ("--up-axis", "--target-up-axis")
_NEGATIVE_AXIS = re.compile(r"^-[XYZxyz](,.*)?$")
#: List options of axes (``zoo --up-axes +Y -Z``), and what one of their values reads as.
_AXIS_LIST_OPTIONS = ("--up-axes",)
_AXIS_VALUE = re.compile(r"^([+-]|neg|pos)?[XYZ](,.*)?$", re.IGNORECASE)


def _glued_axes(argv: Sequence[str]) -> List[str]:
    """``--up-axis -Y`` as ``--up-axis=-Y``, and ``--up-axes +Y -Z`` as
    ``--up-axes=+Y,-Z``: argparse alone reads ``-Y`` as an option and says
    the value is missing."""
    out: List[str] = []
    for arg in argv:
        if out and out[-1] in _AXIS_OPTIONS and _NEGATIVE_AXIS.match(arg):
            out[-1] = f"{out[-1]}={arg}"
        else:
            out.append(arg)
    return _glued_axis_lists(out)


def _glued_axis_lists(argv: List[str]) -> List[str]:
    """The values after an option of :data:`_AXIS_LIST_OPTIONS` glued to it as
    one comma list where one of them begins with a minus."""
    out: List[str] = []
    i = 0
    while i < len(argv):
        out.append(argv[i])
        j = i + 1
        if argv[i] in _AXIS_LIST_OPTIONS:
            while j < len(argv) and _AXIS_VALUE.match(argv[j]):
                j += 1
            values = argv[i + 1:j]
            if any(v.startswith("-") for v in values):
                out[-1] = f"{argv[i]}={','.join(values)}"
            else:
                out += values
        i = j
    return out


def parse_args(parser: argparse.ArgumentParser,
               argv: Optional[Sequence[str]] = None) -> argparse.Namespace:
    """Parse :obj:`argv`, taking ``key=value`` overrides wherever they stand
    (also after an option such as ``--init-from CKPT``, where argparse alone
    would reject them), and a command's ``files`` (``render``) or ``items``
    (``sweep``'s configs and overrides) also after its options."""
    argv = _glued_axes(sys.argv[1:] if argv is None else argv)
    if "--traceback" in argv[1:]:  # also after the command's name
        argv = ["--traceback"] + [a for a in argv if a != "--traceback"]
    args, extra = parser.parse_known_args(argv)
    overrides = [a for a in extra if "=" in a and not a.startswith("-")]
    if hasattr(args, "overrides") and overrides:
        args.overrides = list(args.overrides or []) + overrides
        extra = [a for a in extra if a not in overrides]
    rest = next((getattr(args, key) for key in ("files", "items")
                 if isinstance(getattr(args, key, None), list)), None)
    if extra and rest is not None and not any(a.startswith("-") for a in extra):
        rest += extra  # `render A.bvh --units cm B.bvh OUT.gif`: files after an option
        extra = []
    if extra:
        parser.error(f"unrecognized arguments: {' '.join(extra)}")
    return args


def _is_utf8(stream: Any) -> bool:
    try:
        return codecs.lookup(getattr(stream, "encoding", None) or "utf-8").name == "utf-8"
    except LookupError:
        return False


def _escape(err: UnicodeEncodeError) -> Tuple[Any, int]:
    """Error handler: a file name's undecodable bytes as they were
    (``surrogateescape``), any other character as an escape."""
    try:
        return codecs.lookup_error("surrogateescape")(err)
    except UnicodeEncodeError:
        return codecs.backslashreplace_errors(err)


codecs.register_error("satagraph.escape", _escape)


@contextlib.contextmanager
def _escaped_output() -> Iterator[None]:
    r"""Write what the output's encoding lacks as escapes (``\u30bb``): a
    joint name or path printed to a cp1252 console or file (Windows) or
    in a C locale failed the command (``'charmap' codec can't encode``)."""
    changed = [(s, s.errors) for s in (sys.stdout, sys.stderr)
               if not _is_utf8(s) and hasattr(s, "reconfigure")]
    for stream, _ in changed:
        stream.reconfigure(errors="satagraph.escape")
    try:
        yield
    finally:
        for stream, errors in changed:
            stream.reconfigure(errors=errors)


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the ``satagraph`` command; returns the exit code.

    Args:
        argv (list[str], optional): Arguments (default: ``sys.argv[1:]``).
    """
    parser = build_parser()
    args = parse_args(parser, argv)
    retain_freed_memory()  # batches of frame graphs: no page faults per call
    before, shown = warnings.formatwarning, warnings.showwarning
    if not args.traceback:
        warnings.formatwarning = _format_warning
    warnings.showwarning = _once(shown, one_line=not args.traceback)
    try:
        with warnings.catch_warnings(), _escaped_output(), terminate_as_interrupt():
            if getattr(args, "scale_free", False):
                from satagraph.transforms.rig_reading import UnitsWarning
                warnings.simplefilter("ignore", UnitsWarning)
            if os.environ.get("SATAGRAPH_PLUGINS"):  # one's own modules and layers
                from satagraph.experiment.registry import import_user_plugins
                import_user_plugins()
            code = args.func(args)
    except BrokenPipeError:  # `satagraph inspect FOLDER | head`: the reader has gone
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except (BVHError, CommandError, OSError, ValueError) as err:
        if args.traceback:
            raise
        print(f"{PROG}: error: {_message(err)}", file=sys.stderr)
        return 2
    except ModuleNotFoundError as err:
        if args.traceback:
            raise
        print(f"{PROG}: error: {_missing_module(err)}", file=sys.stderr)
        return 2
    except (MemoryError, RuntimeError) as err:  # a --window of thousands of frames
        if args.traceback or _out_of_memory(err) is None:
            raise
        hint = " (a shorter --window needs less)" if hasattr(args, "window") else ""
        print(f"{PROG}: error: {_out_of_memory(err)}{hint}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        if args.traceback:
            raise
        print(f"{PROG}: interrupted (outputs are written whole or not at all)",
              file=sys.stderr)
        return 130
    finally:
        warnings.formatwarning, warnings.showwarning = before, shown
    return int(code or 0)



def run() -> None:
    """The ``satagraph`` console command (and ``python -m satagraph``):
    :func:`main` on ``sys.argv``, then exit with its code.

    Before exiting it moves every object into the collector's permanent
    generation (:func:`gc.freeze`), so the interpreter's final collection
    skips the hundreds of thousands that torch, PyG and Lightning leave:
    that collection took 1.2 s of each command on a 2-core CPU, longer than
    a retarget's own work. ``atexit`` handlers, buffered output and
    temporary-file clean-up still run. :func:`main` (what tests and other
    Python code call) leaves the collector alone.
    """
    code = main()
    gc.freeze()
    raise SystemExit(code)

#: Optional packages and the extra of ``setup.cfg`` that installs each.
EXTRAS = {"imageio_ffmpeg": "viz", "torch_scatter": "scatter", "sentencepiece": "dev",
          "pybvh": "bench"}


@contextlib.contextmanager
def terminate_as_interrupt() -> Iterator[None]:
    """SIGTERM (what a cluster sends before it kills a job, and ``kill`` and
    ``timeout`` send) stops a command as Ctrl-C does: the write under way is
    taken back, one line says so, exit code 130; by default it ended the
    process at once, without a line, the temporary file of that write left
    behind. Training stops at the end of its batch instead, saving
    ``last.ckpt`` (:func:`~satagraph.experiment.train.train`). The main
    thread's only; the handler before is put back."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt

    before = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, signal.SIG_DFL if before is None else before)


def _missing_module(err: ModuleNotFoundError) -> str:
    """One line for a package a command needs and this installation lacks."""
    name = (err.name or "").split(".")[0]
    if not name:  # a package's own message (Lightning's for TensorBoard)
        return " ".join(str(err).split())
    extra = EXTRAS.get(name)
    how = (f"pip install 'satagraph[{extra}]'" if extra
           else "reinstall satagraph (pip install satagraph) with its dependencies")
    return f"this command needs the Python package {name!r}, which is not installed: {how}"


def _once(show, one_line: bool = False):
    """:func:`warnings.showwarning` that shows each warning line once per
    command (a file's rig is read again at each step that canonicalises
    it), :obj:`one_line` as :func:`_format_warning` writes it: Lightning
    replaces :func:`warnings.formatwarning` when it is imported (after the
    command began) with one that put ``FILE:LINE:`` before every warning
    raised in a path holding "lightning" (``satagraph/lightning/`` too)."""
    seen = set()

    def show_once(message, category, filename, lineno, file=None, line=None):
        key = (category, str(message))
        if key not in seen:
            seen.add(key)
            if one_line:
                warnings.formatwarning = _format_warning
            show(message, category, filename, lineno, file, line)
    return show_once


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
