r"""Bad inputs and failure scenarios against the real ``satagraph`` CLI.

Generates well over a hundred distinct bad inputs into a temporary folder
(hostile BVH files, special files, poisoned training data, broken configs,
non-checkpoints and planted pickles, unwritable outputs, a locked run
folder), runs the real command on each as a subprocess with a timeout, and
classifies the outcome:

- ``clean error``: non-zero exit, a ``satagraph...: error: ...`` message, no
  traceback;
- ``handled``: exit 0 and the result checked correct (where the input is
  odd but valid: a BOM, CR-only lines, Latin-1 names, a 3000-level chain);
- ``traceback``, ``hang`` (past the timeout), ``silent wrong`` (exit 0 where
  an error was due, or a result that fails its check, or a planted payload
  that ran).

Usage::

    .venv/bin/python benchmarks/bad_inputs.py            # every case (~5-10 min)
    .venv/bin/python benchmarks/bad_inputs.py --quick    # no training cases

writes ``benchmarks/results/bad_inputs.md`` (counts by outcome, then every
case). ``tests/test_bad_inputs.py`` runs the fast cases in-process.
"""
from __future__ import annotations

import argparse
import contextlib
import csv
import io
import os
import re
import signal
import subprocess
import sys
import time
import traceback
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Dict, List, Optional, Sequence

REPO = Path(__file__).resolve().parents[1]
OUTCOMES = ("clean error", "handled", "traceback", "hang", "silent wrong")

#: A small valid BVH file: a root with 6 channels and two children.
BASE = ["HIERARCHY", "ROOT Hips", "{", "  OFFSET 0 0 0",
        "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation",
        "  JOINT Spine", "  {", "    OFFSET 0 10 0", "    CHANNELS 3 Zrotation Xrotation Yrotation",
        "    End Site", "    {", "      OFFSET 0 10 0", "    }", "  }",
        "  JOINT Leg", "  {", "    OFFSET 2 -10 0", "    CHANNELS 3 Zrotation Xrotation Yrotation",
        "    End Site", "    {", "      OFFSET 0 -10 0", "    }", "  }", "}",
        "MOTION", "Frames: 3", "Frame Time: 0.0333333",
        "0 90 0 0 0 0 10 0 0 0 0 5", "1 90 1 0 0 0 20 0 0 0 0 6",
        "2 90 2 0 0 0 30 0 0 0 0 7"]
L_MOTION = BASE.index("MOTION")


@dataclass
class Case:
    r"""One bad input: ``argv(tmp)`` builds it under the case folder and
    returns the CLI arguments; ``expect`` is ``"error"`` or ``"handled"``;
    ``check(tmp)`` (for ``handled``, and for errors that must leave no
    trace) says whether the result is right."""

    name: str
    group: str
    argv: Callable[[Path], List[str]]
    expect: str = "error"
    check: Optional[Callable[[Path], bool]] = None
    timeout: float = 60.0
    slow: bool = False


@dataclass
class Result:
    case: Case
    outcome: str
    code: Optional[int]
    seconds: float
    message: str = ""
    extra: Dict[str, str] = field(default_factory=dict)


# ------------------------------------------------------------ BVH variants
def _lines(edit: Callable[[List[str]], List[str]]) -> str:
    return "\n".join(edit(list(BASE))) + "\n"


def _set(i: int, text: str) -> Callable[[List[str]], List[str]]:
    def edit(lines: List[str]) -> List[str]:
        lines[i] = text
        return lines
    return edit


def _drop(i: int) -> Callable[[List[str]], List[str]]:
    return lambda lines: lines[:i] + lines[i + 1:]


def _insert(i: int, text: str) -> Callable[[List[str]], List[str]]:
    return lambda lines: lines[:i] + [text] + lines[i:]


def _chain(depth: int) -> str:
    lines = ["HIERARCHY"]
    for d in range(depth):
        kind = "ROOT" if d == 0 else "JOINT"
        chans = ("6 Xposition Yposition Zposition" if d == 0 else "3") + \
            " Zrotation Xrotation Yrotation"
        lines += [f"{kind} j{d}", "{", "OFFSET 0 1 0", f"CHANNELS {chans}"]
    lines += ["}"] * depth + ["MOTION", "Frames: 1", "Frame Time: 0.0333333",
                             " ".join(["0"] * (3 + 3 * depth))]
    return "\n".join(lines) + "\n"


#: name -> text (str) or bytes of a bad or odd BVH file.
BVH_ERRORS: Dict[str, object] = {
    "empty": "",
    "whitespace only": "  \n\t\n",
    "no HIERARCHY": _lines(_drop(0)),
    "missing MOTION": "\n".join(BASE[:L_MOTION]) + "\n",
    "unclosed brace": _lines(_drop(L_MOTION - 1)),
    "extra closing brace": _lines(_insert(L_MOTION, "}")),
    "JOINT outside any joint": _lines(_insert(L_MOTION, "JOINT X")),
    "two ROOTs": _lines(_insert(L_MOTION, "ROOT Other\n{\nOFFSET 0 0 0\n}")),
    "joint without OFFSET": _lines(_drop(7)),
    "OFFSET with 2 values": _lines(_set(7, "    OFFSET 0 10")),
    "OFFSET non-numeric": _lines(_set(7, "    OFFSET 0 ten 0")),
    "OFFSET nan": _lines(_set(7, "    OFFSET 0 nan 0")),
    "OFFSET inf": _lines(_set(7, "    OFFSET 0 inf 0")),
    "OFFSET 1e400": _lines(_set(7, "    OFFSET 0 1e400 0")),
    "CHANNELS count mismatch": _lines(_set(8, "    CHANNELS 2 Zrotation Xrotation Yrotation")),
    "unknown channel": _lines(_set(8, "    CHANNELS 3 Zrotation Xrotation Wrotation")),
    "duplicate channels": _lines(_set(8, "    CHANNELS 3 Zrotation Zrotation Yrotation")),
    "two rotation channels": _lines(_set(8, "    CHANNELS 2 Zrotation Xrotation")),
    "CHANNELS without count": _lines(_set(8, "    CHANNELS Zrotation Xrotation Yrotation")),
    "CHANNELS on End Site": _lines(_insert(11, "      CHANNELS 3 Zrotation Xrotation Yrotation")),
    "duplicate joint names": _lines(_set(14, "  JOINT Spine")),
    "JOINT without name": _lines(_set(14, "  JOINT")),
    "End without Site": _lines(_set(9, "    End")),
    "unexpected keyword": _lines(_insert(3, "  COLOR red")),
    "Frames missing": _lines(_drop(L_MOTION + 1)),
    "Frame Time missing": _lines(_drop(L_MOTION + 2)),
    "Frames negative": _lines(_set(L_MOTION + 1, "Frames: -3")),
    "Frames non-integer": _lines(_set(L_MOTION + 1, "Frames: 2.5")),
    "Frames huge without data": _lines(_set(L_MOTION + 1, "Frames: 1000000000")),
    "Frame Time zero": _lines(_set(L_MOTION + 2, "Frame Time: 0")),
    "Frame Time negative": _lines(_set(L_MOTION + 2, "Frame Time: -0.03")),
    "Frame Time nan": _lines(_set(L_MOTION + 2, "Frame Time: nan")),
    "Frame Time 1e-400": _lines(_set(L_MOTION + 2, "Frame Time: 1e-400")),
    "frame line too short": _lines(_set(L_MOTION + 4, "1 90 1 0 0 0 20 0 0 0 0")),
    "frame line too long": _lines(_set(L_MOTION + 4, "1 90 1 0 0 0 20 0 0 0 0 6 7")),
    "frame value non-numeric": _lines(_set(L_MOTION + 4, "1 90 1 0 0 0 2O 0 0 0 0 6")),
    "frame value nan": _lines(_set(L_MOTION + 4, "1 90 1 0 0 0 nan 0 0 0 0 6")),
    "frame value inf": _lines(_set(L_MOTION + 4, "1 90 1 0 0 0 -inf 0 0 0 0 6")),
    "frame value 1e400": _lines(_set(L_MOTION + 4, "1 90 1 0 0 0 1e400 0 0 0 0 6")),
    "decimal comma": _lines(_set(L_MOTION + 4, "1 90 1 0 0 0 20,5 0 0 0 0 6")),
    "fewer frame lines": _lines(_drop(L_MOTION + 5)),
    "more frame lines": _lines(_insert(L_MOTION + 6, "3 90 3 0 0 0 40 0 0 0 0 8")),
    "truncated mid-number": _lines(lambda x: x[:-1] + ["2 90 2 0 0 0 3"]).rstrip("\n"),
    "binary garbage": bytes(range(256)) * 8,
    "null bytes": b"HIERARCHY\n\x00\x00\x00ROOT\x00\n",
    "UTF-16 without its byte order mark": _lines(lambda x: x).encode("utf-16-le"),
    "a zip archive": b"PK\x03\x04" + b"\x00" * 64,
    "a JSON file": '{"HIERARCHY": []}\n',
}

#: name -> (text or bytes, check of the inspect JSON output) for odd but valid files.
BVH_HANDLED: Dict[str, object] = {
    "UTF-8 BOM": b"\xef\xbb\xbf" + _lines(lambda x: x).encode(),
    "UTF-16 text (with its byte order mark)": _lines(lambda x: x).encode("utf-16"),
    "CR-only line endings": _lines(lambda x: x).replace("\n", "\r").encode(),
    "CRLF line endings": _lines(lambda x: x).replace("\n", "\r\n").encode(),
    "mixed line endings": _lines(lambda x: x).replace("\n", "\r", 7).encode(),
    "tabs as separators": _lines(lambda x: [y.replace(" ", "\t") for y in x]),
    "Latin-1 joint names": _lines(lambda x: [y.replace("Spine", "Bíceps").replace(
        "Leg", "Bìceps") for y in x]).encode("latin-1"),
    "UTF-8 joint names": _lines(lambda x: [y.replace("Spine", "Wirbelsäule") for y in x]),
    "Frames: 0": _lines(lambda x: x[:L_MOTION + 1] + ["Frames: 0", x[L_MOTION + 2]]),
    "Frame Time typed as fps (inspect)": _lines(_set(L_MOTION + 2, "Frame Time: 30")),
    "exponent notation": _lines(_set(L_MOTION + 4, "1e0 9.0E1 1 0 0 0 2e1 0 0 0 0 6")),
    "3000-level hierarchy": _chain(3000),
    "blank lines everywhere": _lines(lambda x: [y + "\n" for y in x]),
}


def _write(path: Path, data: object) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    if isinstance(data, bytes):
        path.write_bytes(data)
    else:
        path.write_bytes(str(data).encode())
    return path


def _good(tmp: Path, name: str = "good.bvh") -> Path:
    """:data:`BASE`, declared +Y up: three frames of a line-shaped rig do
    not tell their up axis (read +Z, the body then of height 0, which the
    commands refuse since stop 65 rather than write)."""
    return _write(tmp / name, _lines(lambda x: x) + "# satagraph: up_axis=+Y\n")


def _fifo(path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    os.mkfifo(path)
    return path


# ------------------------------------------------------------ case builders
def bvh_cases() -> List[Case]:
    """``inspect`` on every hostile file, odd file and special file."""
    cases = [Case(f"inspect: {name}", "BVH file",
                  lambda t, d=data: ["inspect", str(_write(t / "x.bvh", d))])
             for name, data in BVH_ERRORS.items()]
    cases += [Case(f"inspect: {name}", "BVH file (valid)",
                   lambda t, d=data: ["inspect", "--json", str(_write(t / "x.bvh", d))],
                   expect="handled", check=_names_distinct)
              for name, data in BVH_HANDLED.items()]
    special = {
        "FIFO": lambda t: str(_fifo(t / "x.bvh")),
        "directory": lambda t: str(t),
        "/dev/zero": lambda t: "/dev/zero",
        "/dev/null": lambda t: "/dev/null",
        "missing file": lambda t: str(t / "missing.bvh"),
        "symlink loop": lambda t: _loop(t),
        "dangling symlink": lambda t: _dangling(t),
    }
    cases += [Case(f"inspect: {name}", "special file", lambda t, f=fn: ["inspect", f(t)],
                   timeout=20.0) for name, fn in special.items()]
    return cases


def _loop(tmp: Path) -> str:
    (tmp / "a.bvh").symlink_to(tmp / "b.bvh")
    (tmp / "b.bvh").symlink_to(tmp / "a.bvh")
    return str(tmp / "a.bvh")


def _dangling(tmp: Path) -> str:
    (tmp / "d.bvh").symlink_to(tmp / "nowhere.bvh")
    return str(tmp / "d.bvh")


def _names_distinct(tmp: Path) -> bool:
    out = (tmp / "stdout").read_text()
    return out.lstrip().startswith("{") and '"joints"' in out


def convert_cases() -> List[Case]:
    """``convert``: output paths, options, resampling bounds, writes."""
    ft30 = _lines(_set(L_MOTION + 2, "Frame Time: 30"))
    ft1e9 = _lines(_set(L_MOTION + 2, "Frame Time: 1e9"))
    zero = _lines(lambda x: [re.sub(r"OFFSET .*", "OFFSET 0 0 0", y) for y in x])
    c = "convert"
    return [
        Case(f"{c}: output is a directory", c, lambda t: [c, str(_good(t)), str(t)]),
        Case(f"{c}: output folder missing", c,
             lambda t: [c, str(_good(t)), str(t / "no" / "out.bvh")]),
        Case(f"{c}: output is a FIFO", c,
             lambda t: [c, str(_good(t)), str(_fifo(t / "out.bvh"))], timeout=20.0),
        Case(f"{c}: output is a socket", c, lambda t: [c, str(_good(t)), _socket(t)],
             check=lambda t: (t / "o.sock").is_socket()),
        Case(f"{c}: --fps 0", c, lambda t: [c, str(_good(t)), str(t / "o.bvh"), "--fps", "0"]),
        Case(f"{c}: --fps nan", c, lambda t: [c, str(_good(t)), str(t / "o.bvh"), "--fps", "nan"]),
        Case(f"{c}: --fps -30", c, lambda t: [c, str(_good(t)), str(t / "o.bvh"), "--fps=-30"]),
        Case(f"{c}: --fps 1e9", c, lambda t: [c, str(_good(t)), str(t / "o.bvh"), "--fps", "1e9"]),
        Case(f"{c}: Frame Time typed as fps, --fps 30", c,
             lambda t: [c, str(_write(t / "x.bvh", ft30)), str(t / "o.bvh"), "--fps", "30"],
             check=_no_output),
        Case(f"{c}: Frame Time 1e9, --canonical", c,
             lambda t: [c, str(_write(t / "x.bvh", ft1e9)), str(t / "o.bvh"), "--canonical"],
             check=_no_output),
        Case(f"{c}: zero offsets, --canonical", c,
             lambda t: [c, str(_write(t / "x.bvh", zero)), str(t / "o.bvh"), "--canonical"],
             check=_no_output),
        Case(f"{c}: --up-axis Q", c,
             lambda t: [c, str(_good(t)), str(t / "o.bvh"), "--canonical", "--up-axis", "Q"]),
        Case(f"{c}: --up-axis without --canonical", c,
             lambda t: [c, str(_good(t)), str(t / "o.bvh"), "--up-axis", "Y"]),
        Case(f"{c}: input FIFO", c,
             lambda t: [c, str(_fifo(t / "x.bvh")), str(t / "o.bvh")], timeout=20.0),
        Case(f"{c}: input /dev/zero", c, lambda t: [c, "/dev/zero", str(t / "o.bvh")]),
        Case(f"{c}: 3000-level hierarchy", c,
             lambda t: [c, str(_write(t / "x.bvh", _chain(3000))), str(t / "o.bvh")],
             expect="handled", check=_reads_back),
        Case(f"{c}: in place (same file)", c,
             lambda t: [c, str(_good(t, "o.bvh")), str(t / "o.bvh"), "--fps", "60"],
             expect="handled", check=_reads_back),
        Case(f"{c}: stale temp of a killed run swept", c, _stale_temp, expect="handled",
             check=lambda t: _reads_back(t) and not list(t.glob(".o.bvh.*"))),
        Case(f"{c}: failed write keeps the old file", c,
             lambda t: [c, str(_write(t / "x.bvh", zero)), str(_old(t)), "--canonical"],
             check=lambda t: (t / "o.bvh").read_text() == "previous\n"
             and not list(t.glob(".o.bvh.*"))),
    ]


def _socket(tmp: Path) -> str:
    import socket
    sock = socket.socket(socket.AF_UNIX)
    sock.bind(str(tmp / "o.sock"))
    _SOCKETS.append(sock)
    return str(tmp / "o.sock")


_SOCKETS: list = []


def _stale_temp(tmp: Path) -> List[str]:
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True).stdout.strip()
    (tmp / f".o.bvh.{dead}.0123abcd.tmp.bvh").write_text("partial")
    return ["convert", str(_good(tmp)), str(tmp / "o.bvh")]


def _old(tmp: Path) -> Path:
    return _write(tmp / "o.bvh", "previous\n")


def _no_output(tmp: Path) -> bool:
    return not (tmp / "o.bvh").exists() and not list(tmp.glob(".o.bvh.*"))


def _reads_back(tmp: Path) -> bool:
    return _reads_back_path(tmp / "o.bvh")


# ------------------------------------------------------------ training cases
def _zoo(root: Path) -> Path:
    """A small zoo under ``root/zoo`` (written once)."""
    manifest = root / "zoo" / "manifest.tsv"
    if not manifest.is_file():
        sys.path.insert(0, str(REPO))
        from satagraph.datasets.zoo import write_zoo
        write_zoo(root / "zoo", species=["biped", "quadruped"], clips=2, frames=40)
    return manifest


def _zoo_lines(root: Path) -> List[str]:
    manifest = _zoo(root)
    first = next(csv.DictReader(open(manifest), delimiter="\t"))
    return (manifest.parent / first["path"]).read_text().splitlines()


def _poison(lines: List[str], how: str) -> List[str]:
    out = list(lines)
    m = out.index("MOTION")
    offsets = [i for i, x in enumerate(out) if "OFFSET" in x]
    edits = {
        "root 1e30": lambda: out.__setitem__(m + 4, " ".join(["1e30"] + out[m + 4].split()[1:])),
        "zero offsets": lambda: out.__init__([re.sub(r"OFFSET .*", "OFFSET 0 0 0", x)
                                              for x in out]),
        "Frame Time 30": lambda: out.__setitem__(m + 2, "Frame Time: 30"),
        "Frame Time 1e9": lambda: out.__setitem__(m + 2, "Frame Time: 1e9"),
        "Frames 0": lambda: out.__init__(out[:m + 1] + ["Frames: 0", out[m + 2]]),
        "Frames 1": lambda: out.__init__(out[:m + 1] + ["Frames: 1", out[m + 2], out[m + 3]]),
        "offset 1e30": lambda: out.__setitem__(offsets[3], "OFFSET 0 1e30 0"),
        "angle 1e30": lambda: out.__setitem__(m + 5, " ".join(out[m + 5].split()[:4] + [
            "1e30"] + out[m + 5].split()[5:])),
        "malformed": lambda: out.__setitem__(m + 5, "1 2 3"),
        "2000 fps": lambda: out.__setitem__(m + 2, "Frame Time: 0.0005"),
    }
    edits[how]()
    return out


def _manifest(root: Path, tmp: Path, bad: Sequence[tuple]) -> Path:
    """The zoo manifest plus ``(name, split, text-or-path)`` rows."""
    manifest = _zoo(root)
    rows = list(csv.DictReader(open(manifest), delimiter="\t"))
    for name, split, target in bad:
        if isinstance(target, list):
            path = _write(tmp / f"{name}.bvh", "\n".join(target) + "\n")
        else:
            path = target(tmp)
        rows.append(dict(rows[0], path=str(path), split=split))
    for row in rows:
        if not os.path.isabs(row["path"]):
            row["path"] = str(manifest.parent / row["path"])
    out = tmp / "manifest.tsv"
    with open(out, "w", newline="") as f:
        writer = csv.DictWriter(f, list(rows[0]), delimiter="\t", lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
    return out


def _train(root: Path, tmp: Path, sources: str, *extra: str) -> List[str]:
    return ["train", "tiny", f"data.sources=[{sources}]", f"data.cache_dir={root / 'cache'}",
            "data.window=16", "data.stride=16", "data.batch_size=4", "data.max_files=null",
            "logger.name=none", "trainer.progress=false", "trainer.enable_model_summary=false",
            "trainer.max_epochs=1", "trainer.limit_train_batches=2",
            "trainer.limit_val_batches=1", f"output_dir={tmp / 'run'}", *extra]


def training_cases(root: Path) -> List[Case]:
    """``train`` on poisoned data, broken configs and damaged run folders."""
    cases = []
    for how, split in (("root 1e30", "train"), ("zero offsets", "train"),
                       ("Frame Time 30", "train"), ("Frame Time 1e9", "train"),
                       ("Frames 0", "train"), ("Frames 1", "train"),
                       ("offset 1e30", "train"), ("angle 1e30", "train"),
                       ("malformed", "train"), ("2000 fps", "train"),
                       ("root 1e30", "val"), ("zero offsets", "test")):
        cases.append(Case(f"train: one file with {how} ({split})", "training data",
                          lambda t, h=how, s=split: _train(root, t, str(_manifest(
                              root, t, [("bad", s, _poison(_zoo_lines(root), h))]))),
                          check=_no_checkpoint, slow=True, timeout=180.0))
    specials = {
        "missing file in manifest": lambda t: t / "missing.bvh",
        "FIFO in manifest": lambda t: _fifo(t / "pipe.bvh"),
        "directory in manifest": lambda t: t,
        "/dev/zero in manifest": lambda t: Path("/dev/zero"),
    }
    for name, target in specials.items():
        cases.append(Case(f"train: {name}", "training data",
                          lambda t, g=target: _train(root, t, str(_manifest(
                              root, t, [("bad", "train", g)]))),
                          check=_no_checkpoint, slow=True, timeout=180.0))
    every_split = lambda t: _train(root, t, str(_manifest(root, t, [  # noqa: E731
        ("a", "train", _poison(_zoo_lines(root), "Frames 0")),
        ("b", "val", _poison(_zoo_lines(root), "zero offsets")),
        ("c", "test", _poison(_zoo_lines(root), "Frame Time 30"))])))
    cases += [
        Case("train: bad files in all three splits (all listed at once)", "training data",
             every_split, check=lambda t: _no_checkpoint(t) and all(
                 f"{s}: " in (t / "stderr").read_text() for s in ("train", "val", "test")),
             slow=True, timeout=180.0),
        Case("train: data.on_error=skip trains on the rest", "training data",
             lambda t: every_split(t) + ["data.on_error=skip"], expect="handled",
             check=lambda t: (t / "run" / "skipped_files.txt").read_text().count("\n") == 3
             and (t / "run" / "checkpoints" / "last.ckpt").is_file(),
             slow=True, timeout=180.0),
        Case("train: data.on_error=bogus", "training config",
             lambda t: _train(root, t, str(_zoo(root)), "data.on_error=bogus"), slow=True),
        Case("train: every training file bad, on_error=skip", "training data",
             lambda t: _train(root, t, str(_only_bad(root, t)), "data.on_error=skip"),
             slow=True, timeout=180.0),
        Case("train: manifest without columns", "training data",
             lambda t: _train(root, t, str(_write(t / "m.tsv", "a\tb\n1\t2\n"))), slow=True),
        Case("train: empty manifest", "training data",
             lambda t: _train(root, t, str(_write(t / "m.tsv", ""))), slow=True),
        Case("train: folder without BVH files", "training data",
             lambda t: _train(root, t, str(t)), slow=True),
        Case("train: missing source folder", "training data",
             lambda t: _train(root, t, str(t / "nowhere")), slow=True),
        Case("train: config not found", "training config", lambda t: ["train", "nope"], slow=True),
        Case("train: malformed YAML config", "training config",
             lambda t: ["train", str(_write(t / "c.yaml", "model: [1, 2\n  x: {\n"))], slow=True),
        Case("train: config is a FIFO", "training config",
             lambda t: ["train", str(_fifo(t / "c.yaml"))], slow=True, timeout=30.0),
        Case("train: override without '='", "training config",
             lambda t: _train(root, t, str(_zoo(root)), "trainer.max_epochs"), slow=True),
        Case("train: malformed override value", "training config",
             lambda t: _train(root, t, str(_zoo(root)), "data.batch_size=[1"), slow=True),
        Case("train: unknown module", "training config",
             lambda t: _train(root, t, str(_zoo(root)), "module=transformer"), slow=True),
        Case("train: checkpoint.every_n_steps=0", "training config",
             lambda t: _train(root, t, str(_zoo(root)), "checkpoint.every_n_steps=0"), slow=True),
        Case("train: nonfinite=bogus", "training config",
             lambda t: _train(root, t, str(_zoo(root)), "nonfinite=bogus"), slow=True),
        Case("train: output_dir is a file", "run folder",
             lambda t: _train(root, t, str(_zoo(root)))[:-1] + [
                 f"output_dir={_write(t / 'file', 'x')}"], slow=True),
        Case("train: learning rate 1e30 (loss diverges)", "training",
             lambda t: _train(root, t, str(_zoo(root)), "optim.lr=1e30",
                              "trainer.limit_train_batches=6", "checkpoint.every_n_steps=1"),
             check=_checkpoint_finite, slow=True, timeout=180.0),
        Case("train: --resume without a checkpoint", "run folder",
             lambda t: _train(root, t, str(_zoo(root)), "--resume"), slow=True),
        Case("train: --resume, last.ckpt truncated, no previous", "run folder",
             lambda t: _plant(t, b"PK\x03\x04truncated") + _train(root, t, str(_zoo(root)),
                                                                  "--resume"), slow=True),
        Case("train: --resume, last.ckpt a planted pickle", "run folder",
             lambda t: _plant(t, _evil(t)) + _train(root, t, str(_zoo(root)), "--resume"),
             check=lambda t: not (t / "pwned").exists(), slow=True),
        Case("train: --resume, last.ckpt truncated, previous good", "run folder",
             lambda t: _damaged_last(root, t), expect="handled",
             check=lambda t: (t / "run" / "checkpoints" / "last.damaged.ckpt").is_file(),
             slow=True, timeout=240.0),
        Case("train: --init-from a BVH file", "run folder",
             lambda t: _train(root, t, str(_zoo(root)), "--init-from", str(_good(t))), slow=True),
        Case("train: --init-from missing", "run folder",
             lambda t: _train(root, t, str(_zoo(root)), "--init-from", str(t / "no.ckpt")),
             slow=True),
        Case("train: output_dir held by a live run", "run folder", lambda t: _locked(root, t),
             check=lambda t: not (t / "run" / "checkpoints").exists(), slow=True),
    ]
    return cases


def _only_bad(root: Path, tmp: Path) -> Path:
    out = tmp / "only.tsv"
    bad = _write(tmp / "bad.bvh", "\n".join(_poison(_zoo_lines(root), "Frames 0")) + "\n")
    out.write_text("path\tsplit\n" f"{bad}\ttrain\n")
    return out


def _plant(tmp: Path, data: bytes) -> List[str]:
    _write(tmp / "run" / "checkpoints" / "last.ckpt", data)
    return []


def _evil(tmp: Path) -> bytes:
    import torch

    class Payload:
        def __reduce__(self):
            return (os.system, (f"touch {tmp / 'pwned'}",))

    buf = io.BytesIO()
    torch.save({"state_dict": Payload(), "loops": {}, "optimizer_states": []}, buf)
    return buf.getvalue()


def _damaged_last(root: Path, tmp: Path) -> List[str]:
    args = _train(root, tmp, str(_zoo(root)), "checkpoint.every_n_steps=1")
    env = dict(os.environ, PYTHONPATH=str(REPO))
    subprocess.run([sys.executable, "-m", "satagraph", *args], env=env,
                   capture_output=True, check=True)
    last = tmp / "run" / "checkpoints" / "last.ckpt"
    last.write_bytes(last.read_bytes()[:1000])
    return args[:-1] + [args[-1], "trainer.max_epochs=2", "--resume"]


def _locked(root: Path, tmp: Path) -> List[str]:
    run = tmp / "run"
    run.mkdir(parents=True, exist_ok=True)
    code = ("import fcntl, os, sys, time; fd = os.open(sys.argv[1], os.O_RDWR | os.O_CREAT);"
            "fcntl.flock(fd, fcntl.LOCK_EX); os.write(fd, b'pid %d' % os.getpid());"
            "print('ok', flush=True); time.sleep(120)")
    holder = subprocess.Popen([sys.executable, "-c", code, str(run / ".lock")],
                              stdout=subprocess.PIPE, text=True)
    holder.stdout.readline()
    _HOLDERS.append(holder)
    return _train(root, tmp, str(_zoo(root)))


_HOLDERS: List[subprocess.Popen] = []


def _no_checkpoint(tmp: Path) -> bool:
    return not (tmp / "run" / "checkpoints" / "last.ckpt").exists()


def _checkpoint_finite(tmp: Path) -> bool:
    import torch
    last = tmp / "run" / "checkpoints" / "last.ckpt"
    if not last.exists():
        return True
    state = torch.load(last, weights_only=True)["state_dict"]
    return all(bool(torch.isfinite(v).all()) for v in state.values() if v.is_floating_point())


# ------------------------------------------------------------ model commands
def _model(root: Path) -> Path:
    """A tiny trained checkpoint (trained once)."""
    ckpt = root / "model" / "run" / "checkpoints" / "last.ckpt"
    if not ckpt.is_file():
        env = dict(os.environ, PYTHONPATH=str(REPO))
        subprocess.run([sys.executable, "-m", "satagraph", "train",
                        *_train(root, root / "model", str(_zoo(root)))[1:]],
                       env=env, capture_output=True, check=True)
    return ckpt


def checkpoint_cases() -> List[Case]:
    """Bad ``--ckpt`` files given to reconstruct (no model needed: they fail
    first)."""
    def rec(make: Callable[[Path], Path]) -> Callable[[Path], List[str]]:
        return lambda t: ["reconstruct", "--ckpt", str(make(t)), str(_good(t)),
                          str(t / "o.bvh")]

    def torch_file(obj: object) -> Callable[[Path], Path]:
        def make(t: Path) -> Path:
            import torch
            torch.save(obj, t / "c.ckpt")
            return t / "c.ckpt"
        return make

    g = "checkpoint"
    return [
        Case("--ckpt missing", g, rec(lambda t: t / "no.ckpt")),
        Case("--ckpt a directory", g, rec(lambda t: t)),
        Case("--ckpt a FIFO", g, rec(lambda t: _fifo(t / "c.ckpt")), timeout=20.0),
        Case("--ckpt /dev/zero", g, rec(lambda t: Path("/dev/zero"))),
        Case("--ckpt a BVH file", g, rec(lambda t: _good(t, "c.bvh"))),
        Case("--ckpt empty", g, rec(lambda t: _write(t / "c.ckpt", b""))),
        Case("--ckpt random bytes", g, rec(lambda t: _write(t / "c.ckpt", os.urandom(4096)))),
        Case("--ckpt truncated zip", g, rec(lambda t: _write(t / "c.ckpt", b"PK\x03\x04xx"))),
        Case("--ckpt a planted pickle (torch.save)", g,
             rec(lambda t: _write(t / "c.ckpt", _evil(t))),
             check=lambda t: not (t / "pwned").exists()),
        Case("--ckpt a planted raw pickle", g, rec(_raw_pickle),
             check=lambda t: not (t / "pwned").exists()),
        Case("--ckpt a tensor, not a dict", g, rec(torch_file(None))),
        Case("--ckpt a dict without state_dict", g, rec(torch_file({"a": 1}))),
        Case("--ckpt without hyperparameters", g,
             rec(torch_file({"state_dict": {}, "hyper_parameters": {}}))),
        Case("reconstruct: output is a directory", "model command",
             lambda t: ["reconstruct", "--ckpt", str(t / "none.ckpt"), str(_good(t)), str(t)]),
        Case("reconstruct: output folder missing", "model command",
             lambda t: ["reconstruct", "--ckpt", str(t / "none.ckpt"), str(_good(t)),
                        str(t / "no" / "o.bvh")]),
    ]


def _raw_pickle(tmp: Path) -> Path:
    import pickle

    class Payload:
        def __reduce__(self):
            return (os.system, (f"touch {tmp / 'pwned'}",))

    path = tmp / "c.ckpt"
    with open(path, "wb") as f:
        f.write(pickle.dumps({"state_dict": Payload()}))
    return path


def model_cases(root: Path) -> List[Case]:
    """reconstruct / retarget / eval with a real tiny model."""
    def ckpt(t: Path) -> str:
        return str(_model(root))

    zero = _lines(lambda x: [re.sub(r"OFFSET .*", "OFFSET 0 0 0", y) for y in x])
    f0 = _lines(lambda x: x[:L_MOTION + 1] + ["Frames: 0", x[L_MOTION + 2]])
    ft30 = _lines(_set(L_MOTION + 2, "Frame Time: 30"))
    huge = _lines(_set(L_MOTION + 4, "1e30 90 1 0 0 0 20 0 0 0 0 6"))
    m = "model command"
    cases = [
        Case("reconstruct: input with Frames: 0", m,
             lambda t: ["reconstruct", "--ckpt", ckpt(t), str(_write(t / "x.bvh", f0)),
                        str(t / "o.bvh")], check=_no_output, slow=True),
        Case("reconstruct: input with zero offsets", m,
             lambda t: ["reconstruct", "--ckpt", ckpt(t), str(_write(t / "x.bvh", zero)),
                        str(t / "o.bvh")], check=_no_output, slow=True),
        Case("reconstruct: Frame Time typed as fps", m,
             lambda t: ["reconstruct", "--ckpt", ckpt(t), str(_write(t / "x.bvh", ft30)),
                        str(t / "o.bvh")], check=_no_output, slow=True),
        Case("reconstruct: root at 1e30", m,
             lambda t: ["reconstruct", "--ckpt", ckpt(t), str(_write(t / "x.bvh", huge)),
                        str(t / "o.bvh")], check=_no_output, slow=True),
        Case("reconstruct: input FIFO", m,
             lambda t: ["reconstruct", "--ckpt", ckpt(t), str(_fifo(t / "x.bvh")),
                        str(t / "o.bvh")], slow=True, timeout=60.0),
        Case("reconstruct: --window 0", m,
             lambda t: ["reconstruct", "--ckpt", ckpt(t), str(_good(t)), str(t / "o.bvh"),
                        "--window", "0"], check=_no_output, slow=True),
        Case("reconstruct: --overlap >= --window", m,
             lambda t: ["reconstruct", "--ckpt", ckpt(t), str(_good(t)), str(t / "o.bvh"),
                        "--window", "8", "--overlap", "8"], check=_no_output, slow=True),
        Case("reconstruct: good input", m,
             lambda t: ["reconstruct", "--ckpt", ckpt(t), str(_good(t)), str(t / "o.bvh")],
             expect="handled", check=_reads_back, slow=True),
        Case("reconstruct: a checkpoint with NaN weights", m,
             lambda t: ["reconstruct", "--ckpt", _nan_ckpt(root, t), str(_good(t)),
                        str(t / "o.bvh")], check=_no_output, slow=True),
        Case("retarget: target FIFO", m,
             lambda t: ["retarget", "--ckpt", ckpt(t), str(_good(t)), "--target",
                        str(_fifo(t / "t.bvh")), str(t / "o.bvh")], slow=True, timeout=60.0),
        Case("retarget: target with zero offsets", m,
             lambda t: ["retarget", "--ckpt", ckpt(t), str(_good(t)), "--target",
                        str(_write(t / "t.bvh", zero)), str(t / "o.bvh")],
             check=_no_output, slow=True),
        Case("retarget: output is a directory", m,
             lambda t: ["retarget", "--ckpt", ckpt(t), str(_good(t)), "--target",
                        str(_good(t, "t.bvh")), str(t)], slow=True),
        Case("eval: --json into a directory", m,
             lambda t: ["eval", "--ckpt", ckpt(t), "--json", str(t)], slow=True),
        Case("eval: --json folder missing", m,
             lambda t: ["eval", "--ckpt", ckpt(t), "--json", str(t / "no" / "r.json")],
             slow=True),
        Case("eval: --split bogus", m,
             lambda t: ["eval", "--ckpt", ckpt(t), "--split", "bogus"], slow=True),
        Case("eval: --data missing folder", m,
             lambda t: ["eval", "--ckpt", ckpt(t), "--data", str(t / "nowhere")], slow=True),
        Case("eval: --data with a bad file", m,
             lambda t: ["eval", "--ckpt", ckpt(t), "--data", str(_manifest(
                 root, t, [("bad", "test", _poison(_zoo_lines(root), "zero offsets"))]))],
             slow=True, timeout=120.0),
    ]
    return cases


def _bad_folder(root: Path, tmp: Path, command: str) -> List[str]:
    """``retarget`` / ``reconstruct`` over a folder of every hostile BVH
    file, a FIFO, a dangling link and two good files (one in a subfolder)."""
    src = tmp / "in"
    for i, data in enumerate(BVH_ERRORS.values()):
        _write(src / f"bad{i:03d}.bvh", data)
    _fifo(src / "fifo.bvh")
    (src / "dangling.bvh").symlink_to(tmp / "nowhere.bvh")
    _good(src, "good1.bvh")
    _good(src / "deep", "good2.bvh")
    target = ["--target", str(_good(tmp, "t.bvh"))] if command == "retarget" else []
    return [command, "--ckpt", str(_model(root)), *target, str(src), str(tmp / "out")]


def _folder_done(tmp: Path) -> bool:
    """The two good files written and readable, nothing else written, one
    error line per bad file."""
    out = tmp / "out"
    written = sorted(p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file())
    errors = [x for x in (tmp / "stderr").read_text().splitlines()
              if x.startswith("satagraph: error: ")]
    return (written == ["deep/good2.bvh", "good1.bvh"]
            and all(_reads_back_path(out / w) for w in written)
            and len(errors) == len(BVH_ERRORS) + 2)


def _reads_back_path(path: Path) -> bool:
    sys.path.insert(0, str(REPO))
    from satagraph.io import read_bvh
    import numpy as np
    return bool(np.isfinite(read_bvh(path).raw_channels).all())


def folder_cases(root: Path) -> List[Case]:
    """A folder of bad files among good ones: every bad file said, every
    good one written, the run never stopped halfway."""
    return [Case(f"{command}: a folder of {len(BVH_ERRORS) + 2} bad files and 2 good",
                 "folder", lambda t, c=command: _bad_folder(root, t, c), check=_folder_done,
                 slow=True, timeout=240.0) for command in ("reconstruct", "retarget")]


def _nan_ckpt(root: Path, tmp: Path) -> str:
    import torch
    data = torch.load(_model(root), weights_only=True)
    for key, value in data["state_dict"].items():
        if key.startswith("model.") and value.is_floating_point():
            data["state_dict"][key] = value * float("nan")
    torch.save(data, tmp / "nan.ckpt")
    return str(tmp / "nan.ckpt")


def tags_cases() -> List[Case]:
    g = "tags"
    return [
        Case("tags: --out is a directory", g,
             lambda t: ["tags", str(_good(t)), "--out", str(t)]),
        Case("tags: input FIFO", g, lambda t: ["tags", str(_fifo(t / "x.bvh"))], timeout=20.0),
        Case("tags: --dictionary not JSON", g,
             lambda t: ["tags", str(_good(t)), "--dictionary", str(_write(t / "d.json", "{x"))]),
        Case("tags: --dictionary a FIFO", g,
             lambda t: ["tags", str(_good(t)), "--dictionary", str(_fifo(t / "d.json"))],
             timeout=20.0),
        Case("tags: --out keeps the old file on failure", g,
             lambda t: ["tags", str(_write(t / "x.bvh", "")), "--out", str(_write(
                 t / "o.txt", "previous\n"))],
             check=lambda t: (t / "o.txt").read_text() == "previous\n"),
    ]


def all_cases(root: Path, quick: bool = False) -> List[Case]:
    """Every case; :obj:`quick` leaves out those that train or need a model."""
    cases = bvh_cases() + convert_cases() + checkpoint_cases() + tags_cases()
    if not quick:
        cases += training_cases(root) + model_cases(root) + folder_cases(root)
    names = [c.name for c in cases]
    assert len(names) == len(set(names)), "case names must be distinct"
    return cases


# ------------------------------------------------------------ running
def classify(case: Case, code: Optional[int], stderr: str, tmp: Path) -> str:
    """The outcome of a run (see the module docstring)."""
    if code is None:
        return "hang"
    if "Traceback (most recent call last)" in stderr:
        return "traceback"
    ok = case.check is None or _safe_check(case.check, tmp)
    if code == 0:
        return "handled" if case.expect == "handled" and ok else "silent wrong"
    lines = [x for x in stderr.splitlines() if x.strip()]
    clean = any(re.match(r"^satagraph( \w+)?: error: ", x) for x in lines)
    if not clean:
        return "traceback"
    return "clean error" if ok else "silent wrong"


def _safe_check(check: Callable[[Path], bool], tmp: Path) -> bool:
    try:
        return bool(check(tmp))
    except Exception:  # noqa: BLE001 - a failed check is a wrong result
        return False


def _error_line(stderr: str) -> str:
    lines = stderr.splitlines()
    for i, line in enumerate(lines):
        if re.match(r"^satagraph( \w+)?: error: ", line):
            if line.endswith(":") and i + 1 < len(lines):  # a list follows
                return f"{line} {lines[i + 1].strip()}"
            return line
    lines = [x for x in stderr.splitlines() if x.strip()]
    return lines[-1] if lines else ""


def run_subprocess(case: Case, tmp: Path) -> Result:
    """Run one case as ``python -m satagraph ...`` in :obj:`tmp`."""
    tmp.mkdir(parents=True, exist_ok=True)
    start = time.monotonic()
    try:
        argv = case.argv(tmp)
    except Exception as err:  # noqa: BLE001
        return Result(case, "traceback", None, 0.0, f"setup failed: {err!r}")
    env = dict(os.environ, PYTHONPATH=str(REPO), OMP_NUM_THREADS="1")
    proc = subprocess.Popen([sys.executable, "-m", "satagraph", *argv], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            errors="replace", cwd=tmp, start_new_session=True)
    try:
        out, err = proc.communicate(timeout=case.timeout)
        code: Optional[int] = proc.returncode
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        code = None
    (tmp / "stdout").write_text(out)
    (tmp / "stderr").write_text(err)
    outcome = classify(case, code, err, tmp)
    return Result(case, outcome, code, time.monotonic() - start, _error_line(err))


class _Timeout(Exception):
    pass


def run_in_process(case: Case, tmp: Path) -> Result:
    """Run one case through :func:`satagraph.cli.main` in this process
    (uncaught exceptions count as tracebacks; SIGALRM bounds the time)."""
    from satagraph.cli import main
    tmp.mkdir(parents=True, exist_ok=True)
    start = time.monotonic()
    argv = case.argv(tmp)
    out, err = io.StringIO(), io.StringIO()

    def alarm(signum, frame):
        raise _Timeout()

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.alarm(int(case.timeout))
    code: Optional[int]
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = main(argv)
            except SystemExit as exit_:
                code = exit_.code if isinstance(exit_.code, int) else 2
    except _Timeout:
        code = None
    except Exception:  # noqa: BLE001
        err.write(traceback.format_exc())
        code = 1
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    (tmp / "stdout").write_text(out.getvalue())
    (tmp / "stderr").write_text(err.getvalue())
    outcome = classify(case, code, err.getvalue(), tmp)
    return Result(case, outcome, code, time.monotonic() - start, _error_line(err.getvalue()))


def run_all(cases: Sequence[Case], root: Path, jobs: int = 2) -> List[Result]:
    """Every case as a subprocess, :obj:`jobs` at a time (the model and the
    zoo are built first)."""
    if any(c.slow for c in cases):
        _model(root)
    folders = {c.name: root / "cases" / f"{i:03d}" for i, c in enumerate(cases)}
    try:
        with ThreadPoolExecutor(jobs) as pool:
            return list(pool.map(lambda c: run_subprocess(c, folders[c.name]), cases))
    finally:
        for holder in _HOLDERS:
            holder.kill()


def format_results(results: Sequence[Result], root: Optional[Path] = None) -> str:
    """Markdown: counts by outcome, then one row per case."""
    counts = {o: sum(r.outcome == o for r in results) for o in OUTCOMES}
    unexpected = [r for r in results if r.outcome in ("clean error", "handled")
                  and (r.outcome == "handled") != (r.case.expect == "handled")]
    lines = [f"{len(results)} distinct bad inputs and failure scenarios, each run as "
             "`python -m satagraph ...` in a subprocess (60-240 s timeout).", "",
             "| outcome | cases |", "|---|---|"]
    lines += [f"| {o} | {counts[o]} |" for o in OUTCOMES]
    lines += ["", f"Expected outcome (error vs handled) met in "
              f"{len(results) - len(unexpected)} of {len(results)} cases.", "",
              "| # | group | case | expected | outcome | exit | s | message |",
              "|---|---|---|---|---|---|---|---|"]
    for r in results:
        if root is not None:
            r.message = _short(r.message, root)
    for i, r in enumerate(results):
        message = r.message.replace("|", "\\|")[:220]
        lines.append(f"| {i} | {r.case.group} | {r.case.name.replace('|', '/')} | "
                     f"{r.case.expect} | {r.outcome} | {r.code} | {r.seconds:.1f} | "
                     f"{message} |")
    return "\n".join(lines) + "\n"


def _short(text: str, root: Path) -> str:
    """A message with the work folder's paths shortened."""
    text = re.sub(re.escape(str(root)) + r"/cases/\d+/?", "", text)
    return text.replace(str(root), "<tmp>")


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true",
                        help="leave out the cases that train or need a model")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", type=Path, default=REPO / "benchmarks" / "results" /
                        "bad_inputs.md")
    parser.add_argument("--keep", type=Path, default=None,
                        help="work folder to keep (default: a temporary one)")
    args = parser.parse_args(argv)
    import tempfile
    with tempfile.TemporaryDirectory(prefix="satagraph-bad-") as tmp:
        root = args.keep or Path(tmp)
        start = time.monotonic()
        results = run_all(all_cases(root, args.quick), root, args.jobs)
        text = format_results(results, root)
        sys.path.insert(0, str(REPO))
        from satagraph.utils.files import atomic_write_text
        atomic_write_text(args.out, f"# Bad inputs\n\n{text}\nTotal "
                          f"{time.monotonic() - start:.0f} s.\n", create_parent=True)
    print(text.split("\n\nExpected")[0])
    bad = [r for r in results if r.outcome in ("traceback", "hang", "silent wrong")]
    for r in bad:
        print(f"{r.outcome}: {r.case.name}: {r.message}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
