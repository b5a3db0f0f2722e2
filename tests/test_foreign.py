"""Logs as other software writes them (issue 28): tests/data/foreign/, one file per source.

Each file holds the example grasp (``make_corpus.py`` there writes them). Each is either read
to the SI reference's numbers, or refused with exit 2 and a message naming the option that
fixes it; following that option then gives the reference's estimates. No wrong-unit run
exits 0, in either direction of each likely confusion.
"""

from __future__ import annotations

import csv
import io
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from softtip.errors import InputError
from softtip.io.tables import read_log

SOFTTIP = str(Path(sys.executable).with_name("softtip"))
DATA = Path(__file__).parent / "data" / "foreign"
REFERENCE = DATA / "si_reference.csv"

#: file, read_log keywords → a note that says how it was read (None: no note expected)
READ_RIGHT = [
    ("si_reference.csv", {}, None),
    ("ati_ms_n_nmm.csv", {}, "t ← 'Time (ms)' (ms), fx ← 'Fx (N)' (N)"),
    ("ati_lbf_lbfin.csv", {}, "mx ← 'Tx (lbf-in)' (lbf·in)"),
    ("n_nmm_plain_header.csv", {"moment_units": "N*mm"}, "mx ← 'mx' (N·mm, not in the header)"),
    ("n_nmm_plain_header.csv", {"moment_units": "N-mm"}, "mx ← 'mx' (N·mm, not in the header)"),
    ("kgf_kgfmm_plain_header.csv", {"units": "kgf-mm"}, "fx ← 'fx' (kgf, not in the header)"),
    ("rostopic_echo_p.csv", {}, "t ← 'field.header.stamp' (ns"),
    ("ros2_topic_echo.csv", {}, "ros2 topic echo --csv (no header row)"),
    ("plotjuggler.csv", {}, "t ← '__time' (s"),
    ("tab_separated.tsv", {}, None),
    ("semicolon_decimal_comma.csv", {}, None),
    ("si_reference.csv.gz", {}, None),
    ("si_reference.csv.bz2", {}, None),
    ("si_reference.csv.xz", {}, None),
    ("si_reference.csv.zst", {}, None),
    ("t_in_ms.csv", {"time_units": "ms"}, "t ← 't' (ms, not in the header)"),
    ("t_in_us.csv", {"time_units": "us"}, "t ← 't' (µs, not in the header)"),
    ("t_absolute_ns.csv", {}, "t read in ns, the only unit that makes its first stamp a date"),
    ("upper_case_preamble.csv", {}, "the header is on line 4; the 3 line(s) before it skipped (--skip-rows 3"),
    ("upper_case_preamble.csv", {"skip_rows": 3}, "t ← 'T' (s, not in the header)"),
]


@pytest.mark.parametrize(("name", "kwargs", "note"), READ_RIGHT, ids=[f"{n}-{'-'.join(k)}" for n, k, _ in READ_RIGHT])
def test_read_to_the_reference(name: str, kwargs: dict, note: str | None) -> None:
    ref = read_log(REFERENCE)
    log = read_log(DATA / name, **kwargs)
    np.testing.assert_array_equal(log.t, ref.t)  # to the last bit: stamps and units converted exactly
    np.testing.assert_allclose(log.wrench, ref.wrench, rtol=1e-8, atol=1e-12)
    if note is None:
        assert not [n for n in log.notes if "read as" in n]
    else:
        assert any(note in n for n in log.notes), log.notes
    assert not log.warnings


@pytest.mark.parametrize("quoted", [False, True], ids=["arrow-parser", "python-parser"])
@pytest.mark.parametrize("dialect", [",.", ";,", "\t,"], ids=["comma", "semicolon-decimal-comma", "tab-decimal-comma"])
def test_absolute_decimal_seconds_are_exact_with_a_decimal_comma_too(tmp_path: Path, dialect: str, quoted: bool) -> None:
    # Unix seconds with decimals are read as ns exactly; with a decimal comma they were read as
    # floats (t 0.01999998093 for 0.02, estimates off by 1e-7 degrees)
    delimiter, decimal = dialect
    ref = read_log(REFERENCE)
    lines = REFERENCE.read_text().splitlines()
    rows = []
    for ln in lines[1:]:
        t, rest = ln.split(",", 1)
        cs = round(float(t) * 100)  # t on a grid of 0.01 s (50 Hz): the stamp's text exactly
        cells = [f"17000000{cs // 100:02d}.{cs % 100:02d}", *rest.split(",")]
        rows.append(delimiter.join(c.replace(".", decimal) for c in cells) + (f'{delimiter}"a note"' if quoted else ""))
    if quoted:  # a note spanning two lines: only the Python parser reads the log
        rows[3] = rows[3][: -len('"a note"')] + '"a\nnote"'
    header = delimiter.join(["t", "fx", "fy", "fz", "mx", "my", "mz"] + (["note"] if quoted else []))
    path = tmp_path / "dated.csv"
    path.write_text("\n".join([header, *rows]) + "\n")
    log = read_log(path)
    assert int(log.extra["stamp_ns"][0]) == 1_700_000_000 * 10**9
    np.testing.assert_array_equal(log.t, ref.t)  # to the last bit
    np.testing.assert_array_equal(log.wrench, ref.wrench)


@pytest.mark.parametrize("name", ["rostopic_echo_p.csv", "ros2_topic_echo.csv", "t_absolute_ns.csv"])
def test_absolute_ns_stamps_are_exact_and_kept(name: str) -> None:
    log = read_log(DATA / name)
    stamps = np.array([int(s) for s in log.extra["stamp_ns"]])
    assert stamps[0] == 1_700_000_000_123_456_789
    np.testing.assert_array_equal(log.t, (stamps - stamps[0]) / 1e9)  # correctly rounded, as the text "0.06"
    np.testing.assert_array_equal(log.t, read_log(REFERENCE).t)


#: file, read_log keywords → the located message's part that names the fix
REFUSED = [
    ("missing_cells.csv", {}, ":122: column 'fy': empty cell; expected a number; or give --missing drop"),
    ("stray_quote.csv", {}, ":102: column 'note': a quote opened on this line is closed only on line 202, so the 100"),
    ("unterminated_quote.csv", {}, ":102: column 'note': a quote opened on this line is never closed"),
    ("ati_ms_n_nmm.csv", {"moment_units": "N*m"},
     "column 'Tx (N-mm)': the header says N·mm but --moment-units (or --units) says N*m; leave the option out"),
    ("ati_ms_n_nmm.csv", {"time_units": "s"},  # --units says nothing of time
     "column 'Time (ms)': the header says ms but --time-units says s; leave the option out"),
    ("si_reference.csv", {"columns": "t=time"}, "--columns t=time: no column 'time' in the header"),
    ("si_reference.csv", {"units": "kgf-mm", "force_units": "N"}, "--units kgf-mm says force in kgf, --force-units says N"),
]


@pytest.mark.parametrize(("name", "kwargs", "message"), REFUSED)
def test_refused_naming_the_fix(name: str, kwargs: dict, message: str) -> None:
    with pytest.raises(InputError) as info:
        read_log(DATA / name, **kwargs)
    assert message in str(info.value)
    assert str(info.value).startswith(str(DATA / name))


def test_missing_cells_dropped_or_interpolated() -> None:
    ref = read_log(REFERENCE)
    dropped = read_log(DATA / "missing_cells.csv", missing="drop")
    assert len(dropped.t) == len(ref.t) - 2
    keep = np.ones(len(ref.t), dtype=bool)
    keep[[120, 300]] = False
    np.testing.assert_array_equal(dropped.t, ref.t[keep])  # the time-based stages see the gap
    (note,) = dropped.notes
    assert "empty or nan cells in 2 row(s), the first on line 122: 2 row(s) dropped" in note and "--missing drop" in note
    filled = read_log(DATA / "missing_cells.csv", missing="interpolate")
    np.testing.assert_array_equal(filled.t, ref.t)
    expected = (ref.wrench[119, 1] + ref.wrench[121, 1]) / 2
    assert filled.wrench[120, 1] == pytest.approx(expected)
    assert "2 row(s) filled by linear interpolation in t" in filled.notes[0]


def test_missing_cells_at_the_ends_take_the_nearest_value_and_say_so(tmp_path: Path) -> None:
    # nothing before the first row or after the last to interpolate from: the note said
    # "linear interpolation" for a copied value; Microsoft's NaN spelling is a missing value
    lines = REFERENCE.read_text().splitlines()
    n = len(lines) - 1
    first, last = lines[1].split(","), lines[-1].split(",")
    first[2], last[6] = "", "-nan(ind)"
    path = tmp_path / "ends.csv"
    path.write_text("\n".join([lines[0], ",".join(first), *lines[2:-1], ",".join(last)]) + "\n")
    with pytest.raises(InputError, match=r"column 'fy': empty cell; expected a number; or give --missing drop"):
        read_log(path)
    ref = read_log(REFERENCE)
    log = read_log(path, missing="interpolate")
    assert log.wrench[0, 1] == ref.wrench[1, 1] and log.wrench[-1, 5] == ref.wrench[-2, 5]
    assert ("2 row(s) at the log's start or end filled with the nearest value (no value beyond to interpolate from)"
            in log.notes[0]) and "linear" not in log.notes[0]  # fmt: skip
    assert len(read_log(path, missing="drop").t) == n - 2


def test_a_spreadsheets_empty_columns_are_left_out_and_one_with_values_is_refused(tmp_path: Path) -> None:
    # a spreadsheet saved as CSV ends every line with delimiters: two empty columns were "duplicate
    # column ''", one was carried into the output as a column named ''
    lines = REFERENCE.read_text().splitlines()
    path = tmp_path / "sheet.csv"
    path.write_text("\n".join(ln + ",," for ln in lines) + "\n")
    log, ref = read_log(path), read_log(REFERENCE)
    np.testing.assert_array_equal(log.t, ref.t)
    np.testing.assert_array_equal(log.wrench, ref.wrench)
    assert log.extra == {} and "2 empty column(s) without a name in the header (a spreadsheet's: 8, 9) left out" in log.notes[0]
    lines[5] += ",,"
    lines[6] += ",note,"
    held = tmp_path / "held.csv"
    held.write_text("\n".join([lines[0] + ",,", *(ln if ln.endswith(",") else ln + ",," for ln in lines[1:])]) + "\n")
    with pytest.raises(InputError, match=r"held\.csv:1: column 8 has no name in the header but holds values \(the first "
                                         r"on line 7: 'note'\); expected a name for each column that holds values"):  # fmt: skip
        read_log(held)


def test_columns_option_and_headerless_positions(tmp_path: Path) -> None:
    text = REFERENCE.read_text().replace("t,fx,fy,fz,mx,my,mz", "zeit,a,b,c,d,e,f", 1)
    odd = tmp_path / "odd.csv"
    odd.write_text(text)
    log = read_log(odd, columns="t=zeit,fx=a,fy=b,fz=c,mx=d,my=e,mz=f")
    np.testing.assert_array_equal(log.wrench, read_log(REFERENCE).wrench)
    assert "t ← 'zeit' (s, not in the header)" in log.notes[0]
    bare = tmp_path / "bare.csv"
    bare.write_text(REFERENCE.read_text().split("\n", 1)[1])
    with pytest.raises(InputError, match=r"looks like data.*--columns t=1,fx=2"):
        read_log(bare)
    np.testing.assert_array_equal(read_log(bare, columns="t=1,fx=2,fy=3,fz=4,mx=5,my=6,mz=7").t, read_log(REFERENCE).t)
    # a first row of zeros repeats its "names": still named data, not a header with a duplicate
    zeros = tmp_path / "zeros.csv"
    zeros.write_text("0.0,0.0,0.0,0.0,0.0,0.0,0.0\n" + REFERENCE.read_text().split("\n", 1)[1])
    with pytest.raises(InputError, match=r"zeros.csv:1: duplicate column '0.0'.*Line 1 looks like data.*--columns t=1,fx=2"):
        read_log(zeros)


def test_two_topics_in_one_plotjuggler_file_name_the_option(tmp_path: Path) -> None:
    lines = (DATA / "plotjuggler.csv").read_text().splitlines()
    header = lines[0] + "," + ",".join(c.replace("/ft/", "/ft2/") for c in lines[0].split(",")[1:])
    body = [ln + "," + ",".join(ln.split(",")[1:]) for ln in lines[1:]]
    path = tmp_path / "two.csv"
    path.write_text("\n".join([header, *body]) + "\n")
    with pytest.raises(InputError, match=r"columns '/ft/wrench/force/x', '/ft2/wrench/force/x' could each be 'fx'.*--columns fx="):
        read_log(path)
    log = read_log(path, columns="t=__time,fx=/ft2/wrench/force/x,fy=/ft2/wrench/force/y,fz=/ft2/wrench/force/z,"
                   "mx=/ft2/wrench/torque/x,my=/ft2/wrench/torque/y,mz=/ft2/wrench/torque/z")  # fmt: skip
    np.testing.assert_array_equal(log.wrench, read_log(DATA / "plotjuggler.csv").wrench)


# --------------------------------------------------------------------------------------
# through the installed command


def run(*args: object) -> subprocess.CompletedProcess:
    return subprocess.run([SOFTTIP, *map(str, args)], capture_output=True, text=True, timeout=180)


def _table(path: Path) -> dict[str, list[str]]:
    rows = list(csv.reader(io.StringIO(path.read_text())))
    return {name: [r[j] for r in rows[1:]] for j, name in enumerate(rows[0])}


@pytest.fixture(scope="module")
def reference_estimate(tmp_path_factory: pytest.TempPathFactory) -> dict[str, list[str]]:
    out = tmp_path_factory.mktemp("ref") / "ref.csv"
    done = run("estimate", REFERENCE, "-o", out)
    assert done.returncode == 0, done.stderr
    return _table(out)


def _same_estimates(got: dict[str, list[str]], ref: dict[str, list[str]]) -> None:
    """The reference's states and contact points; the angle within 1° (a last-bit difference in t or in a unit
    conversion still moves the angle where h is at the noise: issue 28 item 5, not done here)."""
    assert got["state"] == ref["state"]
    for name in ("fz", "rx", "rz"):
        np.testing.assert_allclose(np.array(got[name], float), np.array(ref[name], float), rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(np.array(got["angle_deg"], float), np.array(ref["angle_deg"], float), atol=1.0)


CLI_READ = [
    ("ati_ms_n_nmm.csv", []),
    ("ati_lbf_lbfin.csv", []),
    ("rostopic_echo_p.csv", []),
    ("ros2_topic_echo.csv", []),
    ("plotjuggler.csv", []),
    ("semicolon_decimal_comma.csv", []),
    ("si_reference.csv.gz", []),
    ("t_absolute_ns.csv", []),
    ("upper_case_preamble.csv", []),
]


@pytest.mark.parametrize(("name", "args"), CLI_READ)
def test_cli_reads_to_the_reference_estimates(tmp_path: Path, reference_estimate, name: str, args: list[str]) -> None:
    out = tmp_path / "e.csv"
    done = run("estimate", DATA / name, *args, "-o", out)
    assert done.returncode == 0, done.stderr
    _same_estimates(_table(out), reference_estimate)
    assert "Traceback" not in done.stderr


#: file, wrong options → what the message must name; then the options that fix it
CONFUSIONS = [
    # N with N·mm (ATI's export) read as SI, and the old wrong hint followed
    ("n_nmm_plain_header.csv", [], "forces in N with moments in N·mm (--moment-units N*mm)", ["--moment-units", "N*mm"]),
    ("n_nmm_plain_header.csv", ["--units", "kgf-mm"], "(--force-units N --moment-units N*mm)", ["--moment-units", "Nmm"]),
    # the papers' kgf and kgf·mm read as SI, or as N·mm
    ("kgf_kgfmm_plain_header.csv", [], "forces in kgf with moments in kgf·mm (--units kgf-mm)", ["--units", "kgf-mm"]),
    ("kgf_kgfmm_plain_header.csv", ["--moment-units", "N*mm"], "(--units kgf-mm)", ["--units", "kgf-mm"]),
    # SI read as kgf-mm, as N·mm, as lbf/lbf·in
    ("si_reference.csv", ["--units", "kgf-mm"], "forces in N with moments in N·m (the default", []),
    ("si_reference.csv", ["--moment-units", "N*mm"], "forces in N with moments in N·m (the default", []),
    ("si_reference.csv", ["--force-units", "lbf", "--moment-units", "lbf-in"], "N·m (the default", []),
    # lbf with lbf·in read as SI (a header without units)
    ("lbf_plain_header.csv", [], "forces in lbf with moments in lbf·in (--force-units lbf --moment-units lbf*in)",
     ["--force-units", "lbf", "--moment-units", "lbf*in"]),
]


@pytest.mark.parametrize(("name", "wrong", "named", "fix"), CONFUSIONS)
def test_wrong_units_stop_naming_the_pair_that_fits(
    tmp_path: Path, reference_estimate, name: str, wrong: list[str], named: str, fix: list[str]
) -> None:
    src = DATA / name
    if name == "lbf_plain_header.csv":  # ATI's lbf file without the units in its header
        src = tmp_path / name
        lines = (DATA / "ati_lbf_lbfin.csv").read_text().split("\n", 1)
        src.write_text("t,fx,fy,fz,mx,my,mz\n" + lines[1])
    out = tmp_path / "e.csv"
    done = run("estimate", src, *wrong, "-o", out)
    assert done.returncode == 2, done.stderr
    assert named in done.stderr, done.stderr
    assert not out.exists() and "Traceback" not in done.stderr
    done = run("estimate", src, *fix, "-o", out)
    assert done.returncode == 0, done.stderr
    _same_estimates(_table(out), reference_estimate)


def test_cli_missing_and_quotes_stop_with_the_line(tmp_path: Path) -> None:
    out = tmp_path / "e.csv"
    done = run("estimate", DATA / "missing_cells.csv", "-o", out)
    assert done.returncode == 2 and "missing_cells.csv:122: column 'fy': empty cell" in done.stderr
    assert "--missing drop" in done.stderr and not out.exists()
    done = run("estimate", DATA / "missing_cells.csv", "--missing", "drop", "-o", out)
    assert done.returncode == 0, done.stderr
    assert "2 row(s) dropped (t keeps the gap) (--missing drop)" in done.stderr
    assert len(_table(out)["t"]) == 498
    for name in ("stray_quote.csv", "unterminated_quote.csv"):
        out.unlink(missing_ok=True)
        for chunk in ([], ["--chunk-rows", "50"]):
            done = run("estimate", DATA / name, *chunk, "-o", out)
            assert done.returncode == 2, (name, chunk, done.stderr)
            assert f"{name}:102: column 'note': a quote opened on this line" in done.stderr and not out.exists()


def _inf_cell_log(tmp_path: Path) -> Path:
    """The reference with ``inf`` in fy on line 102 (issue 32's abort)."""
    lines = REFERENCE.read_text().splitlines()
    cells = lines[101].split(",")
    cells[2] = "inf"
    lines[101] = ",".join(cells)
    src = tmp_path / "in.csv"
    src.write_text("\n".join(lines) + "\n")
    return src


@pytest.mark.parametrize("chunk", [[], ["--chunk-rows", "50"]])
def test_inf_cell_exits_2_every_time(tmp_path: Path, chunk: list[str]) -> None:
    """issue 32: the message, then no SIGABRT from a pyarrow thread still running at exit (repeated: it was intermittent)."""
    src = _inf_cell_log(tmp_path)
    for _ in range(6):
        done = run("estimate", src, *chunk, "-o", tmp_path / "out.csv")
        assert done.returncode == 2, done.stderr
        assert f"{src}:102: column 'fy': expected a finite number, got 'inf'" in done.stderr
        assert "terminate called" not in done.stderr and not (tmp_path / "out.csv").exists()


def test_csv_reader_threads_get_no_python_owned_memory(monkeypatch) -> None:
    """issue 32: the abort's cause, seen in a core dump: a pyarrow reader thread dropped the last
    reference to a block of a Python object's memory (``pa.py_buffer``) while the interpreter
    finalised; releasing it took the GIL, which ended the thread inside a C++ destructor
    (std::terminate). The one-shot reader now hands pyarrow memory pyarrow allocated."""
    import pyarrow as pa

    from softtip.io.tables import read_log

    given = []
    real = pa.BufferReader

    def spy(obj):
        given.append(obj)
        return real(obj)

    monkeypatch.setattr(pa, "BufferReader", spy)
    log = read_log(REFERENCE)
    assert len(log.t) == 500 and given
    for obj in given:  # an allocated buffer is mutable; a wrapped bytes object or view is not
        assert isinstance(obj, pa.Buffer) and obj.is_mutable, obj


@pytest.mark.slow
def test_inf_cell_exits_2_under_normal_finalisation(tmp_path: Path) -> None:
    """issue 32: the abort happened in the interpreter's finalisation (3 of 143 runs of
    ``python -m softtip.cli`` under load before the fix, 0 of 200 after); the console command skips
    it after a failure, so this runs the module, which does not."""
    src = _inf_cell_log(tmp_path)
    for _ in range(20):
        done = subprocess.run([sys.executable, "-m", "softtip.cli", "estimate", str(src), "-o", str(tmp_path / "o.csv")],
                              capture_output=True, text=True, timeout=180)  # fmt: skip
        assert done.returncode == 2, done.stderr
        assert "terminate called" not in done.stderr


# --------------------------------------------------------------------------------------
# any mix of dialect, units, delimiter, decimal mark and compression reads back the same


from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from softtip.core.units import UNITS, find_unit  # noqa: E402

_HEADERS = {
    "softtip": ("t", "fx", "fy", "fz", "mx", "my", "mz"),
    "ATI": ("Time", "Fx", "Fy", "Fz", "Tx", "Ty", "Tz"),
    "upper": ("T", "FX", "FY", "FZ", "MX", "MY", "MZ"),
    "PlotJuggler": ("__time", *(f"/ft/wrench/{q}/{a}" for q in ("force", "torque") for a in "xyz")),
    "bagpy": ("Time", *(f"wrench.{q}.{a}" for q in ("force", "torque") for a in "xyz")),
}


@settings(max_examples=60, deadline=None)
@given(
    n=st.integers(1, 30),
    seed=st.integers(0, 2**32 - 1),
    style=st.sampled_from(sorted(_HEADERS)),
    delimiter=st.sampled_from([",", "\t", ";"]),
    comma=st.booleans(),
    force=st.sampled_from([u.name for u in UNITS if u.quantity == "force"]),
    moment=st.sampled_from([u.name for u in UNITS if u.quantity == "moment"]),
    in_header=st.booleans(),
    compression=st.sampled_from(["", "gzip", "bz2", "xz", "zstd"]),
    preamble=st.integers(0, 3),
)
def test_any_dialect_reads_back(tmp_path_factory, n, seed, style, delimiter, comma, force, moment, in_header, compression, preamble):
    import bz2
    import gzip
    import lzma

    import pyarrow as pa

    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(1e-3, 2e-2, n))
    w = rng.normal(size=(n, 6)) * [1, 1, 5, 1e-2, 1e-2, 1e-3]
    fu, mu = find_unit(force, "force"), find_unit(moment, "moment")
    in_units = w / np.array([fu.si] * 3 + [mu.si] * 3)
    names = list(_HEADERS[style])
    if in_header:
        names = [names[0]] + [f"{c} ({fu.label})" for c in names[1:4]] + [f"{c} [{mu.name.replace('*', '-')}]" for c in names[4:]]
    decimal_comma = comma and delimiter != ","
    lines = ["# exported by something", "Serial: FT0001", "Rate: 1 kHz"][:preamble]
    lines.append(delimiter.join(names))
    for ti, row in zip(t, in_units):
        cells = [repr(float(ti)), *(repr(float(v)) for v in row)]
        lines.append(delimiter.join(c.replace(".", ",") if decimal_comma else c for c in cells))
    data = ("\n".join(lines) + "\n").encode()
    data = {"": lambda d: d, "gzip": gzip.compress, "bz2": bz2.compress, "xz": lzma.compress,
            "zstd": lambda d: pa.compress(d, codec="zstd", asbytes=True)}[compression](data)  # fmt: skip
    path = tmp_path_factory.mktemp("dialect") / "log.csv"
    path.write_bytes(data)
    kwargs = {} if in_header else {"force_units": force, "moment_units": moment}
    log = read_log(path, **kwargs)
    np.testing.assert_array_equal(log.t, t)
    np.testing.assert_allclose(log.wrench, w, rtol=1e-12, atol=0)


def test_the_input_doc_lists_every_registered_source_and_unit() -> None:
    """docs/guide/input-formats.md (the README's Input section) names what the registries hold."""
    from softtip.io.formats import ROS2_CSV, SOURCES

    doc = (Path(__file__).parents[1] / "docs" / "guide" / "input-formats.md").read_text()
    for source in (*SOURCES, ROS2_CSV):
        assert source.name in doc, source.name
    for unit in UNITS:
        assert f"`{unit.name}`" in doc, unit.name


def test_cli_columns_skip_rows_and_headerless(tmp_path: Path, reference_estimate) -> None:
    lines = REFERENCE.read_text().splitlines()
    odd = tmp_path / "odd.csv"
    odd.write_text("\n".join(["exported 2026-11-27", "zeit;a;b;c;d;e;f", *(ln.replace(",", ";") for ln in lines[1:])]) + "\n")
    out = tmp_path / "e.csv"
    done = run("estimate", odd, "--skip-rows", "1", "--columns", "t=zeit,fx=a,fy=b,fz=c,mx=d,my=e,mz=f", "-o", out)
    assert done.returncode == 0, done.stderr
    assert "read as --columns: t ← 'zeit' (s, not in the header)" in done.stderr
    _same_estimates(_table(out), reference_estimate)
    bare = tmp_path / "bare.csv"
    bare.write_text("\n".join(lines[1:]) + "\n")
    done = run("estimate", bare, "-o", out)
    assert done.returncode == 2 and "--columns t=1,fx=2,fy=3,fz=4,mx=5,my=6,mz=7" in done.stderr
    done = run("estimate", odd, "--columns", "t=nope", "-o", out)
    assert done.returncode == 2 and "--columns t=nope: no column 'nope' in the header" in done.stderr
    done = run("estimate", bare, "--moment-units", "furlong", "-o", out)
    assert done.returncode == 2 and "expected a moment unit: N*m, N*mm, kN*m, kgf*mm, kgf*cm, lbf*in, lbf*ft" in done.stderr


def test_piecewise_runs_refuse_and_count_stamps_as_the_one_shot_run(tmp_path: Path) -> None:
    """--chunk-rows: wrong units stop by the noise too, ms stamps stop, absolute stamps count from the first."""
    out = tmp_path / "p.csv"
    done = run("estimate", REFERENCE, "--units", "kgf-mm", "--chunk-rows", "50", "-o", out)
    assert done.returncode == 2 and "forces in N with moments in N·m (the default" in done.stderr and not out.exists()
    done = run("estimate", DATA / "t_in_ms.csv", "--chunk-rows", "50", "-o", out)
    assert done.returncode == 2 and "(--time-units ms)" in done.stderr and not out.exists()
    done = run("estimate", DATA / "t_absolute_ns.csv", "--chunk-rows", "50", "-o", out)
    assert done.returncode == 0, done.stderr
    one_shot = tmp_path / "o.csv"
    assert run("estimate", DATA / "t_absolute_ns.csv", "-o", one_shot).returncode == 0
    assert out.read_bytes() == one_shot.read_bytes()


def test_csv_options_on_a_parquet_log_read_it_as_a_csv_log(tmp_path: Path) -> None:
    from softtip.io.tables import write_table

    ref = read_log(REFERENCE)
    path = tmp_path / "log.parquet"
    write_table({"t": ref.t, **{c: ref.wrench[:, i] for i, c in enumerate(("fx", "fy", "fz", "mx", "my", "mz"))}}, path)
    np.testing.assert_allclose(read_log(path, moment_units="N*mm").wrench[:, 3:], ref.wrench[:, 3:] * 1e-3, rtol=1e-15)
    np.testing.assert_array_equal(read_log(path, missing="drop").wrench, ref.wrench)
    assert len(read_log(path).t) == len(ref.t)


_SMALL = {name: "\n".join((DATA / name).read_text().splitlines()[:14]) + "\n" for name in (
    "ati_ms_n_nmm.csv", "ros2_topic_echo.csv", "plotjuggler.csv", "semicolon_decimal_comma.csv", "rostopic_echo_p.csv",
    "upper_case_preamble.csv",
)}  # fmt: skip


@settings(max_examples=150, deadline=None)
@given(
    name=st.sampled_from(sorted(_SMALL)),
    edits=st.lists(
        st.tuples(st.sampled_from(["delete", "insert", "replace"]), st.integers(0, 10_000),
                  st.sampled_from(list(',;\t"\n\r -.e9x#') + ["nan", "", "(N)", "1e400"])),  # fmt: skip
        min_size=1, max_size=4,
    ),
    missing=st.sampled_from(["fail", "drop", "interpolate"]),
)
def test_damaged_foreign_logs_read_or_fail_cleanly(tmp_path_factory, name: str, edits: list, missing: str) -> None:
    """Whatever the damage: a Log with finite values and t non-decreasing, or an InputError naming the file."""
    text = _SMALL[name]
    for op, pos, s in edits:
        pos %= len(text) + 1
        if op == "delete":
            text = text[:pos] + text[pos + 1 :]
        elif op == "insert":
            text = text[:pos] + s + text[pos:]
        else:
            text = text[:pos] + s + text[pos + len(s) :]
    path = tmp_path_factory.mktemp("damaged") / name
    path.write_text(text)
    try:
        log = read_log(path, missing=missing)
    except InputError as exc:
        assert str(exc).startswith(str(path)), exc
        return
    assert len(log.t) >= 1 and np.isfinite(log.t).all() and np.isfinite(log.wrench).all()
    assert (np.diff(log.t) >= 0).all()
    assert all(len(v) == len(log.t) for v in log.extra.values())


@pytest.mark.parametrize("row", [2, 250, -1])
def test_a_later_stamp_beyond_any_clock_is_located(tmp_path: Path, row: int) -> None:
    """A dated log whose stamps gain a digit from a row on (the last row, or a jump of the clock:
    still increasing, dates after 2261, their nanoseconds beyond int64): a located error, never a
    wrapped stamp or a numpy warning."""
    lines = (DATA / "plotjuggler.csv").read_text().splitlines()
    row = row % len(lines)
    lines[row:] = ["9" + line for line in lines[row:]]
    path = tmp_path / "damaged.csv"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError, match=rf"^{path}:{row + 1}: column '__time': the stamp .* beyond the year 2261"):
        read_log(path)


@pytest.mark.parametrize("row", [0, 250, 499])
@pytest.mark.parametrize(("part", "cell"), [
    ("sec", "1700000000e12"), ("sec", "1700000000.5"), ("sec", "-1700000000"),
    ("nanosec", "183456789e12"), ("nanosec", "183456789.5"), ("nanosec", "1183456789"), ("nanosec", "-1"),
])  # fmt: skip
@pytest.mark.parametrize("missing", ["fail", "drop"])
def test_a_split_stamp_part_out_of_range_is_located(tmp_path: Path, row: int, part: str, cell: str, missing: str) -> None:
    """A ROS stamp's seconds or nanoseconds that are not whole, negative, beyond int64 nanoseconds or
    (nanoseconds) a second or more: a located error on any row, never a wrapped or truncated stamp."""
    lines = (DATA / "ros2_topic_echo.csv").read_text().splitlines()
    cells = lines[row].split(",")
    cells[0 if part == "sec" else 1] = cell
    lines[row] = ",".join(cells)
    path = tmp_path / "stamps.csv"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError, match=rf"^{path}:{row + 1}: column 'header\.stamp\.{part}': expected whole "
                       rf"{'seconds' if part == 'sec' else 'nanoseconds'} from 0 to .*got '{cell}'"):  # fmt: skip
        read_log(path, missing=missing)


def test_a_split_stamp_part_out_of_range_in_pieces_exits_2(tmp_path: Path) -> None:
    lines = (DATA / "ros2_topic_echo.csv").read_text().splitlines()
    cells = lines[-1].split(",")
    cells[1] += "0"  # the last row's nanoseconds ×10: beyond a second
    lines[-1] = ",".join(cells)
    path = tmp_path / "stamps.csv"
    path.write_text("\n".join(lines) + "\n")
    done = run("estimate", path, "--chunk-rows", 100, "-o", tmp_path / "out.csv")
    assert done.returncode == 2 and f"{path}:{len(lines)}: column 'header.stamp.nanosec'" in done.stderr, done.stderr
    assert not (tmp_path / "out.csv").exists()


def test_bag_converter_header_stamp_in_secs_and_nsecs(tmp_path: Path) -> None:
    """bagpy/rosbags exports: the header stamp (secs + nsecs, exact), not the recording Time."""
    ros2 = (DATA / "ros2_topic_echo.csv").read_text().splitlines()
    head = "Time,header.seq,header.stamp.secs,header.stamp.nsecs,header.frame_id," + ",".join(
        f"wrench.{q}.{a}" for q in ("force", "torque") for a in "xyz"
    )
    rows = []
    for k, line in enumerate(ros2):
        sec, nsec, frame, *w = line.split(",")
        rows.append(",".join([f"{int(sec) + 0.5:.6f}", str(k), sec, nsec, frame, *w]))
    path = tmp_path / "bagpy.csv"
    path.write_text("\n".join([head, *rows]) + "\n")
    log = read_log(path)
    np.testing.assert_array_equal(log.t, read_log(REFERENCE).t)
    assert "t ← 'header.stamp.secs' (s" in log.notes[0] and "nanosec ← 'header.stamp.nsecs' (ns)" in log.notes[0]


def test_softtip_names_win_over_look_alike_extra_columns(tmp_path: Path) -> None:
    lines = REFERENCE.read_text().splitlines()
    path = tmp_path / "extra.csv"
    path.write_text("\n".join([lines[0] + ",Fx,time", *(ln + ",x,y" for ln in lines[1:])]) + "\n")
    log = read_log(path)
    np.testing.assert_array_equal(log.wrench, read_log(REFERENCE).wrench)
    assert list(log.extra) == ["Fx", "time"] and not log.notes


def test_the_pandas_example_of_the_input_formats_page_runs() -> None:
    """The page's pandas block runs as written on the corpus's ATI export and gives the
    estimates of read_log on the same file."""
    import re

    page = (Path(__file__).parents[1] / "docs" / "guide" / "input-formats.md").read_text(encoding="utf-8")
    (code,) = [b for b in re.findall(r"```python\n(.*?)```", page, re.DOTALL) if "pd.read_csv" in b]
    run = subprocess.run([sys.executable, "-c", code + "\nprint(int((table['state'] == 'line').sum()))"],
                         capture_output=True, text=True, timeout=300, cwd=Path(__file__).parent / "data" / "foreign")  # fmt: skip
    assert run.returncode == 0, run.stderr[-3000:]
    from softtip import estimate

    log = read_log(Path(__file__).parent / "data" / "foreign" / "ati_ms_n_nmm.csv")
    assert int(run.stdout.split()[-1]) == int(np.sum(estimate(log.t, log.wrench).state_names == "line"))


# --------------------------------------------------------------------------------------
# time columns a user's recorder gets wrong (an outsider's files)


def _with_t(tmp_path: Path, name: str, cells: list[str], header: str = "t") -> Path:
    lines = REFERENCE.read_text().splitlines()
    path = tmp_path / name
    rows = [f"{c},{ln.split(',', 1)[1]}" for c, ln in zip(cells, lines[1:])]
    path.write_text("\n".join([f"{header},fx,fy,fz,mx,my,mz", *rows]) + "\n")
    return path


@pytest.mark.parametrize("rate_hz", [3000.0, 7000.0, 19000.0])
def test_ms_stamps_at_a_sensor_rate_without_a_unit_stop_the_command(tmp_path: Path, rate_hz: float) -> None:
    """t in ms at 3–19 kHz reads as 3–19 Hz in seconds, as plausible a rate on its face: before, the
    one-sample tare and the drift tracker swallowed a grasp (no contact, exit 0). Now the command
    asks for the unit, and runs when told."""
    n = len(REFERENCE.read_text().splitlines()) - 1
    path = _with_t(tmp_path, "ms.csv", [f"{k * 1e3 / rate_hz:.6f}" for k in range(n)])
    done = run("estimate", path, "-o", tmp_path / "o.csv")
    assert done.returncode == 2 and not (tmp_path / "o.csv").exists(), done.stderr
    assert f"{rate_hz / 1e3:.4g} Hz if t is in seconds, {rate_hz:.5g} Hz if in milliseconds" in done.stderr, done.stderr
    assert "give --time-units s or --time-units ms" in done.stderr
    told = run("estimate", path, "--time-units", "ms", "--tare-duration", "0.01", "-o", tmp_path / "o.csv")
    assert told.returncode == 0, told.stderr  # (500 samples last 26–166 ms: a tare of 0.2 s would hold them all)
    assert read_log(path, time_units="ms").t[-1] == pytest.approx((n - 1) / rate_hz, rel=1e-5)
    # a log above 20 Hz in seconds is read as it is
    assert not any("--time-units" in w for w in read_log(_with_t(tmp_path, "s.csv", [f"{k / 25.0:.6f}" for k in range(n)])).warnings)


def test_a_stamp_column_that_never_changes_stops_naming_the_time_column(tmp_path: Path) -> None:
    """A driver that never fills header.stamp writes 0 on every row (rostopic echo -p keeps %time)."""
    lines = (DATA / "rostopic_echo_p.csv").read_text().splitlines()
    rows = [ln.split(",") for ln in lines[1:]]
    for row in rows:
        row[2] = "0"
    path = tmp_path / "stamp0.csv"
    path.write_text("\n".join([lines[0], *(",".join(r) for r in rows)]) + "\n")
    with pytest.raises(InputError, match=rf"column 'field\.header\.stamp': every one of the {len(rows)} stamps is 0; .*--columns t=%time$"):
        read_log(path)
    assert len(read_log(path, columns="t=%time").t) == len(rows)


def test_whole_millisecond_dates_are_exact_in_nanoseconds(tmp_path: Path) -> None:
    """1700000000123 ms is 1700000000123000000 ns exactly (its float times 1e6 is 64 ns off)."""
    n = len(REFERENCE.read_text().splitlines()) - 1
    log = read_log(_with_t(tmp_path, "ms.csv", [str(1700000000123 + 20 * k) for k in range(n)]))
    assert log.extra["stamp_ns"][:2].tolist() == [1700000000123000000, 1700000000143000000]
    np.testing.assert_array_equal(log.t, read_log(REFERENCE).t)


def test_interpolate_fills_cells_but_drops_another_topics_rows(tmp_path: Path) -> None:
    """A PlotJuggler export of two topics: the other topic's rows have no wrench value at all.
    --missing interpolate fills a row's empty cells, but does not invent samples at the other
    topic's times: those rows are dropped, as --missing drop does."""
    lines = (DATA / "plotjuggler.csv").read_text().splitlines()
    head, rows = lines[0], lines[1:]
    out = [head + ",/joint_states/position/0"]
    for k, row in enumerate(rows):
        cells = row.split(",")
        if k == 7:
            cells[3] = ""  # one cell missing in a wrench row: filled
        out.append(",".join(cells) + ",")
        if k % 5 == 0:
            t = float(cells[0]) + 0.007
            out.append(f"{t:.9f}" + "," * 6 + ",0.5")  # the other topic's row
    path = tmp_path / "two_topics.csv"
    path.write_text("\n".join(out) + "\n")
    filled = read_log(path, missing="interpolate")
    assert len(filled.t) == len(rows)
    assert any(f"1 row(s) filled by linear interpolation in t, {len(range(0, len(rows), 5))} row(s) without any wrench "
               "value dropped" in note for note in filled.notes), filled.notes  # fmt: skip
    dropped = read_log(path, missing="drop")
    assert len(dropped.t) == len(rows) - 1
    reference = read_log(DATA / "plotjuggler.csv")
    np.testing.assert_array_equal(np.delete(filled.wrench, 7, axis=0), np.delete(reference.wrench, 7, axis=0))


def test_a_constant_stamp_column_stops_in_pieces_too(tmp_path: Path) -> None:
    """softtip's own layout read in pieces: the same stop as read_log's, after the last piece."""
    lines = REFERENCE.read_text().splitlines()
    path = tmp_path / "const.csv"
    path.write_text("\n".join([lines[0], *(f"0,{ln.split(',', 1)[1]}" for ln in lines[1:])]) + "\n")
    done = run("estimate", path, "--chunk-rows", 100, "-o", tmp_path / "o.csv")
    assert done.returncode == 2 and f"{path}: column 't': every one of the {len(lines) - 1} stamps is 0" in done.stderr, done.stderr
    assert not (tmp_path / "o.csv").exists()


def test_stream_replays_a_foreign_file_as_estimate_reads_it(tmp_path: Path) -> None:
    """--replay reads a user's file with estimate's reading options and notes, and stops where
    estimate stops (t in ms at a sensor's rate, no unit), before anything is recorded."""
    ati = DATA / "ati_ms_n_nmm.csv"
    done = run("stream", "--replay", ati, "--speed", 0, "-o", tmp_path / "rec.csv")
    assert done.returncode == 0, done.stderr
    assert f"softtip: {ati}: read as" in done.stderr and "1 contact(s)" in done.stderr
    n = len(REFERENCE.read_text().splitlines()) - 1
    path = _with_t(tmp_path, "ms.csv", [f"{k / 7.0:.6f}" for k in range(n)])
    stopped = run("stream", "--replay", path, "--speed", 0, "-o", tmp_path / "rec2.csv")
    assert stopped.returncode == 2 and "give --time-units s or --time-units ms" in stopped.stderr, stopped.stderr
    assert not (tmp_path / "rec2.csv").exists()
    told = run("stream", "--replay", path, "--time-units", "ms", "--tare-duration", "0.01", "--speed", 0, "-o",
               tmp_path / "rec2.csv")  # fmt: skip
    assert told.returncode == 0, told.stderr
    live = run("stream", "--netft", "192.0.2.1", "--time-units", "ms")
    assert live.returncode == 2 and "apply to --replay" in live.stderr


def test_a_wrong_unit_in_the_header_is_said_to_be_the_headers(tmp_path: Path) -> None:
    """The header says N·m, the data are N·mm: the units check names the pair that fits and says that
    the file's unit, which no option overrides, is what to correct (estimate and a replay alike)."""
    lines = REFERENCE.read_text().splitlines()
    rows = []
    for ln in lines[1:]:
        cells = ln.split(",")
        rows.append(",".join(cells[:4] + [repr(float(c) * 1e3) for c in cells[4:]]))
    path = tmp_path / "hdr.csv"
    path.write_text("\n".join(["t,Fx (N),Fy (N),Fz (N),Tx (N-m),Ty (N-m),Tz (N-m)", *rows]) + "\n")
    for args in (("estimate", path, "-o", tmp_path / "o.csv"), ("stream", "--replay", path, "--speed", 0, "-o", tmp_path / "r.csv")):
        done = run(*args)
        assert done.returncode == 2, done.stderr
        assert "the data fit forces in N with moments in N·mm" in done.stderr
        assert "--moment-units" not in done.stderr  # no option the file's unit would overrule named as the fix
        assert "an option cannot override a unit the file gives: if the data are in another unit, the file is wrong" in done.stderr
    assert not (tmp_path / "o.csv").exists() and not (tmp_path / "r.csv").exists()


def test_a_time_unit_that_puts_the_stamps_beyond_2261_stops_naming_the_one_that_fits(tmp_path: Path) -> None:
    out = tmp_path / "e.csv"
    done = run("estimate", DATA / "rostopic_echo_p.csv", "--time-units", "ms", "-o", out)
    assert done.returncode == 2 and not out.exists()
    assert "column 'field.header.stamp': t in ms puts the first stamp 1.7e+15 s after 1970" in done.stderr
    assert "(--time-units ns)" in done.stderr


def test_a_stamp_going_back_in_a_headerless_ros2_export_names_line_and_columns(tmp_path: Path) -> None:
    lines = (DATA / "ros2_topic_echo.csv").read_text().splitlines(keepends=True)
    lines[300], lines[301] = lines[301], lines[300]  # lines 301 and 302 swapped: 302 goes back
    src = tmp_path / "back.csv"
    src.write_text("".join(lines))
    with pytest.raises(InputError, match=r"back\.csv:302: columns 'header\.stamp\.sec', 'header\.stamp\.nanosec': "
                                         r"expected the stamps non-decreasing"):  # fmt: skip
        read_log(src)


def test_a_cut_last_row_of_a_headerless_export_names_its_layout(tmp_path: Path) -> None:
    text = (DATA / "ros2_topic_echo.csv").read_text().rstrip("\n")
    src = tmp_path / "cut.csv"
    src.write_text(text[: text.rindex(",", 0, len(text) - 40)])  # the last row cut a few cells short
    with pytest.raises(InputError, match=r"cut\.csv:\d+: expected 9 cells \(one per column of the ROS 2 .* layout\)"):
        read_log(src)
