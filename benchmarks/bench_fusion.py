"""Two-finger fusion on the simulator: the object's line and plane from both fingertips.

    python benchmarks/bench_fusion.py          # ~2 min on a quiet 2-core machine

The papers' two-fingered hand (softtip.sim.hand) with both fingertips on one object: a
plate's two edges pinched across its 30 mm width, a stick's two sides, a cube's two opposite
edges (90° wedges), at −45°, 0° and 45° at the right fingertip, two seeds each, the papers'
grasp (joint and gravity disturbances after the grasp), Nano17-class noise, 50 Hz. Over the
held grasp (t > 6 s), time steps read as ``parallel_lines``: the median axial error of the
fused direction against the objects' true line (projected on the plane across the grasp, as
the fingertips measure it: its tilt toward the fingers is in neither measurement), of each
finger's own direction, and of the
plane normal through both lines (plates and sticks); and ``rms(error / reported std)`` per
run (1 when the standard deviations are calibrated).
"""

from __future__ import annotations

import argparse
import math

import numpy as np

import softtip
from softtip.fusion import Finger, PoseSeries, fuse
from softtip.sim import ContactModel, ContactParams, Plate, Wedge, discretise_skin, stick
from softtip.sim.hand import simulate_two_finger

HELD = 6.0
OBJECTS = {
    "plate 1 mm": lambda: Plate(0.001),
    "plate 2 mm": lambda: Plate(0.002),
    "stick Ø 4 mm": lambda: stick(0.004),
    "cube edge (90°)": lambda: Wedge(0.5 * math.pi),
}


def _axial_deg(a, b):
    return np.degrees(np.arccos(np.clip(np.abs(np.sum(a * b, axis=-1)), 0.0, 1.0)))


def run_case(tip, model, obj, angle_deg, seed):
    g = simulate_two_finger(tip, obj, math.radians(angle_deg), rng=seed, model=model)
    fingers = []
    for side in ("right", "left"):
        log = g.logs[side]
        p = g.sensor_poses[side]
        fingers.append(Finger(side, softtip.estimate(log.t, log.wrench, tip), PoseSeries.fixed(p.rotation, p.translation, side)))
    fz = fuse(fingers, object_mass=g.object_mass)
    held = (fz.t > HELD) & (fz.grasp_names == "parallel_lines")
    out = {"share": held.sum() / max(np.count_nonzero(fz.t > HELD), 1)}
    if not held.any():
        return out
    line = g.truth_line()[held]
    e = _axial_deg(fz.direction[held], line)
    out["fused"] = np.median(e)
    out["fused_z"] = np.sqrt(np.mean((np.radians(e) / fz.direction_std[held]) ** 2))
    for k, side in enumerate(("right", "left")):
        est = fingers[k].estimates
        d = g.sensor_poses[side].rotation @ est.direction[held].T
        out[side] = np.nanmedian(_axial_deg(d.T, line))
    n = g.truth_plane_normal()[held]
    en = _axial_deg(fz.plane_normal[held], n)
    out["normal"] = np.median(en)
    out["normal_z"] = np.sqrt(np.mean((np.radians(en) / fz.plane_normal_std[held]) ** 2))
    return out


def fusion_section(seeds=(1, 2), angles=(-45.0, 0.0, 45.0)) -> None:
    tip = softtip.murakami2006()
    model = ContactModel(discretise_skin(tip), ContactParams(), 2)
    print("\n## fusion: two fingertips on one object (median over t > 6 s; z = rms(error / reported std))\n")
    print("| object | angle | seed | parallel | right / left alone | fused | z | plane normal | z |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    pooled = {"fused": [], "normal": [], "fused_z": [], "normal_z": []}
    for name, make in OBJECTS.items():
        for a in angles:
            for s in seeds:
                r = run_case(tip, model, make(), a, s)
                if "fused" not in r:
                    print(f"| {name} | {a:+.0f}° | {s} | {100 * r['share']:.0f} % | — | — | — | — | — |")
                    continue
                for k in pooled:
                    pooled[k].append(r[k])
                print(
                    f"| {name} | {a:+.0f}° | {s} | {100 * r['share']:.0f} % | {r['right']:.1f} / {r['left']:.1f}° | "
                    f"{r['fused']:.1f}° | {r['fused_z']:.2f} | {r['normal']:.1f}° | {r['normal_z']:.2f} |"
                )
    if pooled["fused"]:
        print(
            f"\nall: fused direction median {np.median(pooled['fused']):.1f}°, plane normal median "
            f"{np.median(pooled['normal']):.1f}°; z over runs: direction {np.min(pooled['fused_z']):.2f}–"
            f"{np.max(pooled['fused_z']):.2f} (median {np.median(pooled['fused_z']):.2f}), normal "
            f"{np.min(pooled['normal_z']):.2f}–{np.max(pooled['normal_z']):.2f} (median {np.median(pooled['normal_z']):.2f})"
        )


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=int, nargs="*", default=[1, 2])
    args = ap.parse_args()
    fusion_section(tuple(args.seeds))
