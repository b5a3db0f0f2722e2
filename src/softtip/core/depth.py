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

Online depth
------------
One law per skin cannot fit every object (a round stick sinks less than a thin plate, an
edge loaded along itself acts shallower), so by default softtip learns the depth of each
contact from its own data, with the law as the prior: ``δ = κ δ₀(F_n)`` with ``δ₀`` the
law's depth and a factor ``κ`` (prior 1 ± ``prior_std``). Under the line-contact model the
moment about the effective point, ``h + δ n × f_t``, has no component along the line ``d``:
with ``h_k`` and ``g_k = δ₀ (n × f_k)`` in the tangent frame of the contact point,

``d · (h_k + κ g_k) = 0`` for every sample ``k`` of a window.

Linearised about a direction ``u`` (the smallest eigenvector of ``Σ v vᵀ``,
``v = h + κ g``) and a factor ``κ_c``, the residual of a rotation ``θ`` and a change ``Δκ``
is ``u·v_k + θ e·v_k + Δκ u·g_k`` (``e`` is ``u`` turned by 90° in the tangent plane).
Eliminating ``θ`` leaves the information on ``κ``: the Schur complement
``I = Σ a² − (Σ a b)² / Σ b²`` with ``a = u·g`` (the tangential force across the line) and
``b = e·v`` (the moment about ``e``). It is positive only when the tangential force across
the line varies within the window in a way the moment about ``e`` does not follow; a load
that holds still, or that rises in proportion with the rest of the grasp, leaves ``κ`` to
the prior. A load along the line gives ``a ≈ 0``: no information, and none needed (it does
not turn the direction).

Errors in variables: the noise of ``f`` enters ``g`` (the regressor) and ``h``, and the two
are correlated through ``r × f``, so the 12 window sums (:func:`depth_products`) are first
corrected by their expected noise (:func:`depth_noise_kernel`), as in :mod:`softtip.core.line_fit`;
the information counts only the excitation beyond the noise's scatter (the same χ² margin
as the joint fit), and the standard deviation is inflated for the noise of ``a`` itself.
:func:`depth_solve_kernel` returns the data's own estimate of ``κ`` and its variance; the
estimator keeps the most informative window of the contact and combines it with the prior.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.core._jit import jitable
from softtip.core._xp import NP
from softtip.core.line_fit import MODEL_MARGIN, _chi2_excess, smallest_eigenvector
from softtip.core.spin import tangent_frame_kernel

__all__ = [
    "DepthLaw", "MURAKAMI2006_DEPTH", "lever_depth", "depth_kernel", "skin_depth_law", "N_DEPTH_SUMS",
    "depth_frame_kernel", "depth_products", "depth_noise_kernel", "depth_solve_kernel",
]  # fmt: skip


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


def skin_depth_law(thickness: float) -> DepthLaw:
    """Prior skin law of a skin of ``thickness`` (m) whose material is not known: the
    murakami2006 law scaled as an elastic foundation (stiffness ∝ 1 / thickness), capped at
    the thickness. Only a prior: the online depth learns each contact's own factor."""
    h = float(thickness)
    if not (math.isfinite(h) and h > 0.0):
        raise ValueError(f"skin thickness must be a positive length in m, got {thickness!r}")
    ref = MURAKAMI2006_DEPTH
    return DepthLaw(ref.stiffness * ref.max_depth / h, ref.exponent, h)


def depth_kernel(normal_force, law: DepthLaw, xp):
    """``δ = min((max(F_n, 0) / k)^(1/p), δ_max)`` component-wise (numpy or float)."""
    if law.exponent == 2.0:
        return square_depth_kernel(normal_force, law.stiffness, law.max_depth, xp)
    f_normal = xp.where(normal_force > 0.0, normal_force, 0.0 * normal_force)
    d = xp.pow(f_normal / law.stiffness, 1.0 / law.exponent)
    return xp.where(d > law.max_depth, law.max_depth + 0.0 * d, d)


@jitable
def square_depth_kernel(normal_force, stiffness, max_depth, xp):
    """:func:`depth_kernel` of a law of exponent 2 (stiffness N/m², cap m): a square root
    (correctly rounded in every back end, and cheaper), which compiled code can call."""
    f_normal = xp.where(normal_force > 0.0, normal_force, 0.0 * normal_force)
    d = xp.sqrt(f_normal / stiffness)
    return xp.where(d > max_depth, max_depth + 0.0 * d, d)


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


#: Number of window sums of the online depth: ``h hᵀ`` (3), ``h gᵀ`` (4), ``g gᵀ`` (3),
#: ``Σ δ₀``, ``Σ δ₀²``.
N_DEPTH_SUMS = 12


@jitable
def depth_frame_kernel(rx, ry, rz, nx, ny, nz, xp):
    """The 12 components the products need at a contact point ``r`` (m) with normal ``n``:
    the tangent frame ``t₁, t₂`` (``t₁ × t₂ = n``) and ``a_i = t_i × r``, so that
    ``t_i · (m − r × f) = t_i·m − a_i·f``. Component-wise (floats or arrays)."""
    t1x, t1y, t1z, t2x, t2y, t2z = tangent_frame_kernel(nx, ny, nz, xp)
    return (
        t1x, t1y, t1z, t2x, t2y, t2z,
        t1y * rz - t1z * ry, t1z * rx - t1x * rz, t1x * ry - t1y * rx,
        t2y * rz - t2z * ry, t2z * rx - t2x * rz, t2x * ry - t2y * rx,
    )  # fmt: skip


@jitable
def depth_products(fx, fy, fz, mx, my, mz, frame, d0):
    """The 12 per-sample products whose window sums :func:`depth_solve_kernel` needs.

    ``h = (t₁·q, t₂·q)`` with ``q = m − r × f`` the moment about the surface point ``r``
    and ``g = δ₀ (t₁·(n × f), t₂·(n × f)) = δ₀ (−t₂·f, t₁·f)`` with ``δ₀`` the prior depth
    (m); ``frame`` from :func:`depth_frame_kernel`. Component-wise (floats or arrays).
    Returns ``(h₁h₁, h₁h₂, h₂h₂, h₁g₁, h₁g₂, h₂g₁, h₂g₂, g₁g₁, g₁g₂, g₂g₂, δ₀, δ₀²)``.
    """
    t1x, t1y, t1z, t2x, t2y, t2z, a1x, a1y, a1z, a2x, a2y, a2z = frame
    h1 = t1x * mx + t1y * my + t1z * mz - (a1x * fx + a1y * fy + a1z * fz)
    h2 = t2x * mx + t2y * my + t2z * mz - (a2x * fx + a2y * fy + a2z * fz)
    g1 = -d0 * (t2x * fx + t2y * fy + t2z * fz)
    g2 = d0 * (t1x * fx + t1y * fy + t1z * fz)
    return (h1 * h1, h1 * h2, h2 * h2, h1 * g1, h1 * g2, h2 * g1, h2 * g2, g1 * g1, g1 * g2, g2 * g2, d0, d0 * d0)


@jitable
def depth_noise_kernel(frame, force_std, moment_std):
    """Per-sample noise covariances of ``h`` and ``g`` for a :func:`depth_frame_kernel` frame
    and the sensor's noise (:class:`softtip.core.noise.SensorNoise`'s ``force_std``, N, and
    ``moment_std``, N·m: 3 floats each).

    Returns the 10 covariances ``(hh₁₁, hh₁₂, hh₂₂, hg₁₁, hg₁₂, hg₂₁, hg₂₂, gg₁₁, gg₁₂,
    gg₂₂)``, ``g`` per unit ``δ₀`` (the sums scale them by ``Σ δ₀`` and ``Σ δ₀²``):
    ``h_i = t_i·m − a_i·f`` and ``g_i = b_i·f`` with ``b₁ = −t₂``, ``b₂ = t₁``.
    """
    t1x, t1y, t1z, t2x, t2y, t2z, a1x, a1y, a1z, a2x, a2y, a2z = frame
    sfx, sfy, sfz = force_std[0] * force_std[0], force_std[1] * force_std[1], force_std[2] * force_std[2]
    smx, smy, smz = moment_std[0] * moment_std[0], moment_std[1] * moment_std[1], moment_std[2] * moment_std[2]
    t1, t2 = (t1x, t1y, t1z), (t2x, t2y, t2z)
    a1, a2 = (a1x, a1y, a1z), (a2x, a2y, a2z)
    b1, b2 = (-t2x, -t2y, -t2z), t1

    def mm(u, v):
        return smx * u[0] * v[0] + smy * u[1] * v[1] + smz * u[2] * v[2]

    def ff(u, v):
        return sfx * u[0] * v[0] + sfy * u[1] * v[1] + sfz * u[2] * v[2]

    return (
        mm(t1, t1) + ff(a1, a1), mm(t1, t2) + ff(a1, a2), mm(t2, t2) + ff(a2, a2),
        -ff(a1, b1), -ff(a1, b2), -ff(a2, b1), -ff(a2, b2),
        ff(b1, b1), ff(b1, b2), ff(b2, b2),
    )  # fmt: skip


#: Largest depth factor a linearisation point may take (the skin's cap bounds δ anyway),
#: and the steps of the grid the solve starts from.
KAPPA_MAX = 4.0
KAPPA_GRID = 16
#: Fewest samples of a window that may inform the depth.
MIN_DEPTH_SAMPLES = 5
#: Relative standard deviation of the depth factor a window determines, for what the
#: line-contact model leaves out: the lever of the tangential force also carries the
#: contact's own shift under the load and the object's rolling, not only the depth.
DEPTH_MODEL_STD = 0.1
#: rad; how far off the estimated line may be when the tangential force varies along it
#: (its variation along the line then leaks into the regressor across it).
DEPTH_MISALIGNMENT = 0.1


@jitable
def depth_solve_kernel(sums, count, cov, corr, iterations, xp):
    """The data's own depth factor ``κ`` of a window, and its variance (module docs).

    Parameters
    ----------
    sums : sequence of 12 floats or arrays
        Window sums of :func:`depth_products`.
    count : float or array
        Samples in the window.
    cov : sequence of 10
        Per-sample noise covariances of :func:`depth_noise_kernel`.
    corr : float
        Samples per independent noise sample (1 for white noise).
    iterations : int
        Gauss–Newton steps, from the best factor of a grid over ``[0, KAPPA_MAX]``, each
        from the last one's estimate.
    xp : namespace
        :data:`softtip.core._xp.NP` or :data:`softtip.core._xp.PY`.

    Returns
    -------
    tuple
        ``(kappa, variance)``: the least-squares factor of the window (prior not included)
        and its variance; variance ``inf`` (and ``kappa`` NaN) when the window carries no
        information beyond its noise.
    """
    n = count
    sd0, sd02 = sums[10], sums[11]
    chh11, chh12, chh22, chg11, chg12, chg21, chg22, cgg11, cgg12, cgg22 = cov
    a11, a12, a22 = sums[0] - n * chh11, sums[1] - n * chh12, sums[2] - n * chh22
    b11, b12, b21, b22 = sums[3] - sd0 * chg11, sums[4] - sd0 * chg12, sums[5] - sd0 * chg21, sums[6] - sd0 * chg22
    c11, c12, c22 = sums[7] - sd02 * cgg11, sums[8] - sd02 * cgg12, sums[9] - sd02 * cgg22
    md0, md02 = xp.div(sd0, n), xp.div(sd02, n)
    k1 = xp.maximum(n - 1.0, 0.0)
    margin = corr * _chi2_excess(k1 / corr, xp) + MODEL_MARGIN * k1
    # start: the factor on a coarse grid whose best line leaves the least residual (the
    # linearisation about a far-off factor can diverge when the load's lever dominates h)
    kc = 1.0 + 0.0 * n
    best = None
    for j in range(KAPPA_GRID + 1):
        k = KAPPA_MAX * j / KAPPA_GRID
        m11 = a11 + 2.0 * k * b11 + k * k * c11
        m12 = a12 + k * (b12 + b21) + k * k * c12
        m22 = a22 + 2.0 * k * b22 + k * k * c22
        half = 0.5 * (m11 - m22)
        low = 0.5 * (m11 + m22) - xp.sqrt(half * half + m12 * m12)
        if best is None:
            kc, best = k + 0.0 * n, low
        else:
            better = low < best
            kc, best = xp.where(better, k + 0.0 * n, kc), xp.where(better, low, best)
    kw = var = None
    for _ in range(iterations):
        m11 = a11 + 2.0 * kc * b11 + kc * kc * c11
        m12 = a12 + kc * (b12 + b21) + kc * kc * c12
        m22 = a22 + 2.0 * kc * b22 + kc * kc * c22
        u1, u2, _ = smallest_eigenvector(m11, m12, m22, xp)
        e1, e2 = -u2, u1
        # C = Σ g vᵀ = (Σ h gᵀ)ᵀ + κ Σ g gᵀ
        k11, k12, k21, k22 = b11 + kc * c11, b21 + kc * c12, b12 + kc * c12, b22 + kc * c22
        sbb = e1 * e1 * m11 + 2.0 * e1 * e2 * m12 + e2 * e2 * m22
        saa = u1 * u1 * c11 + 2.0 * u1 * u2 * c12 + u2 * u2 * c22
        sab = u1 * (k11 * e1 + k12 * e2) + u2 * (k21 * e1 + k22 * e2)
        say = -(u1 * (k11 * u1 + k12 * u2) + u2 * (k21 * u1 + k22 * u2))
        info_raw = saa - xp.div(sab * sab, sbb)
        # noise per sample of the residual u·v and of the regressor a = u·g
        var_r = (
            u1 * u1 * chh11 + 2.0 * u1 * u2 * chh12 + u2 * u2 * chh22
            + kc * md0 * (2.0 * u1 * u1 * chg11 + 2.0 * u1 * u2 * (chg12 + chg21) + 2.0 * u2 * u2 * chg22)
            + kc * kc * md02 * (u1 * u1 * cgg11 + 2.0 * u1 * u2 * cgg12 + u2 * u2 * cgg22)
        )  # fmt: skip
        var_a = md02 * (u1 * u1 * cgg11 + 2.0 * u1 * u2 * cgg12 + u2 * u2 * cgg22)
        excess = xp.maximum(info_raw - var_a * margin, 0.0)
        info = xp.div(excess, var_r * corr * (1.0 + xp.div(k1 * var_a, excess)))
        # the residual beyond the noise after the fit (the model's own error) widens it
        cost = u1 * u1 * m11 + 2.0 * u1 * u2 * m12 + u2 * u2 * m22 - xp.div(say * say, info_raw)
        info = xp.div(info, 1.0 + xp.div(xp.maximum(cost, 0.0), xp.maximum(n - 2.0, 1.0) * var_r))
        has = xp.logical_and(info > 0.0, n >= MIN_DEPTH_SAMPLES)
        kw = xp.where(has, kc + xp.div(say, info_raw), xp.nan)
        # model error: DEPTH_MODEL_STD, and the tangential force along the line seen across
        # it through a direction off by DEPTH_MISALIGNMENT (its variation relative to the
        # variation across the line that informs κ)
        sgg_e = e1 * e1 * c11 + 2.0 * e1 * e2 * c12 + e2 * e2 * c22
        sge = e1 * (k11 * e1 + k12 * e2) + e2 * (k21 * e1 + k22 * e2)
        along = xp.maximum(sgg_e - xp.div(sge * sge, sbb), 0.0)
        model = DEPTH_MODEL_STD * DEPTH_MODEL_STD + DEPTH_MISALIGNMENT * DEPTH_MISALIGNMENT * xp.div(along, info_raw)
        var = xp.where(has, xp.div(1.0, info) + model, math.inf)
        # next linearisation point: the window's own estimate (the posterior would hold it
        # back toward the prior), within what the skin allows
        kc = xp.where(has, xp.maximum(kw, 0.0), 1.0 + 0.0 * n)
        kc = xp.where(kc > KAPPA_MAX, KAPPA_MAX + 0.0 * n, kc)
    return kw, var
