"""``satagraph generate``: a motion from a text prompt on any skeleton (see
:mod:`satagraph.pipelines.generate`)."""
from __future__ import annotations

import argparse
import re
import sys
import time
import warnings
from pathlib import Path
from typing import List


def _number(text: str) -> float:
    """A command-line number, or argparse's one-line error."""
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None


def _seconds(text: str) -> float:
    from satagraph.pipelines.generate_inputs import SECONDS_RANGE
    value = _number(text)
    if not SECONDS_RANGE[0] <= value <= SECONDS_RANGE[1]:
        raise argparse.ArgumentTypeError(f"must be between {SECONDS_RANGE[0]:g} and "
                                         f"{SECONDS_RANGE[1]:g} seconds: {text!r}")
    return value


def _window(text: str) -> float:
    """``--window`` and ``--residual-window``: 0 (whole clips) or at least
    half a second."""
    value = _number(text)
    if value != 0.0 and not 0.5 <= value <= 60.0:
        raise argparse.ArgumentTypeError(f"0 (whole clips) or between 0.5 and 60 seconds: "
                                         f"{text!r}")
    return value


def add_generate_parser(sub) -> None:
    """Register ``generate`` on an argparse subparsers object."""
    from satagraph.cli.arguments import (add_carriage_argument, add_device_argument,
                                         add_plant_argument, add_rig_arguments, seed)
    p = sub.add_parser(
        "generate", help="generate a motion from text on any skeleton",
        description="Generate a motion for a text prompt on the skeleton of TARGET.bvh "
        "(any species) with the built-in text-to-motion model or a checkpoint "
        "(`satagraph train t2m_tiny`). "
        "OUT.bvh is on the target's own rig: its axes, units, rest pose and channel "
        "layout. With several --skeleton files, one file per skeleton: "
        "OUT_<skeleton>.bvh beside OUT.bvh (or <skeleton>.bvh inside OUT when it is a "
        "folder). The same seed gives the same motion. Works offline. --prompts FILE "
        "generates one motion per line of FILE into the folder OUT, prompt i with seed "
        "SEED + i, and lists them in OUT/prompts.tsv.")
    p.add_argument("--ckpt", default="builtin",
                   help="a text-to-motion checkpoint, weights file or run folder (its "
                   "checkpoints/last.ckpt), or builtin (the "
                   "default: the small model shipped in the package)")
    what = p.add_mutually_exclusive_group(required=True)
    what.add_argument("--text", help="the prompt, e.g. \"a person walks "
                      "forward and turns left\"; an empty text generates for the skeleton "
                      "alone (the model is trained with some text dropped)")
    what.add_argument("--prompts", metavar="FILE", help="a text file of prompts, one per "
                      "line (blank lines and lines starting with # are skipped); OUT is then "
                      "a folder")
    p.add_argument("--literal", action="store_true",
                   help="give the model the prompt as written (default: a subject noun the "
                   "model never saw in training, e.g. \"dog\", is read as its own subject of "
                   "that body plan, \"four-legged animal\"; the words it never saw are named)")
    p.add_argument("--skeleton", required=True, nargs="+", metavar="TARGET.bvh",
                   help="BVH file(s) whose skeleton the motion is generated on")
    p.add_argument("--seconds", type=_seconds, default=None,
                   help="duration (default: drawn from the model's length model; longer than "
                   "the model's training window, generated in windows, see --window)")
    p.add_argument("--seed", type=seed, default=0, help="random seed (default 0)")
    p.add_argument("--guidance", type=float, default=4.0,
                   help="classifier-free guidance scale of the masked transformer "
                   "(default 4; 1: none; the text is dropped, never the skeleton)")
    p.add_argument("--steps", type=int, default=10, help="decoding steps (default 10)")
    p.add_argument("--guide", default="candidates", metavar="{candidates,logits}",
                   help="how guidance enters the masked transformer's draws: candidates (the "
                   "default: the guided logits choose the most likely tenth of the codes and "
                   "logits guided by --draw-guidance draw among them) or logits (MoMask's: "
                   "codes drawn from the guided logits, which makes gaits 30-45%% faster than "
                   "real ones)")
    p.add_argument("--draw-guidance", type=float, default=2.0,
                   help="with candidates, the guidance of the draw among the candidates "
                   "(default 2; 1: the text-conditioned logits)")
    p.add_argument("--residual-guide", default="logits", metavar="{logits,candidates}",
                   help="the same for the residual transformer (default logits: its guided "
                   "logits are what walks a person backward on a CMU rig)")
    p.add_argument("--window", type=_window, default=None, metavar="SECONDS",
                   help="generate a clip longer than this many seconds window after window, "
                   "each continuing the half window before it (default: the length the "
                   "model was trained on, 4 s for the built-in one; 0: the whole clip at "
                   "once, which past that length reads positions the model never learnt: "
                   "on the benchmark's test prompts the last stretch of a 12-s clip then "
                   "moves at 0.70 of the pace asked and matches its text with R@3 0.608 "
                   "against 0.824 in windows)")
    p.add_argument("--residual-window", type=_window, default=0.0, metavar="SECONDS",
                   help="fill the residual code layers in overlapping windows of this many "
                   "seconds (default 0: the whole clip at once). The built-in generator's "
                   "walks of three seconds or more speed up along the clip (+10 to +21 %% over "
                   "four seconds on the benchmark's probe rigs); 2 "
                   "holds their pace, at some cost to how closely the motion matches the "
                   "text on the benchmark")
    p.add_argument("--ground", action=argparse.BooleanOptionalAction, default=True,
                   help="put the motion on the floor: one vertical shift, its median lowest "
                   "joint at the floor, then each frame that would sink raised onto it "
                   "(--no-ground keeps the decoder's root height; default: on)")
    add_plant_argument(p, default=True)
    add_carriage_argument(p, "the skeleton files'")
    add_device_argument(p, "the generator")
    p.add_argument("--threads", type=int, default=1,
                   help="CPU threads (default 1: the generators are small, and extra "
                   "threads make a busy machine many times slower)")
    p.add_argument("--render", metavar="OUT.gif", default=None,
                   help="also render the generated motions side by side, one titled panel "
                   "per skeleton, to a GIF or an MP4 (as `satagraph render` draws them; "
                   "with --text)")
    p.add_argument("output", metavar="OUT.bvh", nargs="?",
                   help="output file (may also come last after the --skeleton files)")
    add_rig_arguments(p, "", "the skeleton files", per_input=True, scale_free=True)
    p.set_defaults(func=run_generate)


def _targets(args) -> list:
    """The skeleton files, read and checked (one line naming a bad file;
    one that shows no body, as ``retarget --target`` refuses it:
    :func:`~satagraph.data.validate.check_shown_body`)."""
    from satagraph.cli.arguments import check_per_input, read_with_rig
    from satagraph.data.validate import check_shown_body, check_skeleton, check_writable
    check_per_input(args, len(args.skeleton))
    out = []
    for i, path in enumerate(args.skeleton):
        motion = read_with_rig(path, args, index=i)
        check_skeleton(motion, path)
        check_shown_body(motion)
        check_writable(motion, path)
        out.append(motion)
    return out


def _split_output(args) -> None:
    """``--skeleton A.bvh B.bvh OUT.bvh``: the last path is the output when
    no other positional argument gave one."""
    if args.output is None:
        if len(args.skeleton) < 2:
            raise ValueError("generate: OUT.bvh is missing (the file to write; with "
                             "--prompts, the folder)")
        args.output = args.skeleton.pop()


def _spare_inputs(paths: List[str], skeletons: List[str]) -> None:
    """Refuse an output that would overwrite a skeleton given as input, or a
    BVH file satagraph did not write: ``--skeleton a.bvh clip.bvh`` without
    OUT makes ``clip.bvh`` the output."""
    from satagraph.io.bvh_reader import written_by_satagraph
    for path in paths:
        if not Path(path).is_file():
            continue
        if any(Path(s).is_file() and Path(path).samefile(s) for s in skeletons):
            raise ValueError(f"{path}: the output would overwrite an input skeleton; "
                             "give OUT.bvh a new name")
        if not written_by_satagraph(path):
            raise ValueError(f"{path}: exists and was not written by satagraph (a motion "
                             "of yours?); give OUT.bvh a new name or delete it first (with "
                             "several --skeleton files, the last path is OUT when none follows)")


def _prompt_folder(output: str) -> None:
    """Refuse an output of ``--prompts`` that is a file or named as one."""
    folder = Path(output)
    if folder.suffix.lower() == ".bvh" or (folder.exists() and not folder.is_dir()):
        raise ValueError(f"{output}: not a folder: with --prompts, OUT is the folder the "
                         "motions go to")


def _prompt(module, text: str, literal: bool, where: str = ""):
    """The prompt the model is given (``None``: unconditional), with a
    note on stderr where it was read in the model's words or holds words
    the model never saw (:obj:`where`: which prompt of a ``--prompts`` file)."""
    from satagraph.pipelines.prompt_reading import has_words, read_prompt, vocabulary_of
    if text and not has_words(text):  # "!!!": the encoder would read noise
        print(f"satagraph: {where}the prompt {text!r} has no words: the motion is drawn "
              "without text, as --text '' draws it", file=sys.stderr)
        return None
    if not text:
        return None
    reading = read_prompt(text, vocabulary_of(module), subjects=not literal)
    note = reading.note()
    if note:
        keep = " (--literal keeps the prompt as written)" if reading.replaced else ""
        print(f"satagraph: {where}the generator {note}{keep}", file=sys.stderr)
    return reading.text


def read_prompts(path: str) -> List[str]:
    """The prompts of a ``--prompts`` file: one per line, blank lines and
    ``#`` comments skipped.

    Raises:
        ValueError: An unreadable file, not UTF-8, or one without prompts
            (one line naming it).
    """
    from satagraph.utils.files import check_input_file
    check_input_file(path, "prompts file")
    try:
        lines = Path(path).read_text(encoding="utf-8").splitlines()
    except UnicodeDecodeError as err:
        raise ValueError(f"{path}: not UTF-8 text ({err.reason} at byte {err.start})") from None
    prompts = [line.strip() for line in lines]
    prompts = [p for p in prompts if p and not p.startswith("#")]
    if not prompts:
        raise ValueError(f"{path}: no prompts (one per line; # starts a comment)")
    return prompts


def prompt_stem(index: int, text: str) -> str:
    """A file stem for prompt :obj:`index`: ``007_a-person-walks-forward``."""
    slug = "-".join(re.findall(r"[a-z0-9]+", text.lower()))[:40].strip("-")
    return f"{index:03d}_{slug or 'prompt'}"


def _settings(args):
    """The :class:`~satagraph.pipelines.generate.GenerationSettings` of the
    options (a ``--guide`` / ``--residual-guide`` it does not know refused,
    a number it refuses said as its option: ``--draw-guidance must be ...``),
    with torch on ``--threads`` threads."""
    import torch
    from satagraph.nn.generators.sampling import check_guide
    from satagraph.pipelines.generate import GenerationSettings, SettingError
    for guide in (args.guide, args.residual_guide):
        check_guide(guide)
    torch.set_num_threads(args.threads)
    try:
        return GenerationSettings(steps=args.steps, guidance=args.guidance,
                                  ground=args.ground, plant=args.plant,
                                  residual_window=args.residual_window, window=args.window,
                                  guide=args.guide, draw_guidance=args.draw_guidance,
                                  residual_guide=args.residual_guide, carriage=args.carriage)
    except SettingError as err:  # "draw_guidance must be ...": the field, named as its option
        raise ValueError(f"--{err.field.replace('_', '-')} {err.problem}") from None


def run_generate(args) -> int:
    from satagraph.pipelines.generate_inputs import output_paths
    from satagraph.utils.files import check_output_path
    from satagraph.cli.arguments import check_device
    check_device(args.device)  # before any file is read
    _split_output(args)
    prompts = read_prompts(args.prompts) if args.prompts is not None else None
    if prompts is not None:
        _prompt_folder(args.output)
    if args.threads < 1:
        raise ValueError(f"--threads must be at least 1, got {args.threads}")
    paths = [] if prompts is not None else output_paths(args.output, args.skeleton)
    for path in paths + ([args.render] if args.render else []):
        check_output_path(path)
    _spare_inputs(paths, args.skeleton)
    _check_render(args)
    targets = _targets(args)
    from satagraph.io.weights import BUILTIN_VARIANTS, check_weights
    if args.ckpt not in BUILTIN_VARIANTS:  # load_generator says what those are
        check_weights(args.ckpt, kind="text-to-motion")  # a missing file, before the model code
    settings = _settings(args)  # torch and the model code: after the files are checked
    from satagraph.pipelines.generate import generate_on, load_generator, write_all
    from satagraph.io.weights import BUILTIN, builtin_notice
    module = load_generator(args.ckpt).to(args.device)
    if args.ckpt == BUILTIN:
        print(f"satagraph: {builtin_notice('text-to-motion')}", file=sys.stderr)
    if args.prompts is not None:
        return _generate_prompts(args, module, targets, prompts, settings)
    start = time.time()
    text = _prompt(module, args.text.strip(), args.literal)
    motions = [generate_on(module, text, t, args.seconds, args.seed, settings)
               for t in targets]
    write_all(motions, paths)
    took = time.time() - start
    for motion, path, source in zip(motions, paths, args.skeleton):
        print(f"wrote {path}: {motion.num_frames} frames ({motion.duration:.2f} s at "
              f"{motion.fps:g} fps) on the {motion.skeleton.describe()} of {source}")
    print(f"generated in {took:.2f} s")
    if args.render:
        _render(motions, args)
    return 0


def _check_render(args) -> None:
    """``--render`` names a GIF or an MP4, and goes with ``--text``."""
    if args.render is None:
        return
    from satagraph.cli.render import OUTPUTS
    if args.prompts is not None:
        raise ValueError("--render goes with --text (render a --prompts folder with "
                         "`satagraph render`)")
    if Path(args.render).suffix.lower() not in OUTPUTS:
        raise ValueError(f"--render: {args.render} is not a .gif or .mp4 file")
    if Path(args.render).suffix.lower() == ".mp4":
        import imageio_ffmpeg  # noqa: F401  (the viz extra): missing is said before any work


def _render(motions, args) -> None:
    """``--render``: the generated motions side by side, canonicalised as
    their skeleton files were read, one panel per skeleton (each to its own
    scale where the units of one are unknown, :func:`~satagraph.cli.render.own_scales`)."""
    from satagraph.cli.render import own_scales
    from satagraph.transforms.canonical import canonicalize
    from satagraph.transforms.rig_reading import RigReadingWarning
    from satagraph.viz import render
    titles = [Path(s).name for s in args.skeleton]
    fit = own_scales(motions, titles, False)
    with warnings.catch_warnings():  # said when the skeleton files were read
        warnings.simplefilter("ignore", RigReadingWarning)
        shown = [canonicalize(m, fps=None) for m in motions]
    count = render(shown, args.render, titles=titles, fit=fit)
    print(f"wrote {args.render}: {len(shown)} panel(s), {count} frames")


def _generate_prompts(args, module, targets, prompts: List[str], settings) -> int:
    """``--prompts``: every prompt on every skeleton into the folder
    ``args.output``, prompt i with seed ``args.seed + i``; a prompt that
    fails is said in one line and the others go on (exit code 2).
    ``prompts.tsv`` lists what is written as it is written (an interrupt
    left none, or an earlier run's)."""
    from satagraph.pipelines.generate import generate_on, output_paths, rig_inputs, write_all
    from satagraph.utils.files import atomic_write_text
    from satagraph.cli.folders import each_kept
    start = time.time()
    rigs = [rig_inputs(module, t, settings.rest) for t in targets]  # once, not per prompt
    Path(args.output).mkdir(parents=True, exist_ok=True)
    table, listed = Path(args.output) / "prompts.tsv", ["path\tprompt\tskeleton\tseconds\tseed"]
    atomic_write_text(table, listed[0] + "\n")

    def one(item) -> List[str]:
        i, prompt = item
        paths = output_paths(str(Path(args.output) / f"{prompt_stem(i, prompt)}.bvh"),
                             args.skeleton)
        text = _prompt(module, prompt, args.literal, f"prompt {i + 1} ({prompt!r}): ")
        motions = [generate_on(module, text, rig, args.seconds, args.seed + i, settings)
                   for rig in rigs]
        write_all(motions, paths)
        listed.extend("\t".join([Path(path).name, " ".join(prompt.split()), source,
                                 f"{motion.duration:.2f}", str(args.seed + i)])
                      for motion, path, source in zip(motions, paths, args.skeleton))
        atomic_write_text(table, "\n".join(listed) + "\n")
        return paths

    done, failed = each_kept(list(enumerate(prompts)), one, lambda item, err: (
        f"{args.prompts}: prompt {item[0] + 1} ({item[1]!r}): {err}"), args.traceback)
    print(f"generated {len(listed) - 1} motions of {len(done)} of {len(prompts)} "
          f"prompts into {args.output} in {time.time() - start:.1f} s (listed in prompts.tsv)")
    return 2 if failed else 0


__all__: List[str] = ["add_generate_parser", "read_prompts", "prompt_stem"]
