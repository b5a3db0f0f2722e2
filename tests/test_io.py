"""Tests for softtip.io.tables: reading logs (and every bad-input message) and writing tables."""

from __future__ import annotations

import io
import os
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import softtip.io.tables as sio
from softtip.errors import InputError
from softtip.io.tables import Log, read_log, write_table

HEADER = "t,fx,fy,fz,mx,my,mz"
WRENCH = ("fx", "fy", "fz", "mx", "my", "mz")


def _write(tmp_path: Path, text: str | bytes, name: str = "log.csv") -> str:
    """Write ``text`` verbatim (no newline translation) and return the path as a str."""
    path = tmp_path / name
    path.write_bytes(text.encode("utf-8") if isinstance(text, str) else text)
    return str(path)


COLUMNS_HINT = " Other names: map them with --columns t=NAME,fx=NAME,… (docs/guide/input-formats.md lists the headers read as they are)."
MISSING_HINT = "; or give --missing drop (skip the row) or --missing interpolate (fill it)"


def _error(path: str, **kw: str) -> str:
    with pytest.raises(InputError) as info:
        read_log(path, **kw)
    return str(info.value)


def _columns(t: np.ndarray, wrench: np.ndarray) -> dict[str, np.ndarray]:
    return {"t": t, **{name: wrench[:, i] for i, name in enumerate(WRENCH)}}


@pytest.fixture
def sample() -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(7)
    t = np.cumsum(rng.uniform(1e-4, 0.02, 200))
    # Wide dynamic range, negative values and exact zeros.
    wrench = rng.normal(size=(200, 6)) * np.array([1, 10, 1e-3, 1e-6, 0.3, 1e3])
    wrench[5] = 0.0
    return t, wrench


# ---------------------------------------------------------------------------- good input


def test_round_trip_exact_with_17_digits(tmp_path: Path, sample: tuple[np.ndarray, np.ndarray]) -> None:
    t, wrench = sample
    path = str(tmp_path / "out.csv")
    write_table(_columns(t, wrench), path, float_format="%.17g")
    log = read_log(path)
    assert isinstance(log, Log)
    np.testing.assert_array_equal(log.t, t)
    np.testing.assert_array_equal(log.wrench, wrench)
    assert log.t.dtype == np.float64 and log.t.shape == (200,)
    assert log.wrench.dtype == np.float64 and log.wrench.shape == (200, 6)
    assert log.wrench.flags.c_contiguous
    assert log.extra == {}
    assert log.source == path
    assert log.units == "si"


def test_round_trip_default_format_to_10_digits(tmp_path: Path, sample: tuple[np.ndarray, np.ndarray]) -> None:
    t, wrench = sample
    path = tmp_path / "out.csv"
    write_table(_columns(t, wrench), path)  # a PathLike works too
    log = read_log(path)
    np.testing.assert_allclose(log.t, t, rtol=1e-9, atol=0)
    np.testing.assert_allclose(log.wrench, wrench, rtol=1e-9, atol=0)


@settings(max_examples=30, deadline=None)
@given(
    st.lists(st.floats(-1e6, 1e6, allow_nan=False), min_size=1, max_size=20, unique=True),
    st.floats(allow_nan=False, allow_infinity=False),
)
def test_round_trip_property(times: list[float], value: float) -> None:
    buf = io.StringIO()
    t = np.sort(np.array(times))
    wrench = np.full((len(t), 6), value)
    write_table(_columns(t, wrench), buf, float_format="%.17g")
    buf.seek(0)
    log = read_log(buf)
    np.testing.assert_array_equal(log.t, t)
    np.testing.assert_array_equal(log.wrench, wrench)


def test_kgf_mm_is_converted_to_si(tmp_path: Path) -> None:
    path = _write(tmp_path, f"{HEADER}\n0.5,1,2,-1,1,2,-1\n")
    log = read_log(path, units="kgf-mm")
    np.testing.assert_allclose(log.wrench, [[9.80665, 19.6133, -9.80665, 9.80665e-3, 19.6133e-3, -9.80665e-3]])
    np.testing.assert_array_equal(log.t, [0.5])  # t stays in seconds
    assert log.units == "kgf-mm"
    si = read_log(path)
    np.testing.assert_array_equal(si.wrench, [[1, 2, -1, 1, 2, -1]])


def test_column_order_does_not_matter_and_extras_are_kept(tmp_path: Path) -> None:
    ordered = _write(tmp_path, f"{HEADER}\n0,1,2,3,4,5,6\n0.1,7,8,9,10,11,12\n", "a.csv")
    shuffled = _write(
        tmp_path,
        'note, mz ,t,my,id,fz,mx,fy,fx\n'
        '"a, b",6,0,5,007,3,4,2,1\n'
        ' x ,12,0.1,11,1e3,9,10,8,7\n',
        "b.csv",
    )
    a, b = read_log(ordered), read_log(shuffled)
    np.testing.assert_array_equal(a.t, b.t)
    np.testing.assert_array_equal(a.wrench, b.wrench)
    np.testing.assert_array_equal(b.wrench, [[1, 2, 3, 4, 5, 6], [7, 8, 9, 10, 11, 12]])
    # Extras: names stripped, input order, cells verbatim (no number parsing, spaces kept).
    assert list(b.extra) == ["note", "id"]
    assert b.extra == {"note": ["a, b", " x "], "id": ["007", "1e3"]}


def test_tolerated_layout(tmp_path: Path) -> None:
    """BOM, CRLF, comments and blanks before the header, spaces, trailing blank lines."""
    text = "\ufeff# recorded 2024-01-01\r\n\r\n#  units: si\r\n t , fx,fy,fz,mx,my,mz \r\n 0 , 1,2,3,4,5,6\r\n1,1,2,3,4,5,6\r\n\r\n  \r\n"
    log = read_log(_write(tmp_path, text))
    np.testing.assert_array_equal(log.t, [0, 1])
    np.testing.assert_array_equal(log.wrench, [[1, 2, 3, 4, 5, 6]] * 2)


def test_read_from_streams() -> None:
    text = f"{HEADER}\n0,1,2,3,4,5,6\n"
    log = read_log(io.StringIO(text))
    assert log.source == "<stream>"
    np.testing.assert_array_equal(log.wrench, [[1, 2, 3, 4, 5, 6]])
    binary = io.BytesIO(b"\xef\xbb\xbf" + text.encode())
    binary.name = "<stdin>"  # what sys.stdin.buffer reports
    log = read_log(binary)
    assert log.source == "<stdin>"
    np.testing.assert_array_equal(log.t, [0.0])


@pytest.mark.parametrize("where", ["first", "boundary", "late"])
def test_chunked_parse_matches_row_by_row(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, where: str) -> None:
    """The block parser and the careful parser agree, across block boundaries."""
    monkeypatch.setattr(sio, "_CHUNK_ROWS", 4)
    n = {"first": 3, "boundary": 8, "late": 11}[where]
    rows = "".join(f"{0.1 * i!r},{i},{-i},{i * 1e-3},1,2,3,r{i}\n" for i in range(n))
    path = _write(tmp_path, f"{HEADER},tag\n{rows}\n\n")
    fast = read_log(path)
    header = sio._read_header(Path(path).read_text(), path)
    start = (header.lines.tell(), 0)
    t, wrench, extra = sio._parse_careful(header, sio._column_index(header, path), path, start)
    np.testing.assert_array_equal(fast.t, t)
    np.testing.assert_array_equal(fast.wrench, wrench)
    assert fast.extra == extra == {"tag": [f"r{i}" for i in range(n)]}


def test_quoted_line_break_counts_lines_like_an_editor(tmp_path: Path) -> None:
    path = _write(tmp_path, f'{HEADER},note\n0,1,2,3,4,5,6,"two\nlines"\n1,1,2,3,4,5,6,x\n2,oops,2,3,4,5,6,x\n')
    assert _error(path) == f"{path}:5: column 'fx': expected a number, got 'oops'"


# ----------------------------------------------------------------------------- bad input


def test_unknown_units(tmp_path: Path) -> None:
    path = _write(tmp_path, f"{HEADER}\n0,1,2,3,4,5,6\n")
    assert _error(path, units="N-mm") == f"{path}: unknown units 'N-mm'; expected one of: si, kgf-mm"


def test_file_not_found(tmp_path: Path) -> None:
    path = str(tmp_path / "nope.csv")
    assert _error(path) == f"{path}: file not found; expected an existing CSV log file"


def test_unreadable_directory(tmp_path: Path) -> None:
    assert _error(str(tmp_path)) == f"{tmp_path}: is a directory; expected a CSV log file"


@pytest.mark.parametrize(
    ("exc", "expected"),
    [
        (PermissionError(13, "Permission denied"), "permission denied; expected a readable CSV log file"),
        (OSError(5, "Input/output error"), "cannot read (Input/output error); expected a readable CSV log file"),
    ],
)
def test_unreadable_os_errors(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, exc: OSError, expected: str) -> None:
    # Simulated: the tests may run as root, who can read anything.
    path = _write(tmp_path, f"{HEADER}\n0,1,2,3,4,5,6\n")

    def refuse(*args: object, **kwargs: object) -> None:
        raise exc

    monkeypatch.setattr(sio, "open", refuse, raising=False)
    assert _error(path) == f"{path}: {expected}"


def test_not_utf8_text_stream() -> None:
    stream = io.TextIOWrapper(io.BytesIO(b"t,fx\n\xff\n"), encoding="utf-8")
    with pytest.raises(InputError, match=r"^<stream>: not valid UTF-8 \(invalid start byte\); expected UTF-8 text$"):
        read_log(stream)


def test_not_utf8(tmp_path: Path) -> None:
    path = _write(tmp_path, f"{HEADER}\n0,1,2,3,4,5,6\n1,2,3,4,5,6,\xb0\n".encode("latin-1"))
    assert _error(path) == (
        f"{path}:3: not valid UTF-8 (byte 0xb0 at byte offset 46); "
        "expected a UTF-8 text file (re-save it as UTF-8)"
    )


@pytest.mark.parametrize("text", ["", "\n\n  \n"])
def test_empty_file(tmp_path: Path, text: str) -> None:
    path = _write(tmp_path, text)
    assert _error(path) == f"{path}: empty file; expected a CSV header row naming t, fx, fy, fz, mx, my, mz"


def test_only_comments(tmp_path: Path) -> None:
    path = _write(tmp_path, "# nothing here\n")
    assert _error(path) == (
        f"{path}: only comments and blank lines; expected a CSV header row naming t, fx, fy, fz, mx, my, mz"
    )


@pytest.mark.parametrize("tail", ["", "\n", "\n\n\n"])
def test_header_only(tmp_path: Path, tail: str) -> None:
    path = _write(tmp_path, "# comment\n" + HEADER + tail)
    assert _error(path) == (
        f"{path}:2: header only, no data rows; expected at least one row of t, fx, fy, fz, mx, my, mz "
        "after the header"
    )


def test_a_time_column_with_its_unit_in_the_name_is_suggested_with_the_unit(tmp_path: Path) -> None:
    path = _write(tmp_path, "timestamp_ms,fx,fy,fz,mx,my,mz\n0,1,2,3,4,5,6\n")
    assert "Column 1 is 'timestamp_ms': did you mean 't'? (--columns t=timestamp_ms --time-units ms)" in _error(path)
    assert read_log(path, columns="t=timestamp_ms", time_units="ms").wrench.tolist() == [[1, 2, 3, 4, 5, 6]]


def test_missing_columns_with_suggestions(tmp_path: Path) -> None:
    # time, Fx and f_y are read as they are (test_common_names_are_read_and_said): only mz is missing
    path = _write(tmp_path, "time,Fx,f_y,fz,mx,my,torque_zz\n0,1,2,3,4,5,6\n")
    assert _error(path) == (
        f"{path}:1: missing column 'mz'; expected a header with columns "
        "t, fx, fy, fz, mx, my, mz (any order)." + COLUMNS_HINT
    )
    path = _write(tmp_path, "tt,fxx,fy,fz,mx,my,mz\n0,1,2,3,4,5,6\n")
    assert _error(path) == (
        f"{path}:1: missing columns 't', 'fx'; expected a header with columns "
        "t, fx, fy, fz, mx, my, mz (any order). "
        "Column 1 is 'tt': did you mean 't'? Column 2 is 'fxx': did you mean 'fx'?" + COLUMNS_HINT
    )


def test_common_names_are_read_and_said(tmp_path: Path) -> None:
    """time/Fx/f_y/torque_z (the former near misses) are recognised; the note says which column is what."""
    path = _write(tmp_path, "time,Fx,f_y,fz,mx,my,torque_z\n0,1,2,3,4,5,6\n")
    log = read_log(path)
    assert log.wrench.tolist() == [[1, 2, 3, 4, 5, 6]]
    (note,) = log.notes
    assert "t ← 'time' (s, not in the header), fx ← 'Fx' (N, not in the header)" in note


def test_missing_column_difflib_typo(tmp_path: Path) -> None:
    path = _write(tmp_path, "t,fx,fy,fz,mx,my,mzz\n0,1,2,3,4,5,6\n")
    assert _error(path).endswith("Column 7 is 'mzz': did you mean 'mz'?" + COLUMNS_HINT)


def test_missing_column_without_near_miss(tmp_path: Path) -> None:
    path = _write(tmp_path, "t,fx,fy,fz,mx,my\n0,1,2,3,4,5\n")
    assert _error(path) == (
        f"{path}:1: missing column 'mz'; expected a header with columns "
        "t, fx, fy, fz, mx, my, mz (any order)." + COLUMNS_HINT
    )


def test_missing_header_hints(tmp_path: Path) -> None:
    # semicolon- and tab-separated files are read now (issue 28)
    semicolons = _write(tmp_path, "t;fx;fy;fz;mx;my;mz\n0;1;2;3;4;5;6\n", "a.csv")
    assert read_log(semicolons).wrench.tolist() == [[1, 2, 3, 4, 5, 6]]
    commented = _write(tmp_path, "# t,fx,fy,fz,mx,my,mz\n0,1,2,3,4,5,6\n", "b.csv")
    assert _error(commented).startswith(f"{commented}:2: missing columns 't', 'fx',")
    assert _error(commented).endswith(
        "Line 1 looks like the header commented out with '#'; remove the '#', or read the columns by position: "
        "--columns t=1,fx=2,fy=3,fz=4,mx=5,my=6,mz=7." + COLUMNS_HINT
    )
    assert read_log(commented, columns="t=1,fx=2,fy=3,fz=4,mx=5,my=6,mz=7").wrench.tolist() == [[1, 2, 3, 4, 5, 6]]
    spaces = _write(tmp_path, "t fx fy fz mx my mz\n0 1 2 3 4 5 6\n", "s.csv")
    assert "The header looks space-separated; softtip reads comma, tab or semicolon delimiters" in _error(spaces)
    savetxt = _write(tmp_path, "0.0 1 2 3 4 5 6\n0.02 1 2 3 4 5 6\n", "savetxt.txt")  # numpy.savetxt's default
    assert "Line 1 looks like space-separated numbers; softtip reads comma, tab or semicolon" in _error(savetxt)
    assert "its rows look space-separated" in _error(savetxt, columns="t=1,fx=2,fy=3,fz=4,mx=5,my=6,mz=7")
    no_header = _write(tmp_path, "0,1,2,3,4,5,6\n", "c.csv")
    assert _error(no_header).endswith(
        "Line 1 looks like data; expected the header row first (a file without one: give the columns by position, "
        "e.g. --columns t=1,fx=2,fy=3,fz=4,mx=5,my=6,mz=7)." + COLUMNS_HINT
    )
    assert read_log(no_header, columns="t=1,fx=2,fy=3,fz=4,mx=5,my=6,mz=7").wrench.tolist() == [[1, 2, 3, 4, 5, 6]]


def test_duplicate_column(tmp_path: Path) -> None:
    path = _write(tmp_path, "t,fx,fy,fz,mx,my,mz, fx\n0,1,2,3,4,5,6,7\n")
    assert _error(path) == f"{path}:1: duplicate column 'fx' (columns 2 and 8); expected each column name once"


@pytest.mark.parametrize(("row", "got"), [("0.1,1,2,3,4,5", 6), ("0.1,1,2,3,4,5,6,7", 8)])
def test_wrong_number_of_cells(tmp_path: Path, row: str, got: int) -> None:
    path = _write(tmp_path, f"{HEADER}\n0,1,2,3,4,5,6\n{row}\n0.2,1,2,3,4,5,6\n")
    assert _error(path) == f"{path}:3: expected 7 cells (one per header column), got {got}"


def test_a_trailing_delimiter_and_a_footer_are_named(tmp_path: Path) -> None:
    rows = "0,1,2,3,4,5,6,\n0.1,1,2,3,4,5,6,\n"
    path = _write(tmp_path, f"{HEADER}\n{rows}", "comma.csv")
    assert _error(path) == (
        f"{path}:2: expected 7 cells (one per header column), got 8; its last cell is empty: a delimiter at the end "
        "of each row that the header lacks? Remove it"
    )
    for footer, got in (("# end of recording", 1), ("Total samples: 2", 1), ("stopped, 2 samples", 2)):
        path = _write(tmp_path, f"{HEADER}\n0,1,2,3,4,5,6\n0.1,1,2,3,4,5,6\n{footer}\n\n", "footer.csv")
        assert _error(path) == (
            f"{path}:4: expected 7 cells (one per header column), got {got}; this is the file's last line: a footer "
            "after the data, or a row cut short? Delete it"
        )


def test_a_quoted_decimal_comma_in_a_comma_separated_file_is_named(tmp_path: Path) -> None:
    path = _write(tmp_path, f'{HEADER}\n0,"0,5",2,3,4,5,6\n', "dc.csv")
    assert _error(path) == (
        f"{path}:2: column 'fx': expected a number, got '0,5'; a decimal comma: read with semicolon or tab "
        "delimiters only (a comma-separated file needs decimal points; re-export it with them, or with ';' between "
        "cells)"
    )
    assert read_log(_write(tmp_path, "t;fx;fy;fz;mx;my;mz\n0;0,5;2;3;4;5;6\n", "sc.csv")).wrench[0, 0] == 0.5


def test_clock_times_and_utf16_are_named(tmp_path: Path) -> None:
    path = _write(tmp_path, f"{HEADER}\n12:03:04.000,1,2,3,4,5,6\n", "clock.csv")
    assert _error(path) == (
        f"{path}:2: column 't': expected a number, got '12:03:04.000'; clock times (hh:mm:ss) are not read: give t "
        "in seconds, or map a column of seconds or stamps with --columns t=NAME"
    )
    for stamp in ("2024-03-14T10:22:01.120", "2024-03-14 10:22:01.120+01:00"):  # pandas' to_csv of datetime64
        path = _write(tmp_path, f"{HEADER}\n{stamp},1,2,3,4,5,6\n", "iso.csv")
        assert _error(path) == (
            f"{path}:2: column 't': expected a number, got {stamp!r}; dates as text are not read from CSV: give t in "
            "seconds (or Unix time), or write the log as Parquet or Arrow, whose timestamp columns are read as dates"
        )
    utf16 = tmp_path / "u16.txt"
    utf16.write_bytes(f"{HEADER}\n0,1,2,3,4,5,6\n".encode("utf-16"))  # with its byte-order mark, as Excel writes
    assert _error(utf16) == (
        f"{utf16}:1: not valid UTF-8 (byte 0xff at byte offset 0) (a UTF-16 file: it starts with UTF-16's byte-order "
        'mark, as Excel\'s "Unicode text" writes); expected a UTF-8 text file (re-save it as UTF-8)'
    )


def test_non_numeric_cell(tmp_path: Path) -> None:
    path = _write(tmp_path, f"{HEADER},note\n0,1,2,3,4,5,6,ok\n0.1,1,2,3,4,1.5 N,6,also text\n")
    assert _error(path) == f"{path}:3: column 'my': expected a number, got '1.5 N'"


@pytest.mark.parametrize("cell", ["nan", "NaN", "inf", "-Infinity", "1e999"])
def test_nan_or_inf(tmp_path: Path, cell: str) -> None:
    path = _write(tmp_path, f"{HEADER}\n0,1,2,3,4,5,6\n0.1,1,2,{cell},4,5,6\n")
    hint = MISSING_HINT if cell.lower() == "nan" else ""
    assert _error(path) == f"{path}:3: column 'fz': expected a finite number, got '{cell}'{hint}"


def test_nan_in_t(tmp_path: Path) -> None:
    path = _write(tmp_path, f"{HEADER}\nnan,1,2,3,4,5,6\n")
    assert _error(path) == f"{path}:2: column 't': expected a finite number, got 'nan'" + MISSING_HINT


@pytest.mark.parametrize("cell", ["", "  "])
def test_empty_cell(tmp_path: Path, cell: str) -> None:
    path = _write(tmp_path, f"{HEADER}\n0,1,2,3,4,5,6\n0.1,1,2,3,{cell},5,6\n")
    assert _error(path) == f"{path}:3: column 'mx': empty cell; expected a number" + MISSING_HINT


def test_empty_extra_cell_is_fine(tmp_path: Path) -> None:
    log = read_log(_write(tmp_path, f"{HEADER},note\n0,1,2,3,4,5,6,\n"))
    assert log.extra == {"note": [""]}


@pytest.mark.parametrize("t3", ["0.09", "0.05"])
def test_t_going_back(tmp_path: Path, t3: str) -> None:
    path = _write(tmp_path, f"{HEADER}\n0,1,2,3,4,5,6\n0.1,1,2,3,4,5,6\n{t3},1,2,3,4,5,6\n")
    assert _error(path) == (
        f"{path}:4: column 't': expected t non-decreasing (a stamp may repeat, not go back), "
        f"got t = {t3} on line 4 after t = 0.1 on line 3"
    )


def test_t_decreasing_across_block_boundary(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(sio, "_CHUNK_ROWS", 3)
    rows = "".join(f"{t},1,2,3,4,5,6\n" for t in ["0", "1", "2", "1.5", "3"])
    path = _write(tmp_path, f"{HEADER}\n{rows}")
    assert _error(path) == (
        f"{path}:5: column 't': expected t non-decreasing (a stamp may repeat, not go back), "
        "got t = 1.5 on line 5 after t = 2 on line 4"
    )


def test_blank_line_between_data_rows(tmp_path: Path) -> None:
    path = _write(tmp_path, f"{HEADER}\n0,1,2,3,4,5,6\n\n \n1,1,2,3,4,5,6\n")
    assert _error(path) == (
        f"{path}:3: blank line between data rows (data continues on line 5); "
        "expected blank lines only at the end of the file"
    )


def test_first_error_in_file_order_wins(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(sio, "_CHUNK_ROWS", 2)  # the errors sit in different blocks
    good = "".join(f"{t},1,2,3,4,5,6\n" for t in range(3))
    # Line 5: wrong cell count; line 6: non-numeric; line 7: t going back.
    path = _write(tmp_path, f"{HEADER}\n{good}3,1,2\n4,x,2,3,4,5,6\n0,1,2,3,4,5,6\n")
    assert _error(path) == f"{path}:5: expected 7 cells (one per header column), got 3"

    # Within a row, cells are checked in file order: here 'fz' comes before the bad 't' ...
    path = _write(tmp_path, "fz,t,fx,fy,mx,my,mz\n1,0,1,2,4,5,6\nbad,-1,1,2,4,5,6\n")
    assert _error(path) == f"{path}:3: column 'fz': expected a number, got 'bad'"
    # ... and here after it.
    path = _write(tmp_path, "t,fx,fy,mx,my,mz,fz\n0,1,2,4,5,6,1\n-1,1,2,4,5,6,bad\n")
    assert _error(path) == (
        f"{path}:3: column 't': expected t non-decreasing (a stamp may repeat, not go back), "
        "got t = -1 on line 3 after t = 0 on line 2"
    )


_CORRUPTIONS = {
    "text": lambda i: f"{i},1,2,x,4,5,6,n",
    "cells": lambda i: f"{i},1,2",
    "blank": lambda i: f"\n\n{i},1,2,3,4,5,6,n",
    "t": lambda i: f"{i - 2},1,2,3,4,5,6,n",
    "nan": lambda i: f"{i},1,2,3,4,5,nan,n",
}


@pytest.mark.parametrize("kind", sorted(_CORRUPTIONS))
def test_block_size_never_changes_the_reported_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, kind: str
) -> None:
    """The fast parser hands over to the careful one mid-file; the message must not depend on where."""
    n = 9
    for bad in range(1 if kind == "t" else 0, n):  # row 0 has no previous t
        rows = [f'{i},1,2,3,4,5,6,"multi\nline"' if i % 3 == 1 else f"{i},1,2,3,4,5,6,n" for i in range(n)]
        rows[bad] = _CORRUPTIONS[kind](bad)
        path = _write(tmp_path, f"{HEADER},note\n" + "\n".join(rows) + "\n\n")
        messages = set()
        for chunk in (1, 2, 3, 10**6):
            monkeypatch.setattr(sio, "_CHUNK_ROWS", chunk)
            messages.add(_error(path))
        assert len(messages) == 1, messages


def test_stream_errors_name_the_stream() -> None:
    stream = io.StringIO(f"{HEADER}\n0,1,2,3,4,5,x\n")
    stream.name = "<stdin>"
    with pytest.raises(InputError, match=r"^<stdin>:2: column 'mz': expected a number, got 'x'$"):
        read_log(stream)


def test_input_error_is_a_value_error(tmp_path: Path) -> None:
    with pytest.raises(ValueError):
        read_log(tmp_path / "missing.csv")


# ------------------------------------------------------------------------------- writing


def test_write_formats_each_kind(tmp_path: Path) -> None:
    path = tmp_path / "t.csv"
    write_table(
        {
            "t": np.array([0.0, 0.02]),
            "state": ["line", "none"],
            "ok": np.array([True, False]),
            "n": [3, -4],
            "angle_deg": [45.0, np.nan],
            "big": [1e20, -np.inf],
            "note": ["plain", " spaced "],
        },
        path,
    )
    assert path.read_text() == (
        "t,state,ok,n,angle_deg,big,note\n"
        "0,line,1,3,45,1e+20,plain\n"
        "0.02,none,0,-4,nan,-inf, spaced \n"
    )


def test_write_quotes_the_text_cells_that_need_it(tmp_path: Path) -> None:
    # minimal quoting, whichever writer formats a block: a cell's text does not depend on the
    # others (every text cell was quoted once one needed it, so a piece of a log written alone
    # differed from the same rows in the whole)
    path = tmp_path / "t.csv"
    notes = ["a,b", 'say "hi"']
    write_table({"t": [0.0, 1.0], "state": ["line", "none"], "note": notes, "obj": [None, b"x,\ny"]}, path)
    assert path.read_text() == (
        "t,state,note,obj\n"
        '0,line,"a,b",None\n'
        '1,none,"say ""hi""","x,\ny"\n'
    )
    import csv  # reads the quoted cells back verbatim

    assert list(csv.reader(io.StringIO(path.read_text(), newline=""))) == [
        ["t", "state", "note", "obj"], ["0", "line", "a,b", "None"], ["1", "none", 'say "hi"', "x,\ny"]
    ]  # fmt: skip


@pytest.mark.parametrize("digits", [1, 3, 10, 15, 17])
def test_write_rounds_to_the_format_digits(digits: int) -> None:
    """``%.<d>g`` through pyarrow: each value reads back as printf's rounding of it."""
    rng = np.random.default_rng(digits)
    x = np.concatenate(
        [rng.normal(size=300) * 10.0 ** rng.integers(-30, 30, 300), [0.0, -0.0, 1.0, 0.5, 123456789012.0, 1e-300]]
    )
    buf = io.StringIO()
    write_table({"x": x}, buf, float_format=f"%.{digits}g")
    written = np.array([float(v) for v in buf.getvalue().split()[1:]])
    expected = np.array([float(f"%.{digits}g" % v) for v in x])
    # within one unit of the last digit (x * 10**k may round across a tie) ...
    np.testing.assert_allclose(written, expected, rtol=1.01 * 10.0 ** (1 - digits), atol=0)
    # ... nearly always equal where 10**k is exact, for up to 12 digits (more: x * 10**k
    # carries a rounding error near the last digit) ...
    scaled = (np.abs(x) >= 10.0 ** (digits - 23)) & (np.abs(x) < 10.0 ** (digits + 22))
    if digits <= 12:
        assert np.mean(written[scaled] == expected[scaled]) > 0.99
    # ... and always beyond (tiny or huge values go through printf), or with 17 digits
    np.testing.assert_array_equal(written[~scaled], expected[~scaled])
    if digits == 17:
        np.testing.assert_array_equal(written, x)


def test_write_float_format(tmp_path: Path) -> None:
    buf = io.StringIO()
    write_table({"x": [1 / 3, -np.inf, 1e-300]}, buf, float_format="%.3e")
    assert buf.getvalue() == "x\n3.333e-01\n-inf\n1.000e-300\n"


def test_write_to_stdout(capsys: pytest.CaptureFixture[str]) -> None:
    write_table({"a": [1.5], "b c": ["x"]}, None)
    assert capsys.readouterr().out == "a,b c\n1.5,x\n"


def test_write_zero_rows_writes_header(tmp_path: Path) -> None:
    path = tmp_path / "empty.csv"
    write_table({"t": np.empty(0), "fx": []}, path)
    assert path.read_text() == "t,fx\n"


def test_write_round_trips_extras_through_read(tmp_path: Path) -> None:
    path = tmp_path / "x.csv"
    notes = ["plain", "with, comma", 'quote "q"', "two\nlines"]
    write_table({**_columns(np.arange(4.0), np.ones((4, 6))), "note": notes}, path)
    assert read_log(path).extra == {"note": notes}


def test_write_many_blocks_matches_one_block(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    cols = {"t": np.arange(10.0) / 3, "s": [f"s{i}" for i in range(10)], "b": np.arange(10) % 2 == 0}
    one, many = io.StringIO(), io.StringIO()
    write_table(cols, one)
    monkeypatch.setattr(sio, "_CHUNK_ROWS", 3)
    write_table(cols, many)
    assert one.getvalue() == many.getvalue()
    assert one.getvalue().count("\n") == 11


def test_write_rejects_unequal_lengths(tmp_path: Path) -> None:
    path = tmp_path / "x.csv"
    with pytest.raises(ValueError, match=r"different lengths \('t': 3, 'fx': 2\)"):
        write_table({"t": [0.0, 1.0, 2.0], "fx": [1.0, 2.0]}, path)
    assert not path.exists()


@pytest.mark.parametrize(
    ("columns", "float_format", "match"),
    [
        ({}, "%.10g", "no columns"),
        ({"w": np.zeros((2, 6))}, "%.10g", r"column 'w': expected a 1-D sequence, got shape \(2, 6\)"),
        ({"x": [1.0]}, "%.3g %.3g", "must format exactly one float"),
        ({"x": [1.0]}, "%.3g,", "expected no comma"),
    ],
)
def test_write_rejects_bad_arguments(columns: dict, float_format: str, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        write_table(columns, io.StringIO(), float_format=float_format)


class _Explodes:
    """A cell whose text cannot be produced: fails the write part-way through."""

    def __str__(self) -> str:
        raise RuntimeError("boom")


def _failing_columns(n: int = 40, bad_row: int = 30) -> dict[str, list]:
    cells: list[object] = [f"ok{i}" for i in range(n)]
    cells[bad_row] = _Explodes()
    return {"t": list(np.arange(n, dtype=float)), "obj": cells}


def test_atomic_write_leaves_nothing_on_failure(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(sio, "_CHUNK_ROWS", 8)  # several blocks are written before the failure
    written: list[int] = []
    real = sio._write_rows

    def spy(out, plan):  # type: ignore[no-untyped-def]
        try:
            real(out, plan)
        finally:
            written.append(out.tell())

    monkeypatch.setattr(sio, "_write_rows", spy)
    path = tmp_path / "out.csv"
    with pytest.raises(RuntimeError, match="boom"):
        write_table(_failing_columns(), path)
    assert written and written[0] > 0  # the failure really was mid-write
    assert list(tmp_path.iterdir()) == []


def test_atomic_write_keeps_existing_file_on_failure(tmp_path: Path) -> None:
    path = tmp_path / "out.csv"
    path.write_text("precious\n")
    with pytest.raises(RuntimeError, match="boom"):
        write_table(_failing_columns(), path)
    assert path.read_text() == "precious\n"
    assert [p.name for p in tmp_path.iterdir()] == ["out.csv"]


def test_atomic_write_cleans_up_when_replace_fails(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = tmp_path / "out.csv"
    path.write_text("precious\n")

    def no_replace(src: str, dst: str) -> None:
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(sio.os, "replace", no_replace)
    with pytest.raises(InputError, match=r"out\.csv: cannot write \(Permission denied\)"):
        write_table({"t": [1.0]}, path)
    assert path.read_text() == "precious\n"
    assert [p.name for p in tmp_path.iterdir()] == ["out.csv"]


def test_atomic_write_replaces_existing_file(tmp_path: Path) -> None:
    path = tmp_path / "out.csv"
    path.write_text("old\n")
    write_table({"t": [1.0]}, path)
    assert path.read_text() == "t\n1\n"
    assert [p.name for p in tmp_path.iterdir()] == ["out.csv"]
    if os.name == "posix":  # the umask decides the mode, as for a plain open()
        umask = os.umask(0)
        os.umask(umask)
        assert path.stat().st_mode & 0o777 == 0o666 & ~umask


def test_write_to_missing_directory_or_directory(tmp_path: Path) -> None:
    missing = tmp_path / "no" / "out.csv"
    with pytest.raises(InputError, match=r"no/out\.csv: cannot write \(No such file or directory\)"):
        write_table({"t": [1.0]}, missing)
    with pytest.raises(InputError, match="is a directory"):
        write_table({"t": [1.0]}, tmp_path)
    assert list(tmp_path.iterdir()) == []


def test_write_to_stream_leaves_it_open() -> None:
    buf = io.StringIO()
    write_table({"t": [0.5]}, buf)
    assert not buf.closed and buf.getvalue() == "t\n0.5\n"


# ------------------------------------------------------------- time: repeats, scale, cuts


def _log_text(t: np.ndarray, extra: str = "") -> str:
    rng = np.random.default_rng(11)
    w = rng.normal(size=(len(t), 6)) * 0.1
    rows = "".join(f"{ti!r},{','.join(repr(x) for x in wi)}{extra}\n" for ti, wi in zip(t.tolist(), w.tolist()))
    return f"{HEADER}{',note' if extra else ''}\n{rows}"


def test_repeated_stamps_are_kept_counted_and_located(tmp_path: Path) -> None:
    t = np.arange(50) * 1e-3
    t[[10, 11, 30]] = t[[9, 9, 29]]  # lines 11, 12 and 31 repeat the stamp before
    path = _write(tmp_path, _log_text(t))
    log = read_log(path)
    np.testing.assert_array_equal(log.t, t)
    assert log.repeated_t == 3
    assert log.warnings == (
        f"{path}: 3 repeated time stamps (the first on line 12: t = 0.009 s as on the line before); kept in file order",
    )


def test_gaps_in_t_are_counted_and_the_largest_located(tmp_path: Path) -> None:
    """Samples a recorder lost (a step of more than 10 median steps and 0.05 s): kept, and said
    once with how many, the largest and the line after it; jitter and a clean log say nothing."""
    t = np.arange(400) * 1e-3
    t[100:] += 0.2  # 200 samples lost before line 102 (the header is line 1)
    t[300:] += 0.06  # and 60 before line 302
    log = read_log(_write(tmp_path, _log_text(t)))
    np.testing.assert_array_equal(log.t, t)
    (note,) = log.warnings
    assert "t has 2 gaps longer than 0.05 s (the largest 0.201 s, before line 102: about 200 samples at one per " in note
    jitter = np.arange(400) * 1e-3
    jitter[200:] += 0.004  # 4 samples: a recorder's hiccup, not a gap
    assert read_log(_write(tmp_path, _log_text(jitter))).warnings == ()


@pytest.mark.parametrize("offset", [-1, 0, 1])
def test_a_gap_read_in_blocks_is_said_as_read_at_once(tmp_path: Path, monkeypatch, offset: int) -> None:
    """The block reader (``iter_log``, the run in pieces) says a gap in the words of ``read_log``,
    also on a block's first row, its last, and the first row of the next."""
    from softtip.io.tables import iter_log

    monkeypatch.setattr(sio, "_CSV_BLOCK_BYTES", 8192)  # blocks of about 70 rows
    monkeypatch.setattr(sio, "_LOCATE_BYTES", 4096)
    t = np.arange(2000) * 1e-3
    path = _write(tmp_path, _log_text(t))
    sizes = [len(block[0]) for block in iter_log(path)]
    assert len(sizes) > 5
    at = int(np.cumsum(sizes)[3]) + offset  # the fifth block's first row, and either side of it
    t[at:] += 0.3
    path = _write(tmp_path, _log_text(t))
    blocks = iter_log(path)
    for _ in blocks:
        pass
    assert blocks.warnings() == read_log(path).warnings
    assert f"before line {at + 2}: about 300 samples" in blocks.warnings()[0]


def test_repeated_stamp_in_a_file_with_quoted_cells_names_the_row(tmp_path: Path) -> None:
    path = _write(tmp_path, f'{HEADER},note\n0,1,2,3,4,5,6,"a\nb"\n0.001,1,2,3,4,5,6,x\n0.001,1,2,3,4,5,6,x\n')
    log = read_log(path)
    assert log.repeated_t == 1
    assert "(the first on data row 3: t = 0.001 s as on the row before)" in log.warnings[0]


def test_slow_parser_also_accepts_repeats(tmp_path: Path) -> None:
    # a text cell the fast path cannot take ("1_0" is a number to Python, not to pyarrow)
    path = _write(tmp_path, f"{HEADER}\n0,1_0,2,3,4,5,6\n0,1,2,3,4,5,6\n1,1,2,3,4,5,6\n")
    log = read_log(path)
    np.testing.assert_array_equal(log.wrench[:, 0], [10, 1, 1])
    assert log.repeated_t == 1 and "line 3" in log.warnings[0]


@pytest.mark.parametrize("rate", [10.0, 50.0, 1000.0, 7000.0, 20000.0])
def test_plausible_time_scale_gives_no_warning(tmp_path: Path, rate: float) -> None:
    t = 1.7e9 + np.arange(40) / rate  # epoch seconds are seconds
    assert read_log(_write(tmp_path, _log_text(t))).warnings == ()


@pytest.mark.parametrize(
    ("scale", "rate", "guess"),
    [
        (1e3, 1000.0, "if t is in milliseconds 1e+03 Hz"),
        (1e3, 50.0, "if t is in milliseconds 50 Hz"),
        (1e6, 1000.0, "in microseconds 1e+03 Hz"),
        (1e9, 7000.0, "in nanoseconds 7e+03 Hz"),
    ],
)
def test_time_in_ms_us_or_ns_is_reported(tmp_path: Path, scale: float, rate: float, guess: str) -> None:
    t = np.arange(40) / rate * scale
    path = _write(tmp_path, _log_text(t))
    (note,) = read_log(path).warnings
    assert note.startswith(f"{path}: column 't': median step ")
    assert "implausible for a force/torque log (expected 2 Hz to 100 kHz with t in seconds)" in note
    assert guess in note, note
    assert note.endswith("Give t in seconds: the tare duration and every time window are in seconds")


def test_epoch_stamps_in_t_are_read_in_the_unit_that_makes_them_a_date(tmp_path: Path) -> None:
    """Integer Unix-time ns in a plain ``t`` column: exact int64, t from the first, the stamps kept."""
    ns = 1_700_000_000_123_456_789 + np.arange(40) * 142_857
    rows = "".join(f"{v},1,2,3,4,5,6\n" for v in ns.tolist())
    log = read_log(_write(tmp_path, f"{HEADER}\n{rows}"))
    np.testing.assert_array_equal(log.t, (ns - ns[0]) / 1e9)
    assert log.extra["stamp_ns"].tolist() == ns.tolist()
    assert not log.warnings and "t read in ns, the only unit that makes its first stamp a date" in log.notes[0]


def test_log_cut_inside_its_last_number_is_reported(tmp_path: Path) -> None:
    text = _log_text(np.arange(30) * 1e-3)
    whole = _write(tmp_path, text.rstrip("\n"), "whole.csv")  # no final line break, nothing cut
    assert read_log(whole).warnings == ()
    last = text.rstrip("\n").rsplit("\n", 1)[1]
    cut_text = text.rstrip("\n")[: -(len(last.rsplit(",", 1)[1]) - 3)]  # the last number keeps 3 characters
    cut = _write(tmp_path, cut_text, "cut.csv")
    log = read_log(cut)
    assert len(log.t) == 30  # the row is kept ...
    (note,) = log.warnings  # ... and said
    assert note.startswith(f"{cut}:31: the file ends inside this line (no line break after it) and its last cell ")
    assert "the log was probably cut while being written" in note


def test_short_last_cell_of_a_counter_column_is_not_a_cut(tmp_path: Path) -> None:
    rows = "".join(f"{i * 1e-3!r},0.1234,0.1,0.1,0.1,0.1,0.1,{10 + i}\n" for i in range(20))
    path = _write(tmp_path, f"{HEADER},trial\n{rows}0.02,0.1234,0.1,0.1,0.1,0.1,0.1,9")  # no final line break
    assert read_log(path).warnings == ()


def test_log_cut_inside_its_last_row_is_an_error_that_says_so(tmp_path: Path) -> None:
    text = _log_text(np.arange(30) * 1e-3).rstrip("\n")
    path = _write(tmp_path, text[: text.rfind(",") - 2])
    assert _error(path) == (
        f"{path}:31: expected 7 cells (one per header column), got 6 "
        "(the file ends inside line 31, with no line break after it: was it cut while being written? "
        "Delete that line to use the rest, or give --missing drop)"
    )
    path = _write(tmp_path, text[: text.rfind(",") + 2] + "e")  # "0.e"-like: a number cut after its e
    assert _error(path).endswith(
        "(the file ends inside line 31, with no line break after it: was it cut while being written? "
        "Delete that line to use the rest, or give --missing drop)"
    )


@pytest.mark.parametrize("missing", ["drop", "interpolate"])
@pytest.mark.parametrize("cut", ["cells", "number", "delimiter"])
def test_log_cut_inside_its_last_row_is_dropped_with_missing_drop(tmp_path: Path, missing: str, cut: str) -> None:
    # the cut line's cells are missing: --missing drop (and interpolate, which has nothing after
    # it to fill from) reads the rows before it, the values of the file without that line, and says so
    text = _log_text(np.arange(30) * 1e-3).rstrip("\n")
    keep = text[: text.rfind("\n") + 1]
    end = {"cells": text.rfind(",") - 2, "number": text.rfind(",") + 2, "delimiter": text.rfind(",") + 1}[cut]
    cut_text = text[:end] + ("e" if cut == "number" else "")
    log = read_log(_write(tmp_path, cut_text, "cut.csv"), missing=missing)
    whole = read_log(_write(tmp_path, keep, "kept.csv"))
    np.testing.assert_array_equal(log.t, whole.t)
    np.testing.assert_array_equal(log.wrench, whole.wrench)
    assert len(log.t) == 29 and log.warnings == ()
    (note,) = [n for n in log.notes if ":31: " in n]
    assert note.startswith(f"{tmp_path / 'cut.csv'}:31: the file ends inside this line (no line break after it) and it cannot be read (")
    assert note.endswith(f"): dropped (--missing {missing})")
    assert not [n for n in log.notes if "empty or nan cells" in n]  # not counted as a missing sample


@pytest.mark.parametrize("last", ["more cells", "t back", "complete"])
def test_an_unterminated_last_row_that_is_whole_is_not_dropped(tmp_path: Path, last: str) -> None:
    # a cut only takes cells away: a last row with every cell (too many, or t going back) is an
    # error --missing does not hide, nor suggests; a complete one is read
    text = _log_text(np.arange(30) * 1e-3).rstrip("\n")
    if last == "more cells":
        text += ",1.0"
    elif last == "t back":
        text = text[: text.rfind("\n") + 1] + "0.0" + text[text.rfind("\n") + 1 :][len(repr(0.029)) :]
    path = _write(tmp_path, text)
    if last == "complete":
        assert len(read_log(path, missing="drop").t) == 30
        return
    error = _error(path, missing="drop")
    assert error == _error(path) and error.startswith(f"{path}:31: ") and "--missing" not in error


def test_a_cut_header_is_not_dropped(tmp_path: Path) -> None:
    # no line break at all: nothing to keep, the error stands whatever --missing says
    path = _write(tmp_path, HEADER[:-3])
    assert _error(path, missing="drop") == _error(path)
    # the only data line cut: nothing left, and the message says which line was dropped
    path = _write(tmp_path, f"{HEADER}\n0.0,1,2", "only.csv")
    assert _error(path, missing="drop") == (
        f"{path}:1: header only, no data rows; expected at least one row of t, fx, fy, fz, mx, my, mz after the header "
        "(line 2, inside which the file ends, was dropped: --missing drop)"
    )


# ----------------------------------------------------- the fast path accepts what the careful one does

_CELLS = st.one_of(
    st.floats(allow_nan=False, allow_infinity=False).map(repr),
    st.floats(-1e6, 1e6).map(lambda x: f"{x:.6g}"),
    st.sampled_from(
        ["1", "+1", "-0", ".5", "5.", "1e5", "1E-5", "1e", " 1", "1 ", "1_0", "0x10", "inf", "-nan", "NaN", "",
         "1,5", '"2.5"', "1e400", "1e-400", "١", "1d5", "--1", "0001.5", "+.5e+3", "nan", "NA", "null"]
    ),  # fmt: skip
)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.lists(_CELLS, min_size=7, max_size=7), min_size=1, max_size=6), st.booleans())
def test_fast_and_careful_parsers_agree(tmp_path_factory: pytest.TempPathFactory, rows: list[list[str]], increasing: bool) -> None:
    """pyarrow's reader never accepts what the row-by-row parser rejects, nor reads another value."""
    if increasing:
        for i, row in enumerate(rows):
            row[0] = str(i)
    path = _write(tmp_path_factory.mktemp("agree"), f"{HEADER},note\n" + "".join(",".join(r) + ",x\n" for r in rows))
    careful: Log | str
    try:
        text = Path(path).read_text()
        t, w, extra, _, _ = sio._parse(text, path)
        careful = Log(t=t, wrench=w, extra=extra, source=path, units="si")
    except InputError as exc:
        careful = str(exc)
    try:
        fast: Log | str = read_log(path)
    except InputError as exc:
        fast = str(exc)
    if isinstance(careful, str):
        assert fast == careful
    elif isinstance(fast, str) and "expected stamps that increase" in fast:  # read_log's check of the whole log
        assert len(careful.t) > 1 and (careful.t == careful.t[0]).all(), fast
    elif isinstance(fast, str) and "beyond the year 2261" in fast:  # read_log's check of the time unit
        assert careful.t[0] >= sio.LATEST_STAMP_S, fast
    else:
        assert isinstance(fast, Log), fast
        absolute = sio.ABSOLUTE_STAMP_S <= careful.t[0] < sio.LATEST_STAMP_S  # counted from the first, stamps kept
        np.testing.assert_array_equal(fast.t, careful.t - careful.t[0] if absolute else careful.t)
        np.testing.assert_array_equal(fast.wrench, careful.wrench)
        assert {k: v for k, v in fast.extra.items() if k != "stamp_ns"} == careful.extra


_GOOD = _log_text(np.arange(12) * 1e-3, ',"a, ""b"""')


@settings(max_examples=80, deadline=None)
@given(
    st.lists(
        st.tuples(
            st.sampled_from(["delete", "insert", "replace", "cut", "dup-line"]),
            st.integers(0, len(_GOOD) - 1),
            st.sampled_from(list(',"\n\r -.e9x\x00\ufeff#') + ["nan", "\u00e9"]),
        ),
        min_size=1,
        max_size=4,
    )
)
def test_mutated_logs_read_cleanly_or_fail_cleanly(tmp_path_factory: pytest.TempPathFactory, edits: list) -> None:
    """Random damage to a good log: an InputError or a valid Log, identical to the careful parser's."""
    text = _GOOD
    for kind, at, piece in edits:
        at = min(at, len(text))
        if kind == "delete":
            text = text[:at] + text[at + 1 :]
        elif kind == "insert":
            text = text[:at] + piece + text[at:]
        elif kind == "replace":
            text = text[:at] + piece + text[at + 1 :]
        elif kind == "cut":
            text = text[: max(at, 1)]
        else:
            start = text.rfind("\n", 0, at) + 1
            end = text.find("\n", at)
            end = len(text) if end < 0 else end + 1
            text = text[:end] + text[start:end] + text[end:]
    path = _write(tmp_path_factory.mktemp("mut"), text)
    try:
        log = read_log(path)
    except InputError as exc:
        message = str(exc)
        assert message.startswith(path + ":"), message
        return
    assert np.isfinite(log.t).all() and np.isfinite(log.wrench).all() and (np.diff(log.t) >= 0).all()
    t, w, extra, _, _ = sio._parse(_decode_for_test(path), path)
    np.testing.assert_array_equal(log.t, t)
    np.testing.assert_array_equal(log.wrench, w)
    assert log.extra == extra
    assert log.repeated_t == int(np.count_nonzero(np.diff(t) == 0))


def _decode_for_test(path: str) -> str:
    return sio._decode(Path(path).read_bytes(), path)


@pytest.mark.parametrize("name", ["t.csv", "t.parquet"])
def test_rows_go_to_a_binary_file_too(tmp_path: Path, name: str) -> None:
    """What an atomic writer hands over may be a binary file: same bytes as a text one."""
    cols = {"t": np.arange(3.0) / 7, "state": np.array(["none", "line", "point"]), "ok": np.array([1, 0, 1]) > 0}
    plan = sio._plan_table(cols, "%.10g")
    plan.parquet = name.endswith(".parquet")
    with open(tmp_path / ("b" + name), "wb") as fh:
        sio._write_rows(fh, plan)
    write_table(cols, tmp_path / name)
    if plan.parquet:
        import pyarrow.parquet as pq

        assert pq.read_table(tmp_path / ("b" + name)).equals(pq.read_table(tmp_path / name))
    else:
        assert (tmp_path / ("b" + name)).read_bytes() == (tmp_path / name).read_bytes()


def test_read_reports_progress_in_bytes(tmp_path: Path) -> None:
    text = _log_text(np.arange(300) * 1e-3)
    path = _write(tmp_path, text)
    steps: list[int] = []
    log = read_log(path, progress=steps.append)
    assert len(log.t) == 300
    # every byte between the header line and the last line break
    assert sum(steps) == len(text.encode()) - len(HEADER) - 2


def test_csv_blocks_formatted_on_threads_are_written_in_order(tmp_path, monkeypatch):
    import softtip.io.tables as tables

    n = 3 * tables._CHUNK_ROWS + 17
    rng = np.random.default_rng(4)
    cols = {"t": np.arange(n) * 1e-3, "x": rng.normal(size=n), "flag": rng.random(n) > 0.5}
    seen = []
    tables.write_table(cols, tmp_path / "threads.csv", progress=seen.append)
    monkeypatch.setattr(tables, "_WRITE_THREADS", 1)
    tables.write_table(cols, tmp_path / "one.csv")
    assert (tmp_path / "threads.csv").read_bytes() == (tmp_path / "one.csv").read_bytes()
    assert sum(seen) == n and len(seen) == 4


def test_stamps_whose_nanoseconds_overflow_int64_stop(tmp_path) -> None:
    """Whole seconds from 2262 on would overflow ``stamp_ns`` (int64 ns): a stamp that late is no
    clock's, and the run stops; one just before it is an absolute stamp, kept exactly."""
    late = _write(tmp_path, HEADER + "\n" + "".join(f"{9_223_372_037 + i},0,0,0,0,0,0\n" for i in range(3)))
    with pytest.raises(InputError, match=r"puts the first stamp 9\.22e\+09 s after 1970, beyond the year 2261"):
        read_log(late)
    early = _write(tmp_path, HEADER + "\n" + "".join(f"{9_100_000_000 + i},0,0,0,0,0,0\n" for i in range(3)))
    log = read_log(early)
    assert log.t.tolist() == [0.0, 1.0, 2.0] and log.stamps_ns.tolist() == [9_100_000_000_000_000_000 + i * 10**9 for i in range(3)]
