"""What ``satagraph generate`` checks before the model loads: the durations
it may ask for and the files it writes (:mod:`satagraph.pipelines.generate`
generates; this module imports neither torch nor the model code, so that a
bad duration or output path is said at once)."""
from __future__ import annotations

import os
from pathlib import Path
from typing import List, Sequence

#: Durations a generation may ask for, seconds (``generate --seconds``).
SECONDS_RANGE = (0.1, 60.0)


def check_seconds(seconds: float) -> float:
    """:obj:`seconds`, refused (one line) outside :data:`SECONDS_RANGE`."""
    if not SECONDS_RANGE[0] <= seconds <= SECONDS_RANGE[1]:  # also NaN
        raise ValueError(f"a duration must be between {SECONDS_RANGE[0]:g} and "
                         f"{SECONDS_RANGE[1]:g} seconds, got {seconds!r}")
    return float(seconds)


def output_paths(output: str, skeletons: Sequence[str]) -> List[str]:
    """Where each skeleton's motion goes: :obj:`output` for one skeleton;
    for several, ``<output stem>_<skeleton stem>.bvh`` beside :obj:`output`
    (or ``<skeleton stem>.bvh`` inside it when it is a folder), numbered
    where stems repeat."""
    if len(skeletons) == 1 and not os.path.isdir(output):
        return [output]
    out, seen = [], {}
    folder = os.path.isdir(output)
    base = Path(output)
    for path in skeletons:
        stem = Path(path).stem
        seen[stem] = seen.get(stem, 0) + 1
        name = stem if seen[stem] == 1 else f"{stem}-{seen[stem]}"
        out.append(str(base / f"{name}.bvh") if folder
                   else str(base.with_name(f"{base.stem}_{name}.bvh")))
    return out


__all__ = ["SECONDS_RANGE", "check_seconds", "output_paths"]
