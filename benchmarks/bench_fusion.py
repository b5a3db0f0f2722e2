"""Two-finger fusion on the simulator: the object's line and plane from both fingertips.

    python benchmarks/bench_fusion.py          # about a minute of CPU time
    python benchmarks/bench_fusion.py --physics drake --objects "plate 1 mm" "cube edge (90°)"   # Drake: 5-60 s a log the first time

The papers' two-fingered hand (softtip.sim.hand) with both fingertips on one object: a
plate's two edges pinched across its 30 mm width, a stick's two sides, a cube's two opposite
edges (90° wedges), at −45°, 0° and 30° at the right fingertip, the papers' grasp (joint and
gravity disturbances after the grasp), then the same rocked about two axes
(``simulate_two_finger(rock=True)``), Nano17-class noise, 50 Hz. Over the
held grasp (t > 6 s), time steps read as ``parallel_lines``: the median axial error of the
fused direction against the objects' true line (projected on the plane across the grasp, as
the fingertips measure it: its tilt toward the fingers is in neither measurement), of each
finger's own direction, and of the
plane normal through both lines (plates and sticks); and ``rms(error / reported std)`` per
run (1 when the standard deviations are calibrated).

Where a miscalibration comes from: each finger's own ``z`` (its angle error against its own
true line over its reported angle std: the single-finger estimator's calibration) and
whether the two fingers' errors have the same sign in the hand frame (a shared error, which
averaging the two cannot reduce). The spread of ``z`` per group (unrocked / rocked) closes
the table. ``--angles``, ``--seeds``, ``--noise`` (sensor noise × k, the estimator told the
Nano17 preset × k) and ``--objects`` check scenarios other than the default grid;
``--told-true-noise`` tells the estimator the simulated sensor's noise (with its quantisation)
instead of the Nano17 preset, which assumes 1.7 times the simulated force noise and 1.4 times
its moment noise: with the preset every reported std is conservative, the more so where the
noise dominates the error; ``--noise-from-tare`` lets the estimator measure the noise from a
1.5 s tare of each log (``EstimatorConfig(noise_from_tare="on")``; without it the estimator keeps the model it is told, ``"off"``), as a user would. ``--load R`` (``--load-direction``, ``--load-profile``) puts a
friction load on the object during the hold instead of rocking it
(:class:`softtip.sim.hand.FrictionLoad`, the same vector in the hand at both fingertips;
the stiffer 2 MPa shear layer of ``bench_accuracy.py --sections friction``), errors from the
load on. ``--rock-axes 0 30 60`` rocks each grasp three ways (the tangent axes of
:func:`softtip.sim.scenario.rock_scenario` turned by those angles): the 0.4° model error of
a confirmed line stands for how the axis turns with the pattern of excitation, which one
pattern per run shows as a fixed offset. ``--tip sphere`` puts a 12 mm sphere on both
fingers, a fingertip the defaults were not set on.

``--physics drake`` (or ``both``) simulates each fingertip with Drake's hydroelastic contact
instead of softtip's Winkler skin (``benchmarks/drake_physics.py``: the same scenarios, seeds
and sensor model; frictionless quasi-static for the papers' grasp and the rocking, SAP with
friction for ``--load``; logs cached under ``benchmarks/.cache/drake``, 5–60 s each the first
time). On that frictionless cap every thin line gives the same wrench (see the module), so a
plate and a cube's edge differ only by the loads they carry; ``--objects`` takes names from
either object list to run fewer of them.
"""

from __future__ import annotations

import argparse
import functools
import math
import sys
from pathlib import Path

import numpy as np

import softtip
from softtip.core.axial import axial_difference
from softtip.core.fingertip import Sphere
from softtip.core.noise import NANO17
from softtip.estimator import EstimatorConfig
from softtip.estimator.tare import noise_in_use
from softtip.fusion import Finger, PoseSeries, fuse
from softtip.sim import (
    ContactModel,
    ContactParams,
    Cylinder,
    Plate,
    Wedge,
    discretise_skin,
    stick,
)
from softtip.sim.hand import FrictionLoad, simulate_two_finger
from softtip.sim.sensor import SensorModel
from softtip.sim.simulate import FRICTION_SHEAR_MODULUS

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _markdown import markdown_option, run_with_markdown  # noqa: E402

HELD = 6.0
OBJECTS = {
    "plate 1 mm": lambda: Plate(0.001),
    "plate 2 mm": lambda: Plate(0.002),
    "stick Ø 4 mm": lambda: stick(0.004),
    "cube edge (90°)": lambda: Wedge(0.5 * math.pi),
}
#: Fingertips (``--tip``): the papers' and one the defaults were not set on.
TIPS = {
    "murakami2006": softtip.murakami2006,
    "sphere": lambda: Sphere(0.012, center=(0.0, 0.0, 0.012)),
}
#: Further objects for checks beyond the default grid (``--objects``).
MORE_OBJECTS = {
    "plate 3 mm": lambda: Plate(0.003),
    "stick Ø 6 mm": lambda: stick(0.006),
    "cylinder Ø 4 mm": lambda: Cylinder(0.004),
    "60° wedge": lambda: Wedge(math.pi / 3),
}


def _axial_deg(a, b):
    return np.degrees(np.arccos(np.clip(np.abs(np.sum(a * b, axis=-1)), 0.0, 1.0)))


def _drake(load) -> functools.partial:
    """Each finger simulated by Drake: frictionless quasi-static, or SAP with friction for a load."""
    from drake_physics import DRAKE_MISSING, drake_available, simulate_drake

    if not drake_available():
        raise SystemExit(DRAKE_MISSING)
    return functools.partial(simulate_drake, solver="quasistatic" if load is None else "sap", progress=sys.stderr.isatty())


def run_case(tip, model, obj, angle_deg, seed, rock=False, noise=1.0, told="preset", load=None, rock_axes=0.0,
             simulate=None):  # fmt: skip
    kw = {"rock_axes": math.radians(rock_axes)} if rock else {}
    kw.update({"model": model} if simulate is None else {"simulate": simulate})
    g = simulate_two_finger(tip, obj, math.radians(angle_deg), rng=seed, rock=rock, load=load, **kw)
    sensor = SensorModel(noise_std=tuple(noise * np.asarray(SensorModel().noise_std)))
    if told == "true":  # the estimator told the simulated sensor's noise with its quantisation, not the Nano17 preset's
        config = EstimatorConfig(noise=sensor.noise_model(), noise_from_tare="off")
    elif told == "tare":  # measured from the samples before contact (at about 2 s)
        config = EstimatorConfig(noise=NANO17.scaled(noise), noise_from_tare="on", tare_duration=1.5)
    else:  # the model it is told, whatever the tare shows
        config = EstimatorConfig(noise=NANO17.scaled(noise), noise_from_tare="off")
    fingers = []
    for k, side in enumerate(("right", "left")):
        log = g.logs[side]
        w = log.wrench if noise == 1.0 else sensor.measure(log.wrench_true, np.random.default_rng(1000 * seed + k))
        p = g.sensor_poses[side]
        est = softtip.estimate(log.t, w, tip, config)
        pose = PoseSeries.fixed(p.rotation, p.translation, side)
        fingers.append(Finger(side, est, pose, noise_in_use(config, est.tare)))
    fz = fuse(fingers, object_mass=g.object_mass)
    # rocked: once both axes were excited; a friction load: once it is on
    start = 8.0 if rock else (HELD if load is None else (9.5 if load.profile == "drag" else 7.0))
    held = (fz.t > start) & (fz.grasp_names == "parallel_lines")
    out = {"share": held.sum() / max(np.count_nonzero(fz.t > start), 1)}
    if not held.any():
        return out
    line = g.truth_line()[held]
    e = _axial_deg(fz.direction[held], line)
    out["fused"] = np.median(e)
    out["fused_z"] = np.sqrt(np.mean((np.radians(e) / fz.direction_std[held]) ** 2))
    signed = []
    for k, side in enumerate(("right", "left")):
        est = fingers[k].estimates
        d = (g.sensor_poses[side].rotation @ est.direction[held].T).T
        out[side] = np.nanmedian(_axial_deg(d, line))
        # the finger's own calibration: its angle error against its own true line
        own = held & (est.state == 2)
        e_own = np.abs(axial_difference(est.angle[own], g.logs[side].truth.angle[own]))
        out[side + "_z"] = np.sqrt(np.nanmean((e_own / est.angle_std[own]) ** 2))
        # signed error about the common axis (hand x, across the grasp)
        d = d * np.where(np.sum(d * line, axis=-1) < 0, -1.0, 1.0)[:, None]
        signed.append(np.nanmean(np.cross(line, d)[:, 0]))
    out["shared"] = signed[0] * signed[1] > 0
    n = g.truth_plane_normal()[held]
    en = _axial_deg(fz.plane_normal[held], n)
    out["normal"] = np.median(en)
    out["normal_z"] = np.sqrt(np.mean((np.radians(en) / fz.plane_normal_std[held]) ** 2))
    return out


def fusion_section(
    seeds=(1,), angles=(-45.0, 0.0, 30.0), objects=None, noise=1.0, told="preset", load=None, rock_axes=(0.0,),
    tip_name="murakami2006", physics="winkler",
) -> None:
    objects = objects or OBJECTS
    tip = TIPS[tip_name]()
    simulate = _drake(load) if physics == "drake" else None
    if simulate is not None:
        model = None
    elif load is None:
        model = ContactModel(discretise_skin(tip), ContactParams(), 2)
    else:  # the stiffer shear layer of bench_accuracy's friction section: the default cannot hold the loads
        model = ContactModel(discretise_skin(tip, 10000), ContactParams(shear_modulus=FRICTION_SHEAR_MODULUS), 2)
    print(f"\n### fusion: two fingertips on one object, {'Winkler skin' if simulate is None else 'Drake'}\n")
    print("Median over the held grasp (t > 6 s, or once rocked about both axes, t > 8 s); z = rms(error / reported std);")
    print("each finger's own z against its own line; shared:")
    what = {
        "true": "told the simulated sensor's",
        "tare": "measured it from a 1.5 s tare",
        "preset": "told the Nano17 preset's (1.7 times the simulated force noise, 1.4 times the moment noise)",
    }[told]
    print(f"both fingers' errors of one sign in the hand frame; sensor noise × {noise:g}; the estimator {what}; "
          f"fingertips: {tip_name}")
    if simulate is None:
        print("physics: softtip's Winkler skin")
    else:
        from drake_physics import drake_version

        print(f"physics: drake {drake_version()}, hydroelastic modulus 2 MPa, resolution hint 2 mm, "
              + ("frictionless quasi-static" if load is None else "SAP with friction μ = 1"))
    if load is not None:
        way = "across" if load.across else "along"
        skin = "shear modulus 2 MPa, 10 000 skin elements; " if simulate is None else ""
        print(f"With a friction load, {load.profile} {way} the line at the right fingertip"
              + (f", {load.ratio:g} of the grasp force" if load.profile != "slip" else "")
              + f", errors from t > {9.5 if load.profile == 'drag' else 7.0:g} s; {skin}no rocking")  # fmt: skip
    print()
    print("| object | rocked | angle | seed | parallel | right / left alone | finger z | shared | fused | z | plane normal | z |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for rock in (False,) if load is not None else (False, True):
        pooled = {"fused": [], "normal": [], "fused_z": [], "normal_z": [], "finger_z": [], "shared": []}
        per_object: dict[str, list[float]] = {}
        cases = [(name, make, a, s, ax) for name, make in objects.items() for a in angles for s in seeds
                 for ax in (rock_axes if rock else (0.0,))]  # fmt: skip
        for name, make, a, s, ax in cases:
            rocked = ("yes" if ax == 0.0 else f"axes {ax:+.0f}°") if rock else "no"
            try:
                r = run_case(tip, model, make(), a, s, rock, noise, told, load, ax, simulate)
            except RuntimeError as exc:  # the simulator cannot hold the grasp (friction)
                print(f"| {name} | {rocked} | {a:+.0f}° | {s} | simulator: {exc} |")
                continue
            if "fused" not in r:
                print(f"| {name} | {rocked} | {a:+.0f}° | {s} | {100 * r['share']:.0f} % | — | — | — | — | — | — | — |")
                continue
            for k in ("fused", "normal", "fused_z", "normal_z", "shared"):
                pooled[k].append(r[k])
            pooled["finger_z"] += [r["right_z"], r["left_z"]]
            per_object.setdefault(name, []).append(r["fused_z"])
            print(
                f"| {name} | {rocked} | {a:+.0f}° | {s} | {100 * r['share']:.0f} % | "
                f"{r['right']:.1f} / {r['left']:.1f}° | {r['right_z']:.2f} / {r['left_z']:.2f} | "
                f"{'yes' if r['shared'] else 'no'} | {r['fused']:.1f}° | {r['fused_z']:.2f} | {r['normal']:.1f}° | "
                f"{r['normal_z']:.2f} |"
            )
        if pooled["fused"]:
            fz, nz = np.asarray(pooled["fused_z"]), np.asarray(pooled["normal_z"])
            print(
                f"\n{'rocked' if rock else 'papers grasp'}: fused direction median {np.median(pooled['fused']):.1f}°, "
                f"plane normal median {np.median(pooled['normal']):.1f}°; z over runs: direction "
                f"{fz.min():.2f}–{fz.max():.2f} (rms {np.sqrt(np.mean(fz**2)):.2f}), normal "
                f"{nz.min():.2f}–{nz.max():.2f} (rms {np.sqrt(np.mean(nz**2)):.2f}); single fingers "
                f"{np.min(pooled['finger_z']):.2f}–{np.max(pooled['finger_z']):.2f}; errors shared in "
                f"{sum(pooled['shared'])} of {len(pooled['shared'])} runs"
            )
            each = ", ".join(f"{k} {np.sqrt(np.mean(np.square(v))):.2f}" for k, v in per_object.items())
            print(f"direction z per object (rms over its runs): {each}\n")


def main(argv: list[str]) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    markdown_option(ap)
    ap.add_argument("--seeds", type=int, nargs="*", default=[1])
    ap.add_argument("--angles", type=float, nargs="*", default=[-45.0, 0.0, 30.0], help="degrees at the right fingertip")
    ap.add_argument("--noise", type=float, default=1.0, help="sensor noise × this (the estimator told the Nano17 preset × this)")
    ap.add_argument("--objects", nargs="+", default=["default"], metavar="NAME",
                    help="'default' (the grid's four), 'more' (four others) or objects by name from either: "
                    + ", ".join(repr(k) for k in {**OBJECTS, **MORE_OBJECTS}))
    ap.add_argument("--physics", choices=("winkler", "drake", "both"), default="winkler",
                    help="each fingertip's contact model: softtip's Winkler skin, Drake's hydroelastic contact, or both in turn")
    told = ap.add_mutually_exclusive_group()
    told.add_argument("--told-true-noise", action="store_true", help="tell the estimator the simulated sensor's noise (default: the Nano17 preset)")
    told.add_argument("--noise-from-tare", action="store_true", help="the estimator measures the noise from a 1.5 s tare (default: the Nano17 preset)")
    ap.add_argument("--load", type=float, help="a friction load on the object, this fraction of the grasp force (no rocking)")
    ap.add_argument("--load-direction", choices=("across", "along"), default="across", help="at the right fingertip's line")
    ap.add_argument("--load-profile", choices=("push", "drag", "slip"), default="push")
    ap.add_argument("--tip", choices=sorted(TIPS), default="murakami2006", help="both fingertips' shape (sphere: R 12 mm)")
    ap.add_argument("--rock-axes", type=float, nargs="+", default=[0.0], metavar="DEG",
                    help="rock about tangent axes turned by these angles (one rocked run each; rock_scenario's rock_axes)")
    args = ap.parse_args(argv)
    known = {**OBJECTS, **MORE_OBJECTS}
    objects = {}
    for name in args.objects:
        if name in ("default", "more"):
            objects.update(OBJECTS if name == "default" else MORE_OBJECTS)
        elif name in known:
            objects[name] = known[name]
        else:
            ap.error(f"--objects: unknown object {name!r}; choose 'default', 'more' or one of {', '.join(map(repr, known))}")
    load = None
    if (args.load is not None or args.load_profile == "slip") and args.rock_axes != [0.0]:
        ap.error("--rock-axes goes with the rocked runs; a friction load is not rocked")
    if args.load is None and args.load_profile in ("push", "drag") and (args.load_profile, args.load_direction) != ("push", "across"):
        ap.error("--load-direction and --load-profile go with --load R (or --load-profile slip)")
    if args.load is not None or args.load_profile == "slip":
        load = FrictionLoad(args.load or 0.0, args.load_direction == "across", args.load_profile)
    told = "true" if args.told_true_noise else "tare" if args.noise_from_tare else "preset"
    for physics in ("winkler", "drake") if args.physics == "both" else (args.physics,):
        fusion_section(tuple(args.seeds), tuple(args.angles), objects, args.noise, told, load, tuple(args.rock_axes),
                       args.tip, physics)  # fmt: skip


if __name__ == "__main__":
    sys.exit(run_with_markdown(main, "bench_fusion.py"))
