"""Reading force/torque logs and writing result tables (CSV, Parquet and Arrow IPC / Feather v2).

Input logs (see the manual, docs/manual.md, and docs/guide/input-formats.md) are CSV files with a
header row naming at least the columns ``t, fx, fy, fz, mx, my, mz`` in any order, or Parquet
or Arrow IPC files (by the name's extension, :func:`softtip.io.formats.table_format`:
``.parquet``; ``.arrow`` or ``.feather``) with those columns; other columns are kept and
otherwise ignored. ``t`` is non-decreasing: a repeated stamp is accepted and counted, a stamp
that goes back is an error. Everything is converted to SI (s, N, N·m) here, at the edge, and
nowhere else.

Accepted CSV layout, beyond plain CSV:

* a UTF-8 byte-order mark, CRLF or LF line ends, quoted cells (the stdlib :mod:`csv` dialect);
  a quoted cell may span lines, but not take in lines that look like data rows (a stray or
  unterminated quote is an error naming its line: the rows read equal the file's);
* comma, tab or semicolon delimiters (sniffed from the header line), a decimal comma with tab
  or semicolon; gzip, bzip2, xz and zstd compression (by the first bytes);
* blank lines and lines starting with ``#`` (comments) **before** the header are skipped, and
  so are preamble lines before the first line that names the columns (or ``skip_rows``);
* blank lines at the end of the file are ignored. A blank line between data rows is an error;
* the headers of the sources in :data:`softtip.io.formats.SOURCES` (ATI, ``rostopic echo
  -p``, ``ros2 topic echo --csv`` without a header, PlotJuggler, bag converters), case-
  insensitively, with units in the header (``Fx (N)``, ``Tz (N-mm)``); ``columns`` maps
  anything else. Per-quantity units (:data:`softtip.core.units.UNITS`) for columns whose
  header gives none; absolute stamps counted from the first (kept as ``stamp_ns``), integer
  ns divided exactly so that a bag and a CSV of it give the same ``t`` to the last bit.

Every problem with an input log raises :class:`~softtip.errors.InputError` naming the file,
the line (1-based, as a text editor counts, header included; Parquet: the row), the column
where one applies, and what was expected. The first problem in file order is the one
reported. What is suspicious but not wrong goes to :attr:`Log.warnings`: repeated stamps,
a time scale no force/torque sensor has (``t`` in ms, µs or ns), a file that ends inside a
line whose last number is shorter than on the lines before (cut while being written).

Engine, chosen by measurement (a 1e6-row, 93 MB log; 2-core machine shared with other
work, so ranges): pyarrow's C++ CSV reader on one thread parses it in 0.27–0.34 s, its
default threads 0.37–0.47 s, pandas' C engine 0.27–0.47 s, softtip's former hand-written
Python reader 3.8–4.3 s. pyarrow is needed for Parquet anyway and pandas is not otherwise
used, so CSV goes through pyarrow; the Python parser stays only to word an error (and for
the odd cell pyarrow does not take but Python's ``float`` does, such as ``1_000``). In one
run of ``python benchmarks/bench_core.py --only end-to-end`` (same machine, busy) reading
that log took 0.51 s of CPU against 3.44 s for the former reader, and writing the 46
columns ``softtip estimate`` had then (47 now) for it 4.3 s (pyarrow's CSV writer formatting 46 M numbers,
~90 ns each) against 16 s for the former writer; Parquet: read 0.19 s, write 0.60 s (2.40 s
with pyarrow's default dictionary encoding of every column). CSV numbers are now formatted by a
compiled loop where numba is installed (:mod:`softtip.io._csvtext`, the same bytes; 18 ns
per number against 83 ns for the fallback in ``python benchmarks/bench_core.py --only bounds``,
48-59 before its digits were made a word at a time). pandas' C
engine, measured in pyarrow's place on the same 93 MB (1e6 rows, 7 columns; seven runs): 0.28-0.46 s
of CPU against pyarrow's 0.27-0.42 s, the same values (re-measured with ``--only bounds``: 0.27
against 0.26 s): not faster beyond the noise, and not a dependency; pyarrow stays.

Output tables are written atomically when going to a path: a failure never leaves a
partial file behind and never touches an existing file at the destination.

Logs larger than memory: :func:`iter_log` reads a CSV or Parquet file block by block with
the values and warnings of :func:`read_log`, and :class:`TableWriter` writes a table piece
by piece (``softtip estimate`` uses both through :mod:`softtip.apps.chunked`).
"""

from __future__ import annotations

import contextlib
import csv
import difflib
import gc
import io
import itertools
import math
import os
import re
import sys
from collections import deque
from collections.abc import Callable, Iterable, Mapping, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, replace
from typing import Any, BinaryIO, NamedTuple, TextIO

import numpy as np
from numpy.typing import NDArray

from softtip.core.units import (
    PLAUSIBLE_RATE_HZ,
    UNIT_SYSTEM_UNITS,
    UNIT_SYSTEMS,
    Unit,
    find_unit,
    get_unit,
    seconds_from_ns,
    unit_names,
    wrench_scale,
    wrench_to_si,
)
from softtip.errors import InputError
from softtip.io.formats import (
    ROLE_QUANTITY,
    ROLES,
    TABLE_FORMATS,
    ColumnAbsent,
    ColumnError,
    ColumnMap,
    LogFormat,
    parse_column_spec,
    recognised_roles,
    resolve_columns,
    stated_unit,
    table_format,
)

__all__ = [
    "REQUIRED_COLUMNS", "Log", "LogBlocks", "NotStreamable", "PreparedRows", "TableWriter", "iter_log", "read_log",
    "write_table",
]  # fmt: skip

#: Columns every input log must have, in wrench order after ``t``.
REQUIRED_COLUMNS: tuple[str, ...] = ("t", "fx", "fy", "fz", "mx", "my", "mz")
_EXPECTED_HEADER = ", ".join(REQUIRED_COLUMNS)

# Rows parsed (read) or formatted (write) per block: bounds the number of live Python
# string objects, which dominate memory and time for 1e6-row files.
_CHUNK_ROWS = 65536
#: Threads that format CSV blocks at once (at most the machine's cores).
_WRITE_THREADS = 4

# Header names people use for time; difflib alone does not connect them to "t".
_TIME_ALIASES = frozenset({"time", "times", "timestamp", "ts", "sec", "secs", "seconds"})

#: Cells read as missing (empty) in a required column: pyarrow's CSV reader's default null values,
#: written out so that the row-by-row parser, which words the errors, reads the same ones.
_NULL_CELLS = frozenset(("", "#N/A", "#N/A N/A", "#NA", "-1.#IND", "-1.#QNAN", "-NaN", "-nan", "1.#IND", "1.#QNAN",
                         "N/A", "NA", "NULL", "NaN", "n/a", "nan", "null",
                         "nan(ind)", "-nan(ind)"))  # fmt: skip  (the last two: Microsoft's C library's NaN)

#: What an error about a missing or NaN cell adds: the options that read such a log.
_MISSING_FIX = "; or give --missing drop (skip the row) or --missing interpolate (fill it)"

#: The name given a header's unnamed column (a spreadsheet's empty one), then its position: no
#: header holds it (a control character), and no output does (:func:`_finish` drops the column).
_UNNAMED = "\x00column "

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
        Sample times, s, non-decreasing (a stamp may repeat; see ``repeated_t``).
    wrench : ndarray of float64, shape (N, 6)
        ``fx, fy, fz`` in N and ``mx, my, mz`` in N·m, sensor frame.
    extra : dict of str to list of str or ndarray
        The input's other columns, in input order, N values each: from CSV a list of the
        cells' original text (surrounding whitespace included); from Parquet an array of
        the column's values. Absolute stamps add ``stamp_ns`` (int64 ns, :attr:`stamps_ns`).
    source : str
        The file name as given, or the stream's name (``"<stdin>"``).
    units : str
        The units the file was read in, ``"si"`` or ``"kgf-mm"`` (``wrench`` is SI anyway).
    repeated_t : int
        Samples whose ``t`` equals the one before (accepted, counted).
    warnings : tuple of str
        What looked wrong without being an error, each naming the file (and the line where
        one applies): repeated stamps, an implausible time scale (``t`` in ms, µs or ns
        instead of s), a last line cut while the file was written. A command line tool
        prints them; a library user may check them.
    first_line : int or None
        The CSV line (1-based) of the first data row when every row is one line (row ``i`` is
        then on line ``first_line + i``), for messages about a row; ``None`` where rows are
        named by number (Parquet, a quoted cell spanning lines, a bag).
    notes : tuple of str
        How a file not in softtip's own layout was read: which column was taken for what,
        in which unit; lines skipped before the header; absolute stamps; rows with missing
        cells dropped or filled. A command line tool prints them.
    force_unit, moment_unit : str
        The units the wrench columns were in (names of :data:`softtip.core.units.UNITS`).
    units_in_header : tuple of str
        The wrench columns whose unit the file gave: the header, a row of units under it, or a
        line before it (``Torque Units,N-mm``).
    time_suspect : str or None
        The warning about ``t``'s scale when its unit was not given and another one fits
        (``t`` in ms read as s): a command line tool stops with it (``--time-units``).
    """

    t: NDArray[np.float64]
    wrench: NDArray[np.float64]
    extra: dict[str, Any]
    source: str
    units: str
    repeated_t: int = 0
    warnings: tuple[str, ...] = ()
    first_line: int | None = None
    notes: tuple[str, ...] = ()
    force_unit: str = "N"
    moment_unit: str = "N*m"
    time_suspect: str | None = None
    units_in_header: tuple[str, ...] = ()

    @property
    def stamps_ns(self) -> NDArray[np.int64] | None:
        """The absolute stamps, ns since the Unix epoch, that ``t`` counts from (the column
        ``stamp_ns`` the reader added, or one the file had); ``None`` without any."""
        stamps = self.extra.get("stamp_ns")
        if stamps is None:
            return None
        return _whole_ns(stamps)


#: A time stamp from this many seconds on is absolute (after 1973 in Unix time): ``t`` counts from the first.
ABSOLUTE_STAMP_S = 1e8
#: ... and up to this many (2261 in Unix time): its nanoseconds fit int64 (to 2262), as ``stamp_ns`` keeps them.
LATEST_STAMP_S = 9.2e9


def _dating_units(first: float, units: tuple[str, ...]) -> list[str]:
    """The time units among ``units`` that make a first stamp ``first`` a date (Unix time from
    :data:`ABSOLUTE_STAMP_S` to :data:`LATEST_STAMP_S`)."""
    return [u for u in units if ABSOLUTE_STAMP_S <= first * get_unit(u, "time").si < LATEST_STAMP_S]


def _to_seconds(t: NDArray[np.float64], si: float) -> NDArray[np.float64]:
    """``t`` in a unit of ``si`` seconds as seconds: divided by 1000, 1e6 or 1e9 (exact, so correctly
    rounded: ``3900`` ms gives the float ``3.9``, as the text ``"3.9"`` does), not multiplied by 1e-3."""
    if si == 1.0:
        return t
    per_second = round(1.0 / si)
    return t / float(per_second) if abs(per_second * si - 1.0) < 1e-12 else t * si


def _to_seconds_like(wrench: NDArray[np.float64], scale: NDArray[np.float64]) -> NDArray[np.float64]:
    """Each column times its ``scale``, dividing by an exact power of ten where the scale is one's
    inverse (N·mm: ``/ 1000``, correctly rounded), multiplying otherwise. SI columns: ``wrench``
    itself (each value would be divided by 1)."""
    if (scale == 1.0).all():
        return wrench
    out = np.empty_like(wrench)
    for k, si in enumerate(scale):
        out[:, k] = _to_seconds(wrench[:, k], float(si))
    return out


def _units_label(force: str, moment: str) -> str:
    """``"si"``/``"kgf-mm"`` for the presets, else ``"N, N*mm"``."""
    for name, pair in UNIT_SYSTEM_UNITS.items():
        if pair == (force, moment):
            return name
    return f"{force}, {moment}"


def _finish(
    t: NDArray[Any], wrench: NDArray[np.float64], extra: dict[str, Any], header: _Header, fmt: LogFormat,
    source: str, units: str, first_line: int | None, raw: bytes | None,
) -> Log:
    """The :class:`Log` of parsed columns: missing cells, time unit and origin, wrench units, notes."""
    cmap = header.cmap
    names = header.names
    named = "name" if header.columnar else "header"
    notes: list[str] = []

    def where(i: int) -> str:
        return f"line {first_line + i}" if first_line is not None else f"data row {i + 1}"

    def at(i: int) -> str:
        """A message's start for data row ``i``: ``file:line``, or ``file: data row``."""
        return f"{source}:{first_line + i}" if first_line is not None else f"{source}: {where(i)}"

    unnamed = [name for name in extra if name.startswith(_UNNAMED)]
    for name in unnamed:  # a spreadsheet's empty columns: dropped; one that holds values has no name to go by
        cells = np.asarray(extra.pop(name), dtype=object)
        held = np.flatnonzero([not (c != c or not str(c).strip()) for c in cells.tolist()])
        if len(held):
            raise InputError(
                f"{source}:{header.line}: column {name[len(_UNNAMED):]} has no name in the header but holds values "
                f"(the first on {where(int(held[0]))}: {cells[held[0]]!r}); expected a name for each column that holds values"
            )
    if unnamed:
        notes.append(f"{source}: {len(unnamed)} empty column(s) without a name in the header (a spreadsheet's: "
                     f"{', '.join(n[len(_UNNAMED):] for n in unnamed)}) left out")  # fmt: skip

    own = header.t_stated and all(names[cmap.index[r]] == r for r in ROLES) if cmap is not None else False
    read_as = cmap is not None and not cmap.native(names) and not own  # softtip's own file: its metadata's units
    if read_as:
        notes.append(f"{source}: read as {cmap.source}: {cmap.describe(names, named)}")
    if header.preamble:
        notes.append(
            f"{source}: the header is on line {header.line}; the {header.preamble} line(s) before it skipped "
            f"(--skip-rows {header.line - 1} says so)"
        )
    # missing cells (only with --missing drop|interpolate; else the parsers raised)
    bad_t = np.isnan(t) if t.dtype.kind == "f" else np.zeros(len(t), dtype=bool)
    bad = bad_t | np.isnan(wrench).any(axis=1)
    if bad.any():
        first = int(np.argmax(bad))
        # a row with no wrench value at all is not this sensor's sample (another topic's row of a
        # PlotJuggler export): dropped, not invented by interpolation
        no_wrench = np.isnan(wrench).all(axis=1)
        keep = ~(bad_t | no_wrench) if fmt.missing == "interpolate" else ~bad
        if fmt.missing == "interpolate":
            filled = int(np.count_nonzero(keep & bad))
            tt = t[keep].astype(np.float64)
            w = wrench[keep]
            outside = np.zeros(len(tt), dtype=bool)  # a hole before a column's first value or after its last
            for k in range(6):
                hole = np.isnan(w[:, k])
                if hole.any() and (~hole).any():
                    have = np.flatnonzero(~hole)
                    outside[: have[0]] |= hole[: have[0]]
                    outside[have[-1] + 1 :] |= hole[have[-1] + 1 :]
                    w[hole, k] = np.interp(tt[hole], tt[~hole], w[~hole, k])  # the nearest value beyond the ends
            ends = int(np.count_nonzero(outside))
            what = ", ".join(
                ([f"{filled - ends} row(s) filled by linear interpolation in t"] if filled > ends else [])
                + ([f"{ends} row(s) at the log's start or end filled with the nearest value (no value beyond to "
                    "interpolate from)"] if ends else [])  # fmt: skip
            ) or "0 row(s) filled"
            if bad_t.any():
                what += f", {int(np.count_nonzero(bad_t))} row(s) without t dropped"
            if (no_wrench & ~bad_t).any():
                what += f", {int(np.count_nonzero(no_wrench & ~bad_t))} row(s) without any wrench value dropped"
            wrench = w
        else:
            what = f"{int(np.count_nonzero(bad))} row(s) dropped (t keeps the gap)"
            wrench = wrench[keep]
        t = t[keep]
        extra = {k: [v for v, ok in zip(col, keep) if ok] if isinstance(col, list) else col[keep] for k, col in extra.items()}
        notes.append(f"{source}: empty or nan cells in {int(np.count_nonzero(bad))} row(s), the first on {where(first)}: {what} (--missing {fmt.missing})")
        first_line = None if not keep.all() else first_line
        if not len(t):
            raise InputError(f"{source}: every row has an empty or nan cell; expected at least one complete row")
        if np.isnan(wrench).any():
            raise InputError(f"{source}: a wrench column has no value at all; expected at least one number in each")
    if len(t) > 1 and (t == t[0]).all():  # no time at all: every window would hold the whole log
        t_name = names[header.index["t"]]
        others = [n for j, n in enumerate(names) if j != header.index["t"] and re.search("time|stamp", n, re.IGNORECASE)]
        raise InputError(
            f"{source}: column {t_name!r}: every one of the {len(t)} stamps is {t[0]}; expected stamps that increase "
            "(a driver that never fills the header stamp writes 0). If another column holds the time, map it: "
            + (f"--columns t={others[0]}" if len(others) == 1 else
               f"--columns t=NAME{' (named like a time here: ' + ', '.join(map(repr, others)) + ')' if others else ''}")
        )
    # time: unit and origin
    tunit = cmap.units["t"] if cmap is not None else get_unit("s", "time")
    if "nanosec" in header.index or header.t_in_ns:
        tunit = get_unit("ns", "time")
    back = np.flatnonzero(np.diff(t) < 0)
    if len(back):  # only a stamp split in seconds and nanoseconds gets here
        i = int(back[0]) + 1
        cols = [names[header.index[r]] for r in ("t", "nanosec") if r in header.index]
        loc = at(i)
        raise InputError(
            f"{loc}: column{'s' if len(cols) > 1 else ''} {', '.join(map(repr, cols))}: expected the stamps "
            f"non-decreasing (a stamp may repeat, not go back), got {t[i]} ns after {t[i - 1]} ns on the row before"
        )
    origin = header.t_origin_ns  # int ns (0 but for a timestamp column with holes)
    start = (float(t[0]) + origin) * tunit.si
    explicit_time = fmt.time_unit is not None or header.t_stated or (
        cmap is not None and (cmap.from_header["t"] or tunit.name != "s")
    )
    if not explicit_time and start >= LATEST_STAMP_S and len(t) > 1:
        # no date in seconds: the one unit that makes the first stamp a date (Unix time ns, µs or ms)
        dated = _dating_units(float(t[0]), ("ms", "us", "ns"))
        if len(dated) == 1:
            tunit = get_unit(dated[0], "time")
            start = float(t[0]) * tunit.si
            explicit_time = True
            if read_as:  # the unit read, not the default the columns were mapped with
                notes[0] = f"{source}: read as {cmap.source}: {replace(cmap, units={**cmap.units, 't': tunit}).describe(names, named)}"
            notes.append(
                f"{source}: column {names[header.index['t']]!r}: t read in {tunit.label}, the only unit that makes its "
                f"first stamp a date (give --time-units to say otherwise)"
            )
    if start >= LATEST_STAMP_S and len(t) and not header.t_dated:  # after 2261 in Unix time, in the unit given: no clock's
        dated = _dating_units(float(t[0]), ("s", "ms", "us", "ns"))
        raise InputError(
            f"{source}: column {names[header.index['t']]!r}: t in {tunit.label} puts the first stamp {start:.3g} s after "
            "1970, beyond the year 2261; expected seconds since the epoch or since a start"
            + (f": the unit that makes it a date is {dated[0]} (--time-units {dated[0]})" if len(dated) == 1 else
               " (--time-units)")
        )
    if ABSOLUTE_STAMP_S <= start < LATEST_STAMP_S or header.t_dated:  # from 1973 to 2261 in Unix time, or typed a date
        # a later stamp beyond 2261 (a damaged digit): no clock's, and its nanoseconds beyond int64
        late = np.flatnonzero((t.astype(np.float64) + origin) * tunit.si >= LATEST_STAMP_S)
        if len(late):
            raise InputError(
                f"{at(late[0])}: column {names[header.index['t']]!r}: the stamp {t[late[0]] + origin} ({tunit.label}) "
                f"is {(float(t[late[0]]) + origin) * tunit.si:.4g} s after 1970, beyond the year 2261, where the first "
                f"is {start:.4g} s; expected the stamps of one clock (a damaged digit?)"
            )
        if t.dtype.kind == "f" and np.abs(t).max() < 2.0**53 and (t == np.floor(t)).all():
            t = t.astype(np.int64)  # whole s, ms or µs read as floats: exact as integers (ms × 1e6 is not in float64)
        if t.dtype.kind in "iu":
            ns = t * round(tunit.si * 1e9) + origin
            t_s = seconds_from_ns(ns)
            stamps = ns.tolist()
        else:
            t_s = _to_seconds(t - t[0], tunit.si)
            stamps = (np.round(t * (tunit.si * 1e9)).astype(np.int64) + origin).tolist()
        stamps = np.array(stamps, dtype=np.int64)
        own = _file_stamps(extra["stamp_ns"], stamps) if "stamp_ns" in extra else None
        if own is not None:
            stamps = own  # the file's own: as exact, or more (t printed with fewer digits)
        elif "stamp_ns" in extra:  # the file's own would be lost
            raise InputError(
                f"{source}: column 'stamp_ns' holds other values than the absolute stamps of column "
                f"{names[header.index['t']]!r}, which softtip writes under that name; expected one of them (rename "
                "the column, or read the time from it: --columns t=stamp_ns --time-units ns)"
            )
        extra = {**extra, "stamp_ns": stamps}  # int64 in Parquet and Arrow, digits in CSV
        notes.append(f"{source}: absolute stamps ({tunit.label}): t counts from the first, {stamps[0]} ns; the stamps go along as column stamp_ns")
    else:
        t_s = _to_seconds(t.astype(np.float64) + origin, tunit.si)
    t_s = np.ascontiguousarray(t_s, dtype=np.float64)
    # wrench units
    if cmap is not None:
        for k, role in enumerate(ROLES[1:]):
            if role in cmap.counts:  # counts are whole numbers: fractions are values in units already
                col = np.asarray(wrench[:, k], dtype=np.float64)
                frac = np.flatnonzero(np.isfinite(col) & (col != np.floor(col)))
                if len(frac):
                    per_unit, line = cmap.counts[role]
                    quantity = ROLE_QUANTITY[role]
                    i = int(frac[0])
                    loc = at(i)
                    raise InputError(
                        f"{loc}: column {names[header.index[role]]!r}: line {line} says its values "
                        f"are counts ({per_unit:g} per unit), but {float(col[i])!r} is not a whole number; if the values are in "
                        f"{cmap.units[role].label} already, give --{quantity}-units {cmap.units[role].name} to read them as they are"
                    )
        scale = np.array([cmap.units[r].si / cmap.counts.get(r, (1.0,))[0] for r in ROLES[1:]])
        wrench = _to_seconds_like(np.asarray(wrench, dtype=np.float64), scale)
        scale = np.ones(6)
        force_unit, moment_unit = cmap.units["fx"].name, cmap.units["mx"].name
    else:
        force_unit, moment_unit = UNIT_SYSTEM_UNITS[units]
        scale = wrench_scale(force_unit, moment_unit)
    repeated, time_notes = _time_notes(t_s, source, first_line, explicit=explicit_time, column=names[header.index["t"]])
    cut = _cut_last_line(raw, source, len(t_s)) if raw is not None and header.delimiter == "," else None
    return Log(
        t=t_s,
        # in SI already: the values as they are (x * 1.0 is x), without two copies of the wrench
        wrench=np.ascontiguousarray(wrench, dtype=np.float64) if (scale == 1.0).all() else np.asarray(wrench, dtype=np.float64) * scale,
        extra=extra,
        source=source,
        units=_units_label(force_unit, moment_unit),
        repeated_t=repeated,
        warnings=tuple(time_notes) + ((cut,) if cut else ()),
        first_line=first_line,
        notes=tuple(notes),
        force_unit=force_unit,
        moment_unit=moment_unit,
        time_suspect=next((n for n in time_notes if "--time-units" in n), None),
        units_in_header=tuple(names[header.index[r]] for r in ROLES[1:] if cmap is not None and cmap.from_header[r]),
    )


# --------------------------------------------------------------------------------------
# reading


def read_log(
    path: str | os.PathLike[str] | TextIO,
    units: str | None = None,
    *,
    progress: Callable[[int], object] | None = None,
    columns: Mapping[str, str] | str | None = None,
    force_units: str | None = None,
    moment_units: str | None = None,
    time_units: str | None = None,
    missing: str = "fail",
    skip_rows: int | None = None,
) -> Log:
    """Read a force/torque log from a CSV or Parquet file, or a CSV text stream.

    Parameters
    ----------
    path : str, path-like or text stream
        File to read (a name ending in ``.parquet`` is read as Parquet, ``.arrow`` or
        ``.feather`` as Arrow IPC (Feather v2), anything else as CSV, gzip/bzip2/xz/zstd-compressed CSV recognised by its first bytes), or an open
        CSV stream (``sys.stdin``, ``io.StringIO``; a binary stream is decoded as UTF-8).
        A stream is read to its end and not closed.
    units : {"si", "kgf-mm"} or None
        Units of the wrench columns in the file: ``"si"`` (N, N·m) or ``"kgf-mm"`` (kgf,
        kgf·mm; 1 kgf = 9.80665 N). ``None`` (default): SI, or for Parquet the units its
        metadata names (``softtip.units``); a Parquet file whose metadata names other units
        than ``units`` is an error. A CSV header that gives a column's unit (``Fx (N)``)
        wins over the default; one that contradicts ``units`` is an error.
    progress : callable, optional
        Called with the number of bytes parsed after each block of a CSV file (e.g.
        ``tqdm.update`` with the file's size as total).
    columns : mapping or str, optional
        Role (``t``, ``fx`` … ``mz``) → header name (or 1-based position in a file without
        a header row); a string ``"t=Time,fx=Fx,…"`` is parsed. Without it the headers of
        the sources in :data:`softtip.io.formats.SOURCES` are recognised.
    force_units, moment_units, time_units : str, optional
        Units of the force (N, kgf, lbf), moment (N*m, N*mm, kgf*mm, lbf*in) and time
        (s, ms, us, ns) columns whose header does not say (docs/guide/input-formats.md).
        Absolute stamps (from 1e8 s on) are counted from the first; the stamps go along
        as an extra column ``stamp_ns``.
    missing : {"fail", "drop", "interpolate"}
        An empty or ``nan`` cell in a required column: an error naming this option
        (default), its row dropped, or its value interpolated linearly in ``t`` (a row
        without ``t`` is dropped). Either way :attr:`Log.notes` counts them. With ``"drop"``
        or ``"interpolate"`` a last line that the file ends inside (no line break after it)
        and that cannot be read (cells missing: cut while the file was written) is dropped
        too, and said in :attr:`Log.notes`.
    skip_rows : int, optional
        Lines before the header row (a preamble); by default found (blank, ``#`` and lines
        before the first line that names the columns).

    Returns
    -------
    Log
        ``t`` shape (N,) in s, ``wrench`` shape (N, 6) in N and N·m, N ≥ 1; repeated
        stamps counted and anything suspicious in ``warnings``.

    Raises
    ------
    InputError
        Unknown ``units``; file missing, unreadable or not UTF-8; empty file; no data rows;
        missing or duplicate columns; a row with the wrong number of cells; an empty,
        non-numeric, NaN or infinite cell in a required column; ``t`` going back; a blank
        line between data rows; a quote that swallows lines. The message names the file,
        the line (Parquet: the row) and the column, and says what was expected (and the
        option that fixes it). The first problem in file order wins.

    Notes
    -----
    CSV is parsed by pyarrow's C++ reader; only when it finds a problem is the file read
    again row by row, to name the first bad line the way a text editor counts it (the
    module's docstring gives the figures).
    """
    source = _source_name(path)
    if units is not None and units not in UNIT_SYSTEMS:
        raise InputError(f"{source}: unknown units {units!r}; expected one of: {', '.join(UNIT_SYSTEMS)}")
    fmt = _log_format(source, units, columns, force_units, moment_units, time_units, missing, skip_rows)
    columnar = None if hasattr(path, "read") else _columnar(path)  # type: ignore[arg-type]
    if columnar is not None:
        if skip_rows is not None:
            article = "an" if columnar == "arrow" else "a"
            raise InputError(f"{source}: --skip-rows applies to CSV logs; {article} {TABLE_FORMATS[columnar][1]} file has "
                             "no lines before its columns")  # fmt: skip
        stated = [o for o, v in (("--force-units", force_units), ("--moment-units", moment_units),
                                 ("--time-units", time_units)) if v is not None]  # fmt: skip
        return _read_parquet(path, source, units, columnar, fmt, stated)  # type: ignore[arg-type]
    data = _read_data(path, source)
    if isinstance(data, bytes):
        data = _decompress(data, source)
    # A last line cut while the file was written (the file ends inside it, cells missing) is
    # dropped by --missing drop or interpolate (nothing follows it to fill it from), and said.
    cut = None
    try:
        parsed = _parse_data(data, source, progress, fmt)
    except _CutLine as exc:
        if fmt.missing == "fail" or _without_cut_line(data) is None:
            raise
        cut = (exc.line, exc.reason)
    else:
        last = _cut_after_delimiter(data, parsed) if fmt.missing != "fail" else None
        if last is not None:  # cut just after a delimiter: its last cells empty, not missing samples
            cut = (last, "its last cell is empty")
    if cut is not None:
        data = _without_cut_line(data)
        try:  # every row before the cut one was read (the first parse stopped at it): only a whole-file check fails
            parsed = _parse_data(data, source, None, fmt)  # (progress was told of these bytes)
        except InputError as again:
            raise InputError(f"{again} (line {cut[0]}, inside which the file ends, was dropped: --missing {fmt.missing})") from None
    t, wrench, extra, first_line, quoted, header = parsed
    raw = data if isinstance(data, bytes) else None
    first_line = None if quoted else first_line
    log = _finish(t, wrench, extra, header, fmt, source, units or "si", first_line, raw)
    if cut is not None:
        note = (f"{source}:{cut[0]}: the file ends inside this line (no line break after it) and it cannot be read "
                f"({cut[1]}): dropped (--missing {fmt.missing})")  # fmt: skip
        log = replace(log, notes=log.notes + (note,))
    return log


def _parse_data(data: bytes | str, source: str, progress: Callable[[int], object] | None, fmt: LogFormat):
    """A CSV log's text parsed: pyarrow's reader, else (something is off, or a stream that is
    not UTF-8-encodable) the row-by-row parser, which says what."""
    parsed = _parse_arrow(data, source, progress, fmt) if isinstance(data, bytes) else None
    if parsed is None:
        text = _decode(data, source) if isinstance(data, bytes) else _strip_bom(data)
        parsed = _parse_with_header(text, source, fmt)
    return parsed


def _log_format(source: str, units: str | None, columns: Any, force_units: str | None, moment_units: str | None,
                time_units: str | None, missing: str, skip_rows: int | None) -> LogFormat:
    """The :class:`LogFormat` of :func:`read_log`'s arguments; a bad one raises :class:`InputError`."""
    try:
        if isinstance(columns, str):
            columns = parse_column_spec(columns)
        if skip_rows is not None and (not isinstance(skip_rows, int) or skip_rows < 0):
            raise ValueError(f"skip_rows must be a non-negative integer, got {skip_rows!r}")
        return LogFormat.of(
            units, columns=dict(columns or {}), force_unit=force_units, moment_unit=moment_units,
            time_unit=time_units, missing=missing, skip_rows=skip_rows,
        )  # fmt: skip
    except ValueError as exc:
        raise InputError(f"{source}: {exc}") from None


#: First bytes of the compressed files :func:`_decompress` takes, and pyarrow's codec for each.
_COMPRESSION_MAGIC = ((b"\x1f\x8b", "gzip"), (b"BZh", "bz2"), (b"\xfd7zXZ\x00", "xz"), (b"\x28\xb5\x2f\xfd", "zstd"))


def _decompress(data: bytes, source: str) -> bytes:
    """The CSV text of a gzip, bzip2, xz or zstd file (found by its first bytes); other data as it is."""
    codec = next((name for magic, name in _COMPRESSION_MAGIC if data.startswith(magic)), None)
    if codec is None:
        return data
    if codec == "xz":  # pyarrow's builds often lack lzma
        import lzma

        try:
            return lzma.decompress(data)
        except lzma.LZMAError as exc:
            raise InputError(f"{source}: not a readable xz file ({exc}); expected xz-compressed CSV") from None
    import pyarrow as pa

    try:
        with pa.CompressedInputStream(pa.BufferReader(data), codec) as stream:
            return stream.read()
    except (pa.ArrowException, OSError) as exc:
        raise InputError(f"{source}: not a readable {codec} file ({exc}); expected {codec}-compressed CSV") from None


def _columnar(path: str | os.PathLike[str]) -> str | None:
    """``"parquet"`` or ``"arrow"`` for a table file of that format (by its name), None for CSV."""
    fmt = table_format(path)
    return None if fmt == "csv" else fmt


class _ColumnarFile:
    """A Parquet or Arrow IPC (Feather v2) file, opened for reading: one interface for both.

    Attributes ``schema`` (with the key-value metadata) and ``num_rows``; :meth:`read` gives the
    whole table, :meth:`iter_batches` record batches of at most ``rows`` rows. Opening raises
    what pyarrow raises (``OSError``, ``pa.ArrowException``).
    """

    def __init__(self, path: str | os.PathLike[str], fmt: str):
        import pyarrow as pa

        self.fmt = fmt
        if fmt == "parquet":
            import pyarrow.parquet as pq

            # ParquetFile, not read_table: the latter imports pyarrow.dataset (~0.2 s) for nothing here.
            # Memory-mapped: the column chunks are read in place from the page cache, where reading
            # them copies each into fresh memory whose first touch the kernel zeroes (1e7 rows in
            # a fresh process: 0.39-0.42 s of CPU against 0.43-0.53 s; bench_core.py --only bounds)
            self._file: Any = pq.ParquetFile(path, memory_map=True)
            self.schema = self._file.schema_arrow
            self.num_rows = int(self._file.metadata.num_rows)
        else:
            source = pa.memory_map(os.fspath(path))
            try:
                self._file = pa.ipc.open_file(source)
            except BaseException:
                source.close()
                raise
            self._source = source
            self.schema = self._file.schema
            self.num_rows = sum(self._file.get_batch(i).num_rows for i in range(self._file.num_record_batches))

    def read(self) -> Any:
        return self._file.read() if self.fmt == "parquet" else self._file.read_all()

    def iter_batches(self, rows: int, columns: list[str] | None = None) -> Any:
        if self.fmt == "parquet":
            yield from self._file.iter_batches(batch_size=rows, columns=columns)
            return
        for i in range(self._file.num_record_batches):
            batch = self._file.get_batch(i)
            if columns is not None:
                batch = batch.select(columns)
            for start in range(0, batch.num_rows, rows):
                yield batch.slice(start, rows)

    def close(self) -> None:
        self._file.close() if self.fmt == "parquet" else self._source.close()

    def __enter__(self) -> _ColumnarFile:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def columnar_rows(path: str | os.PathLike[str]) -> int | None:
    """The rows of a Parquet or Arrow IPC file (from its footer, not its data); None for CSV."""
    fmt = _columnar(path)
    if fmt is None:
        return None
    with _ColumnarFile(path, fmt) as f:
        return f.num_rows


def _source_name(path: str | os.PathLike[str] | TextIO) -> str:
    if hasattr(path, "read"):
        name = getattr(path, "name", None)
        # A stream opened on a file descriptor has an int name; it tells the user nothing.
        return name if isinstance(name, str) else "<stream>"
    return os.fspath(path) if not isinstance(path, bytes) else os.fsdecode(path)


def _opening_error(exc: OSError, source: str, what: str) -> InputError:
    """The located message for a file that cannot be opened (missing, a directory, denied)."""
    if isinstance(exc, FileNotFoundError):
        return InputError(f"{source}: file not found; expected an existing {what}")
    if isinstance(exc, IsADirectoryError):
        return InputError(f"{source}: is a directory; expected a {what}")
    return InputError(f"{source}: permission denied; expected a readable {what}")


def _read_data(path: str | os.PathLike[str] | TextIO, source: str, what: str = "CSV log file") -> bytes | str:
    """The whole input: bytes from a file, or what a stream gives (bytes or text).

    A text stream that is not UTF-8-encodable (lone surrogates) comes back as text.
    Every failure becomes an :class:`InputError`.
    """
    try:
        if hasattr(path, "read"):
            data = path.read()
        else:
            with open(path, "rb") as fh:
                data = fh.read()
    except (FileNotFoundError, IsADirectoryError, PermissionError) as exc:
        raise _opening_error(exc, source, what) from None
    except UnicodeDecodeError as exc:
        # A text stream (e.g. stdin) decoding on the fly: no byte offset into the file.
        raise InputError(f"{source}: not valid UTF-8 ({exc.reason}); expected UTF-8 text") from None
    except OSError as exc:
        raise InputError(f"{source}: cannot read ({exc.strerror or exc}); expected a readable {what}") from None
    if isinstance(data, str):
        try:
            return data.encode("utf-8")
        except UnicodeEncodeError:
            return data
    return bytes(data)


def _strip_bom(text: str) -> str:
    return text[1:] if text.startswith("\ufeff") else text


def _not_utf8(source: str, line: int, byte: int, offset: int, start: bytes) -> InputError:
    """The error of a byte that is not UTF-8 at ``offset`` of a file whose first bytes are ``start``."""
    utf16 = start[:2] in (b"\xff\xfe", b"\xfe\xff")  # a UTF-16 byte-order mark: Excel's "Unicode text"
    what = " (a UTF-16 file: it starts with UTF-16's byte-order mark, as Excel's \"Unicode text\" writes)" if utf16 else ""
    columnar = next((fmt for fmt, magic in (("parquet", b"PAR1"), ("arrow", b"ARROW1")) if start.startswith(magic)), None)
    if columnar is not None:  # read as CSV by its name (or from standard input)
        suffix, name = TABLE_FORMATS[columnar][0][0], TABLE_FORMATS[columnar][1]
        kind = f"{'an' if name[0] in 'AEIOU' else 'a'} {name} file (it starts as one)"
        if source == "<stdin>":
            return InputError(f"{source}: {kind} on standard input, which takes CSV only; expected its file's name as "
                              f"INPUT, ending in {suffix}")  # fmt: skip
        return InputError(f"{source}: {kind}, read as CSV by its name; expected a name ending in {suffix} (rename it)")
    return InputError(
        f"{source}:{line}: not valid UTF-8 (byte 0x{byte:02x} at byte offset {offset}){what}; "
        "expected a UTF-8 text file (re-save it as UTF-8)"
    )


def _decode(data: bytes, source: str) -> str:
    """The bytes as text, BOM removed; invalid UTF-8 is an error naming the line."""
    skip = 3 if data.startswith(b"\xef\xbb\xbf") else 0
    try:
        return data[skip:].decode("utf-8")
    except UnicodeDecodeError as exc:
        offset = skip + exc.start
        raise _not_utf8(source, _line_breaks(data, offset) + 1, data[offset], offset, data[:8]) from None


def _line_breaks(data: bytes, end: int | None = None) -> int:
    """Line breaks in ``data[:end]`` as a text editor counts them: CR LF, LF or a lone CR."""
    end = len(data) if end is None else end
    return data.count(b"\n", 0, end) + data.count(b"\r", 0, end) - data.count(b"\r\n", 0, end)


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
    line: int  # line number of the header (its first line); a file without one: the line before the data
    data_base: int  # a data record's physical line = data_base + csv line_num
    lines: io.StringIO  # the text, positioned just after the header record
    comments: list[tuple[int, str]]  # (line, text) of the comment lines before the header
    delimiter: str = ","
    decimal: str = "."
    cmap: ColumnMap | None = None  # the roles' columns and units; None: not every role found
    preamble: int = 0  # lines skipped before the header that were neither blank nor comments
    headerless: bool = False
    t_in_ns: bool = False  # set by a parser that read absolute decimal seconds exactly, as int64 ns
    columnar: bool = False  # the names are a Parquet or Arrow file's columns, not a header's
    t_dated: bool = False  # t's column is typed a date (Arrow's timestamp): absolute stamps, whatever the year
    t_origin_ns: int = 0  # the stamps are t + this (int64 ns): absolute stamps with holes, exact as float64 offsets
    t_stated: bool = False  # the file says t is in seconds (softtip's Parquet or Arrow metadata): not second-guessed

    @property
    def index(self) -> dict[str, int]:
        return self.cmap.index if self.cmap is not None else {}


# Delimiters sniffed, in order of preference on a tie.
_DELIMITERS = (",", "\t", ";")
# Lines looked at for a header row after a preamble.
_PREAMBLE_LINES = 50


def _split_line(line: str, delimiter: str) -> list[str]:
    try:
        return [c.strip() for c in next(csv.reader([line], delimiter=delimiter))]
    except (csv.Error, StopIteration):
        return []


def _sniff_delimiter(line: str) -> str:
    """The delimiter of a header (or first data) line: the most frequent of comma, tab, semicolon."""
    counts = {d: line.count(d) for d in _DELIMITERS}
    best = max(_DELIMITERS, key=lambda d: (counts[d], -_DELIMITERS.index(d)))
    return best if counts[best] else ","


_DECIMAL_COMMA = re.compile(r"^[-+]?\d+,\d*(?:[eE][-+]?\d+)?$")


def _try_columns(names: list[str], fmt: LogFormat, source: str, line: int, headerless: bool = False,
                 absent: list[tuple[int, InputError]] | None = None) -> ColumnMap | None:  # fmt: skip
    """The line's :class:`ColumnMap`, or None; ``absent`` given: a column ``--columns`` names that
    this line lacks is put there (the header may come later), not raised: the error of the line
    with the most of the named columns, the first such."""
    try:
        return resolve_columns(names, fmt, headerless=headerless)
    except ColumnError as exc:
        error = InputError(f"{source}:{line}: {exc}")
        if absent is None or not isinstance(exc, ColumnAbsent):
            raise error from None
        if not absent or exc.found > absent[0][0]:
            absent[:] = [(exc.found, error)]
        return None


def _read_header(text: str, source: str, fmt: LogFormat | None = None) -> _Header:
    """Find the header row: after ``fmt.skip_rows`` lines, or the first line that is not blank
    or a comment, or (when that line names no recognised columns) the first of the next
    :data:`_PREAMBLE_LINES` that does (a preamble). Sniff its delimiter and decimal mark, and
    map its columns. A file whose first line is the ``ros2 topic echo --csv`` layout has no header."""
    fmt = fmt or LogFormat()
    lines = io.StringIO(text, newline="")
    lineno = 0
    comments: list[tuple[int, str]] = []
    line = ""
    skip = fmt.skip_rows
    for line in lines:
        lineno += 1
        stripped = line.strip()
        if skip is not None and lineno <= skip:
            comments.append((lineno, stripped))
            continue
        if not stripped:
            continue
        if stripped.startswith("#"):
            comments.append((lineno, stripped))
            continue
        break
    else:
        what = "only comments and blank lines" if comments else "empty file"
        raise InputError(f"{source}: {what}; expected a CSV header row naming {_EXPECTED_HEADER}")

    delimiter = _sniff_delimiter(line)
    first = _split_line(line, delimiter)
    headerless = _headerless(first, fmt)
    preamble = 0
    if headerless:
        cmap = _try_columns(_positional_names(first, fmt), fmt, source, lineno, headerless=True)
        if cmap is not None:
            names = _positional_names(first, fmt)
            lines.seek(lines.tell() - len(line))
            return _Header(names=names, line=lineno - 1, data_base=lineno - 1, lines=lines, comments=comments,
                           delimiter=delimiter, decimal=_sniff_decimal(text, lines.tell(), delimiter), cmap=cmap,
                           headerless=True)  # fmt: skip
    # --columns naming what the first line lacks: that line may be a preamble's
    absent: list[tuple[int, InputError]] = []
    cmap = _try_columns(first, fmt, source, lineno, absent=absent if skip is None else None)
    if cmap is None and skip is None and not headerless:
        # a preamble: the header is the first of the next lines that names the columns
        start = lines.tell()
        ahead, k = [], lineno
        # no line names them all: the one naming most (4 roles at least), for the error to be on it
        partial = (max(3, len(recognised_roles(first))), 0, 0, "", "")
        for later in itertools.islice(lines, _PREAMBLE_LINES):
            k += 1
            ahead.append((k, later))
            d = _sniff_delimiter(later)
            cells = _split_line(later, d)
            found = _try_columns(cells, fmt, source, k, absent=absent) if later.strip() else None
            if found is not None:
                comments += [(lineno, line.strip())] + [(n, x.strip()) for n, x in ahead[:-1]]
                preamble = k - lineno
                line, lineno, delimiter, cmap = later, k, d, found
                break
            roles = len(recognised_roles(cells)) if later.strip() else 0
            if roles > partial[0]:
                partial = (roles, k, lines.tell(), later, d)
        else:
            if absent:
                looked = f"lines {lineno}–{k} looked at; " if k > lineno else ""
                raise InputError(f"{absent[0][1]} ({looked}a header further down: --skip-rows N skips the N lines before it)")
            lines.seek(start)
            if partial[1]:
                _, k, pos, later, d = partial
                comments += [(lineno, line.strip())] + [(n, x.strip()) for n, x in ahead[: k - lineno - 1]]
                preamble = k - lineno
                line, lineno, delimiter = later, k, d
                lines.seek(pos)
    reader = csv.reader(itertools.chain([line], lines), delimiter=delimiter)
    try:
        names = [name.strip() for name in next(reader)]
    except csv.Error as exc:
        raise InputError(f"{source}:{lineno}: malformed CSV header ({exc}); expected {_EXPECTED_HEADER}") from None
    # a spreadsheet's empty columns have no name: each its own, which no header holds, until
    # _finish drops them (or refuses one that holds values)
    names = [name or f"{_UNNAMED}{j + 1}" for j, name in enumerate(names)]
    # csv pulls lines one at a time, so ``lines`` now sits right after the header record.
    data_base = lineno - 1 + reader.line_num
    if cmap is not None:
        cmap = _units_row(names, cmap, lines, fmt, source, data_base + 1, delimiter)
        data_base += bool(cmap.units_row)
        cmap = _stated_units(names, cmap, comments, fmt, source)
    decimal = _sniff_decimal(text, lines.tell(), delimiter)
    return _Header(names=names, line=lineno, data_base=data_base, lines=lines, comments=comments,
                   delimiter=delimiter, decimal=decimal, cmap=cmap, preamble=preamble)  # fmt: skip


_BRACKETED = re.compile(r"^[\[(]\s*(.*?)\s*[\])]$")


def _units_row(names: list[str], cmap: ColumnMap, lines: io.StringIO, fmt: LogFormat, source: str, line: int,
               delimiter: str) -> ColumnMap:  # fmt: skip
    """A row of units under the header (``s,N,N,N,N-mm,…``, as loggers write one) read into the
    column map, ``lines`` then past it; else ``cmap`` as it is and ``lines`` where it was.

    It is one when no cell of ``t``, ``fx`` … ``mz`` on it is a number and one at least is a
    unit of its quantity; a cell there that is no such unit, or that contradicts the header's
    unit or a unit option, is an error naming the line and column."""
    pos = lines.tell()
    cells = _split_line(lines.readline(), delimiter)
    roles = [r for r in ROLES if cmap.index[r] < len(cells)]
    given = {r: _BRACKETED.sub(r"\1", cells[cmap.index[r]]) for r in roles}
    found = {r: find_unit(c, ROLE_QUANTITY[r]) for r, c in given.items() if c}
    if not any(found.values()) or any(_is_number(c.replace(",", ".")) for c in given.values()):
        lines.seek(pos)
        return cmap
    units, from_header = dict(cmap.units), dict(cmap.from_header)
    for role in found:
        quantity, column = ROLE_QUANTITY[role], names[cmap.index[role]]
        option = fmt.unit_option(quantity)
        try:
            unit = stated_unit(given[role], quantity, option, column, "the units row")
        except ColumnError as exc:
            raise InputError(f"{source}:{line}: {exc}") from None
        if cmap.from_header[role] and cmap.units[role] is not unit:
            raise InputError(
                f"{source}:{line}: column {column!r}: the units row says {unit.label} but the header says "
                f"{cmap.units[role].label}; expected one unit per column"
            )
        units[role], from_header[role] = unit, True
    return replace(cmap, units=units, from_header=from_header, units_row=line, row_units=frozenset(found))


# A line before the header that states a quantity's unit: ``Force Units,N`` or ``Torque
# Units:,N-mm`` (ATI's DAQ F/T and Net F/T logs), ``# time unit: ms``; or how many counts a
# column's values hold per unit: ``Counts per Unit Force,1000000`` (ATI's Net F/T and Ethernet
# Axia demo logs, whose Fx … Tz are raw counts to be divided by it).
_STATED_UNIT = re.compile(
    r"^#?\s*(force|torque|moment|time)[\s_-]*units?\s*[:=]?\s*(?:[,;\t]\s*)*([^,;\t]*?)[\s,;\t]*$", re.IGNORECASE
)
_STATED_COUNTS = re.compile(
    r"^#?\s*counts[\s_-]*per[\s_-]*unit[\s_-]*(force|torque|moment)\s*[:=]?\s*(?:[,;\t]\s*)*([^,;\t]*?)[\s,;\t]*$",
    re.IGNORECASE,
)


def _stated(comments: list[tuple[int, str]], pattern: re.Pattern) -> dict[str, list[tuple[int, str]]]:
    """Quantity → the (line, value) of each line ``pattern`` matches (a value in brackets taken
    out of them, a remark in brackets after it left out: ``N (calibrated)``; a value naming
    another quantity's units, a small table's header, left out)."""
    stated: dict[str, list[tuple[int, str]]] = {}
    for line, text in comments:
        match = pattern.match(text)
        if match is None:
            continue
        value = _BRACKETED.sub(r"\1", match[2].strip())
        value = re.sub(r"^([^(\[]+?)\s*[(\[].*[)\]]$", r"\1", value)
        if not value or re.search(r"\bunits?\b", value, re.IGNORECASE):
            continue
        quantity = "moment" if match[1].lower() in ("torque", "moment") else match[1].lower()
        stated.setdefault(quantity, []).append((line, value))
    return stated


def _stated_unit(found: list[tuple[int, str]], quantity: str, fmt: LogFormat, source: str) -> tuple[Unit, int]:
    """The unit the lines before the header give ``quantity``, and the first line giving it. A
    unit option decides where it is given: a line naming another known unit is then an error,
    one naming no unit softtip knows (``see calibration sheet``) is left to the option."""
    option = fmt.unit_option(quantity)
    known = [(line, text, find_unit(text, quantity)) for line, text in found]
    units = {unit for _, _, unit in known if unit is not None}
    if option is not None:
        given = get_unit(option, quantity)
        for line, text, unit in known:
            # one unit in the file, another in the option: stop, as for a header's; lines that
            # contradict each other are the option's to settle
            if len(units) == 1 and unit is not None and unit is not given:
                raise InputError(
                    f"{source}:{line}: {text!r} says the {quantity} unit is {unit.label} but --{quantity}-units (or "
                    f"--units) says {option}; leave the option out to use the unit the file gives"
                )
        return given, known[0][0]
    if len(units) > 1:
        (l1, t1, _), (l2, t2, _) = [k for k in known if k[2] is not None][:2]
        raise InputError(
            f"{source}:{l2}: {t2!r} contradicts {t1!r} on line {l1} for the {quantity} unit; expected one "
            f"(--{quantity}-units says which)"
        )
    if not units:
        line, text = found[0]
        raise InputError(
            f"{source}:{line}: unknown {quantity} unit {text!r} on a line before the header; expected one of: "
            f"{', '.join(unit_names(quantity))} (or give --{quantity}-units)"
        )
    line, _, unit = next(k for k in known if k[2] is not None)
    return unit, line


def _stated_units(names: list[str], cmap: ColumnMap, comments: list[tuple[int, str]], fmt: LogFormat,
                  source: str) -> ColumnMap:  # fmt: skip
    """The units lines before the header state (see :data:`_STATED_UNIT`) read into the column
    map for the columns whose header (or units row) gives none, and the counts per unit of those
    columns (:data:`_STATED_COUNTS`, not with a unit option: the option says the values are in
    that unit). A unit there that is no such unit, that contradicts the header's, the units
    row's, an option or another such line, or counts that are no positive number or differ
    between two lines, are an error naming the line."""
    stated = _stated(comments, _STATED_UNIT)
    counted = _stated(comments, _STATED_COUNTS)
    if not stated and not counted:
        return cmap
    units, from_header, stated_on, counts = dict(cmap.units), dict(cmap.from_header), {}, {}
    per_unit: dict[str, tuple[float, int]] = {}
    for quantity, found in counted.items():
        values = []
        for line, text in found:
            try:
                value = float(text)
            except ValueError:
                value = math.nan
            if not (math.isfinite(value) and value > 0):
                raise InputError(
                    f"{source}:{line}: counts per unit {quantity} {text!r}; expected a positive number (the columns "
                    f"of {quantity} without a unit of their own are divided by it)"
                )
            if values and value != values[0][0]:
                raise InputError(
                    f"{source}:{line}: counts per unit {quantity} {text} contradicts {values[0][0]:g} on line "
                    f"{values[0][1]}; expected one"
                )
            values.append((value, line))
        per_unit[quantity] = values[0]
    for role in ROLES:
        quantity = ROLE_QUANTITY[role]
        if quantity in per_unit and not cmap.from_header[role] and fmt.unit_option(quantity) is None:
            counts[role] = per_unit[quantity]  # raw counts: the column has no unit of its own
    resolved = {q: _stated_unit(found, q, fmt, source) for q, found in stated.items()}
    for role in ROLES:
        quantity = ROLE_QUANTITY[role]
        if quantity not in resolved:
            continue
        unit, line = resolved[quantity]
        if from_header[role]:
            if units[role] is not unit:
                column = names[cmap.index[role]]
                where = f"the units row on line {cmap.units_row}" if role in cmap.row_units else "the header"
                raise InputError(
                    f"{source}:{line}: column {column!r}: this line says {unit.label} but {where} says "
                    f"{units[role].label}; expected one unit per column"
                )
            continue
        if fmt.unit_option(quantity) is None:
            units[role], from_header[role], stated_on[role] = unit, True, line
    return replace(cmap, units=units, from_header=from_header, stated_on=stated_on, counts=counts)


def _sniff_decimal(text: str, pos: int, delimiter: str) -> str:
    """``","`` when the data's numbers use a decimal comma (only with tab or semicolon delimiters)."""
    if delimiter == ",":
        return "."
    sample = text[pos : pos + 4096].splitlines()[:20]
    cells = [c.strip() for ln in sample for c in ln.split(delimiter)]
    return "," if any(_DECIMAL_COMMA.match(c) for c in cells) else "."


def _headerless(cells: list[str], fmt: LogFormat) -> bool:
    """Whether a first line is data: every cell but text ones a number (``ros2 topic echo --csv``)."""
    numeric = [_is_number(c.replace(",", ".")) for c in cells]
    if len(cells) == 9 and all(numeric[:2]) and not numeric[2] and all(numeric[3:]):
        return True  # ros2 topic echo --csv of a WrenchStamped
    return bool(fmt.columns) and all(v.isdigit() for v in fmt.columns.values()) and sum(numeric) >= len(ROLES)


def _positional_names(cells: list[str], fmt: LogFormat) -> list[str]:
    from softtip.io.formats import ROS2_CSV_NAMES

    if len(cells) == len(ROS2_CSV_NAMES) and not fmt.columns:
        return list(ROS2_CSV_NAMES)
    return [str(j + 1) for j in range(len(cells))]


def _parse(
    text: str, source: str, fmt: LogFormat | None = None
) -> tuple[NDArray[Any], NDArray[np.float64], dict[str, list[str]], int, bool]:
    """``t`` (N,), wrench (N, 6) in the file's units, the extra columns, the line of the
    first data row, and whether the data holds a quote (then rows may span lines)."""
    return _parse_with_header(text, source, fmt)[:5]  # type: ignore[return-value]


def _parse_with_header(
    text: str, source: str, fmt: LogFormat | None = None
) -> tuple[NDArray[Any], NDArray[np.float64], dict[str, list[str]], int, bool, _Header]:
    """:func:`_parse`, and the header it found."""
    fmt = fmt or LogFormat()
    header = _read_header(text, source, fmt)
    index = _column_index(header, source)
    # Millions of small lists/strings trigger the cyclic GC over and over (quadratic-ish);
    # none of them form cycles.
    gc_was_enabled = gc.isenabled()
    gc.disable()
    start = (header.lines.tell(), 0)
    quoted = '"' in text[start[0]:]
    try:
        if fmt.missing == "fail":
            try:
                return (*_parse_fast(header, index), header.data_base + 1, quoted, header)
            except _Suspect as suspect:
                resume = suspect.resume
        else:  # empty cells to keep: row by row
            resume = start
        # Re-read row by row from just before the problem: on a 1e6-row file with a bad last
        # row this costs one block, not the whole file again.
        try:
            found = _parse_careful(header, index, source, resume, fmt.missing)  # normally raises
            if resume != start:
                # Nothing wrong after all (not expected): never return a partial log.
                found = _parse_careful(header, index, source, start, fmt.missing)
        except InputError as exc:
            raise _with_cut_hint(exc, text, source, header.data_base) from None
        return (*found, header.data_base + 1, quoted, header)
    finally:
        if gc_was_enabled:
            gc.enable()


def _ns_of(cell: str) -> int | None:
    """A decimal number of seconds as integer ns when that is exact (at most 9 decimals), else None."""
    from decimal import Decimal, InvalidOperation

    try:
        ns = Decimal(cell.strip()).scaleb(9)
    except InvalidOperation:
        return None
    return int(ns) if ns.is_finite() and ns == ns.to_integral_value() and 0 <= ns < 2**63 else None


def _swallowed(cell: str, delimiter: str, ncol: int) -> int:
    """How many of the lines inside a cell that spans lines look like data rows (a stray quote)."""
    return sum(1 for ln in re.split(r"\r\n|\r|\n", cell)[1:] if ln.count(delimiter) >= ncol - 1 >= 1)


def _swallow_error(source: str, line: int, column: str, cell: str, end_line: int, at_end: bool, k: int) -> InputError:
    where = "is never closed" if at_end else f"is closed only on line {end_line}"
    return InputError(
        f"{source}:{line}: column {column!r}: a quote opened on this line {where}, so the {k} line{'s' if k > 1 else ''} "
        f"after it that look{'' if k > 1 else 's'} like data rows would be read as text of this cell; expected each row "
        "on its own line: close the quote on this line or remove it (rows read must equal the file's)"
    )


def _with_cut_hint(exc: InputError, text: str, source: str, data_base: int) -> InputError:
    """Add a hint to an error on the last line (a data line) when the file ends inside it."""
    if text.endswith(("\n", "\r")):
        return exc
    last = text.count("\n") + 1
    if last <= data_base:
        return exc
    return _cut_hint(exc, source, last)


#: The end of the message of a last line with too few or too many cells (said otherwise when the file was cut inside it)
_FOOTER_HINT = "; this is the file's last line: a footer after the data, or a row cut short? Delete it"


class _Unfinished(InputError):
    """A row that ends too early: cells missing, or its last cell not a number (what a line cut
    short looks like, when it is the file's last and the file ends inside it)."""


class _CutLine(InputError):
    """An error on a file's last line, which the file ends inside (no line break after it),
    that a line cut while the file was written gives (:class:`_Unfinished`). ``line``: its
    number; ``reason``: what is wrong with it."""

    def __init__(self, message: str, line: int, reason: str):
        super().__init__(message)
        self.line, self.reason = line, reason


def _cut_hint(exc: InputError, source: str, last: int) -> InputError:
    """:func:`_with_cut_hint` for a file without a line break after its line ``last``."""
    if not str(exc).startswith(f"{source}:{last}: "):
        return exc
    reason = str(exc).removeprefix(f"{source}:{last}: ").removesuffix(_FOOTER_HINT)
    text = (f"{source}:{last}: {reason} (the file ends inside line {last}, with no line break after it: was it cut "
            "while being written? Delete that line to use the rest")  # fmt: skip
    if not isinstance(exc, _Unfinished):  # a whole row (too many cells, t going back): not dropped by --missing
        return InputError(text + ")")
    return _CutLine(text + ", or give --missing drop)", last, reason)


def _without_cut_line(data: bytes | str) -> bytes | str | None:
    """``data`` up to its last line break (its cut last line dropped); None without a line break."""
    end = data.rfind(b"\n" if isinstance(data, bytes) else "\n") + 1
    return data[:end] if end else None


def _cut_after_delimiter(data: bytes | str, parsed: tuple) -> int | None:
    """The number of ``data``'s last line when the file ends inside it just after a delimiter
    and its last row, so read, has an empty required cell (a line cut there, not a missing
    sample); else None. ``parsed``: :func:`_parse_data` of ``data``."""
    t, wrench, _, _, quoted, header = parsed
    nl, cr = (b"\n", b"\r") if isinstance(data, bytes) else ("\n", "\r")
    delimiter = header.delimiter.encode() if isinstance(data, bytes) else header.delimiter
    blank = b" \t" if isinstance(data, bytes) else " \t"
    # (the line's end alone: no copy of a file of gigabytes)
    if quoted or not len(t) or data.endswith((nl, cr)) or not data[-4096:].rstrip(blank).endswith(delimiter):
        return None
    if not (bool(np.isnan(wrench[-1]).any()) or (t.dtype.kind == "f" and bool(np.isnan(t[-1])))):
        return None
    breaks = data.count(nl)
    return breaks + 1 if breaks else None


# Header text looked at by the fast path; a header record longer than this goes the slow way.
_HEADER_PREFIX = 1 << 16


def _parse_arrow(
    data: bytes, source: str, progress: Callable[[int], object] | None = None, fmt: LogFormat | None = None
) -> tuple[NDArray[Any], NDArray[np.float64], dict[str, list[str]], int, bool, _Header] | None:
    """Parse a well-formed CSV log with pyarrow; ``None`` at the first oddity of any kind.

    Accepts only what :func:`_parse_careful` accepts, with the same values (both parse
    numbers correctly rounded); everything else, including header problems, is left to
    the text parser, which words the error. With ``fmt.missing`` other than ``"fail"``
    empty and ``nan`` cells of the required columns come back as NaN.
    """
    import pyarrow as pa
    from pyarrow import csv as pacsv

    fmt = fmt or LogFormat()
    skip = 3 if data.startswith(b"\xef\xbb\xbf") else 0
    prefix = data[skip : skip + _HEADER_PREFIX]
    whole = skip + len(prefix) == len(data)
    if not whole:
        prefix = prefix[: prefix.rfind(b"\n") + 1]
    try:
        prefix_text = prefix.decode("utf-8")
        header = _read_header(prefix_text, source, fmt)
        index = _column_index(header, source)
    except (UnicodeDecodeError, InputError):
        return None
    pos = header.lines.tell()
    if not whole and pos >= len(prefix_text):
        return None  # the header record may go on past the prefix
    start = skip + len(prefix_text[:pos].encode("utf-8"))
    # Blank lines at the end are allowed; pyarrow would take them for one-cell rows.
    end = _end_of_content(data)
    if end <= start:
        return None  # header only: the text parser words it
    breaks = [i for i in (data.find(b"\n", end), data.find(b"\r", end)) if i >= 0]
    if data.find(b'"', max(data.rfind(b"\n", 0, end), data.rfind(b"\r", 0, end), start), end) >= 0:
        end = len(data)  # a quote on the last line may be open: leave the end to the parsers
    else:
        end = min(breaks) if breaks else len(data)
    names = header.names
    roles = _roles(index)
    exact = {index[r] for r in ("t", "nanosec") if r in index and (r == "nanosec" or "nanosec" in index)}
    first_row = bytes(data[start : data.find(b"\n", start) if data.find(b"\n", start) > 0 else end])
    first_t = _split_line(first_row.decode("utf-8", "replace"), header.delimiter)[index["t"] :][:1]
    long_int = bool(first_t) and first_t[0].isdigit() and len(first_t[0]) >= 16
    if (header.cmap is not None and header.cmap.units["t"].name == "ns") or long_int:
        exact.add(index["t"])  # integer ns stamps: int64, exact beyond 2**53
    decimal_t = bool(first_t) and _exact_seconds(first_t[0], header) and "nanosec" not in index
    if decimal_t:  # absolute seconds with decimals (PlotJuggler, bag converters): exact, as ns
        exact.discard(index["t"])
    types = {
        name: (pa.int64() if j in exact else pa.float64()) if j in index.values() else pa.string()
        for j, name in enumerate(names)
    }
    if decimal_t:
        types[names[index["t"]]] = pa.decimal128(19, 9)
    body = memoryview(data)[start:end]
    try:
        reader = pacsv.open_csv(  # block by block, so that progress can be shown
            pa.BufferReader(_arrow_owned(body)),
            # one thread: faster than pyarrow's default threads on a busy 2-core machine
            read_options=pacsv.ReadOptions(column_names=names, use_threads=False),
            parse_options=pacsv.ParseOptions(
                delimiter=header.delimiter, newlines_in_values=True, ignore_empty_lines=False
            ),
            convert_options=pacsv.ConvertOptions(
                column_types=types, check_utf8=True, strings_can_be_null=False, quoted_strings_can_be_null=False,
                decimal_point=header.decimal, null_values=sorted(_NULL_CELLS),
            ),
        )
        try:
            # bytes per row, from the first lines: progress in bytes without tracking them
            sample = body[: 1 << 16]
            row_bytes = len(sample) / max(1, bytes(sample).count(b"\n"))
            batches, reported = [], 0
            for batch in reader:
                batches.append(batch)
                if progress is not None:
                    step = min(int(batch.num_rows * row_bytes), len(body) - reported)
                    reported += step
                    progress(step)
            table = pa.Table.from_batches(batches, schema=reader.schema)
        finally:
            reader.close()  # its read-ahead thread ends here, not at exit (a SIGABRT otherwise)
    except (pa.ArrowException, ValueError):
        return None
    if progress is not None and reported < len(body):
        progress(len(body) - reported)
    n = table.num_rows
    wanted = [table.column(index[name]) for name in roles]
    if n == 0 or (fmt.missing == "fail" and any(col.null_count for col in wanted)):
        return None
    quoted = data.find(b'"', start, end) >= 0
    if quoted and bytes(body).count(b"\n") + (not bytes(body).endswith(b"\n")) != n:
        return None  # a record spans lines: the text parser tells a note from a stray quote
    # filled in place: fresh pages cost more than the copy itself, so no temporaries
    if decimal_t:
        if wanted[0].null_count:
            return None
        # a decimal128's 16 bytes are its unscaled integer, little-endian: here the stamp in ns (< 2**63)
        t = np.concatenate([np.frombuffer(c.buffers()[1], dtype=np.int64)[2 * c.offset : 2 * (c.offset + len(c)) : 2]
                            for c in wanted[0].chunks]) if wanted[0].num_chunks else np.zeros(0, dtype=np.int64)
        header.t_in_ns = True
    elif index["t"] in exact and "nanosec" not in index:
        t = wanted[0].to_numpy(zero_copy_only=False).astype(np.float64) if wanted[0].null_count else np.array(
            wanted[0].to_numpy(), dtype=np.int64
        )
    elif "nanosec" in index:
        if any(c.null_count for c in (wanted[0], wanted[-1])):
            return None  # the text parser words (or drops) it
        sec, nsec = np.array(wanted[0].to_numpy(), dtype=np.int64), np.array(wanted[-1].to_numpy(), dtype=np.int64)
        if not (_split_stamp_valid("t", sec).all() and _split_stamp_valid("nanosec", nsec).all()):
            return None  # the text parser words it
        t = sec * 1_000_000_000 + nsec
    else:
        t = np.array(wanted[0].to_numpy(zero_copy_only=False), dtype=np.float64)
    wrench = np.empty((n, 6))
    for i, col in enumerate(wanted[1:7]):
        wrench[:, i] = col.to_numpy(zero_copy_only=False)
    tf = t.astype(np.float64, copy=False)
    if fmt.missing == "fail":
        if not (np.isfinite(tf).all() and np.isfinite(wrench).all()):
            return None
    elif np.isinf(tf).any() or np.isinf(wrench).any():
        return None
    if (np.diff(tf[~np.isnan(tf)]) < 0).any():
        return None
    extra = {names[j]: table.column(j).to_pylist() for j in range(len(names)) if j not in index.values()}
    return t, wrench, extra, header.data_base + 1, quoted, header


def _arrow_owned(data: memoryview) -> Any:
    """A copy of ``data`` in memory pyarrow allocated (not a Python object's).

    pyarrow's CSV reader reads ahead on its own threads, and one of them may drop the last
    reference to a block a little after the reader is closed. A block of a Python object's
    memory (``pa.py_buffer``) then takes the GIL to release the object; when that happens
    while the interpreter finalises (a run that failed on the log ends at once), the thread
    is ended inside a C++ destructor and the process aborts ("terminate called without an
    active exception", exit -6; seen in a core dump, 3 of 143 runs under load). Memory
    pyarrow owns is freed without the GIL. The copy costs the text's size for as long as
    it is read.
    """
    import pyarrow as pa

    buf = pa.allocate_buffer(len(data))
    np.frombuffer(buf, dtype=np.uint8)[:] = np.frombuffer(data, dtype=np.uint8)
    return buf


def _end_of_content(data: bytes) -> int:
    """``len(data.rstrip())`` without copying a large file."""
    size = 4096
    while True:
        tail = data[-size:]
        stripped = tail.rstrip()
        if stripped or size >= len(data):
            return len(data) - len(tail) + len(stripped)
        size *= 8


#: Hz: below this a t read in seconds is also a sensor's rate read in milliseconds (7 Hz or
#: 7 kHz, an ATI Net F/T's rate): with no unit given, the run asks which
_AMBIGUOUS_RATE_HZ = 20.0
_TIME_UNITS = (("milliseconds", 1e-3, "ms"), ("microseconds", 1e-6, "us"), ("nanoseconds", 1e-9, "ns"))
#: A step in t longer than this many median steps, and than :data:`_GAP_MIN_S`, is a gap (samples
#: a recorder lost): said, not refused
_GAP_STEPS = 10.0
_GAP_MIN_S = 0.05


def _median_step(step: NDArray[np.float64]) -> float:
    """s: the median of the steps in t that move (NaN for fewer than 10: a few hand-typed rows
    say nothing about a sensor's rate)."""
    moving = step[step > 0]
    return float(np.median(moving)) if len(moving) >= 10 else math.nan


def _gap_threshold(median: float) -> float:
    """s: the step in t beyond which samples are missing, for a log whose median step is ``median``."""
    return max(_GAP_STEPS * median, _GAP_MIN_S)


def _gap_note(source: str, count: int, largest: float, where: str, median: float) -> str:
    """The note on the gaps in t: how many, the largest and where it ends."""
    return (
        f"{source}: t has {count} gap{'s' if count > 1 else ''} longer than {_gap_threshold(median):.3g} s (the largest "
        f"{largest:.6g} s, before {where}: about {max(round(largest / median) - 1, 1)} samples at one per "
        f"{median:.6g} s); the estimator runs on across a gap as if its two sides were consecutive samples (its time "
        "windows hold none from inside it)"
    )


def _time_notes(
    t: NDArray[np.float64], source: str, first_line: int | None, *, explicit: bool = False,
    column: str = "t",
) -> tuple[int, list[str]]:
    """Count repeated stamps and say what looks wrong with the time scale.

    ``first_line`` is the line of the first data row when every row is one line (then row
    ``i`` is on line ``first_line + i``), else ``None`` (rows are then named by number).
    ``explicit``: the time unit was given (header, option or softtip's metadata), so it is not
    second-guessed; else a rate as plausible in seconds as in milliseconds asks for ``--time-units``.
    ``column``: the time column's name in the file.
    """

    def where(i: int) -> str:
        return f"line {first_line + i}" if first_line is not None else f"data row {i + 1}"

    notes = []
    step = np.diff(t)
    repeated = step == 0
    n_repeated = int(np.count_nonzero(repeated))
    if n_repeated:
        i = int(np.argmax(repeated)) + 1
        notes.append(
            f"{source}: {n_repeated} repeated time stamp{'s' if n_repeated > 1 else ''} (the first on {where(i)}: "
            f"t = {float(t[i]):.10g} s as on the {'line' if first_line is not None else 'row'} before); kept in file order"
        )
    median = _median_step(step)
    coarse = 2 * n_repeated > len(step)
    if coarse:  # most stamps repeat: the clock ticks slower than the samples come
        notes.append(
            f"{source}: column {column!r}: {n_repeated} of {len(step)} steps are 0"
            + (f" (median step of the rest {median:.6g} s)" if median == median else "")
            + ": the stamps are coarser than the sampling, and every time window (the tare, the "
            "line evidence) counts samples of equal stamps as one instant; expected stamps of the samples' own "
            "resolution"
        )
        # the rate is the samples' over the log's span (the median of the moving steps is the tick)
        span = float(t[-1] - t[0]) if len(t) else 0.0
        median = span / len(step) if span > 0 and len(step) >= 10 else math.nan
    if median == median:
        low, high = PLAUSIBLE_RATE_HZ
        rate = 1.0 / median
        if not low <= rate <= high:
            guesses = [
                f"in {name} {1.0 / (median * scale):.3g} Hz (--time-units {option})"
                for name, scale, option in _TIME_UNITS
                if low <= 1.0 / (median * scale) <= high and not explicit
            ]
            guess = f"; if t is {', or '.join(guesses)}" if guesses else ""
            notes.append(
                f"{source}: column {column!r}: median step {median:.6g} s, i.e. {rate:.3g} samples/s: implausible for a "
                f"force/torque log (expected {low:g} Hz to {high / 1e3:g} kHz with t in seconds){guess}. "
                "Give t in seconds: the tare duration and every time window are in seconds"
            )
        elif rate < _AMBIGUOUS_RATE_HZ and not explicit:
            notes.append(
                f"{source}: column {column!r}: median step {median:.6g}: {rate:.4g} Hz if t is in seconds, {rate * 1e3:.5g} Hz "
                "if in milliseconds, and no unit in the header says which (a force/torque sensor may stream at "
                "either): give --time-units s or --time-units ms"
            )
        if low <= rate <= high and not coarse:  # a time scale in doubt is said above; its gaps would say nothing
            gaps = step > _gap_threshold(median)
            if gaps.any():
                i = int(np.argmax(step)) + 1
                notes.append(_gap_note(source, int(np.count_nonzero(gaps)), float(step[i - 1]), where(i), median))
    return n_repeated, notes


def _cut_last_line(data: bytes, source: str, n_rows: int) -> str | None:
    """A warning when the file ends inside a line whose last number looks cut short.

    A recorder writes whole lines; a file that stops without a line break was cut while
    being written (a crash, a full disk, a copy of a file still growing). The row is kept
    (it parsed) but said: when its last cell is shorter than that cell on every one of the
    (up to 100) lines before, its last number has lost digits.
    """
    if not data or data.endswith((b"\n", b"\r")) or n_rows < 4:
        return None
    last_break = data.rfind(b"\n")
    last = data[last_break + 1 :]
    if b'"' in last:
        return None
    # the lines before (a window of bytes; its first line may be partial, or the header)
    before = data[max(0, last_break - 200 * (len(last) + 1)) : last_break + 1].splitlines()[1:][-100:]
    ncells = last.count(b",") + 1
    cells = [line.rsplit(b",", 1)[-1].strip() for line in before if line.count(b",") + 1 == ncells]
    cell = last.rsplit(b",", 1)[-1].strip()
    # only a column of measured values (a decimal point or an exponent in every cell), not
    # counters, flags or text, whose lengths vary by nature
    if len(cells) < 3 or not all(b"." in c or b"e" in c.lower() for c in cells):
        return None
    lengths = [len(c) for c in cells]
    if len(cell) >= min(lengths):
        return None
    line = data.count(b"\n") + 1
    return (
        f"{source}:{line}: the file ends inside this line (no line break after it) and its last cell "
        f"{cell.decode('utf-8', 'replace')!r} is shorter than on any of the {len(lengths)} lines before: the "
        "log was probably cut while being written and this number lost digits (the row is kept; delete the line "
        "if it is incomplete)"
    )


# --------------------------------------------------------------------------------------
# Parquet

#: Key-value metadata softtip reads and writes in a Parquet file's schema.
PARQUET_UNITS_KEY = "softtip.units"
PARQUET_FINGERTIP_KEY = "softtip.fingertip"


def _read_parquet(path: str | os.PathLike[str], source: str, units: str | None, fmt: str = "parquet",
                  layout: LogFormat | None = None, stated: Sequence[str] = ()) -> Log:  # fmt: skip
    """A log from a Parquet or Arrow IPC (Feather v2) file (``fmt``): the same columns and checks as
    CSV, rows named by number: the column names read as a CSV header's, with the options
    ``layout`` gives (columns, units, ``--missing``; :func:`_read_mapped_table`). The schema's
    ``softtip.units`` metadata (softtip's own files) gives the wrench's units where the names
    give none, and says ``t`` is in seconds. ``stated``: the per-quantity unit options given
    (their names), which a file with that metadata refuses."""
    import pyarrow as pa

    layout = layout or LogFormat.of(units)
    name = TABLE_FORMATS[fmt][1]
    what = f"{name} log file"
    try:
        with _ColumnarFile(path, fmt) as pf:
            table = pf.read()
    except (FileNotFoundError, IsADirectoryError, PermissionError) as exc:
        raise _opening_error(exc, source, what) from None
    except (pa.ArrowException, OSError) as exc:
        raise InputError(f"{source}: not a readable {name} file ({exc}); expected a{'n' if fmt == 'arrow' else ''} {what}") from None
    meta = {k.decode("utf-8", "replace"): v.decode("utf-8", "replace") for k, v in (table.schema.metadata or {}).items()}
    file_units = meta.get(PARQUET_UNITS_KEY)
    if file_units is not None and file_units not in UNIT_SYSTEMS:
        raise InputError(
            f"{source}: metadata {PARQUET_UNITS_KEY} = {file_units!r}; expected one of: {', '.join(UNIT_SYSTEMS)}"
        )
    if units is not None and file_units is not None and units != file_units:
        raise InputError(
            f"{source}: the file's metadata says its wrench is in {file_units}, but {units} was asked for; "
            f"expected the units to agree (leave them out to use the file's)"
        )
    names = list(table.column_names)
    if file_units is not None and stated:
        raise InputError(
            f"{source}: the file's metadata says its wrench is in {file_units} and its t in s; {', '.join(stated)} "
            f"appl{'ies' if len(stated) == 1 else 'y'} to a file without that metadata (leave "
            f"{'it' if len(stated) == 1 else 'them'} out)"
        )
    if units is None and file_units not in (None, "si"):  # the metadata's units for the columns that give none
        force, moment = UNIT_SYSTEM_UNITS[file_units]
        layout = replace(layout, force_unit=force, moment_unit=moment)
    # every file through the same checks as a CSV log's (time unit and origin, the units the
    # wrench was read in for the units check); softtip's metadata says t is in seconds
    return _read_mapped_table(table, names, source, layout, units or file_units or "si", t_stated=file_units is not None)


def _table_numbers(col: Any, where: str, *, missing: bool = False, exact: bool = False,
                   expected: str = "a number") -> NDArray[Any]:  # fmt: skip
    """A Parquet or Arrow column of a required role as numbers (float64; int64 when ``exact``, an
    integer column of a stamp without nulls), or the located error (``where``: the file and the
    column; rows counted from 1; ``expected``: what a cell should be, in the message of a null).
    ``missing``: nulls (as NaN) and NaN pass, for ``--missing``."""
    import pyarrow as pa

    if not (pa.types.is_floating(col.type) or pa.types.is_integer(col.type)):
        raise InputError(f"{where}: expected numbers, got type {col.type}")
    exact = exact and pa.types.is_integer(col.type) and not col.null_count
    if col.null_count and not missing:
        row = int(np.argmax(col.is_null().to_numpy(zero_copy_only=False))) + 1
        raise InputError(f"{where}, row {row}: empty (null); expected {expected}{_MISSING_FIX}")
    v = np.asarray(col.to_numpy(zero_copy_only=False), dtype=np.int64 if exact else np.float64)
    bad = np.isinf(v) if missing or exact else ~np.isfinite(v)
    if bad.any():
        row = int(np.argmax(bad))
        raise InputError(f"{where}, row {row + 1}: expected a finite number, got {float(v[row])!r}"
                         f"{'' if np.isinf(v[row]) else _MISSING_FIX}")  # fmt: skip
    return v


def _whole_ns(column: Any) -> NDArray[np.int64] | None:
    """A ``stamp_ns`` column (softtip's int64, a file's integers or CSV text) as int64 ns; None
    where it holds other than whole numbers."""
    values = np.asarray(column)
    if values.dtype.kind in "iu":
        return values.astype(np.int64, copy=False)
    if values.dtype.kind == "f":  # a float column (Parquet, Arrow): its whole values, to float64's resolution
        whole = np.isfinite(values).all() and (values == np.floor(values)).all() and np.abs(values).max(initial=0) < 2**63
        return values.astype(np.int64) if whole else None
    try:  # text (CSV): numpy's conversion is exact for whole numbers, as int() is
        return values.astype(str).astype(np.int64)
    except (ValueError, OverflowError):  # a column of that name that holds no whole ns
        return None


def _file_stamps(column: Any, stamps: NDArray[np.int64]) -> NDArray[np.int64] | None:
    """A log's own ``stamp_ns`` column as int64 ns where it holds ``stamps`` (the stamps of its
    ``t``) to ``t``'s resolution: within half a sample's step (at least 1 µs), as ``t`` printed
    with fewer digits than the column's exact nanoseconds is; None where it holds others."""
    values = _whole_ns(column)
    if values is None or values.shape != stamps.shape:
        return None
    steps = np.diff(stamps)
    moving = steps[steps > 0]
    tolerance = max(1000.0, 0.5 * float(np.median(moving))) if len(moving) else 1000.0
    return values if bool((np.abs(values - stamps) <= tolerance).all()) else None


def _said(value: Any, origin: int) -> str:
    """A stamp as a message gives it: the value, or ``origin`` plus a whole offset as an integer."""
    return repr(value.item()) if not origin else str(origin + int(value))


def _is_time_type(kind: Any) -> bool:
    """A Parquet or Arrow column type that carries its own time unit: a timestamp (a date, as
    pandas writes ``datetime64`` and ROS exports write ``header.stamp``) or a duration."""
    import pyarrow as pa

    return pa.types.is_timestamp(kind) or pa.types.is_duration(kind)


def _stamps_as_ns(col: Any, where: str, fmt: LogFormat, split: bool) -> Any:
    """A timestamp or duration column as int64 nanoseconds (Unix time for a timestamp, whatever
    its time zone: Arrow keeps timestamps in UTC), or the located error where the options say
    otherwise. The unit is the column type's: ``--time-units`` would contradict it."""
    import pyarrow as pa

    if fmt.time_unit is not None:
        raise InputError(f"{where}: its type {col.type} carries its own time unit; --time-units {fmt.time_unit} "
                         "applies to a column of numbers (leave it out)")  # fmt: skip
    if split:
        raise InputError(f"{where}: its type {col.type} is a whole stamp; expected whole seconds when a nanosec "
                         "column is mapped too (leave --columns nanosec=... out)")  # fmt: skip
    try:
        return col.cast(pa.duration("ns") if pa.types.is_duration(col.type) else pa.timestamp("ns")).cast(pa.int64())
    except pa.ArrowInvalid as exc:  # beyond int64 nanoseconds (after 2262)
        raise InputError(f"{where}: {exc}; expected stamps between the years 1678 and 2262") from None


def _check_time_order(t: NDArray[Any], source: str, columns: str, unit: str = "", origin: int = 0) -> None:
    """The located error of stamps that go back (a missing, NaN, stamp skipped); ``columns``: their
    names; ``unit``: said after the values (`` ns`` for a date's nanoseconds); ``origin``: added
    to the values said (``t`` holds offsets from it)."""
    tf = t.astype(np.float64, copy=False)
    known = np.flatnonzero(~np.isnan(tf))
    back = np.flatnonzero(np.diff(tf[known]) < 0)
    if len(back):
        row, before = int(known[back[0] + 1]), int(known[back[0]])
        raise InputError(
            f"{source}: column {columns}, row {row + 1}: expected t non-decreasing (a stamp may repeat, not go back), "
            f"got t = {_said(t[row], origin)}{unit} at row {row + 1} after t = {_said(t[before], origin)}{unit} at row "
            f"{before + 1}"
        )


def _read_mapped_table(table: Any, names: list[str], source: str, fmt: LogFormat, units: str, *,
                       t_stated: bool = False) -> Log:  # fmt: skip
    """A Parquet or Arrow table whose column names are read as a CSV header's (the recognised
    layouts, ``--columns``, units in the names or the unit options; ``fmt``), then the same
    missing cells, time unit and origin and wrench units as a CSV log (:func:`_finish`); rows
    named by number. ``t_stated``: the file says its ``t`` is in seconds (softtip's metadata)."""
    import pyarrow as pa
    import pyarrow.compute  # noqa: F401  (pa.compute)

    stripped = [n.strip() for n in names]
    header = _Header(names=stripped, line=0, data_base=0, lines=io.StringIO(), comments=[], columnar=True,
                     t_stated=t_stated)  # fmt: skip
    try:
        header.cmap = resolve_columns(stripped, fmt)
        dated = [name for name, f in zip(stripped, table.schema) if pa.types.is_timestamp(f.type)]
        if header.cmap is None and "t" not in fmt.columns and len(dated) == 1:
            # no layout names a time column, and one column is typed a date (pandas' index,
            # ``__index_level_0__`` when unnamed; a ROS export's ``header.stamp``): it is t
            header.cmap = resolve_columns(stripped, replace(fmt, columns={**fmt.columns, "t": dated[0]}))
            if header.cmap is not None:
                header.cmap = replace(header.cmap, source=header.cmap.source.replace("--columns", "its one date-typed column", 1))
    except ColumnError as exc:
        raise InputError(f"{source}: {exc}") from None
    try:
        index = _column_index(header, source)
    except InputError as exc:  # the CSV wording, without a header line
        said = str(exc).replace(f"{source}:0: ", f"{source}: ", 1)
        if len(dated) > 1 and "missing column" in said and "'t'" in said:
            said += f" Columns typed a date: {', '.join(map(repr, dated))}; say which is t: --columns t=NAME."
        raise InputError(said) from None
    n = table.num_rows
    if n == 0:
        raise InputError(f"{source}: no rows; expected at least one row of {_EXPECTED_HEADER}")
    values = {}
    for role in _roles(index):
        where = f"{source}: column {names[index[role]]!r}"
        col = table.column(index[role])
        typed = role == "t" and _is_time_type(col.type)
        if typed:
            header.cmap = replace(header.cmap, typed={"t": str(col.type)}, units={**header.cmap.units, "t": get_unit("ns", "time")})
            header.t_dated = pa.types.is_timestamp(col.type)
            col = _stamps_as_ns(col, where, fmt, "nanosec" in index)
            header.t_in_ns = True
            if col.null_count and fmt.missing != "fail" and col.null_count < len(col):
                # NaN for the holes needs float64, which holds a date's nanoseconds to 256 ns:
                # offsets from the first stamp are exact (to 104 days)
                header.t_origin_ns = int(pa.compute.min(col).as_py())
                col = pa.compute.subtract(col, header.t_origin_ns)
        v = _table_numbers(col, where, missing=fmt.missing != "fail", exact=role in _SPLIT_STAMP,
                           expected="a time stamp" if typed else "a number")  # fmt: skip
        if role in _SPLIT_STAMP and "nanosec" in index:
            ok = _split_stamp_valid(role, v) | np.isnan(v)
            if not ok.all():
                row = int(np.argmin(ok))
                raise InputError(f"{where}, row {row + 1}: expected {_SPLIT_STAMP[role][1]} (the stamp is split in "
                                 f"seconds and nanoseconds), got {v[row]!r}")  # fmt: skip
        values[role] = v
    t = values["t"]
    if "nanosec" in index:  # whole seconds and nanoseconds: exact as int64 ns, as a CSV log's (_combine_time)
        t = _combine_time(np.column_stack((values["t"], values["nanosec"])).astype(np.float64), ["t", "nanosec"])
    wrench = np.empty((n, 6))
    for k, role in enumerate(ROLES[1:]):
        wrench[:, k] = values[role]
    _check_time_order(t, source, " and ".join(repr(names[index[r]]) for r in ("t", "nanosec") if r in index),
                      " ns" if header.t_in_ns else "", header.t_origin_ns)  # fmt: skip
    extra = {names[j]: table.column(j).to_numpy(zero_copy_only=False) for j in range(len(names)) if j not in index.values()}
    return _finish(t, wrench, extra, header, fmt, source, units, None, None)


def _column_index(header: _Header, source: str) -> dict[str, int]:
    """Map each required column to its position; raise on duplicate or missing names.

    The header's names may be those of :data:`~softtip.io.formats.SOURCES`: a missing column is
    one no dialect reads, and no column a dialect reads is offered as a misspelling."""
    names, line = header.names, header.line
    positions = ",".join(f"{c}={k + 1}" for k, c in enumerate(REQUIRED_COLUMNS))
    looks_like_data = (
        f"Line {line} looks like data; expected the header row first (a file without one: give the columns "
        f"by position, e.g. --columns {positions})."
    )
    seen: dict[str, int] = {}
    for j, name in enumerate(names):
        if name in seen:
            unnamed = [k + 1 for k, n in enumerate(names) if not n.strip()]
            raise InputError(
                f"{source}:{line}: duplicate column {name!r} (columns {seen[name] + 1} and {j + 1}); "
                "expected each column name once"
                # a first row of data repeats values (zeros) as no header repeats a name
                + (f". {looks_like_data}" if all(_is_number(n.replace(",", ".")) for n in names) else "")
                # a spreadsheet's empty columns: a delimiter at the end of every line, or more
                + (f". Columns {', '.join(map(str, unnamed))} have no name (a spreadsheet's empty columns, or a "
                   "delimiter at the end of each line?): delete them, or name them" if not name.strip() else "")
            )  # fmt: skip
        seen[name] = j

    if header.cmap is not None:
        return {r: header.cmap.index[r] for r in (*ROLES, "nanosec") if r in header.cmap.index}
    missing = [c for c in REQUIRED_COLUMNS if c not in seen]
    read = recognised_roles(names)
    if any(c not in read for c in missing):  # else each is read, by dialects that do not go together
        missing = [c for c in missing if c not in read]
    else:
        read = {}
    if missing:
        msg = (
            f"{source}:{line}: missing column{'s' if len(missing) > 1 else ''} "
            f"{', '.join(repr(c) for c in missing)}; expected a header with columns "
            f"{_EXPECTED_HEADER} (any order)"
        )
        hints = _near_misses(missing, names, set(read.values()))
        if len(names) == 1:
            for delim, label in ((";", "semicolon"), ("\t", "tab")):
                if delim in names[0]:
                    hints.append(f"The header looks {label}-separated; expected commas between columns.")
            cells = names[0].split()
            if set(REQUIRED_COLUMNS) <= set(cells):
                hints.append("The header looks space-separated; softtip reads comma, tab or semicolon delimiters: "
                             "replace the spaces between cells (e.g. tr -s ' ' ',').")  # fmt: skip
            elif len(cells) > 1 and all(_is_number(c) for c in cells):  # numpy.savetxt's default: spaces, no header
                hints.append(f"Line {line} looks like space-separated numbers; softtip reads comma, tab or semicolon "
                             "delimiters: replace the spaces between cells (e.g. tr -s ' ' ','), then give the "
                             "header or --columns.")  # fmt: skip
        # numpy.savetxt(header=...) writes "# t,fx,...": point at it rather than guess.
        commented = [
            ln
            for ln, text in header.comments
            if set(REQUIRED_COLUMNS) <= {x.strip() for x in text.lstrip("#").split(",")}
        ]
        if commented:
            hints.append(
                f"Line {commented[-1]} looks like the header commented out with '#'; remove the '#', or read the "
                f"columns by position: --columns {','.join(f'{c}={k + 1}' for k, c in enumerate(REQUIRED_COLUMNS))}."
            )
        elif all(_is_number(n.replace(",", ".")) for n in names):
            hints.append(looks_like_data)
        hints.append(
            "Other names: map them with --columns t=NAME,fx=NAME,… (docs/guide/input-formats.md lists the headers read as they are)."
        )
        raise InputError(" ".join([msg + ".", *hints]))
    return {c: seen[c] for c in REQUIRED_COLUMNS}


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def _near_misses(missing: list[str], names: list[str], read: set[int] | None = None) -> list[str]:
    """'did you mean' hints: header names that look like a missing required column.

    Names are compared after lower-casing and dropping everything but letters and digits,
    so ``Fx``, ``f_x``, ``f x`` and ``fx [N]`` all point at ``fx``. ``read``: positions of
    columns a dialect reads already (not a misspelling).
    """

    def norm(s: str) -> str:
        return "".join(ch for ch in s.lower() if ch.isalnum())

    # Only names that are not already a required column can be the misspelling.
    candidates = {j: norm(n) for j, n in enumerate(names) if n not in REQUIRED_COLUMNS and j not in (read or ())}
    hints = []
    for col in missing:
        best: int | None = None
        for j, cand in candidates.items():
            if cand == col or (col == "t" and cand in _TIME_ALIASES):
                best = j
                break
        if best is None and col == "t":  # a time column with a unit in its name: timestamp_ms, time_us
            best = next((j for j, cand in candidates.items() if "time" in cand or "stamp" in cand), None)
        if best is None:
            match = difflib.get_close_matches(col, list(candidates.values()), n=1, cutoff=0.6)
            if match:
                best = next(j for j, cand in candidates.items() if cand == match[0])
        if best is not None:
            unit = re.search(r"(?:^|[^a-z])(ms|us|ns|msec|usec|nsec)$", names[best].strip().lower()) if col == "t" else None
            how = f" (--columns t={names[best]} --time-units {unit.group(1)[:2]})" if unit else ""
            hints.append(f"Column {best + 1} is {names[best]!r}: did you mean {col!r}?{how}")
            del candidates[best]
    return hints


_DECIMAL_SECONDS = re.compile(r"^\s*\d{9,10}\.\d{1,9}\s*$")


def _exact_seconds(cell: str, header: _Header) -> bool:
    """Whether a first ``t`` cell is an absolute stamp in seconds with decimals (read exactly, as ns)."""
    cmap = header.cmap
    cell = cell.replace(",", ".") if header.decimal == "," else cell  # a decimal comma: the same stamp
    return (
        bool(_DECIMAL_SECONDS.match(cell))
        and (cmap is None or cmap.units["t"].name == "s")
        and ABSOLUTE_STAMP_S <= float(cell) < LATEST_STAMP_S
    )


def _roles(index: Mapping[str, int]) -> list[str]:
    """The roles of ``index`` in block order: ``t``, ``fx`` … ``mz``, then ``nanosec`` if there."""
    return [r for r in (*ROLES, "nanosec") if r in index]


#: A stamp split in seconds and nanoseconds (ROS): whole seconds that int64 nanoseconds hold
#: (to 2262), whole nanoseconds below a second.
_SPLIT_STAMP = {"t": (LATEST_STAMP_S, "whole seconds from 0 to 9.2e9"), "nanosec": (1e9, "whole nanoseconds from 0 to 999999999")}


def _split_stamp_valid(role: str, value: Any) -> Any:
    """Whether ``value`` (a float, or an array: elementwise) is a valid ``role`` part of a split stamp."""
    high = _SPLIT_STAMP[role][0]
    if isinstance(value, float):  # a cell of the row-by-row parser: no array per cell
        return 0.0 <= value < high and value == math.floor(value)
    return (value >= 0) & (value < high) & (value == np.floor(value))


def _combine_time(block: NDArray[np.float64], roles: list[str]) -> NDArray[Any]:
    """``t`` of a block: its first column, or seconds and nanoseconds combined as int64 ns."""
    if "nanosec" not in roles:
        return np.ascontiguousarray(block[:, 0])
    sec, nsec = block[:, 0], block[:, roles.index("nanosec")]
    if not (np.isfinite(sec).all() and np.isfinite(nsec).all()):
        return np.full(len(sec), np.nan)
    return sec.astype(np.int64) * 1_000_000_000 + nsec.astype(np.int64)


def _parse_fast(
    header: _Header, index: dict[str, int]
) -> tuple[NDArray[Any], NDArray[np.float64], dict[str, list[str]]]:
    """Parse a well-formed log in blocks; raise :class:`_Suspect` at the first oddity.

    Work per block is in C (csv, ``zip``, numpy's string-to-float), so a 1e6-row log takes
    a few seconds. Error reporting is left to :func:`_parse_careful`.
    """
    ncol = len(header.names)
    roles = _roles(index)
    reader = csv.reader(header.lines, delimiter=header.delimiter)
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
            k = n_read = len(rows)
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
            if not blocks and "nanosec" not in index:
                first_t = cols[index["t"]][0].strip()
                if _exact_seconds(first_t, header) or (first_t.isdigit() and len(first_t) >= 16):
                    raise _Suspect(previous)  # stamps that are exact only as ns: the careful parser reads them so
            block = np.empty((len(rows), len(roles)))
            for i, name in enumerate(roles):
                cells = cols[index[name]]
                if header.decimal == ",":
                    cells = [c.replace(",", ".") for c in cells]
                block[:, i] = np.array(cells, dtype=np.float64)
            t = block[:, 0]
            if not np.isfinite(block).all() or t[0] < last_t or (np.diff(t) < 0).any():
                raise _Suspect(previous)  # from the previous block: t's predecessor is there
            if "nanosec" in roles and not all(_split_stamp_valid(r, block[:, roles.index(r)]).all() for r in _SPLIT_STAMP):
                raise _Suspect(previous)
            if reader.line_num - current[1] != n_read:  # a record spans lines
                if any(_swallowed(c, header.delimiter, ncol) for j in extra_idx for c in cols[j]):
                    raise _Suspect(previous)
            last_t = t[-1]
            blocks.append(block)
            for j in extra_idx:
                extra[header.names[j]].extend(cols[j])
    except (ValueError, csv.Error):  # a non-numeric cell, or csv's own complaints
        raise _Suspect(previous) from None
    if not blocks:
        raise _Suspect(previous)  # header only: the careful parser words it
    data = np.concatenate(blocks) if len(blocks) > 1 else blocks[0]
    return _combine_time(data, roles), np.ascontiguousarray(data[:, 1:7]), extra


def _lines_at_end(lines: Any) -> bool:
    """Whether the text ``lines`` reads from (an :class:`io.StringIO` or :class:`_FileLines`) is all read."""
    if isinstance(lines, _FileLines):
        return lines.at_end()
    return lines.tell() >= len(lines.getvalue())


class _FileLines:
    """The lines of a text file from its current position, for :func:`_parse_careful` in place
    of an :class:`io.StringIO` of the whole text (a line at a time in memory): ``seek`` takes
    it back to where it started (the only position that parser seeks to here)."""

    def __init__(self, text: io.TextIOWrapper) -> None:
        self._text = text
        self._begin = text.tell()

    def seek(self, pos: int) -> int:
        self._text.seek(self._begin)
        return pos

    def readline(self) -> str:
        return self._text.readline()

    def __iter__(self) -> _FileLines:
        return self

    def __next__(self) -> str:
        line = self._text.readline()  # not iteration: that would turn tell() off
        if not line:
            raise StopIteration
        return line

    def at_end(self) -> bool:
        return self._text.read(1) == ""


def _parse_careful(
    header: _Header, index: dict[str, int], source: str, start: tuple[int, int], missing: str = "fail", keep: bool = True
) -> tuple[NDArray[Any], NDArray[np.float64], dict[str, list[str]]]:
    """Row-by-row parse that raises the first problem in file order, with its line.

    Starts at ``start`` = ``(text position, csv line_num)`` of a record boundary in the data
    (``line_num`` 0: the first data record). Returns the rows from there if, against
    expectation, nothing is wrong. ``missing`` other than ``"fail"``: an empty or ``nan``
    cell of a required column is kept as NaN. ``keep`` False: the rows are checked, not
    kept (memory bounded by a row: :meth:`LogBlocks.locate_error` over a whole file), and
    empty arrays come back.
    """
    names = header.names
    ncol = len(names)
    roles = _roles(index)
    # Required cells are checked left to right as they appear in the file.
    checks = sorted((j, name) for name, j in index.items())
    extra_idx = [j for j in range(ncol) if j not in index.values()]
    header.lines.seek(start[0])
    reader = csv.reader(header.lines, delimiter=header.delimiter)
    comma = header.decimal == ","
    fix = _MISSING_FIX
    # A record ends on line base + line_num and starts one after the previous one ended.
    base = header.data_base + start[1]
    values: list[list[float]] = []
    big_t: list[int | float] = []  # t cells as Python numbers (ints beyond 2**53 kept exact)
    exact_ns: list[int | None] | None = None  # absolute decimal seconds as ns, as the pyarrow path reads them
    if start[1] == 0 and "nanosec" not in index:
        first = header.lines.readline()
        header.lines.seek(start[0])
        cells = _split_line(first, header.delimiter)
        if len(cells) == ncol and _exact_seconds(cells[index["t"]], header):
            exact_ns = []
    extra: dict[str, list[str]] = {names[j]: [] for j in extra_idx}
    prev_end = 0
    rows = 0
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
        span = reader.line_num - prev_end
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
        if span > 1:  # a quoted cell spans lines: fine for a note, not when it takes in data rows
            for j, cell in enumerate(row):
                k = _swallowed(cell, header.delimiter, ncol)
                if k:
                    at_end = _lines_at_end(header.lines) and cell.endswith(("\n", "\r"))
                    column = names[j] if j < len(names) else f"#{j + 1}, beyond the header's {len(names)}"
                    raise _swallow_error(source, line, column, cell, base + prev_end, at_end, k)
        if len(row) != ncol:
            hint = ""
            if len(row) == ncol + 1 and not row[-1].strip():
                hint = "; its last cell is empty: a delimiter at the end of each row that the header lacks? Remove it"
            elif all(_is_blank(more) for more in reader):  # the file's last line (the reader is not needed after this)
                hint = _FOOTER_HINT
            per = f"one per column of the {header.cmap.source} layout" if header.headerless and header.cmap else "one per header column"
            error = _Unfinished if len(row) < ncol else InputError  # cells missing: a line cut short, if it is the last
            raise error(f"{source}:{line}: expected {ncol} cells ({per}), got {len(row)}{hint}")
        sample = [0.0] * len(roles)
        for j, name in checks:
            cell = row[j]
            where = f"{source}:{line}: column {names[j]!r}"
            if not cell.strip():
                if missing != "fail":
                    sample[roles.index(name)] = math.nan
                    continue
                raise InputError(f"{where}: empty cell; expected a number{fix}")
            try:
                value = float(cell.replace(",", ".") if comma else cell)
            except ValueError:
                if cell.strip() in _NULL_CELLS:  # a missing value's spelling (pyarrow's reader takes it as one too)
                    if missing != "fail":
                        sample[roles.index(name)] = math.nan
                        continue
                    raise InputError(f"{where}: expected a number, got {cell!r} (a missing value){fix}") from None
                clock = name in ("t", "nanosec") and re.fullmatch(r"\s*\d{1,2}:\d{2}(:\d{2}([.,]\d+)?)?\s*", cell)
                hint = ("; clock times (hh:mm:ss) are not read: give t in seconds, or map a column of seconds or "
                        "stamps with --columns t=NAME") if clock else ""  # fmt: skip
                if name == "t" and re.match(r"\s*\d{4}-\d{2}-\d{2}[T ]\d", cell):  # ISO 8601, as pandas' to_csv writes
                    hint = ("; dates as text are not read from CSV: give t in seconds (or Unix time), or write the log "
                            "as Parquet or Arrow, whose timestamp columns are read as dates")  # fmt: skip
                if not comma and re.fullmatch(r"\s*[-+]?\d+,\d+\s*", cell):  # a quoted decimal comma
                    hint = ("; a decimal comma: read with semicolon or tab delimiters only (a comma-separated file "
                            "needs decimal points; re-export it with them, or with ';' between cells)")
                error = _Unfinished if j == len(row) - 1 else InputError  # the row's last cell: a number cut short?
                raise error(f"{where}: expected a number, got {cell!r}{hint}") from None
            if math.isnan(value) and missing != "fail":
                sample[roles.index(name)] = math.nan
                continue
            if not math.isfinite(value):
                raise InputError(f"{where}: expected a finite number, got {cell!r}{fix if math.isnan(value) else ''}")
            if "nanosec" in index and name in _SPLIT_STAMP and not _split_stamp_valid(name, value):
                raise InputError(
                    f"{where}: expected {_SPLIT_STAMP[name][1]} (the stamp is split in seconds and nanoseconds), "
                    f"got {cell.strip()!r}; if this column is not a stamp's part, map the columns with --columns"
                )
            if name == "t":
                if value < last_t:
                    raise InputError(
                        f"{where}: expected t non-decreasing (a stamp may repeat, not go back), got "
                        f"t = {cell.strip()} on line {line} after t = {last_t_text} on line {last_t_line}"
                    )
                last_t, last_t_text, last_t_line = value, cell.strip(), line
                if abs(value) > 2.0**53:
                    try:
                        value = int(cell)  # type: ignore[assignment]
                    except ValueError:
                        pass
            sample[roles.index(name)] = value
        rows += 1
        if not keep:
            continue
        big_t.append(sample[0])
        if exact_ns is not None:
            exact_ns.append(_ns_of(row[index["t"]].replace(",", ".") if comma else row[index["t"]]))
        values.append(sample)
        for j in extra_idx:
            extra[names[j]].append(row[j])
    if not rows and start[1] == 0:
        raise InputError(
            f"{source}:{header.line}: header only, no data rows; expected at least one row of "
            f"{_EXPECTED_HEADER} after the header"
        )
    data = np.array(values, dtype=np.float64).reshape(-1, len(roles))
    t = _combine_time(data, roles)
    if any(isinstance(v, int) for v in big_t) and all(isinstance(v, int) for v in big_t):
        t = np.array(big_t, dtype=np.int64)
    if exact_ns and all(v is not None for v in exact_ns):
        t = np.array(exact_ns, dtype=np.int64)
        header.t_in_ns = True
    return t, np.ascontiguousarray(data[:, 1:7]), extra


# --------------------------------------------------------------------------------------
# writing


def write_table(
    columns: Mapping[str, Sequence[Any] | np.ndarray],
    dest: str | os.PathLike[str] | None | TextIO,
    *,
    float_format: str = "%.10g",
    metadata: Mapping[str, str] | None = None,
    progress: Callable[[int], object] | None = None,
    statistics: bool = False,
) -> None:
    """Write columns as a CSV table with a header row, as Parquet or as Arrow IPC (Feather v2).

    Parameters
    ----------
    columns : mapping of str to 1-D sequence or array, each of length N
        Header names (in mapping order) and their values. Values are written as given:
        convert units first.
    dest : str, path-like, text stream or None
        ``None`` writes CSV to ``sys.stdout``; a stream is written to and left open; a path
        is written atomically (a temporary file in the same directory, then
        ``os.replace``): on any failure the temporary file is removed and an existing file
        at ``dest`` is left untouched. A path ending in ``.parquet`` is written as Parquet
        (pyarrow; values exactly, booleans as booleans, text as strings, ``metadata`` in
        the schema's key-value metadata; :data:`PARQUET_COMPRESSION`, dictionary encoding
        for the columns that are not floating point, no column statistics unless
        ``statistics``), one ending in ``.arrow`` or ``.feather`` as Arrow IPC (the Feather
        v2 file format; the same columns and types, :data:`ARROW_COMPRESSION`).
        :class:`TableWriter` writes a table piece by piece.
    float_format : str
        CSV only: a printf-style format for one float. ``"%.<d>g"`` with ``d`` ≤ 17 (the
        default ``"%.10g"``; ``"%.17g"`` round-trips float64 exactly) writes each value
        rounded to ``d`` significant digits as the shortest text that reads back to it
        (pyarrow's writer: ``1e-05`` may come out as ``0.00001``, ``45.0`` as ``45``);
        any other format is applied by Python, cell by cell (slower).
    metadata : mapping of str to str, optional
        Parquet and Arrow IPC only: key-value metadata stored with the schema (softtip writes
        the units and the fingertip; see :data:`PARQUET_UNITS_KEY`, :data:`PARQUET_FINGERTIP_KEY`).
    progress : callable, optional
        Called with the number of rows written after each block (e.g. ``tqdm.update``).
    statistics : bool
        Parquet only: write each column chunk's statistics (min, max, null count), which
        readers use to skip row groups in queries; off by default (they cost write time).

    CSV blocks are formatted on up to :data:`_WRITE_THREADS` threads at once (pyarrow formats
    without holding the GIL) and written in order; at most twice that many wait in memory.

    CSV cells: NaN as ``nan``, infinities as ``inf``/``-inf``; booleans as ``0``/``1``;
    integers, strings and anything else with ``str``. A text cell that holds a comma, a quote
    or a line break is quoted (a quote doubled inside), and only such a cell, whichever writer
    formats it: a cell's text does not depend on the other cells.

    Raises
    ------
    ValueError
        No columns, a column that is not 1-D, columns of different lengths, or a
        ``float_format`` that does not format exactly one float into a plain cell.
    InputError
        ``dest`` cannot be created or replaced (missing directory, no permission, a
        directory at ``dest``). It is a ``ValueError`` too.
    """
    text = dest is None or hasattr(dest, "write") or _columnar(dest) is None  # type: ignore[arg-type]
    plan = _plan_table(columns, float_format, text=text)
    plan.progress = progress
    if dest is None:
        _write_rows(sys.stdout, plan)
    elif hasattr(dest, "write"):
        _write_rows(dest, plan)  # type: ignore[arg-type]
    else:
        plan.columnar = _columnar(dest)  # type: ignore[arg-type]
        plan.parquet = plan.columnar is not None
        plan.metadata = dict(metadata or {})
        plan.statistics = statistics
        _write_atomic(os.fspath(dest), plan)  # type: ignore[arg-type]


@dataclass
class _Plan:
    header: str
    row_format: str  # one row's % format, ending in "\n"
    converters: list[Callable[[np.ndarray], list[Any]]]
    arrays: list[np.ndarray]
    n: int
    names: list[str]
    digits: int | None = None  # pyarrow writer, floats rounded to this many digits; None: Python's %
    quoting: str = "none"  # pyarrow's quoting_style
    parquet: bool = False  # a binary table (Parquet or Arrow IPC): booleans as booleans, text as plain strings
    columnar: str | None = None  # "parquet" or "arrow"
    metadata: dict[str, str] | None = None
    statistics: bool = False
    progress: Callable[[int], object] | None = None
    compiled: _Columns | None = None  # how the compiled CSV formatter takes the columns


def _plan_table(columns: Mapping[str, Sequence[Any] | np.ndarray], float_format: str, *, text: bool = True) -> _Plan:
    """Validate the columns and decide each one's cell format, before touching ``dest``
    (``text``: for CSV; a binary table needs no quoting, which is not looked for then)."""
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
    quoting = "none"
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
            specs.append("%d")
            converters.append(_to_list)
        elif kind in "iu":
            specs.append("%d")
            converters.append(_to_list)
        elif kind == "U":
            specs.append("%s")
            converters.append(_str_cells)
            if text and _needs_quotes(arr):
                quoting = "needed"
        elif kind == "O" and _is_text(arr):  # a text column kept as str objects (text_column): as unicode
            specs.append("%s")
            converters.append(_str_cells)
            if text and any(ch in "".join(arr.tolist()) for ch in _CSV_SPECIAL):
                quoting = "needed"
        else:  # bytes, objects, complex, datetimes: their str(), quoted when needed
            specs.append("%s")
            converters.append(_object_cells)
            quoting = "needed"  # not known before the cells are made
        arrays.append(arr)
    if len(set(lengths.values())) > 1:
        detail = ", ".join(f"{k!r}: {v}" for k, v in lengths.items())
        raise ValueError(f"columns have different lengths ({detail}); expected all the same")
    names = [str(name) for name in columns]
    header = ",".join(_quote(name) for name in names) + "\n"
    match = re.fullmatch(r"%\.(\d+)g", float_format)
    digits = int(match.group(1)) if match and 1 <= int(match.group(1)) <= 17 else None
    return _Plan(
        header, ",".join(specs) + "\n", converters, arrays, next(iter(lengths.values())), names, digits, quoting
    )


def text_column(cells: Sequence[str]) -> np.ndarray:
    """Text cells as a 1-D numpy array of ``str`` objects, for a table column.

    Not a numpy unicode array: its cells are all as wide as the longest, so one 2000-character
    note made every cell of a 250000-row column 8000 bytes (2 GB). Written as a unicode
    column would be (quoted only when a cell needs it)."""
    out = np.empty(len(cells), dtype=object)
    out[:] = cells
    return out


def _is_text(arr: np.ndarray) -> bool:
    """Whether every cell of an object array is a ``str``."""
    return all(type(x) is str for x in arr.tolist())


def _needs_quotes(arr: np.ndarray) -> bool:
    """Whether any cell of a numpy string column holds a comma, quote or line break."""
    codes = np.ascontiguousarray(arr).view(np.uint32)
    return bool(np.isin(codes, [ord(ch) for ch in _CSV_SPECIAL]).any())


# Exact powers of ten, 10**0 .. 10**22 (every one is a float64 exactly).
_POW10 = 10.0 ** np.arange(23)


def _digit_exponents(x: np.ndarray, digits: int) -> np.ndarray:
    """``digits - 1 - floor(log10(|x|))``: the power of ten that brings ``x`` to ``digits``
    digits before the point (NaN for NaN, +inf for 0, -inf for ±inf).

    ``floor(log10(|x|))`` as the compiled formatter (:mod:`softtip.io._csvtext`) takes it:
    ``floor(e2 * log10(2))`` of the binary exponent ``e2``, one more where ``|x|`` reaches the
    float nearest the next power of ten; not numpy's ``log10``, whose last bit varies with the
    machine's vector unit (the text is the same: see the module of the compiled formatter)."""
    from softtip.io._csvtext import _TEN_LOW, _TENS

    with np.errstate(all="ignore"):
        a = np.abs(x)
        e2 = np.frexp(a)[1].astype(np.int64) - 1
        p = (e2 * 78913) >> 18  # floor(e2 * log10(2)) for |e2| < 1650 (tested)
        np.clip(p, -_TEN_LOW - 1, len(_TENS) - _TEN_LOW - 2, out=p)
        p += a >= _TENS[p + 1 + _TEN_LOW]
        k = (digits - 1 - p).astype(np.float64)
        k[a == 0] = np.inf
        k[np.isinf(a)] = -np.inf
        k[np.isnan(a)] = np.nan
    return k


def _round_significant(x: np.ndarray, digits: int) -> np.ndarray:
    """``x`` rounded to ``digits`` significant decimal digits, as the nearest float64.

    ``m / 10**k`` (or ``m * 10**k``) with ``10**k`` exact (``|k|`` ≤ 22) is correctly
    rounded, so the result's shortest text has at most ``digits`` digits; values beyond
    that range (below 1e-13 or from 1e32 on, for 10 digits) go through Python's printf one
    by one. Zeros, NaN and infinities are left as they are. Where ``x * 10**k`` lands within
    its rounding error of a tie the last digit may differ from printf's by one.

    Vectorised with one table look-up for ``10**k`` and the common case (``0 ≤ k ≤ 22``:
    ``|x|`` below ``10**digits``) done for all values at once; the other cases are fixed
    on the (usually empty) subsets they concern.
    """
    if digits >= 17:
        return x
    k = _digit_exponents(x, digits)
    with np.errstate(all="ignore"):
        finite = np.isfinite(k)
        up = finite & (k >= 0) & (k <= 22)
        if up.all():
            scale = _POW10[k.astype(np.intp)]
            out = x * scale
            np.rint(out, out=out)
            np.divide(out, scale, out=out)
            return out
        out = x.copy()
        ku = np.where(up, k, 0.0).astype(np.intp)
        scale = _POW10[ku]
        rounded = np.rint(x * scale) / scale
        out[up] = rounded[up]
        down = finite & (k < 0) & (k >= -22)
        if down.any():
            q = _POW10[(-k[down]).astype(np.intp)]
            out[down] = np.rint(x[down] / q) * q
        far = finite & ~up & ~down
    if far.any():
        out[far] = [float(f"%.{digits}g" % v) for v in x[far].tolist()]
    return out


def _to_list(a: np.ndarray) -> list[Any]:
    return a.tolist()


def _quote(cell: str) -> str:
    if any(ch in cell for ch in _CSV_SPECIAL):
        return '"' + cell.replace('"', '""') + '"'
    return cell


def _minimal_quotes(text: bytes) -> bytes:
    """pyarrow's CSV text (``quoting_style="needed"``: every text cell quoted) with only the cells
    that hold a comma, a quote or a line break quoted, as the compiled formatter and Python's
    printf path write them: the same bytes whichever writes a block, and whatever the rest of
    the table holds (a piece of a log written alone gives the text it has in the whole)."""
    rows = csv.reader(io.StringIO(text.decode("utf-8"), newline=""))
    return "".join(",".join(_quote(cell) for cell in row) + "\n" for row in rows).encode("utf-8")


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


def _write_rows(out: TextIO | BinaryIO, plan: _Plan) -> None:
    """Write the table with its header to a text stream (Parquet: to its binary buffer), in
    blocks; a binary stream (an atomic writer's temporary file, say) is written to as UTF-8."""
    if not hasattr(out, "encoding"):
        text = io.TextIOWrapper(out, encoding="utf-8", newline="", write_through=True)  # type: ignore[arg-type]
        try:
            _write_rows(text, plan)
        finally:
            text.flush()
            text.detach()
        return
    if plan.parquet:
        _write_parquet(out, plan)
        return
    out.write(plan.header)
    with _CsvBlocks(out) as blocks:
        blocks.add(plan)


class _CsvBlocks:
    """CSV text formatted in blocks of :data:`_CHUNK_ROWS` rows on a pool of threads and written
    to ``out`` in order by the caller's thread, across any number of tables (:meth:`add`; a
    :class:`TableWriter`'s pieces): formatting floats is the cost, and the compiled formatter and
    pyarrow's writer both run without the GIL, so the blocks of the next piece are formatted
    while the file gets the ones before them. At most ``threads`` blocks wait to be written; with
    one thread, the caller formats and writes each block in turn. :meth:`flush` writes what is
    pending; leaving the ``with`` block flushes, or, on an error, drops what is pending. A block
    that fails (its formatting or its write) drops every block after it: the text written is
    always whole rows from the start, never with a gap."""

    def __init__(self, out: TextIO, threads: int | None = None) -> None:
        self.out = out
        self.binary = getattr(out, "buffer", None)
        from softtip.core._cores import usable_cores

        self.workers = max(1, min(threads or _WRITE_THREADS, usable_cores()))
        self.buffers = _TextBuffers()  # the compiled formatter's memory, block after block, piece after piece
        self.pending: deque = deque()
        self.pool: ThreadPoolExecutor | None = None
        self.failed = False  # a block failed: nothing after it is written (no hole in the text)
        self.primed: tuple | None = None  # the columns' dtypes the formatter was called for, threads idle

    def add(self, plan: _Plan) -> None:
        """Start formatting ``plan``'s rows; write the blocks before them that are done."""
        from pyarrow import csv as pacsv

        if self.failed:
            raise RuntimeError("a CSV block failed before; nothing more is written")
        if plan.digits is None:  # a float format that is not %.Ng: Python's printf, in this thread, in order
            self.flush()
            _write_rows_printf(self.out, plan)
            return
        if self.binary is not None:
            self.out.flush()  # a header first
        compiled = _compiled_csv(plan)
        layout = tuple(a.dtype.str for a in plan.arrays)
        if compiled and layout != self.primed:  # compiled (or loaded from numba's cache) with no thread running
            self.flush()
            self.buffers.put(_compiled_block(plan, 0, min(plan.n, 1), self.buffers)[0])
            self.primed = layout
        options = pacsv.WriteOptions(include_header=False, quoting_style=plan.quoting)

        def text_of(start: int) -> Any:
            stop = min(start + _CHUNK_ROWS, plan.n)
            if compiled:
                return _compiled_block(plan, start, stop, self.buffers)
            sink = io.BytesIO()
            pacsv.write_csv(_arrow_block(plan, start, stop, rounded=True), sink, options)
            return (_minimal_quotes(sink.getvalue()) if plan.quoting == "needed" else sink.getvalue()), None

        if self.workers == 1:  # the caller's thread alone (``--jobs 1``): each block at once
            for start in range(0, plan.n, _CHUNK_ROWS):
                done: Future = Future()
                done.set_result(text_of(start))
                self.pending.append((plan, start, done))
                self._put_one()
            return
        if self.pool is None:
            self.pool = ThreadPoolExecutor(max_workers=self.workers)  # its threads start as blocks need them
        for start in range(0, plan.n, _CHUNK_ROWS):
            self.pending.append((plan, start, self.pool.submit(text_of, start)))
            while len(self.pending) > self.workers:  # every thread busy while the caller writes one: memory bounded
                self._put_one()

    def _put_one(self) -> None:
        plan, start, done = self.pending.popleft()
        try:
            _put_block(self.out, self.binary, plan, start, done, self.buffers)
        except BaseException:
            self.failed = True
            self.close(write=False)
            raise

    def flush(self) -> None:
        """Write every pending block (none once one failed)."""
        while self.pending and not self.failed:
            self._put_one()
        if self.binary is not None and not self.failed:
            self.binary.flush()

    def close(self, *, write: bool = True) -> None:
        """Write the pending blocks (``write``) and end the threads (also when writing fails)."""
        try:
            if write:
                self.flush()
        finally:
            if self.pool is not None:
                self.pool.shutdown(wait=True, cancel_futures=True)
                self.pool = None
            self.pending.clear()

    def __enter__(self) -> _CsvBlocks:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self.close(write=exc_type is None)


def _compiled_csv(plan: _Plan) -> bool:
    """Whether the compiled formatter writes this table's CSV text: numba installed and allowed
    (:func:`softtip.core._jit.jit_enabled`: from :data:`~softtip.core._jit.JIT_MIN_SAMPLES`
    rows on, or at once when numba is loaded already), floats to at most
    :data:`softtip.io._csvtext.MAX_DIGITS` digits. Else pyarrow's writer (the same bytes)."""
    from softtip.core._jit import JIT_MIN_SAMPLES, jit_enabled
    from softtip.io._csvtext import MAX_DIGITS

    if plan.digits is None or plan.digits > MAX_DIGITS:
        return False
    return jit_enabled(JIT_MIN_SAMPLES if "numba" in sys.modules else plan.n)


def _put_block(out, binary, plan: _Plan, start: int, done, buffers: _TextBuffers | None) -> None:
    data, used = done.result()
    text = data if used is None else memoryview(data)[:used]
    if binary is not None:
        binary.write(text)
    else:
        out.write(bytes(text).decode("utf-8"))
    if used is not None and buffers is not None:
        buffers.put(data)
    if plan.progress is not None:
        plan.progress(min(start + _CHUNK_ROWS, plan.n) - start)


def _arrow_block(plan: _Plan, start: int, stop: int, *, rounded: bool) -> Any:
    """Rows ``start:stop`` as a pyarrow table: floats rounded for CSV, booleans 0/1 for CSV."""
    import pyarrow as pa

    cols = []
    for arr in plan.arrays:
        a = arr[start:stop]
        kind = a.dtype.kind
        if kind == "f":
            cols.append(pa.array(_round_significant(a, plan.digits) if rounded and plan.digits else a))
        elif kind == "b":
            cols.append(pa.array(a if plan.parquet else a.view(np.int8)))
        elif kind in "iu":
            cols.append(pa.array(a))
        elif kind == "U":
            cols.append(_arrow_strings(a, plain=plan.parquet))
        else:  # their text, unquoted: pyarrow quotes
            cells = [x.decode("utf-8", "replace") if isinstance(x, bytes) else str(x) for x in a.tolist()]
            cols.append(pa.array(cells, type=pa.string()))
    if not plan.parquet:
        return pa.Table.from_arrays(cols, names=plan.names)
    # a numpy number or flag is never a null (NaN is a value): such columns are required, which
    # spares Parquet their definition levels, a quarter of the write's time on softtip's 47
    # columns (bench_core.py --only bounds); text stays nullable (by its type, so every block of a file has one schema)
    fields = [pa.field(name, c.type, nullable=arr.dtype.kind not in "fbiu")
              for name, c, arr in zip(plan.names, cols, plan.arrays)]  # fmt: skip
    return pa.Table.from_arrays(cols, schema=pa.schema(fields))


def _string_buffers(arr: Any) -> tuple[np.ndarray, np.ndarray]:
    """A pyarrow string array's cell offsets (int64, ``len + 1``) and UTF-8 bytes, without copying the text."""
    import pyarrow as pa

    wide = pa.types.is_large_string(arr.type)
    bufs = arr.buffers()
    offsets = np.frombuffer(bufs[1], dtype=np.int64 if wide else np.int32)[arr.offset : arr.offset + len(arr) + 1]
    data = np.frombuffer(bufs[2], dtype=np.uint8) if bufs[2] is not None else np.zeros(0, dtype=np.uint8)
    return offsets.astype(np.int64), data


class _TextBuffers:
    """Memory the compiled CSV formatter reuses from block to block (and a :class:`TableWriter`
    from piece to piece): the columns' values gathered for the loop, and the blocks' text
    until it is written. Fresh arrays for each block were paid in page faults, a third of the
    write's CPU time (system time). At most as many sets as blocks in flight are made."""

    def __init__(self) -> None:
        self._scratch: list[dict[str, np.ndarray]] = []
        self._out: list[np.ndarray] = []

    def scratch(self, nf: int, ni: int, nt: int, rows: int) -> dict[str, np.ndarray]:
        """Arrays ``floats`` (nf, >= rows), ``ints`` (ni, ...), ``codes`` (nt, ...) and
        ``far`` (nf * rows values), taken until :meth:`give` hands them back."""
        try:
            got = self._scratch.pop()  # atomic under the GIL: threads take different sets
        except IndexError:
            got = {}
        if not got or got["floats"].shape[0] != nf or got["ints"].shape[0] != ni or got["codes"].shape[0] != nt or got["floats"].shape[1] < rows:
            got = {"floats": np.empty((nf, rows)), "ints": np.empty((ni, rows), dtype=np.int64),
                   "codes": np.empty((nt, rows), dtype=np.int64), "far": np.empty(nf * rows)}  # fmt: skip
        return got

    def give(self, scratch: dict[str, np.ndarray]) -> None:
        self._scratch.append(scratch)

    def out(self, size: int) -> np.ndarray:
        """A byte buffer of at least ``size`` bytes, taken until :meth:`put` hands it back."""
        try:
            got = self._out.pop()
        except IndexError:
            got = None
        if got is None or len(got) < size:
            got = np.empty(size, dtype=np.uint8)  # untouched pages cost nothing: the bound may be loose
        return got

    def put(self, data: np.ndarray) -> None:
        """Hand back a buffer of :meth:`out` (its text written)."""
        self._out.append(data)


@dataclass
class _Columns:
    """How the compiled formatter takes a table's columns (the same for every block)."""

    floats: list[int]  # column indices
    ints: list[int]  # integers and booleans that fit int64
    texts: list[int]  # everything else, as text cells
    layout: np.ndarray  # (ncols, 2): kind (0 float, 1 integer, 2 text) and index within the kind
    quote: np.ndarray  # (nt,) bool


def _compiled_columns(plan: _Plan) -> _Columns:
    if plan.compiled is not None:
        return plan.compiled
    floats: list[int] = []
    ints: list[int] = []
    texts: list[int] = []
    layout = np.empty((len(plan.arrays), 2), dtype=np.int64)
    quote = []
    for c, arr in enumerate(plan.arrays):
        kind = arr.dtype.kind
        if kind == "f":
            layout[c] = 0, len(floats)
            floats.append(c)
        elif kind in "bi" or (kind == "u" and (arr.dtype.itemsize < 8 or not len(arr) or int(arr.max()) < 2**63)):
            layout[c] = 1, len(ints)
            ints.append(c)
        else:
            layout[c] = 2, len(texts)
            texts.append(c)
            quote.append(kind not in "iu" and plan.quoting == "needed")
    plan.compiled = _Columns(floats, ints, texts, layout, np.array(quote, dtype=np.bool_))
    return plan.compiled


def _text_cells(a: np.ndarray) -> tuple[np.ndarray | None, np.ndarray, np.ndarray]:
    """A block of a text column as cell indices (None: one cell a row, in order), cell offsets
    (int64, cells + 1) and UTF-8 bytes, the text pyarrow's writer gives each cell."""
    import pyarrow as pa
    import pyarrow.compute as pc

    kind = a.dtype.kind
    if kind == "U":
        found = _levels(a)
        if found is not None:
            codes, levels = found
            text = [cell.encode("utf-8") for cell in levels]
            offsets = np.zeros(len(text) + 1, dtype=np.int64)
            np.cumsum([len(t) for t in text], out=offsets[1:])
            return codes, offsets, np.frombuffer(b"".join(text), dtype=np.uint8)
        cells = pa.array(a, type=pa.string())
    elif kind in "iu":  # beyond int64: pyarrow's own text of the integer
        cells = pc.cast(pa.array(a), pa.string())
    else:
        text = [x.decode("utf-8", "replace") if isinstance(x, bytes) else str(x) for x in a.tolist()]
        cells = pa.array(text, type=pa.string())
    offsets, data = _string_buffers(cells)
    return None, offsets, data


def _compiled_block(plan: _Plan, start: int, stop: int, buffers: _TextBuffers | None = None) -> tuple[np.ndarray, int]:
    """Rows ``start:stop`` as CSV text (UTF-8 bytes ``[:used]`` of the array returned) by the
    compiled formatter (:mod:`softtip.io._csvtext`): the bytes :func:`_arrow_block` and
    pyarrow's writer give.

    Floats are rounded and formatted in the compiled loop; integers and booleans too (as
    pyarrow's writer writes them: ``-12``, ``0``/``1``); text cells are their pyarrow text,
    copied in by the loop, quoted where they need it (:func:`_minimal_quotes`). ``buffers``: where the gathered
    columns and the text go (reused; :meth:`_TextBuffers.put` the array back when written).
    """
    from softtip.io._csvtext import FLOAT_CELL_BYTES, SLACK_BYTES, format_rows

    buffers = buffers or _TextBuffers()
    cols = _compiled_columns(plan)
    n = stop - start
    digits = plan.digits
    assert digits is not None
    sc = buffers.scratch(len(cols.floats), len(cols.ints), len(cols.texts), max(n, 1))
    floats, ints, code_table = sc["floats"], sc["ints"], sc["codes"]
    for j, c in enumerate(cols.floats):
        np.copyto(floats[j, :n], plan.arrays[c][start:stop])
    for j, c in enumerate(cols.ints):
        np.copyto(ints[j, :n], plan.arrays[c][start:stop], casting="unsafe")  # booleans to 0/1; uint64 below 2**63
    bound = n * (len(cols.floats) * (digits + FLOAT_CELL_BYTES) + len(cols.ints) * 20 + len(plan.arrays) + 1)
    # the text cells of every column in one table: cell indices shifted by the columns before
    cell_off = [np.zeros(1, dtype=np.int64)]
    data_parts = []
    cells_before = bytes_before = 0
    for t, c in enumerate(cols.texts):
        codes, offsets, data = _text_cells(plan.arrays[c][start:stop])
        lengths = np.diff(offsets)
        if codes is None:
            code_table[t, :n] = np.arange(cells_before, cells_before + n)
            longest = int(lengths.sum())
        else:
            np.add(codes, cells_before, out=code_table[t, :n])
            longest = int(lengths.max()) * n
        bound += (longest + n) * (2 if cols.quote[t] else 1) + 2 * n
        cell_off.append(offsets[1:] - offsets[0] + bytes_before)
        data_parts.append(data[offsets[0] : offsets[-1]])
        cells_before += len(offsets) - 1
        bytes_before += int(offsets[-1] - offsets[0])
    cells = np.concatenate(cell_off)
    text = np.concatenate(data_parts) if data_parts else np.zeros(0, dtype=np.uint8)
    far_off, far_data = np.zeros(1, dtype=np.int64), np.zeros(0, dtype=np.uint8)
    bound += SLACK_BYTES  # the loop writes whole words past a cell's end
    out = buffers.out(bound)
    while True:
        used, far = format_rows(floats, ints, code_table, cells, text, cols.quote, cols.layout, digits,
                                far_off, far_data, sc["far"], out, n)  # fmt: skip
        if far < len(far_off):
            break
        # values the rounding does not take in one step (rare): the fallback's value, pyarrow's text, again
        far_off, far_data = _far_text(sc["far"][:far], digits)
        if len(out) < bound + int(far_off[-1]):
            out = np.empty(bound + int(far_off[-1]), dtype=np.uint8)
    buffers.give(sc)
    return out, used


def _far_text(values: np.ndarray, digits: int) -> tuple[np.ndarray, np.ndarray]:
    """pyarrow's text of ``values`` rounded by Python's printf (:func:`_round_significant`'s way
    beyond one-step rounding), as cell offsets and UTF-8 bytes."""
    import pyarrow as pa
    import pyarrow.compute as pc

    rounded = np.array([float(f"%.{digits}g" % v) for v in values.tolist()])
    off, data = _string_buffers(pc.cast(pa.array(rounded), pa.string()))
    return off - off[0], data


def _levels(a: np.ndarray) -> tuple[np.ndarray, list[str]] | None:
    """A numpy unicode column of at most :data:`_MAX_LEVELS` distinct cells as codes (int8,
    a row each) and its cells in order of appearance; None for a column of more."""
    n = len(a)
    codes = np.zeros(n, dtype=np.int8)
    levels: list[str] = []
    left = np.ones(n, dtype=bool)
    i = 0
    while n:
        same = a == a[i]
        codes[same] = len(levels)
        levels.append(str(a[i]))
        left &= ~same
        if not left.any():
            break
        if len(levels) >= _MAX_LEVELS:
            return None
        i = int(np.argmax(left))
    return codes, levels


# A text column with at most this many distinct cells is dictionary-encoded on its way to pyarrow.
_MAX_LEVELS = 16


def _arrow_strings(a: np.ndarray, *, plain: bool) -> Any:
    """A numpy unicode column as a pyarrow array of its text.

    A column of a few distinct values (softtip's ``state`` and ``line_evidence``) is found
    by a few whole-column comparisons and handed over dictionary-encoded (pyarrow's CSV
    writer takes that as it is), ~4× faster than pyarrow's conversion cell by cell;
    ``plain``: decoded to a plain string array (so a Parquet file's column type stays
    ``string``). Other columns go through pyarrow's conversion.
    """
    import pyarrow as pa

    found = _levels(a)
    if found is None:
        return pa.array(a, type=pa.string())
    codes, levels = found
    out = pa.DictionaryArray.from_arrays(pa.array(codes), pa.array(levels, type=pa.string()))
    return out.dictionary_decode() if plain else out


def _write_rows_printf(out: TextIO, plan: _Plan) -> None:
    """Rows with Python's ``%``, in blocks.

    Each block is formatted by one ``%`` on a repeated row format: the loop over cells
    runs in C, which beats per-cell Python formatting and ``np.char.mod``.
    """
    for start in range(0, plan.n, _CHUNK_ROWS):
        stop = min(start + _CHUNK_ROWS, plan.n)
        cols = [conv(a[start:stop]) for conv, a in zip(plan.converters, plan.arrays)]
        cells = tuple(itertools.chain.from_iterable(zip(*cols)))
        out.write((plan.row_format * (stop - start)) % cells)
        if plan.progress is not None:
            plan.progress(stop - start)


# Rows per Parquet row group (and per progress step).
_PARQUET_ROWS = 1 << 18

#: Parquet compression, chosen by measurement (``python benchmarks/bench_core.py --only bounds``:
#: the 47 columns of ``softtip estimate``'s output for a 1e6-row log, 2-core machine shared with
#: other work, CPU time of the write, file size; two runs), dictionary encoding only for the
#: columns that are not floats (a float column of measurements has no repeats to find), no
#: statistics: snappy 360-381 ns/row, 159 MB; none 386-401 ns/row, 313 MB (more bytes to write);
#: lz4 364-393 ns/row, 150 MB; zstd 527-608 ns/row, 126 MB. Statistics add ~10 % (snappy
#: 397-427 ns/row); pyarrow's defaults (dictionary on every column, statistics) 1390-1725 ns/row,
#: 176 MB. Snappy and lz4 are equally fast within the noise; snappy is what every Parquet reader reads.
PARQUET_COMPRESSION = "snappy"

#: Arrow IPC (Feather v2) compression, chosen by the same measurement: none 125-139 ns/row, 339 MB
#: (read back memory-mapped, without a copy); lz4 148-192 ns/row, 156 MB; zstd 381-406 ns/row, 120 MB.
#: Arrow IPC is the format for speed; Parquet is the compact one.
ARROW_COMPRESSION: str | None = None


def _write_parquet(out: TextIO, plan: _Plan) -> None:
    binary = getattr(out, "buffer", out)
    out.flush()
    writer = None
    try:
        for start in range(0, max(plan.n, 1), _PARQUET_ROWS):
            stop = min(start + _PARQUET_ROWS, plan.n)
            table = _arrow_block(plan, start, stop, rounded=False)
            if writer is None:
                writer = _columnar_writer(binary, table, plan.metadata, plan.columnar or "parquet", statistics=plan.statistics)
            writer.write_table(table)
            if plan.progress is not None and stop > start:
                plan.progress(stop - start)
    finally:
        if writer is not None:
            writer.close()
    binary.flush()


def _columnar_writer(binary: BinaryIO, first: Any, metadata: Mapping[str, str] | None, fmt: str = "parquet", *,
                     statistics: bool = False) -> Any:
    """A writer (``write_table``, ``close``) of tables like ``first``, ``metadata`` in the schema.

    Parquet: :data:`PARQUET_COMPRESSION`, dictionary encoding only for the columns that are not
    floating point, column statistics only when asked (``statistics``). Arrow IPC (the Feather v2
    file format): :data:`ARROW_COMPRESSION`.
    """
    import pyarrow as pa

    schema = first.schema.with_metadata(dict(metadata or {}))
    if fmt == "arrow":
        options = pa.ipc.IpcWriteOptions(compression=ARROW_COMPRESSION)
        return pa.ipc.new_file(binary, schema, options=options)
    import pyarrow.parquet as pq

    coded = [field.name for field in schema if not pa.types.is_floating(field.type)]
    return pq.ParquetWriter(binary, schema, compression=PARQUET_COMPRESSION, use_dictionary=coded, write_statistics=statistics)


def _write_atomic(path: str, plan: _Plan) -> None:
    from softtip.io.atomic import atomic_write

    with atomic_write(path) as fh:
        _write_rows(fh, plan)


# --------------------------------------------------------------------------------------
# piece by piece: logs larger than memory


#: Bytes of CSV text per block of :func:`iter_log`.
_CSV_BLOCK_BYTES = 1 << 22
#: Bytes of CSV text read at once to find the line of an error met by :func:`iter_log`.
_LOCATE_BYTES = 1 << 22


class _NoPlace(Exception):
    """:meth:`LogBlocks.locate_error` cannot place an error in bounded memory."""


class NotStreamable(Exception):
    """:func:`iter_log` met something its block reader does not take (a trailing blank
    line, a cell only Python's parser reads, or an error): read the log at once with
    :func:`read_log`, which takes it or words the error."""


class LogBlocks:
    """A CSV or Parquet log read block by block (:func:`iter_log`).

    Iterate for ``(t, wrench, extra)`` blocks in SI (``extra``: the other columns' values,
    numpy arrays: text from CSV); after the last block :meth:`warnings` says what
    :attr:`Log.warnings` would (repeated stamps; the time scale, judged on the first block;
    a cut last line). Raises :class:`NotStreamable` while iterating for anything else.
    """

    def __init__(self, path: str | os.PathLike[str], units: str | None, rows: int, progress: Callable[[int], object] | None):
        self.source = _source_name(path)
        self.path = os.fspath(path)
        if units is not None and units not in UNIT_SYSTEMS:
            raise InputError(f"{self.source}: unknown units {units!r}; expected one of: {', '.join(UNIT_SYSTEMS)}")
        self.columnar = _columnar(self.path)  # Parquet or Arrow IPC, else None (CSV)
        self.parquet = self.columnar is not None
        self.rows, self.progress = rows, progress
        self.units = units
        self.n = 0
        self.repeated = 0
        self._first_repeat = -1
        self._repeat_t = math.nan
        self._first_t: NDArray[np.float64] | None = None
        self._last_t = -math.inf
        # gaps in t (steps beyond _gap_threshold of the first block's median step): how many,
        # the largest and the row after it
        self._gap_median = math.nan
        self._gaps = 0
        self._gap_largest = 0.0
        self._gap_row = -1
        self._first_line: int | None = None
        self._quoted: bool | None = None  # whether the data holds a quote (then rows may span lines); None: not looked
        # CSV: rows (one line each) read and found good before the reader stopped on what looks like an error
        self._error_at: int | None = None
        # CSV: where the text starts (after a BOM) when its first 64 kB are not UTF-8
        self._bad_prefix: int | None = None
        self._header: _Header | None = None
        self._index: dict[str, int] = {}
        self._t_stated = False  # Parquet or Arrow: the file's metadata says t is in seconds

    def __iter__(self) -> Any:
        blocks = self._parquet_blocks() if self.parquet else self._csv_blocks()
        try:
            yield from self._checked(blocks)
        finally:
            blocks.close()  # at once, not when collected: a native reader thread must not outlive the run

    def _checked(self, blocks: Any) -> Any:
        for t, wrench, extra in blocks:
            if not (np.isfinite(t).all() and np.isfinite(wrench).all()) or (np.diff(t) < 0).any() or t[0] < self._last_t:
                self._error_at = self.n
                raise NotStreamable("a value to word")
            step = np.diff(t, prepend=self._last_t)  # step[k]: from the row before to row k (inf at the first)
            same = np.flatnonzero(step == 0)
            if len(same) and self._first_repeat < 0:
                self._first_repeat = self.n + int(same[0])
                self._repeat_t = float(t[same[0]])
            self.repeated += len(same)
            if self._first_t is None:
                if t[0] >= ABSOLUTE_STAMP_S or any(
                        "--time-units" in note for note in _time_notes(t, self.source, None, explicit=self._t_stated)[1]):  # fmt: skip
                    raise NotStreamable("absolute stamps or a time unit to guess: read_log counts or refuses them")
                self._first_t = t
                median = _median_step(step[1:])
                if median == median and PLAUSIBLE_RATE_HZ[0] <= 1.0 / median <= PLAUSIBLE_RATE_HZ[1]:
                    self._gap_median = median  # gaps are measured against the first block's rate
            if self._gap_median == self._gap_median:
                gaps = np.flatnonzero((step > _gap_threshold(self._gap_median)) & np.isfinite(step))
                if len(gaps):
                    self._gaps += len(gaps)
                    k = int(gaps[np.argmax(step[gaps])])
                    if step[k] > self._gap_largest:
                        self._gap_largest, self._gap_row = float(step[k]), self.n + k
            self._last_t = float(t[-1])
            self.n += len(t)
            yield t, wrench_to_si(wrench, self.units or "si"), extra
        if self.n > 1 and self.repeated == self.n - 1:
            raise NotStreamable("every time stamp is the same: read_log refuses the log")

    def warnings(self) -> tuple[str, ...]:
        """What :attr:`Log.warnings` holds for the whole log (after the last block)."""
        first_line = self._first_line
        if first_line is not None and (self.repeated or not self._ends_with_break()):
            if self._quoted is None:  # one more pass over the file, only when a line number is to be given
                self._quoted = self._has_quote()
            first_line = None if self._quoted else first_line
        notes = []
        if self.repeated:
            where = f"line {first_line + self._first_repeat}" if first_line is not None else f"data row {self._first_repeat + 1}"
            what = "line" if first_line is not None else "row"
            notes.append(
                f"{self.source}: {self.repeated} repeated time stamp{'s' if self.repeated > 1 else ''} (the first on "
                f"{where}: t = {self._repeat_t:.10g} s as on the {what} before); kept in file order"
            )
        if self._first_t is not None:
            notes += [n for n in _time_notes(self._first_t, self.source, first_line, explicit=self._t_stated)[1]
                      if "median step" in n]  # fmt: skip
        if self._gaps:
            where = f"line {first_line + self._gap_row}" if first_line is not None else f"data row {self._gap_row + 1}"
            notes.append(_gap_note(self.source, self._gaps, self._gap_largest, where, self._gap_median))
        if not self.parquet and first_line is not None:
            cut = self._cut_tail(first_line)
            if cut:
                notes.append(cut)
        return tuple(notes)

    def _csv_blocks(self) -> Any:
        import pyarrow as pa
        import pyarrow.compute as pc
        from pyarrow import csv as pacsv

        try:
            with open(self.path, "rb") as fh:
                prefix = fh.read(_HEADER_PREFIX + 3)
                size = os.fstat(fh.fileno()).st_size
        except OSError:
            raise NotStreamable("unreadable") from None
        skip = 3 if prefix.startswith(b"\xef\xbb\xbf") else 0
        prefix = prefix[skip:]
        whole = skip + len(prefix) >= size
        if not whole:  # whole lines (lone CR line ends too)
            prefix = prefix[: max(prefix.rfind(b"\n"), prefix.rfind(b"\r")) + 1]
        try:
            text = prefix.decode("utf-8")
        except UnicodeDecodeError:
            if not any(prefix.startswith(magic) for magic, _ in _COMPRESSION_MAGIC):
                self._size, self._bad_prefix = size, skip  # the error is located in windows, not by reading it all
            raise NotStreamable("header") from None
        try:
            header = _read_header(text, self.source)
            index = _column_index(header, self.source)
        except InputError:
            raise NotStreamable("header") from None
        if header.cmap is None or not header.cmap.native(header.names) or header.delimiter != "," or header.preamble:
            raise NotStreamable("not softtip's own layout: read_log maps it")
        if any(name.startswith(_UNNAMED) for name in header.names):
            raise NotStreamable("unnamed columns: read_log leaves them out")
        pos = header.lines.tell()
        if not whole and pos >= len(text):
            raise NotStreamable("long header")
        start = skip + len(text[:pos].encode("utf-8"))
        self._first_line = header.data_base + 1
        names = header.names
        types = {name: pa.float64() if j in index.values() else pa.string() for j, name in enumerate(names)}
        extra_idx = [j for j in range(len(names)) if j not in index.values()]
        self._size, self._start = size, start
        self._header, self._index = header, index
        done = 0  # rows yielded
        stream = pa.OSFile(self.path)
        reader = None
        try:
            stream.seek(start)
            reader = pacsv.open_csv(
                stream,
                read_options=pacsv.ReadOptions(column_names=names, use_threads=False, block_size=_CSV_BLOCK_BYTES),
                parse_options=pacsv.ParseOptions(newlines_in_values=True, ignore_empty_lines=False),
                convert_options=pacsv.ConvertOptions(
                    column_types=types, check_utf8=True, strings_can_be_null=False, quoted_strings_can_be_null=False,
                    null_values=sorted(_NULL_CELLS),
                ),
            )
            while True:
                try:
                    batch = reader.read_next_batch()
                except StopIteration:
                    break
                if batch.num_rows == 0:
                    continue
                cols = [batch.column(index[name]) for name in REQUIRED_COLUMNS]
                if any(c.null_count for c in cols):
                    self._error_at = done
                    raise NotStreamable("empty cell")
                t = np.array(cols[0].to_numpy(), dtype=np.float64)
                wrench = np.empty((batch.num_rows, 6))
                for i, col in enumerate(cols[1:]):
                    wrench[:, i] = col.to_numpy()
                for j in extra_idx:  # a quoted cell spanning lines: a note, unless it takes in data rows
                    col = batch.column(j)
                    spans = pc.or_(pc.match_substring(col, "\n"), pc.match_substring(col, "\r"))
                    if pc.any(spans).as_py():
                        self._quoted = True  # line numbers are not row numbers from here on
                        cells = col.filter(spans).to_pylist()
                        if any(_swallowed(cell, ",", len(names)) for cell in cells):
                            self._error_at = done
                            raise NotStreamable("a quote takes in lines that look like data rows")
                # object arrays of str: a numpy unicode array would take 4 bytes times the longest cell for every cell
                extra = {names[j]: text_column(batch.column(j).to_pylist()) for j in extra_idx}
                if self.progress is not None:
                    self.progress(batch.num_rows)
                yield t, wrench, extra
                done += batch.num_rows
        except (pa.ArrowException, ValueError):
            self._error_at = done
            raise NotStreamable("parser") from None
        except OSError:
            raise NotStreamable("parser") from None
        finally:
            if reader is not None:
                reader.close()  # end its read-ahead thread before the file goes (a SIGABRT at exit otherwise)
            stream.close()

    def locate_error(self) -> InputError | None:
        """After a :class:`NotStreamable` on what looks like an error in a CSV log: the error
        :func:`read_log` would raise, found by reading the file from the last good row in
        windows of :data:`_LOCATE_BYTES` (memory bounded by that, not by the file).

        Where line breaks cannot be counted as rows (quoted cells that may span lines, lone
        carriage returns, a line longer than a window) the file is parsed row by row from its
        first data row instead, a line at a time. ``None`` when the reader did not stop on an
        error, or the parser finds none (a cell only Python's parser reads):
        :func:`read_log` on the whole file decides then.
        """
        if not self.parquet and self._bad_prefix is not None:  # not UTF-8 within the header's 64 kB
            try:
                with open(self.path, "rb") as fh:
                    return self._first_bad_utf8(fh, self._bad_prefix, 1)
            except (OSError, _NoPlace):
                return None
        if self.parquet or self._error_at is None or self._header is None or self._first_line is None:
            return None
        try:
            with open(self.path, "rb") as fh:
                return self._locate(fh)
        except (OSError, UnicodeDecodeError, _NoPlace):
            return None

    def _locate(self, fh: BinaryIO) -> InputError | None:
        bad_utf8 = self._first_bad_utf8(fh)
        if bad_utf8 is not None:  # read_log decodes the whole file first: this error wins wherever it is
            return bad_utf8
        try:
            return self._locate_in_windows(fh)
        except _NoPlace:
            return self._locate_row_by_row(fh)

    def _locate_row_by_row(self, fh: BinaryIO) -> InputError | None:
        """:meth:`_locate` for a file that cannot be cut into windows by counting line breaks
        (quoted cells that may span lines, lone carriage returns, a line longer than a window):
        :func:`read_log`'s row-by-row parser over the whole data, a line at a time in memory."""
        header, index = self._header, self._index
        fh.seek(self._start)
        text = io.TextIOWrapper(fh, encoding="utf-8", newline="")
        try:
            lines = _FileLines(text)
            part = _Header(names=header.names, line=header.line, data_base=header.data_base, lines=lines, comments=[],
                           delimiter=header.delimiter, decimal=header.decimal, cmap=header.cmap)  # fmt: skip
            try:
                _parse_careful(part, index, self.source, (0, 0), keep=False)
            except InputError as exc:
                if self._ends_with_break():
                    return exc
                # as read_log's hint: the last line counted by its line feeds
                last = self._count(fh, b"\n") + 1
                return _cut_hint(exc, self.source, last) if last > header.data_base else exc
            return None
        finally:
            text.detach()  # the caller closes the file

    def _count(self, fh: BinaryIO, what: bytes) -> int:
        """How often ``what`` (one byte) occurs in the file after a BOM (bounded memory)."""
        fh.seek(0)
        head = fh.read(3)
        n = 0 if head == b"\xef\xbb\xbf" else head.count(what)
        while chunk := fh.read(1 << 24):
            n += chunk.count(what)
        return n

    def _locate_in_windows(self, fh: BinaryIO) -> InputError | None:
        """:meth:`_locate` from the last good row, in windows; :class:`_NoPlace` where line
        breaks cannot be counted as rows."""
        # the first byte of the last good row (the context of the next: t must not go back)
        skip = max(self._error_at - 1, 0)
        fh.seek(self._start)
        pos, left = self._start, skip
        while left:
            chunk = fh.read(_LOCATE_BYTES)
            if not chunk:
                return None
            if chunk.count(b"\r") != chunk.count(b"\r\n") or b'"' in chunk:
                raise _NoPlace("lone CR line ends (or a CR LF cut by the chunk), or quotes: lines are not rows here")
            breaks = chunk.count(b"\n")
            if breaks < left:
                left -= breaks
                pos += len(chunk)
                continue
            k = -1
            for _ in range(left):
                k = chunk.index(b"\n", k + 1)
            pos += k + 1
            left = 0
        line = self._first_line + skip  # the line at pos
        header, index = self._header, self._index
        while True:
            fh.seek(pos)
            window = fh.read(_LOCATE_BYTES)
            at_end = pos + len(window) >= self._size
            if not at_end:
                cut = window.rfind(b"\n") + 1
                if cut == 0:
                    raise _NoPlace("a line longer than a window")
                window = window[:cut]
                body = window.rstrip(b"\r\n")  # blank lines at a window's end may be followed by data
                last = body.rfind(b"\n") + 1
                if last == 0:
                    raise _NoPlace("one line in a window")
            if b'"' in window or window.count(b"\r") != window.count(b"\r\n"):
                raise _NoPlace("quotes or lone CRs: a record may span lines")
            if not window.strip():
                return None
            text = window.decode("utf-8")
            lines = io.StringIO(text)
            part = _Header(names=header.names, line=header.line, data_base=line - 1, lines=lines, comments=[],
                           delimiter=header.delimiter, decimal=header.decimal, cmap=header.cmap)  # fmt: skip
            try:
                _parse_careful(part, index, self.source, (0, 0))
            except InputError as exc:
                if at_end and not window.endswith((b"\n", b"\r")):
                    return _cut_hint(exc, self.source, line + window.count(b"\n"))
                return exc
            if at_end:
                return None  # nothing wrong after all: read_log says what it takes
            # on from the last data line of this window (the next one's context)
            line += window.count(b"\n", 0, last)
            pos += last

    def _first_bad_utf8(self, fh: BinaryIO, start: int | None = None, line: int | None = None) -> InputError | None:
        """The error :func:`read_log` gives for invalid UTF-8, from a pass over the file (bounded memory)
        from byte ``start`` (line ``line``; default: the first data row's)."""
        pos = self._start if start is None else start
        fh.seek(pos)
        line, held = (self._first_line or 1) if line is None else line, b""
        while True:
            chunk = fh.read(_LOCATE_BYTES)
            data = held + chunk
            # whole lines (lone CR line ends too): no character is split; a CR that may be a CR LF's waits
            cut = len(data) if not chunk else max(data.rfind(b"\n"), data.rfind(b"\r", 0, len(data) - 1)) + 1
            if chunk and cut == 0 and len(data) > 4 * _LOCATE_BYTES:
                raise _NoPlace("a line longer than 4 windows")
            part, held = data[:cut], data[cut:]
            try:
                part.decode("utf-8")
            except UnicodeDecodeError as exc:
                at = line + _line_breaks(part, exc.start)
                return _not_utf8(self.source, at, part[exc.start], pos + exc.start, part[:8] if pos == 0 else b"")
            if not chunk:
                return None
            line += _line_breaks(part)
            pos += len(part)

    def _ends_with_break(self) -> bool:
        """Whether the file ends with a line break (else its last line may have been cut)."""
        with open(self.path, "rb") as fh:
            fh.seek(max(0, self._size - 1))
            return fh.read(1) in (b"\n", b"\r")

    def _has_quote(self) -> bool:
        with open(self.path, "rb") as fh:
            fh.seek(self._start)
            while chunk := fh.read(1 << 24):
                if b'"' in chunk:
                    return True
        return False

    def _cut_tail(self, first_line: int) -> str | None:
        with open(self.path, "rb") as fh:
            fh.seek(max(self._start, self._size - (1 << 16)))
            tail = fh.read()
        note = _cut_last_line(tail, self.source, self.n if self.n >= 4 else 0)
        if note is None:
            return None
        # the tail's line count is not the file's: every data row is one line here
        line = first_line + self.n - 1
        return re.sub(rf"^{re.escape(self.source)}:\d+:", f"{self.source}:{line}:", note)

    def _parquet_blocks(self) -> Any:
        """Blocks of a Parquet or Arrow IPC file."""
        import pyarrow as pa

        try:
            pf = _ColumnarFile(self.path, self.columnar or "parquet")
        except (pa.ArrowException, OSError):
            raise NotStreamable("unreadable") from None
        with pf:
            meta = {k.decode("utf-8", "replace"): v.decode("utf-8", "replace") for k, v in (pf.schema.metadata or {}).items()}
            file_units = meta.get(PARQUET_UNITS_KEY)
            if (file_units is not None and file_units not in UNIT_SYSTEMS) or (
                self.units is not None and file_units is not None and self.units != file_units
            ):
                raise NotStreamable("units")
            self.units = self.units or file_units or "si"
            self._t_stated = file_units is not None  # t in s, as the one-shot reader takes it
            names = list(pf.schema.names)
            header = _Header(names=[n.strip() for n in names], line=0, data_base=0, lines=io.StringIO(), comments=[])
            try:
                index = _column_index(header, self.source)
            except InputError:
                raise NotStreamable("columns") from None
            for name in REQUIRED_COLUMNS:
                typ = pf.schema.field(index[name]).type
                if not (pa.types.is_floating(typ) or pa.types.is_integer(typ)):
                    raise NotStreamable("types")
            if pf.num_rows == 0:
                raise NotStreamable("no rows")
            extra_idx = [j for j in range(len(names)) if j not in index.values()]
            try:
                for batch in pf.iter_batches(self.rows):
                    cols = [batch.column(index[name]) for name in REQUIRED_COLUMNS]
                    if any(c.null_count for c in cols):
                        raise NotStreamable("null")
                    t = np.array(cols[0].to_numpy(), dtype=np.float64)
                    wrench = np.empty((batch.num_rows, 6))
                    for i, col in enumerate(cols[1:]):
                        wrench[:, i] = col.to_numpy()
                    extra = {names[j]: batch.column(j).to_numpy(zero_copy_only=False) for j in extra_idx}
                    if self.progress is not None:
                        self.progress(batch.num_rows)
                    yield t, wrench, extra
            except (pa.ArrowException, OSError):
                raise NotStreamable("reader") from None


def iter_log(
    path: str | os.PathLike[str],
    units: str | None = None,
    *,
    rows: int = 1 << 16,
    progress: Callable[[int], object] | None = None,
) -> LogBlocks:
    """A CSV or Parquet log file, block by block, for logs larger than memory.

    Parameters
    ----------
    path : str or path-like
        As :func:`read_log` (a file; Parquet or Arrow IPC by the extension).
    units : {"si", "kgf-mm"} or None
        As :func:`read_log`.
    rows : int
        Parquet and Arrow IPC: rows per block (CSV blocks are pyarrow's, ~4 MB of text).
    progress : callable, optional
        Called with the number of rows of each block.

    Returns
    -------
    LogBlocks
        Iterate it for ``(t, wrench, extra)`` blocks; the values are those
        :func:`read_log` gives, in pieces. Anything :func:`read_log` would report (or that
        only its Python parser reads) raises :class:`NotStreamable` during the iteration:
        read the file with :func:`read_log` then, for the located message.
    """
    return LogBlocks(path, units, rows, progress)


class PreparedRows(NamedTuple):
    """Rows for :meth:`TableWriter.write`, made by :meth:`TableWriter.prepare`."""

    plan: _Plan  #: the checked columns and their cell formats
    blocks: Iterable[Any]  #: Parquet and Arrow IPC: the Arrow tables to write, in order (CSV: none)


class TableWriter:
    """:func:`write_table`, piece by piece, to an open stream (an atomic writer's file).

    Parameters
    ----------
    out : text or binary stream
        Left open.
    parquet : bool
        Parquet (one row group per block) instead of CSV: ``format="parquet"``.
    format : {"csv", "parquet", "arrow"}, optional
        The table's format (:func:`softtip.io.formats.table_format` of a file name gives it);
        ``"arrow"``: Arrow IPC, the Feather v2 file format (one record batch per block).
    float_format, metadata, statistics
        As :func:`write_table`.
    threads : int, optional
        CSV: the most threads formatting blocks at once (default: as :func:`write_table`).

    Each :meth:`write` appends rows with the same columns; the CSV header comes with the
    first. CSV text cells are quoted, when one needs it, piece by piece (each piece as
    :func:`write_table` would quote it). Call :meth:`close` at the end, or use it as a context
    manager: on an error it writes the CSV rows handed to it so far (unless writing them failed)
    and stops, with no Parquet or Arrow footer. CSV is formatted on threads
    while the caller goes on (:class:`_CsvBlocks`): a piece's last rows may be written (and
    ``progress`` told) by the next :meth:`write` or by :meth:`close`, so its arrays must not
    change until then.
    """

    def __init__(self, out: TextIO | BinaryIO, *, parquet: bool = False, format: str | None = None, float_format: str = "%.10g",
                 metadata: Mapping[str, str] | None = None, statistics: bool = False, threads: int | None = None):
        self.format = format or ("parquet" if parquet else "csv")
        if self.format not in TABLE_FORMATS:
            raise ValueError(f"format {self.format!r}; expected one of: {', '.join(TABLE_FORMATS)}")
        self.out, self.parquet, self.float_format = out, self.format != "csv", float_format
        self.statistics = statistics
        self.metadata = dict(metadata or {})
        self.names: list[str] | None = None
        self._writer: Any = None
        if not hasattr(out, "encoding"):
            self._text = io.TextIOWrapper(out, encoding="utf-8", newline="", write_through=True)  # type: ignore[arg-type]
        else:
            self._text = None
        self._blocks = None if self.parquet else _CsvBlocks(self._text or out, threads)  # type: ignore[arg-type]

    def prepare(self, columns: Mapping[str, Sequence[Any] | np.ndarray]) -> PreparedRows:
        """What :meth:`write` makes of ``columns`` before it writes: the checked plan and, for
        Parquet and Arrow IPC, the Arrow blocks. It reads nothing of the writer's state but its
        settings, so another thread may make it (``softtip estimate --jobs``: the threads that
        estimated the pieces) and hand it to :meth:`write`."""
        prepared = self._plan(columns)
        return PreparedRows(prepared.plan, tuple(prepared.blocks))

    def _plan(self, columns: Mapping[str, Sequence[Any] | np.ndarray]) -> PreparedRows:
        """:meth:`prepare`'s, with the Arrow blocks made one at a time as they are written (a
        table written in one call holds one block beside its columns, not all of them)."""
        plan = _plan_table(columns, self.float_format, text=not self.parquet)
        if not self.parquet:
            return PreparedRows(plan, ())
        plan.parquet = True
        blocks = (
            _arrow_block(plan, start, min(start + _PARQUET_ROWS, plan.n), rounded=False)
            for start in range(0, plan.n, _PARQUET_ROWS)
        )  # fmt: skip
        return PreparedRows(plan, blocks)

    def write(self, columns: Mapping[str, Sequence[Any] | np.ndarray] | PreparedRows,
              progress: Callable[[int], object] | None = None) -> None:  # fmt: skip
        """Append the rows of ``columns`` (the same names, in the same order, every time), or of
        what :meth:`prepare` made of them."""
        prepared = columns if isinstance(columns, PreparedRows) else self._plan(columns)
        plan = prepared.plan
        if self.names is not None and plan.names != self.names:
            raise ValueError(f"columns {plan.names} differ from the first piece's {self.names}")
        plan.progress = progress
        out = self._text or self.out
        if self.parquet:
            binary = getattr(out, "buffer", out)
            out.flush()
            for table in prepared.blocks:
                if self._writer is None:
                    self._writer = _columnar_writer(binary, table, self.metadata, self.format, statistics=self.statistics)
                self._writer.write_table(table)
                if progress is not None:
                    progress(table.num_rows)
        else:
            assert self._blocks is not None
            if self.names is None:
                out.write(plan.header)
            self._blocks.add(plan)
        self.names = plan.names

    def close(self, *, finish: bool = True) -> None:
        """Finish the file (CSV: the rows still being formatted; Parquet: its footer); the stream
        stays open. ``finish=False`` (a failure): stop, with nothing more written, its threads ended."""
        try:
            if self._blocks is not None:
                blocks, self._blocks = self._blocks, None
                blocks.close(write=finish)
            if self._writer is not None:
                writer, self._writer = self._writer, None
                if finish:
                    writer.close()
            if finish:
                (self._text or self.out).flush()
        finally:
            if self._text is not None:
                self._text.detach()
                self._text = None

    def __enter__(self) -> TableWriter:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()
            return
        # an error elsewhere: the rows handed over so far still go out, whole (a table cut after
        # its last piece, as without the threads); the error raised is the one that stopped it
        try:
            if self._blocks is not None and not self._blocks.failed:
                with contextlib.suppress(Exception):
                    self._blocks.flush()
        finally:
            self.close(finish=False)
