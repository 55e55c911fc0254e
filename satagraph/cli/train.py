"""``satagraph train | reconstruct | retarget | eval | export-weights | code-bank`` subcommands."""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import List, Optional, Sequence

from satagraph.cli.arguments import (add_device_argument, check_device, positive_float,
                                     positive_int, rig_overrides)
from satagraph.cli.folders import run_over_folder
from satagraph.cli.progress import ProgressLine
from satagraph.transforms.rest import REST_MODES


#: What the model commands do with a folder (their ``--help``).
FOLDER_NOTE = ("A folder {what} reads every .bvh below it and writes each result to the same "
               "path below a folder OUT (the model loaded once; a file that fails is said in "
               "one line and the others go on; exit code 2 if any failed).")


def _in_out(p: argparse.ArgumentParser, dest: str, metavar: str) -> None:
    """The input (a file or a folder) and output positionals of a model
    command, and ``--skip-existing``."""
    p.add_argument(dest, metavar=metavar, help="a .bvh file, or a folder of them")
    p.add_argument("output", metavar="OUT", help="the .bvh file to write, or the folder "
                   f"(created) for a folder {metavar}")
    p.add_argument("--skip-existing", action="store_true",
                   help="leave out every file whose result is already in OUT, whole (one "
                   "satagraph wrote to the end; a write that was stopped leaves none), so "
                   "that a folder run that was interrupted goes on, and (for a folder) "
                   "every file that another such run into OUT makes, so that two share "
                   "the work; the summary counts them. It trusts those results: ones written with another --ckpt or "
                   "other options are kept as they are (delete them, or leave the flag "
                   "out, to redo them)")


def _skip(args, output: str) -> bool:
    """Whether ``--skip-existing`` leaves out the single file :obj:`output`
    (said in one line)."""
    from satagraph.cli.folders import complete_output
    if not (args.skip_existing and complete_output(output)):
        return False
    print(f"{output}: skipped, already there (--skip-existing)")
    return True


def add_train_parsers(sub) -> None:
    """Register the model subcommands on an argparse subparsers object."""
    from satagraph.cli.arguments import (add_carriage_argument, add_mirror_argument,
                                         add_plant_argument, add_refine_argument,
                                         add_settle_argument, add_still_argument,
                                         add_two_rests_argument)
    p = sub.add_parser("train", help="train a model from a config",
                       description="Train from an omegaconf YAML config, one of the named "
                       "configs shipped with satagraph (a name it does not know lists them) "
                       "or a path, with dotted overrides, e.g. `satagraph train tiny "
                       "--data my_bvh_folder trainer.max_epochs=2 data.batch_size=8`. A named "
                       "config's data.sources may be the project's own data folder, which "
                       "an installed satagraph does not have: --data trains on yours.")
    p.add_argument("config", help="config name (tiny, sata_vae, ...) or path")
    p.add_argument("overrides", nargs="*", help="key.sub=value overrides")
    p.add_argument("--resume", action="store_true",
                   help="continue from the run's last checkpoint")
    p.add_argument("--init-from", metavar="CKPT",
                   help="start from another run's weights (fine-tuning): a checkpoint, "
                   "a run folder, a .safetensors weights file, builtin or builtin-wide "
                   "(builtin: the built-in generator in a text-to-motion config, e.g. "
                   "finetune_t2m_builtin)")
    p.add_argument("--init-normalizer", choices=("data", "checkpoint"), default="data",
                   help="with --init-from, the feature normaliser: refitted on this "
                   "config's data (default) or the checkpoint's own, so that its weights "
                   "see the features as they were trained to (needed to --blend the "
                   "fine-tune back with the checkpoint)")
    p.add_argument("--data", action="append", metavar="PATH", default=None,
                   help="a BVH folder or manifest to train on, in place of the config's "
                   "data.sources; repeat it for several (a folder without a manifest.tsv "
                   "is split 80/10/10 by file name; NAME=PATH names its dataset, else the "
                   "folder's name does)")
    _data_rig(p)
    p.set_defaults(func=run_train)

    p = sub.add_parser("reconstruct", help="encode and decode a BVH on its own skeleton",
                       description="Sliding-window reconstruction of IN.bvh into OUT.bvh. "
                       + FOLDER_NOTE.format(what="IN"))
    _common(p)
    _ground(p, default=False)
    add_settle_argument(p)
    add_refine_argument(p)
    add_mirror_argument(p, default=True)
    add_two_rests_argument(p, default="unmirrored")
    _in_out(p, "input", "IN")
    _rig(p, scale_free=True)
    p.set_defaults(func=run_reconstruct)

    p = sub.add_parser("retarget", help="transfer a motion onto another skeleton",
                       description="Retarget SOURCE.bvh onto TARGET.bvh's skeleton (any "
                       "species); OUT.bvh is in the target's axes, units and channel layout "
                       "at the source's frame rate. " + FOLDER_NOTE.format(what="SOURCE"))
    _common(p)
    _ground(p, default=True)
    add_plant_argument(p)
    add_settle_argument(p)
    add_still_argument(p)
    add_mirror_argument(p, default=False)
    add_two_rests_argument(p, default=False)
    add_carriage_argument(p)
    p.add_argument("--target", required=True, metavar="TARGET.bvh",
                   help="the skeleton to put the motion on; its frames, where it has any, "
                   "show how the character stands (--ground, --carriage); OUT is written "
                   "on its rig: joints, channels, rest offsets, axes and units")
    _in_out(p, "source", "SOURCE")
    _rig(p, what="SOURCE.bvh", scale_free=True)
    _rig(p, "target", "TARGET.bvh", scale_free=True)
    p.set_defaults(func=run_retarget)

    p = sub.add_parser("eval", help="metrics of a checkpoint on a split, per dataset",
                       description="Evaluate JR, RT, JP, FS, GP per dataset on a split "
                       "(with RT and JP over the clip's height, RT/H and JP/H, and SAME's "
                       "retarget error RE), each skeleton read in the rest pose reconstruct "
                       "shows it (--rest).")
    p.add_argument("--ckpt", required=True,
                   help="a checkpoint, a weights file, a run folder (its "
                   "checkpoints/last.ckpt), builtin or builtin-wide")
    p.add_argument("--split", default="test", choices=["train", "val", "test"],
                   help="which split of the data to score (default: test)")
    p.add_argument("--data", nargs="*", action="extend",
                   help="sources (default: the training sources; repeat it, as train's "
                   "--data, or list several)")
    p.add_argument("--json", metavar="FILE", help="also write the table as JSON")
    p.add_argument("--max-batches", type=int, default=None,
                   help="evaluate at most this many batches (default: the whole split)")
    p.add_argument("--on-error", choices=["raise", "skip"], default=None,
                   help="a file of the split that cannot be read: stop, naming every such "
                   "file (raise), or score the others with a warning naming them (skip; "
                   "default: the checkpoint's data.on_error)")
    _rest(p, "As reconstruct and retarget show it; file: as the checkpoint's data "
          "section may read it for training")
    p.add_argument("--retarget", action="store_true",
                   help="also the retarget error onto copies of each split file's "
                   "skeleton with paired ground truth: bone-scaled (internal) and "
                   "with a leaf chain dropped, a bone split and bones scaled (cross)")
    _data_rig(p)
    p.set_defaults(func=run_eval)

    p = sub.add_parser("export-weights", help="write a trained model as a safetensors "
                       "weights file", description="Write the weights of RUN (its "
                       "checkpoints/last.ckpt) or CKPT to OUT.safetensors with everything "
                       "needed to rebuild the model offline (config, normaliser, semantic "
                       "encoder, fps, window, training data, provenance). No pickle: "
                       "the file cannot carry code.")
    p.add_argument("source", metavar="RUN_OR_CKPT",
                   help="a run folder (its checkpoints/last.ckpt) or a checkpoint file")
    p.add_argument("output", metavar="OUT.safetensors",
                   help="the weights file to write (refused unless it ends in .safetensors)")
    p.add_argument("--half", action="store_true",
                   help="store the network in float16 (the normaliser stays float32)")
    p.add_argument("--force", action="store_true",
                   help="write a file over the 8 MB limit")
    p.add_argument("--training-data", metavar="TEXT",
                   help="what it was trained on (default: the run's data sources)")
    p.add_argument("--command", metavar="TEXT", help="the command that trained it")
    p.add_argument("--minutes", type=float, help="training wall time in minutes")
    p.add_argument("--machine", metavar="TEXT", help="where it was trained")
    p.add_argument("--note", metavar="TEXT", help="free-text provenance")
    p.add_argument("--decoder", metavar="RVQ.ckpt",
                   help="(a text-to-motion model) decode with this SATA-RVQ's decoder: "
                   "one fine-tuned from the generator's autoencoder with its encoder and "
                   "codebooks frozen (optim.frozen); refused for any other")
    p.add_argument("--length", metavar="T2M.ckpt",
                   help="(a text-to-motion model) draw durations with this generator's "
                   "length model: one trained from RUN_OR_CKPT with every other part "
                   "frozen (optim.frozen=[skeleton,masked,residual]); refused for any other")
    p.add_argument("--blend", metavar="BASE",
                   help="write (1 - ALPHA) * BASE + ALPHA * RUN_OR_CKPT instead (WiSE-FT): "
                   "BASE is what the fine-tune started from (a checkpoint, a weights "
                   "file, builtin or builtin-wide) and whose normaliser it kept "
                   "(train --init-normalizer checkpoint); keeps much of what the "
                   "fine-tune learnt with less of its drift")
    p.add_argument("--alpha", type=float, default=None,
                   help="with --blend, the fine-tune's share in [0, 1]")
    p.set_defaults(func=run_export_weights)

    p = sub.add_parser("code-bank", help="code a text-to-motion config's training windows "
                       "once, for fast training (data.code_bank)",
                       description="Draw WINDOWS training windows of a text-to-motion "
                       "config (module: t2m; every epoch of the endless zoo new rigs and "
                       "clips, augmented as in training), code them with its frozen "
                       "autoencoder (model.autoencoder) and write them to OUT.safetensors. "
                       "Train on it with `satagraph train CONFIG data.code_bank=OUT`.")
    p.add_argument("config", help="a text-to-motion config name or path")
    p.add_argument("output", metavar="OUT.safetensors",
                   help="the bank of drawn windows' codes and captions to write")
    p.add_argument("overrides", nargs="*", help="key.sub=value overrides")
    p.add_argument("--windows", type=positive_int, required=True,
                   help="windows to draw at least: batches are kept whole, and an "
                   "epoch's last batch may be short, so up to a batch more may come")
    p.add_argument("--max-minutes", type=positive_float, default=None,
                   help="stop drawing after this long and write the windows drawn "
                   "(default: no limit; Ctrl-C writes them too, exit code 130)")
    add_device_argument(p, "the autoencoder")
    p.add_argument("--swap-rigs", type=float, default=0.0, metavar="SHARE",
                   help="show this share of the captured human rigs' windows (CMU's, "
                   "CC_Base's: rigs of 20 windows or more, never the zoo's) on another "
                   "such rig's skeleton, codes and captions kept, so that a rig with one "
                   "captioned clip learns what the others do (default 0)")
    p.add_argument("--data", action="append", metavar="PATH", default=None,
                   help="a captioned BVH folder or manifest to draw from, in place of the "
                   "config's data.sources (repeat it for several; NAME=PATH names its "
                   "dataset); train on the bank with the same --data")
    _data_rig(p)
    p.set_defaults(func=run_code_bank)


def _common(p) -> None:
    p.add_argument("--ckpt", default="auto",
                   help="a checkpoint or run folder from `satagraph train`, a .safetensors weights "
                   "file from `satagraph export-weights`, builtin (weights shipped in "
                   "the package, best on humans and animals of four limbs or fewer), "
                   "builtin-wide (shipped too: every body plan of the zoo, insects, "
                   "crabs, spiders and snakes as well) or auto (the default: builtin, "
                   "or builtin-wide where a rig has six or more legs or none)")
    p.add_argument("--window", type=int, default=None,
                   help="frames per window (default: the training window)")
    p.add_argument("--overlap", type=int, default=None,
                   help="frames shared by consecutive windows, cross-faded from one "
                        "into the next (default: window / 4)")
    add_device_argument(p, "the model")
    _rest(p, "The output keeps the target file's rest pose either way")


def _rest(p, note: str) -> None:
    """``--rest``: how reconstruct, retarget and eval show each skeleton."""
    p.add_argument("--rest", choices=REST_MODES, default="auto",
                   help="the rest pose the model sees each skeleton in: the file's, its "
                   "first frame's pose, its mean pose over the frames in which the body "
                   "stands (standing), or auto (default): standing for rigs whose rest pose "
                   "is a line (every bone along its joint's X as Bandai's, or all up as "
                   "Reallusion's) or a captured pose, else the file's; alternate: the pose "
                   f"auto does not choose. {note}")


def _ground(p, default: bool) -> None:
    import argparse
    p.add_argument("--ground", action=argparse.BooleanOptionalAction, default=default,
                   help="move the output up or down by one constant so that its feet "
                   "stand where the input's do, in character heights, then raise each "
                   "frame that would sink onto the floor (--no-ground keeps the "
                   "decoder's root height; default: "
                   f"{'on' if default else 'off'})")


def _rig(p, prefix: str = "", what: str = "the input", scale_free: bool = False) -> None:
    from satagraph.cli.arguments import add_rig_arguments
    add_rig_arguments(p, prefix, what, scale_free=scale_free)


def _data_rig(p) -> None:
    _rig(p, what="every data file without its own setting (a manifest's "
         "up_axis / scale column or a data.sources entry's up_axis / units)")


def run_train(args) -> int:
    """Train; exit code 1 (one line on stderr) when a non-finite loss or
    gradient stopped the run, or another run holds the output folder."""
    from satagraph.experiment.config import load_config
    from satagraph.lightning.reliability import RunLockedError, TrainingStopped
    from satagraph.experiment.train import last_checkpoint, train
    if args.init_normalizer != "data" and not args.init_from:
        raise ValueError("--init-normalizer goes with --init-from CKPT")
    cfg = load_config(args.config, list(args.overrides) + rig_overrides(args))
    if args.data:
        cfg["data"]["sources"] = list(args.data)
    start = time.time()
    try:
        module, dm, trainer, run_dir = train(cfg, resume=args.resume,
                                             init_from=args.init_from,
                                             init_normalizer=args.init_normalizer)
    except (TrainingStopped, RunLockedError) as err:
        print(f"satagraph: error: {err}", file=sys.stderr)
        return 1
    except KeyboardInterrupt as err:
        if args.traceback:
            raise
        print(_interrupted(Path(cfg["output_dir"]), *err.args[:1]), file=sys.stderr)
        return 130
    best = trainer.checkpoint_callback.best_model_path
    skipped = f"; {len(dm.skipped)} bad files left out (skipped_files.txt)" \
        if dm.skipped else ""
    resumed = [c.resumed_step for c in trainer.callbacks
               if getattr(c, "resumed_step", None) is not None]
    if resumed and trainer.global_step == resumed[0]:
        print(f"nothing to train: {cfg['name']} stood at step {trainer.global_step}, where "
              "its limit stops it (raise trainer.max_steps, max_epochs or max_time to go "
              f"on); checkpoints in {run_dir / 'checkpoints'}")
        return 0
    done = (f"from step {resumed[0]} to {trainer.global_step} ({_epochs_done(trainer)})"
            if resumed else f"for {trainer.global_step} steps ({_epochs_done(trainer)})")
    print(f"trained {cfg['name']} {done} in "
          f"{time.time() - start:.0f} s; checkpoints in {run_dir / 'checkpoints'} "
          f"(best: {best or 'n/a'}, last: {last_checkpoint(trainer)}){skipped}")
    return 0


def _epochs_done(trainer) -> str:
    """The epochs a run has trained, a fraction where a limit of time or
    steps stopped it inside one (``trainer.current_epoch`` said 2 after 1.6)."""
    per_epoch = trainer.num_training_batches / max(trainer.accumulate_grad_batches, 1)
    if not per_epoch or per_epoch == float("inf"):
        return f"epoch {trainer.current_epoch}"
    epochs = trainer.global_step / per_epoch
    return (f"{epochs:.0f} epoch{'s' * (round(epochs) != 1)}" if abs(epochs - round(epochs)) < 0.05
            else f"{epochs:.1f} epochs")


def _interrupted(run_dir: Path, saved_step: Optional[int] = None) -> str:
    """The line for a training run stopped by Ctrl-C (or SIGTERM): the
    checkpoint the interrupt wrote (at :obj:`saved_step`), else where
    ``--resume`` goes on from, or that it has nothing to go on from yet."""
    from satagraph.lightning.reliability import LAST, PREVIOUS, epoch_checkpoints
    folder = run_dir / "checkpoints"
    if saved_step is not None:
        return (f"satagraph: interrupted at step {saved_step}, saved as {folder / LAST}: "
                "train --resume goes on from there")
    kept = [p for p in (folder / LAST, folder / PREVIOUS) if p.is_file()]
    kept += epoch_checkpoints(folder)  # what resume_checkpoint falls back to
    if kept:
        return (f"satagraph: interrupted: train --resume goes on from {kept[0]} "
                "(the steps after it are trained again)")
    return (f"satagraph: interrupted before {run_dir}'s first checkpoint "
            "(checkpoint.every_n_steps, every_minutes and each epoch's end write one): "
            "nothing to resume; run the command again without --resume")


def run_code_bank(args) -> int:
    """Write a code bank (:func:`~satagraph.data.code_bank.draw_code_bank`)."""
    import lightning as L
    import torch

    from satagraph.data.code_bank import (DrawInterrupted, check_swap_share, draw_code_bank,
                                          swap_skeletons)
    from satagraph.experiment.config import load_config
    from satagraph.experiment.train import build_datamodule, build_module, check_config
    from satagraph.utils.files import check_output_path
    check_swap_share(args.swap_rigs)
    check_device(args.device)
    cfg = load_config(args.config, list(args.overrides) + rig_overrides(args))
    if args.data:
        cfg["data"]["sources"] = list(args.data)
    cfg = check_config(cfg)
    if cfg["module"] != "t2m":
        raise ValueError(f"{args.config}: module {cfg['module']!r} is not a text-to-motion "
                         "model (module: t2m)")
    if cfg["data"].get("code_bank"):
        raise ValueError(f"{args.config}: a code bank is drawn from the sources; "
                         "unset data.code_bank")
    check_output_path(args.output, create_parent=True)
    if cfg["threads"]:
        torch.set_num_threads(int(cfg["threads"]))
    L.seed_everything(int(cfg["seed"]), workers=True)
    dm = build_datamodule(cfg)
    dm.setup("fit")
    module = build_module(cfg, dm).eval().to(args.device)
    loader = dm.train_dataloader()
    start = time.time()

    def batches(epoch: int):
        if hasattr(loader.sampler, "set_epoch"):
            loader.sampler.set_epoch(epoch)
        return (batch.to(args.device) for batch in loader)

    progress = ProgressLine(sys.stderr, "windows")
    interrupted = False
    try:
        bank = draw_code_bank(module, batches, args.windows, progress,
                              None if args.max_minutes is None else 60.0 * args.max_minutes)
    except DrawInterrupted as stop:  # Ctrl-C keeps what was drawn, as --max-minutes
        bank, interrupted = stop.bank, True
    finally:
        progress.end()  # before an error too
    bank = swap_skeletons(bank, args.swap_rigs, seed=int(cfg["seed"]))
    bank.data = {"sources": cfg["data"]["sources"], "window": int(cfg["data"]["window"])}
    bank.save(args.output)
    said = "satagraph: interrupted: " if interrupted else ""
    print(f"{said}wrote {len(bank)} windows ({bank.codes.size(0)} frames) of {cfg['name']} "
          f"to {args.output} in {time.time() - start:.0f} s", file=sys.stderr)
    return 130 if interrupted else 0


def motion_autoencoder(module, name: str, scored: bool = False):
    """:obj:`module`, refused (one line) where it is a text-to-motion model:
    ``retarget``, ``reconstruct`` and ``eval`` (:obj:`scored`: where it says
    what scores one) need a motion autoencoder."""
    if not hasattr(module, "embed"):
        where = ("; the repository's benchmarks/t2m.py --ckpt C --data FOLDER scores a "
                 "text-to-motion model on your captioned clips" if scored else "")
        raise ValueError(f"{name}: a text-to-motion model; this command needs a motion "
                         "autoencoder (builtin, builtin-wide, or a run of satagraph train "
                         f"with a SATA, SAME or padded model){where}")
    return module


def _load(args, motions: Sequence, paths: Sequence[str], cache: Optional[dict] = None):
    """The model of ``--ckpt`` (``auto``: the built-in one for the rigs of
    :obj:`motions`, :mod:`~satagraph.pipelines.builtin_choice`), saying on
    stderr which built-in model is used and why; with :obj:`cache` (a dict
    kept across the files of a folder), each model is loaded and named once."""
    from satagraph.io.weights import builtin_notice, check_weights, is_builtin
    from satagraph.pipelines.builtin_choice import AUTO, choose_builtin
    name, why = args.ckpt, ""
    if name == AUTO:
        name, reason = choose_builtin([m.skeleton for m in motions], paths)
        why = f"--ckpt auto ({reason}): "
    if cache is not None and name in cache:
        return cache[name], cache[name].embed
    check_weights(name)  # a missing file said before Lightning and the model code load
    from satagraph.experiment.train import load_module
    module = motion_autoencoder(load_module(name, map_location=args.device), name)
    if is_builtin(name):
        print(f"satagraph: {why}{builtin_notice(name=name)}", file=sys.stderr)
    if cache is not None:
        cache[name] = module
    return module, module.embed


def _read(args, key: str):
    """The BVH file ``args.<key>`` with its ``--[target-]up-axis`` /
    ``--[target-]units``."""
    from satagraph.cli.arguments import read_with_rig
    return read_with_rig(getattr(args, key), args, "target" if key == "target" else "")


def run_reconstruct(args) -> int:
    """Reconstruct a file, or every BVH file of a folder (:mod:`satagraph.cli.folders`)."""
    models: dict = {}
    check_device(args.device)  # before any file is read
    _check_windows(args)  # once, also for a folder of sources
    if Path(args.input).is_dir():
        _check_ckpt(args)  # once: not as a failure of every file, into a new folder
        return run_over_folder(args.input, args.output,
                               lambda src, out: _reconstruct_file(args, src, out, models),
                               "reconstructed", args.traceback, args.skip_existing)
    if not _skip(args, args.output):
        print(_reconstruct_file(args, args.input, args.output, models))
    return 0


def _check_ckpt(args) -> None:
    """Refuse a ``--ckpt`` file that cannot be read before a folder's files
    are read (``auto`` is checked once it is chosen, :func:`_load`; a single
    file is read first, before torch loads)."""
    from satagraph.io.weights import check_weights
    from satagraph.pipelines.builtin_choice import AUTO
    if args.ckpt != AUTO:
        check_weights(args.ckpt)


def _check_windows(args) -> None:
    """Refuse ``--window`` / ``--overlap`` before the model loads, naming
    the options: a negative overlap always, the pair where ``--window`` is
    given (else the window is the model's)."""
    from satagraph.data.validate import check_windows, default_windows
    given = " ".join(f"--{k} {v}" for k, v in (("window", args.window),
                                               ("overlap", args.overlap)) if v is not None)
    try:
        if args.overlap is not None and args.overlap < 0:
            raise ValueError("an overlap is 0 frames or more")
        if args.window is not None:
            check_windows(*default_windows(None, args.window, args.overlap))
    except ValueError as err:
        raise ValueError(f"{given}: {err}") from None


def _reconstruct_file(args, source: str, output: str, models: dict) -> str:
    from satagraph.cli.arguments import read_with_rig
    from satagraph.data.validate import check_motion
    from satagraph.utils.files import check_output_path
    check_output_path(output)
    motion = read_with_rig(source, args)
    check_motion(motion, source)  # before a model is chosen for it (auto) and loaded
    module, embed = _load(args, [motion], [source], models)
    from satagraph.io import write_bvh  # torch, PyG: after the files and --ckpt are checked
    from satagraph.pipelines.inference import reconstruct_motion
    line = ProgressLine(sys.stderr, "windows refined") if args.refine else None
    try:  # a refined long take is minutes: its windows are counted as they go
        out = reconstruct_motion(module, motion, embed, args.window, args.overlap, args.rest,
                                 args.ground, args.settle, args.mirror, args.two_rests,
                                 args.refine, None if line is None else line.add)
    finally:
        if line is not None:
            line.end()
    write_bvh(out, output)
    return f"wrote {output}: {out.num_frames} frames, {out.num_joints} joints"


def run_retarget(args) -> int:
    """Retarget a file, or every BVH file of a folder (:mod:`satagraph.cli.folders`),
    onto ``--target``."""
    from satagraph.data.validate import check_skeleton
    models: dict = {}
    check_device(args.device)  # before any file is read
    _check_windows(args)  # once, also for a folder of sources
    target = _read(args, "target")
    check_skeleton(target, args.target)  # once, also for a folder of sources
    if Path(args.source).is_dir():
        _check_ckpt(args)  # once: not as a failure of every file, into a new folder
        memos: dict = {}  # a Retargeter per model: the target's work done once, not per file
        return run_over_folder(args.source, args.output, lambda src, out: _retarget_file(
            args, src, target, out, models, memos), "retargeted", args.traceback,
            args.skip_existing)
    if not _skip(args, args.output):
        print(_retarget_file(args, args.source, target, args.output, models))
    return 0


def _retarget_file(args, source_path: str, target, output: str, models: dict,
                   memos: Optional[dict] = None) -> str:
    """Retarget one file; with :obj:`memos` (a dict kept across the files of
    a folder), what is computed of the target alone is computed once
    (:func:`_retargeter`)."""
    from satagraph.cli.arguments import read_with_rig
    from satagraph.data.validate import check_motion
    from satagraph.utils.files import check_output_path
    check_output_path(output)
    source = read_with_rig(source_path, args)
    check_motion(source, source_path)  # before a model is chosen for it (auto) and loaded
    module, embed = _load(args, [source, target], [source_path, args.target], models)
    from satagraph.io import write_bvh  # torch, PyG: after the files and --ckpt are checked
    out = _retargeter(args, module, embed, target, memos)(source)
    write_bvh(out, output)
    return (f"wrote {output}: {out.num_frames} frames of {source_path} on the "
            f"{out.skeleton.describe()} of {args.target}")


def _retargeter(args, module, embed, target, memos: Optional[dict] = None):
    """The :class:`~satagraph.pipelines.inference.Retargeter` of
    :obj:`module` onto :obj:`target` with the command's options; with
    :obj:`memos`, made once per model (``--ckpt auto`` may choose two), all
    sharing one :class:`~satagraph.pipelines.inference.RigMemo`."""
    from satagraph.pipelines.inference import Retargeter, RigMemo
    if memos is not None and module in memos:
        return memos[module]
    retarget = Retargeter(module, target, embed, args.window, args.overlap, rest=args.rest,
                          ground=args.ground, plant=args.plant, settle=args.settle,
                          still=args.still, mirror=args.mirror, two_rests=args.two_rests,
                          carriage=args.carriage,
                          memo=None if memos is None else memos.setdefault("target", RigMemo()))
    if memos is not None:
        memos[module] = retarget
    return retarget


def run_eval(args) -> int:
    from satagraph.pipelines.evaluation import (evaluate, format_table, scoring_data,
                                                split_loader)
    from satagraph.utils.files import atomic_write_text, check_output_path
    from satagraph.experiment.train import load_module
    if args.json:
        check_output_path(args.json)
    if args.max_batches is not None and args.max_batches < 1:
        raise ValueError(f"--max-batches must be at least 1, got {args.max_batches}")
    module = motion_autoencoder(load_module(args.ckpt), args.ckpt, scored=True)
    dm = scoring_data(module.meta.get("data") or {}, args.rest, args.data, args.up_axis,
                      args.units, args.split, args.on_error)
    if not len(dm.datasets[args.split]):
        raise ValueError(f"no windows in the {args.split!r} split of {dm.sources} (a "
                         "manifest's split column; a folder without one is split 80/10/10 "
                         "by file name: try another --split)")
    results = evaluate(module, split_loader(dm, args.split), args.max_batches)
    print(format_table(results))
    if args.retarget:
        _print_retarget(module, dm.datasets[args.split].files, results)
    if args.json:
        atomic_write_text(args.json, json.dumps(results, indent=2) + "\n")
    return 0


def _previous_provenance(source: str) -> dict:
    """``{"previous": ...}``: the provenance of a weights file re-exported
    (a new decoder, half precision), so that how it was first trained
    stays with it; ``{}`` for a checkpoint."""
    from satagraph.io.weights import is_weights_file, read_weights_metadata
    if not is_weights_file(source):
        return {}
    previous = read_weights_metadata(source).get("provenance") or {}
    return {"previous": previous} if previous else {}


def _blend(module, source: str, base: Optional[str], alpha: Optional[float]) -> dict:
    """``export-weights --blend BASE --alpha A``: loads the blend of
    :obj:`base` and :obj:`source` into :obj:`module` and returns its
    provenance (``{}`` without ``--blend``)."""
    if base is None:
        return {}
    from satagraph.experiment.blend import blend_state, check_blend_meta
    from satagraph.experiment.train import load_module
    from satagraph.io.weights import module_hyper_parameters, resolve_weights
    start = load_module(base)  # as a module: older files gain the buffers they lack
    check_blend_meta(module_hyper_parameters(start), module_hyper_parameters(module), base,
                     source)
    module.load_state_dict(blend_state(start.state_dict(), module.state_dict(), alpha,
                                       base, source))
    return {"blend": {"base": base, "alpha": float(alpha),
                      **_previous_provenance(resolve_weights(base))}}


def run_export_weights(args) -> int:
    from satagraph import __version__
    from satagraph.utils.files import check_output_path
    from satagraph.io.weights import save_weights
    from satagraph.experiment.train import load_module
    if (args.blend is None) != (args.alpha is None):  # before any file is read
        raise ValueError("--blend BASE and --alpha A go together")
    if not args.output.endswith(".safetensors"):  # "export-weights w.safetensors last.ckpt"
        raise ValueError(f"{args.output}: the weights file must end in .safetensors (the "
                         "order is RUN_OR_CKPT OUT.safetensors)")
    check_output_path(args.output)
    from satagraph.io.weights import resolve_weights
    source = resolve_weights(args.source) if os.path.isdir(args.source) else args.source  # a run
    module = load_module(source)
    for flag, part in (("decoder", "swap_decoder"), ("length", "swap_length")):
        if getattr(args, flag):
            if not hasattr(module, part):
                raise ValueError(f"--{flag}: {source} is not a text-to-motion model")
            getattr(module, part)(getattr(args, flag))
    blend = _blend(module, source, args.blend, args.alpha)
    provenance = {k: v for k, v in (("command", args.command), ("minutes", args.minutes),
                                    ("machine", args.machine), ("note", args.note))
                  if v is not None}
    provenance.update(source=source, satagraph_version=__version__,
                      **{k: getattr(args, k) for k in ("decoder", "length") if getattr(args, k)},
                      **blend, **_previous_provenance(source))
    size = save_weights(module, args.output, half=args.half,
                        training_data=args.training_data, provenance=provenance,
                        force=args.force)
    print(f"wrote {args.output}: {size / 2**20:.2f} MB "
          f"({'float16' if args.half else 'float32'} weights of {source})")
    return 0


def _print_retarget(module, files, results: dict) -> None:
    """Retarget error table (internal and cross settings) per dataset; the
    values go into :obj:`results` as ``retarget`` and ``retarget_cross``."""
    from satagraph.pipelines.evaluation import retarget_error_table
    table = retarget_error_table(module, files, module.embed)
    internal, cross = table["internal"], table["cross"]
    print("\n| dataset | retarget error internal (x1000 / H^2) | cross (x1000 / H^2) |\n"
          "|---|---|---|")
    for name in sorted(internal, key=lambda g: (g == "all", g)):
        print(f"| {name} | {internal[name]:.3f} | {cross[name]:.3f} |")
        results.setdefault(name, {}).update(retarget=internal[name],
                                            retarget_cross=cross[name])


__all__: List[str] = ["add_train_parsers"]
