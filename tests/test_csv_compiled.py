"""The compiled CSV formatter (softtip.io._csvtext) writes the bytes pyarrow's writer writes.

``write_table`` formats floats with the compiled loop when numba is installed and with
pyarrow's writer otherwise; the two must give the same text, byte for byte, for every float
(subnormals, -0.0, NaN, infinities, 1e±308, values that round at the last digit, integers
near 2**53) and every other column kind (integers, booleans, text that needs quotes).
"""

import io
import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from softtip.core._jit import set_jit
from softtip.io.tables import text_column, write_table

pytest.importorskip("numba")


@pytest.fixture(autouse=True)
def _restore_jit():
    old = set_jit(None)
    yield
    set_jit(old)


def _text(columns, flag: bool, **kwargs) -> bytes:
    set_jit(flag)
    out = io.StringIO()
    write_table(columns, out, **kwargs)
    return out.getvalue().encode("utf-8")


def _same(columns, **kwargs) -> None:
    fallback = _text(columns, False, **kwargs)
    compiled = _text(columns, True, **kwargs)
    if compiled != fallback:
        rows = [(i, a, b) for i, (a, b) in enumerate(zip(fallback.splitlines(), compiled.splitlines())) if a != b]
        pytest.fail(f"first row that differs (fallback, compiled): {rows[:1]}")


def _ties(draw_int: int, exp: int) -> float:
    """A value whose 11th significant digit is 5: it rounds at the 10th."""
    return float(f"{draw_int}5e{exp}")


def _near_power_of_ten(q: int, steps: int, sign: float) -> float:
    """The float nearest 10**q moved ``steps`` units in the last place (where the exponent of
    the first digit changes)."""
    x = float(f"1e{q}")
    for _ in range(abs(steps)):
        x = math.nextafter(x, math.inf if steps > 0 else 0.0)
    return sign * x


# floats of every kind: the whole range (subnormals, 1e±308), special values, and values near
# the edges the formatter cares about (powers of ten, the 10th digit, 2**53)
FLOATS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(allow_subnormal=True, min_value=-1e-300, max_value=1e-300),
    st.sampled_from([0.0, -0.0, math.nan, -math.nan, math.inf, -math.inf, 5e-324, -5e-324, 2.2250738585072014e-308,
                     1.7976931348623157e308, -1.7976931348623157e308, 1e308, 1e-308, 1e-7, 1e-6, 1e-5, 1e9, 1e10]),
    st.builds(_ties, st.integers(10**9, 10**10 - 1), st.integers(-330, 300)),
    st.builds(lambda k, s: float(2**53 + k) * s, st.integers(-5000, 5000), st.sampled_from([1.0, -1.0])),
    st.builds(lambda m, e: m * 10.0**e, st.integers(-(10**12), 10**12), st.integers(-40, 40)),
    st.builds(lambda x, e: math.nextafter(10.0**e, x), st.sampled_from([0.0, math.inf]), st.integers(-30, 30)),
    st.builds(_near_power_of_ten, st.integers(-325, 308), st.integers(-3, 3), st.sampled_from([1.0, -1.0])),
)


@settings(max_examples=300, deadline=None)
@given(st.lists(FLOATS, min_size=1, max_size=40), st.sampled_from([10, 10, 10, *range(1, 14)]))
@example([9.9999999995, 99999.999995, 0.1 + 0.2, 1 / 3, -2.5e-7, 1234567890.5, 12345678905.0], 10)
def test_the_compiled_and_the_fallback_text_are_the_same_bytes(values, digits):
    x = np.array(values, dtype=np.float64)
    _same({"x": x, "y": x[::-1].copy()}, float_format=f"%.{digits}g")


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.tuples(FLOATS, st.integers(-(2**63), 2**63 - 1), st.booleans(),
                       st.sampled_from(["none", "contact", 'a "quoted" cell', "a,b", "two\nlines", "é", ""])),
             min_size=1, max_size=30),
    st.booleans(),
)  # fmt: skip
def test_every_column_kind_is_written_the_same(rows, as_objects):
    x, i, b, s = map(list, zip(*rows))
    cells = text_column(s) if as_objects else np.array(s)
    _same({"x": np.array(x), "i": np.array(i, dtype=np.int64), "b": np.array(b), "s": cells,
           "u": np.array([abs(v) for v in i], dtype=np.uint64), "i8": np.array(i, dtype=np.int64).astype(np.int8)})  # fmt: skip


def test_a_long_table_in_blocks_and_threads_is_the_same():
    rng = np.random.default_rng(8380)
    n = 200_000  # several blocks, formatted on several threads
    x = rng.standard_normal(n) * 10.0 ** rng.integers(-40, 40, n)
    x[::97] = np.nan
    x[::101] = 0.0
    state = np.where(x > 0, "contact", "none")
    _same({"t": np.arange(n) / 7000.0, "x": x, "state": state, "k": np.arange(n)})


def test_the_compiled_path_is_taken():
    """The comparison above compares two different writers (not pyarrow with itself)."""
    from softtip.io import tables

    plan = tables._plan_table({"x": np.array([1.5, np.nan])}, "%.10g")
    set_jit(True)
    assert tables._compiled_csv(plan)
    out, used = tables._compiled_block(plan, 0, 2)
    assert bytes(out[:used]) == b"1.5\nnan\n"
    set_jit(False)
    assert not tables._compiled_csv(plan)
    assert not tables._compiled_csv(tables._plan_table({"x": np.array([1.5])}, "%.17g"))  # beyond its digits


@settings(max_examples=300, deadline=None)
@given(FLOATS)
def test_the_exponent_of_the_first_digit_is_exact_but_next_to_a_power_of_ten(x):
    """floor(log10(|x|)) from the binary exponent (no log10): exact, except that a value
    between 10**q and the float nearest it may take the other side (the text is the same)."""
    from fractions import Fraction

    from softtip.io.tables import _digit_exponents

    k = _digit_exponents(np.array([x]), 10)[0]
    if math.isnan(x):
        assert math.isnan(k)
        return
    if x == 0 or math.isinf(x):
        assert k == (math.inf if x == 0 else -math.inf)
        return
    p = 9 - int(k)
    a = Fraction(abs(x))
    exact = math.floor(math.log10(abs(x)))  # then made exact: 10**exact <= |x| < 10**(exact + 1)
    while Fraction(10) ** exact > a:
        exact -= 1
    while Fraction(10) ** (exact + 1) <= a:
        exact += 1
    if p != exact:  # |x| between 10**q and the float nearest it
        q = max(p, exact)
        assert abs(p - exact) == 1
        nearest = Fraction(float(f"1e{q}"))
        assert min(Fraction(10) ** q, nearest) <= a <= max(Fraction(10) ** q, nearest)


def test_a_writer_reuses_its_buffers_across_pieces_and_tables_of_other_shapes():
    """The compiled formatter's memory is kept from one block (and piece) to the next: a
    piece of other columns, or more rows, must not see the previous piece's values."""
    from softtip.io.tables import TableWriter

    set_jit(True)
    rng = np.random.default_rng(8380)
    pieces = [{"t": rng.normal(size=n), "s": np.array(["a", "b"] * (n // 2)), "k": np.arange(n)} for n in (6, 10, 4)]
    out = io.StringIO()
    writer = TableWriter(out)
    for piece in pieces:
        writer.write(piece)
    writer.close()
    whole = {k: np.concatenate([p[k] for p in pieces]) for k in pieces[0]}
    assert out.getvalue().encode() == _text(whole, False)


@pytest.mark.parametrize("threads", [1, 3])
@pytest.mark.parametrize("binary", [False, True])
def test_a_writer_formats_the_next_pieces_while_the_file_gets_the_ones_before(monkeypatch, threads, binary):
    """Blocks of several pieces in flight at once (blocks of 7 rows, up to 2 x threads pending):
    the file gets every row once, in order, the bytes of one write of the whole table."""
    import softtip.io.tables as tables

    set_jit(True)
    monkeypatch.setattr(tables, "_CHUNK_ROWS", 7)
    rng = np.random.default_rng(8381)
    sizes = (5, 23, 1, 40, 14)
    pieces = [{"t": rng.normal(size=n) * 10.0 ** rng.integers(-5, 5, size=n), "k": np.arange(n) - 3} for n in sizes]
    out = io.BytesIO() if binary else io.StringIO()
    writer = tables.TableWriter(out, threads=threads)
    for piece in pieces:
        writer.write(piece)
    writer.close()
    whole = {k: np.concatenate([p[k] for p in pieces]) for k in pieces[0]}
    got = out.getvalue() if binary else out.getvalue().encode()
    assert got == _text(whole, False)


def test_a_block_that_fails_leaves_no_gap_and_nothing_after_it(monkeypatch):
    """A block failing while blocks of later pieces are in flight: what was written is the
    table's first rows, whole, and nothing after them (no gap a reader could not see)."""
    import softtip.io.tables as tables

    set_jit(True)
    monkeypatch.setattr(tables, "_CHUNK_ROWS", 5)
    real = tables._compiled_block

    def failing(plan, start, stop, buffers=None):
        if plan.arrays[0][0] == 200.0 and start == 5:  # the second block of the third piece
            raise MemoryError("no memory for this block")
        return real(plan, start, stop, buffers)

    monkeypatch.setattr(tables, "_compiled_block", failing)
    pieces = [{"t": np.arange(12.0) + 100.0 * k, "k": np.arange(12) + 12 * k} for k in range(5)]
    out = io.StringIO()
    with pytest.raises(MemoryError), tables.TableWriter(out, threads=3) as writer:
        for piece in pieces:
            writer.write(piece)
    whole = {c: np.concatenate([p[c] for p in pieces]) for c in pieces[0]}
    lines = _text(whole, False).decode().splitlines(keepends=True)
    assert out.getvalue() == "".join(lines[: 1 + 2 * 12 + 5])  # header, two pieces, the third's first block
