r"""Do other tools read satagraph's BVH files as satagraph means them, and
does satagraph read theirs? Blender as the independent reader and writer.

For real files of ../shared/data and for what ``satagraph retarget``,
``reconstruct``, ``generate``, ``convert --canonical`` and ``zoo`` write,
Blender's BVH importer (no axis conversion, scale 1) imports each file and
gives every bone's world head position per frame; satagraph reads the same
file (:func:`satagraph.io.read_bvh`) and does its own forward kinematics.
The table gives, per file, whether Blender imported it, whether joint
names, joint count, frame count and frame time agree, and the largest
position difference over all joints and frames as a fraction of the
character's size (the median over frames of its joints' largest extent).
For the real files, Blender's BVH exporter writes the import back and
satagraph reads that: the same comparison against the original's FK, and
whether ``satagraph inspect`` reads the same up axis, units, height and
bind frame from both.

Usage::

    .venv/bin/python benchmarks/interop.py     # ~10 min; needs `blender` on PATH

writes ``benchmarks/results/interop.md`` (``--out``); without Blender it
says so in one line and exits 0.
"""
from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Dict, List, Optional

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO / "benchmarks"), str(REPO)]  # this checkout's satagraph

from results_io import SHARED_DATA, missing_data  # noqa: E402
from satagraph.io import read_bvh  # noqa: E402
from satagraph.utils.files import atomic_write_text  # noqa: E402

OUT = REPO / "benchmarks" / "results" / "interop.md"
#: Real files, one or two of each dataset and dialect.
REAL = ["cmu/01_01.bvh", "bandai/dataset-1_bow_active_001.bvh", "dog/D1_001_KAN01_001.bvh",
        "ccbase/006_01.bvh", "ccbase/007_01.bvh", "fixtures/test3.bvh",
        "fixtures/test_freebvh.bvh", "fixtures/test_mocapbank.bvh"]
#: A file passes when every joint is within this fraction of the character's size.
TOLERANCE = 1e-4

#: Run inside Blender: import argv[0] without axis conversion, write the
#: bones' world heads per frame (argv[1].bin, float64) and the names, frame
#: rate and frame count (argv[1].json); export to argv[2] when given.
BLENDER_SCRIPT = r'''
import array, builtins, json, sys
import bpy
import io_anim_bvh.import_bvh as importer
# Blender 3.4's importer opens with mode 'rU', which Python 3.11 removed:
# the same universal-newline text mode without the 'U'.
importer.open = lambda p, mode="r", *a, **k: builtins.open(p, mode.replace("U", ""), *a, **k)
src, out, export = (sys.argv[sys.argv.index("--") + 1:] + [""])[:3]
bpy.ops.import_anim.bvh(filepath=src, axis_forward="Y", axis_up="Z", global_scale=1.0,
                        rotate_mode="NATIVE", update_scene_fps=True, use_fps_scale=False)
obj, scene = bpy.context.view_layer.objects.active, bpy.context.scene
start, end = (int(round(f)) for f in obj.animation_data.action.frame_range)
pos = array.array("d")
for f in range(start, end + 1):
    scene.frame_set(f)
    for bone in obj.pose.bones:
        pos.extend(tuple(obj.matrix_world @ bone.head))
with open(out + ".bin", "wb") as fh:
    pos.tofile(fh)
json.dump(dict(names=[b.name for b in obj.pose.bones], frames=end - start + 1,
               fps=scene.render.fps / scene.render.fps_base, version=bpy.app.version_string),
          open(out + ".json", "w"))
if export:
    bpy.ops.export_anim.bvh(filepath=export, frame_start=start, frame_end=end,
                            global_scale=1.0, rotate_mode="NATIVE")
'''


def blender_reading(path: Path, work: Path, export: Optional[Path] = None) -> Dict:
    """Blender's import of :obj:`path`: ``names``, ``frames``, ``fps``,
    ``version`` and ``positions`` (:math:`(T, J, 3)`); ``error`` (its last
    line of output) where the import failed."""
    script, out = work / "blender_dump.py", work / path.stem
    script.write_text(BLENDER_SCRIPT)
    run = subprocess.run(["blender", "-b", "--factory-startup", "--python-exit-code", "1",
                          "--python", str(script), "--", str(path), str(out),
                          str(export or "")], capture_output=True, text=True, timeout=1800)
    if run.returncode or not out.with_suffix(".json").is_file():
        lines = [l for l in (run.stdout + run.stderr).splitlines() if l.strip()
                 and not l.startswith(("Blender quit", "Location:"))]
        return {"error": lines[-1] if lines else f"exit {run.returncode}"}
    meta = json.loads(out.with_suffix(".json").read_text())
    pos = np.fromfile(out.with_suffix(".bin"), dtype=np.float64)
    meta["positions"] = pos.reshape(meta["frames"], len(meta["names"]), 3)
    return meta


def blender_name(name: str) -> str:
    """A joint name as Blender's importer names its bone (spaces joined by
    underscores, at most 63 bytes)."""
    return "_".join(name.split()).encode()[:63].decode(errors="ignore")


def satagraph_reading(path: Path) -> Dict:
    """satagraph's reading of :obj:`path`: joint names (end sites left
    out, as Blender makes no bones of them), frame count, frame rate and
    FK positions :math:`(T, J, 3)`."""
    motion = read_bvh(path)
    joints = [j for j, end in enumerate(motion.skeleton.end_site) if not end]
    return {"names": [blender_name(motion.skeleton.names[j]) for j in joints],
            "frames": motion.num_frames, "fps": motion.fps,
            "positions": motion.global_positions()[:, joints]}


def position_error(ref: Dict, other: Dict) -> float:
    """The largest distance between the same-named joints of two readings,
    over all frames, as a fraction of the character's size in :obj:`ref`:
    the median over frames of its joints' largest extent (a standing
    character's height, whatever its up axis; travel left out)."""
    index = {n: k for k, n in enumerate(other["names"])}
    a = ref["positions"]
    b = other["positions"][:, [index[n] for n in ref["names"]]]
    size = float(np.median(np.ptp(a, axis=1).max(axis=-1)))
    return float(np.linalg.norm(a - b, axis=-1).max()) / size


def compare(ref: Dict, other: Dict) -> Dict:
    """Agreement of two readings (``same_header`` and ``error``); frame
    times agree to the digits files give (``0.041667`` is 24 fps)."""
    same = (sorted(ref["names"]) == sorted(other["names"])
            and ref["frames"] == other["frames"]
            and abs(1 / ref["fps"] - 1 / other["fps"]) < 1e-4 / ref["fps"])
    err = position_error(ref, other) if same else float("nan")
    return {"same_header": same, "error": err}


def inspect_reading(path: Path) -> Dict:
    """How ``satagraph inspect`` reads a file: up axis, units and scale,
    the height in metres and whether frame 0 is a bind pose."""
    run = subprocess.run([sys.executable, "-m", "satagraph", "inspect", "--json", str(path)],
                         capture_output=True, text=True, cwd=REPO, check=True)
    info = json.loads(run.stdout)
    rig = info["rig"]
    return {"up_axis": rig["up_axis"], "units": rig["units"], "scale": rig["scale"],
            "height_m": info["height_m"], "bind_frame": info["bind_frame"]}


def same_inspection(a: Dict, b: Dict) -> bool:
    """Whether two :func:`inspect_reading` agree, heights to 1e-3: Blender's
    importer lengthens an End Site of length zero to 0.1 file units (its
    "zero length node found"), which its exporter writes back, and End
    Sites count in the height (0.1 cm of a 1.74 m Mixamo rig: 5.7e-4)."""
    return (all(a[k] == b[k] for k in a if k != "height_m")
            and abs(a["height_m"] - b["height_m"]) <= 1e-3 * a["height_m"])


def written_files(work: Path) -> List[Path]:
    """What satagraph's commands write, from the real files (built-in
    weights)."""
    cli, d, out = [sys.executable, "-m", "satagraph"], SHARED_DATA, work / "written"
    out.mkdir()
    dog, cmu = d / "dog/D1_001_KAN01_001.bvh", d / "cmu/01_01.bvh"
    bandai, ccbase = d / "bandai/dataset-1_bow_active_001.bvh", d / "ccbase/006_01.bvh"
    runs = {"retarget_cmu_to_dog.bvh": ["retarget", cmu, "OUT", "--target", dog],
            "reconstruct_bandai.bvh": ["reconstruct", bandai, "OUT"],
            "generate_cmu.bvh": ["generate", "--text", "a person walks forward",
                                 "--skeleton", cmu, "OUT"],
            "generate_dog.bvh": ["generate", "--text", "a dog walks forward",
                                 "--skeleton", dog, "OUT"],
            "convert_canonical_ccbase.bvh": ["convert", "--canonical", ccbase, "OUT"],
            "convert_canonical_bandai.bvh": ["convert", "--canonical", bandai, "OUT"],
            "convert_dog.bvh": ["convert", dog, "OUT"]}
    for name, args in runs.items():
        args = [str(out / name) if a == "OUT" else str(a) for a in args]
        subprocess.run(cli + args, check=True, capture_output=True, cwd=REPO)
    subprocess.run(cli + ["zoo", "--clips", "1", "--seed", "0", "--frames", "60",
                          str(out / "zoo")], check=True, capture_output=True, cwd=REPO)
    zoo = sorted((out / "zoo").rglob("*.bvh"))[::3]
    return sorted(out.glob("*.bvh")) + zoo


def _row(label: str, path: Path, work: Path, export: Optional[Path] = None) -> Dict:
    blender = blender_reading(path, work, export)
    if "error" in blender:
        return {"file": label, "imported": False, "note": blender["error"][:80]}
    mine = satagraph_reading(path)
    row = {"file": label, "imported": True, "joints": len(mine["names"]),
           "frames": mine["frames"], "version": blender["version"], **compare(mine, blender)}
    if export is not None and export.is_file():
        back = compare(mine, satagraph_reading(export))
        row.update(back_same=back["same_header"], back_error=back["error"],
                   inspect_same=same_inspection(inspect_reading(path),
                                                inspect_reading(export)))
    return row


def _fmt(v: float) -> str:
    return "-" if v is None or v != v else f"{v:.1e}"


def table(rows: List[Dict]) -> str:
    """The markdown table of the rows."""
    head = ("| file | Blender imports | joints | frames | names, count, frames, frame time agree "
            "| max position error / size | Blender export read back: header agrees "
            "| its max error / size | `inspect` agrees |\n|---|---|---|---|---|---|---|---|---|\n")
    lines = []
    for r in rows:
        if not r["imported"]:
            lines.append(f"| {r['file']} | **no**: {r['note']} | | | | | | | |")
            continue
        back = ("| - | - | - |" if "back_same" not in r else
                f"| {'yes' if r['back_same'] else '**no**'} | {_fmt(r['back_error'])} "
                f"| {'yes' if r['inspect_same'] else '**no**'} |")
        lines.append(f"| {r['file']} | yes | {r['joints']} | {r['frames']} "
                     f"| {'yes' if r['same_header'] else '**no**'} | {_fmt(r['error'])} {back}")
    return head + "\n".join(lines) + "\n"


def main(argv: Optional[List[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=OUT, help="the table (default: %(default)s)")
    args = parser.parse_args(argv)
    if shutil.which("blender") is None:
        print("benchmarks/interop.py: needs Blender (`blender` on PATH) as the independent "
              "BVH reader; none found, nothing compared")
        return 0
    message = missing_data("benchmarks/interop.py")
    if message:
        print(message)
        return 0
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        for rel in REAL:
            rows.append(_row(rel, SHARED_DATA / rel, work, work / f"exported_{Path(rel).name}"))
            print(rows[-1], flush=True)
        for path in written_files(work):
            rows.append(_row(str(path.relative_to(work / "written")), path, work))
            print(rows[-1], flush=True)
    version = next((r["version"] for r in rows if r.get("version")), "?")
    worst = max((r["error"] for r in rows if r["imported"] and r["error"] == r["error"]),
                default=float("nan"))
    text = (f"# BVH interoperability with Blender {version}\n\n"
            "Blender's BVH importer (axis_forward=Y, axis_up=Z: no conversion; scale 1) "
            "against satagraph's reader and FK, per file, all frames and joints (end "
            f"sites left out: Blender makes no bones of them); pass: below {TOLERANCE:g} "
            f"of the character's size. Largest error: {_fmt(worst)}. Real files are also "
            "exported by Blender's BVH exporter and read back by satagraph. "
            "Run: `.venv/bin/python benchmarks/interop.py`.\n\n" + table(rows))
    atomic_write_text(args.out, text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
