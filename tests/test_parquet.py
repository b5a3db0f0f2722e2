"""Parquet logs: the columns, checks and located errors of CSV, units and fingertip in the metadata."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.feather as feather
import pyarrow.parquet as pq
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from softtip.core.units import KGF, KGF_MM
from softtip.errors import InputError
from softtip.io.tables import PARQUET_UNITS_KEY, read_log, write_table

WRENCH = ("fx", "fy", "fz", "mx", "my", "mz")


def _table(n: int = 50, seed: int = 3) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(1e-4, 2e-3, n))
    w = rng.normal(size=(n, 6)) * np.array([1, 10, 1e-3, 1e-6, 0.3, 1e3])
    return {"t": t, **{name: w[:, i] for i, name in enumerate(WRENCH)}}


def _error(path: Path, **kw: str) -> str:
    with pytest.raises(InputError) as info:
        read_log(path, **kw)
    return str(info.value)


def _write_pq(path: Path, columns: dict, metadata: dict | None = None) -> Path:
    table = pa.table(columns)
    if metadata:
        table = table.replace_schema_metadata(metadata)
    pq.write_table(table, path)
    return path


def test_round_trip_is_exact_and_keeps_extras_and_metadata(tmp_path: Path) -> None:
    cols = _table()
    extras = {"tag": np.array([f"r{i}" for i in range(50)]), "qw": np.linspace(0, 1, 50), "ok": np.arange(50) % 2 == 0}
    path = tmp_path / "log.parquet"
    write_table({**extras, **cols}, path, metadata={PARQUET_UNITS_KEY: "si", "note": "hello"})
    meta = pq.read_schema(path).metadata
    assert meta[b"note"] == b"hello" and meta[PARQUET_UNITS_KEY.encode()] == b"si"
    log = read_log(path)
    np.testing.assert_array_equal(log.t, cols["t"])
    np.testing.assert_array_equal(log.wrench, np.column_stack([cols[c] for c in WRENCH]))
    assert list(log.extra) == ["tag", "qw", "ok"]
    np.testing.assert_array_equal(log.extra["qw"], extras["qw"])
    assert log.extra["tag"].tolist() == extras["tag"].tolist()
    assert log.extra["ok"].dtype == bool and log.extra["ok"].tolist() == extras["ok"].tolist()
    assert log.units == "si" and log.warnings == () and log.repeated_t == 0


def test_integer_columns_and_any_order(tmp_path: Path) -> None:
    cols = {name: np.arange(5, dtype=np.int32) for name in reversed(("t",) + WRENCH)}
    log = read_log(_write_pq(tmp_path / "i.parquet", cols))
    np.testing.assert_array_equal(log.t, np.arange(5.0))
    assert log.wrench.dtype == np.float64 and log.wrench.shape == (5, 6)


def test_units_from_metadata_and_conflicts(tmp_path: Path) -> None:
    cols = _table()
    # the key is part of the file format (files written by any softtip version): spelled out here
    path = _write_pq(tmp_path / "k.parquet", cols, {"softtip.units": "kgf-mm"})
    log = read_log(path)
    assert log.units == "kgf-mm"
    np.testing.assert_allclose(log.wrench[:, 0], cols["fx"] * KGF)
    np.testing.assert_allclose(log.wrench[:, 3], cols["mx"] * KGF_MM)
    assert read_log(path, units="kgf-mm").units == "kgf-mm"
    assert _error(path, units="si") == (
        f"{path}: the file's metadata says its wrench is in kgf-mm, but si was asked for; expected the units to "
        "agree (leave them out to use the file's)"
    )
    plain = _write_pq(tmp_path / "s.parquet", cols)
    assert read_log(plain).units == "si" and read_log(plain, units="kgf-mm").units == "kgf-mm"
    odd = _write_pq(tmp_path / "o.parquet", cols, {PARQUET_UNITS_KEY: "furlongs"})
    assert _error(odd) == f"{odd}: metadata softtip.units = 'furlongs'; expected one of: si, kgf-mm"


def test_missing_and_misspelled_columns(tmp_path: Path) -> None:
    cols = _table()
    cols["kraft x"] = cols.pop("fx")
    path = _write_pq(tmp_path / "m.parquet", cols)
    assert _error(path) == (
        f"{path}: missing column 'fx'; expected a header with columns t, fx, fy, fz, mx, my, mz (any order). "
        "Other names: map them with --columns t=NAME,fx=NAME,… (docs/guide/input-formats.md lists the headers read "
        "as they are)."
    )
    log = read_log(path, columns="fx=kraft x")  # the option the message names
    np.testing.assert_array_equal(log.wrench[:, 0], cols["kraft x"])


def test_foreign_column_names_are_read_as_a_csv_headers(tmp_path: Path) -> None:
    # ATI's names (Time, Fx … Tz), any case, as in a CSV header; the note says how they were read
    cols = _table()
    ati = {"Time": cols["t"], **{n: cols[w] for n, w in zip(("Fx", "Fy", "Fz", "Tx", "Ty", "Tz"), WRENCH)}}
    path = _write_pq(tmp_path / "ati.parquet", ati)
    log = read_log(path)
    np.testing.assert_array_equal(log.t, cols["t"])
    np.testing.assert_array_equal(log.wrench, np.column_stack([cols[w] for w in WRENCH]))
    assert "mx ← 'Tx' (N·m" in log.notes[0]


def test_unit_options_and_missing_apply_as_to_csv(tmp_path: Path) -> None:
    cols = _table()
    cols["t"] = np.round(cols["t"] * 1e3, 3)  # ms
    path = _write_pq(tmp_path / "u.parquet", cols)
    log = read_log(path, moment_units="N*mm", force_units="kgf", time_units="ms")
    np.testing.assert_allclose(log.t, cols["t"] * 1e-3, rtol=1e-15)
    np.testing.assert_allclose(log.wrench[:, :3], np.column_stack([cols[w] for w in WRENCH[:3]]) * KGF, rtol=1e-15)
    np.testing.assert_allclose(log.wrench[:, 3:], np.column_stack([cols[w] for w in WRENCH[3:]]) * 1e-3, rtol=1e-15)
    assert (log.force_unit, log.moment_unit) == ("kgf", "N*mm")
    # a file whose metadata gives its units refuses the options; --skip-rows never applies
    meta = _write_pq(tmp_path / "meta.parquet", _table(), {PARQUET_UNITS_KEY: "si"})
    assert _error(meta, moment_units="N*mm") == (
        f"{meta}: the file's metadata says its wrench is in si and its t in s; --moment-units applies to a file "
        "without that metadata (leave it out)"
    )
    assert _error(meta, skip_rows=2) == (
        f"{meta}: --skip-rows applies to CSV logs; a Parquet file has no lines before its columns"
    )
    # nulls: the error names the row and --missing, which drops or fills them
    cols = {k: v.tolist() for k, v in _table().items()}
    cols["fz"][6] = None
    holes = _write_pq(tmp_path / "holes.parquet", cols)
    assert _error(holes).endswith("row 7: empty (null); expected a number; or give --missing drop (skip the row) "
                                  "or --missing interpolate (fill it)")  # fmt: skip
    assert len(read_log(holes, missing="drop").t) == 49
    filled = read_log(holes, missing="interpolate")
    t = np.array(cols["t"])
    assert filled.wrench[6, 2] == pytest.approx(np.interp(t[6], t[[5, 7]], [cols["fz"][5], cols["fz"][7]]))


def test_kgf_mm_metadata_holds_for_foreign_names(tmp_path: Path) -> None:
    cols = _table()
    cols["Fx"] = cols.pop("fx")
    path = _write_pq(tmp_path / "k.parquet", cols, {PARQUET_UNITS_KEY: "kgf-mm"})
    log = read_log(path)
    np.testing.assert_allclose(log.wrench[:, 0], cols["Fx"] * KGF, rtol=1e-15)
    np.testing.assert_allclose(log.wrench[:, 3], cols["mx"] * KGF_MM, rtol=1e-15)


@pytest.mark.parametrize(
    ("column", "row", "value", "expected"),
    [
        ("fz", 7, None, "column 'fz', row 7: empty (null); expected a number; or give --missing drop (skip the row) or "
                        "--missing interpolate (fill it)"),
        ("my", 3, float("nan"), "column 'my', row 3: expected a finite number, got nan; or give --missing drop (skip "
                                "the row) or --missing interpolate (fill it)"),
        ("t", 1, float("inf"), "column 't', row 1: expected a finite number, got inf"),
    ],
)
def test_bad_cells_name_column_and_row(tmp_path: Path, column: str, row: int, value: float | None, expected: str) -> None:
    cols = {k: v.tolist() for k, v in _table().items()}
    cols[column][row - 1] = value
    path = _write_pq(tmp_path / "b.parquet", cols)
    assert _error(path) == f"{path}: {expected}"


def test_text_column_is_an_error(tmp_path: Path) -> None:
    cols = _table()
    cols["mx"] = cols["mx"].astype(str)
    path = _write_pq(tmp_path / "s.parquet", cols)
    assert _error(path) == f"{path}: column 'mx': expected numbers, got type string"


def test_time_going_back_and_repeating(tmp_path: Path) -> None:
    cols = _table()
    cols["t"][20] = cols["t"][18]
    path = _write_pq(tmp_path / "back.parquet", cols)
    t = cols["t"]
    assert _error(path) == (
        f"{path}: column 't', row 21: expected t non-decreasing (a stamp may repeat, not go back), "
        f"got t = {float(t[20])!r} at row 21 after t = {float(t[19])!r} at row 20"
    )
    cols = _table()
    cols["t"][[20, 30]] = cols["t"][[19, 29]]
    log = read_log(_write_pq(tmp_path / "rep.parquet", cols))
    assert log.repeated_t == 2
    assert "2 repeated time stamps (the first on data row 21:" in log.warnings[0]


def test_time_in_milliseconds_is_reported(tmp_path: Path) -> None:
    cols = _table()
    cols["t"] = np.arange(50) * 1.0  # 1 kHz, in ms
    (note,) = read_log(_write_pq(tmp_path / "ms.parquet", cols)).warnings
    assert "median step 1 s, i.e. 1 samples/s: implausible" in note and "if t is in milliseconds 1e+03 Hz" in note


def test_softtips_metadata_says_t_is_in_seconds(tmp_path: Path) -> None:
    # 10 Hz in s is also 10 kHz in ms: a file without softtip's metadata is asked which, as a CSV
    # log with a plain header; softtip's own file (a slow recording) is not
    cols = _table()
    cols["t"] = np.arange(50) * 0.1
    plain = read_log(_write_pq(tmp_path / "plain.parquet", cols))
    assert plain.time_suspect is not None and "give --time-units s or --time-units ms" in plain.time_suspect
    own = read_log(_write_pq(tmp_path / "own.parquet", cols, {PARQUET_UNITS_KEY: "si"}))
    assert own.time_suspect is None and own.warnings == () and own.notes == ()
    np.testing.assert_array_equal(own.t, plain.t)
    np.testing.assert_array_equal(own.wrench, plain.wrench)


@pytest.mark.parametrize("content", [b"", b"t,fx\n0,1\n", b"PAR1garbagePAR1"])
def test_not_parquet(tmp_path: Path, content: bytes) -> None:
    path = tmp_path / "x.parquet"
    path.write_bytes(content)
    message = _error(path)
    assert message.startswith(f"{path}: not a readable Parquet file (")
    assert message.endswith("); expected a Parquet log file")


def test_missing_file_and_empty_table(tmp_path: Path) -> None:
    missing = tmp_path / "none.parquet"
    assert _error(missing) == f"{missing}: file not found; expected an existing Parquet log file"
    empty = _write_pq(tmp_path / "e.parquet", {k: v[:0] for k, v in _table().items()})
    assert _error(empty) == f"{empty}: no rows; expected at least one row of t, fx, fy, fz, mx, my, mz"


def test_write_is_atomic_and_keeps_an_existing_file_on_failure(tmp_path: Path) -> None:
    class Explodes:
        def __str__(self) -> str:
            raise RuntimeError("boom")

    path = tmp_path / "out.parquet"
    path.write_bytes(b"precious")
    with pytest.raises(RuntimeError, match="boom"):
        write_table({"t": [0.0, 1.0], "obj": ["a", Explodes()]}, path)
    assert path.read_bytes() == b"precious"
    assert [p.name for p in tmp_path.iterdir()] == ["out.parquet"]


def test_write_zero_rows_and_progress(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import softtip.io.tables as sio

    path = tmp_path / "z.parquet"
    write_table({"t": np.empty(0), "state": np.array([], dtype=str)}, path)
    assert pq.read_table(path).num_rows == 0
    monkeypatch.setattr(sio, "_PARQUET_ROWS", 16)
    steps: list[int] = []
    cols = _table(50)
    write_table(cols, tmp_path / "p.parquet", progress=steps.append)
    assert steps == [16, 16, 16, 2]
    assert pq.ParquetFile(tmp_path / "p.parquet").num_row_groups == 4
    np.testing.assert_array_equal(read_log(tmp_path / "p.parquet").t, cols["t"])


def test_orientation_columns_of_a_parquet_log(tmp_path: Path) -> None:
    """Gravity compensation reads numeric extra columns; its errors name the row."""
    from softtip.calibration.payload import compensate_log

    n = 50
    cols = {**_table(n), "qw": np.ones(n), "qx": np.zeros(n), "qy": np.zeros(n), "qz": np.zeros(n)}
    payload = tmp_path / "p.toml"
    payload.write_text("[payload]\nmass = 0.01\ncom = [0, 0, 0.01]\n")
    path = tmp_path / "q.parquet"
    write_table(cols, path)
    compensated = compensate_log(read_log(path), payload)
    np.testing.assert_allclose(compensated.wrench[:, 2] - read_log(path).wrench[:, 2], 0.01 * 9.80665, rtol=1e-3)
    cols["qw"][6] = 2.0
    write_table(cols, path)
    with pytest.raises(InputError) as info:
        compensate_log(read_log(path), payload)
    assert str(info.value) == (
        f"{path}: data row 7: column 'qw': qw, qx, qy, qz = 2.0, 0.0, 0.0, 0.0 has norm 2; expected a unit "
        "quaternion (norm within 0.001 of 1)"
    )


def test_lean_writer_settings(tmp_path: Path) -> None:
    """No dictionary on float columns, no statistics unless asked (docs/guide/input-formats.md)."""
    from softtip.io.tables import PARQUET_COMPRESSION

    cols = {**_table(), "state": np.array(["none", "point"] * 25), "k": np.arange(50)}
    path = tmp_path / "lean.parquet"
    write_table(cols, path)
    group = pq.ParquetFile(path).metadata.row_group(0)
    chunks = {group.column(i).path_in_schema: group.column(i) for i in range(group.num_columns)}
    assert all(not c.is_stats_set for c in chunks.values())
    assert all(c.compression == PARQUET_COMPRESSION.upper() for c in chunks.values())
    assert not any("DICTIONARY" in e for e in chunks["fx"].encodings)
    assert any("DICTIONARY" in e for e in chunks["state"].encodings)
    write_table(cols, path, statistics=True)
    group = pq.ParquetFile(path).metadata.row_group(0)
    assert all(group.column(i).is_stats_set for i in range(group.num_columns))
    assert group.column(0).statistics.min == cols["t"].min()


def test_a_stamp_split_in_seconds_and_nanoseconds_is_exact(tmp_path: Path) -> None:
    # a ROS export's names (PlotJuggler, rosbags-dataframe): header.stamp.sec and .nanosec, integers
    cols = _table()
    ns = 1_700_000_000_123_456_789 + np.round(cols["t"] * 1e9).astype(np.int64)
    table = {"header.stamp.sec": ns // 10**9, "header.stamp.nanosec": ns % 10**9}
    table.update({f"wrench.{'force' if w[0] == 'f' else 'torque'}.{w[1]}": cols[w] for w in WRENCH})
    log = read_log(_write_pq(tmp_path / "ros.parquet", table))
    np.testing.assert_array_equal(log.extra["stamp_ns"], ns)
    np.testing.assert_allclose(log.t, (ns - ns[0]) * 1e-9, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(log.wrench, np.column_stack([cols[w] for w in WRENCH]))


@settings(max_examples=40, deadline=None)
@given(
    unit=st.sampled_from(["s", "ms", "us", "ns"]),
    tz=st.sampled_from([None, "UTC", "Europe/Berlin", "-05:00"]),
    first=st.integers(-(2**61) // 10**9, 2**62 // 10**9),  # s after 1970 (1897 to 2116), within int64 ns
    steps=st.lists(st.integers(1, 10**6), min_size=1, max_size=30),
)
def test_a_timestamp_column_is_read_exactly_as_absolute_stamps(unit: str, tz: str | None, first: int, steps: list[int]) -> None:
    # pandas' datetime64 and ROS exports' header.stamp written as Arrow timestamps, any unit or time zone
    per = {"s": 10**9, "ms": 10**6, "us": 10**3, "ns": 1}[unit]
    ticks = first * (10**9 // per) + np.cumsum([0, *steps])
    ns = ticks * per
    cols = _table(len(ticks))
    table = pa.table({"t": pa.array(ticks, pa.timestamp(unit, tz=tz)), **{w: cols[w] for w in WRENCH}})
    with tempfile.TemporaryDirectory() as tmp:
        log = read_log(_write_pq(Path(tmp, "ts.parquet"), table))
    # a date, whatever the year (numbers are dates from 1973 on): counted from the first, the stamps kept
    np.testing.assert_array_equal(log.extra["stamp_ns"], ns)
    np.testing.assert_allclose(log.t, (ns - ns[0]) * 1e-9, rtol=1e-15, atol=0)
    np.testing.assert_array_equal(log.wrench, np.column_stack([cols[w] for w in WRENCH]))


def test_timestamp_and_duration_columns_in_parquet_and_arrow(tmp_path: Path) -> None:
    cols = _table()
    ns = 1_764_000_000_123_456_789 + np.round(cols["t"] * 1e9).astype(np.int64)
    wrench = {w: cols[w] for w in WRENCH}
    # an Arrow file, and ATI's names with a timestamp Time column and moments in N·mm
    arrow = tmp_path / "ts.arrow"
    feather.write_feather(pa.table({"t": pa.array(ns, pa.timestamp("ns")), **wrench}), arrow)
    np.testing.assert_array_equal(read_log(arrow).extra["stamp_ns"], ns)
    ati = {"Time": pa.array(ns // 1000, pa.timestamp("us", tz="UTC"))}
    ati.update({n: cols[w] * (1e3 if n[0] == "T" else 1.0) for n, w in zip(("Fx", "Fy", "Fz", "Tx", "Ty", "Tz"), WRENCH)})
    log = read_log(_write_pq(tmp_path / "ati.parquet", ati), moment_units="N*mm")
    np.testing.assert_array_equal(log.extra["stamp_ns"], ns // 1000 * 1000)
    np.testing.assert_allclose(log.wrench, np.column_stack([cols[w] for w in WRENCH]), rtol=1e-15)
    # a duration: seconds since a start, no stamps to keep
    us = np.round(cols["t"] * 1e6).astype(np.int64)
    log = read_log(_write_pq(tmp_path / "dur.parquet", {"t": pa.array(us, pa.duration("us")), **wrench}))
    np.testing.assert_allclose(log.t, us * 1e-6, rtol=1e-15)
    assert "stamp_ns" not in log.extra
    # the type gives the unit: --time-units contradicts it
    path = tmp_path / "ts.parquet"
    _write_pq(path, {"t": pa.array(ns, pa.timestamp("ns")), **wrench})
    assert _error(path, time_units="ms") == (
        f"{path}: column 't': its type timestamp[ns] carries its own time unit; --time-units ms applies to a column "
        "of numbers (leave it out)"
    )
    # a null stamp: named with --missing, dropped with it
    holes = pa.array([None if i == 4 else v for i, v in enumerate(ns.tolist())], pa.timestamp("ns"))
    path = _write_pq(tmp_path / "holes.parquet", {"t": holes, **wrench})
    assert "row 5: empty (null); expected a time stamp; or give --missing drop" in _error(path)
    log = read_log(path, missing="drop")
    np.testing.assert_array_equal(log.extra["stamp_ns"], np.delete(ns, 4))
    # stamps that go back: in ns
    back = _write_pq(tmp_path / "back.parquet", {"t": pa.array(ns[[0, 2, 1]], pa.timestamp("ns")), **{w: cols[w][:3] for w in WRENCH}})
    assert _error(back).endswith(f"got t = {ns[1]} ns at row 3 after t = {ns[2]} ns at row 2")


@pytest.mark.parametrize("name", ["__index_level_0__", "header.stamp", "recorded"])
def test_the_one_date_typed_column_is_the_time(tmp_path: Path, name: str) -> None:
    # pandas writes an unnamed DatetimeIndex as __index_level_0__; a ROS export's header.stamp as
    # one date: when no layout names a time column, the one column typed a date is t
    cols = _table()
    ns = 1_709_632_800_123_456_789 + np.round(cols["t"] * 1e9).astype(np.int64)
    table = {name: pa.array(ns, pa.timestamp("ns")), "frame_id": ["ft"] * len(ns), **{w: cols[w] for w in WRENCH}}
    log = read_log(_write_pq(tmp_path / "d.parquet", table))
    np.testing.assert_array_equal(log.extra["stamp_ns"], ns)
    assert "read as its one date-typed column and " in log.notes[0]
    assert f"t ← {name!r} (ns, its type timestamp[ns])" in log.notes[0]
    # two such columns: which is the time is the user's to say
    table["other"] = pa.array(ns, pa.timestamp("ns"))
    two = _error(_write_pq(tmp_path / "two.parquet", table))
    assert "missing column 't'" in two and f"Columns typed a date: {name!r}, 'other'; say which is t: --columns t=NAME." in two


def test_a_stamp_ns_column_of_the_file_is_never_overwritten(tmp_path: Path) -> None:
    # softtip adds stamp_ns beside absolute stamps: a file's own column of that name must agree
    cols = _table()
    ns = 1_764_000_000_123_456_789 + np.round(cols["t"] * 1e9).astype(np.int64)
    wrench = {w: cols[w] for w in WRENCH}
    same = read_log(_write_pq(tmp_path / "same.parquet", {"t": pa.array(ns, pa.timestamp("ns")), **wrench, "stamp_ns": ns}))
    np.testing.assert_array_equal(same.extra["stamp_ns"], ns)
    other = _write_pq(tmp_path / "other.parquet", {"t": pa.array(ns, pa.timestamp("ns")), **wrench, "stamp_ns": ns * 0 + 7})
    assert _error(other) == (
        f"{other}: column 'stamp_ns' holds other values than the absolute stamps of column 't', which softtip writes "
        "under that name; expected one of them (rename the column, or read the time from it: --columns t=stamp_ns "
        "--time-units ns)"
    )
    # pandas' to_csv of t = stamp_ns / 1e9: t to 100 ns, the column exact; the column's stamps are kept
    pandas = tmp_path / "pandas.csv"
    rows = [f"{v / 1e9!r},1,2,3,0.1,0.2,0.3,{v}" for v in ns.tolist()]
    pandas.write_text("t,fx,fy,fz,mx,my,mz,stamp_ns\n" + "\n".join(rows) + "\n")
    np.testing.assert_array_equal(read_log(pandas).stamps_ns, ns)
    csv = tmp_path / "other.csv"
    rows = [f"{s / 1e9:.6f},1,2,3,0.1,0.2,0.3,{k}" for k, s in enumerate(ns - ns % 1000)]
    csv.write_text("t,fx,fy,fz,mx,my,mz,stamp_ns\n" + "\n".join(rows) + "\n")
    assert "column 'stamp_ns' holds other values" in _error(csv)


def test_stamps_coarser_than_the_sampling_are_said_so(tmp_path: Path) -> None:
    # datetime64[s] of a 50 Hz sensor: most stamps repeat; the note says so, with the column's
    # own name, and does not ask for seconds (the type gives them)
    cols = _table(500)
    t = np.arange(500) * 0.02
    seconds = 1_709_632_800 + np.floor(t).astype(np.int64)
    ati = {"Time": pa.array(seconds, pa.timestamp("s")), **{n: cols[w] for n, w in zip(("Fx", "Fy", "Fz", "Tx", "Ty", "Tz"), WRENCH)}}
    log = read_log(_write_pq(tmp_path / "s.parquet", ati))
    notes = [n for n in log.warnings if "steps are 0" in n]
    assert notes == [f"{tmp_path / 's.parquet'}: column 'Time': 490 of 499 steps are 0: the stamps are coarser than "
                     "the sampling, and every time window (the tare, the line evidence) counts samples of equal stamps "
                     "as one instant; expected stamps of the samples' own resolution"]  # fmt: skip
    assert not any("Give t in seconds" in n for n in log.warnings)
