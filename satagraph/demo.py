r"""``satagraph demo``: the whole pipeline in minutes, with no data and no
network.

1. write the procedural zoo (:func:`satagraph.data.zoo.write_zoo`);
2. train a small SATA-VAE on it (``experiments/demo.yaml``) for a few
   minutes, or on the user's BVH folders and manifests instead;
3. retarget a biped walk onto a quadruped, onto a bird and onto a
   differently proportioned human (:func:`satagraph.data.augment.scale_bones`,
   whose ground truth gives a retargeting error);
4. render the four side by side (GIF and PNG contact sheet);
5. print what was written where and how long each step took.

Example::

    from satagraph.demo import DemoOptions, run_demo
    result = run_demo(DemoOptions(output="demo_output", minutes=1.0))
    print(result.steps[-1].written)
"""
from __future__ import annotations

import contextlib
import json
import sys
import time
import warnings
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Dict, Iterator, List, Optional, Sequence, TextIO, Tuple

import numpy as np
from omegaconf import OmegaConf

from satagraph.io.files import atomic_write_text
from satagraph.motion import Motion

#: The species the retargeting step needs in the zoo.
REQUIRED_SPECIES: Tuple[str, ...] = ("biped", "quadruped", "bird")
#: The zoo species the demo writes by default: the body plans it was tuned
#: on (the zoo's later species, fowl, crab, spider and longtail, on request).
DEMO_SPECIES: Tuple[str, ...] = ("biped", "quadruped", "bird", "hexapod", "snake")


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


@dataclass
class DemoStep:
    r"""One step of the demo: its name, wall time, the files it wrote and a
    one-line note."""

    name: str
    seconds: float = 0.0
    written: List[str] = field(default_factory=list)
    note: str = ""


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
    from satagraph.data.zoo import write_zoo

    species = list(options.species or DEMO_SPECIES)
    species += [s for s in REQUIRED_SPECIES if s not in species]
    return write_zoo(folder, species=species, clips=options.clips,
                     seed=options.seed, frames=options.frames)


def demo_config(options: DemoOptions, sources: Sequence[str], run_dir: Path
                ) -> Dict[str, Any]:
    """The training config: :attr:`DemoOptions.config` with the data
    sources, run folder and training time of the demo, then the user's
    overrides."""
    from satagraph.config import load_config

    cfg = load_config(options.config)
    cfg["data"]["sources"] = [str(s) for s in sources]
    cfg["output_dir"] = str(run_dir)
    if options.minutes is not None:
        cfg.setdefault("trainer", {})["max_time"] = {"minutes": float(options.minutes)}
    for item in options.overrides:
        if "=" not in item:
            raise ValueError(f"override {item!r} is not of the form key=value")
    merged = OmegaConf.merge(OmegaConf.create(cfg),
                             OmegaConf.from_dotlist(list(options.overrides)))
    return OmegaConf.to_container(merged, resolve=True)


def train_demo(cfg: Dict[str, Any]) -> Tuple[Any, Any]:
    """Step 2: train; returns the trained module and the trainer."""
    from satagraph.train import train

    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", ".*does not have many workers.*")
        warnings.filterwarnings("ignore", ".*Checkpoint directory.*exists.*")
        module, _, trainer, _ = train(cfg)
    return module, trainer


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


def retarget_demo(module, cfg: Dict[str, Any], clips: Dict[str, Path],
                  folder: Path, seed: int = 0) -> Tuple[List[Panel], str, float]:
    r"""Step 3: retarget the source walk onto the quadruped, the bird and a
    bone-scaled copy of the source's human skeleton, and write the BVH
    files (a copy of the source and the rescaled human's ground truth too).

    Returns:
        The panels (source first), the ground truth file and the mean joint
        position error of the rescaled human against it, relative to the
        height (see :func:`pose_error`).
    """
    from satagraph.data.augment import scale_bones
    from satagraph.data.datamodule import semantic_embedder
    from satagraph.inference import retarget_motion
    from satagraph.io import read_bvh, write_bvh

    data = cfg["data"]
    embed = semantic_embedder(data.get("semantic_encoder", "offline"), data.get("cache_dir"))
    window = int(data.get("window", 64))
    source = read_bvh(clips["source"])
    human = scale_bones(source, 0.7, 1.3, seed=seed)
    folder.mkdir(parents=True, exist_ok=True)
    name = _rig(str(clips["source"]))
    panels = [Panel(f"source: {name}", source, str(folder / f"source_{name}.bvh"))]
    targets = [(f"quadruped: {_rig(str(clips['quadruped']))}", read_bvh(clips["quadruped"])),
               (f"bird: {_rig(str(clips['bird']))}", read_bvh(clips["bird"])),
               (f"rescaled human: {name}", human)]
    for title, target in targets:
        out = retarget_motion(module, source, target, embed, window, window // 4)
        stem = title.split(": ")[1] + ("_rescaled" if title.startswith("rescaled") else "")
        panels.append(Panel(title, out, str(folder / f"walk_on_{stem}.bvh")))
    truth = str(folder / f"ground_truth_{name}_rescaled.bvh")
    for panel in panels:
        write_bvh(panel.motion, panel.path)
    write_bvh(human, truth)
    return panels, truth, pose_error(panels[-1].motion, human)


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
    from satagraph.data.canonical import canonicalize
    from satagraph.viz import render

    motions = [canonicalize(p.motion, fps=None) for p in panels]
    return render(motions, gif, titles=[p.title for p in panels], sheet=sheet)


# ----------------------------------------------------------------- main
def run_demo(options: DemoOptions, stream: TextIO = sys.stdout) -> DemoResult:
    r"""Run the whole demo into :attr:`DemoOptions.output`.

    Args:
        options (DemoOptions): What to do.
        stream (TextIO): Where the status lines go.
    """
    out = Path(options.output)
    result = DemoResult(str(out))
    progress = _Progress(result, 4, stream)
    zoo = out / "zoo"
    with progress.step("zoo", f"writing the procedural zoo to {zoo}") as step:
        rows = write_demo_zoo(zoo, options)
        step.written = [str(zoo / "manifest.tsv")]
        step.note = (f"{len(rows)} BVH clips of {len({r['skeleton'] for r in rows})} "
                     f"skeletons ({', '.join(dict.fromkeys(r['species'] for r in rows))})")
    sources = options.data or [str(zoo / "manifest.tsv")]
    cfg = demo_config(options, sources, out / "run")
    with progress.step("train", f"training {cfg['name']} on {', '.join(sources)} "
                       f"(at most {_budget(cfg)})") as step:
        module, trainer = train_demo(cfg)
        from satagraph.train import last_checkpoint
        step.written = [last_checkpoint(trainer)]
        step.note = _training_note(trainer)
    with progress.step("retarget", "retargeting a biped walk onto a quadruped, a "
                       "bird and a rescaled human") as step:
        panels, truth, error = retarget_demo(module, cfg, pick_clips(rows, zoo),
                                             out / "retarget", options.seed)
        step.written = [p.path for p in panels] + [truth]
        step.note = (f"rescaled human: mean joint error {100 * error:.1f}% of the "
                     "height vs the bone-scaled ground truth")
    with progress.step("render", "rendering the four side by side") as step:
        gif, sheet = out / "demo.gif", out / "demo_sheet.png"
        count = render_demo(panels, gif, sheet)
        step.written = [str(gif), str(sheet)]
        step.note = f"{len(panels)} panels, {count} frames"
    _write_json(out / "summary.json", result.to_dict())
    return result


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
    return "\n".join(lines)


__all__ = ["DemoOptions", "DemoResult", "DemoStep", "Panel", "run_demo",
           "format_summary", "write_demo_zoo", "demo_config", "train_demo",
           "pick_clips", "retarget_demo", "render_demo", "pose_error"]
