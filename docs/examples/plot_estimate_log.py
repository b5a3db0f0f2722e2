"""
Estimate a log
==============

Run the estimator on the shipped example grasp (a simulated 45° line contact on the
papers' fingertip with Nano17-class noise) and draw the papers' four panels: force,
moment, the tangential spin torque ``|h|`` with its significance level, and the measured
direction with the truth (45°) dashed.
"""

import numpy as np

import softtip
from softtip.viz.plot import plot_estimates

log = softtip.load_example()  # or softtip.io.tables.read_log("grasp.csv")
est = softtip.estimate(log.t, log.wrench, "murakami2006")

line = est.state == softtip.STATES.index("line")
print(f"{line.sum()} of {len(est.t)} samples are a line contact")
print(f"median direction {np.degrees(np.nanmedian(est.angle[line])):.1f}° (truth 45°)")

fig = plot_estimates(est, reference_angles=[45.0])
