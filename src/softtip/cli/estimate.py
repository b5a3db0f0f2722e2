"""``softtip estimate``: a log (CSV, Parquet, bag) through the batch estimator to CSV/Parquet, a figure, a bag, a Rerun view."""

from __future__ import annotations

import os
import shutil
import sys
import warnings
from pathlib import Path

import click
import numpy as np

from softtip.cli.options import (
    FRAMES_HELP,
    bag_warnings,
    check_figure_path,
    check_outputs,
    check_units,
    estimator_options,
    is_bag,
    make_config,
    optional_extra,
    parquet_metadata,
    progress_bar,
    tare_warnings,
)  # fmt: skip
from softtip.cli.types import check_lowpass, option
from softtip.errors import InputError
from softtip.estimator.results import EstimatorWarning
from softtip.estimator.tare import bias_to_toml
from softtip.fingertip import load_fingertip
from softtip.pipeline import STATES
from softtip.pipeline import estimate as run_estimate
from softtip.units import UNIT_SYSTEMS, wrench_to_si

__all__ = ["estimate"]

@click.command(
    "estimate",
    help="""Estimate contact point, normal, spin torque, contact state and edge direction
from a force/torque log.

INPUT is a CSV file with a header row and columns t, fx, fy, fz, mx, my, mz (t in s,
non-decreasing: repeated stamps are counted and reported; extra columns are kept and copied
to the output), or a Parquet file with those columns (name ending in .parquet; its
softtip.units metadata gives the units). '-' reads CSV from standard input. With
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
writes the estimates as a rosbag2 (MCAP) with standard messages on /softtip/state,
/softtip/contact_point, /softtip/normal, /softtip/edge_direction and /softtip/wrench, plus
the raw wrench; with --to-bag and no -o no CSV is written.

"""
    + FRAMES_HELP
)
@click.argument("input_path", metavar="INPUT", required=False, type=click.Path(allow_dash=True))
@option("--example", is_flag=True, help="Use the shipped example grasp (a 45° line contact, murakami2006 tip) as INPUT.")
@option("-o", "--output", type=click.Path(dir_okay=False, writable=True), help="Output CSV, or Parquet for a name ending in .parquet (default: CSV on standard output).")
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
@option("--to-bag", "to_bag", type=click.Path(file_okay=False), metavar="DIR", help="Also write the estimates as a rosbag2 directory (MCAP storage); DIR must not exist.")
@option("--rerun", "rerun_spawn", is_flag=True, help="Show the fingertip, force, contact point, normal and edge in a Rerun viewer (needs the rerun-sdk package).")
@option("--rerun-save", type=click.Path(dir_okay=False), metavar="FILE.rrd", help="Save the Rerun 3-D view and time series to FILE.rrd (open with `rerun FILE.rrd`).")
@option("--payload", type=click.Path(dir_okay=False), metavar="FILE.toml", help="Remove the fingertip's weight ([payload] mass kg, com m; see calibrate-payload) before taring, using INPUT's qw, qx, qy, qz columns (sensor frame in a z-up world frame).")
@option("-q", "--quiet", is_flag=True, help="No summary on standard error (warnings and errors still are).")
@option("--save-bias", type=click.Path(dir_okay=False), metavar="FILE.toml", help="Write the bias used (the tare's) to FILE.toml, for --bias of a later run.")
@estimator_options
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
    **estimator_opts,
):
    from softtip.examples import EXAMPLE_PATH
    from softtip.io import Log, read_log

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
    if rerun_spawn:  # at once: without a display the viewer would fail only after the whole run
        from softtip.viz import check_viewer  # rerun itself is imported later

        check_viewer()
    fingertip = load_fingertip(tip)
    config = make_config(estimator_opts, tip=fingertip)

    bag_log = None
    if example:
        log = read_log(EXAMPLE_PATH, units="si")
    elif input_path == "-":
        log = read_log(sys.stdin, units=units)
    elif is_bag(input_path):
        bag = optional_extra("softtip.bag", "ros")
        bag_log = bag.read_bag(input_path, topic, allow_partial=allow_partial)
        bag_warnings(input_path, bag_log)
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
        size = os.path.getsize(input_path) if os.path.isfile(input_path) else 0
        with progress_bar(size, "reading", unit="B") as bar:
            log = read_log(input_path, units=units, progress=bar.update)
    for note in log.warnings:  # repeated stamps, an implausible time scale, a cut last line
        click.echo(f"softtip: warning: {note}", err=True)
    if topic is not None and bag_log is None:
        raise click.UsageError("--topic applies to bag input only")
    if allow_partial and bag_log is None:
        raise click.UsageError("--allow-partial applies to bag input only")
    if payload is not None:  # gravity compensation first: the tare then removes only the sensor bias
        from softtip.payload import compensate_log

        log = compensate_log(log, payload)
    check_lowpass(estimator_opts["lowpass"], log.t)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", EstimatorWarning)  # printed below, from est.warnings
            est = run_estimate(log.t, log.wrench, fingertip, config)
    except ValueError as exc:  # e.g. a low-pass cutoff above Nyquist for this log's rate
        raise click.UsageError(str(exc)) from None
    check_units(est, fingertip, config, log.units, log.source)

    columns = est.columns(units=output_units)
    for name, values in log.extra.items():
        columns[name if name not in columns else f"input_{name}"] = np.asarray(values)

    source = "example grasp" if example else Path(log.source).name
    _write_estimate_outputs(
        est, columns, log, bag_log, config, fingertip,
        output=output, plot_path=plot_path, plot_units=plot_units, title=f"softtip: {source}",
        to_bag=to_bag, rerun_spawn=rerun_spawn, rerun_save=rerun_save,
        metadata=parquet_metadata(fingertip, tip, output_units, log),
    )  # fmt: skip

    counts = {name: int(np.count_nonzero(est.state == code)) for code, name in enumerate(STATES)}
    tare_warnings(est)
    if save_bias is not None:
        if any(p is not None and Path(p).resolve() == Path(save_bias).resolve() for p in (input_path, output, plot_path)):
            raise InputError(f"--save-bias {save_bias}: is also an input or output of this run")
        if not np.all(np.isfinite(est.bias)):
            raise InputError(f"--save-bias {save_bias}: no bias: the whole log lies within the tare")
        from softtip.calibration import atomic_write_text

        atomic_write_text(save_bias, bias_to_toml(est.bias, f"softtip sensor bias ({est.tare.summary()})"))
        click.echo(f"softtip: bias -> {save_bias}", err=True)
    if est.n_pulling:
        click.echo(
            f"softtip: warning: {est.n_pulling} sample(s) in contact by force had no contact point where the force "
            "pushes into the fingertip; reported as none",
            err=True,
        )
    if quiet:
        return
    # the summary goes to standard error whatever the output: per contact, since samples
    # pooled over several contacts (a -45° grasp, then a +45° one) have no common direction
    from softtip.summary import format_summary, summarise_contacts

    targets = [p for p in (output, to_bag, rerun_save) if p is not None] or ["standard output"]
    confirmed = int(np.count_nonzero(est.line_evidence == 2))
    summary = ", ".join(f"{v} {k}" + (f" ({confirmed} confirmed)" if k == "line" else "") for k, v in counts.items())
    click.echo(
        f"softtip: {len(est)} samples ({summary}; {est.n_contacts} contact(s)) -> {', '.join(map(str, targets))}",
        err=True,
    )
    for line in format_summary(summarise_contacts(est)):
        click.echo(f"softtip: {line}", err=True)


def _write_estimate_outputs(
    est, columns, log, bag_log, config, fingertip, *, output, plot_path, plot_units, title, to_bag, rerun_spawn, rerun_save,
    metadata,
) -> None:
    """Write every output of ``estimate``; all appear together, or none (and no temporary file stays)."""
    import io as _io

    from softtip.atomic import AtomicFile, cannot_write, commit_all, write_stdout
    from softtip.io import write_table

    viz = optional_extra("softtip.viz", "viz") if (rerun_spawn or rerun_save) else None
    pending: list[AtomicFile] = []
    bag_written = False
    try:
        if plot_path is not None:
            from softtip.plot import plot_estimates

            # drawn in memory first: a full disk then gives the OS's reason, not the image writer's
            image = _io.BytesIO()
            threshold = config.line_threshold(est.h_std)
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
            bag = optional_extra("softtip.bag", "ros")
            if bag_log is not None:
                bag.write_estimates_bag(to_bag, est, bag_log.wrench, bag_log.stamps_ns, bag_log.frame_id, bag_log.topic)
            else:
                bag.write_estimates_bag(to_bag, est, log.wrench)
            bag_written = True
        # the table last, atomically (softtip.atomic, through write_table); then the others are put in place
        if output is not None:
            with progress_bar(len(est), "writing") as bar:
                write_table(columns, output, metadata=metadata, progress=bar.update)
        elif to_bag is None:
            with progress_bar(len(est), "writing") as bar:
                write_stdout(lambda out: write_table(columns, out, progress=bar.update))
        commit_all(pending)
        bag_written = False  # every output is in place: keep the bag
    finally:
        for f in pending:
            f.discard()
        if bag_written:
            shutil.rmtree(to_bag, ignore_errors=True)


