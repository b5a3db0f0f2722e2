"""Reading force/torque logs and writing result tables (CSV).

Input logs (SPEC §4) are CSV files with a header row naming at least the columns
``t, fx, fy, fz, mx, my, mz`` in any order; other columns are kept as text and otherwise
ignored. ``t`` is in seconds; the wrench is in SI or, on request, in the papers' kgf and
kgf·mm, and is converted to SI on reading.

Accepted layout, beyond plain CSV:

* a UTF-8 byte-order mark, CRLF or LF line ends, quoted cells (the stdlib :mod:`csv` dialect);
* blank lines and lines starting with ``#`` (comments) **before** the header are skipped;
* blank lines at the end of the file are ignored. A blank line between data rows is an error.
* header names are compared after stripping surrounding whitespace, with exact case.

Every problem with an input log raises :class:`~softtip.errors.InputError` naming the file,
the line (1-based, as a text editor counts, header included), the column where one
applies, and what was expected. The first problem in file order is the one reported.

Output tables are written atomically when going to a path: a failure never leaves a
partial file behind and never touches an existing file at the destination.
"""

from __future__ import annotations

import csv
import difflib
import gc
import io
import itertools
import math
import os
import sys
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, TextIO

import numpy as np
from numpy.typing import NDArray

from softtip.errors import InputError
from softtip.units import UNIT_SYSTEMS, wrench_to_si

__all__ = ["Log", "read_log", "write_table", "REQUIRED_COLUMNS"]

#: Columns every input log must have, in wrench order after ``t``.
REQUIRED_COLUMNS: tuple[str, ...] = ("t", "fx", "fy", "fz", "mx", "my", "mz")
_EXPECTED_HEADER = ", ".join(REQUIRED_COLUMNS)

# Rows parsed (read) or formatted (write) per block: bounds the number of live Python
# string objects, which dominate memory and time for 1e6-row files.
_CHUNK_ROWS = 65536

# Header names people use for time; difflib alone does not connect them to "t".
_TIME_ALIASES = frozenset({"time", "times", "timestamp", "ts", "sec", "secs", "seconds"})

# Characters that force a CSV cell to be quoted.
_CSV_SPECIAL = (",", '"', "\n", "\r")


@dataclass(frozen=True, eq=False)
class Log:
    """A force/torque log, in SI.

    ``eq=False``: comparing two logs element-wise is left to numpy; identity equality
    avoids the ambiguous truth value of array fields.

    Attributes
    ----------
    t : ndarray of float64, shape (N,)
        Sample times, s, strictly increasing.
    wrench : ndarray of float64, shape (N, 6)
        ``fx, fy, fz`` in N and ``mx, my, mz`` in N·m, sensor frame.
    extra : dict of str to list of str
        The input's other columns, in input order, each a list of N cells kept as the
        original text (surrounding whitespace included).
    source : str
        The file name as given, or the stream's name (``"<stdin>"``).
    units : str
        The units the file was read in, ``"si"`` or ``"kgf-mm"`` (``wrench`` is SI anyway).
    """

    t: NDArray[np.float64]
    wrench: NDArray[np.float64]
    extra: dict[str, list[str]]
    source: str
    units: str


# --------------------------------------------------------------------------------------
# reading


def read_log(path: str | os.PathLike[str] | TextIO, units: str = "si") -> Log:
    """Read a force/torque log from a CSV file or text stream.

    Parameters
    ----------
    path : str, path-like or text stream
        File to read, or an open stream (``sys.stdin``, ``io.StringIO``; a binary stream
        is decoded as UTF-8). A stream is read to its end and not closed.
    units : {"si", "kgf-mm"}
        Units of the wrench columns in the file: ``"si"`` (N, N·m) or ``"kgf-mm"`` (kgf,
        kgf·mm; 1 kgf = 9.80665 N). ``t`` is always in seconds.

    Returns
    -------
    Log
        ``t`` shape (N,) in s, ``wrench`` shape (N, 6) in N and N·m, N ≥ 1.

    Raises
    ------
    InputError
        Unknown ``units``; file missing, unreadable or not UTF-8; empty file; no data rows;
        missing or duplicate columns; a row with the wrong number of cells; an empty,
        non-numeric, NaN or infinite cell in a required column; ``t`` not strictly
        increasing; a blank line between data rows. The message names the file, the line
        and the column, and says what was expected. The first problem in file order wins.
    """
    source = _source_name(path)
    if units not in UNIT_SYSTEMS:
        raise InputError(f"{source}: unknown units {units!r}; expected one of: {', '.join(UNIT_SYSTEMS)}")
    text = _read_text(path, source)
    t, wrench, extra = _parse(text, source)
    return Log(t=t, wrench=wrench_to_si(wrench, units), extra=extra, source=source, units=units)


def _source_name(path: str | os.PathLike[str] | TextIO) -> str:
    if hasattr(path, "read"):
        name = getattr(path, "name", None)
        # A stream opened on a file descriptor has an int name; it tells the user nothing.
        return name if isinstance(name, str) else "<stream>"
    return os.fspath(path) if not isinstance(path, bytes) else os.fsdecode(path)


def _read_text(path: str | os.PathLike[str] | TextIO, source: str) -> str:
    """Whole input as text, BOM removed; every failure becomes an :class:`InputError`."""
    try:
        if hasattr(path, "read"):
            data = path.read()
        else:
            with open(path, "rb") as fh:
                data = fh.read()
    except FileNotFoundError:
        raise InputError(f"{source}: file not found; expected an existing CSV log file") from None
    except IsADirectoryError:
        raise InputError(f"{source}: is a directory; expected a CSV log file") from None
    except PermissionError:
        raise InputError(f"{source}: permission denied; expected a readable CSV log file") from None
    except UnicodeDecodeError as exc:
        # A text stream (e.g. stdin) decoding on the fly: no byte offset into the file.
        raise InputError(f"{source}: not valid UTF-8 ({exc.reason}); expected UTF-8 text") from None
    except OSError as exc:
        raise InputError(
            f"{source}: cannot read ({exc.strerror or exc}); expected a readable CSV log file"
        ) from None

    if isinstance(data, str):
        return data[1:] if data.startswith("\ufeff") else data
    data = bytes(data)
    skip = 3 if data.startswith(b"\xef\xbb\xbf") else 0
    try:
        return data[skip:].decode("utf-8")
    except UnicodeDecodeError as exc:
        offset = skip + exc.start
        line = data.count(b"\n", 0, offset) + 1
        raise InputError(
            f"{source}:{line}: not valid UTF-8 (byte 0x{data[offset]:02x} at byte offset {offset}); "
            "expected a UTF-8 text file (re-save it as UTF-8)"
        ) from None


def _is_blank(row: list[str]) -> bool:
    return not row or (len(row) == 1 and not row[0].strip())


class _Suspect(Exception):
    """Raised by the fast parser when something is off; the careful one says what.

    ``resume`` is where the careful parser may start: ``(text position, csv line_num)`` at
    the start of a block that precedes the problem, with no problem before it.
    """

    def __init__(self, resume: tuple[int, int]) -> None:
        super().__init__(resume)
        self.resume = resume


@dataclass
class _Header:
    names: list[str]  # stripped header names
    line: int  # line number of the header (its first line)
    data_base: int  # a data record's physical line = data_base + csv line_num
    lines: io.StringIO  # the text, positioned just after the header record
    comments: list[tuple[int, str]]  # (line, text) of the comment lines before the header


def _parse(text: str, source: str) -> tuple[NDArray[np.float64], NDArray[np.float64], dict[str, list[str]]]:
    """``t`` (N,), wrench (N, 6) in the file's units, and the extra columns."""
    header = _read_header(text, source)
    index = _column_index(header, source)
    # Millions of small lists/strings trigger the cyclic GC over and over (quadratic-ish);
    # none of them form cycles.
    gc_was_enabled = gc.isenabled()
    gc.disable()
    start = (header.lines.tell(), 0)
    try:
        try:
            return _parse_fast(header, index)
        except _Suspect as suspect:
            resume = suspect.resume
        # Re-read row by row from just before the problem: on a 1e6-row file with a bad last
        # row this costs one block, not the whole file again.
        found = _parse_careful(header, index, source, resume)  # normally raises
        if resume != start:
            # Nothing wrong after all (not expected): never return a partial log.
            found = _parse_careful(header, index, source, start)
        return found
    finally:
        if gc_was_enabled:
            gc.enable()


def _read_header(text: str, source: str) -> _Header:
    lines = io.StringIO(text, newline="")
    lineno = 0
    comments: list[tuple[int, str]] = []
    for line in lines:
        lineno += 1
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith("#"):
            comments.append((lineno, stripped))
            continue
        break
    else:
        what = "only comments and blank lines" if comments else "empty file"
        raise InputError(f"{source}: {what}; expected a CSV header row naming {_EXPECTED_HEADER}")

    reader = csv.reader(itertools.chain([line], lines))
    try:
        names = [name.strip() for name in next(reader)]
    except csv.Error as exc:
        raise InputError(f"{source}:{lineno}: malformed CSV header ({exc}); expected {_EXPECTED_HEADER}") from None
    # csv pulls lines one at a time, so ``lines`` now sits right after the header record.
    data_base = lineno - 1 + reader.line_num
    return _Header(names=names, line=lineno, data_base=data_base, lines=lines, comments=comments)


def _column_index(header: _Header, source: str) -> dict[str, int]:
    """Map each required column to its position; raise on duplicate or missing names."""
    names, line = header.names, header.line
    seen: dict[str, int] = {}
    for j, name in enumerate(names):
        if name in seen:
            raise InputError(
                f"{source}:{line}: duplicate column {name!r} (columns {seen[name] + 1} and {j + 1}); "
                "expected each column name once"
            )
        seen[name] = j

    missing = [c for c in REQUIRED_COLUMNS if c not in seen]
    if missing:
        msg = (
            f"{source}:{line}: missing column{'s' if len(missing) > 1 else ''} "
            f"{', '.join(repr(c) for c in missing)}; expected a header with columns "
            f"{_EXPECTED_HEADER} (any order, exact case)"
        )
        hints = _near_misses(missing, names)
        if len(names) == 1:
            for delim, label in ((";", "semicolon"), ("\t", "tab")):
                if delim in names[0]:
                    hints.append(f"The header looks {label}-separated; expected commas between columns.")
        # numpy.savetxt(header=...) writes "# t,fx,...": point at it rather than guess.
        commented = [
            ln
            for ln, text in header.comments
            if set(REQUIRED_COLUMNS) <= {x.strip() for x in text.lstrip("#").split(",")}
        ]
        if commented:
            hints.append(f"Line {commented[-1]} looks like the header commented out with '#'; remove the '#'.")
        elif all(_is_number(n) for n in names):
            hints.append(f"Line {line} looks like data; expected the header row first.")
        raise InputError(" ".join([msg + ".", *hints]) if hints else msg)
    return {c: seen[c] for c in REQUIRED_COLUMNS}


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def _near_misses(missing: list[str], names: list[str]) -> list[str]:
    """'did you mean' hints: header names that look like a missing required column.

    Names are compared after lower-casing and dropping everything but letters and digits,
    so ``Fx``, ``f_x``, ``f x`` and ``fx [N]`` all point at ``fx``.
    """

    def norm(s: str) -> str:
        return "".join(ch for ch in s.lower() if ch.isalnum())

    # Only names that are not already a required column can be the misspelling.
    candidates = {j: norm(n) for j, n in enumerate(names) if n not in REQUIRED_COLUMNS}
    hints = []
    for col in missing:
        best: int | None = None
        for j, cand in candidates.items():
            if cand == col or (col == "t" and cand in _TIME_ALIASES):
                best = j
                break
        if best is None:
            match = difflib.get_close_matches(col, list(candidates.values()), n=1, cutoff=0.6)
            if match:
                best = next(j for j, cand in candidates.items() if cand == match[0])
        if best is not None:
            hints.append(f"Column {best + 1} is {names[best]!r}: did you mean {col!r}?")
            del candidates[best]
    return hints


def _parse_fast(
    header: _Header, index: dict[str, int]
) -> tuple[NDArray[np.float64], NDArray[np.float64], dict[str, list[str]]]:
    """Parse a well-formed log in blocks; raise :class:`_Suspect` at the first oddity.

    Work per block is in C (csv, ``zip``, numpy's string-to-float), so a 1e6-row log takes
    a few seconds. Error reporting is left to :func:`_parse_careful`.
    """
    ncol = len(header.names)
    reader = csv.reader(header.lines)
    extra_idx = [j for j, name in enumerate(header.names) if j not in index.values()]
    extra: dict[str, list[str]] = {header.names[j]: [] for j in extra_idx}
    blocks: list[NDArray[np.float64]] = []
    last_t = -math.inf
    # Block starts as (text position, line_num): csv pulls whole lines only when asked, so
    # between blocks the stream sits exactly after the last record read.
    previous = current = (header.lines.tell(), 0)
    first_blank_block: tuple[int, int] | None = None  # start of the block with the first blank row
    try:
        while True:
            previous, current = current, (header.lines.tell(), reader.line_num)
            rows = list(itertools.islice(reader, _CHUNK_ROWS))
            if not rows:
                break
            k = len(rows)
            while k and _is_blank(rows[k - 1]):
                k -= 1
            if k and first_blank_block is not None:
                raise _Suspect(first_blank_block)  # data after a blank line
            if k < len(rows):
                if first_blank_block is None:
                    first_blank_block = current
                rows = rows[:k]
            if not rows:
                continue
            if set(map(len, rows)) != {ncol}:
                raise _Suspect(previous)
            cols = list(zip(*rows))
            block = np.empty((len(rows), 7))
            for i, name in enumerate(REQUIRED_COLUMNS):
                block[:, i] = np.array(cols[index[name]], dtype=np.float64)
            t = block[:, 0]
            if not np.isfinite(block).all() or t[0] <= last_t or not (np.diff(t) > 0).all():
                raise _Suspect(previous)  # from the previous block: t's predecessor is there
            last_t = t[-1]
            blocks.append(block)
            for j in extra_idx:
                extra[header.names[j]].extend(cols[j])
    except (ValueError, csv.Error):  # a non-numeric cell, or csv's own complaints
        raise _Suspect(previous) from None
    if not blocks:
        raise _Suspect(previous)  # header only: the careful parser words it
    data = np.concatenate(blocks) if len(blocks) > 1 else blocks[0]
    return np.ascontiguousarray(data[:, 0]), np.ascontiguousarray(data[:, 1:]), extra


def _parse_careful(
    header: _Header, index: dict[str, int], source: str, start: tuple[int, int]
) -> tuple[NDArray[np.float64], NDArray[np.float64], dict[str, list[str]]]:
    """Row-by-row parse that raises the first problem in file order, with its line.

    Starts at ``start`` = ``(text position, csv line_num)`` of a record boundary in the data
    (``line_num`` 0: the first data record). Returns the rows from there if, against
    expectation, nothing is wrong.
    """
    names = header.names
    ncol = len(names)
    # Required cells are checked left to right as they appear in the file.
    checks = sorted((j, name) for name, j in index.items())
    extra_idx = [j for j in range(ncol) if j not in index.values()]
    header.lines.seek(start[0])
    reader = csv.reader(header.lines)
    # A record ends on line base + line_num and starts one after the previous one ended.
    base = header.data_base + start[1]
    values: list[list[float]] = []
    extra: dict[str, list[str]] = {names[j]: [] for j in extra_idx}
    prev_end = 0
    first_blank: int | None = None
    last_t, last_t_text, last_t_line = -math.inf, "", 0
    while True:
        try:
            row = next(reader)
        except StopIteration:
            break
        except csv.Error as exc:
            raise InputError(
                f"{source}:{base + reader.line_num}: malformed CSV ({exc}); expected {ncol} cells"
            ) from None
        line = base + prev_end + 1
        prev_end = reader.line_num
        if _is_blank(row):
            if first_blank is None:
                first_blank = line
            continue
        if first_blank is not None:
            raise InputError(
                f"{source}:{first_blank}: blank line between data rows (data continues on line {line}); "
                "expected blank lines only at the end of the file"
            )
        if len(row) != ncol:
            raise InputError(
                f"{source}:{line}: expected {ncol} cells (one per header column), got {len(row)}"
            )
        sample = [0.0] * 7
        for j, name in checks:
            cell = row[j]
            where = f"{source}:{line}: column {name!r}"
            if not cell.strip():
                raise InputError(f"{where}: empty cell; expected a number")
            try:
                value = float(cell)
            except ValueError:
                raise InputError(f"{where}: expected a number, got {cell!r}") from None
            if not math.isfinite(value):
                raise InputError(f"{where}: expected a finite number, got {cell!r}")
            if name == "t":
                if not value > last_t:
                    raise InputError(
                        f"{where}: expected t strictly increasing, got t = {cell.strip()} on line {line} "
                        f"after t = {last_t_text} on line {last_t_line}"
                    )
                last_t, last_t_text, last_t_line = value, cell.strip(), line
            sample[REQUIRED_COLUMNS.index(name)] = value
        values.append(sample)
        for j in extra_idx:
            extra[names[j]].append(row[j])
    if not values and start[1] == 0:
        raise InputError(
            f"{source}:{header.line}: header only, no data rows; expected at least one row of "
            f"{_EXPECTED_HEADER} after the header"
        )
    data = np.array(values, dtype=np.float64).reshape(-1, 7)
    return np.ascontiguousarray(data[:, 0]), np.ascontiguousarray(data[:, 1:]), extra


# --------------------------------------------------------------------------------------
# writing


def write_table(
    columns: Mapping[str, Sequence[Any] | np.ndarray],
    dest: str | os.PathLike[str] | None | TextIO,
    *,
    float_format: str = "%.10g",
) -> None:
    """Write columns as a CSV table with a header row.

    Parameters
    ----------
    columns : mapping of str to 1-D sequence or array, each of length N
        Header names (in mapping order) and their values. Floating-point columns are
        formatted with ``float_format`` (NaN as ``nan``); booleans as ``0``/``1``; integers,
        strings and anything else with ``str``. Cells containing a comma, quote or line
        break are quoted as CSV requires. Values are written as given: convert units first.
    dest : str, path-like, text stream or None
        ``None`` writes to ``sys.stdout``; a stream is written to and left open; a path is
        written atomically (a temporary file in the same directory, then ``os.replace``):
        on any failure the temporary file is removed and an existing file at ``dest`` is
        left untouched.
    float_format : str
        A printf-style format for one float, e.g. ``"%.10g"`` (default) or ``"%.17g"``
        (round-trips float64 exactly).

    Raises
    ------
    ValueError
        No columns, a column that is not 1-D, columns of different lengths, or a
        ``float_format`` that does not format exactly one float into a plain cell.
    InputError
        ``dest`` cannot be created or replaced (missing directory, no permission, a
        directory at ``dest``). It is a ``ValueError`` too.
    """
    plan = _plan_table(columns, float_format)
    if dest is None:
        _write_rows(sys.stdout, plan)
    elif hasattr(dest, "write"):
        _write_rows(dest, plan)  # type: ignore[arg-type]
    else:
        _write_atomic(os.fspath(dest), plan)  # type: ignore[arg-type]


@dataclass
class _Plan:
    header: str
    row_format: str  # one row's % format, ending in "\n"
    converters: list[Callable[[np.ndarray], list[Any]]]
    arrays: list[np.ndarray]
    n: int


def _plan_table(columns: Mapping[str, Sequence[Any] | np.ndarray], float_format: str) -> _Plan:
    """Validate the columns and decide each one's cell format, before touching ``dest``."""
    if not columns:
        raise ValueError("write_table: no columns; expected at least one")
    try:
        probe = float_format % (1.5,)
    except (TypeError, ValueError) as exc:
        raise ValueError(
            f"float_format {float_format!r} must format exactly one float, e.g. '%.10g' ({exc})"
        ) from None
    if any(ch in probe for ch in _CSV_SPECIAL):
        raise ValueError(
            f"float_format {float_format!r} gives {probe!r}; expected no comma, quote or line break"
        )

    arrays: list[np.ndarray] = []
    specs: list[str] = []
    converters: list[Callable[[np.ndarray], list[Any]]] = []
    lengths: dict[str, int] = {}
    for name, values in columns.items():
        arr = np.asarray(values)
        if arr.ndim != 1:
            raise ValueError(f"column {name!r}: expected a 1-D sequence, got shape {arr.shape}")
        lengths[str(name)] = len(arr)
        kind = arr.dtype.kind
        if kind == "f":
            arr = arr.astype(np.float64, copy=False)
            specs.append(float_format)
            converters.append(_to_list)
        elif kind == "b":
            arr = arr.astype(np.int8)
            specs.append("%d")
            converters.append(_to_list)
        elif kind in "iu":
            specs.append("%d")
            converters.append(_to_list)
        elif kind == "U":
            specs.append("%s")
            converters.append(_str_cells)
        else:  # bytes, objects, complex, datetimes: their str(), quoted when needed
            specs.append("%s")
            converters.append(_object_cells)
        arrays.append(arr)
    if len(set(lengths.values())) > 1:
        detail = ", ".join(f"{k!r}: {v}" for k, v in lengths.items())
        raise ValueError(f"columns have different lengths ({detail}); expected all the same")
    header = ",".join(_quote(str(name)) for name in columns) + "\n"
    return _Plan(header, ",".join(specs) + "\n", converters, arrays, next(iter(lengths.values())))


def _to_list(a: np.ndarray) -> list[Any]:
    return a.tolist()


def _quote(cell: str) -> str:
    if any(ch in cell for ch in _CSV_SPECIAL):
        return '"' + cell.replace('"', '""') + '"'
    return cell


def _str_cells(a: np.ndarray) -> list[str]:
    cells = a.tolist()
    # One C-level scan of the block decides whether any cell needs quoting at all.
    joined = "".join(cells)
    if any(ch in joined for ch in _CSV_SPECIAL):
        cells = [_quote(c) for c in cells]
    return cells


def _object_cells(a: np.ndarray) -> list[str]:
    cells = [x.decode("utf-8", "replace") if isinstance(x, bytes) else str(x) for x in a.tolist()]
    return [_quote(c) for c in cells]


def _write_rows(out: TextIO, plan: _Plan) -> None:
    """Write header and rows in blocks.

    Each block is formatted by one ``%`` on a repeated row format: the loop over cells
    runs in C, which beats per-cell Python formatting and ``np.char.mod``.
    """
    out.write(plan.header)
    for start in range(0, plan.n, _CHUNK_ROWS):
        stop = min(start + _CHUNK_ROWS, plan.n)
        cols = [conv(a[start:stop]) for conv, a in zip(plan.converters, plan.arrays)]
        cells = tuple(itertools.chain.from_iterable(zip(*cols)))
        out.write((plan.row_format * (stop - start)) % cells)


def _write_atomic(path: str, plan: _Plan) -> None:
    from softtip.atomic import atomic_write

    with atomic_write(path) as fh:
        _write_rows(fh, plan)
