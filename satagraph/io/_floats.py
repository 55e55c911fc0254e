r"""Vectorised parsing of whitespace-separated decimal numbers (numpy only).

BVH frame lines hold plain decimals such as ``-12.5``, ``.25`` or
``3.1e-005``. :func:`parse_decimal_table` reads them with a few whole-buffer
passes instead of one call per number, block by block (so that temporaries
stay small and are reused):

1. runs of non-blank bytes are cut at ``e``/``E`` into *pieces* (a number,
   or the exponent after a mark); one running count of digits and dots
   (the dots shifted by four bits) gives both counts for every piece;
2. all digits, copied out in order by :meth:`bytes.translate`, are read
   eight at a time as little-endian ``uint64`` words (SWAR), each piece
   through the word that ends at its last digit (two words past 8 digits);
3. each number is its digit integer :math:`m < 10^{15}` times
   :math:`10^k`, :math:`|k| \le 22`: one correctly rounded multiplication or
   division of exact doubles (Clinger's fast path), so every value is the
   double :func:`float` gives.

Anything else (``nan``, ``1,5``, ``--1``, more than 15 digits counting
leading zeros, a line with the wrong count of numbers, ...) makes it return
:obj:`None`; the caller then falls back to a general parser that also names
the offending line.
"""
from __future__ import annotations

from typing import Optional, Tuple

import numpy as np

#: Most digits in one number (or exponent) of the fast path.
MAX_DIGITS = 15
#: Bytes per block (blocks end at a line break).
BLOCK_BYTES = 1 << 18
_ALPHABET = b"0123456789 \t\r\n.-+eE"
_NOT_DIGITS = b" \t\r\n.-+eE"
_POW10 = 10.0 ** np.arange(23)  # exact in float64
_U64 = np.uint64
_ZEROS = _U64(0x3030303030303030)  # eight ASCII '0'
#: _KEEP[z] clears the z first (lowest) bytes of a little-endian word.
_KEEP = np.array([(~((1 << (8 * z)) - 1)) & (2**64 - 1) for z in range(9)],
                 dtype=np.uint64)


def parse_decimal_table(raw: bytes, rows: int, cols: int) -> Optional[np.ndarray]:
    r"""The numbers of :obj:`raw`, :obj:`cols` per line on :obj:`rows`
    non-blank lines, or :obj:`None` where the fast path does not apply.

    Numbers are separated by spaces or tabs, lines end with ``\n`` (or
    ``\r\n``); blank lines are skipped.

    Args:
        raw (bytes): The text of the lines.
        rows (int): Expected count of non-blank lines.
        cols (int): Expected count of numbers on each of them.

    Shapes:
        - **output**: :math:`(rows, cols)`, float64
    """
    if not raw or raw.translate(None, _ALPHABET) or not _crlf_only(raw):
        return None
    exponents = b"e" in raw or b"E" in raw
    values, counts = [], []
    start = 0
    while start < len(raw):
        stop = raw.find(b"\n", start + BLOCK_BYTES) + 1 or len(raw)
        block = _parse_block(raw[start:stop], exponents)
        if block is None:
            return None
        values.append(block[0])
        counts.append(block[1])
        start = stop
    per_line = np.concatenate(counts)
    filled = per_line[per_line > 0]
    if filled.size != rows or not (filled == cols).all():
        return None
    return np.concatenate(values).reshape(rows, cols)


def _crlf_only(raw: bytes) -> bool:
    r"""Whether every ``\r`` is followed by ``\n``."""
    if b"\r" not in raw:
        return True
    b = np.frombuffer(raw, dtype=np.uint8)
    cr = np.flatnonzero(b == 13)
    return cr[-1] + 1 < b.size and bool((b[cr + 1] == 10).all())


def _parse_block(raw: bytes, exponents: bool) -> Optional[Tuple[np.ndarray, np.ndarray]]:
    """Values of the numbers of some whole lines, and the count of numbers
    on each line; :obj:`None` outside the fast path."""
    b = np.frombuffer(raw, dtype=np.uint8)
    pieces = _pieces(b, exponents)
    if pieces is None:
        return None
    starts, ends, is_exp = pieces
    counts = _piece_counts(raw, b, starts, ends, is_exp) if starts.size else None
    if counts is None:
        return None if starts.size else (np.empty(0), np.zeros(1, dtype=np.intp))
    num_digits, fraction, minus = counts
    mantissa = _digit_integers(raw, num_digits)
    if exponents:
        value = _with_exponents(mantissa, fraction, minus, is_exp)
        numbers, minus = starts[~is_exp], minus[~is_exp]
    else:
        value = mantissa / _POW10[fraction]
        numbers = starts
    if value is None:
        return None
    value *= np.where(minus, -1.0, 1.0)  # exact, and keeps -0.0
    per_line = np.diff(np.searchsorted(numbers, np.flatnonzero(b == 10)),
                       prepend=0, append=numbers.size)
    return value, per_line


def _pieces(b: np.ndarray, exponents: bool
            ) -> Optional[Tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Start and end (exclusive) of the runs between blanks and exponent
    marks, and whether each run is an exponent; :obj:`None` unless every
    mark sits between a number and its exponent (not ``e5``, ``1e``,
    ``1e5e3``)."""
    solid = b > 32
    if exponents:
        expo = (b == 101) | (b == 69)
        solid &= ~expo
    edges = np.flatnonzero(solid[1:] != solid[:-1]) + 1
    if b.size and solid[0]:
        edges = np.concatenate(([0], edges))
    if b.size and solid[-1]:
        edges = np.concatenate((edges, [b.size]))
    starts, ends = edges[0::2].copy(), edges[1::2].copy()  # contiguous
    if not exponents:
        return starts, ends, np.zeros(starts.size, dtype=bool)
    is_exp = expo[starts - 1] & (starts > 0)
    before_e = expo[np.minimum(ends, b.size - 1)] & (ends < b.size)
    marks = np.count_nonzero(expo)
    if (np.count_nonzero(is_exp) != marks or np.count_nonzero(before_e) != marks
            or (is_exp & before_e).any()):
        return None
    return starts, ends, is_exp


def _piece_counts(raw: bytes, b: np.ndarray, starts: np.ndarray, ends: np.ndarray,
                  is_exp: np.ndarray
                  ) -> Optional[Tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Digits, digits after the dot and minus sign of each piece; :obj:`None`
    unless each is ``[-]digits[.digits]`` (``+`` allowed on exponents, dots
    not)."""
    # Running count of digits (low nibble) and of dots (the bits above).
    is_dot = b == 46
    code = ((b - 48) <= 9).view(np.uint8) | (is_dot.view(np.uint8) << 4)
    running = np.empty(b.size + 1, dtype=np.int32)
    running[0] = 0
    np.cumsum(code, dtype=np.int32, out=running[1:])
    both = running[ends]
    both -= running[starts]
    num_digits, dots = both & 15, both >> 4
    first = b[starts]
    minus = first == 45
    # Every byte of a piece must be a digit, its dot or its leading sign: a
    # second sign, any other byte or a count past its nibble leaves a rest.
    rest = ends - starts
    rest -= num_digits
    rest -= dots
    rest -= minus
    if b"+" in raw:
        plus = first == 43
        if (plus & ~is_exp).any():
            return None
        rest -= plus
    if (rest.any() or num_digits.min() < 1 or num_digits.max() > MAX_DIGITS
            or dots.max() > 1 or (dots.astype(bool) & is_exp).any()):
        return None
    point = np.flatnonzero(is_dot)
    if point.size == starts.size:  # every piece has a dot
        fraction = ends - point
    else:
        dotted = np.flatnonzero(dots)
        fraction = np.ones(starts.size, dtype=np.intp)
        fraction[dotted] = ends[dotted] - point
    fraction -= 1
    return num_digits, fraction, minus


def _digit_integers(raw: bytes, num_digits: np.ndarray) -> np.ndarray:
    """Integer formed by the :obj:`num_digits` (at most 15) digits of each
    piece, in float64 (exact)."""
    pad = 16
    stream = b"0" * pad + raw.translate(None, _NOT_DIGITS)
    words = np.ndarray((len(stream) - 7,), dtype="<u8", buffer=stream, strides=(1,))
    last = np.cumsum(num_digits)
    last += pad - 8  # word ending at the piece's last digit
    out = _eight_digits(words[last], np.maximum(8 - num_digits, 0))
    long = np.flatnonzero(num_digits > 8)  # rare: eight more digits
    if long.size:
        out[long] += 1e8 * _eight_digits(words[last[long] - 8], 16 - num_digits[long])
    return out


def _eight_digits(word: np.ndarray, skip: np.ndarray) -> np.ndarray:
    """Value of eight ASCII digits packed little-endian (first digit in the
    lowest byte), the first :obj:`skip` of them taken as zeros; float64."""
    x = word - _ZEROS
    x &= _KEEP[skip]
    pairs = x >> _U64(8)
    x *= _U64(10)
    x += pairs  # 16-bit lanes: 10 * digit + next digit
    low = x & _U64(0x000000FF000000FF)
    low *= _U64(100 + (1000000 << 32))
    x >>= _U64(16)
    x &= _U64(0x000000FF000000FF)
    x *= _U64(1 + (10000 << 32))
    x += low
    x >>= _U64(32)
    return x.astype(np.float64)


def _with_exponents(mantissa: np.ndarray, fraction: np.ndarray, minus: np.ndarray,
                    is_exp: np.ndarray) -> Optional[np.ndarray]:
    """Numbers (the pieces that are not exponents) with their exponents
    applied; signs of numbers are left to the caller."""
    value, power = mantissa[~is_exp], -fraction[~is_exp]
    owner = np.flatnonzero(is_exp)  # the number before each exponent ...
    owner -= np.arange(1, owner.size + 1)  # ... counted among numbers only
    exp_value = mantissa[is_exp].astype(np.intp)
    power[owner] += np.where(minus[is_exp], -exp_value, exp_value)
    power[value == 0] = 0
    if power.size and np.abs(power).max() > 22:
        return None
    up = power > 0
    value /= _POW10[np.where(up, 0, -power)]
    if up.any():
        value[up] *= _POW10[power[up]]
    return value
