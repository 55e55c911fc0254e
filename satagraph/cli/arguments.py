"""Argument types and argument groups shared by the ``satagraph`` commands
(imported without torch)."""
from __future__ import annotations

import argparse
from typing import List, Optional, Tuple

import numpy as np

from satagraph.io import read_bvh
from satagraph.motion import Motion


#: The value of ``--up-axis`` / ``--units`` that keeps detection for a file.
AUTO = "auto"


def positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (np.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"must be a positive number: {text!r}")
    return value


def up_axis(text: str) -> Optional[str]:
    """``"z"`` -> ``"+Z"``, ``"-y"`` -> ``"-Y"``; ``"auto"`` -> ``None``
    (detected, as without the option: ``--up-axis auto,z`` for two files)."""
    from satagraph.transforms.rig_reading import normalize_up_axis
    if text.strip().lower() == AUTO:
        return None
    try:
        return normalize_up_axis(text)
    except ValueError as err:
        raise argparse.ArgumentTypeError(str(err)) from None


def units(text: str):
    """A unit name (``cm``, ``in``, ...) or a factor to metres; ``"auto"``
    -> ``None`` (guessed, as without the option: ``--units auto,cm``)."""
    from satagraph.transforms.rig_reading import parse_units
    if text.strip().lower() == AUTO:
        return None
    try:
        return parse_units(text)
    except ValueError as err:
        raise argparse.ArgumentTypeError(str(err)) from None


def _each(parse):
    """An argument type of comma-separated values, each read by
    :obj:`parse` (``"cm,file"`` -> ``[0.01, "file"]``; one value stays
    itself: ``"cm"`` -> ``0.01``)."""
    def read(text: str):
        values = [parse(part.strip()) for part in text.split(",")]
        return values[0] if len(values) == 1 else values
    read.__name__ = parse.__name__
    return read


def add_rig_arguments(parser: argparse.ArgumentParser, prefix: str = "",
                      what: str = "the input", per_input: bool = False,
                      scale_free: bool = False) -> None:
    """``--[PREFIX-]up-axis`` and ``--[PREFIX-]units`` (alias
    ``--[PREFIX-]scale``): how to read a rig where detection guesses
    wrong. They are used as given, never re-guessed. With
    :obj:`per_input` (commands that read several files) each takes one
    value for every file or a comma-separated value per file, in order
    (``--units cm,cmu``: a dog in centimetres beside a CMU human). With
    :obj:`scale_free` (a command whose output is the same in any units: the
    models, contacts, grounding and planting read bodies in their own
    heights) the units' help says so, and :func:`~satagraph.cli.main` does
    not show the command's
    :class:`~satagraph.transforms.rig_reading.UnitsWarning`."""
    dash = f"--{prefix}-" if prefix else "--"
    wrap = _each if per_input else (lambda parse: parse)

    def each(example: str) -> str:
        return (f"; one for every file, or one per file in order, comma-separated "
                f"({example})" if per_input else "")
    parser.add_argument(f"{dash}up-axis", type=wrap(up_axis), default=None,
                        metavar="AXIS", help=f"up axis of {what} (+X, -X, +Y, "
                        "-Y, +Z, -Z; a bare letter means +; auto: detected) instead of "
                        "detecting it" + each("+Z,auto"))
    parser.add_argument(f"{dash}units", f"{dash}scale", type=wrap(units), default=None,
                        metavar="UNITS", help=f"units of {what}: m, cm, mm, in, "
                        "ft, cmu (CMU mocap units), mmd (MikuMikuDance's, 8 cm), file "
                        "(keep the file's own), a "
                        "factor to metres or auto (guessed), instead of guessing them"
                        + each("auto,cm") + (SCALE_FREE_NOTE if scale_free else ""))
    if scale_free:
        parser.set_defaults(scale_free=True)


#: What ``--units`` help adds for a command whose output is the same in any units.
SCALE_FREE_NOTE = ("; this command's output is the same in any units (the model reads a "
                   "body in its own heights), so units it cannot decide are not warned about")


def rig_overrides(args: argparse.Namespace) -> List[str]:
    """``--up-axis`` / ``--units`` of a command that reads its data through a
    training config (``train``, ``code-bank``, ``demo``) as
    ``data.preprocessing`` overrides."""
    out = []
    if args.up_axis:
        out.append(f"data.preprocessing.up_axis={args.up_axis}")
    if args.units:
        out.append(f"data.preprocessing.scale={args.units}")
    return out


def check_per_input(args: argparse.Namespace, count: int, prefix: str = "") -> None:
    """Refuse ``--up-axis`` / ``--units`` lists of
    :func:`add_rig_arguments` (``per_input``) whose length is neither one
    nor :obj:`count`."""
    key = f"{prefix}_" if prefix else ""
    for flag in ("up_axis", "units"):
        value = getattr(args, f"{key}{flag}", None)
        if isinstance(value, list) and len(value) not in (1, count):
            raise ValueError(f"--{flag.replace('_', '-')} has {len(value)} values for "
                             f"{count} files: give one for every file or one per file")


def read_with_rig(path: str, args: argparse.Namespace, prefix: str = "",
                  index: int = 0, manifest: Tuple[Optional[str], Optional[float]] = (None, None)
                  ) -> Motion:
    """Read a BVH file and attach the ``--up-axis`` / ``--units`` of
    :func:`add_rig_arguments` (a :obj:`manifest`'s up axis and scale
    where a flag is not given, the file's own declaration otherwise);
    :obj:`index` is the file's place among the inputs where the options
    give one value per file."""
    from satagraph.transforms.rig_reading import with_rig
    key = f"{prefix}_" if prefix else ""
    up, scale = (_pick(getattr(args, f"{key}{flag}", None), index)
                 for flag in ("up_axis", "units"))
    return with_rig(with_rig(read_bvh(path), *manifest), up, scale)


def _pick(value, index: int):
    """The value of input :obj:`index` of a per-input option."""
    if not isinstance(value, list):
        return value
    return value[0] if len(value) == 1 else value[index]


def positive_int(text: str) -> int:
    return _integer_from(text, 1)


def _integer_from(text: str, low: int) -> int:
    """An option's integer, :obj:`low` or more (one line otherwise)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    if value < low:
        raise argparse.ArgumentTypeError(f"must be at least {low}: {text!r}")
    return value


def seed(text: str) -> int:
    """A ``--seed``: a whole number from 0 to
    :data:`~satagraph.experiment.schema.MAX_SEED`, the range of a config's
    ``seed`` (``zoo --seed -1`` failed as ``expected non-negative integer``,
    ``generate --seed 1e20``'s digits as ``Overflow when unpacking long
    long`` once the model had loaded)."""
    from satagraph.experiment.schema import MAX_SEED
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    if not 0 <= value <= MAX_SEED:
        raise argparse.ArgumentTypeError(f"a seed from 0 to {MAX_SEED} is expected: {text!r}")
    return value


class ListThenFolder(argparse.Action):
    """A list option (``nargs="+"``) that hands a trailing value it cannot
    read to the command's positional :obj:`folder`, where that is not
    given yet: ``zoo --species hexapod DIR`` reads as ``zoo DIR --species
    hexapod`` (argparse alone reads ``DIR`` as a species). Each value goes
    through :obj:`read`, which returns it converted or raises
    :class:`argparse.ArgumentTypeError`; a value it refuses anywhere else
    is refused. The positional is a :class:`Folder` (``nargs="?"``), and
    the command refuses a run without it.

    Args:
        read: Converts and checks one value.
        folder: ``dest`` of the positional a trailing value may fill.
    """

    def __init__(self, option_strings, dest, read=str, folder: str = "out_dir", **kwargs):
        super().__init__(option_strings, dest, **kwargs)
        self.read, self.folder = read, folder

    def __call__(self, parser, namespace, values, option_string=None):
        values = list(values)
        if len(values) > 1 and getattr(namespace, self.folder, None) is None \
                and not self._readable(values[-1]):
            setattr(namespace, self.folder, values.pop())
        try:
            setattr(namespace, self.dest, [self.read(v) for v in values])
        except argparse.ArgumentTypeError as err:
            parser.error(f"argument {option_string}: {err}")

    def _readable(self, value: str) -> bool:
        try:
            self.read(value)
        except argparse.ArgumentTypeError:
            return False
        return True


class Folder(argparse.Action):
    """An optional positional (``nargs="?"``) that :class:`ListThenFolder`
    may have filled: argparse's empty match at the end of the line keeps
    it."""

    def __call__(self, parser, namespace, values, option_string=None):
        if values is not None or getattr(namespace, self.dest, None) is None:
            setattr(namespace, self.dest, values)


def one_of(choices, what: str = "value"):
    """An argument reader that accepts only :obj:`choices`."""
    def read(text: str) -> str:
        if text not in choices:
            raise argparse.ArgumentTypeError(
                f"invalid {what}: {text!r} (choose from {', '.join(choices)})")
        return text
    return read


__all__ = ["positive_float", "positive_int", "up_axis", "units", "add_rig_arguments",
           "check_per_input", "read_with_rig", "ListThenFolder", "Folder",
           "one_of", "seed", "rig_overrides"]


def add_plant_argument(parser: argparse.ArgumentParser, default: bool = False) -> None:
    """``--plant`` / ``--no-plant``: lower the body onto its standing feet
    and hold each foot still on the floor while it stands
    (:func:`~satagraph.transforms.foot_plant.plant_feet`), on by
    :obj:`default` or off."""
    parser.add_argument("--plant", action=argparse.BooleanOptionalAction, default=default,
                        help="lower the body onto its standing feet and hold each foot still "
                        "on the floor while it stands, bending the leg to reach it (a decoded "
                        "stride is often short and its feet glide; default: "
                        f"{'on' if default else 'off'})")


def add_refine_argument(parser: argparse.ArgumentParser) -> None:
    """``--refine STEPS``: fit each window's latent to the input before it
    is decoded (:meth:`~satagraph.lightning.MotionAutoencoderModule.refine_latent`)."""
    parser.add_argument("--refine", type=refine_steps, default=0, metavar="STEPS",
                        help="fit each window's latent to the input by STEPS gradient steps "
                        "through the frozen decoder before decoding it: closer to the input "
                        "on rigs the model never trained on (30 steps: the dog's error a "
                        "fifth of the encoder's alone), at a cost: a 51-s take took 102 s "
                        "instead of 13 on 2 CPU cores, its windows counted on stderr as they go "
                        "(default: 0, the encoder's latent)")


def refine_steps(text: str) -> int:
    """A ``--refine``: a whole number of steps, 0 or more."""
    return _integer_from(text, 0)


def add_settle_argument(parser: argparse.ArgumentParser) -> None:
    """``--settle``: hold the output's root still where its body stands
    still (:func:`~satagraph.transforms.still_root.settle_root`)."""
    parser.add_argument("--settle", action="store_true",
                        help="hold the root still where the decoded body stands still (a "
                        "foot on the ground, no limb moving): for clips in which the "
                        "character stands, sits or lies, which a decoder can drift away; "
                        "it also stops a sidestep whose decoded legs do not step "
                        "(default: off)")


def add_mirror_argument(parser: argparse.ArgumentParser, default: bool) -> None:
    """``--mirror/--no-mirror``: average the decoding with that of the
    input's mirror image (:mod:`~satagraph.transforms.mirror_average`)."""
    parser.add_argument("--mirror", action=argparse.BooleanOptionalAction, default=default,
                        help="also decode the left-right mirror image of the input(s) and "
                        "average the two readings (twice the model's time; a rig whose sides "
                        "do not pair by joint name has no mirror image: see --two-rests; "
                        f"default: {'on' if default else 'off'})")


def add_two_rests_argument(parser: argparse.ArgumentParser, default) -> None:
    """``--two-rests/--no-two-rests``: average the decoding with that of
    the rigs shown in a second rest pose
    (:func:`~satagraph.transforms.rest.second_rest`); :obj:`default`
    ``True``, ``False`` or ``"unmirrored"`` (only rigs without a mirror image)."""
    said = {True: "on", False: "off"}.get(default, "only for a rig without a mirror "
                                          "image, whose sides do not pair")
    parser.add_argument("--two-rests", action=argparse.BooleanOptionalAction, default=default,
                        help="also decode the input(s) with each rig shown in a second rest "
                        "pose (for --rest auto, the pose auto does not choose) and average "
                        "the readings (twice the model's time, four times with --mirror; "
                        f"default: {said})")


def add_carriage_argument(parser: argparse.ArgumentParser, what: str = "TARGET.bvh's") -> None:
    """``--carriage {auto,always,never}``: carry the output as its
    character carries itself in :obj:`what` frames
    (:func:`~satagraph.pipelines.inference.carried_as_character`)."""
    from satagraph.transforms.carriage import CARRIAGE_MODES
    parser.add_argument("--carriage", choices=CARRIAGE_MODES, default="auto",
                        help=f"carry the output as its character carries itself in {what} "
                        "frames (each joint's mean pose taken from them, the decoded swings "
                        "kept): auto where the output never puts down a limb the character "
                        "stands on there (a human's walk decoded onto a quadruped held the "
                        "forepaws up like hands), always, or never (the decoder's carriage); "
                        "default: auto")


def add_still_argument(parser: argparse.ArgumentParser) -> None:
    """``--still/--no-still``: keep a retarget's root still wherever its
    source's root stands still
    (:func:`~satagraph.transforms.still_root.hold_still_source`)."""
    parser.add_argument("--still", action=argparse.BooleanOptionalAction, default=True,
                        help="keep the output's root still wherever the source's root "
                        "stands still (a decoder can glide a body whose source stands "
                        "away; --no-still keeps the decoded path; default: on)")


def add_device_argument(parser: argparse.ArgumentParser, what: str) -> None:
    """``--device``: where :obj:`what` runs (:func:`check_device` refuses one
    this machine lacks)."""
    parser.add_argument("--device", default="cpu",
                        help=f"where to run {what}: cpu, cuda, cuda:1, ... (default: cpu)")


def check_device(device: str) -> None:
    """Refuse a ``--device`` torch cannot name, satagraph does not run on or
    this machine lacks (one line, before any file is read).

    Raises:
        ValueError: What is wrong with it.
    """
    if device == "cpu":  # the default: no torch import before the files are checked
        return
    import torch
    try:
        where = torch.device(device)
    except RuntimeError:
        raise ValueError(f"--device {device}: not a device (cpu, cuda, cuda:1, mps)") from None
    count = {"cpu": 1, "cuda": torch.cuda.device_count() if torch.cuda.is_available() else 0,
             "mps": int(torch.backends.mps.is_available())}.get(where.type)
    if count is None:
        raise ValueError(f"--device {device}: not a device satagraph runs on "
                         "(cpu, cuda, cuda:1, mps)")
    kind = where.type.upper()
    if count == 0:
        raise ValueError(f"--device {device}: no {kind} device on this machine")
    if (where.index or 0) >= count:
        raise ValueError(f"--device {device}: this machine has {count} {kind} device(s), "
                         f"{where.type}:0 to {where.type}:{count - 1}")
