"""CSV rows formatted by a compiled loop (numba): the text pyarrow's writer gives, byte for byte.

:func:`softtip.io.tables.write_table` writes a float as pyarrow's CSV writer writes the value
rounded to ``d`` significant digits by :func:`softtip.io.tables._round_significant`: the
shortest text that reads back to it, in pyarrow's layout (``nan``, ``inf``, ``-0``; plain
decimals for decimal exponents -6 to 9, ``0.00001``, ``45``, ``1234567890``; else
``1.5e+10``, ``1e-7``). Here the same rounding is done in the same float operations: with
``p = floor(log10(|x|))`` and ``k = d - 1 - p``, ``m = rint(x * 10**k)`` (``x / 10**-k`` for
``k < 0``), round half to even, ``10**k`` exact for ``|k|`` ≤ 22. The digits of the integer
``m`` are then the shortest text: for ``d`` ≤ :data:`MAX_DIGITS` the float nearest ``m /
10**k`` has no other decimal of as few digits within its rounding interval (distinct decimals
of at most 14 digits lie at least 1e-14 apart, relative; the interval is 2.2e-16 wide). So no
float-to-shortest algorithm is needed, only integer digits, two at a time from a table.

``p`` is taken from the float's binary exponent (``floor(e2 * log10(2))``, then one
comparison with the nearest float to a power of ten) where numpy's ``log10`` gave it to the
rounding before. The two may differ only for ``|x|`` within a few units in the last place of
a power of ten ``10**q``; there either scale rounds ``x`` to ``10**q`` exactly (its distance
to ``10**q``, relative 1e-15 at most, is far below half a unit of the 14th digit), so the
text is the same.

Values the rounding does not take in one step (``|k|`` > 22: ``|x|`` below about
``10**(d-23)`` or from ``10**(d+22)`` on, subnormals, 1e±308) are formatted by the caller the
fallback's way and handed in as text, in the order the loop meets them: a call without those
texts collects the values instead (:func:`format_rows` says how many) and is run again with
them, which only blocks holding such values pay.

Measured (``python benchmarks/bench_core.py --only bounds``, one thread, CPU time, the 39 float
columns of ``softtip estimate``'s output, NaN cells included): 18 ns per number, rounding
included, against 83 ns for the fallback (softtip's rounding, then pyarrow's writer) and 48-59
ns for this loop when it took numpy's exponents and made the digits two at a time from a table
(a signed division chain, a pass of ``log10``, fresh buffers each block). ``benchmarks/csv_sweep.py``
compares it with both on 1e8 random values.
"""

from __future__ import annotations

import numpy as np

from softtip.core._jit import jitable, lazy_jit

__all__ = ["FLOAT_CELL_BYTES", "MAX_DIGITS", "SLACK_BYTES", "format_rows"]

#: Significant digits the compiled formatter takes (the argument above needs at most 14
#: digits in ``m``, one more than asked where ``p`` lands on the other side of a power of ten).
MAX_DIGITS = 13

#: The longest text of one float cell is this plus its digits: a sign, ``0.`` and five
#: zeros (``-0.000001234``), or a sign, a point and ``e-308``.
FLOAT_CELL_BYTES = 8

#: Bytes ``out`` needs beyond the text: a float's digits are stored as whole words (two of 8
#: bytes, up to 13 bytes after the cell's start, before the rest is cut off).
SLACK_BYTES = 32

# Exact powers of ten, 10**0 .. 10**22 (every one is a float64 exactly): the rounding's scales.
_POW10 = 10.0 ** np.arange(23)
# The float nearest 10**q for q = -_TEN_LOW .. 309 (0.0 below the subnormals, inf above the
# largest float): the comparison that settles ``p``.
_TEN_LOW = 345
_TENS = np.array([float(f"1e{q}") for q in range(-_TEN_LOW, 310)])
# "00" "01" ... "99": two digits of an integer at a time.
# unsigned constants: the digits' arithmetic stays unsigned (no float promotion in numba)
_U8, _U10 = np.uint64(10**8), np.uint64(10)
_U1, _U2B, _U8B, _U48, _U56, _U64 = np.uint64(1), np.uint64(2), np.uint64(8), np.uint64(48), np.uint64(56), np.uint64(64)
# eight '0' characters; "0.000000"
_ZEROS = np.uint64(0x3030303030303030)
_DECIMAL_ZEROS = np.uint64(int.from_bytes(b"0.000000", "little"))
_INT64_MIN = -(2**63)
_INT64_MIN_TEXT = np.frombuffer(str(2**63).encode("ascii"), dtype=np.uint8).copy()
_PAIRS = np.frombuffer("".join(f"{i:02d}" for i in range(100)).encode("ascii"), dtype=np.uint8).copy()


@jitable
def _text8(v):  # pragma: no cover - compiled
    """The 8 decimal digits of ``v`` < 10**8 (leading zeros) as ASCII in a uint64, the first
    digit in the lowest byte: split in halves of 4 digits, 2, 1, each step for every part at
    once in its lane of the word (divisions by 100 and 10 as multiplications, exact below
    10**4 and 10**2)."""
    a = v // np.uint64(10000)
    x = a | ((v - a * np.uint64(10000)) << np.uint64(32))
    q = ((x * np.uint64(5243)) >> np.uint64(19)) & np.uint64(0x0000007F0000007F)
    y = q + ((x - q * np.uint64(100)) << np.uint64(16))
    t = ((y * np.uint64(103)) >> np.uint64(10)) & np.uint64(0x000F000F000F000F)
    return (t + ((y - t * np.uint64(10)) << np.uint64(8))) | np.uint64(0x3030303030303030)


@jitable
def _top_byte(z):  # pragma: no cover - compiled
    """The index of the highest byte of ``z`` (not 0) that is not 0: 0 to 7 (shifts chosen by
    arithmetic, not branches: which byte varies from cell to cell)."""
    s = np.uint64((z >> np.uint64(32)) != 0) << np.uint64(5)
    z >>= s
    t = np.uint64((z >> np.uint64(16)) != 0) << np.uint64(4)
    z >>= t
    u = np.uint64((z >> np.uint64(8)) != 0) << np.uint64(3)
    return np.int64((s + t + u) >> np.uint64(3))


@jitable
def _put8(out, at, w):  # pragma: no cover - compiled
    """``w``'s 8 bytes into ``out[at:at + 8]`` (LLVM makes one store of them: ``at`` unsigned)."""
    out[at] = w & np.uint64(0xFF)
    out[at + np.uint64(1)] = (w >> np.uint64(8)) & np.uint64(0xFF)
    out[at + np.uint64(2)] = (w >> np.uint64(16)) & np.uint64(0xFF)
    out[at + np.uint64(3)] = (w >> np.uint64(24)) & np.uint64(0xFF)
    out[at + np.uint64(4)] = (w >> np.uint64(32)) & np.uint64(0xFF)
    out[at + np.uint64(5)] = (w >> np.uint64(40)) & np.uint64(0xFF)
    out[at + np.uint64(6)] = (w >> np.uint64(48)) & np.uint64(0xFF)
    out[at + np.uint64(7)] = (w >> np.uint64(56)) & np.uint64(0xFF)


@lazy_jit
def format_rows(floats, ints, codes, cell_off, data, quote, layout, digits, far_off, far_data, far_values, out, n):  # pragma: no cover - compiled
    """Write ``n`` CSV rows into ``out``; return the bytes written and the far cells met.

    The buffers may be wider than ``n`` (reused from block to block): the first ``n`` of each row.

    Parameters
    ----------
    floats : ndarray of float64, shape (nf, n) or wider
        The float columns' values (not rounded), a column a row; the first ``n`` of each.
    ints : ndarray of int64, shape (ni, n) or wider
        The integer and boolean columns (booleans as 0 and 1).
    codes : ndarray of int64, shape (nt, n) or wider
        For each text column and row: the index of its cell in ``cell_off``.
    cell_off : ndarray of int64, shape (cells + 1,)
        Cell ``c`` is ``data[cell_off[c]:cell_off[c + 1]]`` (UTF-8).
    data : ndarray of uint8
    quote : ndarray of bool, shape (nt,)
        Text columns whose cells may need quotes: each cell of them that holds a comma, a
        quote or a line break is quoted (``"`` doubled inside), the others are not.
    layout : ndarray of int64, shape (ncols, 2)
        Column ``c`` is float column ``layout[c, 1]`` when ``layout[c, 0]`` is 0, integer
        column when 1, text column when 2.
    digits : int
        Significant digits, 1 to :data:`MAX_DIGITS`.
    far_off, far_data : ndarray of int64, uint8
        The text of the float cells outside the one-step rounding range, in the order the
        loop meets them (row by row), or none.
    far_values : ndarray of float64
        Where the values of the far cells met beyond those texts are put (as many as fit).
    out : ndarray of uint8
        Large enough for the rows (the caller's bound).

    Returns
    -------
    used : int
        Bytes written. Complete only when ``far`` ≤ the texts given.
    far : int
        Far cells met: more than the texts given means the text is incomplete; the values
        are in ``far_values``.
    """
    ncols = layout.shape[0]
    pow10 = _POW10
    tens = _TENS
    pairs = _PAIRS
    scratch = np.empty(24, dtype=np.uint8)
    bits = np.empty(1, dtype=np.float64)
    ibits = bits.view(np.int64)
    unit = np.uint64(1)
    for _ in range(digits):
        unit *= _U10  # 10**digits: m reaches it where the rounding carries into a new digit
    # where the digits of v sit in the text of hi (8 characters) and lo (8 characters)
    short = digits <= 8
    if short:
        shift = np.uint64(8 * (8 - digits))
        back = np.uint64(0)
    else:
        shift = np.uint64(8 * (16 - digits))
        back = _U64 - shift
    pad0 = _ZEROS << np.uint64(8 * digits) if digits < 8 else np.uint64(0)
    pad1 = _ZEROS << np.uint64(8 * (digits - 8)) if 8 < digits < 16 else np.uint64(0)
    nfar = 0
    given = far_off.shape[0] - 1
    pos = 0
    for i in range(n):
        for c in range(ncols):
            if c:
                out[pos] = 44  # ,
                pos += 1
            kind = layout[c, 0]
            j = layout[c, 1]
            if kind == 2:
                cell = codes[j, i]
                a = cell_off[cell]
                b = cell_off[cell + 1]
                needs = False  # quoted only when it holds a comma, a quote or a line break (minimal quoting)
                if quote[j]:
                    for p in range(a, b):
                        ch = data[p]
                        if ch == 44 or ch == 34 or ch == 10 or ch == 13:
                            needs = True
                            break
                if needs:
                    out[pos] = 34
                    pos += 1
                    for p in range(a, b):
                        ch = data[p]
                        out[pos] = ch
                        pos += 1
                        if ch == 34:
                            out[pos] = 34
                            pos += 1
                    out[pos] = 34
                    pos += 1
                else:
                    for p in range(a, b):
                        out[pos] = data[p]
                        pos += 1
                continue
            if kind == 1:
                v = ints[j, i]
                if v == 0 or v == 1:  # booleans, mostly
                    out[pos] = 48 + v
                    pos += 1
                    continue
                if v < 0:
                    out[pos] = 45
                    pos += 1
                    if v == _INT64_MIN:  # no positive int64 of its size
                        for q in range(_INT64_MIN_TEXT.shape[0]):
                            out[pos] = _INT64_MIN_TEXT[q]
                            pos += 1
                        continue
                    v = -v
                q = 24
                while v >= 100:
                    r = v % 100
                    v //= 100
                    q -= 2
                    scratch[q] = pairs[2 * r]
                    scratch[q + 1] = pairs[2 * r + 1]
                if v >= 10:
                    q -= 2
                    scratch[q] = pairs[2 * v]
                    scratch[q + 1] = pairs[2 * v + 1]
                else:
                    q -= 1
                    scratch[q] = 48 + v
                for p in range(q, 24):
                    out[pos] = scratch[p]
                    pos += 1
                continue
            x = floats[j, i]
            if x != x:
                out[pos] = 110  # nan
                out[pos + 1] = 97
                out[pos + 2] = 110
                pos += 3
                continue
            ax = abs(x)
            if ax == np.inf:
                if x < 0:
                    out[pos] = 45
                    pos += 1
                out[pos] = 105  # inf
                out[pos + 1] = 110
                out[pos + 2] = 102
                pos += 3
                continue
            if ax == 0.0:  # a zero: its sign as pyarrow writes it
                if np.signbit(x):
                    out[pos] = 45
                    pos += 1
                out[pos] = 48
                pos += 1
                continue
            # p = floor(log10(ax)): from the binary exponent e2, floor(e2 * log10(2)) is p or p - 1
            bits[0] = ax
            e2 = ((ibits[0] >> 52) & 0x7FF) - 1023
            p = (e2 * 78913) >> 18
            if ax >= tens[p + 1 + _TEN_LOW]:
                p += 1
            k = digits - 1 - p
            if 0 <= k <= 22:
                m = np.rint(ax * pow10[k])
            elif -22 <= k < 0:
                m = np.rint(ax / pow10[-k])
            else:
                if nfar < given:
                    for q in range(far_off[nfar], far_off[nfar + 1]):
                        out[pos] = far_data[q]
                        pos += 1
                elif nfar - given < far_values.shape[0]:
                    far_values[nfar - given] = x
                nfar += 1
                continue
            out[pos] = 45  # a minus sign, kept only when negative (no branch to mispredict)
            pos += x < 0.0
            o = np.uint64(pos)  # unsigned indices: numba adds no wraparound, LLVM merges byte stores into words
            v = np.uint64(m)
            if v >= unit:  # carried into a new digit (9.99...95 -> 10): one digit fewer, p one up
                v //= _U10
                p += 1
            # the digits as text in two words, d0 the first character (little-endian), '0' after the last
            hi = v // _U8
            lo_text = _text8(v - hi * _U8)
            if short:
                d0 = (lo_text >> shift) | pad0
                d1 = _ZEROS
            else:
                if digits <= 10:  # hi < 100: its two digits by one multiplication, in the word's top bytes
                    tens_digit = (hi * np.uint64(103)) >> np.uint64(10)
                    hi_text = (tens_digit | ((hi - tens_digit * _U10) << _U8B) | np.uint64(0x3030)) << _U48
                else:
                    hi_text = _text8(hi)
                d0 = (hi_text >> shift) | (lo_text << back)
                d1 = (lo_text >> shift) | pad1
            # nd: the digits up to the last that is not a zero (the first is not)
            z = d1 ^ _ZEROS
            nd = 9 + _top_byte(z) if z else 1 + _top_byte(d0 ^ _ZEROS)
            if -6 <= p < 10:
                if p < 0:  # 0.000ddd: a word of "0.000000", the digits over it
                    _put8(out, o, _DECIMAL_ZEROS)
                    at = o + np.uint64(1 - p)
                    _put8(out, at, d0)
                    _put8(out, at + _U8B, d1)
                    pos += 1 - p + nd
                elif p >= nd - 1:  # an integer: the first p + 1 characters (zeros padded in)
                    _put8(out, o, d0)
                    _put8(out, o + _U8B, d1)
                    pos += p + 1
                else:  # ddd.ddd: the digits, then the point and the rest shifted one place on
                    _put8(out, o, d0)
                    _put8(out, o + _U8B, d1)
                    at = o + np.uint64(p + 1)
                    out[at] = 46
                    sh = np.uint64(8 * (p + 1))
                    if sh < _U64:
                        t0 = (d0 >> sh) | (d1 << (_U64 - sh))
                        t1 = d1 >> sh
                    else:
                        t0 = d1 >> (sh - _U64)
                        t1 = _ZEROS
                    _put8(out, at + _U1, t0)
                    _put8(out, at + _U1 + _U8B, t1)
                    pos += nd + 1
            else:  # d.ddde+XX
                _put8(out, o, d0)
                out[o + _U1] = 46
                _put8(out, o + _U2B, (d0 >> _U8B) | (d1 << _U56))
                _put8(out, o + _U2B + _U8B, d1 >> _U8B)
                pos += nd + (nd > 1)
                out[pos] = 101  # e
                out[pos + 1] = 43 if p >= 0 else 45
                pos += 2
                ap = p if p >= 0 else -p
                if ap >= 100:
                    out[pos] = 48 + ap // 100
                    pos += 1
                    ap %= 100
                    out[pos] = pairs[2 * ap]
                    out[pos + 1] = pairs[2 * ap + 1]
                    pos += 2
                elif ap >= 10:
                    out[pos] = pairs[2 * ap]
                    out[pos + 1] = pairs[2 * ap + 1]
                    pos += 2
                else:
                    out[pos] = 48 + ap
                    pos += 1
        out[pos] = 10
        pos += 1
    return pos, nfar
