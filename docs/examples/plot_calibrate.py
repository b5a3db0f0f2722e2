"""
Calibrate a fingertip
=====================

Fit a spherical fingertip's centre and radius to the shipped probing log (plane presses
spread over the skin, made by ``scripts/make_calibration_examples.py`` on a sphere of radius
16 mm centred at (0.3, −0.2, 20) mm), then show the presses over time and where each touched
the fitted skin (``softtip calibrate probing.csv --shape sphere`` on the command line).
"""

import matplotlib.pyplot as plt
import numpy as np

from softtip.calibration.probing import calibrate_fingertip, find_presses
from softtip.io.examples import EXAMPLE_PROBING_PATH
from softtip.io.tables import read_log
from softtip.viz.style import NEUTRAL, PALETTE, RC, TRUTH, label, legend_outside

log = read_log(EXAMPLE_PROBING_PATH)
cal = calibrate_fingertip(log.t, log.wrench, shape="sphere")
print(cal.summary())

# %%
# Left: ``|f|`` with each press shaded. Right: the fitted skin seen from above (along the
# sensor's z axis: its outline is the circle) with the contact point of each press, the
# centre plus the radius along the press's fitted normal: the presses cover the cap the
# fingertip touches with.

f = np.linalg.norm(log.wrench[:, :3] - log.wrench[:10, :3].mean(axis=0), axis=1)
with plt.rc_context(RC):
    fig, (ax_t, ax_s) = plt.subplots(1, 2, figsize=(9, 3.6), layout="constrained", width_ratios=(1.6, 1))
    ax_t.plot(log.t, f, color=PALETTE[0], label="|f|")
    for k, press in enumerate(find_presses(f, contact_threshold=0.05)):
        ax_t.axvspan(log.t[press[0]], log.t[press[-1]], color=NEUTRAL, alpha=0.15, lw=0,
                     label="a press" if k == 0 else None)  # fmt: skip
    ax_t.set_xlabel(label("time", "s"))
    ax_t.set_ylabel(label("|f|", "N"))
    legend_outside(ax_t)

    c_mm, r_mm = cal.center * 1e3, cal.radius * 1e3
    a = np.linspace(0.0, 2.0 * np.pi, 200)
    ax_s.plot(c_mm[0] + r_mm * np.cos(a), c_mm[1] + r_mm * np.sin(a), "--", color=TRUTH, lw=1.0,
              label=f"fitted skin, r = {r_mm:.2f} ± {cal.radius_std * 1e3:.2f} mm")  # fmt: skip
    points = c_mm + r_mm * cal.normals
    ax_s.plot(points[:, 0], points[:, 1], "o", color=PALETTE[1], label=f"{cal.n_presses} presses")
    ax_s.set_aspect("equal")
    ax_s.set_xlabel(label("x", "mm"))
    ax_s.set_ylabel(label("y", "mm"))
    legend_outside(ax_s, ncol=1)
plt.show()
