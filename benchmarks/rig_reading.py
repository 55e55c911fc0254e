"""Rig reading benchmark: are up axes and units read right, on every body
plan and exporter dialect, and is every doubtful reading flagged?

Corpus: the procedural zoo's dialect variants (:func:`satagraph.datasets.zoo.
dialect_variants`: every zoo rig -- bipeds, quadrupeds, long-tailed
quadrupeds, birds in three dialects, hexapods, crabs, spiders, snakes --
written in each of the six up axes, in m, cm, inches or an arbitrary unit,
with rest poses that are not T-poses and exporter name noise), each written
to a BVH file and read back with no manifest; and every file of
``../shared/data`` (all of them +Y up).

Up axis: right, and flagged when the confidence is low. Units: the height
after reading (file height x the scale read) against the generator's true
height (both the median over frames of the vertical extent). Units are
*decidable* when the file's unit is a standard one and the file says
enough: a human body plan (bipeds), a known exporter, or a size only metres
make (vertebrates in metres; an arthropod may be a millimetre or a metre
across, so no size decides its units); elsewhere the file's own units must
be kept and reported. One kind of undecidable file cannot be told from a
decidable one: a human in an arbitrary unit that makes it a human height
(:data:`~satagraph.transforms.rig_reading.HUMAN_HEIGHT`) in a standard unit is
exactly what a file in that unit would be. Such files are *look-alikes*:
counted apart, read as the unit they look like (right by chance or not),
never as a success of the reader. A failure is a wrong axis, a decidable
unit read more than 20% off, an undecidable one not kept (look-alikes
excepted), or a look-alike read as anything but the unit it looks like.

Usage::

    .venv/bin/python benchmarks/rig_reading.py [--seeds 0 1 2 3] [--data DIR]
        [--out benchmarks/results/rig_reading]

Where ``../shared/data`` is absent the table says its rows are left out (a
``--data`` folder without a ``manifest.tsv`` is refused).
"""
from __future__ import annotations

import argparse
import csv
import sys
import tempfile
import time
import warnings
from collections import defaultdict
from pathlib import Path
from typing import Dict, List

from satagraph.transforms.rig_reading import HUMAN_HEIGHT, STANDARD_UNITS, UNITS, read_rig
from satagraph.datasets.zoo import apply_dialect, dialect_variants, generate_clip
from satagraph.io import read_bvh, write_bvh

sys.path.insert(0, str(Path(__file__).resolve().parent))
from results_io import SHARED_DATA, data_folder, write_results  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
RESULTS = REPO / "benchmarks" / "results" / "rig_reading"
TOLERANCE = 0.2
#: Body plans with six or more legs.
ARTHROPODS = ("hexapod", "crab", "spider")
#: Units the shared data's files must be read in (``kept``: undecidable).
SHARED_UNITS = {"bandai": "cm", "cmu": "cmu", "ccbase": "cm", "dog": "kept",
                "fixtures/test3.bvh": "m", "fixtures/test_freebvh.bvh": "cm",
                "fixtures/test_mocapbank.bvh": "cm"}


def _decidable(species: str, unit) -> bool:
    return unit in STANDARD_UNITS and (
        species == "biped" or (unit == "m" and species not in ARTHROPODS))


def _looks_like(species: str, unit, height: float):
    """The standard unit a human in an arbitrary unit, :obj:`height` file
    units tall, cannot be told from (``None``: none)."""
    if species != "biped" or unit in STANDARD_UNITS:
        return None
    fits = [u for u in STANDARD_UNITS
            if HUMAN_HEIGHT[0] <= height * UNITS[u] <= HUMAN_HEIGHT[1]]
    return fits[0] if len(fits) == 1 else None


def zoo_rows(seed: int, frames: int, tmp: Path) -> List[Dict]:
    """One row per dialect variant of the zoo drawn with :obj:`seed`."""
    rows = []
    for k, v in enumerate(dialect_variants(seed)):
        clip = generate_clip(v.rig, v.kind, frames=frames, seed=seed * 1000 + k)
        motion, scale = apply_dialect(clip, v.dialect, seed=k)
        path = tmp / f"{seed}_{k}.bvh"
        write_bvh(motion, path)
        reading = read_rig(read_bvh(path))
        height = reading.units.height * reading.units.scale
        ratio = height / read_rig(clip, "+Y", 1.0).units.height
        decidable = _decidable(v.rig.species, v.dialect.unit)
        looks = _looks_like(v.rig.species, v.dialect.unit, reading.units.height)
        right = abs(ratio - 1) <= TOLERANCE
        units_ok = (right if decidable else
                    reading.units.scale == UNITS[looks] if looks else reading.units.kept)
        rows.append({"seed": seed, "rig": v.rig.name, "species": v.rig.species,
                     "kind": v.kind, "dialect": v.dialect.tag,
                     "up_true": v.dialect.up_axis, "up_read": reading.up.axis,
                     "confidence": reading.up.confidence,
                     "flagged": reading.up.low_confidence,
                     "unit": str(v.dialect.unit), "decidable": decidable,
                     "looks_like": looks, "within_20": right,
                     "units_how": reading.units.how, "height_ratio": ratio,
                     "units_ok": units_ok})
    return rows


def shared_rows(data: Path) -> List[Dict]:
    """One row per file of the shared data's manifest."""
    rows = []
    with open(data / "manifest.tsv", newline="") as f:
        for row in csv.DictReader(f, delimiter="\t"):
            reading = read_rig(read_bvh(data / row["path"]))
            want = SHARED_UNITS.get(row["path"], SHARED_UNITS.get(row["dataset"]))
            got = ("kept" if reading.units.kept else
                   reading.to_dict()["units"])
            rows.append({"rig": row["path"], "species": row["dataset"],
                         "up_true": "+Y", "up_read": reading.up.axis,
                         "confidence": reading.up.confidence,
                         "flagged": reading.up.low_confidence,
                         "units_how": reading.units.how, "units": got,
                         "units_ok": got == want})
    return rows


def _summary(rows: List[Dict], key: str) -> List[List]:
    groups = defaultdict(list)
    for r in rows:
        groups[r[key]].append(r)
    groups["all"] = rows
    out = []
    for name, rs in groups.items():
        right = sum(r["up_read"] == r["up_true"] for r in rs)
        flagged = sum(r["flagged"] for r in rs)
        silent_wrong = sum(r["up_read"] != r["up_true"] and not r["flagged"] for r in rs)
        dec = [r for r in rs if r.get("decidable", True)]
        alike = [r for r in rs if r.get("looks_like")]
        und = [r for r in rs if not r.get("decidable", True) and not r.get("looks_like")]
        out.append([name, len(rs), f"{100 * right / len(rs):.1f}%", flagged, silent_wrong,
                    f"{sum(r['units_ok'] for r in dec)}/{len(dec)}",
                    f"{sum(r['units_how'] == 'kept' for r in und)}/{len(und)}",
                    f"{sum(r['units_ok'] for r in alike)}/{len(alike)} "
                    f"({sum(r['within_20'] for r in alike)} within 20%)",
                    sum(not r["units_ok"] for r in rs)])
    return out


def _table(rows: List[List]) -> str:
    head = ("| group | files | up axis right | low confidence (flagged) | wrong and "
            "not flagged | units right where decidable (within 20%) | undecidable: "
            "file units kept and reported | look-alikes read as the unit they look "
            "like | unit failures |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|\n")
    return head + "\n".join("| " + " | ".join(str(c) for c in r) + " |" for r in rows) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3])
    parser.add_argument("--frames", type=int, default=90)
    parser.add_argument("--data", type=lambda t: Path(data_folder(t)), default=None,
                        help="the real files (default ../shared/data, left out "
                             "where it is absent)")
    parser.add_argument("--out", type=Path, default=RESULTS,
                        help="results path without suffix (default "
                             "benchmarks/results/rig_reading)")
    args = parser.parse_args(argv)
    data = args.data or SHARED_DATA
    missing = "" if (data / "manifest.tsv").is_file() else (
        f"{data}: no manifest.tsv there: the real files' rows are left out.")
    if missing:
        print(f"rig_reading.py: {missing}", file=sys.stderr)
    warnings.simplefilter("ignore")
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        zoo = [r for s in args.seeds for r in zoo_rows(s, args.frames, Path(tmp))]
    shared = [] if missing else shared_rows(data)
    text = (f"Zoo dialect variants (seeds {args.seeds}, {args.frames} frames each), "
            "written to BVH and read back without a manifest:\n\n"
            + _table(_summary(zoo, "species"))
            + "\nUnits are decidable for standard units on a human body plan, or in "
            "metres on a body of four legs or fewer; elsewhere the file's own units "
            "must be kept and reported. Look-alikes are humans in an arbitrary unit "
            f"that makes them {HUMAN_HEIGHT[0]:g} to {HUMAN_HEIGHT[1]:g} m tall in a "
            "standard unit: no file can tell them from one in that unit, so they "
            "are read as it and counted apart (how many land within 20% of the "
            "true height is chance).\n")
    if shared:
        text += ("\nEvery file of `../shared/data` (expected units: bandai cm, "
                 "cmu CMU units, ccbase cm, dog kept (undecidable: 45 units tall), "
                 "fixtures m / cm / cm):\n\n" + _table(_summary(shared, "species")))
    else:
        text += f"\n{missing}\n"
    text += f"\n{len(zoo) + len(shared)} files in {time.perf_counter() - start:.0f} s.\n"
    print(text)
    write_results(args.out, "Rig reading: up axis and units", text,
                  {"zoo": zoo, "shared": shared})
    return 0


if __name__ == "__main__":
    sys.exit(main())
