"""Memory stays bounded by the log's size and the piece size, whatever its text cells hold (issue 32)."""

from __future__ import annotations

import functools
import io
import itertools
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from softtip.io.tables import iter_log

SOFTTIP = str(Path(sys.executable).with_name("softtip"))

# Runs a command on the standard output and error it was given (the test's pipes) and then
# writes its exit code and peak resident memory (kB on Linux) onto the standard error, after a mark.
_MARK = "\0peak "
_PEAK = (
    "import resource, subprocess, sys; code = subprocess.run(sys.argv[1:]).returncode; "
    f"sys.stderr.write({_MARK!r} + f'{{code}} {{resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss}}')"
)


def _measured(*args: object, timeout: float = 120) -> tuple[int, float, bytes, str]:
    """A ``softtip`` command's exit code, peak resident memory (MB), standard output and error:
    the run a test measures is the run whose output it checks (one run, not two alike)."""
    done = subprocess.run([sys.executable, "-c", _PEAK, SOFTTIP, *map(str, args)], capture_output=True,
                          timeout=timeout, check=True)  # fmt: skip
    err, mark, stats = done.stderr.decode().rpartition(_MARK)
    assert mark, done.stderr[-3000:]
    code, kb = stats.split()
    return int(code), int(kb) / 1024, done.stdout, err


def _peak_mb(*args: object) -> tuple[int, float]:
    code, mb, _, _ = _measured(*args)
    return code, mb


@pytest.fixture(scope="module")
def plain_log(tmp_path_factory) -> Path:
    """The 200000-row plain log of :func:`_log_with_note` (read, never changed, by the tests)."""
    log = tmp_path_factory.mktemp("plain") / "plain.csv"
    _log_with_note(log, 200000, "ok")
    return log


def _plain_in_pieces(tmp_path_factory, plain_log: Path, *quiet: str) -> tuple[int, float, Path]:
    out = tmp_path_factory.mktemp("pieces") / "p.csv"
    code, mb = _peak_mb("estimate", plain_log, *quiet, "--chunk-rows", 20000, "-o", out)
    assert code == 0 and [p.name for p in out.parent.iterdir()] == ["p.csv"]  # nothing else left behind
    return code, mb, out


@pytest.fixture(scope="module")
def plain_in_pieces_quiet(tmp_path_factory, plain_log: Path) -> tuple[int, float, Path]:
    """``softtip estimate plain.csv -q --chunk-rows 20000 -o p.csv``: exit code, peak memory (MB)
    and the output. The measure two tests compare against (each ran this command on this log)."""
    return _plain_in_pieces(tmp_path_factory, plain_log, "-q")


@pytest.fixture(scope="module")
def plain_in_pieces_loud(tmp_path_factory, plain_log: Path) -> tuple[int, float, Path]:
    """The same without ``-q``: the measure of two other tests (each ran it)."""
    return _plain_in_pieces(tmp_path_factory, plain_log)


def _log_with_note(path: Path, rows: int, note: str, bad_last: bool = False) -> None:
    path.write_text(_log_text(rows, note, bad_last))


@functools.cache
def _log_text(rows: int, note: str, bad_last: bool) -> str:
    """The text of :func:`_log_with_note`'s log, formatted once per process: the same few logs
    (5000 rows in about a hundred tests, 60000 in ten) took 0.02-0.23 s each to format again
    (a string: a test that changes its log changes its own copy, read back from its file)."""
    rng = np.random.default_rng(0)
    w = rng.normal(0.0, 1.0, (rows, 6)) * np.array([3e-3] * 3 + [1.5e-5] * 3)
    lines = ["t,fx,fy,fz,mx,my,mz,note\n"]
    lines += [f"{i / 1000:.3f},{','.join(f'{v:.8f}' for v in w[i])},ok\n" for i in range(rows)]
    lines[101] = lines[101][: -len("ok\n")] + note + "\n"
    if bad_last:
        lines[-1] = lines[-1].replace(",", ",abc", 1)
    return "".join(lines)


def _small_blocks_log(tmp_path: Path, monkeypatch) -> tuple[Path, list[str]]:
    """A 5000-row log with a note column, read in windows of 4 kB and blocks of 8 kB: its path and lines."""
    import softtip.io.tables as tables

    monkeypatch.setattr(tables, "_LOCATE_BYTES", 4096)
    monkeypatch.setattr(tables, "_CSV_BLOCK_BYTES", 8192)
    src = tmp_path / "in.csv"
    _log_with_note(src, 5000, "ok")
    return src, src.read_text().splitlines(keepends=True)


def test_block_reader_text_columns_are_not_as_wide_as_the_longest_cell(tmp_path: Path) -> None:
    src = tmp_path / "in.csv"
    _log_with_note(src, 20000, "x" * 2000)
    blocks = list(iter_log(src))
    assert sum(len(t) for t, _, _ in blocks) == 20000
    for t, _, extra in blocks:
        assert extra["note"].nbytes <= 8 * len(t)  # pointers, not 2000 characters a cell
    assert blocks[0][2]["note"][100] == "x" * 2000


@pytest.mark.parametrize("pieces", [[], ["--chunk-rows", 20000]], ids=["one-shot", "pieces"])
def test_one_long_text_cell_does_not_multiply_memory(tmp_path: Path, pieces: list) -> None:
    """One 2000-character note in 60000 rows took 480 MB more (a unicode column 8000 bytes a cell)."""
    short, long = tmp_path / "short.csv", tmp_path / "long.csv"
    _log_with_note(short, 60000, "ok")
    _log_with_note(long, 60000, "x" * 2000)
    code_short, base = _peak_mb("estimate", short, "-o", tmp_path / "a.csv", *pieces)
    code_long, peak = _peak_mb("estimate", long, "-o", tmp_path / "b.csv", *pieces)
    assert code_short == code_long == 0
    assert peak < base + 120, (base, peak)
    assert ("x" * 2000) in (tmp_path / "b.csv").read_text()


def test_bad_last_line_in_pieces_does_not_read_the_whole_file(tmp_path: Path, plain_in_pieces_loud) -> None:
    """The error of a bad last line read in pieces was found by reading the whole file at once
    (6.8 GB for 1e7 rows; here +235 MB for 4e5 rows); now from the last good row on, in bounded windows:
    no more memory than the run without the bad line."""
    bad = tmp_path / "bad.csv"
    _log_with_note(bad, 200000, "ok", bad_last=True)
    _, good_mb, _ = plain_in_pieces_loud  # the good log's run (plain.csv: the same 200000 rows)
    code, bad_mb, _, err = _measured("estimate", bad, "-o", tmp_path / "out_bad.csv", "--chunk-rows", 20000)
    assert code == 2
    assert bad_mb < good_mb + 50, (good_mb, bad_mb)
    # the one-shot reader's message, to the letter
    assert err == f"softtip: error: {bad}:200001: column 'fx': expected a number, got {_last_fx(bad)!r}\n"
    assert [p.name for p in tmp_path.iterdir()] == ["bad.csv"]


def _last_fx(path: Path) -> str:
    return path.read_text().rstrip("\n").rsplit("\n", 1)[1].split(",")[1]


@pytest.mark.parametrize(
    "where, change",
    [
        (-1, lambda line: line.replace(",", ",,", 1)),  # one cell too many, on the last line
        (-1, lambda line: line[: line.index(",")] + ",inf" + line[line.index(",", line.index(",") + 1) :]),
        (-1, lambda line: line[: line.index(",") + 1] + line[line.index(",") + 1 :].replace(",", ",,", 1)),
        (45000, lambda line: "0.001" + line[line.index(",") :]),  # t goes back
        (45000, lambda line: "\n" + line),  # a blank line between data rows
        (45000, lambda line: line.replace(",", ",\xff", 1)),  # not UTF-8 (as latin-1 bytes)
        (-1, lambda line: line.rstrip("\n").replace(",", ",x", 1)),  # cut, without a line break
        (45000, lambda line: line.replace(",", ", 1_0", 1)),  # a cell only Python's float reads: not an error
    ],
    ids=["cells", "inf", "empty", "t-back", "blank", "utf8", "cut", "python-only"],
)
def test_errors_met_in_pieces_word_as_the_one_shot_reader(tmp_path: Path, where: int, change) -> None:
    src = tmp_path / "in.csv"
    _log_with_note(src, 60000, "ok")
    lines = src.read_text().splitlines(keepends=True)
    lines[where] = change(lines[where])
    src.write_bytes("".join(lines).encode("latin-1"))
    one = subprocess.run([SOFTTIP, "estimate", str(src), "-o", str(tmp_path / "a.csv")], capture_output=True, text=True,
                         timeout=120, check=False)  # fmt: skip
    pieces = subprocess.run([SOFTTIP, "estimate", str(src), "-o", str(tmp_path / "b.csv"), "--chunk-rows", "8192"],
                            capture_output=True, text=True, timeout=120, check=False)  # fmt: skip
    assert pieces.returncode == one.returncode
    assert pieces.stderr.replace("b.csv", "a.csv") == one.stderr


@pytest.mark.parametrize("row", [0, 1, 999, 1000, 1001, 2500, 4999])
@pytest.mark.parametrize("change", ["t-back", "cells", "blank", "nan", "utf8"])
def test_located_error_across_small_windows_is_read_logs(tmp_path: Path, monkeypatch, row: int, change: str) -> None:
    """Windows of 4 kB (a few dozen lines each): the error's line and wording are read_log's wherever it falls."""
    from softtip.errors import InputError
    from softtip.io.tables import NotStreamable, read_log

    if change == "t-back" and row < 2:
        pytest.skip("t = 0.0001 goes back only from the third row on")
    if change == "utf8" and row < 1000:
        pytest.skip("within the header's 64 kB the block reader does not start: read_log words it")
    src, lines = _small_blocks_log(tmp_path, monkeypatch)
    k = row + 1
    lines[k] = {
        "t-back": lambda line: "0.0001" + line[line.index(",") :],
        "cells": lambda line: line.replace(",", ",,", 1),
        "blank": lambda line: "\n" + line,
        "nan": lambda line: line.replace(",", ",nan", 1),
        "utf8": lambda line: line.replace(",", ",\xe9", 1),
    }[change](lines[k])
    src.write_bytes("".join(lines).encode("latin-1"))
    with pytest.raises(InputError) as one:
        read_log(src)
    blocks = iter_log(src)
    with pytest.raises(NotStreamable):
        for _ in blocks:
            pass
    assert str(blocks.locate_error()) == str(one.value)


# --------------------------------------------------------------------------------------
# standard output, in pieces: memory bounded by the piece size (issue 32: a 1e7-row run to
# standard output held the whole log)


def _stdout_run(*args: object) -> subprocess.CompletedProcess:
    return subprocess.run([SOFTTIP, *map(str, args)], capture_output=True, timeout=300, check=False)


def test_pieces_onto_standard_output_are_the_one_shot_table_in_bounded_memory(plain_log: Path,
                                                                            plain_in_pieces_quiet) -> None:  # fmt: skip
    src = plain_log  # 200000 rows
    # the one-shot run (a 15 MB log: not in pieces by itself), into the runner's pipe
    code_one, whole, one, err = _measured("estimate", src, "-q")
    assert code_one == 0, err
    code_out, to_stdout, done, err = _measured("estimate", src, "-q", "--chunk-rows", 20000)  # into the runner's pipe
    assert code_out == 0, err
    assert done == one
    dash = _stdout_run("estimate", src, "-q", "--chunk-rows", 20000, "-o", "-")
    assert dash.returncode == 0, dash.stderr
    assert dash.stdout == one
    code, to_file, _ = plain_in_pieces_quiet  # ... -q --chunk-rows 20000 -o p.csv
    assert code == 0
    assert to_stdout < to_file + 50, (to_stdout, to_file)
    assert to_stdout < whole - 50, (to_stdout, whole)


@pytest.mark.skipif(not Path("/dev/stdout").exists(), reason="needs /dev/stdout")
def test_dev_stdout_through_a_pipe_in_pieces(tmp_path: Path) -> None:
    src = tmp_path / "in.csv"
    _log_with_note(src, 50000, "ok")
    one = _stdout_run("estimate", src, "-q")
    done = subprocess.run(f"{SOFTTIP} estimate {src} -q --chunk-rows 5000 -o /dev/stdout | cat", shell=True,
                          capture_output=True, timeout=300, check=False)  # fmt: skip
    assert done.returncode == 0 and done.stdout == one.stdout, done.stderr
    assert [p.name for p in tmp_path.iterdir()] == ["in.csv"]


def test_a_failure_after_pieces_went_to_standard_output_says_so(tmp_path: Path) -> None:
    """What was written stays written: the located message, exit 2, and before it a warning that the
    table on standard output is cut; the rows there are the good run's first rows."""
    good, bad = tmp_path / "good.csv", tmp_path / "bad.csv"
    _log_with_note(good, 100000, "ok")
    lines = good.read_text().splitlines(keepends=True)
    lines[90001] = lines[90001].replace(",", ",abc", 1)
    bad.write_text("".join(lines))
    ok = _stdout_run("estimate", good, "-q", "--chunk-rows", 10000)
    done = _stdout_run("estimate", bad, "-q", "--chunk-rows", 10000)
    assert done.returncode == 2
    err = done.stderr.decode()
    assert err.endswith(f"softtip: error: {bad}:90002: column 'fx': expected a number, got {lines[90001].split(',')[1]!r}\n"), err
    assert "standard output: " in err and "rows were written before the error below" in err
    n = int(err.split("standard output: ")[1].split(" rows")[0])
    assert 0 < n < 90000
    assert done.stdout == b"".join(ok.stdout.splitlines(keepends=True)[: n + 1])  # the header and n rows


def test_a_quoted_log_onto_standard_output_in_pieces(tmp_path: Path) -> None:
    """A log with quotes goes in pieces onto standard output too (it was read whole): the bytes
    of the run in pieces into a file (text cells quoted piece by piece, manual §4), the cells of
    the one-shot run."""
    import csv

    src = tmp_path / "in.csv"
    _log_with_note(src, 20000, '"a note, quoted"')
    one = _stdout_run("estimate", src, "-q", "-o", tmp_path / "one.csv")
    pieces = _stdout_run("estimate", src, "-q", "--chunk-rows", 2000, "-o", tmp_path / "pieces.csv")
    done = _stdout_run("estimate", src, "-q", "--chunk-rows", 2000)
    assert one.returncode == pieces.returncode == done.returncode == 0, done.stderr
    assert done.stdout == (tmp_path / "pieces.csv").read_bytes()
    with open(tmp_path / "one.csv", newline="") as fh:
        assert list(csv.reader(io.StringIO(done.stdout.decode()))) == list(csv.reader(fh))


@pytest.mark.parametrize("line", [1, 2, 300])
def test_bad_utf8_within_the_first_64_kb_is_located_in_windows(tmp_path: Path, line: int) -> None:
    """Not UTF-8 in the header's 64 kB took the whole-file reader to be worded; now a pass in
    bounded windows gives read_log's message."""
    from softtip.errors import InputError
    from softtip.io.tables import NotStreamable, read_log

    src = tmp_path / "in.csv"
    _log_with_note(src, 5000, "ok")
    lines = src.read_bytes().splitlines(keepends=True)
    lines[line - 1] = lines[line - 1].replace(b",", b",\xe9", 1)
    src.write_bytes(b"".join(lines))
    with pytest.raises(InputError) as whole:
        read_log(src)
    blocks = iter_log(src)
    with pytest.raises(NotStreamable):
        list(blocks)
    found = blocks.locate_error()
    assert found is not None and str(found) == str(whole.value)
    assert f"in.csv:{line}: not valid UTF-8 (byte 0xe9" in str(found)


def test_bad_utf8_near_the_start_in_pieces_takes_no_more_memory(tmp_path: Path, plain_log: Path,
                                                                 plain_in_pieces_loud) -> None:  # fmt: skip
    bad = tmp_path / "bad.csv"
    data = plain_log.read_bytes()  # the good log (200000 rows)
    cut = data.index(b"\n", 1000) + 1
    bad.write_bytes(data[:cut] + data[cut:].replace(b",ok", b",\xe9", 1))
    _, good_mb, _ = plain_in_pieces_loud  # the good log's run: ... -o p.csv --chunk-rows 20000
    code, bad_mb, _, pieces = _measured("estimate", bad, "-o", tmp_path / "b.csv", "--chunk-rows", 20000)
    assert code == 2
    assert bad_mb < good_mb + 30, (good_mb, bad_mb)
    one = subprocess.run([SOFTTIP, "estimate", str(bad), "-o", str(tmp_path / "a.csv")], capture_output=True, text=True,
                         timeout=120, check=False)  # fmt: skip
    assert one.returncode == 2
    assert pieces.replace("b.csv", "a.csv") == one.stderr and "not valid UTF-8" in one.stderr


# --------------------------------------------------------------------------------------
# quoted cells that span lines and lone carriage returns: read in pieces too (they were read
# whole: 1e6 rows with --chunk-rows 20000 took 1.05-1.08 GB against 0.45 GB without them)


def _layout(lines: list[str], layout: str) -> bytes:
    """The lines (each ending in a line feed) with the line ends of ``layout``."""
    text = "".join(lines)
    if layout == "lone-cr":
        text = text.replace("\n", "\r")
    elif layout == "crlf":
        text = text.replace("\n", "\r\n")
    return text.encode("latin-1")


_NOTE = '"a note\nover two lines, with a comma"'
_CHANGES = {
    "none": lambda line: line,
    "t-back": lambda line: "0.0001" + line[line.index(",") :],
    "cells": lambda line: line.replace(",", ",,", 1),
    "blank": lambda line: "\n" + line,
    "nan": lambda line: line.replace(",", ",nan", 1),
    "utf8": lambda line: line.replace(",", ",\xe9", 1),
    "stray-quote": lambda line: line.replace(",ok\n", ',"5 mm plate, edge\n'),
    "cut": lambda line: line.rstrip("\n").replace(",", ",x", 1),
}


@pytest.mark.parametrize("layout", ["lf", "lone-cr", "crlf"])
@pytest.mark.parametrize("notes", [0, 1, 3], ids=["no-note", "one-note", "notes"])
@pytest.mark.parametrize("change, row", [("none", 0), ("t-back", 3000), ("cells", 4999), ("blank", 2000), ("nan", 1200),
                                         ("utf8", 2200), ("stray-quote", 1500), ("stray-quote", 4999), ("cut", 4999)])  # fmt: skip
def test_quoted_lines_and_lone_crs_read_in_pieces_as_read_log(tmp_path: Path, monkeypatch, layout: str, notes: int,
                                                              change: str, row: int) -> None:  # fmt: skip
    """Blocks of 8 kB, windows of 4 kB: the rows read_log gives, or its error to the letter."""
    from softtip.errors import InputError
    from softtip.io.tables import NotStreamable, read_log

    if notes == 0 and layout == "lf":
        pytest.skip("plain lines: test_located_error_across_small_windows_is_read_logs")
    src, lines = _small_blocks_log(tmp_path, monkeypatch)
    for k in (30, 2600, 4000)[:notes]:  # notes before, between and after the changed rows
        lines[k] = lines[k][: -len("ok\n")] + _NOTE + "\n"
    lines[row + 1] = _CHANGES[change](lines[row + 1])
    src.write_bytes(_layout(lines, layout))
    blocks = iter_log(src, rows=1000)
    try:
        one = read_log(src)
    except InputError as exc:
        with pytest.raises(NotStreamable):
            for _ in blocks:
                pass
        assert str(blocks.locate_error()) == str(exc)
        return
    got = list(blocks)
    np.testing.assert_array_equal(np.concatenate([b[0] for b in got]), one.t)
    np.testing.assert_array_equal(np.concatenate([b[1] for b in got]), one.wrench)
    assert [c for b in got for c in b[2]["note"]] == list(one.extra["note"])
    assert blocks.warnings() == one.warnings


@pytest.mark.slow
def test_quoted_lines_and_lone_crs_in_pieces_in_bounded_memory(tmp_path: Path, plain_log: Path,
                                                                plain_in_pieces_quiet) -> None:  # fmt: skip
    """A quoted note over two lines (to a file, and with a bad last line) and lone CR line ends
    (onto standard output): no more memory than the plain log's run (they were read whole), the
    one-shot run's table, the one-shot run's message."""
    import csv

    note, cr, bad = (tmp_path / f"{name}.csv" for name in ("note", "cr", "bad"))
    lines = plain_log.read_text().splitlines(keepends=True)  # 200000 rows
    cr.write_bytes(_layout(lines, "lone-cr"))
    lines[101] = lines[101][: -len("ok\n")] + _NOTE + "\n"
    note.write_text("".join(lines))
    lines[-1] = lines[-1].replace(",", ",abc", 1)
    bad.write_text("".join(lines))
    code, base, plain_out = plain_in_pieces_quiet  # estimate plain.csv -q --chunk-rows 20000 -o p.csv
    assert code == 0
    code, to_file = _peak_mb("estimate", note, "-q", "--chunk-rows", 20000, "-o", tmp_path / "n.csv")
    assert code == 0
    code, to_stdout = _peak_mb("estimate", cr, "-q", "--chunk-rows", 20000)
    assert code == 0
    code, failed, _, err = _measured("estimate", bad, "-q", "--chunk-rows", 20000, "-o", tmp_path / "b.csv")
    assert code == 2
    assert max(to_file, to_stdout, failed) < base + 50, (base, to_file, to_stdout, failed)
    fx = lines[-1].split(",")[1]
    assert err == f"softtip: error: {bad}:200002: column 'fx': expected a number, got {fx!r}\n"
    # the plain log's estimates; the note carried (quoted piece by piece, so compared as cells),
    # row by row (lists of 200001 rows sliced took seconds): every cell but the note's the same
    with open(plain_out, newline="") as a, open(tmp_path / "n.csv", newline="") as b:
        rows = 0
        for rows, (row_a, row_b) in enumerate(itertools.zip_longest(csv.reader(a), csv.reader(b)), 1):
            assert row_a is not None and row_b is not None, rows  # as many rows in each
            note_b = row_b.pop()
            row_a.pop()
            assert row_a == row_b, rows
            if rows == 102:  # rows_b[101]
                assert note_b == _NOTE.strip('"')
    assert rows == 200001
    one = _stdout_run("estimate", cr, "-q")
    assert one.returncode == 0 and one.stdout == plain_out.read_bytes()  # lone CRs: the plain log's bytes
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.csv", "cr.csv", "n.csv", "note.csv"]


@pytest.mark.parametrize("noise", [["--force-noise", "0", "--moment-noise", "0"], ["--moment-noise", "40"]], ids=["lever-only", "noise"])
def test_wrong_units_after_pieces_went_to_standard_output_name_the_pairs_that_fit(tmp_path: Path, noise: list) -> None:
    """Moments in N·mm read as N·m, the tare's noise not telling (a sensor noise given to fit) or
    fitting none: the lever vote over every piece fails after pieces went onto standard output. The
    message names the unit pairs that fit and their options as the one-shot run's does (it said only
    'give --units')."""
    from softtip.io.examples import load_example
    from softtip.io.tables import write_table

    ex = load_example()
    t = np.concatenate([ex.t + k * (ex.t[-1] + ex.t[1]) for k in range(4)])
    w = np.tile(ex.wrench, (4, 1)) * np.array([1, 1, 1, 1e3, 1e3, 1e3])
    src = tmp_path / "nmm.csv"
    write_table({"t": t, **{c: w[:, i] for i, c in enumerate(("fx", "fy", "fz", "mx", "my", "mz"))}}, src)
    one = _stdout_run("estimate", src, "-q", *noise, "-o", tmp_path / "one.csv")
    done = _stdout_run("estimate", src, "-q", *noise, "--chunk-rows", 500)
    assert one.returncode == done.returncode == 2
    said, err = one.stderr.decode(), done.stderr.decode()
    assert "standard output: 2000 rows were written before the error below" in err
    # the same samples, and the same pairs named (or none)
    assert "over 1568 samples with |f| ≥ 0.1 N, read in N and N·m)" in said and "over 1568 samples with |f| ≥ 0.1 N, read in N and N·m)" in err
    fits = said.split("read in N and N·m), but the fingertip reaches only 42.1 mm: ")[1]
    assert err.endswith(f"read in N and N·m): {fits}") and "the fingertip's reach (42.1 mm)" in err
    # named whether or not the noise fits a pair (the lever rules the units read out; the message says which)
    assert "--moment-units N*mm" in fits
    assert ("the noise while taring fits no unit pair" in fits) == (noise[1] != "0")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["nmm.csv"]
