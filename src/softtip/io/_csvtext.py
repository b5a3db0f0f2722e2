"""CSV rows formatted by a compiled loop (numba): the text pyarrow's writer gives, byte for byte.

:func:`softtip.io.tables.write_table` writes a float as pyarrow's CSV writer writes the value
rounded to ``d`` significant digits by :func:`softtip.io.tables._round_significant`: the
shortest text that reads back to it, in pyarrow's layout (``nan``, ``inf``, ``-0``; plain
decimals for decimal exponents -6 to 9, ``0.00001``, ``45``, ``1234567890``; else
``1.5e+10``, ``1e-7``). Here the same rounding is done in the same float operations (``x *
10**k``, round half to even, the exponent ``k`` taken from the caller, who computes it with
numpy as the fallback does), and the digits of the rounded integer ``m`` are the shortest
text: for ``d`` ≤ :data:`MAX_DIGITS` the float nearest ``m / 10**k`` has no other decimal of
as few digits within its rounding interval (distinct decimals of at most 14 digits lie at
least 1e-14 apart, relative; the interval is 2.2e-16 wide). So no float-to-shortest
algorithm is needed, only integer digits.

Values the rounding does not take in one step (``|x|`` below about ``10**(d-23)`` or from
``10**(d+22)`` on: subnormals, 1e±308) are formatted by the caller the fallback's way and
handed in as text, in the order the loop meets them.

Measured (``python benchmarks/bench_core.py --only bounds``, one thread, CPU time): 48-59 ns per
number, rounding included, against 79-83 ns for the fallback (softtip's rounding, then
pyarrow's writer) and 94 ns for pyarrow's writer alone.
"""

from __future__ import annotations

import numpy as np

from softtip.core._jit import lazy_jit

__all__ = ["MAX_DIGITS", "format_rows"]

#: Significant digits the compiled formatter takes (the argument above needs at most 14
#: digits in ``m``, one more than asked where numpy's ``log10`` lands on the other side of
#: a power of ten).
MAX_DIGITS = 13

# Exact powers of ten, 10**0 .. 10**22 (every one is a float64 exactly).
_POW10 = 10.0 ** np.arange(23)


@lazy_jit
def format_rows(floats, exps, codes, cell_off, data, quote, layout, far_off, far_data, out):  # pragma: no cover - compiled
    """Write ``n`` CSV rows into ``out``; return the bytes written.

    Parameters
    ----------
    floats : ndarray of float64, shape (nf, n)
        The float columns' values (not rounded), a column a row.
    exps : ndarray of float64, shape (nf, n)
        ``d - 1 - floor(log10(|x|))`` of each value, as numpy computes it (NaN for NaN,
        +inf for zero, -inf for infinities).
    codes : ndarray of int64, shape (nt, n)
        For each text column and row: the index of its cell in ``cell_off``.
    cell_off : ndarray of int64, shape (cells + 1,)
        Cell ``c`` is ``data[cell_off[c]:cell_off[c + 1]]`` (UTF-8).
    data : ndarray of uint8
    quote : ndarray of bool, shape (nt,)
        Text columns whose cells are quoted (``"`` doubled inside).
    layout : ndarray of int64, shape (ncols,)
        Column ``c`` is float column ``layout[c]`` when ≥ 0, else text column ``-1 - layout[c]``.
    far_off, far_data : ndarray of int64, uint8
        The text of the float cells outside the one-step rounding range, row by row.
    out : ndarray of uint8
        Large enough for the rows (the caller's bound).
    """
    n = floats.shape[1] if floats.shape[0] else codes.shape[1]
    ncols = layout.shape[0]
    digs = np.empty(24, dtype=np.uint8)
    pow10 = _POW10
    pos = 0
    far = 0
    for i in range(n):
        for c in range(ncols):
            if c:
                out[pos] = 44  # ,
                pos += 1
            j = layout[c]
            if j < 0:
                t = -1 - j
                cell = codes[t, i]
                a = cell_off[cell]
                b = cell_off[cell + 1]
                if quote[t]:
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
            x = floats[j, i]
            k = exps[j, i]
            if x != x:
                out[pos] = 110  # nan
                out[pos + 1] = 97
                out[pos + 2] = 110
                pos += 3
                continue
            if x == np.inf or x == -np.inf:
                if x < 0:
                    out[pos] = 45
                    pos += 1
                out[pos] = 105  # inf
                out[pos + 1] = 110
                out[pos + 2] = 102
                pos += 3
                continue
            if 0.0 <= k <= 22.0:
                m = np.rint(x * pow10[int(k)])
                e = -int(k)
            elif -22.0 <= k < 0.0:
                m = np.rint(x / pow10[int(-k)])
                e = int(-k)
            elif x == 0.0:
                m = x
                e = 0
            else:
                a = far_off[far]
                b = far_off[far + 1]
                far += 1
                for p in range(a, b):
                    out[pos] = far_data[p]
                    pos += 1
                continue
            if m == 0.0:  # a zero: its sign as pyarrow writes it
                if np.signbit(m):
                    out[pos] = 45
                    pos += 1
                out[pos] = 48
                pos += 1
                continue
            if m < 0.0:
                out[pos] = 45
                pos += 1
                v = np.int64(-m)
            else:
                v = np.int64(m)
            while v % 10 == 0:
                v //= 10
                e += 1
            nd = 0  # the digits, least significant first, two per division (22 % faster than one)
            while v >= 100:
                r = v % 100
                v //= 100
                digs[nd] = 48 + r % 10
                digs[nd + 1] = 48 + r // 10
                nd += 2
            if v >= 10:
                digs[nd] = 48 + v % 10
                digs[nd + 1] = 48 + v // 10
                nd += 2
            elif v:
                digs[nd] = 48 + v
                nd += 1
            point = nd + e  # digits before the decimal point
            x10 = point - 1  # the decimal exponent of the first digit
            if -6 <= x10 < 10:
                if point <= 0:
                    out[pos] = 48
                    out[pos + 1] = 46
                    pos += 2
                    for _ in range(-point):
                        out[pos] = 48
                        pos += 1
                    for q in range(nd - 1, -1, -1):
                        out[pos] = digs[q]
                        pos += 1
                elif point >= nd:
                    for q in range(nd - 1, -1, -1):
                        out[pos] = digs[q]
                        pos += 1
                    for _ in range(point - nd):
                        out[pos] = 48
                        pos += 1
                else:
                    for q in range(nd - 1, nd - 1 - point, -1):
                        out[pos] = digs[q]
                        pos += 1
                    out[pos] = 46
                    pos += 1
                    for q in range(nd - 1 - point, -1, -1):
                        out[pos] = digs[q]
                        pos += 1
            else:
                out[pos] = digs[nd - 1]
                pos += 1
                if nd > 1:
                    out[pos] = 46
                    pos += 1
                    for q in range(nd - 2, -1, -1):
                        out[pos] = digs[q]
                        pos += 1
                out[pos] = 101  # e
                out[pos + 1] = 43 if x10 >= 0 else 45
                pos += 2
                ax = x10 if x10 >= 0 else -x10
                ne = 0
                while True:
                    digs[ne] = 48 + ax % 10
                    ax //= 10
                    ne += 1
                    if ax == 0:
                        break
                for q in range(ne - 1, -1, -1):
                    out[pos] = digs[q]
                    pos += 1
        out[pos] = 10
        pos += 1
    return pos
