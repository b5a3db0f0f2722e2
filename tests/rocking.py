"""A synthetic rocking grasp (no simulator): a line or an area contact at the fingertip's
top, tilted about two tangent axes with the tangential load turning with the tilt axis."""

import math

import numpy as np

from softtip.core.fingertip import load_fingertip
from softtip.core.noise import NANO17
from softtip.core.spin import tangent_frame_kernel
from softtip.sim.synthetic import smoothstep
from softtip.core._xp import NP

#: Moment per tilt, N·m/rad (≈ 1.3 N·mm per degree: a thin strip at 0.5 kgf).
STIFFNESS = 0.0745


def rocking_log(kind="line", angle_deg=30.0, *, rate=50.0, seed=0, excite="two", amplitude_deg=3.0, load=0.03,
                roll=0.02, noise=NANO17, duration=9.0):  # fmt: skip
    """``(t, wrench, truth_angle)``: tare 1 s, force ramp 1–2 s to 0.5 kgf, a static tilt
    ramped in over 2–2.5 s, then rocking about e1 (3–5 s), e2 (5–7 s) and a figure-eight
    (7–9 s); ``excite="one"``: about one tangent axis (e2) throughout. A ``line`` transmits
    the tilt about ``e = n × d`` (and ``roll`` of it about ``d``), an ``area`` about both."""
    tip = load_fingertip("murakami2006")
    r = tip.project(np.array([0.0, 0.0, 1.0]))
    n = tip.normal(r)
    e1x, e1y, e1z, e2x, e2y, e2z = (float(v) for v in tangent_frame_kernel(*n, NP))
    e1, e2 = np.array([e1x, e1y, e1z]), np.array([e2x, e2y, e2z])
    a = math.radians(angle_deg)
    d = math.cos(a) * e1 + math.sin(a) * e2
    e = np.cross(n, d)
    t = np.arange(0.0, duration, 1.0 / rate)
    force = 0.5 * 9.80665 * smoothstep(t - 1.0)
    amp = math.radians(amplitude_deg)
    w = 2.0 * math.pi
    s1 = np.where((t >= 3.0) & (t < 5.0), np.sin(w * (t - 3.0)), 0.0)
    s2 = np.where((t >= 5.0) & (t < 7.0), np.sin(w * (t - 5.0)), 0.0)
    s1 = s1 + np.where((t >= 7.0) & (t < 9.0), np.sin(0.5 * w * (t - 7.0)), 0.0)
    s2 = s2 + np.where((t >= 7.0) & (t < 9.0), np.sin(w * (t - 7.0)), 0.0)
    if excite == "one":
        s1, s2 = 0.0 * t, np.where(t >= 3.0, np.sin(w * (t - 3.0)), 0.0)
    static = math.radians(3.5) * smoothstep((t - 2.0) / 0.5)
    tilt = amp * (s1[:, None] * e1 + s2[:, None] * e2) + static[:, None] * e2  # tilt vector, rad
    f_t = load * np.cross(n, amp * (s1[:, None] * e1 + s2[:, None] * e2)) / amp
    if kind == "line":
        h = STIFFNESS * ((tilt @ e)[:, None] * e + roll * (tilt @ d)[:, None] * d)
    elif kind == "area":
        h = STIFFNESS * tilt
    else:
        raise ValueError(kind)
    h = h * (force > 0.5)[:, None] * np.minimum(force / (0.5 * 9.80665), 1.0)[:, None]
    f = -force[:, None] * n + f_t * (force > 0.5)[:, None]
    m = np.cross(r, f) + h + 2e-4 * (force > 0.5)[:, None] * n
    wrench = np.concatenate((f, m), axis=1)
    rng = np.random.default_rng(seed)
    wrench = wrench + rng.normal(size=wrench.shape) * np.array(noise.force_std + noise.moment_std)
    return t, wrench, math.atan2(math.sin(a), math.cos(a))
