"""The ``softtip`` command: a thin shell over the library (parse, call, write)."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import click
import numpy as np

from softtip import __version__
from softtip.axial import axial_median
from softtip.errors import InputError
from softtip.fingertip import PRESETS, load_fingertip
from softtip.noise import NANO17, SensorNoise
from softtip.pipeline import STATES, EstimatorConfig, estimate as run_estimate
from softtip.units import KGF, KGF_MM, UNIT_SYSTEMS

FRAMES_HELP = """\
Frames and units: every vector is in the sensor frame (origin at the F/T sensor's
measuring point, z along the finger axis toward the tip, right-handed). Inside and in
every file softtip uses SI: N, N·m, m, s; angles are degrees in files and plots. f and m
are the force and moment the touched object exerts on the fingertip, moment about the
sensor origin; in contact f pushes into the fingertip.
"""

_FORCE_COLUMNS = ("fx", "fy", "fz")
_MOMENT_COLUMNS = ("mx", "my", "mz", "sigma", "hx", "hy", "hz", "h_norm", "h_std")


class _Group(click.Group):
    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except InputError as exc:
            click.echo(f"softtip: error: {exc}", err=True)
            ctx.exit(2)


@click.group(cls=_Group, help="softtip: intrinsic tactile sensing with a soft fingertip on a six-axis F/T sensor.\n\n" + FRAMES_HELP)
@click.version_option(__version__, prog_name="softtip")
def main() -> None:
    pass


@main.command(
    help="""Estimate contact point, normal, spin torque, contact state and edge direction
from a force/torque log.

INPUT is a CSV file with a header row and columns t, fx, fy, fz, mx, my, mz (t in s,
increasing; extra columns are kept and copied to the output). '-' reads standard input.
With --example, softtip's shipped example grasp is used instead.

The output CSV (standard output unless -o) has the columns t, state (none|point|line),
fx..mz (the wrench after bias removal and filtering, the one the estimates come from),
rx, ry, rz (contact point, m), nx, ny, nz (outward normal), sigma (spin torque about the
normal, N·m), hx, hy, hz, h_norm (tangential spin torque, N·m), dx, dy, dz (direction of
the touched edge / strip, an axis), angle_deg (its angle in the tangent frame, degrees in
(-90, 90]; at the tip: from the sensor x axis), h_std (noise level of h, N·m),
angle_std_deg, latched, latch_fallback, then the input's extra columns. r, n, h are empty
(nan) when state is none; d and the angle only for line contacts, where |h| stands out of
the noise.

"""
    + FRAMES_HELP
)
@click.argument("input_path", metavar="INPUT", required=False, type=click.Path(dir_okay=False, allow_dash=True))
@click.option("--example", is_flag=True, help="Use the shipped example grasp (a 45° line contact, murakami2006 tip) as INPUT.")
@click.option("-o", "--output", type=click.Path(dir_okay=False, writable=True), help="Output CSV (default: standard output).")
@click.option(
    "--tip",
    default="murakami2006",
    show_default=True,
    metavar="PRESET_OR_TOML",
    help=f"Fingertip: a preset ({', '.join(sorted(PRESETS))}) or a TOML file ([fingertip] shape = sphere|capsule|ellipsoid, lengths in m).",
)
@click.option(
    "--units",
    type=click.Choice(UNIT_SYSTEMS),
    default="si",
    show_default=True,
    help="Units of the input wrench: si (N, N·m) or kgf-mm (kgf, kgf·mm, the papers').",
)
@click.option(
    "--output-units",
    type=click.Choice(UNIT_SYSTEMS),
    default="si",
    show_default=True,
    help="Units of force and moment columns in the output; lengths stay in m, angles in degrees.",
)
@click.option(
    "--contact-point",
    type=click.Choice(["latch", "track"]),
    default="latch",
    show_default=True,
    help="latch: measure the contact point in the light-force window at the start of the grasp and hold it (the papers'); "
    "track: soft-finger solution every sample (h is then zero by construction: no directions).",
)
@click.option("--plot", "plot_path", type=click.Path(dir_okay=False), help="Also draw the papers' four panels (force, moment, |h|, direction) to this PNG/PDF/SVG.")
@click.option("--plot-units", type=click.Choice(UNIT_SYSTEMS), default="si", show_default=True, help="Units of the plot's force and moment axes.")
@click.option("--lowpass", type=float, metavar="HZ", help="Causal Butterworth low-pass cutoff in Hz (default: no filter).")
@click.option(
    "--tare-duration",
    type=float,
    default=0.2,
    show_default=True,
    metavar="S",
    help="Average the first S seconds (fingertip untouched) as the sensor bias; 0 if INPUT is already tared.",
)
@click.option("--contact-threshold", type=float, default=0.05, show_default=True, metavar="N", help="In contact while |f| is at least this, N.")
@click.option(
    "--latch-window",
    type=(float, float),
    default=(0.2 * KGF, 0.5 * KGF),
    show_default=True,
    metavar="LOW HIGH",
    help="Light-force window for latching the contact point, N (default 0.2–0.5 kgf).",
)
@click.option("--h-min", type=float, default=0.5, show_default=True, metavar="N·mm", help="Smallest |h| reported as a line contact, N·mm.")
@click.option(
    "--force-noise",
    type=float,
    default=NANO17.force_std[0],
    show_default=True,
    metavar="N",
    help="Per-axis standard deviation of the sensor's force noise, N (Nano17-class default).",
)
@click.option(
    "--moment-noise",
    type=float,
    default=NANO17.moment_std[0] * 1e3,
    show_default=True,
    metavar="N·mm",
    help="Per-axis standard deviation of the sensor's moment noise, N·mm.",
)
def estimate(
    input_path,
    example,
    output,
    tip,
    units,
    output_units,
    contact_point,
    plot_path,
    plot_units,
    lowpass,
    tare_duration,
    contact_threshold,
    latch_window,
    h_min,
    force_noise,
    moment_noise,
):
    from softtip.examples import EXAMPLE_PATH
    from softtip.io import read_log, write_table

    if example == (input_path is not None):
        raise click.UsageError("give either INPUT or --example")
    fingertip = load_fingertip(tip)
    try:
        config = EstimatorConfig(
            contact_point=contact_point,
            contact_threshold=contact_threshold,
            latch_window=latch_window,
            noise=SensorNoise((force_noise,) * 3, (moment_noise * 1e-3,) * 3),
            h_min=h_min * 1e-3,
            lowpass_hz=lowpass,
            tare_duration=tare_duration,
        )
    except ValueError as exc:
        raise click.UsageError(str(exc)) from None

    if example:
        log = read_log(EXAMPLE_PATH, units="si")
    elif input_path == "-":
        log = read_log(sys.stdin, units=units)
    else:
        log = read_log(input_path, units=units)
    try:
        est = run_estimate(log.t, log.wrench, fingertip, config)
    except ValueError as exc:  # e.g. a low-pass cutoff above Nyquist for this log's rate
        raise click.UsageError(str(exc)) from None

    columns = est.columns()
    if output_units == "kgf-mm":
        for name in _FORCE_COLUMNS:
            columns[name] = columns[name] / KGF
        for name in _MOMENT_COLUMNS:
            columns[name] = columns[name] / KGF_MM
    for name, values in log.extra.items():
        columns[name if name not in columns else f"input_{name}"] = np.asarray(values)

    plot_tmp = None
    try:
        if plot_path is not None:
            from softtip.plot import plot_estimates

            # drawn to a temporary file first: a failure leaves neither output behind
            plot_path = Path(plot_path)
            plot_tmp = plot_path.with_name(f".{plot_path.name}.partial{plot_path.suffix}")
            source = "example grasp" if example else Path(log.source).name
            threshold = np.maximum(config.h_sigmas * est.h_std, config.h_min)
            plot_estimates(est, plot_tmp, units=plot_units, title=f"softtip: {source}", h_threshold=threshold)
        write_table(columns, output)
        if plot_tmp is not None:
            os.replace(plot_tmp, plot_path)
            plot_tmp = None
    finally:
        if plot_tmp is not None:
            plot_tmp.unlink(missing_ok=True)

    counts = {name: int(np.count_nonzero(est.state == code)) for code, name in enumerate(STATES)}
    if est.n_pulling:
        click.echo(
            f"softtip: warning: {est.n_pulling} sample(s) in contact by force had no contact point where the force "
            "pushes into the fingertip; reported as none",
            err=True,
        )
    if output is not None:
        summary = ", ".join(f"{v} {k}" for k, v in counts.items())
        click.echo(f"softtip: {len(est)} samples ({summary}) -> {output}", err=True)
        if counts["line"]:
            line = est.state == 2
            ang = np.degrees(axial_median(est.angle[line]))
            click.echo(f"softtip: median direction of line samples {ang:+.1f} deg", err=True)


if __name__ == "__main__":  # pragma: no cover
    main()
