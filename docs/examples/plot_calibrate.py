"""
Calibrate a fingertip
=====================

Fit a spherical fingertip's centre and radius to the shipped probing log (plane presses
spread over the skin, made by ``scripts/make_calibration_examples.py``), then show where
the presses touched.
"""

import matplotlib.pyplot as plt

from softtip.calibration.probing import calibrate_fingertip
from softtip.io.examples import EXAMPLE_PROBING_PATH
from softtip.io.tables import read_log

log = read_log(EXAMPLE_PROBING_PATH)
cal = calibrate_fingertip(log.t, log.wrench, shape="sphere")
print(cal.summary())

f = log.wrench[:, :3]
fig, ax = plt.subplots(figsize=(6, 3), layout="constrained")
ax.plot(log.t, (f**2).sum(axis=1) ** 0.5, lw=0.8)
ax.set_xlabel("time [s]")
ax.set_ylabel("|f| [N]")
ax.set_title("Probing log: one bump per press")
