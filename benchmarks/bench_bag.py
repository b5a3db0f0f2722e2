"""Writing estimates as a bag (`softtip estimate --to-bag`): CPU time per sample for each
--ros-distro format, with and without RViz markers, on a 1 kHz log.

The log is the example grasp's wrench interpolated to 1 kHz and repeated (the estimates' content does not
change the cost much: a contact adds the point, normal and edge messages). CPU time
(``time.process_time``), best of ``--repeat`` runs; on a shared machine the figures are
noisy, the ratios less so.

    python benchmarks/bench_bag.py [--seconds 20] [--repeat 3]
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from softtip import estimate, load_example
from softtip.io.bag import write_estimates_bag


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=20.0, help="log length at 1 kHz (default 20 s)")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    ex = load_example()
    n = int(args.seconds * 1000)
    t = np.arange(n) * 1e-3
    tc = np.mod(t, ex.t[-1])  # the example grasp (50 Hz), interpolated to 1 kHz and repeated
    wrench = np.stack([np.interp(tc, ex.t, ex.wrench[:, j]) for j in range(6)], axis=-1)
    est = estimate(t, wrench, "murakami2006")
    print(f"{n} samples (1 kHz), {np.mean(est.state != 0):.0%} in contact; CPU µs per sample, best of {args.repeat}")
    print(f"{'format':10s} {'no markers':>11s} {'markers 50 Hz':>14s} {'every sample':>13s}")
    root = Path(tempfile.mkdtemp(prefix="bench_bag."))
    try:
        for distro in ("humble", "iron", "jazzy", "noetic"):
            row = []
            for markers, rate in ((False, None), (True, 50.0), (True, None)):
                best = np.inf
                for k in range(args.repeat):
                    dest = root / (f"{distro}{k}{markers}{rate}" + (".bag" if distro == "noetic" else ""))
                    t0 = time.process_time()
                    write_estimates_bag(dest, est, wrench, distro=distro, markers=markers, marker_rate=rate)
                    best = min(best, time.process_time() - t0)
                    shutil.rmtree(dest, ignore_errors=True) if dest.is_dir() else dest.unlink()
                row.append(best / n * 1e6)
            print(f"{distro:10s} {row[0]:11.0f} {row[1]:14.0f} {row[2]:13.0f}")
    finally:
        shutil.rmtree(root, ignore_errors=True)


if __name__ == "__main__":
    main()
