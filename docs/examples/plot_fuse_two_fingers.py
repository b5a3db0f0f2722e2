"""
Fuse two fingertips
===================

Simulate both fingertips of the papers' two-fingered hand pinching a 1 mm plate at 30°,
estimate each fingertip's log, and fuse the two contacts into the grasped object's line
and the plate's plane, with the simulator's truth dashed.
"""

import math

import softtip
from softtip.fusion import PoseSeries, fuse_logs
from softtip.fusion.plot import plot_fused
from softtip.sim import Plate
from softtip.sim.hand import simulate_two_finger

tip = softtip.murakami2006()
grasp = simulate_two_finger(tip, Plate(0.001), math.radians(30), n_elements=2000, duration=7.0)

logs = []
for side in ("right", "left"):
    pose = grasp.sensor_poses[side]
    logs.append((side, grasp.logs[side].t, grasp.logs[side].wrench, PoseSeries.fixed(pose.rotation, pose.translation, side)))
fused, fingers = fuse_logs(logs, tip, object_mass=grasp.object_mass)

fig = plot_fused(fused, fingers, truth_line=grasp.truth_line(), truth_normal=grasp.truth_plane_normal())
