"""The ``softtip`` command: a thin shell over the library (parse, call, write)."""

from __future__ import annotations

import math
import os
import sys
import warnings
from pathlib import Path

import click
import numpy as np

from softtip import __version__
from softtip.cli_types import PORT, Number, check_lowpass, check_pair_increasing
from softtip.core.depth import MURAKAMI2006_DEPTH, DepthLaw
from softtip.core.fingertip import PRESETS, Fingertip, load_fingertip
from softtip.core.noise import NANO17, SensorNoise
from softtip.core.units import KGF, KGF_MM, UNIT_SYSTEMS, wrench_to_si
from softtip.errors import InputError
from softtip.estimator import STATES, EstimatorConfig
from softtip.estimator import estimate as run_estimate
from softtip.estimator.depth import tip_depth_law
from softtip.estimator.results import DRIFT_COLUMNS, EstimatorWarning
from softtip.estimator.tare import bias_to_toml, load_bias
from softtip.ros.options import bag_output_options, output_frame_id

FRAMES_HELP = """\
Frames and units: every vector is in the sensor frame (origin at the F/T sensor's
measuring point, z along the finger axis toward the tip, right-handed). Inside and in
every file softtip uses SI: N, N·m, m, s; angles are degrees in files and plots. f and m
are the force and moment the touched object exerts on the fingertip, moment about the
sensor origin; in contact f pushes into the fingertip.
"""

def NON_NEGATIVE(unit: str) -> Number:  # noqa: N802 - reads as a type
    return Number(unit, 0.0)


def POSITIVE(unit: str) -> Number:  # noqa: N802
    return Number(unit, 0.0, min_open=True)

#: stream --speed: 0 (as fast as possible) or within these factors of real time
MIN_SPEED, MAX_SPEED = 1e-3, 1e6
#: stream --timeout upper bound, s (a day; longer waits overflow the host's timers)
MAX_TIMEOUT = 86400.0

_FORCE_COLUMNS = ("fx", "fy", "fz") + DRIFT_COLUMNS[:3]
_MOMENT_COLUMNS = ("mx", "my", "mz", "sigma", "hx", "hy", "hz", "h_norm", "h_std") + DRIFT_COLUMNS[3:]


class _Group(click.Group):
    def invoke(self, ctx):
        from softtip.io.atomic import cannot_write, silence_stdout
        from softtip.io.interrupt import Interrupted, exit_code, terminate_like_ctrl_c

        try:
            with terminate_like_ctrl_c():
                result = super().invoke(ctx)
                try:
                    sys.stdout.flush()  # a full device or a closed pipe shows here at the latest
                except OSError as exc:
                    silence_stdout()
                    raise cannot_write("standard output", exc) from None
                return result
        except InputError as exc:
            click.echo(f"softtip: error: {exc}", err=True)
            ctx.exit(2)
        except KeyboardInterrupt as exc:
            # Ctrl-C, SIGTERM, SIGHUP: every temporary file is gone by now (unwound like an error)
            name = exc.signal_name if isinstance(exc, Interrupted) else "SIGINT"
            click.echo(f"softtip: interrupted ({name})", err=True)
            ctx.exit(exit_code(exc))


@click.group(cls=_Group, help="softtip: intrinsic tactile sensing with a soft fingertip on a six-axis F/T sensor.\n\n" + FRAMES_HELP)
@click.version_option(__version__, prog_name="softtip")
def main() -> None:
    pass


_ESTIMATOR_OPTIONS = [
    click.option(
        "--tip",
        default="murakami2006",
        show_default=True,
        metavar="PRESET_OR_TOML",
        help=f"Fingertip: a preset ({', '.join(sorted(PRESETS))}) or a TOML file ([fingertip] shape = sphere|capsule|ellipsoid, lengths in m).",
    ),
    click.option(
        "--contact-point",
        type=click.Choice(["latch", "track", "joint"]),
        default="latch",
        show_default=True,
        help="latch: measure the contact point in the light-force window at the start of the grasp and hold it (the papers'); "
        "track: soft-finger solution every sample (h is then zero by construction: no directions); "
        "joint: latch, then move the point across the line to where a sliding window (--joint-window) fits the "
        "line-contact model, wherever the window determines it (flagged joint_fallback until one does).",
    ),
    click.option(
        "--joint-window",
        type=POSITIVE("s"),
        default=1.0,
        show_default=True,
        metavar="S",
        help="Sliding window of --contact-point joint, s.",
    ),
    click.option(
        "--joint-max-std",
        type=(POSITIVE("deg"), POSITIVE("mm")),
        default=(2.0, 0.2),
        show_default=True,
        metavar="DEG MM",
        help="--contact-point joint accepts a window when the standard deviations of its line angle and of its "
        "offset across the line are at most these (degrees, mm).",
    ),
    click.option(
        "--joint-max-residual",
        type=POSITIVE("noise standard deviations"),
        default=3.0,
        show_default=True,
        metavar="SIGMAS",
        help="... and the RMS residual of its fit is at most this many noise standard deviations.",
    ),
    click.option("--lowpass", type=POSITIVE("Hz"), metavar="HZ", help="Causal Butterworth low-pass cutoff in Hz (default: no filter)."),
    click.option(
        "--tare-duration",
        type=NON_NEGATIVE("s"),
        default=0.2,
        show_default=True,
        metavar="S",
        help="Take the first S seconds (fingertip untouched) as the sensor bias; 0 if INPUT is already tared.",
    ),
    click.option(
        "--tare-method",
        type=click.Choice(["robust", "median", "mean"]),
        default="robust",
        show_default=True,
        help="How the tare samples make the bias: robust (the mean of the samples that are not spikes), median, "
        "or mean (of all: a spike moves it).",
    ),
    click.option(
        "--bias",
        "bias_file",
        type=click.Path(dir_okay=False),
        metavar="FILE.toml",
        help="Subtract this sensor bias instead of taring ([bias] force = [N, N, N], moment = [N·m, N·m, N·m]; "
        "written by --save-bias or calibrate-payload).",
    ),
    click.option(
        "--hysteresis",
        type=NON_NEGATIVE("noise standard deviations"),
        default=3.0,
        show_default=True,
        metavar="SIGMAS",
        help="Contact ends below --contact-threshold minus this many standard deviations of the noise of |f| "
        "(from --force-noise, after --lowpass; at least half the threshold); 0: one threshold.",
    ),
    click.option(
        "--min-contact-duration",
        type=NON_NEGATIVE("s"),
        default=0.005,
        show_default=True,
        metavar="S",
        help="A contact is reported once |f| has stayed above the release threshold this long, each sample counting "
        "for its sampling interval (a shorter spike is no contact).",
    ),
    click.option(
        "--drift-time-constant",
        type=POSITIVE("s"),
        default=10.0,
        show_default=True,
        metavar="S",
        help="While untouched, follow the sensor's bias drift with a moving average of this time constant.",
    ),
    click.option(
        "--drift-tracking/--no-drift-tracking",
        default=True,
        show_default=True,
        help="Subtract the drift followed while untouched (--no-drift-tracking: report it only, the papers').",
    ),
    click.option("--contact-threshold", type=NON_NEGATIVE("N"), default=0.05, show_default=True, metavar="N", help="In contact while |f| is at least this, N."),
    click.option(
        "--latch-window",
        type=(NON_NEGATIVE("N"), NON_NEGATIVE("N")),
        default=(0.2 * KGF, 0.5 * KGF),
        show_default=True,
        metavar="LOW HIGH",
        help="Light-force window for latching the contact point, N (default 0.2–0.5 kgf).",
    ),
    click.option("--h-min", type=NON_NEGATIVE("N·mm"), default=0.5, show_default=True, metavar="N·mm", help="Smallest |h| reported as a line contact, N·mm."),
    click.option(
        "--force-noise",
        type=NON_NEGATIVE("N"),
        default=NANO17.force_std[0],
        show_default=True,
        metavar="N",
        help="Per-axis standard deviation of the sensor's force noise, N (Nano17-class default).",
    ),
    click.option(
        "--moment-noise",
        type=NON_NEGATIVE("N·mm"),
        default=NANO17.moment_std[0] * 1e3,
        show_default=True,
        metavar="N·mm",
        help="Per-axis standard deviation of the sensor's moment noise, N·mm.",
    ),
    click.option(
        "--relatch-distance",
        type=POSITIVE("mm"),
        metavar="MM",
        help="Latch again when, at light force, the soft-finger contact point moves farther than this from the "
        "latched one, mm (default: only when contact is lost and regained, the papers').",
    ),
    click.option(
        "--depth-compensation/--no-depth-compensation",
        default=None,
        help="Take the moment about the point inside the skin where friction acts, removing the spurious "
        "tangential moment of a tangential force. Its depth is learnt per contact from the data, the skin law "
        "(--skin-law) the prior; the depth, depth_std and depth_from_data columns report it. Default: on when "
        "the fingertip gives a skin (the murakami2006 preset, a file with skin_thickness), in latch mode. "
        "--no-depth-compensation: the papers' method.",
    ),
    click.option(
        "--fixed-depth",
        is_flag=True,
        help="Depth compensation at the skin law's depth as it is, not learnt from the data.",
    ),
    click.option(
        "--skin-law",
        type=(POSITIVE("N/m^P"), POSITIVE(""), POSITIVE("mm")),
        default=None,
        metavar="K P MAX_MM",
        help="Skin law of the depth compensation: normal force = K·depth^P (N, m), depth at most MAX_MM mm "
        "(default: the fingertip's skin; else the murakami2006 skin, "
        f"{MURAKAMI2006_DEPTH.stiffness:g} {MURAKAMI2006_DEPTH.exponent:g} {MURAKAMI2006_DEPTH.max_depth * 1e3:g}).",
    ),
    click.option(
        "--line-evidence",
        type=click.Choice(["on", "off"]),
        default="on",
        show_default=True,
        help="on: tell a line from an area over a sliding window (state area; line_evidence confirmed once the "
        "contact was excited about two tangent axes and h stayed on one, else unconfirmed; under confirmed "
        "evidence the direction comes from the window); off: the papers' per-sample line/point.",
    ),
    click.option("--evidence-window", type=POSITIVE("s"), default=2.0, show_default=True, metavar="S", help="Sliding window of the line evidence, s."),
    click.option(
        "--area-ratio",
        type=(POSITIVE("(eigenvalue ratio)"), POSITIVE("(eigenvalue ratio)")),
        default=(0.2, 0.1),
        show_default=True,
        metavar="ENTER LEAVE",
        help="area when the smaller/larger eigenvalue ratio of h's window covariance (noise removed) reaches ENTER; "
        "a confirmed line again only below LEAVE.",
    ),
    click.option(
        "--excitation",
        type=(POSITIVE("(eigenvalue ratio)"), POSITIVE("N")),
        default=(0.5, 0.01),
        show_default=True,
        metavar="RATIO MIN_N",
        help="Excited about two tangent axes when the tangential load's window covariance has its smaller eigenvalue "
        "beyond the noise, at least RATIO times the larger and at least MIN_N² (N).",
    ),
    click.option(
        "--evidence-reset-distance",
        type=POSITIVE("mm"),
        default=1.0,
        show_default=True,
        metavar="MM",
        help="The line evidence starts afresh when the contact point moves farther than this, mm.",
    ),
    click.option(
        "--evidence-max-std",
        type=POSITIVE("deg"),
        default=10.0,
        show_default=True,
        metavar="DEG",
        help="A window's line direction is used only when its standard deviation is at most this, degrees.",
    ),
]


def _estimator_options(f):
    """The pipeline settings shared by ``estimate`` and ``stream``."""
    for option in reversed(_ESTIMATOR_OPTIONS):
        f = option(f)
    return f


@main.command(
    help="""Estimate contact point, normal, spin torque, contact state and edge direction
from a force/torque log.

INPUT is a CSV file with a header row and columns t, fx, fy, fz, mx, my, mz (t in s,
non-decreasing: repeated stamps are counted and reported; extra columns are kept and copied
to the output), or a Parquet file with those columns (name ending in .parquet; its
softtip.core.units metadata gives the units). '-' reads CSV from standard input. With
--example, softtip's shipped example grasp is used instead.

The output CSV (standard output unless -o; Parquet when -o ends in .parquet, with the
units and the fingertip in its key-value metadata) has the columns t, state (none|point|line|area),
fx..mz (the wrench after bias removal and filtering, the one the estimates come from),
rx, ry, rz (contact point, m), nx, ny, nz (outward normal), sigma (spin torque about the
normal, N·m), hx, hy, hz, h_norm (tangential spin torque, N·m), dx, dy, dz (direction of
the touched edge / strip, an axis), angle_deg (its angle in the tangent frame, degrees in
(-90, 90]; at the tip: from the sensor x axis), h_std (noise level of h, N·m),
angle_std_deg, latched, latch_fallback, relatched (a new latch starts here), depth
(m, the depth compensation used; 0 without it), joint_conditioning, joint_angle_std_deg,
joint_offset_std (m), joint_residual and joint_fallback (the sliding window of
--contact-point joint: reciprocal condition number, standard deviations of its line angle
and offset, RMS fit residual in noise standard deviations, and whether the latched point
is used because no window has been accepted yet), depth_std (m, the depth's standard
deviation), depth_from_data (the contact's own data, not the skin law, determined it),
contact_id (1, 2, ... per contact, 0 out of contact), drift_fx..drift_mz (the bias drift
followed while untouched since the tare, N and N·m), line_evidence (confirmed|unconfirmed on
line samples: whether the contact was excited about two tangent axes with h staying on one),
h_ratio and excitation_ratio (smaller/larger eigenvalue of the evidence window's covariance
of h and of the tangential load, noise removed), then the input's extra columns. r, n, h are empty
(nan) when state is none; d and the angle only for line contacts, where |h| stands out of
the noise.

INPUT may also be a ROS bag (rosbag2 directory with sqlite3 or MCAP storage, a .mcap or
.db3 file, or a ROS 1 .bag; needs the rosbags package): the samples are the
geometry_msgs/msg/WrenchStamped messages of --topic, timed by header.stamp (t counts
from the first message; the stamps are copied to a stamp_ns column). --to-bag
writes the estimates as a bag --ros-distro plays (default humble: rosbag2 metadata version
5, sqlite3; a name ending in .bag: ROS 1) with standard messages on /softtip/state,
/softtip/contact_point, /softtip/normal, /softtip/edge_direction, /softtip/wrench and RViz
markers on /softtip/markers, plus the raw wrench, all with --frame-id; with --to-bag and
no -o no CSV is written. With --payload, --gravity-frame takes the sensor's orientation
from the bag's /tf.

"""
    + FRAMES_HELP
)
@click.argument("input_path", metavar="INPUT", required=False, type=click.Path(allow_dash=True))
@click.option("--example", is_flag=True, help="Use the shipped example grasp (a 45° line contact, murakami2006 tip) as INPUT.")
@click.option("-o", "--output", type=click.Path(dir_okay=False, writable=True), help="Output CSV, or Parquet for a name ending in .parquet (default: CSV on standard output).")
@click.option(
    "--units",
    type=click.Choice(UNIT_SYSTEMS),
    default=None,
    help="Units of the input wrench: si (N, N·m) or kgf-mm (kgf, kgf·mm, the papers').  [default: si, or a Parquet INPUT's own]",
)
@click.option(
    "--output-units",
    type=click.Choice(UNIT_SYSTEMS),
    default="si",
    show_default=True,
    help="Units of force and moment columns in the output; lengths stay in m, angles in degrees.",
)
@click.option("--plot", "plot_path", type=click.Path(dir_okay=False), help="Also draw the papers' four panels (force, moment, |h|, direction) to this PNG/PDF/SVG.")
@click.option("--plot-units", type=click.Choice(UNIT_SYSTEMS), default="si", show_default=True, help="Units of the plot's force and moment axes.")
@click.option("--topic", metavar="TOPIC", help="Bag input: the geometry_msgs/msg/WrenchStamped topic (default: the bag's only one).")
@click.option("--allow-partial", is_flag=True, help="Bag input: use a damaged bag's readable messages (with a warning) instead of stopping.")
@bag_output_options()
@click.option("--gravity-frame", metavar="FRAME", help="With --payload and a bag INPUT: the sensor's orientation from the bag's /tf and /tf_static, FRAME (z up, e.g. world) to the wrench's frame_id, at each stamp (instead of qw, qx, qy, qz columns).")
@click.option("--rerun", "rerun_spawn", is_flag=True, help="Show the fingertip, force, contact point, normal and edge in a Rerun viewer (needs the rerun-sdk package).")
@click.option("--rerun-save", type=click.Path(dir_okay=False), metavar="FILE.rrd", help="Save the Rerun 3-D view and time series to FILE.rrd (open with `rerun FILE.rrd`).")
@click.option("--payload", type=click.Path(dir_okay=False), metavar="FILE.toml", help="Remove the fingertip's weight ([payload] mass kg, com m; see calibrate-payload) before taring, using INPUT's qw, qx, qy, qz columns (sensor frame in a z-up world frame).")
@click.option("-q", "--quiet", is_flag=True, help="No summary on standard error (warnings and errors still are).")
@click.option("--save-bias", type=click.Path(dir_okay=False), metavar="FILE.toml", help="Write the bias used (the tare's) to FILE.toml, for --bias of a later run.")
@click.option(
    "--chunk-rows", type=click.IntRange(min=1), metavar="N",
    help="Process INPUT in pieces of at least N rows, in bounded memory, with the result of the one-shot run (a piece ends "
    "only out of contact: a contact longer than N rows makes its piece as long). [default: pieces of 131072 rows for a CSV "
    "file over 24 MB or a Parquet file over 262144 rows; only for a CSV or Parquet file without --plot, --to-bag, --rerun, "
    "--rerun-save, --payload]",
)  # fmt: skip
@_estimator_options
def estimate(
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
    **estimator_opts,
):
    from softtip.io.examples import EXAMPLE_PATH
    from softtip.io.tables import Log, read_log

    if example == (input_path is not None):
        raise click.UsageError("give either INPUT or --example")
    if example and units not in (None, "si"):
        raise click.UsageError("--units applies to INPUT; the example grasp is in SI")
    if plot_path is not None:
        _check_figure_path(plot_path)
    _check_outputs(
        [("INPUT", None if example else input_path), ("--payload", payload), ("--tip", tip if os.path.isfile(tip) else None),
         ("--bias", estimator_opts.get("bias_file"))],
        [("-o", output), ("--plot", plot_path), ("--to-bag", to_bag), ("--rerun-save", rerun_save), ("--save-bias", save_bias)],
    )
    fingertip = load_fingertip(tip)
    config = _make_config(estimator_opts, tip=fingertip)

    bag_log = None
    if example:
        log = read_log(EXAMPLE_PATH, units="si")
    elif input_path == "-":
        log = read_log(sys.stdin, units=units)
    elif _is_bag(input_path):
        bag = _optional("softtip.io.bag", "ros")
        bag_log = bag.read_bag(input_path, topic, allow_partial=allow_partial)
        _bag_warnings(input_path, bag_log)
        # t counts from the first message; the absolute stamps go along as an extra column
        extra = {"stamp_ns": [str(v) for v in bag_log.stamps_ns.tolist()]}
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
        if chunk_rows is not None and output is None:
            raise click.UsageError("--chunk-rows: needs -o FILE (a piece written to standard output cannot be taken back)")
        if output is not None and topic is None and not allow_partial and not any(others.values()):
            rows = chunk_rows or _auto_chunk_rows(input_path)
            if rows and _estimate_in_pieces(
                input_path, units, rows, fingertip, config, estimator_opts, output=output, output_units=output_units,
                tip=tip, quiet=quiet, save_bias=save_bias,
            ):  # fmt: skip
                return
        size = os.path.getsize(input_path) if os.path.isfile(input_path) else 0
        with _progress_bar(size, "reading", unit="B") as bar:
            log = read_log(input_path, units=units, progress=bar.update)
    for note in log.warnings:  # repeated stamps, an implausible time scale, a cut last line
        click.echo(f"softtip: warning: {note}", err=True)
    if topic is not None and bag_log is None:
        raise click.UsageError("--topic applies to bag input only")
    if allow_partial and bag_log is None:
        raise click.UsageError("--allow-partial applies to bag input only")
    if to_bag is None and (ros_distro is not None or frame_id is not None):
        raise click.UsageError("--ros-distro and --frame-id apply to --to-bag")
    if to_bag is not None:
        from softtip.ros.bagout import bag_format

        bag_format(to_bag, ros_distro)  # a name that does not fit the distribution: stop before the work
    if gravity_frame is not None and (payload is None or bag_log is None):
        raise click.UsageError("--gravity-frame needs --payload and a bag INPUT (with /tf)")
    if payload is not None:  # gravity compensation first: the tare then removes only the sensor bias
        from softtip.calibration.payload import compensate_log, compensate_payload, load_payload

        if gravity_frame is None:
            log = compensate_log(log, payload)
        else:  # the orientation from the bag's /tf
            from dataclasses import replace

            from softtip.fusion.tf import gravity_orientations

            q = gravity_orientations(input_path, gravity_frame, bag_log.frame_ids, bag_log.stamps_ns, frame_id)
            log = replace(log, wrench=compensate_payload(log.wrench, q, load_payload(payload)))
    check_lowpass(estimator_opts["lowpass"], log.t)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", EstimatorWarning)  # printed below, from est.warnings
            est = run_estimate(log.t, log.wrench, fingertip, config)
    except ValueError as exc:  # e.g. a low-pass cutoff above Nyquist for this log's rate
        raise click.UsageError(str(exc)) from None
    _check_units(est, fingertip, config, log.units, log.source)

    columns = _output_columns(est, log.extra, output_units)

    source = "example grasp" if example else Path(log.source).name
    _write_estimate_outputs(
        est, columns, log, bag_log, config, fingertip,
        output=output, plot_path=plot_path, plot_units=plot_units, title=f"softtip: {source}",
        to_bag=to_bag, rerun_spawn=rerun_spawn, rerun_save=rerun_save, ros_distro=ros_distro, frame_id=frame_id,
        metadata=_parquet_metadata(fingertip, tip, output_units, log),
    )  # fmt: skip

    from softtip.estimator.summary import summarise_contacts

    _report_run(
        _RunTotals.of(est, summarise_contacts(est) if not quiet else []),
        input_path=input_path, output=output, plot_path=plot_path, to_bag=to_bag, rerun_save=rerun_save,
        save_bias=save_bias, quiet=quiet,
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
        self.n += len(est)
        for code, name in enumerate(STATES):
            self.counts[name] += int(np.count_nonzero(est.state == code))
        self.confirmed += int(np.count_nonzero(est.line_evidence == 2))
        self.n_pulling += est.n_pulling
        first = self.n_contacts
        self.contacts += [dataclasses.replace(c, index=first + c.index) for c in contacts]
        self.n_contacts = max(self.n_contacts, est.n_contacts)
        self.warnings += [w for w in est.warnings if w not in self.warnings]


def _report_run(totals: _RunTotals, *, input_path, output, plot_path, to_bag, rerun_save, save_bias, quiet) -> None:
    """The end of ``softtip estimate``: tare and warnings, ``--save-bias``, the summary."""
    # in the one-shot run's order: a drift alarm (of any piece) after the contact warnings
    totals.warnings.sort(key=lambda w: w.startswith("the sensor bias drifted"))
    _tare_warnings(totals)
    if save_bias is not None:
        if any(p is not None and Path(p).resolve() == Path(save_bias).resolve() for p in (input_path, output, plot_path)):
            raise InputError(f"--save-bias {save_bias}: is also an input or output of this run")
        if not np.all(np.isfinite(totals.bias)):
            raise InputError(f"--save-bias {save_bias}: no bias: the whole log lies within the tare")
        from softtip.calibration.probing import atomic_write_text

        atomic_write_text(save_bias, bias_to_toml(totals.bias, f"softtip sensor bias ({totals.tare.summary()})"))
        click.echo(f"softtip: bias -> {save_bias}", err=True)
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
    summary = ", ".join(
        f"{v} {k}" + (f" ({totals.confirmed} confirmed)" if k == "line" else "") for k, v in totals.counts.items()
    )
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
AUTO_CHUNK_PARQUET_ROWS = 262_144


def _auto_chunk_rows(path: str) -> int | None:
    """Rows per piece for a log this large (:data:`AUTO_CHUNK_CSV_BYTES`, :data:`AUTO_CHUNK_PARQUET_ROWS`), else None."""
    from softtip.io.chunked import DEFAULT_PIECE_ROWS

    try:
        if path.lower().endswith(".parquet"):
            import pyarrow.parquet as pq

            with pq.ParquetFile(path) as pf:
                large = pf.metadata.num_rows > AUTO_CHUNK_PARQUET_ROWS
        else:
            large = os.path.getsize(path) > AUTO_CHUNK_CSV_BYTES
    except Exception:  # noqa: BLE001 - unreadable in any way: the one-shot reader words it
        return None
    return DEFAULT_PIECE_ROWS if large else None


def _estimate_in_pieces(
    input_path, units, rows, fingertip, config, estimator_opts, *, output, output_units, tip, quiet, save_bias
) -> bool:
    """``softtip estimate`` piece by piece (:mod:`softtip.io.chunked`) into ``output`` (a path);
    ``False`` when the log holds something only the one-shot reader takes or words (nothing
    written then)."""
    from softtip.core.lever import LEVER_MARGIN, LeverVote, fingertip_reach, lever_distances
    from softtip.estimator.summary import summarise_contacts
    from softtip.io.atomic import atomic_write
    from softtip.io.chunked import estimate_pieces
    from softtip.io.tables import NotStreamable, TableWriter, iter_log

    parquet = output is not None and output.lower().endswith(".parquet")
    totals = _RunTotals()
    vote = LeverVote(LEVER_MARGIN * fingertip_reach(fingertip))  # the units check, over the whole log
    total = None
    if input_path.lower().endswith(".parquet"):
        import pyarrow.parquet as pq

        with pq.ParquetFile(input_path) as pf:
            total = pf.metadata.num_rows
    with _progress_bar(total, "estimating") as bar:  # rows estimated and written
        blocks = iter_log(input_path, units, rows=min(rows, 1 << 16))

        def checked():
            first = True
            for block in blocks:
                if first:
                    check_lowpass(estimator_opts["lowpass"], block[0])
                    first = False
                yield block

        def run(out) -> None:
            writer = TableWriter(out, parquet=parquet, metadata=_parquet_metadata(fingertip, tip, output_units, blocks))
            try:
                for est, extra in estimate_pieces(checked(), fingertip, config, rows):
                    vote.add(lever_distances(est.wrench[~est.taring], max(0.1, config.contact_threshold)))
                    columns = _output_columns(est, extra, output_units)
                    writer.write(columns)
                    bar.update(len(est))
                    totals.add(est, summarise_contacts(est) if not quiet else [])
            finally:
                writer.close()
            if vote.n >= 5 and vote.median_above():
                raise NotStreamable("wrong units: the one-shot run says so")  # as _check_units decides

        try:
            with atomic_write(output) as fh:
                run(fh)
        except NotStreamable:  # nothing written: the one-shot run takes it, or says what is wrong
            return False
        except ValueError as exc:  # e.g. a low-pass cutoff above Nyquist for this log's rate
            if isinstance(exc, InputError):
                raise
            raise click.UsageError(str(exc)) from None
    for note in blocks.warnings():
        click.echo(f"softtip: warning: {note}", err=True)
    _report_run(
        totals, input_path=input_path, output=output, plot_path=None, to_bag=None, rerun_save=None,
        save_bias=save_bias, quiet=quiet,
    )  # fmt: skip
    return True


def _output_columns(est, extra, output_units: str) -> dict:
    """The output table: the estimates' columns in ``output_units``, then the input's extra columns."""
    columns = est.columns()
    if output_units == "kgf-mm":
        for name in _FORCE_COLUMNS:
            columns[name] = columns[name] / KGF
        for name in _MOMENT_COLUMNS:
            columns[name] = columns[name] / KGF_MM
    for name, values in extra.items():
        columns[name if name not in columns else f"input_{name}"] = np.asarray(values)
    return columns


def _check_units(est, fingertip, config: EstimatorConfig, units: str, source: str) -> None:
    """Exit 2 when the moment-to-force ratio puts the force far outside the fingertip (wrong --units or --tip)."""
    from softtip.core.lever import check_force_lever

    check_force_lever(
        est.wrench[~est.taring], fingertip, units=units, source=source, min_force=max(0.1, config.contact_threshold)
    )


def _bag_warnings(path: str, bag_log) -> None:
    """Say what was odd about a bag that was read anyway (damaged with --allow-partial; repeated stamps)."""
    if bag_log.damage:
        click.echo(f"softtip: warning: {path}: damaged bag, {len(bag_log.t)} samples used: {bag_log.damage}", err=True)
    if bag_log.repeated_stamps:
        click.echo(
            f"softtip: {path}: {bag_log.repeated_stamps} message(s) repeat the previous header.stamp (kept)", err=True
        )


def _check_outputs(inputs, outputs) -> None:
    """Exit 2 when an output is an input or another output of the run (:func:`softtip.io.atomic.check_distinct`)."""
    from softtip.io.atomic import check_distinct

    check_distinct(inputs, outputs)


def _write_estimate_outputs(
    est, columns, log, bag_log, config, fingertip, *, output, plot_path, plot_units, title, to_bag, rerun_spawn, rerun_save,
    metadata, ros_distro=None, frame_id=None,
) -> None:
    """Write every output of ``estimate``; all appear together, or none (and no temporary file stays)."""
    import io as _io

    from softtip.io.atomic import AtomicFile, cannot_write, commit_all, write_stdout
    from softtip.io.tables import write_table

    viz = _optional("softtip.viz.rerun", "viz") if (rerun_spawn or rerun_save) else None
    pending: list[AtomicFile] = []
    bag_written = False
    try:
        if plot_path is not None:
            from softtip.viz.plot import plot_estimates

            # drawn in memory first: a full disk then gives the OS's reason, not the image writer's
            image = _io.BytesIO()
            threshold = np.maximum(config.h_sigmas * est.h_std, config.h_min)
            plot_estimates(
                est, image, units=plot_units, title=title, h_threshold=threshold,
                fmt=Path(plot_path).suffix.lower().lstrip("."),
            )  # fmt: skip
            pending.append(AtomicFile(plot_path))
            try:
                with pending[-1].open("wb") as fh:
                    fh.write(image.getbuffer())
            except OSError as exc:
                raise cannot_write(plot_path, exc) from None
        if viz is not None:
            rerun_file = None
            if rerun_save:
                pending.append(rerun_file := AtomicFile(rerun_save))
            logger = viz.RerunLogger(fingertip, save=None if rerun_file is None else rerun_file.tmp, spawn=rerun_spawn)
            logger.log_estimates(est)
            logger.close()
        if to_bag is not None:
            bag = _optional("softtip.io.bag", "ros")
            frame = output_frame_id(frame_id, bag_log.frame_id if bag_log is not None else "")
            if bag_log is not None:
                bag.write_estimates_bag(to_bag, est, bag_log.wrench, bag_log.stamps_ns, frame, bag_log.topic, distro=ros_distro)
            else:
                bag.write_estimates_bag(to_bag, est, log.wrench, frame_id=frame, distro=ros_distro)
            bag_written = True
        # the table last, atomically (softtip.io.atomic, through write_table); then the others are put in place
        if output is not None:
            with _progress_bar(len(est), "writing") as bar:
                write_table(columns, output, metadata=metadata, progress=bar.update)
        elif to_bag is None:
            with _progress_bar(len(est), "writing") as bar:
                write_stdout(lambda out: write_table(columns, out, progress=bar.update))
        commit_all(pending)
        bag_written = False  # every output is in place: keep the bag
    finally:
        for f in pending:
            f.discard()
        if bag_written:
            from softtip.ros.bagout import remove_bag

            remove_bag(to_bag)


class _NoProgress:
    """What :func:`_progress_bar` gives when standard error is not a terminal."""

    def update(self, n: int = 1) -> None:
        pass

    def close(self) -> None:
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        pass


def _progress_bar(total: int, what: str, *, unit: str = " rows", file=None, delay: float = 2.0):
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


def _parquet_metadata(fingertip, tip: str, output_units: str, log) -> dict[str, str]:
    """Key-value metadata of a Parquet output: units, fingertip, input, softtip's version."""
    from softtip.io.tables import PARQUET_FINGERTIP_KEY, PARQUET_UNITS_KEY

    meta = {PARQUET_UNITS_KEY: output_units, "softtip.tip": str(tip), "softtip.input": log.source, "softtip.version": __version__}
    try:
        meta[PARQUET_FINGERTIP_KEY] = fingertip.to_toml()
    except (NotImplementedError, AttributeError, TypeError, ValueError):  # e.g. a callable surface
        pass
    return meta


def _check_figure_path(path: str) -> None:
    """A figure path needs an existing folder and a format matplotlib writes (exit 2 otherwise)."""
    from softtip.viz.plot import figure_formats

    p = Path(path)
    formats = figure_formats()
    if p.suffix.lower().lstrip(".") not in formats:
        raise InputError(f"{path}: expected a figure file name ending in one of {', '.join('.' + f for f in sorted(formats))}")
    if not p.parent.is_dir():
        raise InputError(f"{path}: folder {str(p.parent)!r} does not exist")


def _tare_warnings(est) -> None:
    """Say what the tare did, and every warning of the estimator (all from the library)."""
    if est.tare is not None and est.tare.source != "none" and np.all(np.isfinite(est.bias)):
        click.echo(f"softtip: {est.tare.summary()}", err=True)
    for msg in est.warnings:
        click.echo(f"softtip: warning: {msg}", err=True)


def _make_config(opts: dict, sample_rate: float | None = None, tip: Fingertip | None = None) -> EstimatorConfig:
    """The :class:`EstimatorConfig` of the shared estimator options (CLI units → SI)."""
    check_pair_increasing("--latch-window", opts["latch_window"], "N")
    try:
        comp, fixed = opts["depth_compensation"], opts["fixed_depth"]
        if comp is False and fixed:
            raise click.UsageError("--fixed-depth and --no-depth-compensation contradict each other")
        depth = None
        if opts["skin_law"] is not None:
            k, p, max_mm = opts["skin_law"]
            depth = DepthLaw(k, p, max_mm * 1e-3)
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
            noise=SensorNoise((opts["force_noise"],) * 3, (opts["moment_noise"] * 1e-3,) * 3),
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
            relatch_distance=None if relatch is None else relatch * 1e-3,
            depth=depth,
            depth_mode=depth_mode,
            joint_window=opts["joint_window"],
            joint_max_angle_std=math.radians(opts["joint_max_std"][0]),
            joint_max_offset_std=opts["joint_max_std"][1] * 1e-3,
            joint_max_residual=opts["joint_max_residual"],
            line_evidence=opts["line_evidence"] == "on",
            evidence_window=opts["evidence_window"],
            area_ratio=opts["area_ratio"],
            excitation_ratio=opts["excitation"][0],
            excitation_min=opts["excitation"][1],
            evidence_max_angle_std=math.radians(opts["evidence_max_std"]),
            evidence_reset_distance=opts["evidence_reset_distance"] * 1e-3,
        )
    except ValueError as exc:
        raise click.UsageError(str(exc)) from None


def _is_bag(path: str) -> bool:
    from softtip.io.bag import is_bag  # rosbags itself is imported only to read one

    return is_bag(path)


def _optional(module: str, extra: str):
    """Import one of softtip's modules that needs an optional extra; exit 2 naming the extra."""
    import importlib

    try:
        mod = importlib.import_module(module)
        getattr(mod, {"ros": "import_rosbags", "viz": "import_rerun"}[extra])()
    except ImportError as exc:  # the message names the package to install
        raise InputError(str(exc)) from None
    return mod


@main.command(
    help="""Estimate live: from an ATI Net F/T or Axia sensor, or a replayed log.

With --netft HOST softtip reads the calibration (counts per force and torque unit, units)
from the sensor over HTTP (/netftapi2.xml), streams RDT records over UDP, converts them to
SI and runs the streaming estimator on every sample. With --replay
LOG.csv the log is fed through the same path at its recorded rate times --speed (0: as
fast as possible).

Taring: the first --tare-duration seconds (0.2 s) make the sensor bias, so keep
the fingertip untouched when the stream starts (or give --bias FILE); the t key of the
terminal view tares again from the next samples; --device-bias also zeroes the sensor
itself first. The tare is checked (spikes, noise above the noise model, a stream that
starts in contact) and the drift followed while untouched; warnings are shown in the view
and at the end.

The terminal view (standard error, redrawn a few times a second when it is a terminal)
shows the state, contact point, normal, |h|, edge angle ± std, sample rate, and what the
stream went through: packets lost on the network, late and duplicate packets (dropped),
malformed datagrams, samples dropped by softtip's own queue, the device's status word,
restarts and F/T-sequence stalls, and the latest warning; the device's rate (comrdtrate)
is checked against the host clock (a difference over 2 % is warned about). None of these
ends the stream unless named in --strict (then exit 1).

--record FILE.csv writes every sample as it comes (flushed every 0.05 s, always whole
lines): t and the raw wrench fx..mz first (the file is a log that `softtip estimate` and
--replay read as it is), then the columns of `softtip estimate` with its tared wrench as
fx_tared..mz_tared, then seq (RDT sequence or row), lost and dropped (records missing just
before this one: on the network or still to come late / dropped by this host), late,
duplicates and malformed (discarded since the previous row), status (the device's status
word) and host_time (host receive time, s since the Unix epoch). Ctrl-C, SIGTERM and
SIGHUP stop cleanly (exit 0, every row taken written), also during discovery or a silent
stream; so do --duration and the end of a replayed log. No data for --timeout seconds is
an error (exit 1).

"""
    + FRAMES_HELP
)
@click.option("--netft", "host", metavar="HOST", help="Address of the Net F/T / Axia.")
@click.option("--replay", "replay", type=click.Path(dir_okay=False), metavar="LOG.csv", help="Replay a recorded CSV log (columns t, fx, fy, fz, mx, my, mz) instead.")
@click.option("--speed", type=Number("× real time", 0.0, MAX_SPEED), default=1.0, show_default=True, help="Replay speed: 1 real time, 2 twice as fast, 0 as fast as possible.")
@click.option("--units", type=click.Choice(UNIT_SYSTEMS), default="si", show_default=True, help="Units of the replayed log's wrench.")
@click.option("--rdt-port", type=PORT, default=49152, show_default=True, help="UDP port of the sensor's RDT server.")
@click.option("--http-port", type=PORT, default=80, show_default=True, help="HTTP port of the sensor's web server (calibration).")
@click.option("--timeout", type=Number("s", 0.0, MAX_TIMEOUT, min_open=True), default=2.0, show_default=True, metavar="S", help="Give up after S seconds without data from the sensor.")
@click.option("--device-bias", is_flag=True, help="Send the sensor's own bias (zero) command at start, before softtip's tare.")
@click.option("--strict", metavar="FAULTS", default="", help="Comma-separated faults that end the stream (exit 1): status, restart, stall, lost, duplicate, late, malformed, dropped, or all. Default: none (counted, warned).")
@click.option("--duration", type=POSITIVE("s"), metavar="S", help="Stop after S seconds (default: until Ctrl-C or the end of the replayed log).")
@click.option("--record", type=click.Path(dir_okay=False), metavar="FILE.csv", help="Record raw samples and estimates to FILE.csv as they come.")
@click.option("--view/--no-view", default=None, help="Live terminal view (default: when standard error is a terminal).")
@click.option("--rerun", "rerun_spawn", is_flag=True, help="Show the 3-D view live in a Rerun viewer (needs the rerun-sdk package; at most 50 samples/s are drawn).")
@click.option("--rerun-save", type=click.Path(dir_okay=False), metavar="FILE.rrd", help="Save the 3-D view and time series to FILE.rrd.")
@click.option("--payload", type=click.Path(dir_okay=False), metavar="FILE.toml", help="With --replay: remove the fingertip's weight per sample, using the log's qw, qx, qy, qz columns (recorded raw_* columns are then compensated).")
@_estimator_options
@click.pass_context
def stream(
    ctx,
    host,
    replay,
    speed,
    units,
    rdt_port,
    http_port,
    timeout,
    device_bias,
    strict,
    duration,
    record,
    view,
    rerun_spawn,
    rerun_save,
    tip,
    payload=None,
    **estimator_opts,
):
    import signal
    import threading

    from softtip.estimator import Estimator
    from softtip.io.live import KeyReader, LiveStats, Recorder, TerminalView, run_live
    from softtip.io.netft import FAULTS
    from softtip.io.sources import Interrupted, LogSource, SourceError

    if (host is None) == (replay is None):
        raise click.UsageError("give either --netft HOST or --replay LOG.csv")
    if payload is not None and replay is None:
        raise click.UsageError("--payload needs the orientation columns of a replayed log (--replay LOG.csv)")
    if 0 < speed < MIN_SPEED:
        raise click.BadParameter(
            f"{speed:g}; expected 0 (as fast as possible) or a number in [{MIN_SPEED:g}, {MAX_SPEED:g}] × real time",
            param_hint="'--speed'",
        )
    faults = {f.strip() for f in strict.split(",") if f.strip()}
    if "all" in faults:
        faults = set(FAULTS)
    if faults - set(FAULTS):
        raise click.UsageError(f"--strict: unknown fault(s) {', '.join(sorted(faults - set(FAULTS)))}; expected some of {', '.join(FAULTS)} or all")
    if faults and host is None:
        raise click.UsageError("--strict applies to a live sensor (--netft HOST)")
    _check_outputs(
        [("--replay", replay), ("--payload", payload), ("--tip", tip if os.path.isfile(tip) else None),
         ("--bias", estimator_opts.get("bias_file"))],
        [("--record", record), ("--rerun-save", rerun_save)],
    )
    fingertip = load_fingertip(tip)
    recorder = Recorder(record) if record is not None else None
    viz = _optional("softtip.viz.rerun", "viz") if (rerun_spawn or rerun_save) else None

    stop = threading.Event()
    # Ctrl-C, SIGTERM and SIGHUP end the loop between two samples (or a wait for one): the
    # recording stays complete, on a whole line
    stop_signals = [signal.SIGINT, signal.SIGTERM] + ([signal.SIGHUP] if hasattr(signal, "SIGHUP") else [])
    previous = {sig: signal.signal(sig, lambda *_: stop.set()) for sig in stop_signals}
    source = None
    try:
        try:
            if replay is not None:
                if payload is None:
                    source = LogSource.from_csv(replay, units=units, speed=speed, stop=stop)
                else:
                    from softtip.calibration.payload import replay_source

                    source = replay_source(replay, units, speed, payload)
                info = f"(replay x{speed:g})" if speed else "(replay, as fast as possible)"
            else:
                from softtip.io.netft import NetFTSource

                try:
                    source = NetFTSource(host, rdt_port=rdt_port, http_port=http_port, timeout=timeout, device_bias=device_bias, strict=faults, stop=stop)
                except ValueError as exc:
                    raise click.UsageError(str(exc)) from None
                source.open()
                d = source.info
                rate = f"{d.rate_hz:g} Hz" if d.rate_hz else "rate unknown"
                info = f"({d.product}, {d.force_unit} / {d.torque_unit}, {rate})"
            lowpass = estimator_opts["lowpass"]
            if lowpass is not None and source.rate_hz is not None:
                check_lowpass(lowpass, source.rate_hz)
            config = _make_config(
                estimator_opts, sample_rate=source.rate_hz if lowpass is not None else None, tip=fingertip
            )
            if lowpass is not None and source.rate_hz is None:
                raise click.UsageError("--lowpass needs the sample rate, which this source does not report")
            estimator = Estimator(fingertip, config)
            tare_request = threading.Event()
            stats = LiveStats(
                source_name=source.name,
                info=info,
                dropped=(lambda: source.dropped) if hasattr(type(source), "dropped") else None,
                counters=getattr(source, "counters", None),
                warnings=(lambda: source.warnings) if hasattr(type(source), "warnings") else None,
            )
            show = sys.stderr.isatty() if view is None else view
            tare_key = show and sys.stdin.isatty()
            term = TerminalView(
                stats, interval=0.2, h_threshold=config.h_min, recorder=recorder, estimator=estimator,
                tare_key=tare_key,
            ) if show else None  # fmt: skip
            on_estimate = None
            if viz is not None:
                logger = viz.RerunLogger(fingertip, save=rerun_save, spawn=rerun_spawn)
                on_estimate = lambda e, r: logger.log_sample(e)
            keys = KeyReader({"t": tare_request.set}) if tare_key else None
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", EstimatorWarning)  # shown in the view and below
                    summary = run_live(
                        source, estimator, recorder=recorder, view=term, stats=stats, duration=duration, stop=stop,
                        on_estimate=on_estimate, tare_request=tare_request,
                    )  # fmt: skip
            finally:
                if keys is not None:
                    keys.close()
            recorder = None  # closed by run_live
            if viz is not None:
                logger.close()
        except Interrupted:
            click.echo("softtip: interrupted before the first sample; nothing recorded", err=True)
            return
        except SourceError as exc:
            for w in getattr(source, "warnings", None) or []:
                click.echo(f"softtip: warning: {source.name}: {w}", err=True)
            click.echo(f"softtip: error: {exc}", err=True)
            ctx.exit(1)
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        if source is not None and hasattr(source, "close"):
            source.close()
        if recorder is not None:
            recorder.close()
    for w in summary.warnings:
        click.echo(f"softtip: warning: {source.name}: {w}", err=True)
    rate = summary.samples / summary.seconds if summary.seconds > 0 else 0.0
    why = {"end": "end of log", "duration": "duration reached", "interrupt": "interrupted"}[summary.reason]
    c = summary.counters
    more = "".join(f"{c[k]} {k}, " for k in ("late", "duplicates", "malformed") if k in c)
    device = "".join(f", {c[k]} {name}" for k, name in (("restarts", "restarts"), ("stalls", "stalled records"), ("status_records", "with a nonzero status")) if c.get(k))
    click.echo(
        f"softtip: {summary.samples} samples in {summary.seconds:.2f} s ({rate:.1f} Hz), {summary.lost} lost, {more}"
        f"{summary.dropped} dropped by softtip{device}; {estimator.contacts} contact(s); {why}"
        + (f"; recorded -> {record}" if record else ""),
        err=True,
    )
    if estimator.tare_report is not None and estimator.tare_report.source != "none":
        click.echo(f"softtip: {estimator.tare_report.summary()}", err=True)
    for msg in dict.fromkeys(estimator.warnings):
        click.echo(f"softtip: warning: {msg}", err=True)


@main.command(
    help="""Reproduce the papers' experiments (manual §5, E1–E6) on the simulator.

Every condition (edges of different sharpness, the 1 mm plate at −45°, 0°, 45°, 90°, plates
1–15 mm, cylinders Ø 4–14 mm, the fringe of a Ø 40 mm cylinder bottom, contact position)
is simulated with the papers' grasp and measured by the same pipeline as `softtip
estimate` (default options, --no-drift-tracking as in the papers). Writes to --out one figure per experiment laid out like the
papers' (e1_edges.png … e6_contact_position.png) and the summary table summary.md /
summary.csv: per condition the median axial direction error (degrees), the share of
samples with a reported direction, the contact-position error (mm), the line evidence, the
published outcome and whether ours agrees. X1, softtip's extension, rocks thin and thick
objects about two tangent axes and judges line or area (x1_line_or_area.png: h in the
tangent plane as a trace, and the state over time).

"""
    + FRAMES_HELP
)
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default="reproduction", show_default=True, help="Output directory (created).")
@click.option(
    "--only",
    metavar="E1,E2,...",
    help="Run only these experiments (comma-separated ids E1–E6, X1).",
)
@click.option("--seed", type=click.IntRange(min=0), default=2006, show_default=True, help="Seed of the simulated sensor noise.")
@click.option(
    "--jobs",
    type=click.IntRange(1, 64),
    default=min(4, os.cpu_count() or 1),
    show_default="min(4, CPUs)",
    help="Worker processes.",
)
def reproduce(out_dir, only, seed, jobs):
    from tqdm import tqdm

    from softtip.sim.reproduce import run_reproduction

    experiments = [e.strip() for e in only.split(",") if e.strip()] if only else None
    try:
        results = run_reproduction(
            out_dir,
            experiments=experiments,
            seed=seed,
            jobs=jobs,
            progress=lambda it, total: tqdm(it, total=total, desc="simulated grasps", unit="grasp", file=sys.stderr),
        )
    except ValueError as exc:
        raise click.UsageError(str(exc)) from None
    judged = [r for r in results if r.agrees is not None]
    click.echo(
        f"softtip: {len(results)} conditions, {sum(r.agrees for r in judged)} of {len(judged)} agree with the "
        f"published outcomes -> {Path(out_dir) / 'summary.md'}",
        err=True,
    )


def _register_commands() -> None:
    from softtip.cli_calibrate import calibrate, calibrate_payload
    from softtip.sim.commands import simulate

    for command in (simulate, calibrate, calibrate_payload):
        main.add_command(command)
    from softtip.cli_fuse import register

    register(main)


_register_commands()


if __name__ == "__main__":  # pragma: no cover
    main()
