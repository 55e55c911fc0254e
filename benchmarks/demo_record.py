"""The README's `make demo` table, from the summary a demo run wrote.

`make demo` (``satagraph demo``) writes ``demo_output/summary.json``: what
each step did, how long it took, and the quality of its three retargets
(``steps``, ``travel``, ``stride``, ``down``), from the built-in model and
again after the short fine-tune. This turns one such summary into the
table the README quotes, and keeps the summary beside it, so that the
README's figures have a committed record of the run that made them.

    .venv/bin/python benchmarks/demo_record.py [SUMMARY.json] [--note "fresh clone, ..."]
        [--out PATH]

Writes ``benchmarks/results/demo.md`` (and ``.json``: the summary itself).
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Dict, List, Optional

sys.path.insert(0, str(Path(__file__).resolve().parent))

from results_io import write_results  # noqa: E402

OUT = Path(__file__).resolve().parent / "results" / "demo"
#: The demo's retarget steps, built-in then fine-tuned (``satagraph.experiment.demo``).
STAGES = ("retarget", "fine-tuned")


def _cells(quality: Dict[str, float]) -> List[str]:
    """One stage's four cells of a retarget's row."""
    lands = quality.get("lands")
    return [f"{quality['steps']:+.2f}", f"{quality['travel']:.2f}x", f"{quality['stride']:.2f}x",
            "-" if lands is None else f"{lands:.2f}"]


def demo_table(summary: Dict) -> str:
    """The README's table of a demo summary: per retarget, steps, travel,
    stride and down from the built-in model, then after the fine-tune.

    Raises:
        ValueError: If the summary lacks the built-in model's retargets
            (none, or the retargets of a model trained from scratch).
    """
    names = [step["name"] for step in summary.get("steps", [])]
    steps = {step["name"]: step for step in summary.get("steps", [])}
    if "retarget" not in steps:
        raise ValueError("demo_record: the summary has no 'retarget' step (not one that "
                         "`satagraph demo` wrote?)")
    if "train" in steps and names.index("train") < names.index("retarget"):
        raise ValueError("demo_record: the summary's retargets are of a model trained from "
                         "scratch (demo --from-scratch or --data), not of the built-in one")
    tuned = steps.get("fine-tuned", {}).get("quality", {})
    lines = ["| demo retarget | steps (built-in) | travel | stride | down | steps (after the "
             "fine-tune) | travel | stride | down |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for target, quality in steps["retarget"]["quality"].items():
        after = _cells(tuned[target]) if target in tuned else ["-"] * 4
        lines.append(f"| biped -> {target} | " + " | ".join(_cells(quality) + after) + " |")
    train = steps.get("train", {})
    lines += ["", f"Demo run: {summary['seconds']:.0f} s in all; training: "
              f"{train.get('note', 'none')} ({train.get('seconds', 0):.0f} s)."]
    return "\n".join(lines)


def main(argv: Optional[List[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("summary", nargs="?", type=Path,
                        default=Path("demo_output") / "summary.json",
                        help="a demo's summary.json (default: demo_output/summary.json)")
    parser.add_argument("--note", default="", help="where and how the demo ran (one line)")
    parser.add_argument("--out", type=Path, default=OUT, help="results path without suffix")
    args = parser.parse_args(argv)
    try:
        summary = json.loads(args.summary.read_text())
        table = demo_table(summary)
    except (OSError, ValueError, KeyError) as err:
        print(f"demo_record.py: {args.summary}: {err}", file=sys.stderr)
        return 2
    text = (f"`python benchmarks/demo_record.py {args.summary}`"
            + (f" ({args.note})" if args.note else "") + "\n\n" + table + "\n")
    print(text)
    write_results(args.out, "`make demo`'s retargets, as the README quotes them", text, summary)
    return 0


if __name__ == "__main__":
    sys.exit(main())
