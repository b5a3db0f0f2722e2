"""``softtip estimate``: a log (CSV, Parquet, bag) through the batch estimator to CSV/Parquet, a figure, a bag, a Rerun view."""

from __future__ import annotations

import math
import os
import sys
import warnings
from pathlib import Path

import click
import numpy as np

from softtip.cli.bag_options import bag_output_options, output_frame_id
from softtip.cli.options import (
    FRAMES_HELP,
    bag_warnings,
    check_figure_path,
    check_outputs,
    check_units,
    estimator_options,
    full_scale_option,
    full_scale_range,
    is_bag,
    log_format_given,
    log_format_kwargs,
    log_format_names,
    log_format_options,
    make_config,
    optional_extra,
    parquet_metadata,
    print_log_notes,
    progress_bar,
    tare_covers_log,
    tare_warnings,
)  # fmt: skip
from softtip.cli.types import check_lowpass, option
from softtip.core.fingertip import load_fingertip
from softtip.core.fullscale import COARSE_MARGIN, check_full_scale, full_scale_error
from softtip.core.units import UNIT_SYSTEMS, wrench_to_si
from softtip.errors import InputError
from softtip.estimator import STATES
from softtip.estimator import estimate as run_estimate
from softtip.estimator.columns import TOPICS
from softtip.estimator.columns import help_text as column_help
from softtip.estimator.results import EstimatorWarning
from softtip.estimator.tare import bias_to_toml
from softtip.ros import MARKER_TOPIC

__all__ = ["estimate"]

#: ``--jobs`` when not given, for a log processed in pieces: the cores this process may use, at
#: most this many (more were not measured).
DEFAULT_JOBS_MAX = 2

@click.command(
    "estimate",
    help="""Estimate contact point, normal, spin torque, contact state and edge direction
from a force/torque log.

INPUT is a CSV file with a header row and columns t, fx, fy, fz, mx, my, mz (t in s,
non-decreasing: repeated stamps are counted and reported; extra columns are kept and copied
to the output), or a Parquet or Arrow IPC (Feather v2) file with those columns (name
ending in .parquet, .arrow or .feather; its softtip.units metadata gives the units). '-' reads CSV from standard input. With
--example, softtip's shipped example grasp is used instead. Logs as ATI's software,
rostopic echo -p, ros2 topic echo --csv, PlotJuggler and bag converters write them are read
as they are (units from the header; comma, tab or semicolon, a decimal comma; .gz, .bz2, .xz,
.zst; a preamble), and standard error says which column was taken for what in which unit;
--columns, --force-units, --moment-units, --time-units, --missing and --skip-rows for the
rest (docs/guide/input-formats.md). Absolute stamps count from the first (stamp_ns column). A run
whose units make the fingertip geometry or the sensor's noise impossible stops, naming the
unit pair that fits.

The output CSV (standard output unless -o; Parquet when -o ends in .parquet, Arrow IPC
(Feather v2) when it ends in .arrow or .feather, with the units and the fingertip in its
key-value metadata) has these columns, in order, then the
input's extra columns; units are SI (N and N·m, or kgf and kgf·mm with --output-units
kgf-mm), angles in degrees; a number that is not there is nan, a text cell empty, and a flag
is 0 or 1 (booleans in Parquet and Arrow). Every estimate (r, n, sigma, h, |h|, the depth, the
ratios) is nan when state is none; d and the angle only for line contacts, where |h| stands out
of the noise. """
    + column_help()
    + """

INPUT may also be a ROS bag (rosbag2 directory with sqlite3 or MCAP storage, a .mcap or
.db3 file, or a ROS 1 .bag; needs the rosbags package): the samples are the
geometry_msgs/msg/WrenchStamped messages of --topic, timed by header.stamp (t counts
from the first message; the stamps are copied to a stamp_ns column). --to-bag
writes the estimates as a bag --ros-distro plays (default humble: rosbag2 metadata version
5, sqlite3; a name ending in .bag: ROS 1) with standard messages on """
    + ", ".join(t.name for t in TOPICS if t.in_bag)
    + f""" and RViz
markers on {MARKER_TOPIC}, plus the raw wrench, all with --frame-id; with --to-bag and
no -o no CSV is written. With --payload, --gravity-frame takes the sensor's orientation
from the bag's /tf.

"""
    + FRAMES_HELP
)
@click.argument("input_path", metavar="INPUT", required=False, type=click.Path(allow_dash=True))
@option("--example", is_flag=True, help="Use the shipped example grasp (a 45° line contact, murakami2006 tip) as INPUT.")
@option("-o", "--output", type=click.Path(dir_okay=False, writable=True, allow_dash=True), help="Output CSV, or Parquet for a name ending in .parquet, Arrow IPC (Feather v2) for .arrow or .feather (default, or '-': CSV on standard output).")
@option(
    "--units",
    type=click.Choice(UNIT_SYSTEMS),
    default=None,
    help="Units of the input wrench: si (N, N·m) or kgf-mm (kgf, kgf·mm, the papers').  [default: si, or a Parquet INPUT's own]",
)
@option(
    "--output-units",
    type=click.Choice(UNIT_SYSTEMS),
    default="si",
    show_default=True,
    help="Units of force and moment columns in the output; lengths stay in m, angles in degrees.",
)
@option("--plot", "plot_path", type=click.Path(dir_okay=False), help="Also draw the papers' four panels (force, moment, |h|, direction) to this PNG/PDF/SVG.")
@option("--plot-units", type=click.Choice(UNIT_SYSTEMS), default="si", show_default=True, help="Units of the plot's force and moment axes.")
@option("--topic", metavar="TOPIC", help="Bag input: the geometry_msgs/msg/WrenchStamped topic (default: the bag's only one).")
@option("--allow-partial", is_flag=True, help="Bag input: use a damaged bag's readable messages (with a warning) instead of stopping.")
@bag_output_options()
@option("--gravity-frame", metavar="FRAME", help="With --payload and a bag INPUT: the sensor's orientation from the bag's /tf and /tf_static, FRAME (z up, e.g. world) to the wrench's frame_id, at each stamp (instead of qw, qx, qy, qz columns).")
@option("--rerun", "rerun_spawn", is_flag=True, help="Show the fingertip, force, contact point, normal and edge in a Rerun viewer (needs the rerun-sdk package).")
@option("--rerun-save", type=click.Path(dir_okay=False), metavar="FILE.rrd", help="Save the Rerun 3-D view and time series to FILE.rrd (open with `rerun FILE.rrd`).")
@option("--payload", type=click.Path(dir_okay=False), metavar="FILE.toml", help="Remove the fingertip's weight ([payload] mass kg, com m; see calibrate-payload) before taring, using INPUT's qw, qx, qy, qz columns (sensor frame in a z-up world frame).")
@option("-q", "--quiet", is_flag=True, help="Nothing but warnings and errors on standard error (no tare line, no summary).")
@option("--save-bias", type=click.Path(dir_okay=False), metavar="FILE.toml", help="Write the bias used (the tare's) to FILE.toml, for --bias of a later run.")
@option(
    "--chunk-rows", type=click.IntRange(min=1), metavar="N",
    help="Process INPUT in pieces of at least N rows (and at least 1/256 of the log, up to 8192), in bounded memory, with the result of the one-shot run (a piece ends "
    "only out of contact: a contact longer than N rows makes its piece as long). On standard output each piece is "
    "written as it is done: a failure after the first leaves a cut table there (exit 2). [default: pieces of 131072 rows for a CSV "
    "file over 24 MB or a Parquet file over 262144 rows; only for a CSV or Parquet file without --plot, --to-bag, --rerun, "
    "--rerun-save, --payload]",
)  # fmt: skip
@option(
    "--jobs", type=click.IntRange(1, 64), default=None, metavar="N",
    help="Threads (cores) for a log processed in pieces (see --chunk-rows): N estimate pieces at the same time and "
    "N format CSV, while one more reads the log and the main one writes; 1: all on one thread. The output is the same, "
    "bit for bit, whatever N; up to N+3 pieces, and the output of N more, are held in memory. [default: the cores this process may use, at most "
    f"{DEFAULT_JOBS_MAX}]",
)  # fmt: skip
@full_scale_option
@log_format_options
@estimator_options
def estimate(**kwargs) -> None:
    from softtip.io.atomic import Outputs

    # one transaction for every output of the run: all appear, or none (an error, a signal)
    with Outputs() as outputs:
        _estimate(outputs, **kwargs)


def _estimate(
    outputs,
    input_path,
    example,
    output,
    units,
    output_units,
    plot_path,
    plot_units,
    topic,
    to_bag,
    rerun_spawn,
    rerun_save,
    tip,
    payload=None,
    save_bias=None,
    quiet=False,
    allow_partial=False,
    ros_distro=None,
    frame_id=None,
    gravity_frame=None,
    chunk_rows=None,
    full_scale=None,
    jobs=None,
    **estimator_opts,
):
    from softtip.io.examples import EXAMPLE_ANGLE_DEG, EXAMPLE_PATH

    if output == "-":  # standard output, as without -o
        output = None

    sensor_range = full_scale_range(full_scale, estimator_opts.get("sensor"))  # default: the --sensor's, else a Nano17's
    from softtip.io.tables import Log, read_log

    formats = log_format_kwargs(estimator_opts)
    if example == (input_path is not None):
        raise click.UsageError("give either INPUT or --example")
    if example and units not in (None, "si"):
        raise click.UsageError("--units applies to INPUT; the example grasp is in SI")
    if plot_path is not None:
        check_figure_path(plot_path)
    check_outputs(
        [("INPUT", None if example else input_path), ("--payload", payload), ("--tip", tip if os.path.isfile(tip) else None),
         ("--bias", estimator_opts.get("bias_file"))],
        [("-o", output), ("--plot", plot_path), ("--to-bag", to_bag), ("--rerun-save", rerun_save), ("--save-bias", save_bias)],
    )
    # every output file staged before any work: a missing folder or no permission stops the run at once
    for path in (output, plot_path, rerun_save, save_bias):
        if path is not None:
            outputs.file(path)
    staged_bag = None
    if to_bag is not None:
        from softtip.ros.bagout import bag_format

        bag_format(to_bag, ros_distro)  # a name that does not fit the distribution: stop before the work
        staged_bag = outputs.path(to_bag)
    if rerun_spawn:  # at once: without a display the viewer would fail only after the whole run
        from softtip.viz.rerun import check_viewer  # rerun itself is imported later

        check_viewer()
    fingertip = load_fingertip(tip)
    config = make_config(estimator_opts, tip=fingertip)
    if (os.path.isfile(tip) and getattr(fingertip, "skin_thickness", None) is None and not quiet
            and estimator_opts.get("depth_compensation") == "auto" and estimator_opts.get("contact_point") == "latch"):  # fmt: skip
        click.echo(
            f"softtip: {tip}: no skin_thickness, so the depth compensation is off (add skin_thickness = <m> under "
            "[fingertip], e.g. from calibrate --skin-thickness, to turn it on)",
            err=True,
        )

    bag_log = None
    if example:
        log = read_log(EXAMPLE_PATH, units="si")
    elif input_path == "-":
        log = read_log(getattr(sys.stdin, "buffer", sys.stdin), units=units, **formats)  # bytes: compressed input too
    elif is_bag(input_path):
        if log_format_given(formats):
            raise click.UsageError(f"{log_format_names()} apply to CSV input; a bag's WrenchStamped messages are in "
                                   "N, N·m and ns")  # fmt: skip
        bag = optional_extra("softtip.io.bag", "ros")
        bag_log = bag.read_bag(input_path, topic, allow_partial=allow_partial)
        bag_warnings(input_path, bag_log)
        # t counts from the first message; the absolute stamps go along as an extra column
        extra = {"stamp_ns": np.asarray(bag_log.stamps_ns, dtype=np.int64)}
        units = units or "si"
        log = Log(t=bag_log.t, wrench=wrench_to_si(bag_log.wrench, units), extra=extra, source=bag_log.source, units=units)
        frames = ", ".join(repr(f) for f in bag_log.frame_ids)
        click.echo(
            f"softtip: {input_path}: {len(log.t)} samples from {bag_log.topic}, frame_id {frames}, "
            f"t = 0 at stamp {bag_log.stamps_ns[0]} ns",
            err=True,
        )
        if bag_log.record_time_used:
            click.echo(f"softtip: {bag_log.record_time_used} message(s) had a zero header.stamp; their recording time was used", err=True)
    else:
        if os.path.isdir(input_path):
            raise InputError(f"{input_path}: is a directory but not a ROS bag (no metadata.yaml); expected a CSV log or a bag")
        others = {"--plot": plot_path, "--to-bag": to_bag, "--rerun": rerun_spawn, "--rerun-save": rerun_save, "--payload": payload}
        if chunk_rows is not None and any(others.values()):
            given = ", ".join(k for k, v in others.items() if v)
            raise click.UsageError(f"--chunk-rows: not with {given}; expected a run that writes only the table")
        if topic is None and not allow_partial and not any(others.values()) and not log_format_given(formats):
            rows = chunk_rows or _auto_chunk_rows(input_path)
            # standard output (or -o naming it, a pipe): each piece is written as it is done, so
            # memory stays bounded; what is written cannot be taken back (a failure after it:
            # a message, exit 2, a cut table)
            streamed = output is None or _is_own_stdout(output)
            if rows and _estimate_in_pieces(
                input_path, units, rows, fingertip, config, estimator_opts, output=None if streamed else output,
                output_units=output_units, tip=tip, quiet=quiet, save_bias=save_bias, outputs=outputs,
                sensor_range=sensor_range, jobs=jobs, named=output,
            ):  # fmt: skip
                return
        size = os.path.getsize(input_path) if os.path.isfile(input_path) else 0
        with progress_bar(size, "reading", unit="B") as bar:
            log = read_log(input_path, units=units, progress=bar.update, **formats)
    # far beyond the sensor's range: refused before any estimate (just beyond it: after the units check)
    check_full_scale(log.t, log.wrench, sensor_range, log.source, units=log.units, margin=COARSE_MARGIN)
    print_log_notes(log, quiet)  # how a foreign file was read; repeated stamps, an implausible time scale, a cut last line
    if topic is not None and bag_log is None:
        raise click.UsageError("--topic applies to bag input only")
    if allow_partial and bag_log is None:
        raise click.UsageError("--allow-partial applies to bag input only")
    if to_bag is None and (ros_distro is not None or frame_id is not None):
        raise click.UsageError("--ros-distro and --frame-id apply to --to-bag")
    if gravity_frame is not None and (payload is None or bag_log is None):
        raise click.UsageError("--gravity-frame needs --payload and a bag INPUT (with /tf)")
    if payload is not None:  # gravity compensation first: the tare then removes only the sensor bias
        from softtip.core.gravity import compensate_payload, load_payload
        from softtip.io.payload import compensate_log

        if gravity_frame is None:
            log = compensate_log(log, payload)
        else:  # the orientation from the bag's /tf
            from dataclasses import replace

            from softtip.fusion.tf import gravity_orientations

            q = gravity_orientations(input_path, gravity_frame, bag_log.frame_ids, bag_log.stamps_ns, frame_id)
            log = replace(log, wrench=compensate_payload(log.wrench, q, load_payload(payload)))
    check_lowpass(estimator_opts["lowpass_hz"], log.t)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", EstimatorWarning)  # printed below, from est.warnings
            est = run_estimate(log.t, log.wrench, fingertip, config)
    except ValueError as exc:  # e.g. a low-pass cutoff above Nyquist for this log's rate
        raise click.UsageError(str(exc)) from None
    check_units(est, fingertip, config, log)
    check_full_scale(log.t, log.wrench, sensor_range, log.source, units=log.units)

    carried = _carried(None if example or bag_log is not None else input_path, output, log)
    notes: list[str] = []
    est_columns = est.columns(units=output_units)
    est_names = list(est_columns)
    columns = _output_columns(est_columns, log.extra, carried, notes)
    for note in notes:
        click.echo(f"softtip: warning: {note}", err=True)

    source = "example grasp" if example else Path(log.source).name
    _write_estimate_outputs(
        est, columns, log, bag_log, config, fingertip,
        output=output, plot_path=plot_path, plot_units=plot_units, title=f"softtip: {source}",
        truth_angle=EXAMPLE_ANGLE_DEG if example else None,
        to_bag=to_bag, rerun_spawn=rerun_spawn, rerun_save=rerun_save, ros_distro=ros_distro, frame_id=frame_id,
        metadata=parquet_metadata(fingertip, tip, output_units, log), outputs=outputs, staged_bag=staged_bag,
    )  # fmt: skip
    _carry(input_path, output, outputs, est_names, list(log.extra), carried)

    from softtip.estimator.summary import summarise_contacts

    _report_run(
        _RunTotals.of(est, summarise_contacts(est) if not quiet else []),
        input_path=input_path, output=output, plot_path=plot_path, to_bag=to_bag, rerun_save=rerun_save,
        save_bias=save_bias, quiet=quiet, outputs=outputs,
    )  # fmt: skip


class _RunTotals:
    """What ``softtip estimate`` says at the end of a run, summed over the pieces of a log."""

    def __init__(self) -> None:
        self.n = 0
        self.counts = dict.fromkeys(STATES, 0)
        self.confirmed = 0
        self.n_pulling = 0
        self.n_contacts = 0
        self.contacts: list = []
        self.warnings: list[str] = []
        self.bias = np.full(6, np.nan)
        self.tare = None
        self.taring = 0  # samples in the tare window
        self.t_first = self.t_last = math.nan  # s, as read
        self.step = math.nan  # s, the first piece's median step of t

    @classmethod
    def of(cls, est, contacts: list) -> _RunTotals:
        totals = cls()
        totals.add(est, contacts)
        return totals

    def add(self, est, contacts: list) -> None:
        """Add a piece (its contacts' summaries numbered within the piece)."""
        import dataclasses

        if self.tare is None:
            self.tare, self.bias = est.tare, est.bias
        if len(est):
            self.t_first = est.t[0] if not self.n else self.t_first
            self.t_last = est.t[-1]
            if self.step != self.step and len(est) > 1:
                self.step = float(np.median(np.diff(est.t[: 1 << 16])))
        self.n += len(est)
        self.taring += int(np.count_nonzero(est.taring))
        for code, name in enumerate(STATES):
            self.counts[name] += int(np.count_nonzero(est.state == code))
        self.confirmed += int(np.count_nonzero(est.line_evidence == 2))
        self.n_pulling += est.n_pulling
        first = self.n_contacts
        self.contacts += [dataclasses.replace(c, index=first + c.index) for c in contacts]
        self.n_contacts = max(self.n_contacts, est.n_contacts)
        self.warnings += [w for w in est.warnings if w not in self.warnings]


def _coarse_t_note(totals: _RunTotals, output, to_bag) -> str | None:
    """A CSV output's ``t`` is written to 10 significant digits: a log whose ``t`` counts from a
    clock's start long ago (a monotonic clock after days) keeps less than its sample step there."""
    from softtip.io.formats import table_format

    if to_bag is not None or (output is not None and table_format(output) != "csv"):
        return None
    largest = max(abs(totals.t_first), abs(totals.t_last))
    if not (largest > 0 and totals.step > 0):
        return None
    resolution = 10.0 ** (math.floor(math.log10(largest)) - 9)  # a unit of the 10th significant digit
    if resolution <= totals.step / 10:
        return None
    where = output if output is not None else "standard output"
    return (
        f"{where}: t reaches {largest:.4g} s, where the CSV's 10 significant digits resolve {resolution:g} s, more than "
        f"a tenth of the log's {totals.step:.3g} s step: its t cells are rounded off the samples' times (estimates are "
        "not); write Parquet or Arrow (-o OUT.parquet, exact), or count t from the log's start"
    )


def _report_run(
    totals: _RunTotals, *, input_path, output, plot_path, to_bag, rerun_save, save_bias, quiet, outputs
) -> None:
    """The end of ``softtip estimate``: ``--save-bias``, every output put in place (``outputs``
    committed), then tare and warnings and the summary."""
    if save_bias is not None:
        if any(p is not None and Path(p).resolve() == Path(save_bias).resolve() for p in (input_path, output, plot_path)):
            raise InputError(f"--save-bias {save_bias}: is also an input or output of this run")
        if not np.all(np.isfinite(totals.bias)):
            raise InputError(f"--save-bias {save_bias}: no bias: the whole log lies within the tare")
        from softtip.io.atomic import cannot_write

        try:
            with outputs.get(save_bias).open() as fh:
                fh.write(bias_to_toml(totals.bias, f"softtip sensor bias ({totals.tare.summary()})"))
        except OSError as exc:
            raise cannot_write(save_bias, exc) from None
    outputs.commit()
    # in the one-shot run's order: a drift alarm (of any piece) after the contact warnings
    totals.warnings.sort(key=lambda w: w.startswith("the sensor bias drifted"))
    tare_warnings(totals, quiet)
    if save_bias is not None:
        click.echo(f"softtip: bias -> {save_bias}", err=True)
    coarse = _coarse_t_note(totals, output, to_bag)
    if coarse:
        click.echo(f"softtip: warning: {coarse}", err=True)
    if totals.n_pulling:
        click.echo(
            f"softtip: warning: {totals.n_pulling} sample(s) in contact by force had no contact point where the force "
            "pushes into the fingertip; reported as none",
            err=True,
        )
    if quiet:
        return
    # the summary goes to standard error whatever the output: per contact, since samples
    # pooled over several contacts (a -45° grasp, then a +45° one) have no common direction
    from softtip.estimator.summary import format_summary

    targets = [p for p in (output, to_bag, rerun_save) if p is not None] or ["standard output"]
    # "confirmed" is a term of art: the summary says what it needs, for a reader without --help
    confirmed = (
        f" ({totals.confirmed} confirmed by a load turned about two axes)" if totals.confirmed
        else " (none confirmed: the load never turned about two axes while h stayed on one)"
    )  # fmt: skip
    summary = ", ".join(f"{v} {k}" + (confirmed if k == "line" and v else "") for k, v in totals.counts.items())
    click.echo(
        f"softtip: {totals.n} samples ({summary}; {totals.n_contacts} contact(s)) -> {', '.join(map(str, targets))}",
        err=True,
    )
    for line in format_summary(totals.contacts):
        click.echo(f"softtip: {line}", err=True)


#: ``softtip estimate`` processes a log in pieces by itself from these sizes on (~262144 rows):
#: the same output, in less memory and, measured on a 1e6-row log, 2.3 s less system CPU
#: time (the one-shot run's page faults on 1.3 GB of fresh arrays).
AUTO_CHUNK_CSV_BYTES = 24_000_000
#: ``--chunk-rows`` makes pieces of at least 1/MAX_PIECES of the log (a smaller N is taken as
#: that): the result is the same whatever the piece size, the time is not (a fixed cost per piece).
MAX_PIECES = 256
MAX_FLOOR_ROWS = 8192


def _row_estimate(path: str) -> int:
    """The rows of a log, or an upper estimate (a CSV row takes at least 14 bytes: 7 one-digit cells)."""
    from softtip.io.tables import columnar_rows

    try:
        rows = columnar_rows(path)
        return rows if rows is not None else os.path.getsize(path) // 14
    except Exception:  # noqa: BLE001 - unreadable: the reader says why
        return 0
AUTO_CHUNK_PARQUET_ROWS = 262_144


def _auto_chunk_rows(path: str) -> int | None:
    """Rows per piece for a log this large (:data:`AUTO_CHUNK_CSV_BYTES`, :data:`AUTO_CHUNK_PARQUET_ROWS`), else None."""
    from softtip.apps.chunked import DEFAULT_PIECE_ROWS
    from softtip.io.tables import columnar_rows

    try:
        rows = columnar_rows(path)
        large = rows > AUTO_CHUNK_PARQUET_ROWS if rows is not None else os.path.getsize(path) > AUTO_CHUNK_CSV_BYTES
    except Exception:  # noqa: BLE001 - unreadable in any way: the one-shot reader words it
        return None
    return DEFAULT_PIECE_ROWS if large else None


def _default_jobs() -> int:
    """``--jobs`` when not given: the cores this process may run on, at most :data:`DEFAULT_JOBS_MAX`."""
    from softtip.core._cores import usable_cores

    return max(1, min(usable_cores(), DEFAULT_JOBS_MAX))


def _is_own_stdout(path) -> bool:
    """Whether ``path`` (``/dev/stdout``, ``/dev/fd/1``) is this process's standard output, and not a regular file."""
    import stat

    try:
        st, out = os.stat(path), os.fstat(sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):
        return False
    return not stat.S_ISREG(st.st_mode) and os.path.samestat(st, out)


def _estimate_in_pieces(
    input_path, units, rows, fingertip, config, estimator_opts, *, output, output_units, tip, quiet, save_bias, outputs,
    sensor_range=None, jobs=None, named=None,
) -> bool:
    """``softtip estimate`` piece by piece (:mod:`softtip.apps.chunked`) into ``output`` (a path),
    or, for ``output`` None, onto standard output as each piece is done (``named``: the ``-o``
    that named it, whose staged file is dropped); ``False`` when the log holds something only
    the one-shot reader takes or words (nothing written then)."""
    from softtip.apps.chunked import estimate_pieces
    from softtip.core.lever import LEVER_MARGIN, LeverVote, fingertip_reach, lever_distances
    from softtip.estimator.summary import summarise_contacts
    from softtip.io.atomic import cannot_write, write_stdout
    from softtip.io.formats import table_format
    from softtip.io.tables import NotStreamable, TableWriter, columnar_rows, iter_log

    # pieces of a few rows give the same result, but each piece costs a fixed overhead
    # (--chunk-rows 1 took minutes for 5e4 rows): at most about MAX_PIECES pieces
    # (and memory stays bounded: that floor is at most MAX_FLOOR_ROWS)
    rows = max(rows, min(-(-_row_estimate(input_path) // MAX_PIECES), MAX_FLOOR_ROWS))
    jobs = jobs or _default_jobs()
    fmt = table_format(output) if output is not None else "csv"
    sent = [0]  # rows written to standard output: past the first, a failure cannot be taken back
    began = [False]  # whether writing onto standard output began (the header may be there with no row)
    beyond: list[InputError] = []  # the first sample just beyond the sensor's range
    carried = _carried(input_path, output)
    names: dict[str, list[str]] = {}  # the first piece's output and extra column names
    notes: list[str] = []
    totals = _RunTotals()
    vote = LeverVote(LEVER_MARGIN * fingertip_reach(fingertip))  # the units check, over the whole log
    pair_votes: dict[tuple[str, str], LeverVote] = {}  # the same vote for each unit pair, to name those that fit
    first_ratio: list = []  # the tare's noise over the sensor's, from the first piece
    total = columnar_rows(input_path)
    with progress_bar(total, "estimating") as bar:  # rows estimated and written
        blocks = iter_log(input_path, units, rows=min(rows, 1 << 16))

        first_wrench = []

        def checked():
            first = True
            n = 0
            for block in blocks:
                if first:
                    check_lowpass(estimator_opts["lowpass_hz"], block[0])
                    first_wrench.append(block[1])
                    first = False
                check_full_scale(block[0], block[1], sensor_range, input_path, first_sample=n, units=units or "si",
                                 margin=COARSE_MARGIN)  # fmt: skip
                if not beyond:  # just beyond the range: said after the units vote, as the one-shot run does
                    err = full_scale_error(block[0], block[1], sensor_range, input_path, first_sample=n, units=units or "si")
                    if err is not None:
                        beyond.append(err)
                n += len(block[0])
                yield block

        def noise_fits(est) -> None:
            """The units check's noise half on the first piece (the lever's is voted over all); a
            doubt goes to the one-shot run, which words it with both halves."""
            from softtip.cli.options import quiet_samples
            from softtip.core.lever import check_wrench_units
            from softtip.core.units import UNIT_SYSTEM_UNITS

            force_unit, moment_unit = UNIT_SYSTEM_UNITS[blocks.units or "si"]
            try:
                check_wrench_units(np.zeros((0, 6)), fingertip, force_unit=force_unit, moment_unit=moment_unit,
                                   quiet=quiet_samples(est, first_wrench[0]), noise=config.noise)  # fmt: skip
            except InputError:
                raise NotStreamable("wrong units: the one-shot run says so") from None

        def written(n: int) -> None:  # rows in the output (CSV blocks go out behind the pieces)
            sent[0] += n if output is None else 0
            bar.update(n)

        def run(out) -> None:
            with TableWriter(out, format=fmt, metadata=parquet_metadata(fingertip, tip, output_units, blocks),
                             threads=jobs) as writer:  # fmt: skip

                def after(est, extra) -> tuple:
                    """A piece's units-check distances, contact summaries and output rows (its
                    columns' names, the notes on them, what the writer makes of them before it
                    writes: the checked columns, and Parquet's or Arrow's blocks; CSV is formatted
                    on the writer's threads): on the thread that estimated it (with --jobs, in
                    parallel, not in the caller's thread, which writes the output)."""
                    distances = lever_distances(est.wrench[~est.taring], max(0.1, config.contact_threshold))
                    est_columns = est.columns(units=output_units)
                    est_names, piece_notes = list(est_columns), []
                    prepared = writer.prepare(_output_columns(est_columns, extra, carried, piece_notes))
                    return distances, summarise_contacts(est) if not quiet else [], est_names, piece_notes, prepared

                pieces = estimate_pieces(checked(), fingertip, config, rows, jobs=jobs, after=after)
                try:
                    for k, (est, extra, (distances, contacts, est_names, piece_notes, prepared)) in enumerate(pieces):
                        if k == 0:
                            noise_fits(est)
                            _start_pair_votes(pair_votes, first_ratio, vote.limit, blocks.units, est, first_wrench[0], config)
                            names["est"], names["extra"] = est_names, list(extra)
                            notes.extend(piece_notes)  # the same for every piece: the first's said once
                        vote.add(distances)
                        for pair_vote in pair_votes.values():
                            pair_vote.add(distances)
                        began[0] = output is None  # from here standard output may hold a part of the table
                        writer.write(prepared, progress=written)
                        totals.add(est, contacts)
                finally:
                    pieces.close()  # with --jobs, no piece is read or started from now (an error, a signal)
            if totals.n and totals.taring == totals.n:  # nothing estimated, as check_units decides
                raise tare_covers_log(input_path, totals.n, totals.t_first, totals.t_last, config.tare_duration)
            if vote.n >= 5 and vote.median_above():
                raise NotStreamable("wrong units: the one-shot run says so")  # as check_units decides
            if beyond:
                raise beyond[0]

        try:
            try:
                if output is None:
                    write_stdout(run)
                    if named is not None:
                        outputs.get(named).discard()  # -o /dev/stdout: written into already
                else:
                    with outputs.get(output).open() as fh:  # the staged file: put in place with the others
                        run(fh)
                    if names:
                        _carry(input_path, output, outputs, names["est"], names["extra"], carried)
            except OSError as exc:
                raise cannot_write(output, exc) from None
        except NotStreamable as exc:  # nothing written: the one-shot run takes it, or says what is wrong
            found = blocks.locate_error()  # an error in the log, found without reading it at once
            if found is not None:
                _said_cut(sent[0])
                raise found from None
            if sent[0]:  # on standard output already: the one-shot run cannot start over
                _said_cut(sent[0])
                if "units" in str(exc):
                    raise _units_error(input_path, vote, pair_votes, first_ratio[0], blocks.units, fingertip,
                                       max(0.1, config.contact_threshold)) from None  # fmt: skip
                raise InputError(f"{input_path}: cannot be read in pieces past row {sent[0]} ({exc}); give -o FILE") from None
            return False
        except InputError as exc:
            if not str(exc).startswith("standard output"):  # a closed pipe, a full device: said already
                _said_cut(sent[0])
            raise
        except ValueError as exc:  # e.g. a low-pass cutoff above Nyquist for this log's rate
            if isinstance(exc, InputError):
                raise
            raise click.UsageError(str(exc)) from None
        except MemoryError:
            _said_cut(sent[0], began[0])  # the command's message follows
            raise
    for note in [*notes, *blocks.warnings()]:
        click.echo(f"softtip: warning: {note}", err=True)
    _report_run(
        totals, input_path=input_path, output=output, plot_path=None, to_bag=None, rerun_save=None,
        save_bias=save_bias, quiet=quiet, outputs=outputs,
    )  # fmt: skip
    return True


def _start_pair_votes(pair_votes, first_ratio, limit, units, est, first_wrench, config) -> None:
    """The units vote of each unit pair (its lever limit in the units read), and the tare's noise
    ratio, at the first piece of a run in pieces: what :func:`_units_error` names the fix from."""
    from softtip.cli.options import quiet_samples
    from softtip.core.lever import LeverVote, noise_ratio, pair_scales
    from softtip.core.units import UNIT_SYSTEM_UNITS

    force_unit, moment_unit = UNIT_SYSTEM_UNITS[units or "si"]
    for pair, (kf, km) in pair_scales(force_unit, moment_unit).items():
        pair_votes[pair] = LeverVote(limit * kf / km)  # a pair fits when median * km / kf <= limit
    quiet = quiet_samples(est, first_wrench)
    first_ratio.append(noise_ratio(quiet, config.noise) if config.noise is not None else None)


def _units_error(input_path, vote, pair_votes, ratio, units, fingertip, min_force: float) -> InputError:
    """The units check's message for a run whose pieces went onto standard output already (the
    one-shot run cannot start over to word it): the unit pairs that fit and their options, decided
    as the one-shot check decides (the median lever of every piece, the first piece's noise)."""
    from softtip.core.lever import LEVER_MARGIN, fingertip_reach, lever_pairs_text
    from softtip.core.units import UNIT_SYSTEM_UNITS, find_unit

    force_unit, moment_unit = UNIT_SYSTEM_UNITS[units or "si"]
    fits = lever_pairs_text({pair: not (v.n >= 5 and v.median_above()) for pair, v in pair_votes.items()}, ratio,
                            force_unit, moment_unit)  # fmt: skip
    read_in = f"{find_unit(force_unit, 'force').label} and {find_unit(moment_unit, 'moment').label}"
    return InputError(
        f"{input_path}: the forces act more than {LEVER_MARGIN:g} times the fingertip's reach "
        f"({fingertip_reach(fingertip) * 1e3:.3g} mm) from the sensor origin (median of the moment-to-force ratio over "
        f"{vote.n} samples with |f| ≥ {min_force:g} N, read in {read_in}): "
        f"{fits}; or is the fingertip (--tip) the wrong one? "
        "Expected moments in N·m about the sensor origin"
    )


def _said_cut(rows: int, began: bool = False) -> None:
    """Before the error of a run that wrote ``rows`` rows onto standard output (``began``: or
    started writing there): what is there."""
    if rows or began:
        click.echo(
            f"softtip: warning: standard output: {rows} rows were written before the error below and cannot be taken "
            "back; the table there is incomplete or wrong (use it only after exit status 0)",
            err=True,
        )


def _column(values) -> np.ndarray:
    """An extra column as an array: text (a list of the CSV's cells) as str objects, not a unicode array
    as wide as its longest cell in every row (one long note made it gigabytes)."""
    from softtip.io.tables import text_column

    if isinstance(values, list) and all(type(x) is str for x in values):
        return text_column(values)
    return np.asarray(values)


def _output_columns(est_columns: dict, extra, carried=(), notes: list[str] | None = None) -> dict:
    """The output table: the estimates' columns (``Estimates.columns`` in the output's units; added
    to in place), then the input's extra columns (renamed ``input_NAME`` when named like an output
    column, said in ``notes``; a ``carried`` column as a placeholder for
    :func:`softtip.io.carry.carry_columns`)."""
    from softtip.io.carry import extra_names, placeholder

    columns = est_columns
    rows = len(next(iter(columns.values())))
    names = extra_names(list(columns), list(extra))
    for name, values in extra.items():
        columns[names[name]] = placeholder(rows) if name in carried else _column(values)
    renamed = [name for name in extra if names[name] != name]
    if notes is not None and len(renamed) == 1:
        notes.append(f"input column {renamed[0]!r} is named like an output column; written as {names[renamed[0]]!r}")
    elif notes is not None and renamed:  # one line, not one per column (a recording of softtip's own has dozens)
        notes.append(f"{len(renamed)} input columns are named like output columns and written as input_NAME: "
                     + ", ".join(f"{n!r} -> {names[n]!r}" for n in renamed))  # fmt: skip
    return columns


def _carried(input_path, output, log=None) -> list[str]:
    """The input's extra columns to carry with their Arrow type (Parquet or Arrow IPC in and out), else none.
    With the ``log`` read whole: only the columns it kept as extras (not those read as t or the
    wrench under other names), and none when it dropped rows (they are copied row for row)."""
    from softtip.io.formats import table_format

    if input_path in (None, "-") or output is None or "csv" in (table_format(input_path), table_format(output)):
        return []
    from softtip.io.carry import typed_extras
    from softtip.io.tables import REQUIRED_COLUMNS, columnar_rows

    carried = typed_extras(input_path, tuple(REQUIRED_COLUMNS))
    if log is None or not carried:  # pieces of a log of softtip's own columns, each row kept
        return carried
    return [c for c in carried if c in log.extra] if columnar_rows(input_path) == len(log.t) else []


def _carry(input_path, output, outputs, est_names: list[str], extra_names_in: list[str], carried: list[str]) -> None:
    """Put the carried columns (:func:`_carried`) into the staged output."""
    if not carried:
        return
    from softtip.io.carry import carry_columns, extra_names

    names = extra_names(est_names, extra_names_in)
    carry_columns(input_path, outputs.get(output).tmp, {c: names[c] for c in carried})


def _write_estimate_outputs(
    est, columns, log, bag_log, config, fingertip, *, output, plot_path, plot_units, title, to_bag, rerun_spawn, rerun_save,
    metadata, outputs, staged_bag=None, ros_distro=None, frame_id=None, truth_angle=None,
) -> None:
    """Write every output of ``estimate`` into its staged file (``outputs``, committed by the caller)."""
    import io as _io

    from softtip.io.atomic import cannot_write, write_stdout
    from softtip.io.formats import table_format
    from softtip.io.tables import write_table

    viz = optional_extra("softtip.viz.rerun", "viz") if (rerun_spawn or rerun_save) else None
    if plot_path is not None:
        from softtip.viz.plot import plot_estimates

        # drawn in memory first: a full disk then gives the OS's reason, not the image writer's
        image = _io.BytesIO()
        threshold = config.line_threshold(est.h_std)
        plot_estimates(
            est, image, units=plot_units, title=title, h_threshold=threshold,
            reference_angles=None if truth_angle is None else [truth_angle], fmt=Path(plot_path).suffix.lower().lstrip("."),
        )  # fmt: skip
        try:
            with outputs.get(plot_path).open("wb") as fh:
                fh.write(image.getbuffer())
        except OSError as exc:
            raise cannot_write(plot_path, exc) from None
    if viz is not None:
        rerun_file = outputs.get(rerun_save)
        logger = viz.RerunLogger(fingertip, save=None if rerun_file is None else rerun_file.tmp, spawn=rerun_spawn)
        logger.log_estimates(est)
        logger.close()
    if to_bag is not None:
        bag = optional_extra("softtip.io.bag", "ros")
        frame = output_frame_id(frame_id, bag_log.frame_id if bag_log is not None else "")
        try:
            if bag_log is not None:
                bag.write_estimates_bag(staged_bag, est, bag_log.wrench, bag_log.stamps_ns, frame, bag_log.topic, distro=ros_distro)
            else:  # a table's absolute stamps (a ROS export's header.stamp) keep their time in the bag
                bag.write_estimates_bag(staged_bag, est, log.wrench, log.stamps_ns, frame_id=frame, distro=ros_distro)
        except InputError as exc:  # name the destination, not where it was staged
            raise InputError(str(exc).replace(str(staged_bag), str(to_bag))) from None
    if output is not None:
        from softtip.io.tables import TableWriter

        with progress_bar(len(est), "writing") as bar:
            try:
                with outputs.get(output).open() as fh, TableWriter(fh, format=table_format(output), metadata=metadata) as writer:
                    writer.write(columns, progress=bar.update)
            except OSError as exc:
                raise cannot_write(output, exc) from None
    elif to_bag is None:
        with progress_bar(len(est), "writing") as bar:
            write_stdout(lambda out: write_table(columns, out, progress=bar.update))
