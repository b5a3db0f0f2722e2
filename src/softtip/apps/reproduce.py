"""Reproduction of the papers' experiments (manual §5, E1–E6) on the simulator.

Every condition is simulated (:mod:`softtip.sim`: the papers' grasp, Nano17-class sensor)
and then measured with exactly what ``softtip estimate`` runs (:func:`softtip.estimate` with
the default configuration: latched contact point, noise-based observability test; drift
tracking off, as in the papers, :data:`PAPERS_CONFIG`). The
outcome of each condition is judged on the held grasp (``t ≥ EVAL_FROM``):

- ``measured``: the direction is reported on at least half of the samples and its median
  axial error is at most :data:`TOLERANCE_DEG`;
- ``biased``: reported, median error between the tolerance and :data:`LARGE_ERROR_DEG`;
- ``large error``: reported, median error above :data:`LARGE_ERROR_DEG`;
- ``unobservable``: reported on fewer than half of the samples (the direction is missing,
  as softtip reports when ``|h|`` does not stand out of the noise).

A condition agrees with the papers when the papers measured it and ours is ``measured``,
or the papers could not measure it and ours is ``large error`` or ``unobservable``.
E6 (contact position) is judged on the soft-finger position error while the pushing force
exceeds 0.2 kgf, against the papers' 0.5 mm.

Each condition also reports the line evidence of its line samples: the papers' grasps excite
the contact about one axis only, so their lines are ``unconfirmed`` (a tilted plane would
give the same wrench). The extension experiment X1 (not in the papers) rocks the grasped
object about two tangent axes and in a figure-eight (:func:`softtip.sim.rock_scenario`) and
is judged after both axes were excited: a line (thin plate, thin cylinder) agrees when it
is reported ``line`` on at least :data:`X1_LINE_SHARE` of the samples with a median error
within :data:`TOLERANCE_DEG`; an area (thick plate, plane) when ``line`` on at most
:data:`X1_AREA_LINE_SHARE`.
"""

from __future__ import annotations

import math
import os
import signal
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from softtip.apps.pool import end_pool, start_pool
from softtip.core.axial import axial_difference
from softtip.core.fingertip import Fingertip, murakami2006
from softtip.core.units import KGF
from softtip.estimator import AREA, LINE, Estimates, EstimatorConfig, estimate
from softtip.io.atomic import atomic_write_text

__all__ = [
    "TOLERANCE_DEG",
    "LARGE_ERROR_DEG",
    "EVAL_FROM",
    "Condition",
    "ConditionResult",
    "EXPERIMENTS",
    "conditions",
    "run_condition",
    "run_reproduction",
]

#: Median axial error (deg) within which a direction counts as measured (the manual's §6 target).
TOLERANCE_DEG = 3.0
#: Median axial error (deg) above which a direction counts as a large error.
LARGE_ERROR_DEG = 10.0
#: Outcomes are judged on the samples from this time on (s): the grasp is held still.
EVAL_FROM = 6.0
#: Share of samples that must be reported for a direction to count as measured.
MIN_SHARE = 0.5
#: E6: the papers' bound on the contact-position error above 0.2 kgf (m).
POSITION_BOUND = 0.5e-3
#: X1: least share of ``line`` samples of a line contact, most of an area contact.
X1_LINE_SHARE = 0.9
X1_AREA_LINE_SHARE = 0.05
#: X1: period of the rocking (s) and the object angle (deg).
X1_PERIOD = 0.5
X1_ANGLE = 30.0


@dataclass(frozen=True)
class Condition:
    """One simulated grasp of an experiment.

    Parameters
    ----------
    experiment : str
        ``"E1"`` … ``"E6"``.
    kind : str
        Simulator object kind (``plate``, ``cylinder``, ``wedge``, ``fringe``, ``plane``).
    size : float or None
        m: plate thickness, cylinder diameter, fringe cylinder diameter.
    angle_deg : float
        Direction of the object at the contact, degrees (manual §3.4).
    expect_measured : bool or None
        The papers' outcome: direction measured (True), not measured (False), or no
        separate verdict (None).
    published : str
        The papers' outcome in words.
    edge_radius : float
        m: wedge tip radius (E1's sharpness).
    contact_point : tuple or None
        E6: nominal contact point on the skin (m); None: the apex.
    """

    experiment: str
    kind: str
    size: float | None
    angle_deg: float
    expect_measured: bool | None
    published: str
    edge_radius: float = 0.0
    contact_point: tuple[float, float, float] | None = None

    @property
    def variant(self) -> str:
        """The object, in words (without the angle)."""
        if self.kind == "wedge":
            return "sharp 90° edge" if self.edge_radius == 0 else f"90° edge, tip radius {self.edge_radius * 1e3:g} mm"
        if self.kind == "plate":
            return f"plate {self.size * 1e3:g} mm"
        if self.kind == "cylinder":
            return f"cylinder Ø {self.size * 1e3:g} mm"
        if self.kind == "fringe":
            return f"fringe of Ø {self.size * 1e3:g} mm cylinder"
        if self.kind == "plane":
            p = self.contact_point
            return "plane" if self.experiment == "X1" else "plane at the apex" if p is None else f"plane at ({p[0] * 1e3:.1f}, {p[1] * 1e3:.1f}, {p[2] * 1e3:.1f}) mm"
        return self.kind

    @property
    def label(self) -> str:
        plane = self.kind == "plane" and self.experiment != "X1"
        return f"{self.experiment} {self.variant}" + ("" if plane else f" at {self.angle_deg:g}°")


@dataclass(frozen=True)
class ConditionResult:
    """Measured outcome of one condition (angles in degrees, lengths in m, moments in N·m)."""

    condition: Condition
    median_error_deg: float
    share_reported: float
    contact_error: float
    median_h: float
    outcome: str
    agrees: bool | None
    estimates: Estimates = field(repr=False)
    truth_angle_deg: float = math.nan
    force_norm: np.ndarray | None = field(default=None, repr=False)
    position_error: np.ndarray | None = field(default=None, repr=False)
    confirmed_share: float = math.nan
    area_share: float = math.nan


def _measured(expect: bool | None, outcome: str) -> bool | None:
    if expect is None:
        return None
    if outcome in ("line", "area", "line, biased", "neither"):  # X1: line (True) or area (False)
        return outcome == ("line" if expect else "area")
    if expect:
        return outcome == "measured"
    return outcome in ("large error", "unobservable")


E1_PUBLISHED = "measured with good accuracy; sharpness does not matter"
E2_MEASURED = "measured"
E2_NOT = "not measured (no spin torque about an axis in the hand's x-z plane)"


def conditions(experiments: Sequence[str] | None = None) -> list[Condition]:
    """The simulated conditions of the selected experiments (default all), in order."""
    out: list[Condition] = []
    angles3 = (-45.0, 0.0, 45.0)
    for radius in (0.0, 0.5e-3, 1.0e-3):
        out += [Condition("E1", "wedge", None, a, True, E1_PUBLISHED, edge_radius=radius) for a in angles3]
    out += [Condition("E2", "plate", 1e-3, a, True, E2_MEASURED) for a in angles3]
    out.append(Condition("E2", "plate", 1e-3, 90.0, False, E2_NOT))
    for t in (1e-3, 2e-3, 3e-3, 4e-3, 10e-3, 15e-3):
        thin = t <= 2e-3
        text = "measured correctly (≤ 2 mm)" if thin else "large error (≥ 3 mm: the strip becomes round)"
        out += [Condition("E3", "plate", t, a, thin, text) for a in angles3]
    for d in (4e-3, 6e-3, 10e-3, 14e-3):
        thin = d <= 6e-3
        text = "measured (Ø ≤ 6 mm)" if thin else "large error (larger diameters)"
        out += [Condition("E4", "cylinder", d, a, thin, text) for a in angles3]
    out += [Condition("E5", "fringe", 40e-3, a, True, "tangent direction measured") for a in angles3]
    out.append(Condition("E5", "fringe", 40e-3, 90.0, None, "listed among the directions; no separate result"))
    tip = murakami2006()
    for polar in (0.0, 30.0, 60.0, 80.0):
        p = math.radians(polar)
        point = (tip.radius * math.sin(p), 0.0, tip.length + tip.radius * math.cos(p))
        out.append(Condition("E6", "plane", None, 0.0, None, "position error < 0.5 mm above 0.2 kgf", contact_point=point))
    # (not the cylinder side: a plane meets a cylinder along a line, where no single contact
    # point exists)
    for kind, size, line in (("plate", 1e-3, True), ("cylinder", 4e-3, True), ("plate", 15e-3, False), ("plane", None, False)):
        text = "(softtip extension) line, confirmed" if line else "(softtip extension) area"
        out.append(Condition("X1", kind, size, X1_ANGLE, line, text))
    if experiments is not None:
        wanted = {e.upper() for e in experiments}
        unknown = wanted - set(EXPERIMENTS)
        if unknown:
            raise ValueError(f"unknown experiment(s) {', '.join(sorted(unknown))}; expected some of {', '.join(EXPERIMENTS)}")
        out = [c for c in out if c.experiment in wanted]
    return out


def _simulate(condition: Condition, tip: Fingertip, seed: int):
    from softtip.sim import make_object, paper_scenario, push_scenario, rock_scenario, simulate_grasp

    obj = make_object(condition.kind, condition.size, edge_radius=condition.edge_radius)
    angle = math.radians(condition.angle_deg)
    if condition.experiment == "X1":
        scenario = rock_scenario(angle, rock_period=X1_PERIOD)
    elif condition.experiment == "E6":
        scenario = push_scenario(angle, contact_point=condition.contact_point)
    else:
        scenario = paper_scenario(angle)
    return simulate_grasp(tip, obj, scenario, rng=seed)


#: The configuration of the reproduction: the defaults with drift tracking off (the papers
#: tared once; softtip's drift tracking moves their medians by up to 0.02°).
PAPERS_CONFIG = EstimatorConfig(drift_tracking=False)


def run_condition(condition: Condition, *, seed: int = 2006, config: EstimatorConfig | None = None) -> ConditionResult:
    """Simulate one condition and measure it as ``softtip estimate`` does."""
    tip = murakami2006()
    log = _simulate(condition, tip, seed)
    truth = log.truth
    if condition.experiment == "E6":
        # the papers' Fig. 7: soft-finger position error against the pushing force
        est = estimate(log.t, log.wrench, tip, EstimatorConfig(contact_point="track", drift_tracking=False))
        f_norm = np.linalg.norm(log.wrench_true[:, :3], axis=1)
        err = np.linalg.norm(est.point - truth.contact_point, axis=1)
        above = (f_norm >= 0.2 * KGF) & np.isfinite(err)
        worst = float(np.max(err[above])) if above.any() else math.nan
        ok = bool(worst < POSITION_BOUND)
        return ConditionResult(
            condition, math.nan, math.nan, worst, math.nan, "within 0.5 mm" if ok else "beyond 0.5 mm", ok, est,
            force_norm=f_norm, position_error=err,
        )  # fmt: skip

    est = estimate(log.t, log.wrench, tip, PAPERS_CONFIG if config is None else config)
    held = log.t >= EVAL_FROM
    if condition.experiment == "X1":  # after both axes were excited
        a2 = next(d for d in log.scenario.disturbances if d.label == "rock-a2")
        held = log.t >= a2.start + a2.period
    line = held & (est.state == LINE)
    share = float(np.count_nonzero(line) / max(1, np.count_nonzero(held)))
    confirmed = float(np.mean(est.line_evidence[line] == 2)) if line.any() else math.nan
    area = float(np.count_nonzero(held & (est.state == AREA)) / max(1, np.count_nonzero(held)))
    err = np.degrees(np.abs(axial_difference(est.angle[line], truth.angle[line])))
    median_error = float(np.median(err)) if err.size else math.nan
    contact_error = float(np.nanmedian(np.linalg.norm(est.point[held] - truth.contact_point[held], axis=1)))
    median_h = float(np.nanmedian(est.h_norm[held]))
    if condition.experiment == "X1":
        if share >= X1_LINE_SHARE:
            outcome = "line" if median_error <= TOLERANCE_DEG else "line, biased"
        else:
            outcome = "area" if share <= X1_AREA_LINE_SHARE and area > MIN_SHARE else "neither"
    elif share < MIN_SHARE:
        outcome = "unobservable"
    elif median_error <= TOLERANCE_DEG:
        outcome = "measured"
    elif median_error <= LARGE_ERROR_DEG:
        outcome = "biased"
    else:
        outcome = "large error"
    ta = truth.angle[held]
    truth_angle = float(np.degrees(np.median(ta[np.isfinite(ta)]))) if np.isfinite(ta).any() else math.nan
    return ConditionResult(
        condition, median_error, share, contact_error, median_h, outcome,
        _measured(condition.expect_measured, outcome), est, truth_angle, confirmed_share=confirmed, area_share=area,
    )  # fmt: skip


def _grasp_key(c: Condition) -> tuple:
    return (c.experiment == "E6", c.kind, c.size, c.angle_deg, c.edge_radius, c.contact_point)


def _worker_init() -> None:
    """A worker of :func:`run_reproduction`'s pool: the parent decides when it ends.

    Ctrl-C and SIGHUP reach the whole process group; the parent cancels the pool and
    terminates the workers (SIGTERM, at its default action here). A worker whose parent has
    ended (a signal while the pool started, before it knew the worker) ends too.
    """
    from softtip.apps.pool import _end_with_parent

    for name in ("SIGINT", "SIGHUP"):
        if hasattr(signal, name):
            signal.signal(getattr(signal, name), signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    _end_with_parent()


def _run_one(args):
    condition, seed = args
    return run_condition(condition, seed=seed)


#: Experiments: id -> (title, the papers' section).
EXPERIMENTS: dict[str, tuple[str, str]] = {
    "E1": ("Sharp edges of different sharpness", "2004 §IV"),
    "E2": ("Thin plate 1 mm at −45°, 0°, 45°, 90°", "2006 IV-B, Figs. 8–11"),
    "E3": ("Plates 1–15 mm thick", "2006 IV-C, Figs. 14–17"),
    "E4": ("Cylinders Ø 4–14 mm", "2006 IV-D, Figs. 19–22"),
    "E5": ("Fringe of a Ø 40 mm cylinder bottom", "2006 IV-E, Fig. 24"),
    "E6": ("Contact position error vs pushing force, judged above 1.96 N", "2006 IV-A, Fig. 7"),
    "X1": ("Line or area under two-axis rocking", "softtip extension"),
}


def run_reproduction(
    out_dir: str | os.PathLike,
    *,
    experiments: Sequence[str] | None = None,
    seed: int = 2006,
    jobs: int = 1,
    progress: Callable | None = None,
) -> list[ConditionResult]:
    """Run the selected experiments and write figures and the summary table to ``out_dir``.

    Parameters
    ----------
    out_dir : path
        Created if needed. Receives ``e1_edges.png`` … ``e6_contact_position.png``,
        ``summary.md`` and ``summary.csv``.
    experiments : sequence of str, optional
        Subset of ``E1`` … ``E6``.
    seed : int
        Sensor-noise seed (the same for every condition).
    jobs : int
        Worker processes.
    progress : callable, optional
        Wraps the iterator of results (e.g. ``tqdm`` with ``total=``).

    Returns
    -------
    list of ConditionResult
    """
    out = Path(out_dir)
    check_out_dir(out)  # before the work: a file in the way, or no permission
    todo = conditions(experiments)
    # E2's plate also appears in E3: simulate each distinct grasp once
    unique = list(dict.fromkeys(_grasp_key(c) for c in todo))
    args = [(next(c for c in todo if _grasp_key(c) == key), seed) for key in unique]
    if jobs > 1:
        # as softtip estimate --jobs: forked from a preloaded server, started at once, each
        # worker ending with this process (a signal during the start-up leaves none behind)
        pool = start_pool(jobs, _worker_init)
        try:
            it = pool.map(_run_one, args)
            done = list(progress(it, total=len(args)) if progress else it)
        except BaseException:  # an error, Ctrl-C, SIGTERM, SIGHUP: the pool goes now, not after its queue
            end_pool(pool)
            raise
        pool.shutdown()
    else:
        it = map(_run_one, args)
        done = list(progress(it, total=len(args)) if progress else it)
    by_key = dict(zip(unique, done))
    results = []
    for c in todo:
        r = by_key[_grasp_key(c)]
        results.append(replace(r, condition=c, agrees=_measured(c.expect_measured, r.outcome)) if r.condition != c else r)
    _write_report(results, out)
    return results


def check_out_dir(out: Path) -> None:
    """Refuse an output directory that cannot be one (a file or device in the way, no permission).

    Raises
    ------
    InputError
        Naming the directory and what is expected.
    """
    from softtip.errors import InputError

    if out.exists() and not out.is_dir():
        raise InputError(f"{out}: exists and is not a directory; expected a directory for the figures and the summary (-o DIR)")
    existing = out
    while not existing.exists():
        if existing.parent == existing:
            break
        existing = existing.parent
    if not existing.is_dir():
        raise InputError(f"{out}: {existing} is not a directory; expected a directory path for -o DIR")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise InputError(f"{out}: cannot create or write it ({existing}: permission denied); expected a writable directory")


def _write_report(results: Sequence[ConditionResult], out: Path) -> None:
    """Figures and summary into ``out``, all together or none (:class:`softtip.io.atomic.Outputs`)."""
    import shutil
    import tempfile

    from softtip.io.atomic import Outputs, cannot_write

    staging = Path(tempfile.mkdtemp(prefix=".softtip-reproduce."))
    try:
        write_figures(results, staging)
        write_summary(results, staging)
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise cannot_write(out, exc) from None
        with Outputs() as outputs:
            for f in sorted(staging.iterdir()):
                staged = outputs.file(out / f.name)
                try:
                    shutil.move(f, staged.tmp)
                except OSError as exc:
                    raise cannot_write(out / f.name, exc) from None
    finally:
        shutil.rmtree(staging, ignore_errors=True)


# -- report ----------------------------------------------------------------------------------

_FIGURES = {
    "E1": "e1_edges.png",
    "E2": "e2_thin_plate.png",
    "E3": "e3_plate_thickness.png",
    "E4": "e4_cylinders.png",
    "E5": "e5_fringe.png",
    "E6": "e6_contact_position.png",
    "X1": "x1_line_or_area.png",
}


def _fmt(v: float, digits: int) -> str:
    return "–" if not np.isfinite(v) else f"{v:.{digits}f}"


def summary_rows(results: Sequence[ConditionResult]) -> list[dict[str, str]]:
    """One row per condition, as text (the Markdown and CSV tables)."""
    rows = []
    for r in results:
        c = r.condition
        rows.append(
            {
                "experiment": c.experiment,
                "object": c.variant,
                "angle_deg": "–" if c.kind == "plane" else f"{c.angle_deg:g}",
                "published": c.published,
                "ours": r.outcome,
                "agrees": {True: "yes", False: "no", None: "–"}[r.agrees],
                "median_error_deg": _fmt(r.median_error_deg, 1),
                "share_reported": _fmt(r.share_reported, 2),
                "contact_error_mm": _fmt(r.contact_error * 1e3, 2),
                "median_h_nmm": _fmt(r.median_h * 1e3, 2),
                "line_evidence": _evidence_text(r),
            }
        )
    return rows


def _evidence_text(r: ConditionResult) -> str:
    """Line evidence of a condition's line samples (and its area share when any)."""
    if not np.isfinite(r.confirmed_share):
        text = "–"
    elif r.confirmed_share == 0.0:
        text = "unconfirmed"
    elif r.confirmed_share == 1.0:
        text = "confirmed"
    else:
        text = f"{r.confirmed_share:.0%} confirmed"
    if np.isfinite(r.area_share) and r.area_share > 0.0:
        text += f"; area {r.area_share:.0%}"
    return text


def write_summary(results: Sequence[ConditionResult], out: Path) -> None:
    """``summary.csv`` and ``summary.md`` in ``out``."""
    from softtip.io.tables import write_table

    rows = summary_rows(results)
    if not rows:
        return
    write_table({k: [row[k] for row in rows] for k in rows[0]}, out / "summary.csv")
    head = (
        "| exp. | object | angle (°) | published | ours | agrees | median error (°) "
        "| share reported | contact error (mm) | median \\|h\\| (N·mm) | line evidence |"
    )
    lines = [
        "# softtip reproduction of the papers' experiments",
        "",
        f"Simulated grasps (softtip.sim, papers' hand, Nano17-class noise), measured with the default "
        f"`softtip estimate` pipeline (`--no-drift-tracking`, as in the papers). Judged on t ≥ {EVAL_FROM:g} s: *measured* = direction reported on "
        f"≥ {MIN_SHARE:.0%} of the samples with median axial error ≤ {TOLERANCE_DEG:g}°; *biased* ≤ "
        f"{LARGE_ERROR_DEG:g}°; *large error* beyond; *unobservable* = reported on fewer samples. "
        "Contact error: latched point vs the nominal contact point (E6: worst soft-finger error above 0.2 kgf). "
        "Line evidence: whether the line samples were confirmed by excitation about two tangent axes (the papers' "
        f"grasps excite one: unconfirmed). X1 (softtip's extension, not in the papers): the object rocked about two "
        f"tangent axes, judged after both were excited: *line* = reported line on ≥ {X1_LINE_SHARE:.0%} of the "
        f"samples with median error ≤ {TOLERANCE_DEG:g}°; *area* = line on ≤ {X1_AREA_LINE_SHARE:.0%}.",
        "",
        head,
        "|" + "---|" * 11,
    ]
    for row in rows:
        lines.append("| " + " | ".join(row.values()) + " |")
    judged = [r for r in results if r.agrees is not None]
    lines += ["", f"Agreement with the published outcomes: {sum(r.agrees for r in judged)} of {len(judged)} conditions."]
    atomic_write_text(out / "summary.md", "\n".join(lines) + "\n")


def write_figures(results: Sequence[ConditionResult], out: Path) -> None:
    """One figure per experiment present in ``results``, laid out like the papers'."""
    from softtip.viz.plot import plot_direction_chart, plot_estimates, plot_line_or_area, plot_position_error

    by_exp: dict[str, list[ConditionResult]] = {}
    for r in results:
        by_exp.setdefault(r.condition.experiment, []).append(r)
    for exp, rs in by_exp.items():
        title = f"{exp}: {EXPERIMENTS[exp][0]} ({EXPERIMENTS[exp][1]}), simulated"
        path = out / _FIGURES[exp]
        if exp in ("E2", "E5"):
            # force and moment of the 0° grasp, |h| and direction of every angle, in the
            # angle order (and so the colours) of the other experiments' figures
            order = sorted(rs, key=lambda r: r.condition.angle_deg)
            zero = next((k for k, r in enumerate(order) if r.condition.angle_deg == 0.0), 0)
            plot_estimates(
                [r.estimates for r in order],
                path,
                labels=[f"{r.condition.angle_deg:g}°" for r in order],
                title=title,
                reference_angles=[r.truth_angle_deg for r in order],
                detail=zero,
            )
        elif exp == "X1":
            plot_line_or_area(
                [(r.condition.variant, r.estimates, r.truth_angle_deg if r.condition.expect_measured else None) for r in rs],
                path,
                title=title,
            )
        elif exp == "E6":
            plot_position_error(
                [(r.condition.variant, r.force_norm, r.position_error) for r in rs],
                path,
                bound=POSITION_BOUND,
                title=title,
            )
        else:
            rows: dict[str, list[ConditionResult]] = {}
            for r in rs:
                rows.setdefault(r.condition.variant, []).append(r)
            plot_direction_chart(
                [
                    (variant, [r.estimates for r in group], [f"{r.condition.angle_deg:g}°" for r in group], [r.truth_angle_deg for r in group])
                    for variant, group in rows.items()
                ],
                path,
                title=title,
            )
