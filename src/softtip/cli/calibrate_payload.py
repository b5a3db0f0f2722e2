"""``softtip calibrate-payload``: the fingertip's mass, centre of mass and the sensor bias from a still log."""

from __future__ import annotations

import click

from softtip.cli.calibrate import _check_output, _example_or_log, _fail, _read
from softtip.cli.options import full_scale_option, full_scale_range, log_format_kwargs, log_format_options
from softtip.cli.types import dash_is_stdout, option
from softtip.core.fullscale import check_full_scale
from softtip.core.gravity import check_payload
from softtip.core.units import UNIT_SYSTEMS
from softtip.errors import InputError
from softtip.io.atomic import write_stdout
from softtip.io.examples import EXAMPLE_STILL_PATH

__all__ = ["calibrate_payload"]


@click.command(
    "calibrate-payload",
    help="""Estimate the fingertip's mass, centre of mass and the sensor bias.

LOG is a log (CSV, Parquet or Arrow: t, fx, fy, fz, mx, my, mz, qw, qx, qy, qz; '-' reads standard input)
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
@click.argument("input_path", metavar="LOG", required=False, type=click.Path(allow_dash=True, dir_okay=False))
@option("-o", "--output", type=click.Path(dir_okay=False, allow_dash=True), callback=dash_is_stdout, help="Payload TOML file to write (default, or '-': standard output).")
@option("--units", type=click.Choice(UNIT_SYSTEMS), default=None, help="Units of the log's wrench: si (N, N·m) or kgf-mm (kgf, kgf·mm, the papers').  [default: si, or a Parquet or Arrow LOG's own]")
@option("--example", is_flag=True, help="Use the shipped example still log (simulated: a 20 g fingertip, centre of mass 1, -0.5, 20 mm, in 12 orientations) as LOG.")
@full_scale_option
@log_format_options
@click.pass_context
def calibrate_payload(ctx, input_path, output, units, example, full_scale=None, **log_format):
    from softtip.calibration.payload import calibrate_payload as fit_payload
    from softtip.estimator.tare import bias_to_toml
    from softtip.io.atomic import atomic_write_text
    from softtip.io.payload import read_orientation

    input_path = _example_or_log(input_path, example, units, EXAMPLE_STILL_PATH, "still log")
    sensor_range = full_scale_range(full_scale, None)  # default: a Nano17's
    try:
        _check_output(input_path, output)
        log = _read(input_path, units, **log_format_kwargs(log_format))
        # a corrupted row would move the fitted bias, which later runs take with --bias
        check_full_scale(log.t, log.wrench, sensor_range, log.source, units=log.units)
        fit = fit_payload(log.wrench, read_orientation(log), source=log.source)
        try:  # a log's moments in N·mm read as N·m fit a centre of mass metres away
            check_payload(fit.payload, f"{log.source}: the fitted", mass_hint="the log's forces in other units?",
                          com_hint="the log's moments in N·mm read as N·m?")  # fmt: skip
        except InputError as exc:
            raise InputError(f"{exc}; give the log's units (--units, --force-units, --moment-units)") from None
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
