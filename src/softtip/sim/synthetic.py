"""Synthetic wrench logs from the contact models themselves (no contact mechanics).

:func:`synthetic_grasp` builds a grasp like the papers' (contact at 2 s, force rising to
about 0.5 kgf by 4 s, held to 10 s, 50 Hz) by writing the wrench that the line-contact
model of the manual (§3) predicts: ``m = r × f + σ n + h`` with ``h`` perpendicular to the touched
line. During the light-force phase ``h = 0`` (a soft-finger contact); the tangential spin
torque builds up after the force has settled, as the disturbance moments from the finger
joints and gravity do in the papers. It exercises the estimator with a known answer; the
contact-mechanics simulator is a separate matter.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.core.fingertip import Fingertip, load_fingertip
from softtip.core.noise import NANO17, SensorNoise
from softtip.core.spin import tangent_frame
from softtip.core.units import KGF, KGF_MM

__all__ = ["SyntheticGrasp", "synthetic_grasp", "sliding_presses", "smoothstep"]


@dataclass(frozen=True)
class SyntheticGrasp:
    """A synthetic log and its ground truth (SI, sensor frame).

    Attributes
    ----------
    t : (N,) s
    wrench : (N, 6) raw sensor wrench, bias and noise included
    wrench_true : (N, 6) noise- and bias-free wrench
    point : (3,) contact point, m
    normal : (3,) outward normal at the contact
    direction : (3,) unit direction of the touched line
    angle : float, rad, in the tangent frame of the manual (§3.4)
    bias : (6,)
    """

    t: NDArray[np.float64]
    wrench: NDArray[np.float64]
    wrench_true: NDArray[np.float64]
    point: NDArray[np.float64]
    normal: NDArray[np.float64]
    direction: NDArray[np.float64]
    angle: float
    bias: NDArray[np.float64]


def smoothstep(x: ArrayLike) -> NDArray[np.float64]:
    """``3x² − 2x³`` on ``x`` clipped to [0, 1]: a ramp with zero slope at both ends."""
    c = np.clip(np.asarray(x, dtype=float), 0.0, 1.0)
    return c * c * (3.0 - 2.0 * c)


def synthetic_grasp(
    tip: Fingertip | str = "murakami2006",
    *,
    angle_deg: float = 45.0,
    point: NDArray | None = None,
    duration: float = 10.0,
    rate: float = 50.0,
    contact_time: float = 2.0,
    settle_time: float = 4.0,
    force: float = 0.55 * KGF,
    tangential_ratio: float = 0.1,
    spin: float = 0.05 * KGF_MM,
    h_peak: float = 0.8 * KGF_MM,
    h_start: float = 4.5,
    h_rise: float = 1.5,
    noise: SensorNoise | None = NANO17,
    bias: NDArray | None = None,
    seed: int | None = 0,
) -> SyntheticGrasp:
    """A grasp on a line contact at ``angle_deg``, as a raw sensor log.

    Parameters
    ----------
    tip : Fingertip or str
    angle_deg : float
        Direction of the touched line in the tangent frame at the contact, degrees.
    point : array-like (3,), optional
        Contact point on the skin, m; default the fingertip's top (the point of the skin
        farthest along +z on the axis, found by projection).
    duration, rate, contact_time, settle_time : float
        s, Hz, s, s.
    force : float
        Held normal force, N (default 0.55 kgf).
    tangential_ratio : float
        Tangential force as a fraction of the normal force.
    spin : float
        Spin torque about the normal at full force, N·m.
    h_peak, h_start, h_rise : float
        Tangential spin torque reached (N·m), when it starts to build (s) and over how long (s).
    noise : SensorNoise or None
        Gaussian sensor noise; ``None`` for none.
    bias : array-like (6,), optional
        Sensor bias, N and N·m; default a fixed small offset.
    seed : int or None
    """
    tip = load_fingertip(tip)
    rng = np.random.default_rng(seed)
    t = np.arange(int(round(duration * rate))) / rate
    if point is None:
        centre, radius = tip.bounding_sphere
        point = tip.project(centre + np.array([0.0, 0.0, 2.0 * radius]))
    r = tip.project(np.asarray(point, dtype=float))
    n = tip.normal(r)
    e1, e2 = tangent_frame(n)
    a = math.radians(angle_deg)
    d = math.cos(a) * e1 + math.sin(a) * e2
    ht = np.cross(d, n)  # h ⟂ n and d, so that n × h ∥ d

    load = smoothstep((t - contact_time) / (settle_time - contact_time))
    fmag = force * load
    tang = tangential_ratio * fmag[:, None] * (0.6 * e1 + 0.8 * e2)
    f = -fmag[:, None] * n + tang
    sigma = spin * load
    hmag = h_peak * smoothstep((t - h_start) / h_rise)
    m = np.cross(r, f) + sigma[:, None] * n + hmag[:, None] * ht
    w_true = np.concatenate((f, m), axis=-1)
    b = np.array([0.12, -0.05, 0.3, 2e-3, -1e-3, 5e-4]) if bias is None else np.asarray(bias, dtype=float)
    w = w_true + b
    if noise is not None:
        std = np.concatenate((noise.force_std, noise.moment_std))
        w = w + rng.normal(size=w.shape) * std
    return SyntheticGrasp(t, w, w_true, r, n, d, math.atan2(float(d @ e2), float(d @ e1)), b)


def sliding_presses(
    rng: np.random.Generator,
    n_presses: int = 30,
    center=(0.3e-3, -0.2e-3, 20e-3),
    radius: float = 16e-3,
    kappa: float = 0.2e-3,
) -> tuple[NDArray, NDArray]:
    """A probing log of plane presses on a sphere, made without softtip's simulator and
    noise-free: ``(t (N,), wrench (N, 6))``, SI.

    Rigid sphere plus an indentation ``kappa √F`` along the normal; presses within 65° of
    the tip, each 1 s at 100 Hz with the normal force rising to 2–6 N and falling again and a
    friction force of 0.1–0.3 of it turning through 40–120° meanwhile; 0.3 s untouched
    between presses and 0.5 s first. An independent check of ``softtip calibrate``.
    """
    c, dt = np.asarray(center), 0.01
    t, w = [np.arange(0.0, 0.5, dt)], [np.zeros((50, 6))]
    t0 = 0.5
    for _ in range(n_presses):
        cz = rng.uniform(math.cos(math.radians(65.0)), 1.0)
        phi = rng.uniform(0.0, 2.0 * math.pi)
        n = np.array([math.sqrt(1 - cz * cz) * math.cos(phi), math.sqrt(1 - cz * cz) * math.sin(phi), cz])
        a = np.cross([1.0, 0.0, 0.0], n)
        a /= np.linalg.norm(a)
        b = np.cross(n, a)
        force, mu = rng.uniform(2.0, 6.0), rng.uniform(0.1, 0.3)
        turn = math.radians(rng.uniform(40.0, 120.0)) * rng.choice([-1.0, 1.0])
        s = np.arange(0.0, 1.0, dt)
        f_normal = force * np.clip(np.minimum(s, 1.0 - s) / 0.5, 0.0, 1.0)
        ang = rng.uniform(0.0, 2.0 * math.pi) + turn * s
        f = -f_normal[:, None] * n + mu * f_normal[:, None] * (np.cos(ang)[:, None] * a + np.sin(ang)[:, None] * b)
        r = c + (radius - kappa * np.sqrt(f_normal))[:, None] * n
        m = np.cross(r, f) + (rng.normal(0.0, 0.2e-3) * f_normal)[:, None] * n
        t += [t0 + s, t0 + 1.0 + np.arange(0.0, 0.3, dt)]
        w += [np.column_stack((f, m)), np.zeros((30, 6))]
        t0 += 1.3
    return np.concatenate(t), np.concatenate(w)
