"""
Simulate a grasp and reproduce a figure
=======================================

Simulate the papers' grasp of a 1 mm thin plate at four angles (−45°, 0°, 45°, 90°;
experiment E2 of the 2006 paper) with a coarser skin (4000 elements instead of the
reproduction's 11 921, so that it runs in seconds), estimate each log and draw the
direction chart with the true angles dashed. At 90° the grasp makes no spin torque
across the plate, and softtip reports the direction as unobservable, as the paper did.
``softtip reproduce`` runs every experiment at full resolution.
"""

import math

import softtip
from softtip.sim import Plate, paper_scenario, simulate_grasp
from softtip.viz.plot import plot_direction_chart

tip = softtip.murakami2006()
angles = [-45.0, 0.0, 45.0, 90.0]
runs = []
for angle in angles:
    log = simulate_grasp(tip, Plate(0.001), paper_scenario(math.radians(angle)), rng=2006, n_elements=4000)
    runs.append(softtip.estimate(log.t, log.wrench, tip, softtip.EstimatorConfig(drift_tracking=False)))

fig = plot_direction_chart([("plate 1 mm", runs, [f"{a:g}°" for a in angles], angles)])
