"""Simulator benchmark: a 10 s, 50 Hz grasp (500 samples) with >= 10 000 skin elements.

Target (manual §6): <= 2 s on one core. Prints the best of a few runs per object, excluding
the one-off skin discretisation (reported separately).

    python benchmarks/bench_sim.py [--elements N] [--repeat K]
"""

from __future__ import annotations

import argparse
import math
import time

from softtip.core.fingertip import murakami2006
from softtip.sim import ContactModel, ContactParams, Cylinder, Plate, Wedge, discretise_skin, paper_scenario, simulate_grasp


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--elements", type=int, default=12_000)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    tip = murakami2006()
    t0 = time.perf_counter()
    model = ContactModel(discretise_skin(tip, args.elements), ContactParams()).prepare()
    setup = time.perf_counter() - t0
    print(f"skin: {len(model.skin)} elements x {model.quadrature ** 2} quadrature points, setup {setup:.3f} s")
    worst = 0.0
    for name, obj in [("plate 1 mm", Plate(0.001)), ("cylinder 6 mm", Cylinder(0.006)), ("wedge 90°", Wedge())]:
        for angle in (0.0, 45.0):
            best = math.inf
            for _ in range(args.repeat):
                t = time.perf_counter()
                log = simulate_grasp(tip, obj, paper_scenario(math.radians(angle)), rng=0, model=model)
                best = min(best, time.perf_counter() - t)
            worst = max(worst, best)
            print(f"{name:14s} {angle:5.1f}°  {len(log.t)} samples  {best:.3f} s")
    print(f"slowest: {worst:.3f} s for a 500-sample grasp (target <= 2 s)")


if __name__ == "__main__":
    main()
