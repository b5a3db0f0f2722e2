"""Accuracy beyond the papers (issue 5, items 1 and 2), on simulated data with friction and noise.

1. Fingertip calibration: a 30 s probing log (20 plane presses with slides, Nano17-class
   noise) of a true fingertip that differs from the nominal by a few mm. Papers' method:
   the nominal geometry (no calibration). softtip: `calibrate_fingertip`.
2. Gravity compensation: a static edge contact (the papers' grasp, murakami2006 tip)
   while the hand rotates ±90° about its grasp axis with a 20 g fingertip (centre of mass
   20 mm out). Papers' method: tare once, no compensation. softtip: the payload estimated
   by `calibrate_payload` from a contact-free log, then `compensate_payload`. Error: median
   axial direction error of the line samples after the disturbance (t ≥ 6 s), and the share
   of those samples with a reported direction; the static case (no rotation) for reference.

    python benchmarks/bench_calibration.py [--seed N]
"""

from __future__ import annotations

import argparse
import math

import numpy as np
from scipy.spatial.transform import Rotation

from softtip import estimate, murakami2006
from softtip.axial import axial_difference
from softtip.calibration import calibrate_fingertip, simulate_probing
from softtip.fingertip import Capsule, Sphere
from softtip.payload import Payload, calibrate_payload, compensate_payload, payload_wrench
from softtip.sim import HandFrame, SensorModel, Wedge, paper_scenario, simulate_grasp

MM = 1e3


def calibration_rows(seed: int) -> list[tuple[str, str, str]]:
    rows = []
    cases = [
        ("sphere", Sphere(0.016, (0.0, 0.0, 0.020)), Sphere(0.0175, (0.0015, -0.0010, 0.0225)), (0.0, 0.0)),
        ("capsule", Capsule(0.016, 0.020), Capsule(0.0150, 0.0225), (0.0008, -0.0005)),
    ]
    for shape, nominal, true, offset in cases:
        t, w = simulate_probing(true, 30.0, axis_offset=offset, rng=seed)
        cal = calibrate_fingertip(t, w, shape)
        rigid = calibrate_fingertip(t, w, shape, compliance=False)
        if shape == "sphere":
            c_true, c_nom = np.array(true.center), np.array(nominal.center)
        else:
            c_true, c_nom = np.array([*offset, true.length]), np.array([0.0, 0.0, nominal.length])
        rows.append(
            (
                f"{shape}: centre error (mm)",
                f"{np.linalg.norm(c_nom - c_true) * MM:.3f}",
                f"{np.linalg.norm(cal.center - c_true) * MM:.3f} (± {np.linalg.norm(cal.center_std) * MM:.3f}; rigid-skin fit "
                f"{np.linalg.norm(rigid.center - c_true) * MM:.3f})",
            )
        )
        rows.append(
            (
                f"{shape}: radius error (mm)",
                f"{(nominal.radius - true.radius) * MM:+.3f}",
                f"{(cal.radius - true.radius) * MM:+.3f} (± {cal.radius_std * MM:.3f}; rigid-skin fit {(rigid.radius - true.radius) * MM:+.3f})",
            )
        )
    return rows


def direction_error(t, wrench, truth_angle):
    est = estimate(t, wrench, murakami2006())
    after = t >= 6.0
    line = after & (est.state == 2)
    err = np.degrees(np.abs(axial_difference(est.angle[line], truth_angle[line])))
    return (float(np.median(err)) if len(err) else math.nan), line.sum() / after.sum()


def gravity_rows(seed: int) -> list[tuple[str, str, str]]:
    rng = np.random.default_rng(seed)
    payload = Payload(0.02, (0.001, -0.0005, 0.02))
    r0 = Rotation.from_matrix(HandFrame.paper().rotation.T)  # sensor -> hand (z up)
    qc = (Rotation.from_rotvec(rng.normal(size=(500, 3)) * 0.8) * r0).as_quat(scalar_first=True)
    bias = (0.1, -0.05, 0.2, 1e-3, -2e-3, 5e-4)
    fit = calibrate_payload(SensorModel(bias=bias).measure(payload_wrench(qc, payload), rng), qc)
    rows = [
        (
            "payload estimate (20 g, com 20 mm)",
            "-",
            f"mass {fit.payload.mass * 1e3:.3f} ± {fit.mass_std * 1e3:.3f} g, com error "
            f"{np.linalg.norm(np.subtract(fit.payload.com, payload.com)) * MM:.3f} mm",
        )
    ]
    for deg in (-45, 0, 45):
        log = simulate_grasp(murakami2006(), Wedge(), paper_scenario(math.radians(deg)), rng=seed * 1000 + deg + 90)
        theta = math.radians(90.0) * np.sin(2 * np.pi * log.t / 8.0)
        q = (Rotation.from_rotvec(theta[:, None] * [1.0, 0.0, 0.0]) * r0).as_quat(scalar_first=True)
        w_rot = log.wrench + payload_wrench(q, payload)
        static, s_share = direction_error(log.t, log.wrench, log.truth.angle)
        raw, r_share = direction_error(log.t, w_rot, log.truth.angle)
        comp, c_share = direction_error(log.t, compensate_payload(w_rot, q, fit.payload), log.truth.angle)
        rows.append(
            (
                f"edge {deg:+d}°, hand rotating ±90°: direction error (static {static:.2f}°, {s_share:.0%} reported)",
                f"{raw:.2f}° ({r_share:.0%} reported)",
                f"{comp:.2f}° ({c_share:.0%} reported; {comp - static:+.2f}° from static)",
            )
        )
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=3)
    args = ap.parse_args()
    rows = calibration_rows(args.seed) + gravity_rows(args.seed)
    print("| condition | papers' method | softtip |")
    print("| --- | --- | --- |")
    for r in rows:
        print(f"| {r[0]} | {r[1]} | {r[2]} |")


if __name__ == "__main__":
    main()
