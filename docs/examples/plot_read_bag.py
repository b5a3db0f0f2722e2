"""
Read a ROS bag
==============

softtip reads ROS 1 and ROS 2 bags without a ROS installation (the ``ros`` extra,
``pip install "softtip[ros]"``). Here the example grasp is written as a ROS 2 bag
(``geometry_msgs/msg/WrenchStamped`` on ``/ft_sensor/wrench``, with softtip's estimates),
then read back and estimated as any log.
"""

import tempfile
import warnings
from pathlib import Path

import numpy as np

import softtip
from softtip.io.bag import read_bag, write_estimates_bag
from softtip.viz.plot import plot_estimates

log = softtip.load_example()
with warnings.catch_warnings():
    warnings.simplefilter("ignore", softtip.EstimatorWarning)
    est = softtip.estimate(log.t, log.wrench, "murakami2006")

bag_dir = Path(tempfile.mkdtemp()) / "grasp_bag"
write_estimates_bag(bag_dir, est, log.wrench, frame_id="ft_sensor", raw_topic="/ft_sensor/wrench")
print(sorted(p.name for p in bag_dir.iterdir()))

bag = read_bag(bag_dir, "/ft_sensor/wrench")
print(f"{len(bag.t)} WrenchStamped messages, frame {bag.frame_ids[0]!r}")
again = softtip.estimate(bag.t, bag.wrench, "murakami2006")
line = again.state == softtip.STATES.index("line")
print(f"median direction {np.degrees(np.nanmedian(again.angle[line])):.1f}° (truth 45°)")

fig = plot_estimates(again, reference_angles=[45.0])
