"""Depth compensation: friction acts inside the skin, not on its undeformed surface.

Under deep penetration the object's tangential traction is transmitted at the interface,
a depth ``δ`` below the undeformed skin surface where the contact point is located. The
moment about the surface point then carries a spurious tangential part ``−δ n × f_t``
(about the edge axis when ``f_t`` crosses the edge), which rotates the measured direction.
softtip estimates ``δ`` from the normal force with a power-law skin stiffness

``F_n = k δ^p``, i.e. ``δ = min((F_n / k)^(1/p), δ_max)``,

and takes the moment about the *effective* contact point ``r − δ n``. ``δ`` here is the
depth at which friction effectively acts (the lever of the tangential force), which is
what a calibration press measures: :func:`lever_depth` solves it from a press with a
known line direction and a tangential load across it, and :meth:`DepthLaw.fit` fits
``k, p`` to such presses.

The default :data:`MURAKAMI2006_DEPTH` was fitted that way on softtip's simulator: the
papers' 5 mm skin (Winkler modulus 0.6 MPa) pressed by 1 and 2 mm plates from 0.25 to
0.5 kgf with a tangential load of 0.25 of the normal force across the plate, with the
shear layer stiffened to G = 2 MPa (the default E/3 layer has no side-wall stiffness and
lets the strip slide sideways by ~1 mm, which then dominates the lever);
``python benchmarks/bench_accuracy.py --fit-depth`` reproduces the fit. It is a property of the
skin *and* of the object's profile (a thin plate sinks deeper than a round stick at the
same force): calibrate with the objects you expect.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip._xp import NP

__all__ = ["DepthLaw", "MURAKAMI2006_DEPTH", "lever_depth", "depth_kernel"]


@dataclass(frozen=True)
class DepthLaw:
    """Power-law skin stiffness ``F_n = k δ^p`` (depth from the normal force).

    Parameters
    ----------
    stiffness : float
        ``k``, N/m^p.
    exponent : float
        ``p`` (1: linear spring; 1.5: Hertz; a strip pressed into a curved Winkler skin ≈ 2).
    max_depth : float
        Cap of ``δ``, m (the skin thickness: the shell does not give way).
    """

    stiffness: float
    exponent: float = 2.0
    max_depth: float = 0.005

    def __post_init__(self) -> None:
        for name in ("stiffness", "exponent", "max_depth"):
            v = float(getattr(self, name))
            if not (math.isfinite(v) and v > 0.0):
                raise ValueError(f"DepthLaw.{name} must be positive and finite, got {getattr(self, name)!r}")
            object.__setattr__(self, name, v)

    def depth(self, normal_force: ArrayLike) -> NDArray[np.float64]:
        """``δ`` (m) at normal forces ``F_n`` (N, pushing in positive), any shape."""
        return np.asarray(depth_kernel(np.asarray(normal_force, dtype=float), self, NP))

    def force(self, depth: ArrayLike) -> NDArray[np.float64]:
        """``F_n = k δ^p`` (N) at depths ``δ`` (m)."""
        return self.stiffness * np.asarray(depth, dtype=float) ** self.exponent

    @classmethod
    def fit(cls, normal_force: ArrayLike, depth: ArrayLike, max_depth: float = 0.005) -> DepthLaw:
        """Least-squares fit of ``log δ = (log F_n − log k) / p`` to calibration presses.

        The depth is regressed on the force (the controlled variable of a press), so
        presses of several objects over the same force range can be pooled.

        Parameters
        ----------
        normal_force : array-like, shape (N,)
            N; samples with ``F_n <= 0`` or ``δ <= 0`` are ignored.
        depth : array-like, shape (N,)
            m, e.g. from :func:`lever_depth`.
        max_depth : float
            Cap of the fitted law, m.
        """
        f = np.asarray(normal_force, dtype=float).ravel()
        d = np.asarray(depth, dtype=float).ravel()
        ok = np.isfinite(f) & np.isfinite(d) & (f > 0.0) & (d > 0.0)
        if ok.sum() < 2:
            raise ValueError("need at least two presses with positive force and depth to fit a depth law")
        if np.ptp(np.log(f[ok])) == 0.0:
            raise ValueError("need presses at two or more normal forces to fit a depth law")
        slope, icpt = np.polyfit(np.log(f[ok]), np.log(d[ok]), 1)
        p = 1.0 / slope
        return cls(float(np.exp(-icpt * p)), float(p), max_depth)

    def as_dict(self) -> dict:
        """JSON-ready, SI."""
        return {"stiffness_N_per_m^p": self.stiffness, "exponent": self.exponent, "max_depth_m": self.max_depth}


#: murakami2006 skin (5 mm silicone) with the papers' 1–2 mm plates, fitted on the
#: simulator (module docs): ``F_n = 2.0e6 N/m² · δ²``, i.e. 0.99 mm at 0.2 kgf and 1.57 mm at
#: 0.5 kgf (the 1 mm plate's lever is ≈ 1.9 mm there, the 2 mm plate's ≈ 1.25 mm).
MURAKAMI2006_DEPTH = DepthLaw(stiffness=2.0e6, exponent=2.0, max_depth=0.005)


def depth_kernel(normal_force, law: DepthLaw, xp):
    """``δ = min((max(F_n, 0) / k)^(1/p), δ_max)`` component-wise (numpy or float)."""
    fn = xp.where(normal_force > 0.0, normal_force, 0.0 * normal_force)
    d = xp.pow(fn / law.stiffness, 1.0 / law.exponent)
    return xp.where(d > law.max_depth, law.max_depth + 0.0 * d, d)


def lever_depth(wrench: ArrayLike, point: ArrayLike, normal: ArrayLike, direction: ArrayLike) -> NDArray[np.float64]:
    """Depth at which the tangential force acts, from a press with a known line direction.

    With no tangential spin torque about the line's own axis (a line contact transmits
    none, paper III-A), ``d · (m − (r − δ n) × f) = 0`` gives
    ``δ = −d · (m − r × f) / (d · (n × f))``.

    Parameters
    ----------
    wrench : array-like, shape (..., 6)
        Tared wrench, N and N·m.
    point, normal : array-like, shape (..., 3)
        Contact point on the undeformed skin (m) and its outward normal.
    direction : array-like, shape (..., 3)
        Known line direction (unit).

    Returns
    -------
    array, shape (...,)
        ``δ``, m; NaN where the tangential force has no part across the line.
    """
    w = np.asarray(wrench, dtype=float)
    r, n, d = (np.asarray(a, dtype=float) for a in (point, normal, direction))
    f, m = w[..., :3], w[..., 3:]
    q = m - np.cross(r, f)
    den = np.sum(d * np.cross(n, f), axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = -np.sum(d * q, axis=-1) / den
    # the lever is only defined where the force has a clear part across the line
    return np.where(np.abs(den) > 0.05 * np.linalg.norm(f, axis=-1), out, np.nan)
