"""Vectorised decimal parsing of frame lines: exact values, layouts, and the
cases left to the general parser."""
from __future__ import annotations

from pathlib import Path
from typing import List

import numpy as np
import pytest

from satagraph.io import _floats, read_bvh
from satagraph.io._floats import parse_decimal_table


def table(tokens: List[str], cols: int, sep: str = " ", newline: str = "\n") -> bytes:
    rows = [sep.join(tokens[i:i + cols]) for i in range(0, len(tokens), cols)]
    return (newline.join(rows) + newline).encode()


def assert_same_as_float(tokens: List[str], cols: int, **layout) -> None:
    got = parse_decimal_table(table(tokens, cols, **layout), len(tokens) // cols, cols)
    assert got is not None
    want = np.array([float(t) for t in tokens]).reshape(-1, cols)
    np.testing.assert_array_equal(got, want)
    np.testing.assert_array_equal(np.signbit(got), np.signbit(want))  # -0.0


def random_tokens(count: int, seed: int) -> List[str]:
    rng = np.random.default_rng(seed)
    out = []
    for value, style in zip(rng.normal(0, 10.0 ** rng.integers(-3, 5, count)),
                            rng.integers(0, 6, count)):
        if style == 0:
            out.append(f"{value:.{rng.integers(0, 9)}f}")
        elif style == 1:
            out.append(f"{value:.{rng.integers(1, 9)}e}")  # 1.234e-05
        elif style == 2:
            out.append(f"{value:.6g}".replace("e-0", "e-00"))  # 3.12669e-005
        elif style == 3:
            out.append(f"{value:.11g}")  # many significant digits
        elif style == 4:
            out.append(str(int(value)))
        else:
            out.append(f"{value:.4f}".replace("0.", ".", 1))  # .25, -.5
    return out


def test_random_values_bit_exact():
    assert_same_as_float(random_tokens(6000, seed=0), cols=6)


@pytest.mark.parametrize("tokens", [
    ["0", "-0", "-0.0", "0.000", "-.0", "5.", "-5.", ".5", "-.5", "007.50"],
    ["1e5", "1E5", "1e+05", "-1e-005", "2.5E-3", "0e99", "-0e-99", "9e22", "1e-22",
     "123456789012345"],
    ["999999999999999", "-0.00000000000001", "12345678.9", "1234567.89012345",
     "0.12345678901234", "-9876543210987.6", "1", "12", "123", "1234"],
])
def test_edge_values(tokens):
    assert_same_as_float(tokens, cols=len(tokens))


@pytest.mark.parametrize("layout", [
    dict(sep="\t"), dict(sep="  \t "), dict(newline="\r\n"), dict(newline="\n\n"),
    dict(newline=" \r\n\t\r\n"),
])
def test_layouts(layout):
    assert_same_as_float(random_tokens(60, seed=1), cols=6, **layout)


def test_indent_no_final_newline_and_blocks(monkeypatch):
    monkeypatch.setattr(_floats, "BLOCK_BYTES", 50)  # many blocks
    tokens = random_tokens(300, seed=2)
    raw = b"\n  " + table(tokens, 5)[:-1]
    got = parse_decimal_table(raw, 60, 5)
    np.testing.assert_array_equal(got, np.array([float(t) for t in tokens]).reshape(60, 5))


def test_blank_block(monkeypatch):
    monkeypatch.setattr(_floats, "BLOCK_BYTES", 4)  # the last blocks are blank
    got = parse_decimal_table(b"1 2\n3 -4\n" + b"\n" * 20, 2, 2)
    np.testing.assert_array_equal(got, [[1, 2], [3, -4]])


@pytest.mark.parametrize("token", [
    "nan", "inf", "-inf", "+1.5", "1,5", "--1", "1-2", "1.2.3", ".", "-", "-.", "1e",
    "e5", "1e5e3", "1.5e+", "1e2.5", "0x10", "1_0", "1234567890123456",
    "0.123456789012345", "1e-30", "1e23", "1e99999", "\x0b1", "1\x00", "\u00e91",
])
def test_outside_fast_path(token):
    raw = table(["1.5", token, "-2"], 3)
    assert parse_decimal_table(raw, 1, 3) is None
    assert parse_decimal_table(table(["1.5", "1", "-2"], 3), 1, 3) is not None


@pytest.mark.parametrize("raw, rows, cols", [
    (b"1 2 3\n4 5\n", 2, 3),  # short line
    (b"1 2 3\n4 5 6 7\n", 2, 3),  # long line
    (b"1 2 3\n4 5 6\n", 1, 3),  # more lines
    (b"1 2 3\n", 2, 3),  # fewer lines
    (b"1 2 3\r4 5 6\n", 2, 3),  # a lone carriage return
    (b"", 1, 3),
])
def test_wrong_shapes(raw, rows, cols):
    assert parse_decimal_table(raw, rows, cols) is None


BVH = """\
HIERARCHY
ROOT Hips
{{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  End Site
  {{
    OFFSET 0 5 0
  }}
}}
MOTION
Frames: 2
Frame Time: 0.033333
{}
{}
"""


@pytest.mark.parametrize("frame", [
    "0 1.5e-005 -2 10 -20.25 .5",  # fast path
    "0 +1.5 -2 10 -20.25 1e-30",  # general parser
])
def test_read_bvh_values(tmp_path: Path, frame):
    path = tmp_path / "clip.bvh"
    path.write_text(BVH.format(frame, frame))
    want = [float(t) for t in frame.split()]
    np.testing.assert_array_equal(read_bvh(path).raw_channels, [want, want])
