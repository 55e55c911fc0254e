"""Reconstruction with and without the mirror image's reading, on validation
clips that `benchmarks/pretrained_val.py` does not read
(`experiments/PRETRAIN.md` sections 37b-37c).

`pretrained_val.py` reads each zoo plan's first six validation clips and
every third of Bandai's validation files; this reads each plan's clips 7
to 18 of the same stream (`--zoo-clips`: another range) and Bandai's other
validation files (`--no-bandai`: none), each reconstructed by every
checkpoint as one reading and averaged with its mirror image's
(`retarget_canonical(..., mirror=True)`); a built-in model reads the
groups its part of the rule names. Per group: the median JP (% of the
height) of each setting and the paired ratio, the median over the clips
of the averaged reading's JP over the single one's. Prints the table and
the verdict of the rule on the groups measured.

    .venv/bin/python benchmarks/mirror_val.py [--ckpt builtin builtin-wide] [--zoo-clips 7 18] [--out P]
"""
from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path
from typing import Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import pretrained_val as val  # noqa: E402
from results_io import missing_data, write_results  # noqa: E402
from satagraph.experiment.train import load_module  # noqa: E402
from satagraph.motion import Motion  # noqa: E402

OUT = val.ROOT / "benchmarks" / "results" / "mirror_val"
#: The zoo clips of each plan read by default (1-based, inclusive): those
#: after the ones ``pretrained_val.py`` reads.
ZOO_CLIPS = (val.ZOO_PER_PLAN + 1, 18)
#: Section 37b's groups per model: (groups, largest paired ratio, largest mean or None).
RULE = {"builtin": (("zoo biped", "zoo quadruped", "zoo bird", "zoo fowl", "bandai (val)"),
                    1.02, 0.95),
        "builtin-wide": (("zoo hexapod", "zoo crab", "zoo spider"), 1.02, None)}


def fresh_clips(first: int, last: int, bandai: bool = True) -> List[Tuple[str, str, Motion]]:
    """``(group, name, motion)``: each plan's validation clips :obj:`first`
    to :obj:`last` (1-based, in stream order) and, with :obj:`bandai`,
    Bandai's validation files outside every third (each cut as
    ``pretrained_val.py`` cuts them)."""
    count: Dict[str, int] = {}
    zoo = []
    for clip in val.zoo_clips(last):
        count[clip[0]] = count.get(clip[0], 0) + 1
        if count[clip[0]] >= first:
            zoo.append(clip)
    files = val.manifest_paths("bandai", lambda split: split == "val") if bandai else []
    rest = [rel for i, rel in enumerate(files) if i % 3]
    return zoo + [("bandai (val)", rel, val.recon_window(val.real_file(rel))) for rel in rest]


def add_zoo_clips_argument(parser: argparse.ArgumentParser, default: Tuple[int, int]) -> None:
    """``--zoo-clips FIRST LAST``: which of each plan's validation clips to read."""
    parser.add_argument("--zoo-clips", type=int, nargs=2, default=default,
                        metavar=("FIRST", "LAST"),
                        help="each plan's validation clips FIRST to LAST (1-based; default "
                             f"{default[0]} {default[1]})")


def check_arguments(parser: argparse.ArgumentParser, args: argparse.Namespace,
                    script: str) -> bool:
    """Refuse a bad ``--zoo-clips``; ``False`` (with a line on stderr)
    where ``../shared/data`` is missing."""
    if not 1 <= args.zoo_clips[0] <= args.zoo_clips[1]:
        parser.error(f"--zoo-clips: need 1 <= FIRST <= LAST, got {args.zoo_clips}")
    missing = missing_data(script, val.DATA, "the real clips")
    if missing:
        print(missing, file=sys.stderr)
    return missing is None


def read_clips(ckpts: Sequence[str], clips: List[Tuple[str, str, Motion]],
               groups: Dict[str, Sequence[str]], readers: Dict[str, Callable[[object, Motion], float]]
               ) -> Dict[str, Dict[str, Dict[str, List[float]]]]:
    """``results[ckpt][group][setting]``: each reader's JP of every clip
    of a group the checkpoint reads (a built-in name in :obj:`groups`
    reads its own groups; any other checkpoint every group)."""
    results: Dict[str, Dict[str, Dict[str, List[float]]]] = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for ckpt in ckpts:
            module = load_module(ckpt).eval()
            for group, _, motion in clips:
                if ckpt in groups and group not in groups[ckpt]:
                    continue
                cell = results.setdefault(ckpt, {}).setdefault(group, {k: [] for k in readers})
                for key, reader in readers.items():
                    cell[key].append(reader(module, motion))
    return results


def measure_and_write(args: argparse.Namespace, clips: List[Tuple[str, str, Motion]],
                      groups: Dict[str, Sequence[str]],
                      readers: Dict[str, Callable[[object, Motion], float]],
                      table_of: Callable, title: str) -> int:
    """:func:`read_clips`, then the table printed and written with its
    figures to ``args.out``."""
    start = time.perf_counter()
    results = read_clips(args.ckpt, clips, groups, readers)
    text = table_of(results, time.perf_counter() - start)
    print(text)
    write_results(args.out, title, text, results)
    return 0


def table_head(seconds: float, settings: str, columns: Sequence[str]) -> List[str]:
    """The first lines of a rule's table on fresh validation clips."""
    return [f"Validation clips no rule has read; {seconds:.0f} s. JP, % of the height, median "
            f"over the group's clips: {settings}.", "", "| " + " | ".join(columns) + " |",
            "|" + "|".join("---" if c in ("model", "group") else "---:" for c in columns) + "|"]


def pair_cells(cell: Dict[str, List[float]], first: str = "one", second: str = "two") -> str:
    """``n | median first | median second | paired`` of a group's cell (% of the height)."""
    return (f"{len(cell[first])} | {100 * np.median(cell[first]):.1f} | "
            f"{100 * np.median(cell[second]):.1f} | {paired(cell[first], cell[second]):.3f}")


def verdict_line(section: str, found: Tuple[bool, List[str]]) -> str:
    """The last line of a rule's table: ``The rule (PRETRAIN.md N): ...``."""
    ok, failures = found
    return f"The rule (PRETRAIN.md {section}): " + (
        "passes" if ok else "fails: " + "; ".join(failures))


def paired(single: Sequence[float], averaged: Sequence[float]) -> float:
    """Median over clips of the averaged reading's error over the single one's."""
    return float(np.median(np.asarray(averaged) / np.asarray(single)))


def verdict(results: Dict[str, Dict[str, Dict[str, List[float]]]]) -> Tuple[bool, List[str]]:
    """Section 37b's rule on ``results[ckpt][group] = {"single", "mirror"}``
    (per-clip JPs); returns whether it passes and why not."""
    failures = []
    for ckpt, (groups, largest, mean_cap) in RULE.items():
        ratios = {f"{ckpt} {g}": paired(results[ckpt][g]["single"], results[ckpt][g]["mirror"])
                  for g in groups if g in results[ckpt]}
        failures += rule_failures(ratios, largest, mean_cap, f"{ckpt} mean")
    return not failures, failures


def rule_failures(ratios: Dict[str, float], largest: float, mean_cap: Optional[float],
                  mean_name: str = "mean") -> List[str]:
    """What a paired-ratio rule finds: each group above :obj:`largest`, and
    the groups' mean above :obj:`mean_cap` (``None``: no cap)."""
    failures = [f"{g}: {r:.3f} > {largest}" for g, r in ratios.items() if r > largest]
    mean = float(np.mean(list(ratios.values()))) if ratios else float("nan")
    if mean_cap is not None and mean > mean_cap:
        failures.append(f"{mean_name} {mean:.3f} > {mean_cap}")
    return failures


def table(results: Dict[str, Dict[str, Dict[str, List[float]]]], seconds: float) -> str:
    lines = [f"Validation clips `pretrained_val.py` does not read; {seconds:.0f} s. JP, % of "
             "the height, median over the group's clips (n): one reading, averaged with the "
             "mirror image's, and the paired ratio (median of averaged over single).", "",
             "| group | " + " | ".join(f"`{k}`: n, one, mirror, paired" for k in results) + " |",
             "|---|" + "---|" * len(results)]
    groups = list(dict.fromkeys(g for r in results.values() for g in r))
    for group in groups:
        cells = [("" if group not in r else
                  f"{len(r[group]['single'])}, {100 * np.median(r[group]['single']):.1f}, "
                  f"{100 * np.median(r[group]['mirror']):.1f}, "
                  f"{paired(r[group]['single'], r[group]['mirror']):.3f}")
                 for r in results.values()]
        lines.append(f"| {group} | " + " | ".join(cells) + " |")
    if set(RULE) <= set(results):
        ok, failures = verdict(results)
        lines += ["", "The rule (PRETRAIN.md 37b) on these groups: "
                  + ("passes" if ok else "fails: " + "; ".join(failures))]
    return "\n".join(lines) + "\n"


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--ckpt", nargs="+", default=list(RULE),
                        help="checkpoints, .safetensors weights files or built-in names")
    add_zoo_clips_argument(parser, ZOO_CLIPS)
    parser.add_argument("--bandai", action=argparse.BooleanOptionalAction, default=True,
                        help="Bandai's validation files outside every third (default: on)")
    parser.add_argument("--out", type=Path, default=OUT, help="results path without suffix")
    args = parser.parse_args(argv)
    if not check_arguments(parser, args, "mirror_val.py"):
        return 2
    return measure_and_write(
        args, fresh_clips(*args.zoo_clips, bandai=args.bandai),
        {k: v[0] for k, v in RULE.items()},
        {"single": lambda m, x: val.measure(m, x, mirror=False)["jp"],
         "mirror": lambda m, x: val.measure(m, x, mirror=True)["jp"]}, table,
        "Reconstruction with the mirror image's reading, on fresh validation clips "
        "(benchmarks/mirror_val.py)")


if __name__ == "__main__":
    sys.exit(main())
