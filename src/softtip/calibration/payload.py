"""Payload calibration: the fingertip's mass, centre of mass and the sensor bias.

:func:`calibrate_payload` estimates ``m``, ``c`` and the sensor bias from contact-free
samples in varied orientations by linear least squares (force rows: bias and ``m``; moment
rows: bias and ``m c``), with standard deviations from the residual variance.

The payload and its gravity wrench are :mod:`softtip.core.gravity`; compensating logs and
live sources is :mod:`softtip.io.payload`. Their names are re-exported here, where they were
first defined.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.core.gravity import (
    Payload,
    PayloadCompensator,
    compensate_payload,
    gravity_in_sensor,
    load_payload,
    payload_wrench,
)
from softtip.core.units import STANDARD_GRAVITY
from softtip.errors import InputError
from softtip.io.payload import (
    QUATERNION_COLUMNS,
    UNIT_TOLERANCE,
    CompensatedSource,
    compensate_log,
    read_orientation,
    replay_source,
)

__all__ = [
    "QUATERNION_COLUMNS",
    "UNIT_TOLERANCE",
    "Payload",
    "PayloadFit",
    "PayloadCompensator",
    "load_payload",
    "gravity_in_sensor",
    "payload_wrench",
    "compensate_payload",
    "calibrate_payload",
    "read_orientation",
    "compensate_log",
    "CompensatedSource",
    "replay_source",
]

# Refuse a payload fit whose column-scaled design matrix has a condition number above this.
# It grows as 1 / (angular spread of gravity in the sensor frame): 50 is about 8° of spread,
# where the centre of mass is still determined to a few tenths of a mm at Nano17 noise.
_MAX_CONDITION = 50.0


# --------------------------------------------------------------------------------------
# estimating the payload


@dataclass(frozen=True)
class PayloadFit:
    """Result of :func:`calibrate_payload`. SI.

    Attributes
    ----------
    payload : Payload
    bias : ndarray, shape (6,)
        Sensor bias, N and N·m.
    mass_std : float
        kg.
    com_std : ndarray, shape (3,)
        m.
    bias_std : ndarray, shape (6,)
    force_rms, moment_rms : float
        Residual RMS per axis, N and N·m.
    n_samples : int
    gravity_spread_deg : float
        Largest angle between the gravity direction of any sample and their mean, degrees.
    condition : float
        Condition number of the (column-scaled) moment design matrix.
    """

    payload: Payload
    bias: NDArray[np.float64]
    mass_std: float
    com_std: NDArray[np.float64]
    bias_std: NDArray[np.float64]
    force_rms: float
    moment_rms: float
    n_samples: int
    gravity_spread_deg: float
    condition: float

    def summary(self) -> str:
        """Human-readable report (g, mm, N, N·mm)."""
        c, cs = np.asarray(self.payload.com) * 1e3, self.com_std * 1e3
        b, bs = self.bias.copy(), self.bias_std.copy()
        b[3:] *= 1e3
        bs[3:] *= 1e3
        return "\n".join(
            [
                f"payload from {self.n_samples} samples, gravity direction spread {self.gravity_spread_deg:.0f}°, "
                f"condition {self.condition:.3g}",
                f"  mass  {self.payload.mass * 1e3:.3f} ± {self.mass_std * 1e3:.3f} g",
                "  com   " + ", ".join(f"{v:+.3f} ± {s:.3f}" for v, s in zip(c, cs)) + " mm",
                "  bias  force " + ", ".join(f"{v:+.4f} ± {s:.4f}" for v, s in zip(b[:3], bs[:3])) + " N; moment "
                + ", ".join(f"{v:+.3f} ± {s:.3f}" for v, s in zip(b[3:], bs[3:])) + " N·mm",
                f"  residual {self.force_rms * 1e3:.2f} mN, {self.moment_rms * 1e3:.4f} N·mm RMS per axis",
            ]
        )


def _solve_block(a: NDArray, b: NDArray) -> tuple[NDArray, NDArray, float, float]:
    """Least squares ``a x ≈ b`` over rows ``x, y, z`` of each sample, each axis weighted by its noise.

    The sensor's noise differs per axis (an ATI Nano25's ``fz`` noise is three times its
    ``fx``), so one pooled residual variance would make some standard deviations too small
    and others too large. Two passes: ordinary least squares, then per-axis residual
    variances ``s_a²`` weight the rows (feasible generalised least squares) and the
    covariance is ``(Aᵀ W A)⁻¹`` with ``W = diag(1 / s_a²)``.

    Returns
    -------
    x, covariance, RMS residual per axis (unweighted), condition number of the column-scaled ``a``.
    """
    scale = np.linalg.norm(a, axis=0)
    scale = np.where(scale > 0, scale, 1.0)
    s = np.linalg.svd(a / scale, compute_uv=False)
    cond = float(s[0] / s[-1]) if s[-1] > 0 else math.inf
    x, *_ = np.linalg.lstsq(a, b, rcond=None)
    n = len(b) // 3
    dof = max(n - a.shape[1] / 3.0, 1.0)
    var = np.sum(np.square(b - a @ x).reshape(n, 3), axis=0) / dof
    var = np.maximum(var, 1e-30 + 1e-12 * float(var.max()))
    wt = np.tile(1.0 / np.sqrt(var), n)
    x, *_ = np.linalg.lstsq(a * wt[:, None], b * wt, rcond=None)
    r = b - a @ x
    var = np.sum(np.square(r).reshape(n, 3), axis=0) / dof
    var = np.maximum(var, 1e-30 + 1e-12 * float(var.max()))
    wt = np.tile(1.0 / np.sqrt(var), n)
    aw = a * wt[:, None]
    cov = np.linalg.pinv(aw.T @ aw)
    return x, cov, math.sqrt(float(r @ r) / len(b)), cond


def calibrate_payload(wrench: ArrayLike, orientation: ArrayLike, source: str = "<log>") -> PayloadFit:
    """Estimate the fingertip's mass, centre of mass and the sensor bias from contact-free samples.

    Model: ``wrench = bias + (m g_s, c × m g_s)``, linear in ``(bias_f, m)`` (force rows) and
    ``(bias_m, m c)`` (moment rows: ``c × m g_s = −[g_s]× (m c)``), solved separately.

    Parameters
    ----------
    wrench : array-like, shape (N, 6)
        Raw wrench, N and N·m; nothing may touch the fingertip.
    orientation : array-like, shape (N, 4)
        ``qw, qx, qy, qz`` (unit): sensor frame in the world frame, world z up.
    source : str
        Name for error messages.

    Returns
    -------
    PayloadFit

    Raises
    ------
    InputError
        Shapes, too few samples, orientations that do not vary enough (the design is
        ill-conditioned), or a mass that is not significantly positive.
    """
    w = np.asarray(wrench, dtype=float)
    q = np.asarray(orientation, dtype=float)
    if w.ndim != 2 or w.shape[1] != 6 or q.shape != (len(w), 4):
        raise InputError(f"{source}: expected wrench (N, 6) and orientation (N, 4), got {w.shape} and {q.shape}")
    n = len(w)
    if n < 10:
        raise InputError(f"{source}: {n} samples; expected at least 10 contact-free samples in varied orientations")
    g = gravity_in_sensor(q)
    gu = g / STANDARD_GRAVITY
    mean = gu.mean(axis=0)
    mean_dir = mean / np.linalg.norm(mean) if np.linalg.norm(mean) > 1e-9 else np.array([0.0, 0.0, 1.0])
    spread = float(np.degrees(np.arccos(np.clip(gu @ mean_dir, -1.0, 1.0))).max())

    eye = np.tile(np.eye(3), (n, 1))
    a_f = np.column_stack((eye, g.reshape(-1)))
    gx = np.zeros((n, 3, 3))  # −[g]×
    gx[:, 0, 1], gx[:, 0, 2] = g[:, 2], -g[:, 1]
    gx[:, 1, 0], gx[:, 1, 2] = -g[:, 2], g[:, 0]
    gx[:, 2, 0], gx[:, 2, 1] = g[:, 1], -g[:, 0]
    a_m = np.column_stack((eye, gx.reshape(-1, 3)))
    xf, cov_f, rms_f, cond_f = _solve_block(a_f, w[:, :3].reshape(-1))
    xm, cov_m, rms_m, cond_m = _solve_block(a_m, w[:, 3:].reshape(-1))
    cond = max(cond_f, cond_m)
    if not cond <= _MAX_CONDITION:
        raise InputError(
            f"{source}: the orientations do not vary enough to separate the payload from the sensor bias "
            f"(gravity direction in the sensor frame spans only {spread:.1f}° around its mean; condition number "
            f"{cond:.3g} > {_MAX_CONDITION:g}); rotate the finger through ±45° or more about at least two axes"
        )
    mass, mass_var = float(xf[3]), float(cov_f[3, 3])
    if not mass > 3.0 * math.sqrt(mass_var):
        raise InputError(
            f"{source}: the estimated mass {mass * 1e3:.3g} ± {math.sqrt(mass_var) * 1e3:.2g} g is not significantly "
            "positive; expected a fingertip of a few grams or more (was something touching it? Or are the "
            "quaternions in another order, x, y, z, w, or conjugated, the world in the sensor frame? qw, qx, qy, qz "
            "is the sensor frame's orientation in a world frame with z up)"
        )
    mc = xm[3:]
    com = mc / mass
    com_var = (np.diag(cov_m)[3:] + com**2 * mass_var) / mass**2  # first order; the two blocks are independent
    bias = np.concatenate((xf[:3], xm[:3]))
    bias_std = np.sqrt(np.concatenate((np.diag(cov_f)[:3], np.diag(cov_m)[:3])))
    return PayloadFit(
        payload=Payload(mass, tuple(com)),
        bias=bias,
        mass_std=math.sqrt(mass_var),
        com_std=np.sqrt(com_var),
        bias_std=bias_std,
        force_rms=rms_f,
        moment_rms=rms_m,
        n_samples=n,
        gravity_spread_deg=spread,
        condition=cond,
    )
