"""A large random sweep of the compiled CSV number formatter against its references.

    python benchmarks/csv_sweep.py [--numbers 1e8] [--reference /path/to/older/softtip/src] [--seed 1]

Formats ``--numbers`` float64 values (8 columns of a table, 2**18 rows a block) with
``softtip.io.tables``' compiled formatter (:mod:`softtip.io._csvtext`) and compares the bytes
with

* the fallback, pyarrow's writer on the values rounded by ``_round_significant`` (what
  ``write_table`` writes without numba), every block;
* with ``--reference``: the compiled formatter of another softtip tree (its
  ``io/_csvtext.py``, given numpy's ``log10`` exponents as that formatter took them), the bytes
  a release wrote, every block;

and counts the cells that differ from Python's ``'%.10g' % v`` read back and written shortest
(a correctly rounded printf; softtip's rounding is ``rint(x * 10**k)`` in float arithmetic, which
may differ from it at the last digit within the product's rounding error of a tie: counted,
not an error).

The values: a tenth random bit patterns (every exponent, subnormals, NaN payloads,
infinities), the rest ``±10**u`` with ``u`` uniform over the range the one-step rounding takes
(-14 to 32), a tenth of those near a power of ten (a few units in the last place from it), a
tenth ties (an 11th significant digit of 5), and zeros of both signs. Prints the counts and
the first values that differ; exits 1 on any difference from the fallback or the reference.
"""

from __future__ import annotations

import argparse
import importlib.util
import io
import sys
import time
from pathlib import Path

import numpy as np


def values(rng: np.random.Generator, n: int) -> np.ndarray:
    kind = rng.random(n)
    x = np.sign(rng.random(n) - 0.5) * 10.0 ** rng.uniform(-14.0, 32.0, n)
    bits = rng.integers(0, 2**64, n, dtype=np.uint64, endpoint=False).view(np.float64)
    x = np.where(kind < 0.1, bits, x)
    near = (kind >= 0.1) & (kind < 0.2)
    q = rng.integers(-14, 33, n)
    steps = rng.integers(-4, 5, n)
    base = np.array([float(f"1e{v}") for v in range(-14, 33)])[q + 14]
    moved = base.copy()
    for s in (-4, -3, -2, -1, 1, 2, 3, 4):  # a few units in the last place either side
        pick = steps == s
        moved[pick] = np.nextafter(moved[pick], np.inf if s > 0 else 0.0)
        for _ in range(abs(s) - 1):
            moved[pick] = np.nextafter(moved[pick], np.inf if s > 0 else 0.0)
    x = np.where(near, moved * np.sign(rng.random(n) - 0.5), x)
    tie = (kind >= 0.2) & (kind < 0.3)
    m = rng.integers(10**9, 10**10, n)
    e = rng.integers(-24, 22, n)
    ties = (m * 10 + 5) * 10.0 ** e.astype(np.float64)  # 11 digits ending in 5, times a power of ten
    x = np.where(tie, ties, x)
    zero = (kind >= 0.3) & (kind < 0.302)
    return np.where(zero, np.where(rng.random(n) < 0.5, 0.0, -0.0), x)


def numpy_exponents(x: np.ndarray, digits: int) -> np.ndarray:
    """The exponents the formatter was given before (numpy's ``log10``)."""
    with np.errstate(all="ignore"):
        k = np.log10(np.abs(x))
        np.floor(k, out=k)
        np.subtract(digits - 1, k, out=k)
    return k


def reference_text(module, floats: np.ndarray, digits: int) -> bytes:
    """The reference tree's compiled formatter on ``floats`` (nf, n), as its tables module ran it."""
    import pyarrow as pa
    import pyarrow.compute as pc

    nf, n = floats.shape
    exps = np.stack([numpy_exponents(f, digits) for f in floats])
    with np.errstate(invalid="ignore"):
        cols, rows = np.nonzero(np.abs(exps) > 22)
    fin = np.isfinite(exps[cols, rows])
    cols, rows = cols[fin], rows[fin]
    if len(rows):
        order = np.lexsort((cols, rows))
        rows, cols = rows[order], cols[order]
        far = np.array([float(f"%.{digits}g" % v) for v in floats[cols, rows].tolist()])
        arr = pc.cast(pa.array(far), pa.string())
        bufs = arr.buffers()
        far_off = np.frombuffer(bufs[1], dtype=np.int32)[: len(arr) + 1].astype(np.int64)
        far_data = np.frombuffer(bufs[2], dtype=np.uint8)
    else:
        far_off, far_data = np.zeros(1, dtype=np.int64), np.zeros(0, dtype=np.uint8)
    out = np.empty(n * (nf * 25 + nf + 1) + int(far_off[-1]), dtype=np.uint8)
    used = module.format_rows(floats, exps, np.zeros((0, n), dtype=np.int64), np.zeros(1, dtype=np.int64),
                              np.zeros(0, dtype=np.uint8), np.zeros(0, dtype=np.bool_), np.arange(nf, dtype=np.int64),
                              far_off - far_off[0], far_data, out)  # fmt: skip
    return bytes(out[:used])


def printf_text(x: np.ndarray, digits: int) -> np.ndarray:
    """pyarrow's shortest text of Python's correctly rounded ``%.<digits>g`` of each value."""
    import pyarrow as pa
    import pyarrow.compute as pc

    rounded = np.array([float(f"%.{digits}g" % v) for v in x.tolist()])
    return np.array(pc.cast(pa.array(rounded), pa.string()).to_pylist())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--numbers", type=float, default=1e8)
    ap.add_argument("--reference", help="the src folder of another softtip tree whose compiled formatter to compare with")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--digits", type=int, default=10)
    ap.add_argument("--printf-sample", type=float, default=1e5, help="about this many values compared with Python's printf (slow)")
    args = ap.parse_args()

    import pyarrow.csv as pcsv

    import softtip.io.tables as sio
    from softtip.core._jit import set_jit

    set_jit(True)
    reference = None
    if args.reference:
        path = Path(args.reference) / "softtip" / "io" / "_csvtext.py"
        spec = importlib.util.spec_from_file_location("reference_csvtext", path)
        reference = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(reference)
        import numba

        reference.format_rows = numba.njit(nogil=True)(reference.format_rows.py_func)  # no disk cache: loaded by path
    rng = np.random.default_rng(args.seed)
    nf, rows = 8, 1 << 18
    total = int(args.numbers)
    names = [f"x{i}" for i in range(nf)]
    counts = {"numbers": 0, "fallback": 0, "reference": 0, "printf checked": 0, "printf differs": 0}
    shown = 0
    buffers = sio._TextBuffers()
    options = pcsv.WriteOptions(include_header=False)
    seconds = {"compiled": 0.0, "fallback": 0.0, "reference": 0.0}
    printf_every = max(1, int(total / (nf * rows) * 4096 / max(args.printf_sample, 4096)))
    block = 0
    while counts["numbers"] < total:
        x = values(rng, nf * rows)
        floats = x.reshape(nf, rows)
        plan = sio._plan_table(dict(zip(names, floats)), f"%.{args.digits}g")
        t0 = time.process_time()
        out, used = sio._compiled_block(plan, 0, rows, buffers)
        mine = bytes(out[:used])
        buffers.put(out)
        seconds["compiled"] += time.process_time() - t0
        t0 = time.process_time()
        sink = io.BytesIO()
        pcsv.write_csv(sio._arrow_block(plan, 0, rows, rounded=True), sink, options)
        fallback = sink.getvalue()
        seconds["fallback"] += time.process_time() - t0
        checks = [("fallback", fallback)]
        if reference is not None:
            t0 = time.process_time()
            checks.append(("reference", reference_text(reference, np.ascontiguousarray(floats), args.digits)))
            seconds["reference"] += time.process_time() - t0
        for name, theirs in checks:
            if theirs != mine:
                a, b = mine.split(b"\n"), theirs.split(b"\n")
                bad = [i for i in range(min(len(a), len(b))) if a[i] != b[i]]
                counts[name] += sum(1 for i in bad for u, v in zip(a[i].split(b","), b[i].split(b",")) if u != v)
                for i in bad[: max(0, 5 - shown)]:
                    print(f"  differs from the {name}: row {i} values {floats[:, i].tolist()}\n    compiled {a[i]!r}\n    {name} {b[i]!r}")
                    shown += 1
        if block % printf_every == 0:  # a sample against Python's correctly rounded printf
            grid = np.array([row.split(b",") for row in mine.split(b"\n")[:rows]])  # rows x nf
            flat = grid.T.reshape(-1)  # the order of x (x.reshape(nf, rows): column j, row i)
            idx = np.nonzero(np.isfinite(x) & (x != 0))[0][:4096]
            counts["printf checked"] += len(idx)
            counts["printf differs"] += int(np.sum(flat[idx].astype(str) != printf_text(x[idx], args.digits)))
        counts["numbers"] += len(x)
        block += 1
        if block % 20 == 0:
            print(f"  {counts['numbers']:,} numbers: {counts}", flush=True)
    print(f"digits {args.digits}, seed {args.seed}: {counts}")
    print("CPU seconds: " + ", ".join(f"{k} {v:.1f} ({v / counts['numbers'] * 1e9:.0f} ns/number)" for k, v in seconds.items() if v))
    sys.exit(1 if counts["fallback"] or counts["reference"] else 0)


if __name__ == "__main__":
    main()
