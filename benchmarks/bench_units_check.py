"""The units check (softtip.core.lever) over simulated grasps: false alarms and detections.

    python benchmarks/bench_units_check.py      # 72 grasps (about 15 s of CPU time)

For two fingertips, six objects, three edge angles and both scenarios (the papers' grasp and a
plain push), simulate a grasp (20 Hz, 1500 skin elements), tare it on its first samples and
compute the median moment-to-force lever: read in the right units (must be accepted) and as
a kgf-mm log read as SI (should be refused). Prints one line per grasp, then the counts.
"""

import itertools

import numpy as np

from softtip.core.fingertip import Sphere, load_fingertip
from softtip.core.lever import force_lever
from softtip.core.units import KGF, KGF_MM
from softtip.sim.simulate import run_simulation

tips = {"murakami2006": load_fingertip("murakami2006"), "sphere10": Sphere(0.010, (0.0, 0.0, 0.012))}
rows = []
for (tname, tip), kind, angle, scen in itertools.product(tips.items(), ["plane", "plate", "cylinder", "stick", "fringe", "wedge"], [0.0, 45.0, 90.0], ["paper", "push"]):
    try:
        log = run_simulation(kind, None, angle, scenario=scen, tip=tip, rate=20.0, n_elements=1500, seed=1, force=0.5*9.80665 if tname=="murakami2006" else 2.0)
    except Exception as e:
        print("skip", tname, kind, angle, scen, type(e).__name__); continue
    w = log.wrench - log.wrench[: 4].mean(axis=0)
    si = force_lever(w, tip)
    wk = np.concatenate([w[:, :3] / KGF, w[:, 3:] / KGF_MM], axis=1)
    mis = force_lever(wk, tip)
    rows.append((tname, kind, angle, scen, si.median * 1e3, si.plausible, mis.median * 1e3, mis.plausible, si.reach * 1e3))
    print(*rows[-1], flush=True)
si_ok = sum(r[5] for r in rows); mis_caught = sum(not r[7] for r in rows)
print(f"{len(rows)} grasps: SI accepted {si_ok}/{len(rows)}, kgf-mm read as SI refused {mis_caught}/{len(rows)}; max SI lever/reach {max(r[4]/r[8] for r in rows):.3f}, min misread lever/reach {min(r[6]/r[8] for r in rows):.2f}")
for scen in ("paper", "push"):
    sub = [r for r in rows if r[3] == scen]
    print(f"{scen}: {len(sub)} grasps, SI accepted {sum(r[5] for r in sub)}, kgf-mm read as SI refused {sum(not r[7] for r in sub)}")
