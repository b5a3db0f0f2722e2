"""Line or area: what a window of samples says about the contact's type (the maths, no state).

A strip contact (a thin plate's edge, a wedge, a thin cylinder) transmits tangential moment
about one tangent axis only, ``e = n × d``: the object rolls about its own edge. A plane or a
thick object pressed into the skin transmits it about both. From one axis of excitation the
two cannot be told apart (a tilted plane and a tilted thin plate give the same wrench); once
the contact has been excited about two axes, the 2×2 covariance of ``h`` in the tangent
plane over a window separates them: its eigenvalues stay far apart for a line and close for
an area.

Per sample, in the tangent frame ``(e1, e2)`` at the contact point (the angle convention of
the manual: ``e1`` the sensor x axis projected on the tangent plane):
``h`` and the tangential load ``f_t`` (the force projected on the tangent plane; the push
that tilts the object turns with the tilt axis) give :data:`N_SUMS` products
(:func:`evidence_products`); the evidence stage keeps running sums, and window sums are
differences of them. :func:`window_eigen` and :func:`window_direction` turn window sums into

* the covariance of ``h`` and of ``f_t`` over the window with the noise's expected share
  removed (``(1 − L / N) Σ``, ``Σ`` the 2×2 noise covariance from the sensor noise model at
  the contact point, ``L`` samples per independent noise sample: 1 unfiltered, ``1 / g²``
  after a low-pass of white-noise gain ``g``, ``N`` samples in the window), as eigenvalues
  ``major ≥ minor`` (clamped at zero);
* a noise level for each: what the noise alone may still leave in an eigenvalue, the upper
  3 σ tail of a χ² with ``ν = (N − 1) / L`` degrees of freedom (Wilson–Hilferty, as in
  :mod:`softtip.core.line_fit`) plus a 25 % model margin, times the largest noise variance;
* the window's line direction ``d = n × v`` with ``v`` the principal axis of ``h``'s
  variation, as an angle in the tangent frame, and its first-order standard deviation: the
  principal axis of a 2×2 covariance turns by ``C₁₂ / (λ₁ − λ₂)`` for an off-diagonal error
  ``C₁₂``, whose noise share over ``ν`` independent noise samples is
  ``s² (λ₁ + λ₂ + s²) / ν`` (``s²`` the noise variance after any low-pass, so ``s² / ν`` is
  the unfiltered ``s₀² / (N − 1)``: a low-pass leaves the noise at the excitation's few
  hertz as it was, and the axis sees no more and no less of it; the product ``λ₁ λ₂`` of the
  excitation with the across-axis spread is no noise: it varies with the excitation, not
  from sample to sample, and is the model error's), plus the model error: an across-axis spread ``λ₂`` (a line
  that is not quite one; at least the share of the noise that the correction may hide,
  :data:`HIDDEN_SPREAD` ``s²``) turns the axis by as much of ``√(λ₂ / λ₁)`` as the excitation about the
  two axes is correlated over the window, which the tangential load tells (``ρ²/(1 − ρ²)``
  of its correlation across the axis; ½ when the load did not vary). The noise term alone
  is returned too (``angle_noise_std``).

The decisions (thresholds, hysteresis, held verdicts) are the estimator's
(:mod:`softtip.estimator.evidence`). The kernels are scalar functions that the stage's compiled
step calls (:func:`softtip.core._jit.lazy_jit`: compiled with it by numba, or run as Python);
:func:`window_constants` is component-wise (:mod:`softtip.core._xp`'s ``NP``), a table by
window length that the step reads.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

from softtip.core._jit import lazy_jit
from softtip.core._xp import NP
from softtip.core._xp import _py_div as _div  # a / b with IEEE-754 results for b = 0 (compiled too)
from softtip.core.line_fit import MODEL_MARGIN, _chi2_excess
from softtip.core.noise import noise_quad

__all__ = [
    "N_SUMS", "Window", "evidence_products", "tangent_noise_kernel", "noise_constants", "window_eigen",
    "window_direction", "window_constants", "window_floats",
]  # fmt: skip

#: Number of window sums: ``Σ h1, Σ h2, Σ h1², Σ h1 h2, Σ h2²`` and the same for ``f_t``.
N_SUMS = 10

#: Across-axis spread of ``h`` that the noise correction may hide, as a share of the noise
#: variance: the floor of ``λ₂`` in the window direction's model term. Set on the simulator's
#: rocked lines with this constant varied (the calibration table of ``benchmarks/
#: bench_accuracy.py --sections rates``, and the same at 50 Hz with the sensor noise ×2 and ×4):
#: seven objects in nine settings (50 Hz told the Nano17 preset, sensor noise ×1
#: and ×2; told the simulated noise, ×1, ×2 and ×4; 1 and 7 kHz with the preset, 7 kHz behind a
#: 20 Hz low-pass; 7 kHz told the simulated noise): with 0.25 (the noise model's margin) RMS
#: error / std fell outside 0.7–1.5 in 20 of the 63 cells, 19 of them conservative; with 0.1
#: in 5 (the 60° wedge and the 2–3 mm plates with the preset at 1 and 7 kHz, 0.57–0.69; the
#: 1 mm plate told the simulated noise at 50 Hz, 1.68); without a floor the preset's 7 kHz
#: cells reached 1.9 (an overstated noise model hides real spread).
HIDDEN_SPREAD = 0.1

_HALF_PI = 0.5 * math.pi


@lazy_jit
def evidence_products(h1, h2, f1, f2):
    """The :data:`N_SUMS` per-sample products whose window sums :func:`window_eigen` needs.

    Parameters
    ----------
    h1, h2 : float or array
        ``h`` in the tangent frame, N·m.
    f1, f2 : float or array
        Tangential load in the tangent frame, N.
    """
    return (h1, h2, h1 * h1, h1 * h2, h2 * h2, f1, f2, f1 * f1, f1 * f2, f2 * f2)


@lazy_jit
def tangent_noise_kernel(rx, ry, rz, e1x, e1y, e1z, e2x, e2y, e2z, sfx, sfy, sfz, smx, smy, smz):
    """Noise covariance of ``h`` (N²·m²) and of ``f_t`` (N²) in the tangent frame at ``r``.

    ``sf*``, ``sm*``: the sensor noise's variances per axis (N², N²·m²;
    :func:`~softtip.core.noise.noise_variances`). Returns ``(h11, h12, h22, f11, f12, f22)``:
    ``Σ_h = P Σ_m P + P [r]× Σ_f [r]×ᵀ P`` (its diagonal :func:`~softtip.core.noise.noise_quad`)
    and ``Σ_f`` projected on ``(e1, e2)`` (:mod:`softtip.core.noise`).
    """
    h11 = noise_quad(e1x, e1y, e1z, rx, ry, rz, sfx, sfy, sfz, smx, smy, smz)
    h22 = noise_quad(e2x, e2y, e2z, rx, ry, rz, sfx, sfy, sfz, smx, smy, smz)
    # the off-diagonal: the same form between u × r for u = e1, e2
    ax, ay, az = e1y * rz - e1z * ry, e1z * rx - e1x * rz, e1x * ry - e1y * rx
    bx, by, bz = e2y * rz - e2z * ry, e2z * rx - e2x * rz, e2x * ry - e2y * rx
    h12 = smx * e1x * e2x + smy * e1y * e2y + smz * e1z * e2z + sfx * ax * bx + sfy * ay * by + sfz * az * bz
    f11 = sfx * e1x * e1x + sfy * e1y * e1y + sfz * e1z * e1z
    f12 = sfx * e1x * e2x + sfy * e1y * e2y + sfz * e1z * e2z
    f22 = sfx * e2x * e2x + sfy * e2y * e2y + sfz * e2z * e2z
    return h11, h12, h22, f11, f12, f22


class Window(NamedTuple):
    """What one window says (:func:`window_floats`)."""

    h_major: Any  #: larger eigenvalue of h's covariance, noise removed, N²·m²
    h_minor: Any  #: smaller one (≥ 0), N²·m²
    h_noise: Any  #: what noise alone may leave in an eigenvalue of h's covariance, N²·m²
    f_major: Any  #: the same for the tangential load, N²
    f_minor: Any
    f_noise: Any
    angle: Any  #: window line direction ``n × (principal axis of h)``, rad in (−π/2, π/2]
    angle_std: Any  #: its standard deviation, rad (inf when h did not vary)
    angle_noise_std: Any  #: the noise's share of it alone, rad (the rest is model error)


@lazy_jit
def noise_constants(h11, h12, h22, f11, f12, f22):
    """``(largest noise variance of h, mean noise variance of h, largest of f_t)`` from the
    noise covariances of :func:`tangent_noise_kernel`."""
    _, nm, nr = _eigen2(h11, h12, h22)
    s_big, s_small = nm + nr, nm - nr
    _, fm, fr = _eigen2(f11, f12, f22)
    return s_big, 0.5 * (s_big + s_small), fm + fr


@lazy_jit
def _eigen2(a11, a12, a22):
    """``(half, mean, root)`` of the symmetric ``[[a11, a12], [a12, a22]]``: its eigenvalues are
    ``mean ± root``, ``half = (a11 − a22) / 2``."""
    half = 0.5 * (a11 - a22)
    return half, 0.5 * (a11 + a22), math.sqrt(half * half + a12 * a12)


@lazy_jit
def _window_cov(s1, s2, s11, s12, s22, count, n11, n12, n22, keep):
    """``(c11, c12, c22)``: the covariance of a pair over a window from its sums
    (:func:`evidence_products`) of ``count`` samples, less ``keep`` times the noise's ``n``."""
    m1, m2 = _div(s1, count), _div(s2, count)
    c11 = _div(s11, count) - m1 * m1 - keep * n11
    c12 = _div(s12, count) - m1 * m2 - keep * n12
    c22 = _div(s22, count) - m2 * m2 - keep * n22
    return c11, c12, c22


@lazy_jit
def _clamp0(x):
    """``max(x, 0)`` as numpy's: NaN stays NaN (an empty window's)."""
    return x if x != x or x > 0.0 else 0.0


@lazy_jit
def window_eigen(s1, s2_, s11, s12, s22, t1, t2, t11, t12, t22, count, h11, h12, h22, f11, f12, f22, keep):
    """The covariances of ``h`` and ``f_t`` over a window less ``keep`` times the noise's, and
    their eigenvalues, from the window sums (:func:`evidence_products`) of ``count`` samples.

    Returns ``(major, minor, c11, c12, c22, half, root, g11, g12, g22, f_major, f_minor)``:
    ``h``'s eigenvalues clamped at zero and its covariance with ``half = (c11 − c22) / 2`` and
    ``root = (major − minor) / 2`` unclamped, then the load's (NaN for an empty window).
    """
    c11, c12, c22 = _window_cov(s1, s2_, s11, s12, s22, count, h11, h12, h22, keep)
    half, mean, root = _eigen2(c11, c12, c22)
    g11, g12, g22 = _window_cov(t1, t2, t11, t12, t22, count, f11, f12, f22, keep)
    _, gm, gr = _eigen2(g11, g12, g22)
    return (
        _clamp0(mean + root), _clamp0(mean - root), c11, c12, c22, half, root, g11, g12, g22,
        _clamp0(gm + gr), _clamp0(gm - gr),
    )  # fmt: skip


@lazy_jit
def window_direction(major, minor, c11, c12, c22, half, root, g11, g12, g22, s2, nu):
    """``(angle, angle_std, angle_noise_std)`` of a window (rad) from :func:`window_eigen`,
    ``s2`` the mean noise variance of ``h`` (:func:`noise_constants`) and ``nu`` the window's
    independent noise samples (:func:`window_constants`)."""
    # principal axis v of h's variation at angle phi; d = n × v is at phi + 90°
    a = 0.5 * math.atan2(2.0 * c12, 2.0 * half) + _HALF_PI
    if a > _HALF_PI:
        a -= math.pi
    gap = major - minor
    # the spread the noise correction may hide counts as well
    hidden = minor if minor > HIDDEN_SPREAD * s2 else HIDDEN_SPREAD * s2
    # model error: an across-axis spread of h (the line resisting a roll about its own edge a
    # little) turns the axis by as much of √(minor / major) as the window's excitation about
    # the two axes is correlated, which the tangential load tells: its correlation ρ between
    # the axis and across it; without load variation about both axes (or no principal axis)
    # the correlation is unknown: count it as ρ² = ½
    model = _div(hidden, major)
    if root != 0.0:
        cp, sp = _div(c11 - c22, 2.0 * root), _div(c12, root)  # cos 2φ, sin 2φ
        fd = 0.5 * (g11 - g22)
        fm = 0.5 * (g11 + g22)
        f_vv, f_ww, f_vw = fm + fd * cp + g12 * sp, fm - fd * cp - g12 * sp, g12 * cp - fd * sp
        den = (f_vv if f_vv > 0.0 else 0.0) * (f_ww if f_ww > 0.0 else 0.0)
        if den > 0.0:
            rho2 = f_vw * f_vw / den
            one = 1.0 - rho2
            model = model * _div(rho2, one if one > 0.0 else 0.0)
        else:
            model = model * 1.0
    else:
        model = model * 1.0
    # noise, over ν independent noise samples (the products with the noise only; a low-pass
    # leaves the noise under the excitation's few hertz as it was, so the cross products keep
    # their unfiltered share s²·L / N = s² / ν)
    nv = _div(s2 * (major + minor + s2), nu * gap * gap)
    v = nv + model
    return a, (math.sqrt(v) if v >= 0.0 else math.nan), (math.sqrt(nv) if nv >= 0.0 else math.nan)


def window_constants(count, corr: float):
    """``(tail, keep, nu)`` of windows of ``count`` samples (float or array; ``corr`` samples
    per independent noise sample): what noise alone may leave in an eigenvalue per unit noise
    variance (the upper χ² tail per degree of freedom and the model margin), the share of the
    noise covariance to remove, and the independent noise samples."""
    count = np.asarray(count, dtype=float)
    keep = np.maximum(1.0 - NP.div(corr, count), 0.0)
    nu = np.maximum(count - 1.0, 0.0) / corr
    tail = NP.div(_chi2_excess(nu, NP), nu) + MODEL_MARGIN
    return tail, keep, nu


def window_floats(sums, count: float, noise_terms, corr: float) -> Window:
    """What one window says (:class:`Window`) from its :data:`N_SUMS` sums of ``count``
    samples and the noise covariances of :func:`tangent_noise_kernel`: the kernels of the
    stage, composed for one window (tests, the manual's figures)."""
    tail, keep, nu = (float(x) for x in window_constants(count, corr))
    s_big, s2, f_n = noise_constants(*noise_terms)
    e = window_eigen(*(float(x) for x in sums), float(count), *noise_terms, keep)
    angle, angle_std, noise_std = window_direction(*e[:10], s2, nu)
    return Window(e[0], e[1], tail * s_big, e[10], e[11], tail * f_n, angle, angle_std, noise_std)
