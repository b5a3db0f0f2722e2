"""``softtip reproduce``: the papers' experiments on the simulator."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from softtip.cli.options import FRAMES_HELP
from softtip.cli.types import option
from softtip.core._cores import usable_cores

__all__ = ["reproduce"]


@click.command(
    "reproduce",
    help="""Reproduce the papers' experiments (manual §5, E1–E6) on the simulator.

Every condition (edges of different sharpness, the 1 mm plate at −45°, 0°, 45°, 90°, plates
1–15 mm, cylinders Ø 4–14 mm, the fringe of a Ø 40 mm cylinder bottom, contact position)
is simulated with the papers' grasp and measured by the same pipeline as `softtip
estimate` (default options, --no-drift-tracking as in the papers). Writes to -o DIR one figure per experiment laid out like the
papers' (e1_edges.png … e6_contact_position.png) and the summary table summary.md /
summary.csv: per condition the median axial direction error (degrees), the share of
samples with a reported direction, the contact-position error (mm), the line evidence, the
published outcome and whether ours agrees. X1, softtip's extension, rocks thin and thick
objects about two tangent axes and judges line or area (x1_line_or_area.png: h in the
tangent plane as a trace, and the state over time).

"""
    + FRAMES_HELP
)
@option("-o", "--output", "--out", "out_dir", type=click.Path(file_okay=False), default="reproduction", show_default=True, metavar="DIR", help="Output directory (created; --out is the same option).")
@option(
    "--only",
    metavar="E1,E2,...",
    help="Run only these experiments (comma-separated ids E1–E6, X1).",
)
@option("--seed", type=click.IntRange(min=0), default=2006, show_default=True, help="Seed of the simulated sensor noise.")
@option(
    "--jobs",
    type=click.IntRange(1, 64),
    default=min(4, usable_cores()),
    show_default="min(4, the CPUs this process may use)",
    help="Worker processes.",
)
def reproduce(out_dir, only, seed, jobs):
    from tqdm import tqdm

    from softtip.apps.reproduce import run_reproduction

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

