"""Accuracy of softtip's extensions against the papers' method, on the simulator.

    python benchmarks/bench_accuracy.py            # all sections (~1 min)
    python benchmarks/bench_accuracy.py --fit-depth  # refit the default depth law

Every case is a simulated grasp (Winkler skin with the Coulomb-limited tangential layer,
Nano17-class noise, 50 Hz) on the murakami2006 tip. Errors are medians over the held
grasp (t > 6 s) of the samples in contact; directions only where the estimator reports a
line contact (the coverage is printed). Printed table: ``condition | error with the papers'
method | error with softtip's extension``. Sections:

* **depth** (issue 5 item 3): a tangential friction load across the line (0.25 and 0.5
  of the normal force) applied after the grasp, on top of the papers' joint disturbance;
  ``latch`` vs ``latch`` + :data:`~softtip.depth.MURAKAMI2006_DEPTH`. Skin with the shear
  layer stiffened to G = 2 MPa (side walls; with the default E/3 layer the simulator cannot
  hold a load across a thin plate, see :mod:`softtip.sim.scenario`).
* **slide** (item 5): after the grasp the object slides 4 mm along the skin (kinematic
  translation, no tangential load) with the joint disturbance: ``latch`` without re-latch
  (the papers') vs with re-latch at 3 mm.

Room is left for other sections (calibration and gravity: ``bench_calibration.py``).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import time

import numpy as np

from softtip import EstimatorConfig, axial_difference, estimate, murakami2006
from softtip.depth import MURAKAMI2006_DEPTH, DepthLaw, lever_depth
from softtip.sim import (
    ContactModel,
    ContactParams,
    Disturbance,
    Plate,
    SensorModel,
    Wedge,
    discretise_skin,
    paper_scenario,
    push_scenario,
    simulate_grasp,
)
from softtip.units import KGF

TIP = murakami2006()
HELD = 6.0  # s: the grasp is held (disturbances done) from here


def _dir_err(est, log, sel) -> tuple[float, float]:
    """Median axial direction error (deg) over ``sel`` & line, and the line coverage."""
    line = sel & (est.state == 2)
    if not line.any():
        return math.nan, 0.0
    err = np.degrees(np.abs(axial_difference(est.angle[line], log.truth.angle[line])))
    return float(np.median(err)), float(line.sum() / max(sel.sum(), 1))


def _point_err(est, truth_point, sel) -> float:
    """Median contact-point error (mm) over ``sel`` & in contact."""
    m = sel & (est.state > 0)
    return float(np.median(np.linalg.norm(est.point[m] - truth_point[m], axis=1)) * 1e3) if m.any() else math.nan


def _row(cond: str, *cells: str) -> None:
    print(f"| {cond} | " + " | ".join(cells) + " |")


def depth_section(seed: int = 1) -> None:
    print("\n### depth compensation (item 3): direction error, median (line coverage)\n")
    print("| condition | error with the papers' method (latch) | error with softtip's extension (latch + depth) |")
    print("| --- | --- | --- |")
    model = ContactModel(discretise_skin(TIP, 10000), ContactParams(shear_modulus=2e6)).prepare()
    force = 0.5 * KGF
    for name, obj in (("plate 1 mm", Plate(0.001)), ("plate 2 mm", Plate(0.002)), ("wedge 90°", Wedge(math.pi / 2))):
        for ang in (0.0, 45.0, -45.0):
            for ratio in (0.0, 0.25, 0.5):
                a = math.radians(ang)
                e = np.cross([0.0, 0.0, 1.0], [math.cos(a), math.sin(a), 0.0])
                scn = paper_scenario(a, object_mass=0.0)
                scn = dataclasses.replace(scn, tangential_force=tuple(ratio * force * e), load_start=4.0, load_end=5.5)
                try:
                    log = simulate_grasp(TIP, obj, scn, rng=seed, model=model)
                except RuntimeError:
                    _row(f"{name} {ang:+.0f}°, f_t = {ratio:.2f} f_n", "simulator cannot hold it", "")
                    continue
                sel = log.t > HELD
                out = []
                for cfg in (EstimatorConfig(), EstimatorConfig(depth=MURAKAMI2006_DEPTH)):
                    e_, cov = _dir_err(estimate(log.t, log.wrench, TIP, cfg), log, sel)
                    out.append(f"{e_:.1f}° ({cov:.0%})")
                _row(f"{name} {ang:+.0f}°, f_t = {ratio:.2f} f_n across", *out)


def slide_section(seed: int = 1) -> None:
    print("\n### sliding contact (item 5): the object slides 4 mm along the skin after the grasp\n")
    print("| condition | papers' latch (no re-latch): point, direction | re-latch at 3 mm: point, direction (re-latches) |")
    print("| --- | --- | --- |")
    model = ContactModel(discretise_skin(TIP, 10000), ContactParams()).prepare()
    for name, obj in (("plate 1 mm", Plate(0.001)), ("plate 2 mm", Plate(0.002))):
        for ang, slide in ((0.0, (0.0, 0.004, 0.0)), (45.0, (0.0, 0.004, 0.0)), (0.0, (0.004, 0.0, 0.0))):
            for force_kgf in (0.4, 0.5):
                dist = (
                    Disturbance(axis=(0.0, 1.0, 0.0), angle=math.radians(3.5), start=4.0, end=5.0, label="joint"),
                    Disturbance(translation=slide, start=5.5, end=7.5, label="slide"),
                )
                scn = push_scenario(math.radians(ang), disturbances=dist, force=force_kgf * KGF)
                try:
                    log = simulate_grasp(TIP, obj, scn, rng=seed, model=model)
                except RuntimeError:
                    _row(f"{name} {ang:+.0f}°, {force_kgf} kgf", "simulator's force solve fails", "")
                    continue
                r_c = np.asarray(log.truth.contact_point[0])
                truth = TIP.project(np.array([scn.disturbance_pose(float(t), r_c).apply(r_c[None])[0] for t in log.t]))
                sel = log.t > 8.0
                cells = []
                for cfg in (EstimatorConfig(), EstimatorConfig(relatch_distance=3e-3)):
                    est = estimate(log.t, log.wrench, TIP, cfg)
                    e_, cov = _dir_err(est, log, sel)
                    extra = f", {int(est.relatched.sum())} re-latch" if cfg.relatch_distance else ""
                    cells.append(f"{_point_err(est, truth, sel):.2f} mm, {e_:.1f}° ({cov:.0%}){extra}")
                along = "along x" if slide[0] else "along y"
                _row(f"{name} {ang:+.0f}°, {force_kgf} kgf, slide {along}", *cells)


def fit_depth() -> DepthLaw:
    """Refit :data:`MURAKAMI2006_DEPTH` from simulated calibration presses."""
    model = ContactModel(discretise_skin(TIP, 10000), ContactParams(shear_modulus=2e6)).prepare()
    force = 0.5 * KGF
    fs, ds = [], []
    d, n = np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])
    for obj in (Plate(0.001), Plate(0.002)):
        scn = paper_scenario(0.0, object_mass=0.0, joint_rotation=0.0, gravity_spin=0.0, duration=4.5)
        scn = dataclasses.replace(scn, tangential_force=tuple(0.25 * force * np.cross(n, d)), load_start=2.6, load_end=3.0)
        log = simulate_grasp(TIP, obj, scn, SensorModel.ideal(50.0), model=model)
        sel = (log.t >= 3.0) & (log.t <= 4.0)
        fs.append(-log.wrench_true[sel] @ np.r_[n, 0, 0, 0])
        ds.append(lever_depth(log.wrench_true[sel], TIP.project([0.0, 0.0, 1.0]), n, d))
    law = DepthLaw.fit(np.concatenate(fs), np.concatenate(ds))
    print(f"fitted: {law}; default: {MURAKAMI2006_DEPTH}")
    print("depth at 0.2 / 0.5 kgf: fitted", np.round(law.depth([0.2 * KGF, 0.5 * KGF]) * 1e3, 2),
          "mm, default", np.round(MURAKAMI2006_DEPTH.depth([0.2 * KGF, 0.5 * KGF]) * 1e3, 2), "mm")
    return law


def stream_cost() -> None:
    print("\n### streaming cost per sample in contact (median, µs)\n")
    from softtip import Estimator
    from softtip.synthetic import synthetic_grasp

    g = synthetic_grasp(angle_deg=30.0, seed=1)
    for label, cfg in (
        ("latch (default)", EstimatorConfig()),
        ("latch, re-latch at 3 mm", EstimatorConfig(relatch_distance=3e-3)),
        ("latch + depth", EstimatorConfig(depth=MURAKAMI2006_DEPTH)),
        ("track", EstimatorConfig(contact_point="track")),
    ):
        times = []
        for _ in range(3):
            est = Estimator(TIP, cfg)
            for t, w in zip(g.t.tolist(), g.wrench.tolist()):
                t0 = time.perf_counter_ns()
                s = est.update(t, w)
                dt = time.perf_counter_ns() - t0
                if s.state != "none":
                    times.append(dt)
        print(f"| {label} | {np.median(times) / 1e3:.1f} µs |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--fit-depth", action="store_true", help="refit the default depth law and stop")
    ap.add_argument("--sections", nargs="*", default=["depth", "slide", "cost"])
    args = ap.parse_args()
    if args.fit_depth:
        fit_depth()
        return
    print("murakami2006 tip (capsule R 16 mm, cylinder 20 mm), simulator with friction (μ = 1) and Nano17-class noise, 50 Hz")
    for name in args.sections:
        {"depth": depth_section, "slide": slide_section, "cost": stream_cost}[name]()


if __name__ == "__main__":
    main()
