"""``softtip calibrate``: the fingertip geometry from a probing log (and the helpers ``calibrate-payload`` shares)."""

from __future__ import annotations

import os
import sys

import click

from softtip.cli.options import (
    MAX_FORCE_NOISE,
    MAX_MOMENT_NOISE_NMM,
    full_scale_option,
    full_scale_range,
    log_format_kwargs,
    log_format_options,
    sensor_noise,
)
from softtip.cli.types import Length, Number, dash_is_stdout, option
from softtip.core.fingertip import SHAPES
from softtip.core.fullscale import check_full_scale
from softtip.core.noise import NANO17, NOISE_PRESETS
from softtip.core.units import UNIT_SYSTEMS
from softtip.errors import InputError
from softtip.io.atomic import write_stdout
from softtip.io.examples import EXAMPLE_PROBING_PATH

__all__ = ["calibrate"]

#: ``--shape``'s choices: the fingertip shapes that calibrate (from presses, or a mesh's placement).
CALIBRATED_SHAPES = [name for name, cls in SHAPES.items() if cls.calibrates is not None]


def _read(input_path: str, units: str | None, **formats):
    """The log (``formats``: :func:`~softtip.cli.options.log_format_kwargs`), its notes said on stderr."""
    from softtip.cli.options import print_log_notes
    from softtip.io.tables import read_log

    log = read_log(getattr(sys.stdin, "buffer", sys.stdin) if input_path == "-" else input_path, units=units, **formats)
    print_log_notes(log)
    return log


def _example_or_log(input_path, example: bool, units: str | None, path, what: str) -> str:
    if example == (input_path is not None):
        raise click.UsageError(f"give either LOG or --example (the shipped example {what})")
    if example and units not in (None, "si"):
        raise click.UsageError(f"--units applies to LOG; the example {what} is in SI")
    return str(path) if example else input_path


def _check_calibrated_size(tip, log) -> None:
    """Stop a calibrated fingertip of no fingertip's size (:func:`softtip.core.shape.check_size`):
    the size follows the log's moment-to-force ratio, so it names the unit pairs that give a
    fingertip's size (moments in N·mm read as N·m calibrate a tip 1000 times too small)."""
    from softtip.core.lever import describe_pairs, pair_scales
    from softtip.core.shape import SIZE_RANGE, check_size
    from softtip.core.units import find_unit

    force_unit, moment_unit = getattr(log, "force_unit", "N"), getattr(log, "moment_unit", "N*m")
    size = 2.0 * float(tip.bounding_sphere[1])
    lo, hi = SIZE_RANGE
    given = (find_unit(force_unit, "force").name, find_unit(moment_unit, "moment").name)
    fits = [pair for pair, (kf, km) in pair_scales(force_unit, moment_unit).items()
            if pair != given and lo <= size * km / kf <= hi]  # fmt: skip (as the units check scales the lever)
    check_size(tip, log.source, fix="the log's moment-to-force ratio sets the size, so are its units right? "
               f"{describe_pairs(fits, given, options=not getattr(log, 'units_in_header', ()))}; or is it not a probing of "
               "this fingertip?")  # fmt: skip


def _check_output(input_path: str, output: str | None) -> None:
    from softtip.io.atomic import check_distinct

    check_distinct([("LOG", input_path)], [("-o", output)])


def _fail(ctx: click.Context, exc: InputError) -> None:
    # the same message and exit code as the main group gives, also when called on its own
    click.echo(f"softtip: error: {exc}", err=True)
    ctx.exit(2)


_NO_SKIN_THICKNESS = (
    "softtip: the fingertip file has no skin_thickness, so estimate's depth compensation (on for the "
    "murakami2006 preset) stays off for it; give --skin-thickness (the soft skin's thickness) to turn it on"
)


@click.command(
    "calibrate",
    help="""Calibrate the fingertip geometry from a probing log of plane presses.

LOG is a CSV log (t, fx, fy, fz, mx, my, mz; '-' reads standard input) of the fingertip
pressed against a flat, rigid surface at many points spread over the skin (20 or more,
±60° around the tip; untouched for the first --tare-duration seconds), for instance
recorded by `softtip stream --netft ADDRESS --record probe.csv` (of a recording, the raw
columns fx_raw..mz_raw are used). During each press the
surface must not tilt relative to the fingertip, and it should slide a little sideways so
that the friction force turns (40° or more): that is what pins each contact point.
--guide prints the procedure step by step; --example runs on a shipped simulated log.

softtip fits the centre (sphere, ellipsoid) or the cap centre (capsule: axis parallel to
z, cap centre height = length) and the radius (the ellipsoid's three semi-axes, its axes
along the sensor's) by nonlinear least squares over every sample,
with the skin's indentation (∝ √force) as a nuisance parameter, and prints the estimates
with standard deviations and the residual. Each sample is weighted by its noise, propagated
from the sensor noise model (--force-noise, --moment-noise) through the lever arm, so the
force noise does not bias the geometry; the standard deviations are scaled by the
residual's ratio to that model. Refuses (exit 2) when the presses do not excite enough
directions.

Writes a fingertip TOML file (-o, atomically; standard output otherwise) for --tip; a
capsule's offset of its axis from the sensor's z axis is its axis_offset.
""",
)
@click.argument("input_path", metavar="LOG", required=False, type=click.Path(allow_dash=True, dir_okay=False))
@option("--shape", type=click.Choice(CALIBRATED_SHAPES), help="Fingertip shape to fit (required unless --guide; mesh: the placement of --mesh on the sensor).")
@option("--example", is_flag=True, help="Use the shipped example probing log (simulated: 30 presses on a 16 mm sphere centred at 0.3, -0.2, 20.0 mm) as LOG.")
@option("--guide", is_flag=True, help="Print how to record a probing log (where, how hard and how to press) and exit.")
@option("-o", "--output", type=click.Path(dir_okay=False, allow_dash=True), callback=dash_is_stdout, help="Fingertip TOML file to write (default, or '-': standard output).")
@option("--units", type=click.Choice(UNIT_SYSTEMS), default=None, help="Units of the log's wrench: si (N, N·m) or kgf-mm (kgf, kgf·mm, the papers').  [default: si, or a Parquet or Arrow LOG's own]")
@option("--tare-duration", type=Number("s", 0.0), default=0.2, show_default=True, metavar="S", help="Average the first S seconds (untouched) as the sensor bias; 0 if LOG is tared.")
@option("--contact-threshold", type=Number("N", 0.0, min_open=True), default=0.05, show_default=True, metavar="N", help="A press lasts while |f| is at least this (at least 4 times the force noise's magnitude), N.")
@option("--min-force", type=Number("N", 0.0), default=0.5, show_default=True, metavar="N", help="Only samples with |f| at least this enter the fit, N.")
@option("--rigid", is_flag=True, help="Do not fit the skin's indentation (radius then comes out short by about the indentation).")
@option("--mesh", "mesh_path", type=click.Path(dir_okay=False), help="--shape mesh: the fingertip mesh (a mesh fingertip .toml, or .stl/.obj/.ply with --mesh-units); its shift on the sensor is fitted.")
@option("--mesh-units", type=click.Choice(["m", "cm", "mm", "um", "in"]), help="Length unit of a bare --mesh file.")
@option("--rotation", is_flag=True, help="--shape mesh: fit a small rotation as well as the shift (6 DOF).")
@option("--force-noise", type=Number("N", 0.0, MAX_FORCE_NOISE, min_open=True), default=NANO17.force_std[0], show_default=True, metavar="N", help="Per-axis standard deviation of the sensor's force noise, N (Nano17-class default).")
@option("--moment-noise", type=Number("N·mm", 0.0, MAX_MOMENT_NOISE_NMM, min_open=True), default=NANO17.moment_std[0] * 1e3, show_default=True, metavar="N·mm", help="Per-axis standard deviation of the sensor's moment noise, N·mm.")
@option("--sensor", type=click.Choice(list(NOISE_PRESETS)), help="The sensor's noise preset for --force-noise and --moment-noise where they are not given. [default: nano17]")
@option(
    "--skin-thickness", type=Length("mm", 0.0, min_open=True), metavar="LENGTH",
    help="Thickness of the fingertip's soft skin (5mm; a bare number is in mm), written into the fingertip file: "
    "estimate's depth compensation needs it and is off for a file without it.",
)  # fmt: skip
@full_scale_option
@log_format_options
@click.pass_context
def calibrate(
    ctx, input_path, shape, output, units, tare_duration, contact_threshold, min_force, rigid, force_noise, moment_noise,
    example, guide, mesh_path, mesh_units, rotation, skin_thickness=None, sensor=None, full_scale=None, **log_format,
):
    from softtip.calibration.probing import (
        PROBING_GUIDE,
        calibrate_fingertip,
        write_fingertip_toml,
    )

    formats = log_format_kwargs(log_format)
    if guide:
        click.echo(PROBING_GUIDE)
        return
    sensor_range = full_scale_range(full_scale, sensor)  # default: the --sensor's, else a Nano17's
    if shape is None:
        raise click.UsageError(f"Missing option '--shape' ({', '.join(CALIBRATED_SHAPES[:-1])} or {CALIBRATED_SHAPES[-1]}).")
    placement = SHAPES[shape].calibrates == "placement"  # a mesh's pose on the sensor: softtip.calibration.mesh
    if placement or mesh_path is not None:
        if example or input_path is None:
            raise click.UsageError("--shape mesh needs a probing LOG of the mesh fingertip (the example is a sphere's)")
        from softtip.calibration.mesh import calibrate_mesh_file
        from softtip.io.atomic import atomic_write_text

        try:
            if not placement or mesh_path is None or rigid:
                raise InputError("--shape mesh goes with --mesh FILE (and without --rigid)")
            log = _read(input_path, units, **formats)
            check_full_scale(log.t, log.wrench, sensor_range, log.source, units=log.units)
            cal = calibrate_mesh_file(
                log.t, log.wrench, mesh_path, mesh_units, skin_thickness=skin_thickness, rotation=rotation,
                tare_duration=tare_duration, contact_threshold=contact_threshold, min_force=min_force,
            )  # fmt: skip
            if output is not None:
                atomic_write_text(output, cal.tip.to_toml(os.path.dirname(os.path.abspath(output))))
                click.echo(cal.summary())
                click.echo(f"softtip: fingertip -> {output}", err=True)
            else:
                click.echo(cal.summary(), err=True)
                click.echo(cal.tip.to_toml(), nl=False)
        except InputError as exc:
            _fail(ctx, exc)
            return
        _tare_warnings(cal)
        for warning in (cal.fit_warning, cal.precision_warning()):
            if warning:
                click.echo(f"softtip: warning: {warning}", err=True)
        if cal.tip.skin_thickness is None:
            click.echo(_NO_SKIN_THICKNESS, err=True)
        return
    input_path = _example_or_log(input_path, example, units, EXAMPLE_PROBING_PATH, "probing log")
    try:
        _check_output(input_path, output)
        log = _read(input_path, units, **formats)  # a `stream --record` file: its fx_raw..mz_raw (the registry)
        check_full_scale(log.t, log.wrench, sensor_range, log.source, units=log.units)
        cal = calibrate_fingertip(
            log.t, log.wrench, shape, tare_duration=tare_duration, contact_threshold=contact_threshold,
            min_force=min_force, compliance=not rigid, source=log.source,
            noise=sensor_noise(sensor, force_noise, moment_noise),
        )  # fmt: skip
        if skin_thickness is not None:
            from dataclasses import replace

            cal = replace(cal, tip=replace(cal.tip, skin_thickness=skin_thickness))
        _check_calibrated_size(cal.tip, log)
        if skin_thickness is None:
            click.echo(_NO_SKIN_THICKNESS, err=True)
        report = cal.summary()
        if output is not None:
            write_fingertip_toml(cal, output, source=log.source)
            click.echo(report)
            click.echo(f"softtip: fingertip -> {output}", err=True)
        else:
            click.echo(report, err=True)
            write_stdout(cal.tip.to_toml())
    except InputError as exc:
        _fail(ctx, exc)
        return
    _tare_warnings(cal)
    if cal.warning:
        click.echo(f"softtip: warning: {cal.warning}", err=True)
    elif cal.precision_warning():
        click.echo(f"softtip: warning: {cal.precision_warning()}", err=True)
    if cal.noise_warning:
        click.echo(
            f"softtip: warning: {cal.noise_warning} (--force-noise {force_noise:g} N, --moment-noise {moment_noise:g} N·mm)",
            err=True,
        )


def _tare_warnings(cal) -> None:
    """The warnings of the calibration's tare (spikes left out, a fingertip touched while taring)."""
    for note in cal.tare.warnings if cal.tare is not None else ():
        click.echo(f"softtip: warning: {note}", err=True)
