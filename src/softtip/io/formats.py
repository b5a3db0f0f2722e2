"""What a force/torque log from other software looks like: the recognised header dialects,
the column mapping, and the per-quantity units (docs/guide/input-formats.md has the table).

One registry, :data:`SOURCES`, declares each recognised header dialect once (the names its
columns have, the unit of its time column when the header does not say); the reader
(:mod:`softtip.io.tables`), the CLI's messages and the documentation's table come from it.
Units come from :data:`softtip.core.units.UNITS`.

A column is matched on its name with the unit part removed (``"Fx (N)"`` → ``"fx"`` in
``N``; ``"Tz [N-mm]"`` → ``"tz"`` in ``N·mm``), case-insensitively. ``--columns``
(:func:`parse_column_spec`) names columns for anything else, or gives their 1-based
positions for a file without a header row.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from softtip.core.units import UNIT_SYSTEM_UNITS, Unit, find_unit, get_unit

__all__ = [
    "ROLES",
    "ROLE_QUANTITY",
    "SOURCES",
    "Source",
    "LogFormat",
    "ColumnMap",
    "MISSING_POLICIES",
    "parse_column_spec",
    "recognised_roles",
    "resolve_columns",
    "split_unit",
    "stated_unit",
    "TABLE_FORMATS",
    "table_format",
]

#: What a log's columns are read as, in wrench order after ``t``.
ROLES: tuple[str, ...] = ("t", "fx", "fy", "fz", "mx", "my", "mz")
#: The quantity (for units) of each role; ``nanosec`` is the nanosecond part of a stamp split in two.
ROLE_QUANTITY = {"t": "time", "nanosec": "time", **dict.fromkeys(ROLES[1:4], "force"), **dict.fromkeys(ROLES[4:], "moment")}

#: Table files by the name's suffix (lower case): format → (suffixes, name in messages). A name
#: with none of these suffixes is CSV. The readers and writers of :mod:`softtip.io.tables` and
#: the command line dispatch on :func:`table_format`; Arrow IPC is the file format Feather v2 is.
TABLE_FORMATS: dict[str, tuple[tuple[str, ...], str]] = {
    "parquet": ((".parquet",), "Parquet"),
    "arrow": ((".arrow", ".feather"), "Arrow IPC (Feather v2)"),
    "csv": ((), "CSV"),
}


#: Compression suffixes, by the compression's name. The readers take compressed CSV logs by their
#: content, whatever the name; the writers write uncompressed text, so ``-o`` refuses these names.
COMPRESSED_SUFFIXES: dict[str, str] = {".gz": "gzip", ".bz2": "bzip2", ".xz": "xz", ".zst": "zstd", ".lz4": "lz4"}


def table_format(path: object) -> str:
    """``"parquet"``, ``"arrow"`` or ``"csv"``: a table file's format by its name's suffix.

    >>> table_format("run.feather"), table_format("RUN.PARQUET"), table_format("run.csv.gz")
    ('arrow', 'parquet', 'csv')
    """
    import os

    name = os.fspath(path).lower() if isinstance(path, (str, os.PathLike)) else ""  # type: ignore[arg-type]
    for fmt, (suffixes, _) in TABLE_FORMATS.items():
        if name.endswith(suffixes):
            return fmt
    return "csv"


#: ``--missing``: what an empty or ``nan`` cell in a required column does.
MISSING_POLICIES = ("fail", "drop", "interpolate")


def _axes(force: str, moment: str) -> dict[str, tuple[str, ...]]:
    """Patterns for ``fx..mz`` from a pattern with ``{a}`` for the axis letter."""
    out: dict[str, tuple[str, ...]] = {}
    for axis in "xyz":
        out[f"f{axis}"] = tuple(p.format(a=axis) for p in force.split("|"))
        out[f"m{axis}"] = tuple(p.format(a=axis) for p in moment.split("|"))
    return out


@dataclass(frozen=True)
class Source:
    """A header dialect softtip recognises without options.

    Attributes
    ----------
    name : str
        The software that writes it, for messages and the documentation.
    example : str
        A header it writes (shortened with ``…``).
    patterns : dict of str to tuple of str
        For each role (``t``, ``fx`` … ``mz``, optionally ``nanosec``), regular expressions
        (full match, on the lower-cased name without its unit), in order of preference.
    time_unit : str
        Unit of the time column when the header does not give one.
    """

    name: str
    example: str
    patterns: dict[str, tuple[str, ...]]
    time_unit: str = "s"


#: Header dialects, most specific first (the first that maps every role wins). The ROS ones read a
#: WrenchStamped topic's fields, else a Wrench topic's (no header: no "wrench" in the field path).
SOURCES: tuple[Source, ...] = (
    Source(
        "softtip live recording (stream --record)",
        "t,fx_raw,…,mz_raw,state,fx,…,mz,…",
        {"t": ("t",), **_axes(r"f{a}_raw", r"m{a}_raw")},
    ),
    Source(
        "softtip, ATI (Net F/T, DAQ F/T), generic",
        "Time (ms),Fx (N),Fy (N),Fz (N),Tx (N-mm),Ty (N-mm),Tz (N-mm)",
        {"t": ("t", "time", "times", "timestamp", "time_?stamp", "seconds"),
         **_axes(r"f_?{a}|force_?{a}", r"[mt]_?{a}|torque_?{a}|moment_?{a}")},
    ),
    Source(
        "ROS 1 rostopic echo -p",
        "%time,field.header.seq,field.header.stamp,field.header.frame_id,field.wrench.force.x,…,field.wrench.torque.z",
        {"t": (r"field\.header\.stamp", "%time"),
         **_axes(r"field\.wrench\.force\.{a}|field\.force\.{a}", r"field\.wrench\.torque\.{a}|field\.torque\.{a}")},
        time_unit="ns",
    ),
    Source(
        "PlotJuggler (CSV export)",
        "__time,/ft/wrench/force/x,…,/ft/wrench/torque/z",
        {"t": ("__time",), **_axes(r".*/wrench/force/{a}|.*/force/{a}", r".*/wrench/torque/{a}|.*/torque/{a}")},
    ),
    Source(
        "rosbag to CSV converters (bagpy, rosbags, rqt_bag)",
        "Time,header.seq,header.stamp.secs,header.stamp.nsecs,header.frame_id,wrench.force.x,…",
        {"t": (r"(.*[./_])?header[./_]stamp[./_]secs?", "time", "timestamp", r"%time"),
         "nanosec": (r"(.*[./_])?header[./_]stamp[./_]n(ano)?secs?",),
         **_axes(r"(.*[./_])?wrench[./_]force[./_]{a}|force\.{a}", r"(.*[./_])?wrench[./_]torque[./_]{a}|torque\.{a}")},
    ),
)

#: ``ros2 topic echo --csv`` of a geometry_msgs/msg/WrenchStamped topic: no header row; these
#: cells: stamp seconds, stamp nanoseconds, frame_id, force x y z, torque x y z.
ROS2_CSV_NAMES = (
    "header.stamp.sec", "header.stamp.nanosec", "header.frame_id",
    "wrench.force.x", "wrench.force.y", "wrench.force.z", "wrench.torque.x", "wrench.torque.y", "wrench.torque.z",
)  # fmt: skip
ROS2_CSV = Source(
    "ROS 2 ros2 topic echo --csv (no header row)",
    "1700000000,123456789,ft_sensor,0.12,-0.05,0.29,0.002,-0.001,0.0005",
    {"t": (r"header\.stamp\.sec",), "nanosec": (r"header\.stamp\.nanosec",),
     **_axes(r"wrench\.force\.{a}", r"wrench\.torque\.{a}")},
)

_UNIT_IN_NAME = re.compile(r"^(?P<base>.*?)\s*[(\[](?P<unit>[^()\[\]]*)[)\]]\s*$")


def split_unit(name: str) -> tuple[str, str | None]:
    """A header name's base and its unit text: ``"Fx (N)"`` → ``("Fx", "N")``; no unit: None."""
    m = _UNIT_IN_NAME.match(name.strip())
    if m and m.group("base"):
        return m.group("base").strip(), m.group("unit").strip()
    return name.strip(), None


@dataclass(frozen=True)
class LogFormat:
    """How to read a log's columns and units, beyond what its header says.

    Attributes
    ----------
    columns : dict of str to str
        ``--columns``: role (``t``, ``fx`` … ``mz``) → header name, or 1-based column
        position (as text of digits) for a file without a header row.
    force_unit, moment_unit, time_unit : str or None
        Units of the columns whose header does not give one (a name of
        :data:`softtip.core.units.UNITS`); None: N, N·m, and the dialect's time unit (s).
    missing : {"fail", "drop", "interpolate"}
        An empty or ``nan`` cell in a required column: an error (naming the option), its
        row dropped, or its value interpolated linearly in ``t``.
    skip_rows : int or None
        Lines before the header row to skip; None: blank, ``#`` and preamble lines are found.
    """

    columns: Mapping[str, str] = field(default_factory=dict)
    force_unit: str | None = None
    moment_unit: str | None = None
    time_unit: str | None = None
    missing: str = "fail"
    skip_rows: int | None = None

    @classmethod
    def of(cls, units: str | None = None, **kwargs: object) -> LogFormat:
        """A format from ``--units`` (si|kgf-mm) and the per-quantity options; conflicts raise ValueError."""
        fmt = cls(**{k: v for k, v in kwargs.items() if v is not None})  # type: ignore[arg-type]
        for name in ("force_unit", "moment_unit", "time_unit"):
            value = getattr(fmt, name)
            if value is not None:
                object.__setattr__(fmt, name, get_unit(value, name.split("_")[0]).name)
        if fmt.missing not in MISSING_POLICIES:
            raise ValueError(f"unknown --missing {fmt.missing!r}; expected one of: {', '.join(MISSING_POLICIES)}")
        if units is not None and units != "si":
            force, moment = UNIT_SYSTEM_UNITS[units]
            for name, value in (("force", force), ("moment", moment)):
                given = getattr(fmt, f"{name}_unit")
                if given is not None and given != value:
                    raise ValueError(f"--units {units} says {name} in {value}, --{name}-units says {given}; give one")
                object.__setattr__(fmt, f"{name}_unit", value)
        return fmt

    def unit_option(self, quantity: str) -> str | None:
        """The unit an option gives ``quantity`` (``"force"``, ``"moment"``, ``"time"``), or None."""
        return getattr(self, f"{quantity}_unit")


@dataclass(frozen=True)
class ColumnMap:
    """Which column of a log is read as what, in which unit.

    Attributes
    ----------
    index : dict of str to int
        Role → 0-based column position (roles ``t``, ``fx`` … ``mz``, and ``nanosec`` for a
        stamp split in seconds and nanoseconds).
    units : dict of str to Unit
        Role → the unit its values are in.
    from_header : dict of str to bool
        Role → whether the header gave the unit.
    source : str
        The dialect recognised (or ``"--columns"``).
    units_row : int
        The line of a row of units under the header, 0 without one.
    row_units : frozenset of str
        The roles whose unit that row gave.
    stated_on : dict of str to int
        Role → the line before the header that stated its quantity's unit (``Torque Units,N-mm``
        in an ATI log's preamble).
    counts : dict of str to (float, int)
        Role → the counts per unit its raw values are in, and the line that said so (``Counts
        per Unit Force,1000000`` in a Net F/T demo log): the values are divided by it.
    typed : dict of str to str
        Role → the Parquet or Arrow column type that gave its unit (``timestamp[us, tz=UTC]``).
    """

    index: dict[str, int]
    units: dict[str, Unit]
    from_header: dict[str, bool]
    source: str
    units_row: int = 0
    row_units: frozenset[str] = frozenset()
    stated_on: dict[str, int] = field(default_factory=dict)
    counts: dict[str, tuple[float, int]] = field(default_factory=dict)
    typed: dict[str, str] = field(default_factory=dict)

    def native(self, names: Sequence[str]) -> bool:
        """Whether this is softtip's own layout: columns named exactly ``t, fx … mz``, SI, no unit in the header."""
        return (
            "nanosec" not in self.index
            and all(names[self.index[r]] == r for r in ROLES)
            and all(u.si == 1.0 for u in self.units.values())
            and not any(self.from_header.values())
            and not self.counts
            and not self.typed
        )

    def describe(self, names: Sequence[str], named: str = "header") -> str:
        """``t ← 'Time (ms)' (ms), fx ← 'Fx (N)' (N), …`` for the message on stderr; ``named``:
        what gives the names (a CSV file's header, a Parquet or Arrow column's name)."""
        parts = []
        for role in (*ROLES, "nanosec"):
            if role in self.index:
                unit = self.units[role]
                how = "" if self.from_header[role] else f", not in the {named}"
                if role in self.typed:
                    how = f", its type {self.typed[role]}"
                elif role in self.row_units:
                    how = f", from the units row on line {self.units_row}"
                elif role in self.stated_on:
                    how = f", from line {self.stated_on[role]}"
                if role in self.counts:
                    per_unit, line = self.counts[role]
                    how += f", counts ÷ {per_unit:g} from line {line}"
                parts.append(f"{role} ← {names[self.index[role]]!r} ({unit.label}{how})")
        return ", ".join(parts)


def parse_column_spec(text: str) -> dict[str, str]:
    """``"t=Time,fx=Fx,..."`` → ``{"t": "Time", "fx": "Fx", ...}``; ValueError naming what is wrong."""
    out: dict[str, str] = {}
    for part in [p for p in text.split(",") if p.strip()]:
        role, eq, name = part.partition("=")
        role = role.strip()
        if not eq or not name.strip():
            raise ValueError(f"{part.strip()!r} is not ROLE=COLUMN (e.g. t=Time,fx=Fx)")
        if role not in ROLES:
            raise ValueError(f"{role!r} is not one of {', '.join(ROLES)}")
        if role in out:
            raise ValueError(f"{role!r} is given twice")
        out[role] = name.strip()
    return out


def recognised_roles(names: Sequence[str]) -> dict[str, int]:
    """Role → position of the first column some dialect of :data:`SOURCES` reads as it (each
    dialect on its own; for the message that names what no dialect reads)."""
    bases = [split_unit(n)[0].lower() for n in names]
    found: dict[str, int] = {}
    for source in SOURCES:
        for role, patterns in source.patterns.items():
            hits = _match(patterns, bases, set()) if role in ROLES and role not in found else []
            if hits:
                found[role] = hits[0]
    return found


class ColumnError(ValueError):
    """The columns cannot be mapped; ``hint`` says what would fix it."""


class ColumnAbsent(ColumnError):
    """A column ``--columns`` names is not on this line (the header may be further down);
    ``found``: how many of the columns it names the line has."""

    def __init__(self, message: str, found: int) -> None:
        super().__init__(message)
        self.found = found


def _match(patterns: tuple[str, ...], bases: list[str], taken: set[int]) -> list[int]:
    for pattern in patterns:
        hits = [j for j, b in enumerate(bases) if j not in taken and re.fullmatch(pattern, b)]
        if hits:
            return hits
    return []


def resolve_columns(names: Sequence[str], fmt: LogFormat, *, headerless: bool = False) -> ColumnMap | None:
    """Map a header's names to the roles, with units; None when no dialect maps every role.

    Raises
    ------
    ColumnError
        ``--columns`` names a column the header does not have; a role two columns could
        be (two topics in a PlotJuggler export); a unit the header gives that softtip does
        not know, or that contradicts a unit option.
    """
    split = [split_unit(n) for n in names]
    bases = [b.lower() for b, _ in split]
    chosen: dict[str, int] | None = None
    source = ""
    if fmt.columns:
        chosen = {}
        for role, want in fmt.columns.items():
            if want.isdigit() and (headerless or want not in names):
                j = int(want) - 1
                if not 0 <= j < len(names):
                    spaced = len(names) == 1 and len(names[0].split()) > 1
                    raise ColumnAbsent(
                        f"--columns {role}={want}: the file has {len(names)} columns"
                        + ("; its rows look space-separated: softtip reads comma, tab or semicolon delimiters (replace "
                           "the spaces between cells, e.g. tr -s ' ' ',')" if spaced else ""), len(chosen),
                    )  # fmt: skip
            elif want in names:
                j = list(names).index(want)
            else:
                lower = [n.lower() for n in names]
                if want.lower() in lower:
                    j = lower.index(want.lower())
                elif want.lower() in bases:
                    j = bases.index(want.lower())
                else:
                    present = sum(w.lower() in lower or w.lower() in bases for w in fmt.columns.values())
                    raise ColumnAbsent(
                        f"--columns {role}={want}: no column {want!r} in the header ({', '.join(map(repr, names))})",
                        present,
                    )
            chosen[role] = j
        source = "--columns"
    candidates = ((ROS2_CSV,) if headerless else SOURCES) if len(fmt.columns) < len(ROLES) else ()
    for candidate in candidates:
        index = dict(chosen or {})
        taken = set(index.values())
        ok = True
        for role, patterns in candidate.patterns.items():
            if role in index:
                continue
            hits = _match(patterns, bases, taken)
            exact = [j for j in hits if names[j].strip() == role]
            if len(hits) > 1 and len(exact) == 1:
                hits = exact  # softtip's own name wins over a look-alike (an extra "Fx" next to "fx")
            if len(hits) > 1:
                if len({names[j] for j in hits}) < len(hits):
                    return None  # a duplicate name: the reader says so
                listed = ", ".join(repr(names[j]) for j in hits)
                raise ColumnError(
                    f"columns {listed} could each be {role!r} ({candidate.name}); give the one to use with "
                    f"--columns {role}={names[hits[0]]},…"
                )
            if not hits:
                if role == "nanosec":
                    continue
                ok = False
                break
            index[role] = hits[0]
            taken.add(hits[0])
        if ok and "nanosec" in index and not re.search(r"secs?$", bases[index["t"]]):
            del index["nanosec"]  # nanoseconds only complete a seconds stamp
        if ok:
            chosen, source = index, (candidate.name if not fmt.columns else f"--columns and {candidate.name}")
            time_default = candidate.time_unit
            break
    else:
        time_default = "s"
        if chosen is None or any(r not in chosen for r in ROLES):
            return None
    units: dict[str, Unit] = {}
    from_header: dict[str, bool] = {}
    for role, j in chosen.items():
        quantity = ROLE_QUANTITY[role]
        text = split[j][1]
        option = fmt.unit_option(quantity)
        if role == "nanosec":
            units[role], from_header[role] = get_unit("ns", "time"), True
            continue
        if role == "t" and "nanosec" in chosen and option is not None and get_unit(option, "time").name != "s":
            raise ColumnError(
                f"column {names[j]!r} holds the whole seconds of a stamp split in seconds and nanoseconds "
                f"({names[chosen['nanosec']]!r}); --time-units {option} does not apply: leave it out"
            )
        if text is not None:
            units[role], from_header[role] = stated_unit(text, quantity, option, names[j], "the header"), True
        else:
            if role == "t" and "nanosec" in chosen:
                default = "s"
            else:
                default = time_default if quantity == "time" else ("N" if quantity == "force" else "N*m")
            units[role], from_header[role] = get_unit(option or default, quantity), False
    return ColumnMap(index=chosen, units=units, from_header=from_header, source=source)


def stated_unit(text: str, quantity: str, option: str | None, column: str, stated_by: str) -> Unit:
    """The unit a file states for ``column`` (``stated_by``: ``"the header"``, ``"the units row"``),
    checked against the unit option given for its ``quantity`` (``option``, None: none given).

    Raises
    ------
    ColumnError
        No unit of ``quantity`` is named ``text``, or the option names another unit.
    """
    unit = find_unit(text, quantity)
    if unit is None:
        hint = f" (or rename the column and give --{quantity}-units)" if stated_by == "the header" else ""
        raise ColumnError(
            f"column {column!r}: unknown {quantity} unit {text!r} in {stated_by}; expected one of: "
            f"{', '.join(_names(quantity))}{hint}"
        )
    if option is not None and get_unit(option, quantity) is not unit:
        raise ColumnError(
            f"column {column!r}: {stated_by} says {unit.label} but --{quantity}-units{'' if quantity == 'time' else ' (or --units)'} "
            f"says {option}; "
            f"leave the option out to use the unit {stated_by} gives"
        )
    return unit


def _names(quantity: str) -> list[str]:
    from softtip.core.units import unit_names

    return unit_names(quantity)
