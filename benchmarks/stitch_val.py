"""How decoded windows are stitched, on validation material only
(`experiments/PRETRAIN.md` section 52).

`satagraph retarget` and `reconstruct` read a clip in the model's windows
(32 frames at 30 fps, 8 shared by neighbours) and write each window into
the take (:func:`~satagraph.pipelines.inference.cross_fade`). Three rules
for the shared frames are compared with the built-in model on
`benchmarks/pretrained_val.py`'s validation retargets (zoo biped, quadruped
and bird of the validation seeds; a Bandai validation walk to and from the
dog's validation clips and onto CC_Base's validation clips) and on
reconstructions of Bandai validation clips, dog clips outside its test
split and validation-seed zoo clips:

- **cut**: the earlier window's reading up to its last frame, the later
  one's after it (the rule before 30 Nov, stop 69);
- **cross-fade**: the shared frames fade linearly from the earlier
  window's reading into the later one's (the rule since);
- **half**: the earlier window's over the first half of the shared
  frames, a cross-fade over the second half.

Columns: steps and travel (as `benchmarks/pretrained.py` scores them),
foot slide (heights per second of the joints near the ground), JP (% of
the height, median over clips) and **seam**: the largest frame-to-frame
change of the pose's velocity (mean over joints, in heights) near each
seam, over its median away from the seams, averaged over seams: 1 for
a take with no seams, higher where the pose jumps as a window begins.

    .venv/bin/python benchmarks/stitch_val.py [--out P]

About a minute on the project's 2-core VM.
"""
from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path
from typing import Callable, Dict, List, Optional, Sequence

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import pretrained_val as val  # noqa: E402
from pretrained import joint_error  # noqa: E402
from results_io import missing_data, write_results  # noqa: E402
import satagraph.pipelines.inference as inference  # noqa: E402
from satagraph.motion import Motion  # noqa: E402
from satagraph.pipelines.quality import contact, retarget_quality  # noqa: E402

OUT = val.ROOT / "benchmarks" / "results" / "stitch_val"
#: Reconstructed clips per group (Bandai validation, dog not test, zoo).
RECON = {"bandai (val)": 8, "dog (not test)": 6, "zoo": 12}
#: The shipped rule (the module's own, whatever a run patches in).
_FADE = inference.cross_fade


def _cut(whole: np.ndarray, window: np.ndarray, start: int, written: int) -> None:
    """The earlier window's reading of the shared frames, the later's after."""
    shared = max(0, written - start)
    whole[written:start + len(window)] = window[shared:]


def _half(whole: np.ndarray, window: np.ndarray, start: int, written: int) -> None:
    """The earlier window's first half of the shared frames, then a cross-fade."""
    half = max(0, written - start) // 2
    _FADE(whole, window[half:], start + half, written)


RULES: Dict[str, Callable] = {"cut": _cut, "cross-fade": _FADE, "half": _half}


def seam(motion: Motion, window: int, overlap: int) -> float:
    """The pose's largest jump near each seam over its median elsewhere
    (see the module docstring); ``nan`` for a take of one window."""
    x = motion.global_positions() / max(motion.height(), 1e-6)
    jump = np.linalg.norm(x[2:] - 2 * x[1:-1] + x[:-2], axis=-1).mean(-1)
    plan = inference.window_plan(len(x), window, overlap)
    near = np.zeros(len(jump), bool)
    peaks = []
    for (start, _, _), (_, stop, _) in zip(plan[1:], plan[:-1]):
        lo, hi = max(start - 2, 0), min(stop + 1, len(jump))
        peaks.append(jump[lo:hi].max())
        near[lo:hi] = True
    if not peaks or near.all():
        return float("nan")
    return float(np.mean(peaks) / max(np.median(jump[~near]), 1e-12))


def measure(module, pairs, clips) -> Dict[str, Dict[str, float]]:
    """Per group: mean steps, median travel, mean slide, mean seam
    (retargets); median JP, mean slide, mean seam (reconstructions)."""
    window, overlap = inference.default_windows(module)
    got: Dict[str, List[dict]] = {}
    for name, source, target in pairs:
        src, out = inference.retarget_canonical(module, source, target, module.embed)
        row = retarget_quality(src, out, ("steps", "travel", "slide"))
        got.setdefault(name, []).append(dict(row, seam=seam(out, window, overlap)))
    for group, _, clip in clips:
        src, out = inference.reconstruct_canonical(module, clip, module.embed, ground=False)
        got.setdefault(f"reconstruct {group}", []).append(dict(
            jp=100 * joint_error(src, out), slide=contact(out)[0],
            seam=seam(out, window, overlap)))
    return {name: {key: float(np.nanmedian([r[key] for r in rows])
                              if key in ("travel", "jp") else np.nanmean([r[key] for r in rows]))
                   for key in rows[0]} | {"n": len(rows)}
            for name, rows in got.items()}


def recon_clips() -> list:
    """The reconstructed clips: :data:`RECON` of each group."""
    real = val.real_clips()
    out = []
    for prefix, count in RECON.items():
        pool = val.zoo_clips(2) if prefix == "zoo" else [c for c in real if c[0] == prefix]
        out += [("zoo" if prefix == "zoo" else prefix, name, clip)
                for _, name, clip in pool[:count]]
    return out


def table(results: Dict[str, Dict[str, Dict[str, float]]], seconds: float) -> str:
    """One row per group, the rules side by side."""
    rules = list(results)
    groups = list(results[rules[0]])
    head = ["group", "n"] + [f"{m} ({r})" for m in ("steps", "travel", "JP %", "slide",
                                                     "seam") for r in rules]
    lines = [f"Built-in model (`--ckpt builtin`), {seconds:.0f} s on this machine.", "",
             "| " + " | ".join(head) + " |", "|---" + "|---:" * (len(head) - 1) + "|"]
    for group in groups:
        cells = [group, str(results[rules[0]][group]["n"])]
        for key, fmt in (("steps", "{:+.3f}"), ("travel", "{:.3f}"), ("jp", "{:.2f}"),
                         ("slide", "{:.3f}"), ("seam", "{:.2f}")):
            cells += [fmt.format(results[r][group][key]) if key in results[r][group] else "-"
                      for r in rules]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=OUT,
                        help=f"results path without suffix (default {OUT.relative_to(val.ROOT)})")
    args = parser.parse_args(argv)
    missing = missing_data("stitch_val.py", what="the validation clips")
    if missing:
        parser.error(missing)
    warnings.simplefilter("ignore")
    from satagraph.experiment.train import load_module
    module = load_module("builtin")
    pairs, clips = val.retarget_pairs(), recon_clips()
    start, results = time.perf_counter(), {}
    try:
        for rule, stitch in RULES.items():
            inference.cross_fade = stitch
            results[rule] = measure(module, pairs, clips)
    finally:
        inference.cross_fade = _FADE
    text = table(results, time.perf_counter() - start)
    print(text)
    write_results(args.out, "Stitching decoded windows, validation material "
                  "(benchmarks/stitch_val.py)", text, results)
    return 0


if __name__ == "__main__":
    sys.exit(main())
