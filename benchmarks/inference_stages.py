"""Where the time of ``satagraph retarget``, ``reconstruct`` and ``generate``
goes on a CPU (built-in models, default flags): a short and a long real
clip, a dog clip, and a folder of clips, by stage.

Stages: Python start and imports (a fresh process importing what the
command imports, apart), weights loading, BVH reading (with the rig's
reading), canonicalisation, features (the source's and the target's,
the rest shown to the model), semantic embedding, batching, the model's
forward, post-processing (rest restored, root held, grounded, planted,
resampled back, decanonicalised) and BVH writing; ``other`` is the rest of
the command (checks, generation's sampling loop outside the decoder).
Each stage's time is its own, without the stages it calls. The command
runs in this process through :func:`satagraph.cli.main`, the imports done
before; each case runs :obj:`--repeat` times, the cases alternating, and
the median of each stage is shown.

Usage: ``python benchmarks/inference_stages.py [--data ../shared/data]
[--repeat 3] [--threads N] [--folder-files 20] [--out PATH]``. Prints a
markdown table and writes it to ``benchmarks/results/inference_stages.md``
(and ``.json``). Without the real files it says so in one line and exits.
"""
from __future__ import annotations

import argparse
import contextlib
import functools
import importlib
import io
import os
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path
from typing import Callable, Dict, List, Optional, Sequence, Tuple

from results_io import SHARED_DATA, missing_data, write_results  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SHORT = "bandai/dataset-1_bow_active_001.bvh"  # 128 frames at 30 fps
LONG = "cmu/01_01.bvh"  # 2752 frames at 120 fps
DOG = "dog/D1_001_KAN01_001.bvh"  # 1531 frames at 60 fps
HUMAN = "bandai/dataset-1_walk_normal_001.bvh"  # 195 frames at 30 fps
FOLDER = "bandai"  # the first --folder-files clips of it

#: What the commands import (timed in a fresh process).
IMPORTS = ("satagraph.cli", "satagraph.cli.train", "satagraph.experiment.train",
           "satagraph.pipelines.inference", "satagraph.pipelines.generate", "satagraph.io")

_INFERENCE = "satagraph.pipelines.inference"
_GENERATE = "satagraph.pipelines.generate"
#: Stage: the functions whose time is its own, as (module, name).
STAGES: Dict[str, Tuple[Tuple[str, str], ...]] = {
    "load": (("satagraph.experiment.train", "load_module"),
             (_GENERATE, "load_generator")),
    "read": (("satagraph.cli.arguments", "read_with_rig"),),
    "canonicalize": ((_INFERENCE, "canonicalize"), (_GENERATE, "canonicalize")),
    "features": ((_INFERENCE, "source_features"), (_INFERENCE, "shown_rest"),
                 (_INFERENCE, "static_features"), (_INFERENCE, "decoding_target"),
                 (_INFERENCE, "mirror_canonical"), (_GENERATE, "shown_rest"),
                 (_GENERATE, "static_features")),
    "embed": ((_INFERENCE, "_embed"), (_GENERATE, "call_semantic")),
    "batch": ((_INFERENCE, "collate_clips"), (_GENERATE, "collate_clips")),
    "post": tuple((_INFERENCE, name) for name in (
        "features_to_motion", "restore_rest", "settle_root", "hold_still_source",
        "ground_retarget", "plant_feet", "from_canonical", "average_readings",
        "place_reading", "mirror_back")) + tuple((_GENERATE, name) for name in (
            "features_to_motion", "restore_rest", "ground_at", "lift_above_floor",
            "plant_feet", "decanonicalize")),
    "write": (("satagraph.io", "write_bvh"), (_GENERATE, "write_all")),
}
ORDER = ("imports", "load", "read", "canonicalize", "features", "embed", "batch", "model",
         "post", "write", "other")


class StageClock:
    """Seconds per stage, each stage's own (a stage called inside another
    counts for itself only)."""

    def __init__(self) -> None:
        self.totals: Dict[str, float] = {}
        self.stack: List[List] = []

    def enter(self, stage: str) -> None:
        self.stack.append([stage, time.perf_counter(), 0.0])

    def leave(self) -> None:
        stage, start, inner = self.stack.pop()
        took = time.perf_counter() - start
        self.totals[stage] = self.totals.get(stage, 0.0) + took - inner
        if self.stack:
            self.stack[-1][2] += took

    def timed(self, stage: str, fn: Callable) -> Callable:
        @functools.wraps(fn)
        def wrapper(*args, **kwargs):
            self.enter(stage)
            try:
                return fn(*args, **kwargs)
            finally:
                self.leave()
        return wrapper


@contextlib.contextmanager
def instrumented(clock: StageClock):
    """The functions of :data:`STAGES` timed by :obj:`clock` while inside,
    and the forward of every model loaded (``model``)."""
    saved = []
    for stage, names in STAGES.items():
        for module_name, name in names:
            module = importlib.import_module(module_name)
            fn = getattr(module, name)
            saved.append((module, name, fn))
            if stage == "load":
                fn = _hooked(clock, fn)
            setattr(module, name, clock.timed(stage, fn))
    try:
        yield
    finally:
        for module, name, fn in saved:
            setattr(module, name, fn)


def _hooked(clock: StageClock, load: Callable) -> Callable:
    """:obj:`load` whose model's forward (and a generator's autoencoder's
    decoding) counts as ``model``."""
    @functools.wraps(load)
    def wrapper(*args, **kwargs):
        module = load(*args, **kwargs)
        for part in {module, getattr(module, "autoencoder", module)}:
            part.register_forward_pre_hook(lambda *_: clock.enter("model"))
            part.register_forward_hook(lambda *_: clock.leave())
        if hasattr(module, "autoencoder"):  # generation decodes through decode_codes
            auto = module.autoencoder
            auto.decode_codes = clock.timed("model", auto.decode_codes)
        for name, method in (("masked", "generate"), ("residual", "generate"),
                             ("length", "sample")):
            part = getattr(module, name, None)
            if hasattr(part, method):
                setattr(part, method, clock.timed("model", getattr(part, method)))
        if hasattr(module, "encode_text"):
            module.encode_text = clock.timed("embed", module.encode_text)
        return module
    return wrapper


def run_stages(argv: Sequence[str]) -> Dict[str, float]:
    """Seconds per stage of ``satagraph ARGV`` in this process."""
    from satagraph.cli import main
    clock, said = StageClock(), io.StringIO()
    with instrumented(clock), warnings.catch_warnings(), \
            contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(said):
        warnings.simplefilter("ignore")
        clock.enter("other")
        try:
            code = main(list(argv))
        finally:
            clock.leave()
    if code:
        raise RuntimeError(f"satagraph {' '.join(argv)} exited with {code}: "
                           f"{said.getvalue().strip()}")
    return clock.totals


def import_seconds(threads: int) -> float:
    """Wall seconds of a fresh ``python -c 'import ...'`` of :data:`IMPORTS`,
    the interpreter's start included."""
    env = dict(os.environ, PYTHONPATH=str(ROOT), OMP_NUM_THREADS=str(threads))
    start = time.perf_counter()
    subprocess.run([sys.executable, "-c", "import " + ", ".join(IMPORTS)], env=env,
                   check=True, cwd=ROOT)
    return time.perf_counter() - start


def cases(data: Path, scratch: Path, folder_files: int) -> List[Tuple[str, List[str]]]:
    """(name, argv) of every command measured; the folder's clips are
    linked into :obj:`scratch`."""
    folder = scratch / "clips"
    folder.mkdir()
    clips = sorted((data / FOLDER).glob("*.bvh"))[:folder_files]
    for clip in clips:
        (folder / clip.name).symlink_to(clip)
    out = scratch / "out"
    out.mkdir()
    prompts = scratch / "prompts.txt"
    prompts.write_text("a person walks forward\na person waves\n")
    return [
        (f"retarget {Path(SHORT).name} onto {Path(DOG).name}",
         ["retarget", str(data / SHORT), str(out / "short.bvh"), "--target", str(data / DOG)]),
        (f"retarget {Path(LONG).name} onto {Path(DOG).name}",
         ["retarget", str(data / LONG), str(out / "long.bvh"), "--target", str(data / DOG)]),
        (f"retarget {Path(DOG).name} onto {Path(HUMAN).name}",
         ["retarget", str(data / DOG), str(out / "dog.bvh"), "--target", str(data / HUMAN)]),
        (f"retarget a folder of {len(clips)} {FOLDER} clips onto {Path(DOG).name}",
         ["retarget", str(folder), str(out / "folder"), "--target", str(data / DOG)]),
        (f"reconstruct {Path(SHORT).name}",
         ["reconstruct", str(data / SHORT), str(out / "rec_short.bvh")]),
        (f"reconstruct {Path(LONG).name}",
         ["reconstruct", str(data / LONG), str(out / "rec_long.bvh")]),
        (f"generate 4 s on {Path(HUMAN).name}",
         ["generate", str(out / "gen.bvh"), "--text", "a person walks forward",
          "--seconds", "4", "--skeleton", str(data / HUMAN)]),
        (f"generate --prompts (2) on {Path(DOG).name}",
         ["generate", str(out / "gen_prompts"), "--prompts", str(prompts),
          "--seconds", "4", "--skeleton", str(data / DOG)]),
    ]


def measure(runs: List[Tuple[str, List[str]]], repeat: int
            ) -> Dict[str, Dict[str, List[float]]]:
    """Stage seconds of every run, :obj:`repeat` times, the runs alternating."""
    seen: Dict[str, Dict[str, List[float]]] = {name: {} for name, _ in runs}
    for _ in range(repeat):
        for name, argv in runs:
            start = time.perf_counter()
            stages = run_stages(argv)
            stages["total"] = time.perf_counter() - start
            for stage, seconds in stages.items():
                seen[name].setdefault(stage, []).append(seconds)
    return seen


def table(seen: Dict[str, Dict[str, List[float]]], imports: float) -> Tuple[str, dict]:
    """The markdown table (median seconds per stage) and its data."""
    head = ["command", *ORDER, "total (in process)"]
    lines = ["| " + " | ".join(head) + " |", "|---|" + "---:|" * (len(head) - 1)]
    data = {}
    for name, stages in seen.items():
        med = {stage: statistics.median(v) for stage, v in stages.items()}
        med["imports"] = imports
        data[name] = med
        cells = [f"{med.get(stage, 0.0):.2f}" for stage in ORDER]
        lines.append(f"| {name} | " + " | ".join(cells) + f" | {med['total']:.2f} |")
    return "\n".join(lines), data


def main(argv: Optional[List[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=SHARED_DATA,
                        help="the real BVH files (default ../shared/data)")
    parser.add_argument("--repeat", type=int, default=3,
                        help="runs of each command, alternating (median shown)")
    parser.add_argument("--threads", type=int, default=2, help="torch threads (default 2)")
    parser.add_argument("--folder-files", type=int, default=20,
                        help="clips in the folder retargeted (default 20)")
    parser.add_argument("--only", nargs="*", default=None, metavar="WORD",
                        help="only the commands whose name holds one of these words")
    parser.add_argument("--out", type=Path,
                        default=ROOT / "benchmarks" / "results" / "inference_stages",
                        help="results path without suffix")
    args = parser.parse_args(argv)
    missing = missing_data("inference_stages.py", args.data, "the clips timed")
    if missing:
        print(f"{missing}; pass --data DIR", file=sys.stderr)
        return 2
    import torch
    torch.set_num_threads(args.threads)
    for name in IMPORTS:
        importlib.import_module(name)
    imports = statistics.median(import_seconds(args.threads) for _ in range(args.repeat))
    with tempfile.TemporaryDirectory(prefix="satagraph-stages-") as tmp:
        runs = cases(args.data, Path(tmp), args.folder_files)
        if args.only:
            runs = [(n, a) for n, a in runs if any(w in n for w in args.only)]
        seen = measure(runs, args.repeat)
    text, data = table(seen, imports)
    text = (f"Seconds per stage, median of {args.repeat} runs (the commands alternating), "
            f"{args.threads} torch threads, built-in models, default flags; `imports`: a "
            "fresh process importing the commands' modules (not in the total), the other "
            "stages in one process, each stage's own time.\n\n" + text + "\n")
    print(text)
    write_results(args.out, "Inference stages (benchmarks/inference_stages.py)", text,
                  {"repeat": args.repeat, "threads": args.threads, "commands": data})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
