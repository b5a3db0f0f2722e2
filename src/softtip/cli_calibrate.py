"""``softtip calibrate`` and ``softtip calibrate-payload``: click commands (registered in :mod:`softtip.cli`)."""

from __future__ import annotations

import sys

import click

from softtip.atomic import write_stdout
from softtip.cli_types import Number
from softtip.errors import InputError
from softtip.units import UNIT_SYSTEMS

__all__ = ["calibrate", "calibrate_payload"]


def _read(input_path: str, units: str):
    from softtip.io import read_log

    return read_log(sys.stdin if input_path == "-" else input_path, units=units)


def _check_output(input_path: str, output: str | None) -> None:
    from softtip.atomic import check_distinct

    check_distinct([("LOG", input_path)], [("-o", output)])


def _fail(ctx: click.Context, exc: InputError) -> None:
    # the same message and exit code as the main group gives, also when called on its own
    click.echo(f"softtip: error: {exc}", err=True)
    ctx.exit(2)


@click.command(
    "calibrate",
    help="""Calibrate the fingertip geometry from a probing log of plane presses.

LOG is a CSV log (t, fx, fy, fz, mx, my, mz; '-' reads standard input) of the fingertip
pressed against a flat, rigid surface at many points spread over the skin (15 or more,
±60° around the tip; untouched for the first --tare-duration seconds). During each press
the surface must not rotate relative to the fingertip, and it should slide a little (or
the finger rock) so that the friction force turns by 10° or more: that is what pins each
contact point. softtip fits the centre (sphere) or the cap centre (capsule: axis along z,
cap centre height = length) and the radius by nonlinear least squares over every sample,
with the skin's indentation (∝ √force) as a nuisance parameter, and prints the estimates
with standard deviations and the residual. Refuses (exit 2) when the presses do not
excite enough directions.

Writes a SPEC §2 fingertip TOML file (-o, atomically; standard output otherwise) for
--tip. A capsule's x, y axis offset cannot be stored in the file: it is reported (and
warned about when significant).
""",
)
@click.argument("input_path", metavar="LOG", type=click.Path(allow_dash=True, dir_okay=False))
@click.option("--shape", type=click.Choice(["sphere", "capsule"]), required=True, help="Fingertip shape to fit.")
@click.option("-o", "--output", type=click.Path(dir_okay=False), help="Fingertip TOML file to write (default: standard output).")
@click.option("--units", type=click.Choice(UNIT_SYSTEMS), default="si", show_default=True, help="Units of the log's wrench.")
@click.option("--tare-duration", type=Number("s", 0.0), default=0.2, show_default=True, metavar="S", help="Average the first S seconds (untouched) as the sensor bias; 0 if LOG is tared.")
@click.option("--contact-threshold", type=Number("N", 0.0, min_open=True), default=0.05, show_default=True, metavar="N", help="A press lasts while |f| is at least this, N.")
@click.option("--min-force", type=Number("N", 0.0), default=0.5, show_default=True, metavar="N", help="Only samples with |f| at least this enter the fit, N.")
@click.option("--rigid", is_flag=True, help="Do not fit the skin's indentation (radius then comes out short by about the indentation).")
@click.pass_context
def calibrate(ctx, input_path, shape, output, units, tare_duration, contact_threshold, min_force, rigid):
    from softtip.calibration import calibrate_fingertip, write_fingertip_toml

    try:
        _check_output(input_path, output)
        log = _read(input_path, units)
        cal = calibrate_fingertip(
            log.t, log.wrench, shape, tare_duration=tare_duration, contact_threshold=contact_threshold,
            min_force=min_force, compliance=not rigid, source=log.source,
        )  # fmt: skip
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
    if shape == "capsule" and cal.axis_offset_significant():
        x, y = cal.axis_offset * 1e3
        click.echo(
            f"softtip: warning: the capsule's axis is offset by x = {x:+.3f} mm, y = {y:+.3f} mm from the sensor z axis; "
            "a SPEC §2 capsule file cannot hold it (not applied): check the mounting, or calibrate as a sphere",
            err=True,
        )


@click.command(
    "calibrate-payload",
    help="""Estimate the fingertip's mass, centre of mass and the sensor bias.

LOG is a CSV log (t, fx, fy, fz, mx, my, mz, qw, qx, qy, qz; '-' reads standard input)
recorded with nothing touching the fingertip while the finger takes varied orientations
(±45° or more about at least two axes). qw, qx, qy, qz is the unit quaternion of the
sensor frame in a gravity-aligned world frame (world z up). Linear least squares on
wrench = bias + (m g_s, c × m g_s), g_s = Rᵀ (0, 0, −9.80665); prints the estimates with
standard deviations and refuses (exit 2) when the orientations do not vary enough.

Writes a payload TOML file ([payload] mass = kg, com = [x, y, z] m; -o, atomically;
standard output otherwise) for `softtip estimate --payload` and `softtip stream --payload`;
its [bias] table is the sensor bias without the fingertip's weight, for --bias FILE
together with --payload (no tare needed).
""",
)
@click.argument("input_path", metavar="LOG", type=click.Path(allow_dash=True, dir_okay=False))
@click.option("-o", "--output", type=click.Path(dir_okay=False), help="Payload TOML file to write (default: standard output).")
@click.option("--units", type=click.Choice(UNIT_SYSTEMS), default="si", show_default=True, help="Units of the log's wrench.")
@click.pass_context
def calibrate_payload(ctx, input_path, output, units):
    from softtip.calibration import atomic_write_text
    from softtip.estimator.tare import bias_to_toml
    from softtip.payload import calibrate_payload as fit_payload
    from softtip.payload import read_orientation

    try:
        _check_output(input_path, output)
        log = _read(input_path, units)
        fit = fit_payload(log.wrench, read_orientation(log), source=log.source)
        b = fit.bias
        text = (
            f"# softtip calibrate-payload {log.source}: {fit.n_samples} samples; mass std {fit.mass_std * 1e3:.3f} g, "
            "com std " + ", ".join(f"{v * 1e3:.3f}" for v in fit.com_std) + " mm\n"
            "# sensor bias (removed by the tare, not used): force "
            + ", ".join(f"{v:.5g}" for v in b[:3]) + " N, moment " + ", ".join(f"{v:.5g}" for v in b[3:]) + " N·m\n"
            + fit.payload.to_toml()
            + "# the sensor bias without the fingertip's weight: for --bias together with --payload\n"
            + bias_to_toml(b)
        )
        if output is not None:
            atomic_write_text(output, text)
            click.echo(fit.summary())
            click.echo(f"softtip: payload -> {output}", err=True)
        else:
            click.echo(fit.summary(), err=True)
            write_stdout(text)
    except InputError as exc:
        _fail(ctx, exc)
