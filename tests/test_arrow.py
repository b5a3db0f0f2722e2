"""Arrow IPC (Feather v2) logs and outputs: the columns, types, checks and located errors of Parquet.

``.arrow`` and ``.feather`` name the same format (the Arrow IPC file format Feather v2 is); softtip
reads it as it reads Parquet and writes the same columns and types, with the metadata.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.feather as feather
import pyarrow.parquet as pq
import pytest

from softtip import load_example
from softtip.errors import InputError
from softtip.io.formats import table_format
from softtip.io.tables import PARQUET_UNITS_KEY, TableWriter, iter_log, read_log, write_table

SOFTTIP = str(Path(sys.executable).with_name("softtip"))
WRENCH = ("fx", "fy", "fz", "mx", "my", "mz")
SUFFIXES = (".arrow", ".feather")


def run(*args: object) -> subprocess.CompletedProcess:
    return subprocess.run([SOFTTIP, *map(str, args)], capture_output=True, text=True, timeout=120)


def _table(n: int = 50, seed: int = 3) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(1e-4, 2e-3, n))
    w = rng.normal(size=(n, 6)) * np.array([1, 10, 1e-3, 1e-6, 0.3, 1e3])
    return {"t": t, **{name: w[:, i] for i, name in enumerate(WRENCH)}}


def _write(path: Path, columns: dict, metadata: dict | None = None) -> Path:
    """A file written by pyarrow itself (not by softtip): Parquet or Arrow IPC by the name."""
    table = pa.table(columns)
    if metadata:
        table = table.replace_schema_metadata(metadata)
    if path.suffix == ".parquet":
        pq.write_table(table, path)
    else:
        feather.write_feather(table, path)  # Feather v2, lz4-compressed: pyarrow's default
    return path


def _error(path: Path, **kw: str) -> str:
    with pytest.raises(InputError) as info:
        read_log(path, **kw)
    return str(info.value)


def _values(table: pa.Table) -> dict:
    return {name: table.column(name).to_numpy(zero_copy_only=False) for name in table.column_names}


def test_the_suffixes_name_the_format() -> None:
    assert [table_format(p) for p in ("a.arrow", "B.FEATHER", "c.parquet", "d.csv", "e.csv.gz", "f")] == [
        "arrow", "arrow", "parquet", "csv", "csv", "csv"
    ]


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_round_trip_is_exact_with_the_types_and_metadata_of_parquet(tmp_path: Path, suffix: str) -> None:
    cols = _table()
    extras = {"tag": np.array([f"r{i}" for i in range(50)]), "qw": np.linspace(0, 1, 50), "ok": np.arange(50) % 2 == 0,
              "k": np.arange(50, dtype=np.int32)}  # fmt: skip
    path = tmp_path / f"log{suffix}"
    write_table({**extras, **cols}, path, metadata={PARQUET_UNITS_KEY: "si", "note": "hello"})
    write_table({**extras, **cols}, tmp_path / "log.parquet", metadata={PARQUET_UNITS_KEY: "si", "note": "hello"})
    table = feather.read_table(path)
    assert table.schema.equals(pq.read_schema(tmp_path / "log.parquet"), check_metadata=True)
    assert table.schema.metadata[b"note"] == b"hello"
    log = read_log(path)
    np.testing.assert_array_equal(log.t, cols["t"])
    np.testing.assert_array_equal(log.wrench, np.column_stack([cols[c] for c in WRENCH]))
    assert list(log.extra) == ["tag", "qw", "ok", "k"]
    assert log.extra["tag"].tolist() == extras["tag"].tolist()
    assert log.extra["ok"].dtype == bool and log.extra["k"].dtype == np.int32
    assert log.units == "si" and log.warnings == ()


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_blocks_read_as_the_whole(tmp_path: Path, suffix: str) -> None:
    cols = _table(300)
    path = tmp_path / f"b{suffix}"
    with open(path, "wb") as fh:
        writer = TableWriter(fh, format="arrow", metadata={PARQUET_UNITS_KEY: "kgf-mm"})
        for start in range(0, 300, 70):  # one record batch a piece
            writer.write({k: v[start : start + 70] for k, v in cols.items()})
        writer.close()
    blocks = iter_log(path, rows=32)
    parts = list(blocks)
    assert max(len(t) for t, _, _ in parts) <= 32
    whole = read_log(path)
    assert whole.units == blocks.units == "kgf-mm"
    np.testing.assert_array_equal(np.concatenate([t for t, _, _ in parts]), whole.t)
    np.testing.assert_array_equal(np.concatenate([w for _, w, _ in parts]), whole.wrench)


def _cases() -> list:
    return [
        ("fz", 7, None, "column 'fz', row 7: empty (null); expected a number; or give --missing drop (skip the row) or "
                        "--missing interpolate (fill it)"),
        ("my", 3, float("nan"), "column 'my', row 3: expected a finite number, got nan; or give --missing drop (skip "
                                "the row) or --missing interpolate (fill it)"),
        ("t", 1, float("inf"), "column 't', row 1: expected a finite number, got inf"),
    ]


@pytest.mark.parametrize("suffix", SUFFIXES)
@pytest.mark.parametrize(("column", "row", "value", "expected"), _cases())
def test_bad_cells_name_column_and_row_as_in_parquet(tmp_path: Path, suffix, column, row, value, expected) -> None:
    cols = {k: v.tolist() for k, v in _table().items()}
    cols[column][row - 1] = value
    path = _write(tmp_path / f"b{suffix}", cols)
    assert _error(path) == f"{path}: {expected}"
    twin = _write(tmp_path / "b.parquet", cols)
    assert _error(twin) == f"{twin}: {expected}"


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_columns_units_and_time_are_checked_as_in_parquet(tmp_path: Path, suffix: str) -> None:
    def both(name: str, cols: dict, metadata: dict | None = None) -> tuple[str, str]:
        a = _error(_write(tmp_path / f"{name}{suffix}", cols, metadata))
        b = _error(_write(tmp_path / f"{name}.parquet", cols, metadata))
        return a.replace(suffix, ".parquet"), b

    cols = _table()
    cols["kraft x"] = cols.pop("fx")
    a, b = both("m", cols)
    assert a == b and "missing column 'fx'" in a and "--columns t=NAME,fx=NAME" in a
    cols = _table()
    cols["mx"] = cols["mx"].astype(str)
    a, b = both("s", cols)
    assert a == b and a.endswith("column 'mx': expected numbers, got type string")
    cols = _table()
    cols["t"][20] = cols["t"][18]
    a, b = both("back", cols)
    assert a == b and "column 't', row 21: expected t non-decreasing" in a
    a, b = both("odd", _table(), {PARQUET_UNITS_KEY: "furlongs"})
    assert a == b and a.endswith("metadata softtip.units = 'furlongs'; expected one of: si, kgf-mm")
    a, b = both("e", {k: v[:0] for k, v in _table().items()})
    assert a == b and a.endswith("no rows; expected at least one row of t, fx, fy, fz, mx, my, mz")
    cols = _table()
    cols["zeit"] = cols.pop("t")
    path = _write(tmp_path / f"opt{suffix}", cols)  # the CSV options read it as they would a CSV log
    np.testing.assert_array_equal(read_log(path, columns="t=zeit").t, cols["zeit"])
    assert _error(path, skip_rows=1) == (
        f"{path}: --skip-rows applies to CSV logs; an Arrow IPC (Feather v2) file has no lines before its columns"
    )


@pytest.mark.parametrize("suffix", SUFFIXES)
@pytest.mark.parametrize("content", [b"", b"t,fx\n0,1\n", b"ARROW1\x00\x00garbageARROW1", b"PAR1garbagePAR1"])
def test_not_arrow(tmp_path: Path, suffix: str, content: bytes) -> None:
    path = tmp_path / f"x{suffix}"
    path.write_bytes(content)
    message = _error(path)
    assert message.startswith(f"{path}: not a readable Arrow IPC (Feather v2) file (")
    assert message.endswith("); expected an Arrow IPC (Feather v2) log file")
    missing = tmp_path / f"none{suffix}"
    assert _error(missing) == f"{missing}: file not found; expected an existing Arrow IPC (Feather v2) log file"


def _example_columns() -> dict[str, np.ndarray]:
    log = load_example()
    return {"t": log.t, **{name: log.wrench[:, i] for i, name in enumerate(WRENCH)}}


def test_estimate_writes_arrow_as_it_writes_parquet_and_reads_it_back(tmp_path: Path) -> None:
    n = len(load_example().t)
    src = tmp_path / "in.feather"
    write_table({**_example_columns(), "trial": np.full(n, "a b")}, src)
    out = run("estimate", src, "-o", tmp_path / "out.arrow", "--output-units", "kgf-mm")
    assert out.returncode == 0, out.stderr
    twin = run("estimate", src, "-o", tmp_path / "out.parquet", "--output-units", "kgf-mm")
    assert twin.returncode == 0, twin.stderr
    arrow, parquet = feather.read_table(tmp_path / "out.arrow"), pq.read_table(tmp_path / "out.parquet")
    assert arrow.schema.equals(parquet.schema, check_metadata=True)
    assert arrow.schema.metadata[PARQUET_UNITS_KEY.encode()] == b"kgf-mm"
    for name, values in _values(arrow).items():
        np.testing.assert_array_equal(values, _values(parquet)[name], err_msg=name)
    assert arrow.column("trial").to_pylist() == ["a b"] * n
    # the output read back as a log (its t and filtered wrench, in its own units)
    back = run("estimate", tmp_path / "out.arrow", "-o", tmp_path / "again.feather", "--output-units", "kgf-mm")
    assert back.returncode == 2 and "out.arrow: column 'fx', row 1: expected a finite number, got nan" in back.stderr


def test_estimate_in_pieces_gives_the_one_shot_arrow(tmp_path: Path) -> None:
    src = tmp_path / "in.arrow"
    write_table(_example_columns(), src)
    one = run("estimate", src, "-o", tmp_path / "one.arrow")
    pieces = run("estimate", src, "-o", tmp_path / "pieces.feather", "--chunk-rows", "100")
    assert one.returncode == 0 and pieces.returncode == 0, one.stderr + pieces.stderr
    a, b = feather.read_table(tmp_path / "one.arrow"), feather.read_table(tmp_path / "pieces.feather")
    assert a.schema.equals(b.schema)
    for name, values in _values(a).items():
        np.testing.assert_array_equal(values, _values(b)[name], err_msg=name)


def test_typed_extra_columns_are_carried_from_arrow(tmp_path: Path) -> None:
    cols = _example_columns()
    n = len(cols["t"])
    sensor = pa.array([None if i % 7 == 0 else i for i in range(n)], type=pa.int64())  # nullable integers
    src = tmp_path / "in.arrow"
    feather.write_feather(pa.table({**cols, "sensor": sensor}), src, compression="uncompressed")
    for dest in ("out.feather", "out.parquet"):
        out = run("estimate", src, "-o", tmp_path / dest)
        assert out.returncode == 0, out.stderr
        table = feather.read_table(tmp_path / dest) if dest.endswith("feather") else pq.read_table(tmp_path / dest)
        assert table.schema.field("sensor").type == pa.int64()
        assert table.column("sensor").to_pylist() == sensor.to_pylist()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.arrow", "out.feather", "out.parquet"]


def test_a_bad_arrow_file_is_named_and_nothing_is_written(tmp_path: Path) -> None:
    bad = tmp_path / "bad.feather"
    bad.write_bytes(b"not arrow at all\n")
    out = run("estimate", bad, "-o", tmp_path / "out.arrow")
    assert out.returncode == 2
    assert f"softtip: error: {bad}: not a readable Arrow IPC (Feather v2) file (" in out.stderr
    assert "Traceback" not in out.stderr
    assert [p.name for p in tmp_path.iterdir()] == ["bad.feather"]


def test_foreign_names_and_dropped_rows_carry_only_the_extras_row_for_row(tmp_path: Path) -> None:
    # a ROS export (stamp split in int seconds and nanoseconds, a sequence number) written to
    # Parquet and Arrow: the stamp's columns are read as t, not carried as extras; and with a row
    # dropped (--missing drop), a typed extra keeps its rows aligned
    cols = _example_columns()
    n = len(cols["t"])
    ns = 1_709_632_800_123_456_789 + np.round(cols["t"] * 1e9).astype(np.int64)
    ros = {"header.stamp.sec": pa.array(ns // 10**9, pa.int32()), "header.stamp.nanosec": pa.array(ns % 10**9, pa.uint32()),
           "seq": pa.array(np.arange(n), pa.int64())}  # fmt: skip
    ros.update({f"wrench.{'force' if w[0] == 'f' else 'torque'}.{w[1]}": cols[w] for w in WRENCH})
    src = tmp_path / "ros.arrow"
    feather.write_feather(pa.table(ros), src)
    for dest in ("out.arrow", "out.parquet"):
        out = run("estimate", src, "-o", tmp_path / dest, "-q")
        assert out.returncode == 0, out.stderr
        table = feather.read_table(tmp_path / dest) if dest.endswith("arrow") else pq.read_table(tmp_path / dest)
        assert table.column("seq").to_pylist() == list(range(n))
        assert table.column("stamp_ns").to_pylist() == ns.tolist()
        assert "header.stamp.sec" not in table.column_names
    holes = {**cols, "seq": pa.array(np.arange(n), pa.int64())}
    holes["fz"] = np.where(np.arange(n) == 7, np.nan, cols["fz"])
    pq.write_table(pa.table(holes), tmp_path / "holes.parquet")
    out = run("estimate", tmp_path / "holes.parquet", "-o", tmp_path / "holes.out.parquet", "--missing", "drop", "-q")
    assert out.returncode == 0, out.stderr
    assert pq.read_table(tmp_path / "holes.out.parquet").column("seq").to_pylist() == [i for i in range(n) if i != 7]


def _example_table(t: np.ndarray, scale: tuple[float, float] = (1.0, 1.0)) -> pa.Table:
    ex = load_example()
    w = ex.wrench / np.repeat(scale, 3)
    return pa.table({"t": t, **{name: w[:, i] for i, name in enumerate(WRENCH)}})


@pytest.mark.parametrize("suffix", [".parquet", ".arrow"])
@pytest.mark.parametrize("pieces", [[], ["--chunk-rows", "100"]], ids=["one-shot", "pieces"])
def test_softtips_own_column_names_get_a_csv_logs_time_and_units_checks(tmp_path: Path, suffix: str, pieces: list) -> None:
    """A Parquet or Arrow log named ``t, fx … mz`` as softtip writes them, but without softtip's metadata,
    is read as a CSV log with that header: t in ms stops naming --time-units, Unix ns count from the
    first stamp, and the units check sees the units the wrench was read in (such files went through a
    shortcut that did none of it: wrong estimates, exit 0)."""
    ex = load_example()
    base = tmp_path / "base.csv"
    assert run("estimate", "--example", "-o", base).returncode == 0

    def write(name: str, table: pa.Table) -> Path:
        path = tmp_path / (name + suffix)
        (pq.write_table if suffix == ".parquet" else feather.write_feather)(table, path)
        return path

    ms = write("ms", _example_table(ex.t * 1e3))
    done = run("estimate", ms, "-o", tmp_path / "ms.csv", *pieces)
    assert done.returncode == 2 and "if t is in milliseconds 50 Hz (--time-units ms)" in done.stderr, done.stderr
    assert not (tmp_path / "ms.csv").exists()
    told = run("estimate", ms, "--time-units", "ms", "-o", tmp_path / "ms.csv", *pieces)
    assert told.returncode == 0, told.stderr
    assert (tmp_path / "ms.csv").read_bytes() == base.read_bytes()

    dated = write("ns", _example_table(1_700_000_000 * 10**9 + np.round(ex.t * 1e9).astype(np.int64)))
    done = run("estimate", dated, "-o", tmp_path / "ns.csv", *pieces)
    assert done.returncode == 0 and "t counts from the first, 1700000000000000000 ns" in done.stderr, done.stderr
    lines = (tmp_path / "ns.csv").read_text().splitlines()
    assert lines[0].endswith(",stamp_ns") and [ln.rsplit(",", 1)[0] for ln in lines] == base.read_text().splitlines()

    si = write("si", _example_table(ex.t))
    done = run("estimate", si, "--units", "kgf-mm", "-o", tmp_path / "k.csv", *pieces)
    assert done.returncode == 2 and "read in kgf and kgf·mm, the noise while taring is" in done.stderr, done.stderr
    assert "the data fit forces in N with moments in N·m" in done.stderr


def test_a_replay_takes_the_units_of_softtips_metadata(tmp_path: Path) -> None:
    # stream's --units defaulted to si, which the file's kgf-mm contradicted: the replay stopped
    from softtip.core.units import KGF, KGF_MM

    ex = load_example()
    table = _example_table(ex.t, (KGF, KGF_MM)).replace_schema_metadata({PARQUET_UNITS_KEY: "kgf-mm"})
    for suffix in (".parquet", ".arrow"):
        path = tmp_path / ("kgf" + suffix)
        (pq.write_table if suffix == ".parquet" else feather.write_feather)(table, path)
        for args in (("estimate", path, "-o", tmp_path / "e.csv"),
                     ("stream", "--replay", path, "--speed", 0, "-o", tmp_path / "r.csv")):  # fmt: skip
            done = run(*args)
            assert done.returncode == 0, done.stderr
            assert "read as" not in done.stderr  # softtip's own file: its units are its metadata's, not said
        assert "1 contact(s)" in done.stderr


def test_a_columnar_file_read_as_csv_says_what_it_is(tmp_path: Path) -> None:
    # by its name (.csv) or on standard input, a Parquet or Arrow file read as CSV said "not valid UTF-8"
    table = _example_table(load_example().t)
    for fmt, write, suffix, kind in (("parquet", pq.write_table, ".parquet", "a Parquet file"),
                                     ("arrow", feather.write_feather, ".arrow", "an Arrow IPC (Feather v2) file")):  # fmt: skip
        path = tmp_path / f"{fmt}.csv"
        write(table, path)
        done = run("estimate", path)
        assert done.returncode == 2, done.stderr
        assert f"{path}: {kind} (it starts as one), read as CSV by its name; expected a name ending in {suffix}" in done.stderr
        with open(path, "rb") as fh:
            piped = subprocess.run([SOFTTIP, "estimate", "-"], stdin=fh, capture_output=True, text=True, timeout=120)
        assert piped.returncode == 2 and "on standard input, which takes CSV only" in piped.stderr, piped.stderr
