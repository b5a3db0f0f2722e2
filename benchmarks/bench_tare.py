"""Tare, drift and contact flicker: the defaults against the papers' plain pipeline.

    python benchmarks/bench_tare.py [--seeds 10]

"plain" is the pipeline without this release's safeguards: mean tare, one contact
threshold, no minimum duration, no drift tracking (``tare_method="mean",
contact_hysteresis=0, min_contact_duration=0, drift_tracking=False``), which gives the same
numbers as softtip before them. Prints, on synthetic logs (Nano17-class noise):

- a −20 N spike in one sample of the 0.2 s tare: the median edge direction of a 45° grasp;
- an untouched sensor drifting −1 mN/s for 80 s at 50 Hz: the first (false) contact, and
  how fast a drift the default follows;
- contact segments per synthetic grasp at 1 kHz and 7 kHz (one true contact each);
- warnings on clean grasps (false alarms) at 50 Hz and 1 kHz;
- the bias error of the three tare methods over many 10-sample tares.
"""

from __future__ import annotations

import argparse
import warnings

import numpy as np

from softtip import EstimatorConfig, axial_difference, estimate
from softtip.core.noise import NANO17
from softtip.estimator.results import EstimatorWarning
from softtip.sim.synthetic import synthetic_grasp

PLAIN = EstimatorConfig(tare_method="mean", contact_hysteresis=0.0, min_contact_duration=0.0, drift_tracking=False)
DEFAULT = EstimatorConfig()
NOISE = np.r_[NANO17.force_std, NANO17.moment_std]


def run(t, w, cfg):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", EstimatorWarning)
        return estimate(t, w, "murakami2006", cfg)


def segments(mask):
    return int(np.count_nonzero(np.diff(np.r_[0, mask.astype(np.int8)]) == 1))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", type=int, default=10)
    args = ap.parse_args()
    seeds = range(args.seeds)

    print("spike of -20 N in one tare sample, 45° grasp at 50 Hz: median direction (deg), warnings")
    for name, cfg in (("plain", PLAIN), ("default", DEFAULT)):
        ang, warned = [], 0
        for s in seeds:
            g = synthetic_grasp(angle_deg=45.0, seed=s)
            w = g.wrench.copy()
            w[5, 2] -= 20.0
            est = run(g.t, w, cfg)
            line = est.state == 2
            ang.append(np.degrees(np.median(est.angle[line])) if line.any() else np.nan)
            warned += bool(est.warnings)
        print(f"  {name:8s} median over seeds {np.nanmedian(ang):6.1f}  range {np.nanmin(ang):6.1f}–{np.nanmax(ang):6.1f}"
              f"   warned {warned}/{len(seeds)}")  # fmt: skip

    print("untouched sensor drifting -1 mN/s, 80 s at 50 Hz: first contact (s), drift warning")
    for name, cfg in (("plain", PLAIN), ("default", DEFAULT)):
        first, alarms = [], 0
        for s in seeds:
            rng = np.random.default_rng(s)
            t = np.arange(4000) / 50.0
            w = rng.normal(size=(len(t), 6)) * NOISE
            w[:, 2] -= 1e-3 * t
            est = run(t, w, cfg)
            c = est.state > 0
            first.append(t[np.argmax(c)] if c.any() else np.nan)
            alarms += est.drift_alarm
        f = np.array(first)
        print(f"  {name:8s} false contact in {np.count_nonzero(np.isfinite(f))}/{len(seeds)} logs"
              + (f", first at {np.nanmin(f):.1f}–{np.nanmax(f):.1f} s" if np.isfinite(f).any() else "")
              + f"; drift warning in {alarms}/{len(seeds)}")  # fmt: skip

    print("how fast a drift the default follows: untouched, 120 s at 50 Hz, first false contact (s)")
    for rate in (2e-3, 3e-3, 4e-3, 6e-3):
        first = []
        for s in seeds:
            rng = np.random.default_rng(s)
            t = np.arange(6000) / 50.0
            w = rng.normal(size=(len(t), 6)) * NOISE
            w[:, 2] -= rate * t
            c = run(t, w, DEFAULT).contact_id > 0
            first.append(t[np.argmax(c)] if c.any() else np.nan)
        f = np.array(first)
        print(f"  {rate * 1e3:.0f} mN/s: false contact in {np.count_nonzero(np.isfinite(f))}/{len(seeds)} logs"
              + (f", first at {np.nanmin(f):.1f}–{np.nanmax(f):.1f} s" if np.isfinite(f).any() else ""))

    print("contact segments per synthetic grasp (one true contact), and the median direction error (deg)")
    for rate, duration in ((1000.0, 10.0), (7000.0, 7.0)):
        for name, cfg in (("plain", PLAIN), ("hysteresis only", EstimatorConfig(min_contact_duration=0.0)),
                          ("default", DEFAULT)):  # fmt: skip
            segs, errs = [], []
            for s in seeds:
                g = synthetic_grasp(angle_deg=45.0, rate=rate, seed=s, duration=duration)
                est = run(g.t, g.wrench, cfg)
                segs.append(segments(est.contact_id > 0))
                line = (est.state == 2) & (g.t >= 6.0)
                errs.append(np.median(np.degrees(np.abs(axial_difference(est.angle[line], g.angle)))))
            print(f"  {rate:5.0f} Hz {name:16s} segments mean {np.mean(segs):.1f} (min {min(segs)}, max {max(segs)}); "
                  f"median error {np.median(errs):.2f}")  # fmt: skip

    print("warnings on clean grasps (false alarms)")
    for rate, n in ((50.0, 5 * args.seeds), (1000.0, args.seeds)):
        warned = sum(bool(run(g.t, g.wrench, DEFAULT).warnings)
                     for g in (synthetic_grasp(angle_deg=30.0, rate=rate, seed=s) for s in range(n)))  # fmt: skip
        print(f"  {rate:6.0f} Hz: {warned}/{n} grasps warned")

    print("bias error of a 10-sample tare, force z (N), 20000 tares of Nano17-class noise")
    rng = np.random.default_rng(0)
    s = rng.normal(size=(20000, 10)) * NOISE[2]
    med = np.median(s, axis=1)
    print(f"  mean / robust (mean without spikes; no spike here): std {np.std(s.mean(axis=1)):.5f}"
          f"   median: std {np.std(med):.5f} ({np.std(med) / np.std(s.mean(axis=1)):.2f}x)")  # fmt: skip


if __name__ == "__main__":
    main()
