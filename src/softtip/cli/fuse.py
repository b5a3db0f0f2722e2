"""``softtip fuse``: two fingertips' logs fused into the grasped object's local geometry."""

from __future__ import annotations

import os
import sys
import warnings

import click
import numpy as np

from softtip.cli.bag_options import bag_output_options, output_frame_id
from softtip.cli.options import (
    check_figure_path,
    check_units,
    estimator_options,
    full_scale_option,
    full_scale_range,
    is_bag,
    log_format_kwargs,
    log_format_options,
    make_config,
    optional_extra,
    print_log_notes,
    tare_warnings,
)
from softtip.cli.types import Length, Number, dash_is_stdout, option
from softtip.core.fullscale import COARSE_MARGIN, check_full_scale
from softtip.core.units import UNIT_SYSTEMS, seconds_from_ns, wrench_to_si
from softtip.errors import InputError
from softtip.estimator.results import EstimatorWarning

__all__ = ["fuse"]


def _common_clock(paths, logs) -> list[np.ndarray]:
    """Each log's ``t`` (s) on the clock the two share: from the earlier log's first stamp where
    both have absolute stamps (each log's own ``t`` counts from its first), else as read; the
    located error where only one has them or where the logs do not overlap in time."""
    stamps = [log.stamps_ns for log in logs]
    if (stamps[0] is None) != (stamps[1] is None):
        dated, other = (0, 1) if stamps[0] is not None else (1, 0)
        raise InputError(
            f"{paths[dated]} has absolute stamps (dates) and {paths[other]} counts from its own start: expected the "
            "two logs on one clock (both dated, or both counted from the same moment)"
        )
    if stamps[0] is None:
        times = [np.asarray(log.t, dtype=float) for log in logs]
    else:
        origin = min(int(s[0]) for s in stamps)
        times = [seconds_from_ns(np.asarray(s, dtype=np.int64), origin) for s in stamps]
    (a0, a1), (b0, b1) = ((float(t[0]), float(t[-1])) for t in times)
    overlap = min(a1, b1) - max(a0, b0)
    if overlap < 0.0:
        raise InputError(
            f"the logs do not overlap in time: {paths[0]} spans {a0:.6g}–{a1:.6g} s and {paths[1]} {b0:.6g}–{b1:.6g} s"
            f"{' on their common clock (their absolute stamps)' if stamps[0] is not None else ''}; expected two "
            "fingers recorded together"
        )
    longer = max(a1 - a0, b1 - b0)  # the fused rows span the first log: any part without the other is single
    if overlap < 0.9 * longer:
        print(f"softtip: warning: the logs overlap for {overlap:.6g} s of the longer's {longer:.6g} s "
              f"({paths[0]}: {a0:.6g}–{a1:.6g} s, {paths[1]}: {b0:.6g}–{b1:.6g} s); outside it one finger is "
              "fused alone (single)", file=sys.stderr)  # fmt: skip
    return times


def _summary(fused) -> list[str]:
    names = fused.grasp_names
    lines = []
    shares = ", ".join(f"{k} {100 * np.mean(names == k):.0f} %" for k in dict.fromkeys(names.tolist()))
    lines.append(f"{len(fused)} time steps: {shares}")
    lines.append(f"fingers: 1 = {fused.names[0]}, 2 = {fused.names[1]} (columns r1_*, r2_*)")
    par = names == "parallel_lines"
    if par.any():
        d = fused.direction[par]
        d = d * np.where(d @ d[-1] < 0, -1.0, 1.0)[:, None]
        u = np.median(d, axis=0)
        u /= np.linalg.norm(u)
        nrm = fused.plane_normal[par]
        nrm = nrm * np.where(nrm @ nrm[-1] < 0, -1.0, 1.0)[:, None]
        v = np.median(nrm, axis=0)
        v /= np.linalg.norm(v)
        lines.append(
            f"parallel lines: median direction ({u[0]:+.3f}, {u[1]:+.3f}, {u[2]:+.3f}) "
            f"± {np.degrees(np.median(fused.direction_std[par])):.1f} deg, plane normal "
            f"({v[0]:+.3f}, {v[1]:+.3f}, {v[2]:+.3f}) ± {np.degrees(np.median(fused.plane_normal_std[par])):.1f} deg"
        )
    ev = fused.evidence[fused.evidence != ""]
    if len(ev):
        lines.append(f"line evidence: {100 * np.mean(ev == 'confirmed'):.0f} % of the fused time steps confirmed")
    for flag in ("unbalanced", "area"):
        k = int(np.count_nonzero(np.char.find(fused.flag.astype(str), flag) >= 0))
        if k:
            lines.append(f"warning: {k} time step(s) flagged {flag}")
    return lines


@click.command(
    "fuse",
    help="""Fuse two fingertips into the grasped object's local geometry, in a common frame.

INPUTS are either two logs (CSV, Parquet or Arrow; one per fingertip, on one clock) with the fingertips' poses
from --hand FILE.toml (a [finger.NAME] table per fingertip, in the order of the logs) or from
pose columns px, py, pz (m) and qw, qx, qy, qz in each log; or one ROS bag with --topics
(two geometry_msgs/msg/WrenchStamped topics) and --frame (the common frame), the poses
composed from the bag's /tf and /tf_static to each topic's frame_id.

Each log is estimated as by `softtip estimate` (the same options), then the pair is read
per time step of the first log: parallel_lines (a plate or a stick pinched across: the
common direction and the plane through both lines), crossing_lines (two edges: both, their
angle and closest approach), line_and_face, faces, single or none; with the evidence of the
lines (confirmed once the object was rocked about two axes) and flags (unbalanced forces,
an area contact). Writes CSV (standard output without -o), Parquet (-o ending in .parquet) or
Arrow IPC (.arrow, .feather), the contact points as r1_x..r2_z of the first and second finger given (named on standard
error), whatever the input, and the first log's absolute stamps as a last column stamp_ns (a bag's, or a log's whose t
are dates); every column, its unit and when it is NaN: the manual §8 (docs/guide/fused-columns.md). A
summary on standard error. --to-bag also writes the fused line and plane as
geometry_msgs/msg/PoseStamped (x axis along the line, z axis the plane's normal), the contacts as
PointStamped and RViz markers, in the common frame, in the format --ros-distro plays; with
--to-bag and no -o no CSV is written.
""",
)
@click.argument("inputs", nargs=-1, required=True, type=click.Path(exists=False))
@option("-o", "--output", type=click.Path(dir_okay=False, writable=True, allow_dash=True), callback=dash_is_stdout, help="Output CSV, or Parquet for a name ending in .parquet, Arrow IPC (Feather v2) for .arrow or .feather (default, or '-': CSV on standard output).")
@option("--hand", "hand_file", type=click.Path(dir_okay=False), metavar="FILE.toml", help="Fingertip poses in the common frame ([hand] frame, [finger.NAME] translation m, rpy_deg or quaternion).")
@option("--topics", nargs=2, metavar="TOPIC TOPIC", help="Bag input: the two fingertips' wrench topics.")
@option("--frame", metavar="FRAME", help="Bag input: the common frame (e.g. hand, base_link).")
@option("--units", type=click.Choice(UNIT_SYSTEMS), default=None, help="Units of the logs' wrench (CSV, Parquet, Arrow; a bag's wrench): si (N, N·m) or kgf-mm (kgf, kgf·mm, the papers').  [default: si, or a Parquet or Arrow log's own]")
@option("--object-mass", type=Number("kg", 0.0), metavar="KG", help="The object's mass for the force balance (default: unknown; any weight along gravity allowed).")
@option("--gravity", type=(Number("m/s²"), Number("m/s²"), Number("m/s²")), default=(0.0, 0.0, -9.80665), show_default=True, metavar="X Y Z", help="Gravity in the common frame, m/s².")
@option("--point-std", type=Length("mm", 0.0, min_open=True), default="0.05mm", show_default=True, metavar="LENGTH", help="Standard deviation of each contact point across its line, independent between the fingers, for the plane normal (a bare number is in mm).")
@option("--plot", "plot_path", type=click.Path(dir_okay=False), help="Also draw both forces, the grasp reading and the fused angles across the grasp to this PNG/PDF/SVG.")
@option("--rerun", "rerun_spawn", is_flag=True, help="Show both fingertips, their contacts and the fused line or plane in the hand frame in a Rerun viewer (needs rerun-sdk).")
@option("--rerun-save", type=click.Path(dir_okay=False), metavar="FILE.rrd", help="Save that 3-D view and the fused series to FILE.rrd.")
@option("--truth", "truth_file", type=click.Path(dir_okay=False), metavar="FILE.json", help="The simulator's truth.json: the object's true line and plane drawn in the Rerun view and the --plot figure.")
@bag_output_options(frame_default="the common frame: --frame, the hand file's, else hand")
@log_format_options
@estimator_options
@full_scale_option
def fuse(inputs, output, hand_file, topics, frame, units, object_mass, gravity, point_std, plot_path, rerun_spawn, rerun_save,
         truth_file, tip, to_bag=None, ros_distro=None, frame_id=None, full_scale=None, **estimator_opts):  # fmt: skip
    from softtip.core.fingertip import load_fingertip
    from softtip.fusion import fuse_logs, poses_from_columns, read_hand_file
    from softtip.io.tables import read_log, write_table

    formats = log_format_kwargs(estimator_opts)
    if plot_path is not None:
        check_figure_path(plot_path)
    if truth_file is not None and not (rerun_spawn or rerun_save or plot_path):
        raise click.UsageError("--truth draws into the Rerun view or the figure: give --rerun, --rerun-save or --plot")
    if rerun_spawn or rerun_save:
        optional_extra("softtip.viz.rerun", "viz")
    if rerun_spawn:  # at once: without a display the viewer would fail only after the fusion
        from softtip.viz.rerun import check_viewer

        check_viewer()
    from softtip.io.atomic import check_distinct

    check_distinct(
        [("INPUT", p) for p in inputs] + [("--hand", hand_file), ("--bias", estimator_opts.get("bias_file")), ("--truth", truth_file)],
        [("-o", output), ("--plot", plot_path), ("--to-bag", to_bag), ("--rerun-save", rerun_save)],
    )
    if to_bag is None and (ros_distro is not None or frame_id is not None):
        raise click.UsageError("--ros-distro and --frame-id apply to --to-bag")
    if to_bag is not None:
        from softtip.ros.bagout import bag_format

        bag_format(to_bag, ros_distro)
    fingertip = load_fingertip(tip)
    config = make_config(estimator_opts)
    if len(inputs) == 1:
        if not is_bag(inputs[0]):
            raise click.UsageError(f"one log ({inputs[0]}); expected two logs, one per finger (or one bag with "
                                   "--topics TOPIC TOPIC and --frame FRAME)")  # fmt: skip
        if topics is None or frame is None:
            raise click.UsageError("a bag input needs --topics TOPIC TOPIC and --frame FRAME")
        if hand_file is not None:
            raise click.UsageError("--hand applies to CSV inputs; a bag's poses come from its /tf")
        bag = optional_extra("softtip.io.bag", "ros")
        from softtip.fusion.tf import read_tf

        path = inputs[0]
        blogs = [bag.read_bag(path, tp) for tp in topics]
        tree = read_tf(path)
        origin = min(int(b.stamps_ns[0]) for b in blogs)
        common, stamps = frame, blogs[0].stamps_ns
        stamp_ns = np.asarray(stamps, dtype=np.int64)  # the first topic's, whose samples the fused rows are
        logs = []
        for b in blogs:
            if not b.frame_id:
                raise InputError(f"{path}: topic {b.topic!r} has an empty header.frame_id; cannot place it with /tf")
            pose = tree.poses(frame, b.frame_id, b.stamps_ns, origin_ns=origin)
            t, wrench = seconds_from_ns(b.stamps_ns, origin), wrench_to_si(b.wrench, units or "si")
            check_full_scale(t, wrench, full_scale_range(full_scale, estimator_opts.get("sensor")), f"{path} {b.topic}",
                             units=units or "si")  # fmt: skip
            logs.append((b.topic, t, wrench, pose))
    elif len(inputs) == 2:
        if topics is not None or frame is not None:
            raise click.UsageError("--topics and --frame apply to a bag input")
        if all(os.path.isfile(p) for p in inputs) and os.path.samefile(*inputs):
            raise click.UsageError(f"{inputs[0]} and {inputs[1]} are the same file; expected one log per finger")
        read = [read_log(p, units=units, **formats) for p in inputs]
        sensor_range = full_scale_range(full_scale, estimator_opts.get("sensor"))
        for log, path in zip(read, inputs):  # far beyond the sensor's range: refused before any estimate, as by estimate
            check_full_scale(log.t, log.wrench, sensor_range, str(path), units=log.units, margin=COARSE_MARGIN)
        for log in read:
            print_log_notes(log)
        times = _common_clock(inputs, read)
        common = "hand"  # pose columns name no frame
        if hand_file is not None:
            hand = read_hand_file(hand_file)
            if len(hand.fingers) != 2:
                raise InputError(f"{hand_file}: {len(hand.fingers)} [finger.NAME] tables; expected two, in the order of the logs")
            poses = list(hand.fingers.items())
            common = hand.frame
        else:
            poses = [(os.path.basename(p), poses_from_columns(t, log.extra, os.path.basename(p), p))
                     for p, log, t in zip(inputs, read, times)]  # fmt: skip
        logs = [(name, t, log.wrench, pose) for (name, pose), log, t in zip(poses, read, times)]
        print(f"softtip: finger 1 ({poses[0][0]}) <- {inputs[0]}, finger 2 ({poses[1][0]}) <- {inputs[1]}", file=sys.stderr)
        stamp_ns = read[0].stamps_ns  # the first log's absolute stamps, where it had them
        stamps = stamp_ns if stamp_ns is not None else np.rint(times[0] * 1e9).astype(np.int64)
    else:
        raise click.UsageError(f"expected two logs or one bag, got {len(inputs)} inputs")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", EstimatorWarning)  # said below, finger by finger
            fused, fingers = fuse_logs(
                logs, fingertip, config, object_mass=object_mass, gravity=gravity, point_std=point_std
            )
    except ValueError as exc:
        raise click.UsageError(str(exc)) from None
    for finger in fingers:
        tare_warnings(finger.estimates, name=finger.name)
    if len(inputs) == 2:  # units the files say or the options give: checked as `estimate` checks them
        for finger, log, path in zip(fingers, read, inputs):
            check_units(finger.estimates, fingertip, config, log, source=str(path))
            check_full_scale(log.t, log.wrench, sensor_range, str(path), units=log.units)  # just beyond: after the units
    truth = None
    if truth_file:
        from softtip.fusion.viz import read_truth

        truth = read_truth(truth_file, fused.t)
    from softtip.io.atomic import Outputs, cannot_write

    table = fused.columns()
    if stamp_ns is not None and len(stamp_ns) == len(fused.t):  # as `estimate` keeps them: a last column
        table["stamp_ns"] = np.asarray(stamp_ns, dtype=np.int64)

    # one transaction for every output: all appear, or none (an error, a signal)
    with Outputs() as outputs:
        staged = {p: outputs.file(p) for p in (output, plot_path, rerun_save) if p is not None}
        staged_bag = outputs.path(to_bag) if to_bag is not None else None
        if rerun_spawn or rerun_save:
            from softtip.fusion.viz import log_fused

            log_fused(
                fused, fingers, fingertip, save=staged[rerun_save].tmp if rerun_save else None, spawn=rerun_spawn,
                truth=truth,
            )  # fmt: skip
        if to_bag is not None:  # the fused grasp as standard messages (softtip.ros.fused)
            from softtip.ros.fused import write_fused_bag

            try:
                write_fused_bag(staged_bag, fused, fingers, stamps, output_frame_id(frame_id, common), distro=ros_distro)
            except InputError as exc:  # name the destination, not where it was staged
                raise InputError(str(exc).replace(str(staged_bag), str(to_bag))) from None
        if plot_path is not None:
            from softtip.fusion.plot import plot_fused

            up = -np.asarray(gravity) if np.linalg.norm(gravity) > 0 else (0.0, 0.0, 1.0)
            plot_fused(fused, fingers, staged[plot_path].tmp, up=up, truth_line=None if truth is None else truth["line"],
                       truth_normal=None if truth is None else truth["plane_normal"])  # fmt: skip
        if output is not None:
            from softtip.io.formats import table_format
            from softtip.io.tables import TableWriter

            try:
                with staged[output].open() as fh, TableWriter(fh, format=table_format(output)) as writer:
                    writer.write(table)
            except OSError as exc:
                raise cannot_write(output, exc) from None
        elif to_bag is None:
            from softtip.io.atomic import write_stdout

            write_stdout(lambda out: write_table(table, out))
    for line in _summary(fused):
        click.echo(f"softtip: {line}", err=True)

