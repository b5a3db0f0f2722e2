"""Recordings as an outside user brings them: the layouts the foreign-file review found read
wrong or refused without a way out (tests/test_foreign.py holds the rest of the corpus).

* a preamble (Net F/T, DAQ F/T exports) before a header whose names need ``--columns``;
* a units row under the header (``s, N, N, N, N-mm, …``), as LabVIEW-style loggers write it;
* units stated on lines before the header (``Force Units:,N``, ``Torque Units:,N-mm``), as
  ATI's DAQ F/T software writes them;
* a time unit guessed from absolute stamps: the "read as" note says the unit it read.

Each file holds softtip's example grasp (the corpus's SI reference), converted exactly.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from softtip.core.units import UNITS
from softtip.errors import InputError
from softtip.io.tables import read_log

SOFTTIP = str(Path(sys.executable).with_name("softtip"))
REFERENCE = Path(__file__).parent / "data" / "foreign" / "si_reference.csv"
_REF = read_log(REFERENCE)


def _rows(n: int | None = None, *, force: float = 1.0, moment: float = 1.0, time: float = 1.0) -> list[list[str]]:
    """The reference's rows as text, in units whose size in SI is ``force``, ``moment``, ``time``."""
    t, w = _REF.t[:n], _REF.wrench[:n]
    scale = np.array([force] * 3 + [moment] * 3)
    return [[repr(float(ti / time)), *(repr(float(v)) for v in wi / scale)] for ti, wi in zip(t, w)]


def _check(log, n: int | None = None, per_unit: float | None = None) -> None:
    """The log is the reference; ``per_unit``: read from whole counts, so to half a count."""
    np.testing.assert_allclose(log.t, _REF.t[:n], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(log.wrench, _REF.wrench[:n], rtol=1e-12, atol=0 if per_unit is None else 0.5 / per_unit)


# --------------------------------------------------------------------------------------
# --columns on a file with a preamble

_NETFT_PREAMBLE = [
    "Final Sample Period,0.020000",
    "Serial Number,FT12345",
    "Force Units,N",
    "Torque Units,Nm",
    "Counts per Unit Force,1000000",
    "Counts per Unit Torque,1000000",
    "",
]
_NETFT_HEADER = "Time,Status (hex),RDT Sequence,F/T Sequence,Force X,Force Y,Force Z,Torque X,Torque Y,Torque Z"
_NETFT_COLUMNS = "t=Time,fx=Force X,fy=Force Y,fz=Force Z,mx=Torque X,my=Torque Y,mz=Torque Z"


def _netft(path: Path) -> Path:
    """A Net F/T demo log: Fx … Tz in counts, 1e6 per N and per N·m (its preamble says so)."""
    body = [",".join([r[0], "0x00000000", str(k + 1), str(1000 + k), *(str(round(float(v) * 1e6)) for v in r[1:])])
            for k, r in enumerate(_rows())]  # fmt: skip
    path.write_text("\n".join([*_NETFT_PREAMBLE, _NETFT_HEADER, *body]) + "\n")
    return path


def test_columns_find_their_header_after_a_preamble(tmp_path: Path) -> None:
    """--columns names the header's columns: the preamble before it is skipped, as without --columns."""
    path = _netft(tmp_path / "netft.csv")
    log = read_log(path, columns=_NETFT_COLUMNS)
    _check(log, per_unit=1e6)
    assert any("the header is on line 8; the 7 line(s) before it skipped (--skip-rows 7" in n for n in log.notes), log.notes
    np.testing.assert_array_equal(read_log(path, columns=_NETFT_COLUMNS, skip_rows=7).wrench, log.wrench)
    partial = read_log(path, columns="fx=Force X,fy=Force Y,fz=Force Z,mx=Torque X,my=Torque Y,mz=Torque Z")
    np.testing.assert_array_equal(partial.t, log.t)  # t from the dialect, on the header found


def test_columns_not_found_anywhere_name_the_nearest_line_and_skip_rows(tmp_path: Path) -> None:
    path = _netft(tmp_path / "netft.csv")
    with pytest.raises(InputError) as info:
        read_log(path, columns=_NETFT_COLUMNS.replace("Torque Z", "Torque W"))
    message = str(info.value)
    assert message.startswith(f"{path}:8: --columns mz=Torque W: no column 'Torque W' in the header"), message
    assert "--skip-rows" in message


def test_cli_columns_after_a_preamble(tmp_path: Path) -> None:
    path = _netft(tmp_path / "netft.csv")
    out = tmp_path / "e.csv"
    done = subprocess.run([SOFTTIP, "estimate", path, "--columns", _NETFT_COLUMNS, "-o", out],
                          capture_output=True, text=True, timeout=180)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "read as --columns: t ← 'Time' (s, not in the header)" in done.stderr
    assert "fx ← 'Force X' (N, from line 3, counts ÷ 1e+06 from line 5)" in done.stderr
    assert "the header is on line 8" in done.stderr


# --------------------------------------------------------------------------------------
# a units row under the header

_SPELLING = {"N*mm": "N-mm", "N*m": "Nm", "kgf*mm": "kgf·mm", "lbf*in": "lbf-in", "us": "µs"}


def _units_row_file(path: Path, force: str, moment: str, time: str, *, style: str = "{}", delimiter: str = ",",
                    header: str = "Time,Fx,Fy,Fz,Tx,Ty,Tz", n: int | None = None) -> Path:  # fmt: skip
    units = {u.name: u for u in UNITS}
    row = [_SPELLING.get(x, x) for x in (time, force, force, force, moment, moment, moment)]
    body = _rows(n, force=units[force].si, moment=units[moment].si, time=units[time].si)
    lines = [header.replace(",", delimiter), delimiter.join(style.format(u) for u in row),
             *(delimiter.join(r) for r in body)]  # fmt: skip
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def test_a_units_row_under_the_header_gives_the_units(tmp_path: Path) -> None:
    path = _units_row_file(tmp_path / "units_row.csv", "N", "N*mm", "s")
    log = read_log(path)
    _check(log)
    (note,) = [n for n in log.notes if "read as" in n]
    assert "mx ← 'Tx' (N·mm, from the units row on line 2)" in note and "t ← 'Time' (s, from the units row" in note
    assert log.first_line == 3
    lines = path.read_text().splitlines()
    lines[4] = lines[4].replace(",", ",x", 1)
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError, match=r"bad\.csv:5: column 'Fx': expected a number, got 'x"):
        read_log(bad)  # lines counted as in the file, the units row among them


@settings(max_examples=40, deadline=None)
@given(
    force=st.sampled_from([u.name for u in UNITS if u.quantity == "force"]),
    moment=st.sampled_from([u.name for u in UNITS if u.quantity == "moment"]),
    time=st.sampled_from(["s", "ms", "us"]),
    style=st.sampled_from(["{}", "[{}]", "({})", '"{}"']),
    delimiter=st.sampled_from([",", ";", "\t"]),
    header=st.sampled_from(["Time,Fx,Fy,Fz,Tx,Ty,Tz", "t,fx,fy,fz,mx,my,mz", "Time,Status,Fx,Fy,Fz,Tx,Ty,Tz"]),
)
def test_any_units_row_reads_back(tmp_path_factory, force, moment, time, style, delimiter, header) -> None:
    path = tmp_path_factory.mktemp("units_row") / "log.csv"
    if "Status" in header:  # a column the units row leaves empty
        _units_row_file(path, force, moment, time, style=style, delimiter=delimiter, n=40)
        lines = path.read_text(encoding="utf-8").splitlines()
        lines = [ln.split(delimiter, 1)[0] + delimiter + extra + delimiter + ln.split(delimiter, 1)[1]
                 for ln, extra in zip(lines, ["Status", "", *["0"] * (len(lines) - 2)])]  # fmt: skip
        path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    else:
        _units_row_file(path, force, moment, time, style=style, delimiter=delimiter, header=header, n=40)
    _check(read_log(path), 40)


def test_a_units_row_that_contradicts_an_option_or_is_unknown_is_refused(tmp_path: Path) -> None:
    path = _units_row_file(tmp_path / "units_row.csv", "N", "N*mm", "s")
    with pytest.raises(InputError, match=r":2: column 'Tx': the units row says N·mm but --moment-units .* says N\*m"):
        read_log(path, moment_units="N*m")
    counts = tmp_path / "counts.csv"
    counts.write_text(path.read_text().replace("N-mm", "counts", 1))
    with pytest.raises(InputError, match=r":2: column 'Tx': unknown moment unit 'counts' in the units row; expected one of"):
        read_log(counts)
    header_too = tmp_path / "both.csv"
    header_too.write_text(path.read_text().replace("Tx,", "Tx (N-m),", 1))
    with pytest.raises(InputError, match=r":2: column 'Tx \(N-m\)': the units row says N·mm but the header says N·m"):
        read_log(header_too)


def test_cli_units_row_gives_the_si_estimates(tmp_path: Path) -> None:
    path = _units_row_file(tmp_path / "units_row.csv", "lbf", "lbf*in", "ms")
    out, ref = tmp_path / "e.csv", tmp_path / "ref.csv"
    done = subprocess.run([SOFTTIP, "estimate", path, "-o", out], capture_output=True, text=True, timeout=180)
    assert done.returncode == 0, done.stderr
    assert subprocess.run([SOFTTIP, "estimate", REFERENCE, "-o", ref], capture_output=True, timeout=180).returncode == 0
    got, want = (np.genfromtxt(p, delimiter=",", names=True, dtype=None, encoding="utf-8") for p in (out, ref))
    assert (got["state"] == want["state"]).all()
    np.testing.assert_allclose(got["rz"], want["rz"], rtol=1e-6, atol=1e-9)


# --------------------------------------------------------------------------------------
# units stated before the header (ATI's DAQ F/T log: "Force Units:,N", "Torque Units:,N-mm")


def _stated_units_file(path: Path, force: str, moment: str, *, form: str = "{q} Units:,{u}", delimiter: str = ",",
                       case=str, n: int | None = None) -> Path:  # fmt: skip
    units = {u.name: u for u in UNITS}
    body = _rows(n, force=units[force].si, moment=units[moment].si)
    preamble = ["ATI DAQ F/T Data Log", "Serial Number:,FT24117",
                case(form.format(q="Force", u=_SPELLING.get(force, force))),
                case(form.format(q="Torque", u=_SPELLING.get(moment, moment))), "Sample Rate (Hz):,1000"]  # fmt: skip
    header = "Time,Fx,Fy,Fz,Tx,Ty,Tz"
    lines = [*(ln.replace(",", delimiter) for ln in preamble), header.replace(",", delimiter),
             *(delimiter.join(r) for r in body)]  # fmt: skip
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def test_units_stated_before_the_header_give_the_units(tmp_path: Path) -> None:
    path = _stated_units_file(tmp_path / "daq.csv", "N", "N*mm")
    log = read_log(path)
    _check(log)
    (note,) = [n for n in log.notes if "read as" in n]
    assert "fx ← 'Fx' (N, from line 3)" in note and "mx ← 'Tx' (N·mm, from line 4)" in note, note
    assert "t ← 'Time' (s, not in the header)" in note
    assert log.units_in_header == ("Fx", "Fy", "Fz", "Tx", "Ty", "Tz")


@settings(max_examples=40, deadline=None)
@given(
    force=st.sampled_from([u.name for u in UNITS if u.quantity == "force"]),
    moment=st.sampled_from([u.name for u in UNITS if u.quantity == "moment"]),
    form=st.sampled_from(["{q} Units:,{u}", "{q} Units,{u}", "{q} units: {u}", "# {q}_unit = {u}", "{q} Units:,,{u},"]),
    delimiter=st.sampled_from([",", ";", "\t"]),
    case=st.sampled_from([str, str.upper, str.lower]),
)
def test_any_stated_units_read_back(tmp_path_factory, force, moment, form, delimiter, case) -> None:
    path = tmp_path_factory.mktemp("stated") / "log.csv"
    _stated_units_file(path, force, moment, form=form, delimiter=delimiter, case=case, n=40)
    _check(read_log(path), 40)


def test_stated_units_that_contradict_the_file_or_an_option_or_are_unknown_are_refused(tmp_path: Path) -> None:
    path = _stated_units_file(tmp_path / "daq.csv", "N", "N*mm")
    text = path.read_text()
    with pytest.raises(InputError, match=r"daq\.csv:4: 'N-mm' says the moment unit is N·mm but --moment-units .* says N\*m"):
        read_log(path, moment_units="N*m")
    assert read_log(path, moment_units="N*mm").moment_unit == "N*mm"  # the option agrees: no error
    cases = {
        "counts.csv": (text.replace("Torque Units:,N-mm", "Torque Units:,Counts"),
                       r"counts\.csv:4: unknown moment unit 'Counts' on a line before the header; expected one of: .*"
                       r"\(or give --moment-units\)"),
        "header.csv": (text.replace("Tx,", "Tx (N-m),", 1),
                       r"header\.csv:4: column 'Tx \(N-m\)': this line says N·mm but the header says N·m; expected one unit"),
        "twice.csv": (text.replace("Sample Rate", "Torque Units:,Nm\nSample Rate"),
                      r"twice\.csv:5: 'Nm' contradicts 'N-mm' on line 4 for the moment unit; expected one \(--moment-units"),
    }  # fmt: skip
    for name, (body, message) in cases.items():
        (tmp_path / name).write_text(body)
        with pytest.raises(InputError, match=message):
            read_log(tmp_path / name)
    # what the option settles: a unit the file names that softtip does not know, two lines that disagree
    for name in ("counts.csv", "twice.csv"):
        _check(read_log(tmp_path / name, moment_units="N*mm"))
    variants = {  # read as the plain file: the same unit spelled otherwise, a remark, brackets, a table of labels
        "same.csv": text.replace("Tx,Ty,Tz", "Tx (N-mm),Ty (N-mm),Tz (N-mm)", 1),
        "spelled.csv": text.replace("Sample Rate", "torque units = Nmm\nSample Rate"),
        "remark.csv": text.replace("Force Units:,N", "Force Units: N (calibrated)"),
        "brackets.csv": text.replace("Torque Units:,N-mm", "Torque Units (N-mm)"),
        "labels.csv": text.replace("Sample Rate (Hz):,1000", "Force Units,Torque Units\nN,N-mm"),
        "words.csv": text.replace("Force Units:,N", "Force Units:,Newton").replace("Torque Units:,N-mm",
                                                                                      "Torque Units:,Newton-millimeter"),
    }  # fmt: skip
    for name, body in variants.items():
        (tmp_path / name).write_text(body)
        _check(read_log(tmp_path / name))


@pytest.mark.parametrize("per_unit", ["1000000", "1e6", "4000"])
def test_counts_per_unit_before_the_header_divide_the_raw_columns(tmp_path: Path, per_unit: str) -> None:
    """A Net F/T or Ethernet Axia demo log holds counts; the lines before its header say the unit
    and the counts per unit: the columns are divided by them."""
    k = float(per_unit)
    rows = [",".join(["0x00000000", str(j + 1), *(str(round(float(v) * k)) for v in r[1:]), r[0]]) for j, r in enumerate(_rows())]
    path = tmp_path / "axia.csv"
    path.write_text("\n".join(["Start Time,11/29/2026 10:00:00", "RDT Sample Rate,50", "Force Units,N",
                               f"Counts per Unit Force,{per_unit}", "Torque Units,N-m", f"Counts per Unit Torque,{per_unit}",
                               "Status (hex),RDT Sequence,Fx,Fy,Fz,Tx,Ty,Tz,Time", *rows]) + "\n")  # fmt: skip
    log = read_log(path)
    _check(log, per_unit=k)
    (note,) = [n for n in log.notes if "read as" in n]
    assert f"mx ← 'Tx' (N·m, from line 5, counts ÷ {k:g} from line 6)" in note, note
    # values in units under lines that say counts (a file converted and its preamble kept): refused
    # at the first fraction, with the option that reads them as they are
    converted = tmp_path / "converted.csv"
    lines = path.read_text().splitlines()
    converted.write_text("\n".join(lines[:7] + [",".join(["0x00000000", str(j + 1), *r[1:], r[0]])
                                               for j, r in enumerate(_rows())]) + "\n")  # fmt: skip
    with pytest.raises(InputError, match=r"converted\.csv:8: column 'Fx': line 4 says its values are counts \(\S+ per "
                                         r"unit\), but -?[0-9.e-]+ is not a whole number; if the values are in N already, "
                                         r"give --force-units N"):  # fmt: skip  (the number as a float's repr, no numpy type)
        read_log(converted)
    _check(read_log(converted, force_units="N", moment_units="N*m"))


def test_counts_per_unit_that_are_no_positive_number_or_contradict_are_refused(tmp_path: Path) -> None:
    path = _netft(tmp_path / "netft.csv")
    text = path.read_text()
    for name, body, message in [
        ("zero.csv", text.replace("Counts per Unit Force,1000000", "Counts per Unit Force,0"),
         r"zero\.csv:5: counts per unit force '0'; expected a positive number \(the columns of force without a unit"),
        ("word.csv", text.replace("Counts per Unit Torque,1000000", "Counts per Unit Torque,many"),
         r"word\.csv:6: counts per unit moment 'many'; expected a positive number"),
        ("twice.csv", text.replace("Serial Number,FT12345", "Counts per Unit Force,1000"),
         r"twice\.csv:5: counts per unit force 1000000 contradicts 1000 on line 2; expected one$"),
    ]:  # fmt: skip
        (tmp_path / name).write_text(body)
        with pytest.raises(InputError, match=message):
            read_log(tmp_path / name, columns=_NETFT_COLUMNS)
    # a header that gives the unit: the column is in that unit, not in counts
    named = tmp_path / "named.csv"
    named.write_text(text.replace("Force X,Force Y,Force Z", "Force X (N),Force Y (N),Force Z (N)"))
    log = read_log(named, columns=_NETFT_COLUMNS.replace("=Force X", "=Force X (N)").replace("=Force Y", "=Force Y (N)")
                   .replace("=Force Z", "=Force Z (N)"))  # fmt: skip
    np.testing.assert_allclose(log.wrench[:, :3], np.round(_REF.wrench[:, :3] * 1e6), rtol=1e-12)
    np.testing.assert_allclose(log.wrench[:, 3:], _REF.wrench[:, 3:], rtol=1e-12, atol=0.5e-6)
    # the same line also spelled 1e6 agrees with it
    (tmp_path / "again.csv").write_text(text.replace("Serial Number,FT12345", "Counts per Unit Force,1e6"))
    _check(read_log(tmp_path / "again.csv", columns=_NETFT_COLUMNS), per_unit=1e6)


def test_cli_reads_an_ati_daq_log_with_its_units_before_the_header(tmp_path: Path) -> None:
    path = _stated_units_file(tmp_path / "daq.csv", "N", "N*mm")
    out, ref = tmp_path / "e.csv", tmp_path / "ref.csv"
    done = subprocess.run([SOFTTIP, "estimate", path, "-o", out], capture_output=True, text=True, timeout=180)
    assert done.returncode == 0, done.stderr
    assert "mx ← 'Tx' (N·mm, from line 4)" in done.stderr
    assert subprocess.run([SOFTTIP, "estimate", REFERENCE, "-o", ref], capture_output=True, timeout=180).returncode == 0
    got, want = (np.genfromtxt(p, delimiter=",", names=True, dtype=None, encoding="utf-8") for p in (out, ref))
    assert (got["state"] == want["state"]).all()
    np.testing.assert_allclose(got["rz"], want["rz"], rtol=1e-6, atol=1e-9)
    # the line is wrong (it says N·m, the data are in N·mm): the unit check stops the run and
    # names where the unit came from, and nothing is written
    wrong = tmp_path / "wrong.csv"
    wrong.write_text(path.read_text().replace("Torque Units:,N-mm", "Torque Units:,N-m"))
    done = subprocess.run([SOFTTIP, "estimate", wrong, "-o", tmp_path / "w.csv"], capture_output=True, text=True, timeout=180)
    assert done.returncode == 2, done.stderr
    assert "a line before the header" in done.stderr and not (tmp_path / "w.csv").exists()


# --------------------------------------------------------------------------------------
# a time unit found from absolute stamps is the one the "read as" note names


@pytest.mark.parametrize(("digits", "unit"), [(3, "ms"), (6, "µs")])
def test_the_note_names_the_time_unit_read_from_absolute_stamps(tmp_path: Path, digits: int, unit: str) -> None:
    base = 1_764_328_620 * 10**digits
    rows = [[str(base + round(float(r[0]) * 10**digits)), *r[1:]] for r in _rows()]
    path = tmp_path / "stamps.csv"
    path.write_text("\n".join(["timestamp,fx,fy,fz,mx,my,mz", *(",".join(r) for r in rows)]) + "\n")
    log = read_log(path)
    np.testing.assert_allclose(log.t, _REF.t, atol=1e-12)
    (note,) = [n for n in log.notes if "read as" in n]
    assert f"t ← 'timestamp' ({unit}, not in the header)" in note, note


# --------------------------------------------------------------------------------------
# a header softtip cannot map: the message names what is missing, not what it reads


@pytest.mark.parametrize(
    ("text", "missing", "also"),
    [
        ("Zeit;Fx;Fy;Fz;Mx;My;Mz\n0;1;2;3;4;5;6\n", "t", "--columns t=NAME"),
        ("time,Fx,f_y,fz,mx,my,torque_zz\n0,1,2,3,4,5,6\n", "mz", ""),  # 'time', 'Fx', 'f_y' are read as they are
    ],
    ids=["zeit", "typo"],
)
def test_missing_columns_name_only_what_no_dialect_reads(tmp_path: Path, text: str, missing: str, also: str) -> None:
    """'Fx' … 'Mz' are read (any case): only a column no dialect reads is missing ('Zeit', or
    'torque_zz'), and no column that is read is offered as a misspelling."""
    path = tmp_path / "log.csv"
    path.write_text(text)
    with pytest.raises(InputError) as info:
        read_log(path)
    message = str(info.value)
    assert message.startswith(f"{path}:1: missing column {missing!r};"), message
    assert "did you mean" not in message and also in message


_UNSTAMPED = [
    ("PlotJuggler (CSV export)", "__time", "/ft/{q}/{a}", 0, 1),
    ("ROS 1 rostopic echo -p", "%time", "field.{q}.{a}", 1_764_328_620 * 10**9, 10**9),
    ("rosbag to CSV converters (bagpy, rosbags, rqt_bag)", "Time", "{q}.{a}", 0, 1),
]


@pytest.mark.parametrize(("source", "time", "pattern", "base", "per_s"), _UNSTAMPED, ids=[s[0].split()[0] for s in _UNSTAMPED])
def test_exports_of_an_unstamped_wrench_topic(tmp_path: Path, source: str, time: str, pattern: str, base: int,
                                              per_s: int) -> None:  # fmt: skip
    """A geometry_msgs/Wrench topic (no header, so no 'wrench' in the field path): force.x … torque.z."""
    names = [time, *(pattern.format(q=q, a=a) for q in ("force", "torque") for a in "xyz")]
    rows = [[str(base + round(float(r[0]) * per_s)) if per_s > 1 else r[0], *r[1:]] for r in _rows()]
    path = tmp_path / "unstamped.csv"
    path.write_text("\n".join([",".join(names), *(",".join(r) for r in rows)]) + "\n")
    log = read_log(path)
    _check(log)
    assert f"read as {source}: t ← '{time}'" in log.notes[0] and f"fx ← '{names[1]}'" in log.notes[0], log.notes


def test_a_header_without_time_below_a_preamble_is_the_one_named(tmp_path: Path) -> None:
    """A Net F/T export in counts has no time column: the error is on its header (line 9, below
    the preamble), naming only t, not the first preamble line with every column 'missing'."""
    path = tmp_path / "netft_counts.csv"
    body = [",".join(["0x00000000", str(k + 1), str(1000 + k), *(str(round(float(v) * 1e6)) for v in r[1:])])
            for k, r in enumerate(_rows(20))]  # fmt: skip
    path.write_text("\n".join([*_NETFT_PREAMBLE, "", "Status (hex),RDT Sequence,F/T Sequence,Fx,Fy,Fz,Tx,Ty,Tz", *body]) + "\n")
    with pytest.raises(InputError) as info:
        read_log(path)
    assert str(info.value).startswith(f"{path}:9: missing column 't';"), str(info.value)
    assert "--columns t=NAME" in str(info.value)


def test_a_stray_quote_in_a_cell_beyond_the_header_fails_cleanly(tmp_path: Path) -> None:
    """A quote left open in a row with a cell more than the header has ("a, ""b"," — a damaged note
    column) swallows the next row: an InputError naming the line, not an IndexError."""
    rows = [",".join([*r, '"a, ""b"""']) for r in _rows(6)]
    rows[0] = rows[0][:-2] + ',"'
    path = tmp_path / "stray.csv"
    path.write_text("\n".join(["t,fx,fy,fz,mx,my,mz,note", *rows]) + "\n")
    with pytest.raises(InputError, match=r"stray\.csv:2: .*quote opened on this line"):
        read_log(path)


def test_a_time_unit_option_on_a_stamp_split_in_seconds_and_nanoseconds_is_refused(tmp_path: Path) -> None:
    """ros2 topic echo --csv and bag converters split the stamp in sec + nanosec: a --time-units
    other than s cannot apply (it was ignored while the note said 't ← … (ms)')."""
    rows = [[str(1_764_328_620 + int(r[0].split(".")[0])), str(round(float(r[0]) % 1 * 1e9)), "ft", *r[1:]] for r in _rows(30)]
    path = tmp_path / "echo.csv"
    path.write_text("\n".join(",".join(r) for r in rows) + "\n")
    with pytest.raises(InputError, match=r"echo\.csv:1: column 'header\.stamp\.sec' holds the whole seconds of a stamp .*--time-units ms"):
        read_log(path, time_units="ms")
    np.testing.assert_array_equal(read_log(path, time_units="s").t, read_log(path).t)
