r"""``satagraph demo``: the whole pipeline in minutes, with no data and no
network.

1. write the procedural zoo (:func:`satagraph.datasets.zoo.write_zoo`);
2. retarget a biped walk onto a quadruped, onto a bird and onto a
   differently proportioned human (:func:`satagraph.transforms.augment.scale_bones`,
   whose ground truth gives a retargeting error) with the built-in model,
   and score each retarget (:mod:`satagraph.pipelines.quality`: limbs in step with
   the source, root travel and stride against the source's);
3. render the four side by side (GIF and PNG contact sheet);
4. fine-tune the built-in model on the zoo for a few minutes
   (``experiments/demo.yaml``; or train from scratch, ``--from-scratch``,
   always so when no built-in weights ship or ``--data`` names the user's
   BVH folders and manifests) and score the same retargets with it;
5. print what was written where, how long each step took and the scores.

Example::

    from satagraph.experiment.demo import DemoOptions, run_demo
    result = run_demo(DemoOptions(output="demo_output", minutes=1.0))
    print(result.steps[-1].written)
"""
from __future__ import annotations

import contextlib
import json
import shutil
import sys
import time
import warnings
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Dict, Iterator, List, Optional, Sequence, TextIO, Tuple

import numpy as np
from satagraph.utils.files import atomic_write_text
from satagraph.motion import Motion

#: The species the retargeting step needs in the zoo.
REQUIRED_SPECIES: Tuple[str, ...] = ("biped", "quadruped", "bird")
#: The zoo species the demo writes by default: the body plans its retargets
#: need and the fowl (the other species on request). Every further body plan
#: slows how fast a few minutes of training learn limb timing (see
#: ``benchmarks/plan_mixing.py`` and experiments/PRETRAIN.md).
DEMO_SPECIES: Tuple[str, ...] = ("biped", "quadruped", "bird", "fowl")


@dataclass
class DemoOptions:
    r"""What :func:`run_demo` does.

    Args:
        output (str): Output folder (created).
        minutes (float, optional): Training time (``trainer.max_time``);
            ``None`` keeps the config's (4 minutes).
        data (list[str], optional): Train on these BVH folders / manifests
            instead of the zoo.
        species (list[str], optional): Zoo species (default:
            :data:`DEMO_SPECIES`; biped, quadruped and bird are always
            written).
        clips (int): Zoo clips per skeleton.
        frames (int): Frames per zoo clip.
        seed (int): Zoo seed; also the bone-scaling seed of the rescaled
            human.
        config (str): Training config (name in ``experiments/`` or path).
        overrides (list[str]): Dotted config overrides (``key.sub=value``),
            applied last.
        from_scratch (bool): Train a new model instead of fine-tuning the
            built-in one (always so when none ships).
    """

    output: str = "demo_output"
    minutes: Optional[float] = None
    data: Optional[List[str]] = None
    species: Optional[List[str]] = None
    clips: int = 4
    frames: int = 120
    seed: int = 0
    config: str = "demo"
    overrides: List[str] = field(default_factory=list)
    from_scratch: bool = False


@dataclass
class DemoStep:
    r"""One step of the demo: its name, wall time, the files it wrote and a
    one-line note."""

    name: str
    seconds: float = 0.0
    written: List[str] = field(default_factory=list)
    note: str = ""
    quality: Dict[str, Dict[str, Any]] = field(default_factory=dict)


@dataclass
class DemoResult:
    r"""What :func:`run_demo` did, step by step."""

    output: str
    steps: List[DemoStep] = field(default_factory=list)

    @property
    def seconds(self) -> float:
        return sum(s.seconds for s in self.steps)

    def to_dict(self) -> Dict[str, Any]:
        return {"output": self.output, "seconds": self.seconds,
                "steps": [asdict(s) for s in self.steps]}


@dataclass
class Panel:
    r"""One motion of the rendering: title, motion and the BVH file it was
    written to."""

    title: str
    motion: Motion
    path: str


class _Progress:
    """Short status lines around the steps, and their timing."""

    def __init__(self, result: DemoResult, total: int, stream: TextIO) -> None:
        self.result, self.total, self.stream = result, total, stream
        self.panels: List[Panel] = []

    def say(self, text: str) -> None:
        print(text, file=self.stream, flush=True)

    @contextlib.contextmanager
    def step(self, name: str, what: str) -> Iterator[DemoStep]:
        step = DemoStep(name)
        self.say(f"[{len(self.result.steps) + 1}/{self.total}] {what} ...")
        start = time.perf_counter()
        yield step
        step.seconds = time.perf_counter() - start
        self.result.steps.append(step)
        note = f": {step.note}" if step.note else ""
        self.say(f"      {name} done in {step.seconds:.1f} s{note}")


# ---------------------------------------------------------------- steps
def write_demo_zoo(folder: Path, options: DemoOptions) -> List[Dict[str, str]]:
    """Step 1: the procedural zoo (always with the species the retargeting
    needs)."""
    from satagraph.datasets.zoo import write_zoo

    species = list(options.species or DEMO_SPECIES)
    species += [s for s in REQUIRED_SPECIES if s not in species]
    return write_zoo(folder, species=species, clips=options.clips,
                     seed=options.seed, frames=options.frames)


def demo_config(options: DemoOptions, sources: Sequence[str], run_dir: Path,
                base: Optional[Dict[str, Any]] = None) -> Dict[str, Any]:
    """The training config: :attr:`DemoOptions.config` with the data
    sources, run folder and training time of the demo, then the user's
    overrides. With :obj:`base` (the built-in model's hyperparameters) the
    model, loss, window and facing smoothing are the built-in model's and
    the learning rate a fine-tune's."""
    from satagraph.experiment.config import load_config, merge_overrides
    from satagraph.experiment.schema import resolve_config

    cfg = load_config(options.config)
    cfg["data"]["sources"] = [str(s) for s in sources]
    cfg["output_dir"] = str(run_dir)
    if base is not None:
        from satagraph.data.dataset import data_facing_smooth
        cfg["model"], cfg["loss"] = dict(base["model"]), dict(base.get("loss") or {})
        meta = base.get("meta", {})
        cfg["data"]["window"] = int(meta.get("window", cfg["data"]["window"]))
        cfg["data"]["preprocessing"] = dict(cfg["data"].get("preprocessing") or {},
                                            facing_smooth=data_facing_smooth(meta.get("data")))
        cfg["optim"] = dict(cfg["optim"], **FINE_TUNE_OPTIM)
    if options.minutes is not None:
        cfg["trainer"]["max_time"] = {"minutes": float(options.minutes)}
    for item in options.overrides:
        if base is not None and item.startswith("model."):
            raise ValueError(f"override {item!r}: the fine-tune keeps the built-in "
                             "model's architecture; add --from-scratch to change it")
    return resolve_config(merge_overrides(cfg, options.overrides, options.config))


#: Optimiser settings of the demo's fine-tune from the built-in weights.
FINE_TUNE_OPTIM: Dict[str, Any] = {"lr": 3.0e-4, "warmup_epochs": 0}


def train_demo(cfg: Dict[str, Any], init_from: Optional[str] = None) -> Tuple[Any, Any]:
    """Step 2: train (from :obj:`init_from`'s weights when given); returns
    the trained module and the trainer."""
    from satagraph.experiment.train import train

    run_dir = Path(cfg["output_dir"])
    if (run_dir / "checkpoints").is_dir():  # the demo's own run of a previous call
        shutil.rmtree(run_dir / "checkpoints")
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", ".*does not have many workers.*")
        module, _, trainer, _ = train(cfg, init_from=init_from)
    return module, trainer


def builtin_module():
    """The built-in model, or ``None`` when this version ships none."""
    from satagraph.io.weights import builtin_path
    from satagraph.experiment.train import load_module

    return load_module("builtin").eval() if builtin_path().is_file() else None


def module_embedder(module, cache_dir: Optional[str] = None):
    """:meth:`module.embed <satagraph.lightning.MotionAutoencoderModule.embed>`,
    its text embeddings cached in :obj:`cache_dir`."""
    module.set_semantic_cache(cache_dir)
    return module.embed


def _rig(path: str) -> str:
    """``zoo0-quadruped-blender-tail_walk.bvh`` -> ``quadruped-blender-tail``."""
    name = Path(path).stem.rsplit("_", 1)[0]
    return name.split("-", 1)[1] if name.startswith("zoo") else name


def pick_clips(rows: Sequence[Dict[str, str]], zoo: Path) -> Dict[str, Path]:
    r"""The zoo clips of the retargeting step: the source (a biped walk,
    on the biped skeleton held out for testing when there is one) and a
    quadruped and a bird clip giving the target skeletons (the first of
    their species)."""
    def first(species: str, prefer_split: Optional[str] = None) -> Path:
        mine = [r for r in rows if r["species"] == species]
        walks = [r for r in mine if Path(r["path"]).stem.endswith("_walk")] or mine
        held = [r for r in walks if r["split"] == prefer_split]
        if not walks:
            raise ValueError(f"the zoo has no {species} clip")
        return zoo / (held or walks)[0]["path"]

    return {"source": first("biped", "test"), "quadruped": first("quadruped"),
            "bird": first("bird")}


def retarget_demo(module, embed, clips: Dict[str, Path], folder: Path, window: int,
                  seed: int = 0) -> Tuple[List[Panel], str, float, Dict[str, Dict]]:
    r"""Step 3: retarget the source walk onto the quadruped, the bird and a
    bone-scaled copy of the source's human skeleton, and write the BVH
    files (a copy of the source and the rescaled human's ground truth too).

    Returns:
        The panels (source first), the ground truth file, the mean joint
        position error of the rescaled human against it, relative to the
        height (see :func:`pose_error`), and per target the
        :func:`~satagraph.pipelines.quality.retarget_quality` of its retarget, its
        stride and ``lands`` (against the target's own clip) included (with
        the source's own root travel, ``source_travel``, in leg lengths).
    """
    from satagraph.transforms.augment import scale_bones
    from satagraph.pipelines.inference import from_canonical, retarget_canonical
    from satagraph.io import read_bvh, write_bvh
    from satagraph.pipelines.quality import retarget_quality, root_travel
    from satagraph.transforms.canonical import canonicalize

    source = read_bvh(clips["source"])
    human = scale_bones(source, 0.7, 1.3, seed=seed)
    folder.mkdir(parents=True, exist_ok=True)
    name = _rig(str(clips["source"]))
    panels = [Panel(f"source: {name}", source, str(folder / f"source_{name}.bvh"))]
    targets = [(f"quadruped: {_rig(str(clips['quadruped']))}", read_bvh(clips["quadruped"])),
               (f"bird: {_rig(str(clips['bird']))}", read_bvh(clips["bird"])),
               (f"rescaled human: {name}", human)]
    qualities: Dict[str, Dict] = {}
    for title, target in targets:
        src, canon = retarget_canonical(module, source, target, embed, window, window // 4)
        own = canonicalize(target, fps=src.fps)
        quality = retarget_quality(src, canon, ("steps", "travel", "stride", "ground",
                                                "upright", "lands"), target=own)
        qualities[title.split(":")[0]] = dict(quality, source_travel=root_travel(src))
        stem = title.split(": ")[1] + ("_rescaled" if title.startswith("rescaled") else "")
        panels.append(Panel(title, from_canonical(canon, source),
                            str(folder / f"walk_on_{stem}.bvh")))
    truth = str(folder / f"ground_truth_{name}_rescaled.bvh")
    for panel in panels:
        write_bvh(panel.motion, panel.path)
    write_bvh(human, truth)
    return panels, truth, pose_error(panels[-1].motion, human), qualities


def quality_note(qualities: Dict[str, Dict], error: float) -> str:
    """One line per model: each target's in-step correlation with the source
    (1 = every limb in step, 0 = chance or still), its root travel against
    the source's (1.00 = as far, in leg lengths) and its stride against the
    source's (how far the limb ends swing; where it is shorter than the
    travel, the feet skate) and how often the limbs the target's own clip
    stands on are down (``lands``: 1.00 as often, 0 a limb held up)."""
    parts = [f"{name} steps {q['steps']:+.2f} travel {q['travel']:.2f}x"
             + ("" if q.get("stride") is None else f" stride {q['stride']:.2f}x")
             + ("" if q.get("lands") is None else f" down {q['lands']:.2f}")
             for name, q in qualities.items()]
    return ("; ".join(parts) + f"; rescaled human joint error {100 * error:.1f}% of "
            "its height vs the bone-scaled ground truth")


def pose_error(motion: Motion, truth: Motion) -> float:
    r"""Mean root-relative joint position error of :obj:`motion` against
    :obj:`truth` (same skeleton and frames), relative to the height."""
    def relative(m: Motion) -> np.ndarray:
        pos = m.global_positions()
        return pos - pos[:, :1]
    err = np.linalg.norm(relative(motion) - relative(truth), axis=-1).mean()
    return float(err / max(truth.height(), 1e-8))


def render_demo(panels: Sequence[Panel], gif: Path, sheet: Path) -> int:
    """Step 4: the panels side by side (each canonicalised: facing +Z,
    starting at the origin) as a GIF and a PNG contact sheet."""
    from satagraph.transforms.canonical import canonicalize
    from satagraph.viz import render

    motions = [canonicalize(p.motion, fps=None) for p in panels]
    return render(motions, gif, titles=[p.title for p in panels], sheet=sheet)


# ----------------------------------------------------------------- main
def run_demo(options: DemoOptions, stream: TextIO = sys.stdout) -> DemoResult:
    r"""Run the whole demo into :attr:`DemoOptions.output`.

    With the built-in model (unless :attr:`DemoOptions.from_scratch`):
    zoo, retarget with the built-in model, render, a short fine-tune from it
    on the zoo, and the same retargets with the fine-tuned model. Without
    one: zoo, train from scratch, retarget, render.

    Args:
        options (DemoOptions): What to do.
        stream (TextIO): Where the status lines go.

    Raises:
        RunLockedError: Another live demo writes to the same output folder
            (it held the run whose checkpoints a second one removed).
        FileNotFoundError: A source of :attr:`DemoOptions.data` is missing.
        ValueError: The training config or an override is refused.

    Both said before anything is written (the zoo, the retargets and their
    rendering were, and left behind).
    """
    from satagraph.datasets.sources import resolve_sources
    from satagraph.lightning.reliability import run_lock
    if options.data:
        resolve_sources(options.data)
    out = Path(options.output)
    builtin = None if options.from_scratch or options.data else builtin_module()
    cfg = demo_config(options, options.data or [str(out / "zoo" / "manifest.tsv")],
                      out / "run", None if builtin is None else builtin.hparams)
    with run_lock(out, "--output"):
        return _run_demo(options, stream, builtin, cfg)


def _run_demo(options: DemoOptions, stream: TextIO, builtin, cfg: Dict[str, Any]
              ) -> DemoResult:
    """:func:`run_demo`'s steps, under its lock, with the built-in model
    (``None``: trained from scratch) and the training config."""
    out = Path(options.output)
    result = DemoResult(str(out))
    progress = _Progress(result, 4 if builtin is None else 5, stream)
    zoo = out / "zoo"
    with progress.step("zoo", f"writing the procedural zoo to {zoo}") as step:
        rows = write_demo_zoo(zoo, options)
        step.written = [str(zoo / "manifest.tsv")]
        step.note = (f"{len(rows)} BVH clips of {len({r['skeleton'] for r in rows})} "
                     f"skeletons ({', '.join(dict.fromkeys(r['species'] for r in rows))})")
    clips = pick_clips(rows, zoo)
    if builtin is not None:
        _retarget_step(progress, "retarget", "with the built-in model", builtin, clips,
                       out / "retarget", options.seed)
        _render_step(progress, result, out)
    what = ("fine-tuning the built-in model" if builtin is not None else
            f"training {cfg['name']} from scratch")
    with progress.step("train", f"{what} on {', '.join(cfg['data']['sources'])} "
                       f"(at most {_budget(cfg)})") as step:
        module, trainer = train_demo(cfg, None if builtin is None else "builtin")
        from satagraph.experiment.train import last_checkpoint
        step.written = [last_checkpoint(trainer)]
        step.note = _training_note(trainer)
    name = "retarget" if builtin is None else "fine-tuned"
    _retarget_step(progress, name, "with the trained model", module, clips,
                   out / ("retarget" if builtin is None else "retarget_finetuned"),
                   options.seed, cfg["data"]["cache_dir"])
    if builtin is None:
        _render_step(progress, result, out)
    _write_json(out / "summary.json", result.to_dict())
    return result


def _retarget_step(progress: _Progress, name: str, how: str, module, clips: Dict[str, Path],
                   folder: Path, seed: int, cache_dir: Optional[str] = None) -> None:
    from satagraph.pipelines.inference import default_windows

    with progress.step(name, f"retargeting a biped walk onto a quadruped, a bird and a "
                       f"rescaled human {how}") as step:
        panels, truth, error, qualities = retarget_demo(
            module, module_embedder(module, cache_dir), clips, folder,
            default_windows(module)[0], seed)
        step.written = [p.path for p in panels] + [truth]
        step.note = quality_note(qualities, error)
        step.quality = qualities
        progress.panels = panels


def _render_step(progress: _Progress, result: DemoResult, out: Path) -> None:
    with progress.step("render", "rendering the four side by side") as step:
        gif, sheet = out / "demo.gif", out / "demo_sheet.png"
        count = render_demo(progress.panels, gif, sheet)
        step.written = [str(gif), str(sheet)]
        step.note = f"{len(progress.panels)} panels, {count} frames"


def _budget(cfg: Dict[str, Any]) -> str:
    trainer = cfg.get("trainer") or {}
    limits = []
    if trainer.get("max_time"):
        minutes = trainer["max_time"]
        limits.append(f"{minutes.get('minutes', 0):g} min" if isinstance(minutes, dict)
                      else str(minutes))
    if trainer.get("max_steps", -1) not in (-1, None):
        limits.append(f"{trainer['max_steps']} steps")
    return " or ".join(limits) or f"{trainer.get('max_epochs')} epochs"


def _training_note(trainer) -> str:
    metrics = {k: float(v) for k, v in trainer.callback_metrics.items()
               if k in ("train_loss", "val_loss")}
    losses = ", ".join(f"{k} {v:.3f}" for k, v in sorted(metrics.items()))
    return (f"{trainer.current_epoch} epochs, {trainer.global_step} steps"
            + (f", {losses}" if losses else ""))


def _write_json(path: Path, value: Dict[str, Any]) -> None:
    atomic_write_text(path, json.dumps(value, indent=2) + "\n")


def format_summary(result: DemoResult) -> str:
    """The closing summary: each step's time and files."""
    lines = [f"satagraph demo: done in {result.seconds:.0f} s; everything is in "
             f"{result.output}/"]
    for step in result.steps:
        lines.append(f"  {step.name:<9} {step.seconds:7.1f} s  {step.note}")
        lines += [f"  {'':<9} {'':>9}  -> {path}" for path in step.written]
    lines.append(f"  {'summary':<9} {'':>9}  -> {Path(result.output) / 'summary.json'}")
    if any(step.quality for step in result.steps):
        lines.append("  steps: correlation of each limb end's forward swing with the source's "
                     "(+1 in step, 0 chance or standing still); travel: root distance in leg "
                     "lengths against the source's (1.00x = as far); stride: how far the limb "
                     "ends swing fore and aft against the source's (a stride shorter than the "
                     "travel: the feet skate); down: how often the limbs the target's own clip "
                     "stands on are on the floor, against that clip (1.00 as often; 0: a limb "
                     "held up, as a quadruped's forepaws carried like a human's hands)")
    return "\n".join(lines)


__all__ = ["DemoOptions", "DemoResult", "DemoStep", "Panel", "run_demo",
           "format_summary", "write_demo_zoo", "demo_config", "train_demo",
           "pick_clips", "retarget_demo", "render_demo", "pose_error", "quality_note",
           "builtin_module", "module_embedder", "FINE_TUNE_OPTIM"]
