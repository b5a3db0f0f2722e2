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
from softtip.cli.types import ColumnSpec, Force, Length, Number, UnitName, check_pair_increasing, option
from softtip.core.depth import MURAKAMI2006_DEPTH, DepthLaw
from softtip.core.fingertip import PRESETS, Fingertip
from softtip.core.noise import NANO17, SensorNoise
from softtip.errors import InputError
from softtip.estimator import EstimatorConfig
from softtip.estimator.depth import tip_depth_law
from softtip.estimator.tare import load_bias

FRAMES_HELP = """\
Frames and units: every vector is in the sensor frame (origin at the F/T sensor's
measuring point, z along the finger axis toward the tip, right-handed). Inside and in
every file softtip uses SI: N, N·m, m, s; angles are degrees in files and plots. f and m
are the force and moment the touched object exerts on the fingertip, moment about the
sensor origin; in contact f pushes into the fingertip.
"""

#: Upper bounds of --force-noise (N) and --moment-noise (N·mm): far above any six-axis F/T sensor's noise
MAX_FORCE_NOISE, MAX_MOMENT_NOISE_NMM = 100.0, 10_000.0


def NON_NEGATIVE(unit: str) -> Number:  # noqa: N802 - reads as a type
    return Number(unit, 0.0)


def POSITIVE(unit: str) -> Number:  # noqa: N802
    return Number(unit, 0.0, min_open=True)


#: A positive length option of the estimator: a unit may be given (3mm, 0.3cm); a bare number is in mm
MM_POSITIVE = Length("mm", 0.0, min_open=True)


def _model_std_option(name: str, default: float, what: str):
    """A model-error standard deviation in degrees, added in quadrature to a reported one."""
    return option(name, type=NON_NEGATIVE("deg"), default=default, show_default=True, metavar="DEG",
                  help=f"Model error of {what}, added in quadrature to its standard deviation, degrees (0: none).")  # fmt: skip


_ESTIMATOR_OPTIONS = [
    option(
        "--tip",
        default="murakami2006",
        show_default=True,
        metavar="PRESET_OR_TOML",
        help=f"Fingertip: a preset ({', '.join(sorted(PRESETS))}) or a TOML file ([fingertip] shape = sphere|capsule|ellipsoid, lengths in m).",
    ),
    option(
        "--contact-point",
        type=click.Choice(["latch", "track", "line-fit", "joint"]),
        default="latch",
        show_default=True,
        help="latch: measure the contact point in the light-force window at the start of the grasp and hold it (the papers'); "
        "track: soft-finger solution every sample (h is then zero by construction: no directions); "
        "line-fit: latch, then move the point across the line to where a sliding window (--joint-window) fits the "
        "line-contact model, wherever the window determines it (flagged line_fit_fallback until one does); "
        "joint: its former name.",
    ),
    option(
        "--joint-window",
        type=POSITIVE("s"),
        default=1.0,
        show_default=True,
        metavar="S",
        help="Sliding window of --contact-point line-fit, s.",
    ),
    option(
        "--joint-max-std",
        type=(POSITIVE("deg"), MM_POSITIVE),
        default=(2.0, "0.2mm"),
        show_default=True,
        metavar="DEG MM",
        help="--contact-point line-fit accepts a window when the standard deviations of its line angle and of its "
        "offset across the line are at most these (degrees, a length: mm unless a unit is given).",
    ),
    option(
        "--joint-max-residual",
        type=POSITIVE("noise standard deviations"),
        default=3.0,
        show_default=True,
        metavar="SIGMAS",
        help="... and the RMS residual of its fit is at most this many noise standard deviations.",
    ),
    option("--lowpass", type=POSITIVE("Hz"), metavar="HZ", help="Causal Butterworth low-pass cutoff in Hz (default: no filter)."),
    option(
        "--tare-duration",
        type=NON_NEGATIVE("s"),
        default=0.2,
        show_default=True,
        metavar="S",
        help="Take the first S seconds (fingertip untouched) as the sensor bias; 0 if the wrench is already tared.",
    ),
    option(
        "--tare-method",
        type=click.Choice(["robust", "median", "mean"]),
        default="robust",
        show_default=True,
        help="How the tare samples make the bias: robust (the mean of the samples that are not spikes), median, "
        "or mean (of all: a spike moves it).",
    ),
    option(
        "--bias",
        "bias_file",
        type=click.Path(dir_okay=False),
        metavar="FILE.toml",
        help="Subtract this sensor bias instead of taring ([bias] force = [N, N, N], moment = [N·m, N·m, N·m]; "
        "written by --save-bias or calibrate-payload).",
    ),
    option(
        "--hysteresis",
        type=NON_NEGATIVE("noise standard deviations"),
        default=3.0,
        show_default=True,
        metavar="SIGMAS",
        help="Contact ends below --contact-threshold minus this many standard deviations of the noise of |f| "
        "(from --force-noise, after --lowpass; at least half the threshold); 0: one threshold.",
    ),
    option(
        "--min-contact-duration",
        type=NON_NEGATIVE("s"),
        default=0.005,
        show_default=True,
        metavar="S",
        help="A contact is reported once |f| has stayed above the release threshold this long, each sample counting "
        "for its sampling interval (a shorter spike is no contact).",
    ),
    option(
        "--drift-time-constant",
        type=POSITIVE("s"),
        default=10.0,
        show_default=True,
        metavar="S",
        help="While untouched, follow the sensor's bias drift with a moving average of this time constant.",
    ),
    option(
        "--drift-tracking/--no-drift-tracking",
        default=True,
        show_default=True,
        help="Subtract the drift followed while untouched (--no-drift-tracking: report it only, the papers').",
    ),
    option("--contact-threshold", type=Force(0.0), default=0.05, show_default=True, metavar="FORCE", help="In contact while |f| is at least this (N unless kgf is given)."),
    option(
        "--latch-window",
        type=(Force(0.0), Force(0.0)),
        default=("0.2kgf", "0.5kgf"),
        show_default=True,
        metavar="LOW HIGH",
        help="Light-force window for latching the contact point (forces: N unless kgf is given).",
    ),
    option("--h-min", type=NON_NEGATIVE("N·mm"), default=0.5, show_default=True, metavar="N·mm", help="Smallest |h| reported as a line contact, N·mm."),
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
    option(
        "--sensor",
        type=click.Choice(["nano17", "nano25", "mini40"]),
        help="The sensor's noise preset (ATI Nano17, Nano25, Mini40 class; per axis, fz apart) for --force-noise and "
        "--moment-noise where they are not given. [default: nano17]",
    ),
    option(
        "--noise-from-tare",
        is_flag=True,
        help="Measure the noise model from the tare's samples (each axis's standard deviation) instead of "
        "--force-noise/--moment-noise, which stay the fallback; needs at least 30 tare samples "
        "(--tare-duration 1 at 50 Hz).",
    ),
    option(
        "--relatch-distance",
        type=MM_POSITIVE,
        metavar="LENGTH",
        help="Latch again when, at light force, the soft-finger contact point moves farther than this from the "
        "latched one (3mm, 0.3cm; a bare number is in mm). Default: only when contact is lost and regained, the papers'.",
    ),
    option(
        "--depth-compensation/--no-depth-compensation",
        default=None,
        help="Take the moment about the point inside the skin where friction acts, removing the spurious "
        "tangential moment of a tangential force. Its depth is learnt per contact from the data, the skin law "
        "(--skin-law) the prior; the depth, depth_std and depth_from_data columns report it. Default: on when "
        "the fingertip gives a skin (the murakami2006 preset, a file with skin_thickness), in latch mode. "
        "--no-depth-compensation: the papers' method.",
    ),
    option(
        "--fixed-depth",
        is_flag=True,
        help="Depth compensation at the skin law's depth as it is, not learnt from the data.",
    ),
    option(
        "--skin-law",
        type=(POSITIVE("N/m^P"), POSITIVE(""), MM_POSITIVE),
        default=None,
        metavar="K P MAX_DEPTH",
        help="Skin law of the depth compensation: normal force = K·depth^P (N, m), depth at most MAX_DEPTH (a length, mm unless a unit is given) "
        "(default: the fingertip's skin; else the murakami2006 skin, "
        f"{MURAKAMI2006_DEPTH.stiffness:g} {MURAKAMI2006_DEPTH.exponent:g} {MURAKAMI2006_DEPTH.max_depth * 1e3:g}mm).",
    ),
    option(
        "--line-evidence",
        type=click.Choice(["on", "off"]),
        default="on",
        show_default=True,
        help="on: tell a line from an area over a sliding window (state area while the window shows h spread over "
        "both tangent axes; line_evidence confirmed once the contact was excited about two tangent axes, by the load "
        "or --rocked, and h stayed on one, else unconfirmed; the direction from the window wherever h varied along "
        "one axis); off: the papers' per-sample line/point.",
    ),
    option("--evidence-window", type=POSITIVE("s"), default=2.0, show_default=True, metavar="S", help="Sliding window of the line evidence, s."),
    option(
        "--significance-window",
        type=NON_NEGATIVE("s"),
        default=0.015,
        show_default=True,
        metavar="S",
        help="|h| turns significant (line) when most samples of the last S seconds are above the line threshold, "
        "and not when most are below 2/3 of it (0, or a sample period longer than S: each sample alone, the papers').",
    ),
    option(
        "--area-ratio",
        type=(POSITIVE("(eigenvalue ratio)"), POSITIVE("(eigenvalue ratio)")),
        default=(0.2, 0.1),
        show_default=True,
        metavar="ENTER LEAVE",
        help="area when the smaller/larger eigenvalue ratio of h's window covariance (noise removed) reaches ENTER; "
        "a confirmed line again only below LEAVE.",
    ),
    option(
        "--area-share",
        type=Number("(share of the window)", 0.0, 1.0, min_open=True, max_open=True),
        default=0.35,
        show_default=True,
        metavar="SHARE",
        help="area while more than this share of the evidence window's samples show h spread over both tangent axes "
        "(a reading of the current window, revisited as it slides).",
    ),
    option(
        "--rocked",
        type=(Number("s"), Number("s")),
        multiple=True,
        metavar="START END",
        help="The object was rocked about two tangent axes from START to END (s, the log's time; repeat for more): "
        "a window wholly inside counts as excited about two axes, so h on one axis there confirms a line (for a "
        "skin on which the load cannot show it, manual §3.5).",
    ),
    option(
        "--excitation",
        type=(POSITIVE("(eigenvalue ratio)"), POSITIVE("N")),
        default=(0.5, 0.01),
        show_default=True,
        metavar="RATIO MIN_N",
        help="Excited about two tangent axes when the tangential load's window covariance has its smaller eigenvalue "
        "beyond the noise, at least RATIO times the larger and at least MIN_N² (N).",
    ),
    option(
        "--evidence-reset-distance",
        type=MM_POSITIVE,
        default="1mm",
        show_default=True,
        metavar="LENGTH",
        help="The line evidence starts afresh when the contact point moves farther than this (a bare number is in mm).",
    ),
    option(
        "--evidence-max-std",
        type=POSITIVE("deg"),
        default=10.0,
        show_default=True,
        metavar="DEG",
        help="A window's line direction is used only when its standard deviation is at most this, degrees.",
    ),
    _model_std_option("--evidence-model-std", 0.4, "a window's line direction (what no window shows)"),
    _model_std_option("--unconfirmed-model-std", 5.0,
                      "an unconfirmed line's direction (from one axis of excitation: its rolling bias)"),  # fmt: skip
]


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
        "linearly in t (a row without t is dropped). Dropped or filled rows are counted on standard error.",
    ),
    option("--skip-rows", type=click.IntRange(min=0), metavar="N", help="Lines before the header row (a preamble). [default: found]"),
]


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


def log_format_given(kwargs: dict) -> bool:
    """Whether any :func:`log_format_options` differs from its default."""
    return any(v not in (None, "fail", {}) for v in kwargs.values())


def print_log_notes(log) -> None:
    """How a foreign log was read (columns, units, skipped lines, missing cells), then its warnings."""
    for note in getattr(log, "notes", ()):
        click.echo(f"softtip: {note}", err=True)
    suspect = getattr(log, "time_suspect", None)
    if suspect is not None:  # t in ms read as s: a one-sample tare and windows of thousands of samples
        raise InputError(suspect.replace(". Give t in seconds:", ". Stopped: give --time-units (or t in seconds):"))
    for note in log.warnings:  # repeated stamps, an implausible time scale, a cut last line
        click.echo(f"softtip: warning: {note}", err=True)


def sensor_noise(sensor: str | None, force_noise: float, moment_noise_nmm: float) -> SensorNoise:
    """The noise model of ``--sensor`` and ``--force-noise`` (N) / ``--moment-noise`` (N·mm): an option given on
    the command line wins for its quantity, the preset (per axis) gives the rest."""
    from softtip.core.noise import SENSOR_CLASSES

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
    preset = SENSOR_CLASSES[{"nano17": "Nano17", "nano25": "Nano25", "mini40": "Mini40"}[sensor]]
    return SensorNoise(
        given.force_std if explicit["force_noise"] else preset.force_std,
        given.moment_std if explicit["moment_noise"] else preset.moment_std,
    )


def estimator_options(f):
    """The pipeline settings shared by ``estimate`` and ``stream``."""
    for decorator in reversed(_ESTIMATOR_OPTIONS):
        f = decorator(f)
    return f


def check_units(est, fingertip, config: EstimatorConfig, log, source: str | None = None) -> None:
    """Exit 2 when the wrench's units make the fingertip geometry or the sensor's noise impossible
    (:func:`softtip.core.lever.check_wrench_units`), naming the unit pairs that fit the data."""
    from softtip.core.lever import check_wrench_units

    check_wrench_units(
        est.wrench[~est.taring], fingertip, force_unit=getattr(log, "force_unit", "N"),
        moment_unit=getattr(log, "moment_unit", "N*m"), quiet=quiet_samples(est, log.wrench), noise=config.noise,
        source=source or log.source, min_force=max(0.1, config.contact_threshold),
    )  # fmt: skip


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


def check_outputs(inputs, outputs) -> None:
    """Exit 2 when an output is an input or another output of the run (:func:`softtip.io.atomic.check_distinct`)."""
    from softtip.io.atomic import check_distinct

    outputs = list(outputs)
    check_output_names(outputs)
    check_distinct(inputs, outputs)


def check_output_names(outputs) -> None:
    """Exit 2 naming the option when an output is given as an empty name or as an existing directory."""
    for label, path in outputs:
        if path is None:
            continue
        text = os.fspath(path)
        if text == "" or (isinstance(path, Path) and not path.name):
            text = "" if text == "." else text
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
    from tqdm import tqdm

    file = sys.stderr if file is None else file
    tty = file.isatty()
    if not tty:
        return _NoProgress()
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
    """The :class:`EstimatorConfig` of the shared estimator options (CLI units → SI)."""
    check_pair_increasing("--latch-window", opts["latch_window"], "N")
    try:
        comp, fixed = opts["depth_compensation"], opts["fixed_depth"]
        if comp is False and fixed:
            raise click.UsageError("--fixed-depth and --no-depth-compensation contradict each other")
        depth = None
        if opts["skin_law"] is not None:
            k, p, max_depth = opts["skin_law"]
            depth = DepthLaw(k, p, max_depth)
        depth_mode = "auto"
        if comp is False:
            depth_mode = "off"
        elif comp or fixed:
            depth_mode = "law" if fixed else "online"
            if depth is None and (tip is None or tip_depth_law(tip) is None):
                depth = MURAKAMI2006_DEPTH
        relatch = opts["relatch_distance"]
        return EstimatorConfig(
            contact_point=opts["contact_point"],
            contact_threshold=opts["contact_threshold"],
            latch_force_range=opts["latch_window"],
            noise=sensor_noise(opts.get("sensor"), opts["force_noise"], opts["moment_noise"]),
            h_min=opts["h_min"] * 1e-3,
            lowpass_hz=opts["lowpass"],
            sample_rate=sample_rate,
            tare_duration=opts["tare_duration"],
            tare_method=opts["tare_method"],
            bias=None if opts["bias_file"] is None else load_bias(opts["bias_file"]),
            contact_hysteresis=opts["hysteresis"],
            contact_min_duration=opts["min_contact_duration"],
            drift_time_constant=opts["drift_time_constant"],
            track_drift=opts["drift_tracking"],
            relatch_distance=relatch,
            depth=depth,
            depth_mode=depth_mode,
            joint_window=opts["joint_window"],
            joint_max_angle_std=math.radians(opts["joint_max_std"][0]),
            joint_max_offset_std=opts["joint_max_std"][1],
            joint_max_residual=opts["joint_max_residual"],
            line_evidence=opts["line_evidence"] == "on",
            evidence_window=opts["evidence_window"],
            area_ratio=opts["area_ratio"],
            area_share=opts["area_share"],
            rocked=tuple(opts["rocked"]),
            excitation_ratio=opts["excitation"][0],
            excitation_min=opts["excitation"][1],
            evidence_max_angle_std=math.radians(opts["evidence_max_std"]),
            evidence_model_std=math.radians(opts["evidence_model_std"]),
            unconfirmed_model_std=math.radians(opts["unconfirmed_model_std"]),
            evidence_reset_distance=opts["evidence_reset_distance"],
            significance_window=opts["significance_window"],
            noise_from_tare=opts["noise_from_tare"],
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
