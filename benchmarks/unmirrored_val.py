"""A second rest's reading where no mirror image is read, on validation
clips no rule has read (`experiments/PRETRAIN.md` section 40).

Section 39's second rest helped the spider alone, the one plan it read
whose rigs have no mirror image (legs numbered across the body). Each
spider, snake and hexapod clip of each plan's validation clips 57 to 80
(`--zoo-clips`) is reconstructed by `builtin-wide` as `reconstruct` does
by default and with `two_rests="unmirrored"` (a second rest only where
no mirror image is read). Hexapods have mirror images: their readings
must not change. Prints the table and section 40's verdict.

    .venv/bin/python benchmarks/unmirrored_val.py [--zoo-clips 57 80] [--out P]
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
from satagraph.pipelines.inference import UNMIRRORED, reconstruct_canonical  # noqa: E402

OUT = val.ROOT / "benchmarks" / "results" / "unmirrored_val"
#: Each plan's validation clips read by default: after section 39's (45-56).
ZOO_CLIPS = (57, 80)
GROUPS = {"builtin-wide": ("zoo spider", "zoo snake", "zoo hexapod")}
#: Section 40's rule: the largest paired ratio of each group.
LARGEST = {"zoo spider": 0.95, "zoo snake": 1.02, "zoo hexapod": 1.0}


def jp(module, motion: Motion, two_rests) -> float:
    """JP (fraction of the height) of the default reconstruction."""
    src, out = reconstruct_canonical(module, motion, module.embed, ground=False,
                                     two_rests=two_rests)
    return joint_error(src, out)


def verdict(results: Dict[str, Dict[str, Dict[str, List[float]]]]) -> Tuple[bool, List[str]]:
    """Section 40's rule on ``results["builtin-wide"][group] = {"one", "two"}``;
    a hexapod clip whose reading changed at all fails it."""
    groups = results["builtin-wide"]
    ratios = {g: mirror_val.paired(c["one"], c["two"]) for g, c in groups.items()}
    failures = [f"{g}: {r:.3f} > {LARGEST[g]}" for g, r in ratios.items() if r > LARGEST[g]]
    hexapod = groups.get("zoo hexapod")
    if hexapod and hexapod["one"] != hexapod["two"]:
        failures.append("zoo hexapod: a mirrored reading changed")
    return not failures, failures


def table(results: Dict[str, Dict[str, Dict[str, List[float]]]], seconds: float) -> str:
    lines = mirror_val.table_head(
        seconds, "today's reading, with a second rest where no mirror image is read, and "
        "the paired ratio", ("group", "n", "today", "unmirrored second rest", "paired"))
    for group, cell in results["builtin-wide"].items():
        lines.append(f"| {group} | {mirror_val.pair_cells(cell)} |")
    return "\n".join(lines + ["", mirror_val.verdict_line("40", verdict(results))]) + "\n"


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    mirror_val.add_zoo_clips_argument(parser, ZOO_CLIPS)
    parser.add_argument("--out", type=Path, default=OUT, help="results path without suffix")
    args = parser.parse_args(argv)
    args.ckpt = list(GROUPS)
    if not mirror_val.check_arguments(parser, args, "unmirrored_val.py"):
        return 2
    return mirror_val.measure_and_write(
        args, mirror_val.fresh_clips(*args.zoo_clips, bandai=False), GROUPS,
        {"one": lambda m, x: jp(m, x, False), "two": lambda m, x: jp(m, x, UNMIRRORED)},
        table, "A second rest where no mirror image is read, on fresh validation clips "
        "(benchmarks/unmirrored_val.py)")


if __name__ == "__main__":
    sys.exit(main())
