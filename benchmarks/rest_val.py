"""Reconstruction read in one rest pose and in two, on validation clips no
rule has read (`experiments/PRETRAIN.md` section 39).

Each clip is reconstructed as `reconstruct` does by default (its reading
averaged with its mirror image's) and, besides, with `two_rests=True`
(also read with both rigs in the rest pose `auto` does not choose, the
four readings averaged). The zoo's clips are each plan's validation clips
45 to 56 (`--zoo-clips`); the real ones are Bandai's validation files
outside every third and the dog's non-test files (each cut as
`pretrained_val.py` cuts them). A built-in model reads the groups `auto`
gives it. Per group: the median JP (% of the height) of each setting and
the paired ratio (median over clips of two rests' JP over one's). Prints
the table and the verdict of section 39's rule.

    .venv/bin/python benchmarks/rest_val.py [--ckpt builtin builtin-wide] [--zoo-clips 45 56] [--out P]
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple


sys.path.insert(0, str(Path(__file__).resolve().parent))
import mirror_val  # noqa: E402
import pretrained_val as val  # noqa: E402
from pretrained import joint_error  # noqa: E402
from satagraph.motion import Motion  # noqa: E402
from satagraph.pipelines.inference import reconstruct_canonical  # noqa: E402

OUT = val.ROOT / "benchmarks" / "results" / "rest_val"
#: Each plan's validation clips read by default (1-based, inclusive): after
#: those sections 37c (19-30), 38 (31-36) and 39's exploration (37-44) read.
ZOO_CLIPS = (45, 56)
#: The groups each built-in model reads (what ``auto`` gives it).
GROUPS = {"builtin": ("zoo biped", "zoo quadruped", "zoo bird", "zoo fowl", "bandai (val)",
                      "dog (not test)"),
          "builtin-wide": ("zoo hexapod", "zoo crab", "zoo spider")}
#: Section 39's rule: no group's paired ratio above the first, their mean
#: at most the second.
LARGEST, MEAN_CAP = 1.02, 0.97


def fresh_clips(first: int, last: int) -> List[Tuple[str, str, Motion]]:
    """``(group, name, motion)``: the zoo's and Bandai's clips of
    :func:`mirror_val.fresh_clips` and the dog's non-test clips."""
    dog = sorted(val.manifest_paths("dog", lambda split: split != "test"))
    return mirror_val.fresh_clips(first, last) + [
        ("dog (not test)", rel, val.recon_window(val.real_file(rel))) for rel in dog]


def jp(module, motion: Motion, two_rests: bool) -> float:
    """JP (fraction of the height) of the default reconstruction, read in
    one rest pose or two."""
    src, out = reconstruct_canonical(module, motion, module.embed, ground=False,
                                     two_rests=two_rests)
    return joint_error(src, out)


def verdict(results: Dict[str, Dict[str, Dict[str, List[float]]]]) -> Tuple[bool, List[str]]:
    """Section 39's rule on ``results[ckpt][group] = {"one", "two"}`` (per-clip JPs)."""
    ratios = {f"{ckpt} {g}": mirror_val.paired(cell["one"], cell["two"])
              for ckpt, groups in results.items() for g, cell in groups.items()}
    failures = mirror_val.rule_failures(ratios, LARGEST, MEAN_CAP)
    return not failures, failures


def table(results: Dict[str, Dict[str, Dict[str, List[float]]]], seconds: float) -> str:
    lines = mirror_val.table_head(
        seconds, "one rest (today's default: with the mirror image's reading), two rests, "
        "and the paired ratio (median of two over one)",
        ("model", "group", "n", "one rest", "two rests", "paired"))
    for ckpt, groups in results.items():
        for group, cell in groups.items():
            lines.append(f"| `{ckpt}` | {group} | {mirror_val.pair_cells(cell)} |")
    return "\n".join(lines + ["", mirror_val.verdict_line("39", verdict(results))]) + "\n"


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--ckpt", nargs="+", default=list(GROUPS),
                        help="built-in names (each reads its groups) or checkpoints (every group)")
    mirror_val.add_zoo_clips_argument(parser, ZOO_CLIPS)
    parser.add_argument("--out", type=Path, default=OUT, help="results path without suffix")
    args = parser.parse_args(argv)
    if not mirror_val.check_arguments(parser, args, "rest_val.py"):
        return 2
    return mirror_val.measure_and_write(
        args, fresh_clips(*args.zoo_clips), GROUPS,
        {"one": lambda m, x: jp(m, x, False), "two": lambda m, x: jp(m, x, True)}, table,
        "Reconstruction read in one rest pose and in two, on fresh validation clips "
        "(benchmarks/rest_val.py)")


if __name__ == "__main__":
    sys.exit(main())
