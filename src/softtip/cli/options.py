"""What several ``softtip`` commands share: the estimator options and their :class:`EstimatorConfig`,
optional extras, output checks, the progress bar."""

from __future__ import annotations

import math
import os
import sys
from pathlib import Path

import click
import numpy as np

from softtip import __version__
from softtip.cli.frames import FRAMES_HELP  # noqa: F401 - the commands import it from here
from softtip.cli.types import (
    ColumnSpec,
    Force,
    Length,
    Number,
    Scaled,
    UnitName,
    as_written,
    check_pair_increasing,
    option,
)  # fmt: skip
from softtip.core.fingertip import PRESETS, SHAPES, Fingertip
from softtip.core.fullscale import DEFAULT_SENSOR, SENSOR_RANGES, FullScale, parse_full_scale
from softtip.core.noise import NANO17, NOISE_PRESETS, SensorNoise
from softtip.errors import InputError
from softtip.estimator import EstimatorConfig
from softtip.estimator.depth import asked_skin_law
from softtip.estimator.settings import Setting, settings_of
from softtip.estimator.tare import load_bias

#: Upper bounds of --force-noise (N) and --moment-noise (N·mm): far above any six-axis F/T sensor's noise
MAX_FORCE_NOISE, MAX_MOMENT_NOISE_NMM = 100.0, 10_000.0


def POSITIVE(unit: str) -> Number:  # noqa: N802 - reads as a type
    return Number(unit, 0.0, min_open=True)


#: How a setting's command-line unit (:attr:`Setting.cli_unit`) is shown and converted to SI
_SCALED_UNITS = {"deg": math.pi / 180.0, "N·mm": 1e-3, "mm/√s": 1e-3}


def _part_type(s: Setting) -> click.ParamType:
    """The click type of a number setting (or a part of a tuple one), in the unit a person types."""
    bounds = {"min_open": s.low_open, "max_open": s.high_open}
    if s.cli_unit == "force":
        return Force(s.low, s.high, **bounds)
    if s.cli_unit == "mm":
        return Length("mm", s.low, s.high, **bounds)
    if s.cli_unit in _SCALED_UNITS:
        scale = _SCALED_UNITS[s.cli_unit]
        low, high = (None if b is None else b / scale for b in (s.low, s.high))
        return Scaled(s.cli_unit, scale, low, high, **bounds)
    if s.kind == "int":
        return click.IntRange(None if s.low is None else int(s.low), None if s.high is None else int(s.high),
                              min_open=s.low_open, max_open=s.high_open)  # fmt: skip
    return Number(s.unit, s.low, s.high, **bounds)


def _as_typed(s: Setting, value) -> str:
    """A default in the unit a person types it (:attr:`Setting.cli_unit`)."""
    if s.cli_unit == "mm":
        return f"{as_written(value * 1e3)}mm"
    if s.cli_unit in _SCALED_UNITS:
        return as_written(value / _SCALED_UNITS[s.cli_unit])
    return as_written(value)


def _help(s: Setting) -> str:
    """The option's help: the setting's, with the unit it is typed in when the help does not say it."""
    unit = s.cli_unit if s.cli_unit in _SCALED_UNITS else s.unit if s.cli_unit is None else ""
    text = s.help
    if unit and not unit.startswith("(") and unit not in text and s.kind in ("float", "int"):
        more = text.endswith("...")
        text = f"{text.rstrip('. ')}, {'degrees' if unit == 'deg' else unit}" + (" ..." if more else ".")
    entries = {p.cli_unit for p in s.parts} | {s.cli_unit}
    if "mm" in entries:  # how a length is typed
        text += " Lengths: 3mm, 0.3cm; a bare number is in mm."
    if "force" in entries:
        text += " Forces: N unless kgf is given."
    return text


def setting_option(s: Setting):
    """The click option of one estimator setting: ``--`` + its name, its type, range, default and help
    from its :class:`~softtip.estimator.settings.Setting` (the keyword argument is the field's name)."""
    default = getattr(EstimatorConfig, s.name, None) if s.kind != "composite" else None
    attrs = {"help": _help(s), "metavar": s.metavar}
    if s.kind == "bool":
        return option(f"{s.option}/--no-{s.option[2:]}", s.name, default=default, show_default=True, help=s.help)
    if s.kind == "choice":
        # a switch's choice (on, off, ...): the bare option means on, as when it was a flag
        bare = {"is_flag": False, "flag_value": "on"} if "on" in s.choices else {}
        return option(s.option, s.name, type=click.Choice(list(s.choices)), default=default, show_default=True,
                      help=s.help, **bare)  # fmt: skip
    if s.kind == "tuples":
        return option(s.option, s.name, type=tuple(_part_type(p) for p in s.parts), multiple=True, **attrs)
    if s.kind == "tuple":
        attrs["type"] = tuple(_part_type(p) for p in s.parts)
        if default is not None and s.make is None:
            attrs["show_default"] = s.cli_default or " ".join(_as_typed(p, v) for p, v in zip(s.parts, default))
    else:
        attrs["type"] = _part_type(s)
        if default is not None:
            attrs["show_default"] = s.cli_default or _as_typed(s, default)
    return option(s.option, s.name, default=default if s.make is None else None, **attrs)


def config_options() -> list[str]:
    """The command-line options of the estimator's settings, as :func:`estimator_options` adds them."""
    out = []
    for s in settings_of(EstimatorConfig):
        out += list(s.options) if s.kind == "composite" else [s.option] if s.cli else []
    return out


#: The options of the composite settings (:attr:`Setting.options`), written here by hand: a
#: noise preset whose per-axis values the two noise options override, a bias read from a file.
_COMPOSITE_OPTIONS = {
    "bias": [
        option(
            "--bias",
            "bias_file",
            type=click.Path(dir_okay=False),
            metavar="FILE.toml",
            help="Subtract this sensor bias instead of taring ([bias] force = [N, N, N], moment = [N·m, N·m, N·m]; "
            "written by --save-bias or calibrate-payload).",
        ),
    ],
    "noise": [
        option(
            "--sensor",
            type=click.Choice(list(NOISE_PRESETS)),
            help="The sensor's noise preset (ATI Nano17, Nano25, Mini40 class; per axis, fz apart) for --force-noise "
            "and --moment-noise where they are not given. Another sensor (a Mini45, Gamma, Axia80 of --full-scale): "
            "give its noise, or let the tare measure it (--noise-from-tare on). [default: nano17]",
        ),
        option(
            "--force-noise",
            type=Number("N", 0.0, MAX_FORCE_NOISE),
            default=NANO17.force_std[0],
            show_default=True,
            metavar="N",
            help="Per-axis standard deviation of the sensor's force noise, N (Nano17-class default).",
        ),
        option(
            "--moment-noise",
            type=Number("N·mm", 0.0, MAX_MOMENT_NOISE_NMM),
            default=round(NANO17.moment_std[0] * 1e3, 12),
            show_default=True,
            metavar="N·mm",
            help="Per-axis standard deviation of the sensor's moment noise, N·mm.",
        ),
    ],
}


def _estimator_options() -> list:
    """``--tip``, then one option per estimator setting in the config's order (:func:`setting_option`;
    a composite setting's options in its place)."""
    out = [
        option(
            "--tip",
            default="murakami2006",
            show_default=True,
            metavar="PRESET_OR_TOML",
            help=f"Fingertip: a preset ({', '.join(sorted(PRESETS))}) or a TOML file ([fingertip] shape = "
            f"{'|'.join(SHAPES)}, lengths in m; a mesh's file in the units it states).",
        )
    ]
    for s in settings_of(EstimatorConfig):
        if s.kind == "composite":
            out += _COMPOSITE_OPTIONS[s.name]
        elif s.cli:
            out.append(setting_option(s))
    return out


_ESTIMATOR_OPTIONS = _estimator_options()


_LOG_FORMAT_OPTIONS = [
    option(
        "--columns",
        type=ColumnSpec(),
        metavar="ROLE=COLUMN,…",
        help="Which column is t, fx, fy, fz, mx, my, mz, by header name (or 1-based position for a file without a "
        "header row), e.g. t=Time,fx=Fx,…,mz=Tz. Not needed for softtip's, ATI's, rostopic echo -p, ros2 topic echo "
        "--csv and PlotJuggler headers (docs/guide/input-formats.md).",
    ),
    option("--force-units", type=UnitName("force"), help="Units of the force columns whose header gives none. [default: N]"),
    option(
        "--moment-units", type=UnitName("moment"),
        help="Units of the moment columns whose header gives none (N*m, N*mm, kgf*mm, lbf*in; N-mm, Nmm, N·mm "
        "alike). [default: N*m]",
    ),  # fmt: skip
    option(
        "--time-units", type=UnitName("time"),
        help="Units of the time column when its header gives none (s, ms, us, ns). Absolute stamps (Unix time) count "
        "from the first; they go along as a stamp_ns column. [default: s, ns for ROS stamps]",
    ),  # fmt: skip
    option(
        "--missing",
        type=click.Choice(["fail", "drop", "interpolate"]),
        default="fail",
        show_default=True,
        help="An empty or nan cell in t, fx … mz: stop naming it, drop its row (t keeps the gap), or interpolate "
        "linearly in t (before a column's first value or after its last: that value; a row without t is dropped). drop and interpolate also drop a last line cut short (the file "
        "ends inside it, its cells missing). Dropped or filled rows are counted on standard error.",
    ),
    option("--skip-rows", type=click.IntRange(min=0), metavar="N", help="Lines before the header row (a preamble). [default: found]"),
]


#: ``--full-scale``, the same for every command that reads a wrench (estimate, stream, calibrate)
_FULL_SCALE_OPTION = option(
    "--full-scale", metavar="SENSOR|FORCE,MOMENT|off",
    help="The sensor's full-scale range: a sample beyond it (a corrupted row) stops the run naming it. A sensor ("
    + ", ".join(SENSOR_RANGES) + "; rated range per axis), FORCE,MOMENT in N and N·m for every axis, or off "
    "(then only values no sensor gives).  [default: the --sensor's where the command has one, else nano17]",
)  # fmt: skip


def full_scale_option(f):
    """``--full-scale``: the plausibility bound of every wrench read (:func:`full_scale_range`)."""
    return _FULL_SCALE_OPTION(f)


def full_scale_range(full_scale: str | None, sensor: str | None) -> FullScale:
    """The range ``--full-scale`` gives: as given, else the ``--sensor``'s, else a Nano17's
    (:func:`softtip.core.fullscale.parse_full_scale`); exit 2 naming the option for anything else."""
    try:
        return parse_full_scale(full_scale or sensor or DEFAULT_SENSOR)
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="'--full-scale'") from None


def log_format_options(f):
    """How a CSV log's columns, units and missing cells are read (:func:`softtip.io.tables.read_log`)."""
    for decorator in reversed(_LOG_FORMAT_OPTIONS):
        f = decorator(f)
    return f


def log_format_kwargs(opts: dict) -> dict:
    """Pop the :func:`log_format_options` from a command's keyword arguments, as :func:`read_log`'s keywords."""
    return {
        "columns": opts.pop("columns", None), "force_units": opts.pop("force_units", None),
        "moment_units": opts.pop("moment_units", None), "time_units": opts.pop("time_units", None),
        "missing": opts.pop("missing", "fail") or "fail", "skip_rows": opts.pop("skip_rows", None),
    }  # fmt: skip


def log_format_names() -> str:
    """The :func:`log_format_options` as a message names them: ``--columns, …, --missing and --skip-rows``."""
    names = ["--" + key.replace("_", "-") for key in log_format_kwargs({})]
    return f"{', '.join(names[:-1])} and {names[-1]}"


def log_format_given(kwargs: dict) -> bool:
    """Whether any :func:`log_format_options` differs from its default."""
    return any(v not in (None, "fail", {}) for v in kwargs.values())


def print_log_notes(log, quiet: bool = False) -> None:
    """How a foreign log was read (columns, units, skipped lines, missing cells; not with
    ``quiet``), then its warnings."""
    for note in () if quiet else getattr(log, "notes", ()):
        click.echo(f"softtip: {note}", err=True)
    suspect = getattr(log, "time_suspect", None)
    if suspect is not None:  # t in ms read as s: a one-sample tare and windows of thousands of samples
        raise InputError(suspect.replace(". Give t in seconds:", ". Stopped: give --time-units (or t in seconds):"))
    for note in log.warnings:  # repeated stamps, an implausible time scale, a cut last line
        click.echo(f"softtip: warning: {note}", err=True)


def sensor_noise(sensor: str | None, force_noise: float, moment_noise_nmm: float) -> SensorNoise:
    """The noise model of ``--sensor`` and ``--force-noise`` (N) / ``--moment-noise`` (N·mm): an option given on
    the command line wins for its quantity, the preset (per axis) gives the rest."""
    explicit = {"force_noise": True, "moment_noise": True}
    ctx = click.get_current_context(silent=True)
    if ctx is not None:
        for name in explicit:
            try:
                source = ctx.get_parameter_source(name)
            except KeyError:
                continue
            explicit[name] = source is not None and source.name not in ("DEFAULT", "DEFAULT_MAP")
    given = SensorNoise((force_noise,) * 3, (moment_noise_nmm * 1e-3,) * 3)
    if sensor is None:
        return given
    preset = NOISE_PRESETS[sensor]
    return SensorNoise(
        given.force_std if explicit["force_noise"] else preset.force_std,
        given.moment_std if explicit["moment_noise"] else preset.moment_std,
    )


def estimator_options(f):
    """The pipeline settings shared by ``estimate`` and ``stream``."""
    for decorator in reversed(_ESTIMATOR_OPTIONS):
        f = decorator(f)
    return f


def tare_covers_log(source: str, n: int, t_first: float, t_last: float, tare_duration: float) -> InputError:
    """The error of a log of ``n`` samples (t from ``t_first`` to ``t_last``, s as read) that lies
    within its tare window: nothing estimated, so the time unit read is likely wrong (or, for one
    sample, the log is too short to tare)."""
    if n == 1:
        return InputError(
            f"{source}: one sample (t = {t_first:.6g} s): nothing to estimate, as the first {tare_duration:g} s tare the "
            "sensor; expected a log longer than the tare, or --tare-duration 0 (or a --bias) for one that is tared"
        )
    return InputError(
        f"{source}: the whole log ({n} samples, t from {t_first:.6g} to {t_last:.6g} s as read) lies within the first "
        f"{tare_duration:g} s used to tare the sensor: nothing to estimate. If t is in another unit than read (a "
        "header's 'Time (ms)' over seconds), correct the header or give --time-units; a log that is already tared "
        "needs --tare-duration 0 (or a --bias)"
    )


def check_units(est, fingertip, config: EstimatorConfig, log, source: str | None = None) -> None:
    """Exit 2 when the wrench's units make the fingertip geometry or the sensor's noise impossible
    (:func:`softtip.core.lever.check_wrench_units`), naming the unit pairs that fit the data."""
    from softtip.core.lever import check_wrench_units

    taring = np.asarray(est.taring, dtype=bool)
    if len(taring) and taring.all():  # nothing estimated: a log that cannot be what its reader took it for
        t = np.asarray(log.t, dtype=float)
        raise tare_covers_log(source or log.source, len(t), t[0], t[-1], config.tare_duration)
    given = getattr(log, "units_in_header", ())
    try:
        check_wrench_units(
            est.wrench[~est.taring], fingertip, force_unit=getattr(log, "force_unit", "N"),
            moment_unit=getattr(log, "moment_unit", "N*m"), quiet=quiet_samples(est, log.wrench), noise=config.noise,
            source=source or log.source, min_force=max(0.1, config.contact_threshold), options=not given,
        )  # fmt: skip
    except InputError as exc:
        if not given:
            raise
        raise InputError(
            f"{exc}. The file gives the units of {', '.join(map(repr, given))} (its header, a units row or a line "
            "before the header such as 'Torque Units,N-mm'), and an option cannot override a unit the file gives: if "
            "the data are in another unit, the file is wrong; correct it"
        ) from None


def quiet_samples(est, wrench):
    """The input ``wrench``'s samples in a run's tare window (its first 50 when it did not tare), for the noise check."""
    taring = np.asarray(est.taring, dtype=bool)[: len(wrench)]
    return wrench[: len(taring)][taring] if np.count_nonzero(taring) >= 6 else wrench[:50]


def bag_warnings(path: str, bag_log) -> None:
    """Say what was odd about a bag that was read anyway (damaged with --allow-partial; repeated stamps)."""
    if bag_log.damage:
        click.echo(f"softtip: warning: {path}: damaged bag, {len(bag_log.t)} samples used: {bag_log.damage}", err=True)
    if bag_log.repeated_stamps:
        click.echo(
            f"softtip: {path}: {bag_log.repeated_stamps} message(s) repeat the previous header.stamp (kept)", err=True
        )


def check_outputs(inputs, outputs, table_formats: tuple[str, ...] = ("csv", "parquet", "arrow")) -> None:
    """Exit 2 when an output is an input or another output of the run (:func:`softtip.io.atomic.check_distinct`),
    or ``-o`` is named like a table the command does not write (``table_formats``: :func:`check_table_names`)."""
    from softtip.io.atomic import check_distinct

    outputs = list(outputs)
    check_output_names(outputs)
    check_table_names(outputs, table_formats)
    check_distinct(inputs, outputs)


def check_table_names(outputs, formats: tuple[str, ...] = ("csv", "parquet", "arrow")) -> None:
    """Exit 2 when ``-o`` (a table: CSV, or Parquet / Arrow IPC by its name where the command
    writes them, ``formats``) is named like a ROS bag, or like a table format the command does
    not write, which it would otherwise fill with CSV text; the remedy names ``--to-bag`` where
    the command has it."""
    from softtip.io.bag import BAG_SUFFIXES
    from softtip.io.formats import COMPRESSED_SUFFIXES, TABLE_FORMATS, table_format

    labels = [label for label, _ in outputs]
    for label, path in outputs:
        if label != "-o" or path is None:
            continue
        suffix = Path(os.fspath(path)).suffix
        codec = COMPRESSED_SUFFIXES.get(suffix.lower())
        if codec is not None:
            plain = os.fspath(path)[: -len(suffix)]
            parquet = "; or -o OUT.parquet, which is compressed" if "parquet" in formats else ""
            raise click.BadParameter(
                f"{path} is named like {'an' if codec[0] in 'aeiouxl' else 'a'} {codec}-compressed file, but -o writes "
                f"uncompressed text; expected a name without {suffix} (-o {plain}, then compress it: {codec} {plain})"
                f"{parquet}", param_hint="'-o'",
            )  # fmt: skip
        if Path(os.fspath(path)).suffix.lower() in BAG_SUFFIXES:
            remedy = f"; a bag is written by --to-bag {path}" if "--to-bag" in labels else ""
            raise click.BadParameter(
                f"{path} is named like a ROS bag, but -o writes a table (CSV unless --help says otherwise), not a bag; "
                f"expected another name{remedy}", param_hint="'-o'",
            )  # fmt: skip
        if table_format(path) not in formats:
            kind = TABLE_FORMATS[table_format(path)][1]
            raise click.BadParameter(
                f"{path} is named like {'an' if kind[0] in 'AEIOU' else 'a'} {kind} file, but this command writes CSV; "
                "expected a name ending in .csv",
                param_hint="'-o'",
            )


def check_output_names(outputs) -> None:
    """Exit 2 naming the option when an output is given as an empty name or as an existing directory."""
    for label, path in outputs:
        if path is None:
            continue
        text = os.fspath(path)
        if text == "" or (isinstance(path, Path) and not path.name):
            if text and os.path.isdir(text):  # '.', whose name is empty
                raise click.BadParameter(f"{text} is a directory; expected a file name", param_hint=f"'{label}'")
            raise click.BadParameter(f"{text!r} is an empty file name; expected a file name", param_hint=f"'{label}'")



class _NoProgress:
    """What :func:`progress_bar` gives when standard error is not a terminal."""

    def update(self, n: int = 1) -> None:
        pass

    def close(self) -> None:
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        pass


def progress_bar(total: int, what: str, *, unit: str = " rows", file=None, delay: float = 2.0):
    """A tqdm bar on standard error, shown only on a terminal and only after ``delay`` s."""
    file = sys.stderr if file is None else file
    tty = file.isatty()
    if not tty:
        return _NoProgress()
    from tqdm import tqdm  # only on a terminal: importing it costs a command 20 ms of start-up
    # no monitor thread: a daemon thread alive at interpreter exit, with pyarrow loaded,
    # aborted the process ("terminate called without an active exception") in ~half the
    # runs that ended on an error
    tqdm.monitor_interval = 0
    size = {}
    try:
        if tty and os.get_terminal_size(file.fileno()).lines <= 0:  # a pty with no size: tqdm would draw nothing
            size = {"ncols": 80, "nrows": 20}
    except (OSError, ValueError, AttributeError):
        size = {"ncols": 80, "nrows": 20}
    return tqdm(
        total=total, desc=f"softtip: {what}", unit=unit, unit_scale=True, file=file, delay=delay,
        disable=not tty, leave=False, **size,
    )  # fmt: skip


def parquet_metadata(fingertip, tip: str, output_units: str, log) -> dict[str, str]:
    """Key-value metadata of a Parquet output: units, fingertip, input, softtip's version."""
    from softtip.io.tables import PARQUET_FINGERTIP_KEY, PARQUET_UNITS_KEY

    meta = {PARQUET_UNITS_KEY: output_units, "softtip.tip": str(tip), "softtip.input": log.source, "softtip.version": __version__}
    try:
        meta[PARQUET_FINGERTIP_KEY] = fingertip.to_toml()
    except ValueError:  # a tip with no TOML form (callables, a mesh built from arrays): the file names none
        pass
    return meta


def check_figure_path(path: str) -> None:
    """A figure path needs an existing folder and a format matplotlib writes (exit 2 otherwise)."""
    from softtip.viz.plot import figure_formats

    p = Path(path)
    formats = figure_formats()
    if p.suffix.lower().lstrip(".") not in formats:
        raise InputError(f"{path}: expected a figure file name ending in one of {', '.join('.' + f for f in sorted(formats))}")
    if not p.parent.is_dir():
        raise InputError(f"{path}: folder {str(p.parent)!r} does not exist")


def tare_warnings(est, quiet: bool = False, name: str | None = None) -> None:
    """Say what the tare did (not when ``quiet``), and every warning of the estimator (all from the library);
    each line after ``name:`` when given (one of several fingertips)."""
    head = "softtip: " if name is None else f"softtip: {name}: "
    if not quiet and est.tare is not None and est.tare.source != "none" and np.all(np.isfinite(est.bias)):
        click.echo(f"{head}{est.tare.summary()}", err=True)
    for msg in est.warnings:
        click.echo(f"{head}warning: {msg}", err=True)


def make_config(opts: dict, sample_rate: float | None = None, tip: Fingertip | None = None) -> EstimatorConfig:
    """The :class:`EstimatorConfig` of the estimator options (:func:`estimator_options`; already in SI)."""
    check_pair_increasing("--latch-window", opts["latch_window"], "N")
    values = {}
    for s in settings_of(EstimatorConfig):
        if s.kind == "composite" or not s.cli:
            continue
        v = opts[s.name]
        if s.kind == "tuples":
            v = tuple(v)
        elif s.make is not None and v is not None:
            v = s.make(*v)
        values[s.name] = v
    values["skin_law"] = asked_skin_law(values["depth_compensation"], values["skin_law"], tip)
    try:
        return EstimatorConfig(
            **values,
            noise=sensor_noise(opts.get("sensor"), opts["force_noise"], opts["moment_noise"]),
            sample_rate=sample_rate,
            bias=None if opts["bias_file"] is None else load_bias(opts["bias_file"]),
        )
    except ValueError as exc:
        raise click.UsageError(str(exc)) from None


def is_bag(path: str) -> bool:
    from softtip.io.bag import is_bag  # rosbags itself is imported only to read one

    return is_bag(path)


def optional_extra(module: str, extra: str):
    """Import one of softtip's modules that needs an optional extra; exit 2 naming the extra."""
    import importlib

    try:
        mod = importlib.import_module(module)
        getattr(mod, {"ros": "import_rosbags", "viz": "import_rerun"}[extra])()
    except ImportError as exc:  # the message names the package to install
        raise InputError(str(exc)) from None
    return mod
