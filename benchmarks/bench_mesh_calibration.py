"""Monte Carlo check of the mesh placement calibration's standard deviations.

    python benchmarks/bench_mesh_calibration.py [--trials 100] [--presses 20]

Each trial shifts a tessellated capsule (the papers' fingertip, 64 segments) by a random
offset (0.5 mm per axis), synthesises a probing log of plane presses on it
(softtip.sim.probing.mesh_probing_log: soft-finger model, skin indentation 0.2 mm/√N,
friction 0.25 turning through 90° per press, Nano17 noise at 200 Hz) and fits the shift
with the capsule at its nominal place. Prints the RMS error per axis and the error / reported
standard deviation (mean: bias in standard deviations; spread: should be 0.7-1.5).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from softtip.calibration.mesh import calibrate_mesh
from softtip.core.mesh import MeshFingertip, capsule_mesh
from softtip.core.noise import NANO17
from softtip.sim.probing import mesh_probing_log


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--trials", type=int, default=100)
    ap.add_argument("--presses", type=int, default=20,
                    help="plane presses per trial (calibrate_mesh needs 6 usable ones for the offset, 9 with the rotation)")
    args = ap.parse_args()
    v, f = capsule_mesh(0.016, 0.020, segments=64)
    nominal = MeshFingertip(v, f)
    err, z, kappa = [], [], []
    t0 = time.perf_counter()
    for trial in range(args.trials):
        rng = np.random.default_rng(1000 + trial)
        shift = rng.normal(scale=0.5e-3, size=3)
        t, w = mesh_probing_log(MeshFingertip(v + shift, f), args.presses, rng, noise=NANO17)
        cal = calibrate_mesh(t, w, nominal)
        err.append(cal.translation - shift)
        z.append((cal.translation - shift) / cal.translation_std)
        kappa.append((cal.compliance - 2e-4) / cal.compliance_std)
    err, z, kappa = np.array(err), np.array(z), np.array(kappa)
    print(f"mesh placement calibration, {args.trials} trials of {args.presses} presses ({time.perf_counter() - t0:.0f} s)")
    for i, axis in enumerate("xyz"):
        print(
            f"  {axis}: rms error {np.sqrt(np.mean(err[:, i] ** 2)) * 1e3:.3f} mm   "
            f"error/std mean {z[:, i].mean():+.2f}, spread {z[:, i].std():.2f}"
        )
    print(f"  compliance: error/std mean {kappa.mean():+.2f}, spread {kappa.std():.2f}")


if __name__ == "__main__":
    main()
