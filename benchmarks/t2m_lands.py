"""Do generated animals put their limbs down? (issue 19; PRETRAIN.md section 54)

``benchmarks/t2m.py``'s per-skeleton probes alone, without its evaluator:
every probe prompt on every skeleton of the test table (the zoo's biped,
quadruped, bird and hexapod test rigs, a Bandai test rig, CMU ``01_01`` and
the dog), :data:`t2m.PROBE_SEEDS` seeds, 4 s each, with the default
sampling, and their ``down`` (``lands`` against the skeleton's own clip,
median over the travelling prompts: 1 where every limb the clip stands on
comes down as often, 0 where one never does: a quadruped's forepaws
carried like a human's hands).

    .venv/bin/python benchmarks/t2m_lands.py [--ckpt builtin] [--seeds 6] [--prompts val]
        [--carriage auto|always|never] [--out PATH]

Writes ``benchmarks/results/t2m_lands.md`` (and ``.json``).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import List, Optional

import torch

sys.path.insert(0, str(Path(__file__).resolve().parent))

import t2m  # noqa: E402
from results_io import missing_data, write_results  # noqa: E402

OUT = Path(__file__).resolve().parent / "results" / "t2m_lands"


def main(argv: Optional[List[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--ckpt", default="builtin", help="a t2m checkpoint (default: builtin)")
    parser.add_argument("--seeds", type=int, default=t2m.PROBE_SEEDS)
    parser.add_argument("--prompts", choices=("test", "val"), default="test",
                        help="the skeletons: the test table's (default) or, to choose "
                             "settings on, the zoo's validation rigs, a Bandai validation "
                             "rig and the dog's first validation clip")
    parser.add_argument("--carriage", choices=t2m.CARRIAGE_MODES, default=None,
                        help="GenerationSettings.carriage (default: generate's)")
    parser.add_argument("--out", type=Path, default=OUT, help="results path without suffix")
    args = parser.parse_args(argv)
    line = missing_data("t2m_lands.py")
    if line:
        print(line, file=sys.stderr)
        return 2
    torch.manual_seed(0)
    start = time.perf_counter()
    _, test = t2m.real_items(False, 0, args.prompts)
    targets = t2m.skeleton_targets(test, False, args.prompts)
    settings = (None if args.carriage is None
                else t2m.GenerationSettings(carriage=args.carriage))
    rows = t2m.skeleton_probes(t2m.load_generator(args.ckpt), targets, args.seeds,
                               settings=settings)
    lines = ["| skeleton | prompts' subject | probes |", "|---|---|---|"]
    lines += [f"| {r['skeleton']} | {r['subject']} | {t2m.probe_cell(r['probes'])} |"
              for r in rows]
    given = "".join(f" --{k} {v}" for k, v in (("prompts", args.prompts if args.prompts != "test"
                                                    else None), ("carriage", args.carriage)) if v)
    text = (f"`python benchmarks/t2m_lands.py --ckpt {args.ckpt} --seeds {args.seeds}{given}` "
            f"({time.perf_counter() - start:.0f} s)\n\n" + "\n".join(lines) + "\n")
    print(text)
    write_results(args.out, "Generated limbs that come down (t2m.py's skeleton probes)",
                  text, {"ckpt": args.ckpt, "seeds": args.seeds, "prompts": args.prompts,
                         "carriage": args.carriage, "rows": rows})
    return 0


if __name__ == "__main__":
    sys.exit(main())
