"""Fingertip calibration: the skin geometry's offset and radius (or semi-axes) from plane presses.

Why the obvious residual does not work
--------------------------------------
For one sample, Bicchi's soft-finger equations ``m − c × f = p × f + σ p / R``, ``|p| = R``
have a solution for *any* trial centre ``c`` and radius ``R`` (that is what
:func:`softtip.core.location.contact_from_wrench` computes), so a single sample says nothing
about the geometry. Information comes only from a constraint shared by several samples.

The model used here
-------------------
The probing log is a sequence of **presses** of the fingertip against a flat, rigid
surface (a table). During one press the surface does not rotate relative to the
fingertip, so the contact normal ``n_k`` is the same for every sample of press ``k`` and,
on a sphere (or the capsule's hemispherical cap), so is the contact point
``c + R n_k`` — even while the surface slides and the friction force turns. Per sample
``i`` of press ``k``::

    m_i = r_i × f_i + σ_i n_k,      r_i = c + (R − κ √(F_n,i)) n_k,      F_n,i = −f_i · n_k

* ``σ_i`` (spin about the normal) is left free: the residual is the part of
  ``m_i − r_i × f_i`` in the tangent plane of ``n_k`` (two numbers per sample), so twisting
  the finger during a press does no harm.
* ``κ √F_n`` is the indentation of the skin: the tangential (friction) force acts at the
  surface of the table, which lies below the undeformed skin by the penetration ``δ``. For
  an elastic layer on a rigid spherical shell pressed by a plane (a Winkler foundation,
  softtip's skin model) ``F = k π R δ²``, so ``δ ∝ √F``; ``κ`` (m/√N) is fitted. Without it
  the radius comes out short by the mean indentation (about 0.3–0.5 mm at 2–4 N).
* The unknowns: ``c`` (3), ``R``, ``κ`` and a normal ``n_k`` per press (2 each), fitted by
  nonlinear least squares (:func:`scipy.optimize.least_squares`) over every sample at once.

What identifies the geometry: within a press the friction force must turn (the surface
slides a little, or the finger rocks) so that ``m = r × f`` pins the contact point ``r_k`` in
3-D, and the presses must be spread over the skin so that the points ``r_k`` fix a sphere.
Pure normal presses (``f ∥ n``, as on a frictionless surface) put every wrench axis through
``c`` and leave ``R`` undetermined; presses at one spot or along one circle leave ``c``
undetermined. Both are refused (:class:`~softtip.errors.InputError`): per press the spread
of the force direction is checked, and after the fit the conditioning of the Jacobian.

The capsule's cylinder axis is parallel to ``z``; its cap centre ``(x, y, length)`` and
radius are fitted from presses on the cap (contact normals at least 20° above the equator;
others are counted and left out), and ``(x, y)`` becomes the capsule's ``axis_offset``.
The axis-aligned ellipsoid's centre and three semi-axes are fitted the same way: the contact
point of press ``k`` is the skin point with outward normal ``n_k``, ``c + D² n_k / |D n_k|``
(``D = diag(a, b, c)``), moved in by the indentation. Each shape says what it fits (its
:class:`~softtip.core.shape.PressModel`, the shape protocol); :data:`SHAPES` lists them.

Noise: errors in variables
--------------------------
The force is measured with noise too, and in ``m − r × f`` that noise is multiplied by the
lever arm ``r`` (30–40 mm). Plain least squares then prefers a shorter lever arm: with an
ordinary Nano17's noise and presses whose friction turns while the force ramps, the centre
came out about 1 mm too far from the sensor and the radius 1 mm too small, at 5–13
reported standard deviations. Each sample's two tangential residuals are therefore
whitened by their noise covariance propagated from the sensor noise model through the
current lever arm (:func:`_whiten`); the objective's noise share is then two per sample
whatever the trial geometry, so its minimum is not pulled towards shorter lever arms. The
start values (the point of each press) use least squares with the normal matrix corrected
for the force noise's expected share.

Standard deviations come from the Jacobian of the whitened residuals at the solution,
``cov = s² (JᵀJ)⁻¹``, scaled by ``s² = Σ res² / (n_res − n_par)`` (about 1 when the noise
model is right; reported as :attr:`Calibration.noise_ratio`), so a noise model off by a
constant factor still gives honest standard deviations.

Limits: the weighting removes the first-order bias; where the presses excite little
compared with the noise (friction turning only while the force ramps, 0.1–0.3 of the
normal force, a Nano25's noise) the objective is far from quadratic over the scatter and
the curvature's standard deviations understate it several times over. Such fits end far
from the start sphere; :attr:`Calibration.warning` says so, and the standard deviations of
fits ending more than :data:`JACKKNIFE_SHIFT` from it come from a delete-one-press
jackknife too (:func:`_jackknife_std`; the larger of the two per parameter). On held, sliding presses (the procedure of :data:`PROBING_GUIDE`) the
curvature's are honest; the radius is then the least precise parameter because it trades
off against the indentation ``κ`` unless the presses span a wide range of forces.
``benchmarks/bench_calibration.py`` prints both kinds of log. The sensor's noise is taken
as white and the tare (the mean of the first ``tare_duration`` s without spikes) as exact.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares

from softtip.core._vec import cross as _cross
from softtip.core._vec import skew as _skew
from softtip.core._vec import tangent_basis as _tangent_basis
from softtip.core._xp import NP
from softtip.core.fingertip import SHAPES as _ALL_SHAPES
from softtip.core.fingertip import Fingertip
from softtip.core.noise import NANO17, SensorNoise
from softtip.core.shape import PressModel, sphere_kernel
from softtip.errors import InputError
from softtip.estimator.config import EstimatorConfig
from softtip.estimator.tare import TareReport, tare_from_samples
from softtip.io.atomic import atomic_write_text

__all__ = [
    "JACKKNIFE_SHIFT",
    "MAX_START_SHIFT",
    "PROBING_GUIDE",
    "TARGET_STD",
    "SHAPES",
    "Calibration",
    "calibrate_fingertip",
    "find_presses",
    "write_fingertip_toml",
]

#: How to record a probing log (``softtip calibrate --guide`` prints it).
PROBING_GUIDE = """\
How to record a probing log for `softtip calibrate`

You need: the fingertip on its sensor, and a flat, rigid, dry surface (a table top, a
steel or glass plate; not foam, rubber or cloth) that you can press it against.

1. Start recording and keep the fingertip untouched for the first second (the tare):
     softtip stream --netft ADDRESS --record probe.csv
   (or any logger writing t, fx, fy, fz, mx, my, mz).
2. Press 20 to 40 times, each at a different spot of the skin:
   - where: spread the spots evenly over the part that touches things, from the very tip
     out to 60° from it, all the way round (a capsule: only the rounded cap, not lower
     than 20° above where the cap meets the cylinder; an ellipsoid: out to 85°, down to
     its widest part, which separates its height from its length);
   - how hard: vary it, about half the presses light (1-2 N, 100-200 g on a kitchen
     scale) and half firm (5-8 N), each held for 1-2 s: the spread of forces separates
     the radius from the skin's indentation (presses all at 2-4 N leave the two
     entangled, which is most of the radius' uncertainty);
   - how to move while holding: slide the surface (or the finger) sideways by about half
     a millimetre one way, then across, or in a small circle, so that the friction force
     turns by 40° or more. Do not tilt the surface relative to the finger and do not roll
     the finger (the contact spot must stay the same during a press); twisting about the
     contact normal does no harm;
   - between presses, lift off completely (below 0.05 N) for a moment.
3. Stop the recording (Ctrl-C), then fit the geometry:
     softtip calibrate probe.csv --shape sphere -o my_tip.toml
   with --force-noise and --moment-noise set to your sensor's noise (the standard
   deviation of each axis while untouched; defaults: a Nano17).
4. Check the report: the standard deviations (30 presses held at 1.5-4 N at 100 Hz:
   a Nano17 about 0.01-0.05 mm, a Nano25 0.07 mm for the centre's x, y but 0.2-0.3 mm
   for its height and the radius; they fall as 1/sqrt(presses), and a warning above
   0.1 mm says how many presses would reach it), and a residual near 1 times the noise
   model's (a warning below 0.5 or above 2 means the noise options do not fit the
   sensor). A log without presses, presses at one spot, or a force that never turns
   within a press are refused with a message saying which.

Try it without hardware: softtip calibrate --example --shape sphere
"""

#: Shapes :func:`calibrate_fingertip` can fit (those of :data:`softtip.core.fingertip.SHAPES`
#: calibrated from presses).
SHAPES = tuple(name for name, cls in _ALL_SHAPES.items() if cls.calibrates == "presses")
# The fit is refused when the correlation matrix of the geometry parameters has a
# condition number above this (a combination of them is undetermined by the data).
_MAX_CONDITION = 1e4
#: Largest :attr:`Calibration.start_shift` without a warning (healthy simulated logs: ≤ 2).
MAX_START_SHIFT = 3.0
#: :attr:`Calibration.start_shift` above which the standard deviations also come from a
#: delete-one-press jackknife: below the warning's threshold, since fits that end 2-3 from
#: the start sphere can already be far off (held, sliding presses on the simulator: ≤ 2.5).
JACKKNIFE_SHIFT = 2.0
#: Standard deviation (m) above which :meth:`Calibration.precision_warning` says how many
#: presses would reach it: 0.1 mm keeps centre and radius within 0.2 mm at 2 std.
TARGET_STD = 0.1e-3
# ... and when the start-value sphere through the presses' contact points has a radius
# deviation above this fraction of the radius (the points do not span a cap).
_MAX_START_SPREAD = 0.1


@dataclass(frozen=True)
class Calibration:
    """Result of :func:`calibrate_fingertip`. SI units.

    Attributes
    ----------
    tip : Sphere, Capsule or Ellipsoid
        The calibrated fingertip.
    center : ndarray, shape (3,)
        Sphere or ellipsoid centre, or the capsule's cap centre ``(x, y, length)``, m, sensor frame.
    radius : float
        Skin radius, m (NaN for an ellipsoid: see :attr:`parameters`).
    compliance : float
        Indentation coefficient ``κ``, m/√N: the surface is ``κ √F_n`` below the skin.
    center_std : ndarray, shape (3,)
        Standard deviations of ``center``, m.
    radius_std, compliance_std : float
        Standard deviations, m and m/√N.
    parameters, parameters_std : ndarray, shape (P,)
        The shape's fitted parameters (the names of its
        :attr:`~softtip.core.shape.PressModel.names`: the centre, then the radius or the
        ellipsoid's semi-axes) and their standard deviations, m.
    residual_rms : float
        RMS of the tangential moment residual, N·m.
    noise_ratio : float
        RMS of the residual in units of its noise predicted by the sensor noise model
        (about 1 when the model fits and the noise model is right; the standard
        deviations are scaled by it).
    n_presses : int
        Presses used in the fit.
    n_skipped : int
        Presses left out (too few samples above ``min_force``; for the capsule also presses
        on or near the cylinder side).
    n_samples : int
        Samples in the fit.
    condition : float
        Condition number of the geometry parameters' correlation matrix.
    start_shift : float
        Distance of the fitted centre from the centre of the start sphere (through the
        presses' contact points located one press at a time), in standard deviations of
        that sphere's radius. Up to about 2 on logs where the standard deviations are
        honest; above :data:`MAX_START_SHIFT` the presses excite too little for the
        sensor's noise and the result may be off by several standard deviations
        (:attr:`warning` says so).
    normals : ndarray, shape (K, 3)
        Fitted contact normal of each press used.
    std_method : str
        ``"curvature"``: the standard deviations are ``s² (JᵀJ)⁻¹`` at the solution;
        ``"jackknife"``: per parameter the larger of those and a delete-one-press
        jackknife's (fits with a :attr:`start_shift` above :data:`JACKKNIFE_SHIFT`, which
        includes every fit with a :attr:`warning`, or when asked).
    tare : TareReport or None
        The bias taken from the first ``tare_duration`` s (the estimator's tare: spikes left
        out) and its warnings (spikes, a fingertip touched while taring); None when the log
        was already tared.
    """

    tip: Fingertip
    center: NDArray[np.float64]
    radius: float
    compliance: float
    center_std: NDArray[np.float64]
    radius_std: float
    compliance_std: float
    residual_rms: float
    noise_ratio: float
    n_presses: int
    n_skipped: int
    n_samples: int
    condition: float
    start_shift: float
    parameters: NDArray[np.float64] = field(repr=False)
    parameters_std: NDArray[np.float64] = field(repr=False)
    normals: NDArray[np.float64] = field(repr=False)
    std_method: str = "curvature"
    tare: TareReport | None = field(default=None, repr=False)

    @property
    def shape(self) -> str:
        """The shape's name (:data:`SHAPES`)."""
        return self.tip.kind

    @property
    def model(self) -> PressModel:
        """What was fitted: the shape's :class:`~softtip.core.shape.PressModel`."""
        return self.tip.press_model()

    @property
    def axis_offset(self) -> NDArray[np.float64]:
        """Capsule: ``(x, y)`` of the cap centre, m (the capsule's ``axis_offset``)."""
        return self.center[:2].copy()

    @property
    def warning(self) -> str:
        """Why the result may be off by more than its standard deviations, or ``""``."""
        if self.start_shift <= MAX_START_SHIFT:
            return ""
        how = (
            "the standard deviations are from refits leaving out one press at a time (the fit's curvature understates "
            "them here), which cover the error in most but not all such cases"
            if self.std_method == "jackknife"
            else "the result may be off by several standard deviations"
        )
        return (
            f"the fit ended {self.start_shift:.1f} standard deviations from the sphere through the presses' own contact "
            f"points: the presses excite too little for the sensor's noise, and {how}; press harder (1-8 N) and slide "
            "the surface while holding each press (softtip calibrate --guide)"
        )

    def precision_warning(self, target: float = TARGET_STD) -> str:
        """What it would take to bring every standard deviation to ``target`` (m), or ``""``.

        The standard deviations fall as ``1/√presses``, so about
        ``n_presses (std / target)²`` presses like these are needed. With the default
        0.1 mm the centre and radius stay within 0.2 mm in 95 % of calibrations.
        """
        return precision_text(
            self.model.stds(self.parameters_std), self.n_presses, target, "every standard deviation",
            "presses over a wider range of forces (half of them at 1-2 N, half at 5-8 N) separate the radius from the "
            "skin's indentation and help most (softtip calibrate --guide)",
        )  # fmt: skip

    @property
    def noise_warning(self) -> str:
        """``""``, or why the noise model does not fit: the residual is outside 0.5–2 times the model's."""
        if 0.5 <= self.noise_ratio <= 2.0:
            return ""
        return (
            f"the residual is {self.noise_ratio:.2f} times the noise model's; the standard deviations allow for it, but "
            "the weights are best with this sensor's noise (the standard deviation of each axis in the untouched part "
            "of the log)"
        )

    def summary(self) -> str:
        """Human-readable report, mm."""
        mm = 1e3
        head, tail = self.model.report(self.parameters, self.parameters_std)
        lines = [
            f"shape {self.shape}: {self.n_presses} presses ({self.n_skipped} left out), {self.n_samples} samples",
            *head,
            f"  indentation {self.compliance * mm:.4f} ± {self.compliance_std * mm:.4f} mm/√N "
            f"({self.compliance * mm * 2.0:.3f} mm at 4 N)",
            f"  residual   {self.residual_rms * mm:.4f} N·mm RMS (tangential moment), {self.noise_ratio:.2f} × the sensor "
            f"noise model's, condition {self.condition:.3g}",
        ]
        lines += tail
        if self.std_method == "jackknife":
            lines.append("  ± are the larger of the fit's curvature and a delete-one-press jackknife")
        return "\n".join(lines)


# --------------------------------------------------------------------------------------
# presses


def find_presses(
    force_norm: ArrayLike, contact_threshold: float = 0.05, min_samples: int = 3
) -> list[NDArray[np.intp]]:
    """Split a log into presses: maximal runs of samples with ``|f| ≥ contact_threshold``.

    Parameters
    ----------
    force_norm : array-like, shape (N,)
        ``|f|`` of the tared log, N.
    contact_threshold : float
        N.
    min_samples : int
        Shorter runs (glitches) are dropped.

    Returns
    -------
    list of int arrays
        Sample indices of each press, in time order.
    """
    on = np.asarray(force_norm, dtype=float) >= contact_threshold
    edges = np.flatnonzero(np.diff(np.concatenate(([0], on.astype(np.int8), [0]))))
    return [np.arange(a, b) for a, b in zip(edges[::2], edges[1::2]) if b - a >= min_samples]


def force_spread(f: NDArray) -> float:
    """Sine of the typical angle the force direction turns through within a press."""
    u = f / np.linalg.norm(f, axis=1, keepdims=True)
    lam = np.linalg.eigvalsh(u.T @ u / len(u))  # ascending
    return float(math.sqrt(max(lam[1], 0.0) / lam[2]))


def _press_point(f: NDArray, m: NDArray, force_var: NDArray) -> NDArray:
    """Point ``r`` with ``m ≈ r × f`` over a press (spin ignored: start value only).

    Least squares on ``A r = m`` with ``A = −[f]×``, its normal matrix corrected for the
    force noise's expected share (``E[[ε]×ᵀ[ε]×] = tr(Σ_f) I − Σ_f`` per sample), so that
    noise does not pull the point towards the sensor origin.
    """
    a = -_skew(f).reshape(-1, 3)  # r × f = −f × r
    ata = a.T @ a
    corrected = ata - len(f) * (np.sum(force_var) * np.eye(3) - np.diag(force_var))
    # the correction is an expectation: where it would eat most of the signal, keep plain least squares
    if np.linalg.eigvalsh(corrected)[0] > 0.25 * np.linalg.eigvalsh(ata)[0]:
        ata = corrected
    return np.linalg.solve(ata, a.T @ m.reshape(-1))


def _sphere_fit(points: NDArray) -> tuple[NDArray, float, float]:
    """Algebraic sphere through ``points`` (K, 3): centre, radius and the radius' standard deviation.

    ``|r|² = 2 c·r + d`` is linear in ``(c, d)``, so its covariance (scaled by the residual
    variance) holds globally, not just near one solution: a small spread of the points
    (one spot, one circle) shows up as a large radius deviation wherever the fit lands.
    """
    a = np.column_stack((2.0 * points, np.ones(len(points))))
    b = np.sum(points * points, axis=1)
    scale = np.linalg.norm(a, axis=0)
    sol, *_ = np.linalg.lstsq(a / scale, b, rcond=None)
    sol = sol / scale
    c = sol[:3]
    r2 = sol[3] + c @ c
    if not r2 > 0 or len(points) <= 4:
        return c, math.nan, math.inf
    resid = b - a @ sol
    cov = (resid @ resid) / (len(b) - 4) * np.linalg.pinv(a.T @ a)
    radius = math.sqrt(r2)
    grad = np.concatenate((c, [0.5])) / radius  # dR = (c·dc + dd/2) / R
    return c, radius, math.sqrt(max(float(grad @ cov @ grad), 0.0))


# --------------------------------------------------------------------------------------
# the fit


#: Presses the fit needs at least: the sphere through their points that starts it has 4
#: parameters, and one press more is what shows its spread (through 4 points any sphere fits).
MIN_PRESSES = 5
#: deg: the least turn of a press's force direction that locates its point (``min_spread``).
MIN_TURN_DEG = 3.0


def precision_text(stds: dict[str, float], n_presses: int, target: float, what: str, advice: str) -> str:
    """``""``, or the calibration warning of its largest standard deviation (``stds``: name → m)
    above ``target`` (m): they fall as ``1/√presses``, so about ``n_presses (std / target)²``
    presses like these bring ``what`` to ``target``; ``advice`` says how to press."""
    name = max(stds, key=lambda k: stds[k])
    worst = stds[name]
    if not worst > target:
        return ""
    need = math.ceil(n_presses * (worst / target) ** 2)
    return (
        f"the {name} is known to ±{worst * 1e3:.2f} mm (1 std) only: about {need} presses like these would bring "
        f"{what} to {target * 1e3:.2g} mm (they fall as 1/√presses); {advice}"
    )


def _not_excited(detail: str, model: PressModel) -> InputError:
    return InputError(
        f"the presses do not excite enough directions to calibrate the fingertip: {detail}. "
        "Press the fingertip against a flat surface at many points spread over the skin (at least "
        f"{MIN_PRESSES}, better 15 or more, covering {model.coverage}), and during each press let the surface "
        f"slide or the finger rock a little so that the friction force turns (at least {MIN_TURN_DEG:g}° to locate "
        "the press; 40° or more pins its point well)"
    )


#: A probing log touched while taring: the calibration takes no bias of its own
PROBING_TOUCHED_REMEDY = (
    "record the probing log again with the fingertip untouched at its start, or tare_duration 0 "
    "(--tare-duration 0) for a log that is already tared"
)


def tare_probing_log(
    t: NDArray[np.float64], w: NDArray[np.float64], tare_duration: float, noise: SensorNoise = NANO17
) -> tuple[NDArray[np.float64], TareReport | None]:
    """The wrench ``w`` (N, 6) less its bias from the first ``tare_duration`` s, by the
    estimator's tare (the mean without spikes: one corrupted sample among the untouched ones
    would otherwise move every press by its share of the mean), and that tare's report
    (None, and ``w`` as it is, when ``tare_duration`` is 0: the log is already tared)."""
    if not tare_duration > 0:
        return w, None
    config = EstimatorConfig(noise=noise, tare_duration=tare_duration, noise_from_tare="off")  # the fit uses ``noise``
    tare = tare_from_samples(w[t - t[0] < tare_duration], config, touched_remedy=PROBING_TOUCHED_REMEDY)
    return w - tare.bias, tare


def calibrate_fingertip(
    t: ArrayLike,
    wrench: ArrayLike,
    shape: str = "sphere",
    *,
    tare_duration: float = 0.2,
    contact_threshold: float = 0.05,
    min_force: float = 0.5,
    min_spread: float = math.sin(math.radians(MIN_TURN_DEG)),
    compliance: bool = True,
    noise: SensorNoise = NANO17,
    jackknife: bool | None = None,
    source: str = "<log>",
) -> Calibration:
    """Fit the fingertip's centre and radius to a probing log of plane presses.

    Parameters
    ----------
    t : array-like, shape (N,)
        Sample times, s, increasing.
    wrench : array-like, shape (N, 6)
        Raw wrench ``fx, fy, fz`` (N), ``mx, my, mz`` (N·m), sensor frame.
    shape : {"sphere", "capsule", "ellipsoid"}
        One of :data:`SHAPES`. Capsule: cylinder axis along z, cap centre ``(x, y, length)``;
        ellipsoid: axis-aligned, centre and semi-axes.
    tare_duration : float
        The first ``tare_duration`` s (fingertip untouched) give the bias, their mean without
        spikes (:func:`tare_probing_log`); 0 if the log is already tared.
    contact_threshold : float
        N; presses are the runs with ``|f|`` at least this (raised to 4 times the force
        noise's magnitude ``sqrt(Σ σ_f²)`` when that is larger, so that noise alone does not
        make presses).
    min_force : float
        N; only samples with ``|f| ≥ min_force`` enter the fit (the soft-finger model and
        the signal-to-noise ratio are poor at the very first touch).
    min_spread : float
        Sine of the smallest turn of the force direction within a press for the press to
        locate its contact point in 3-D (start values; such presses must number ≥ 4).
    compliance : bool
        Fit the indentation ``κ √F_n`` (module docs); False assumes a rigid skin.
    noise : SensorNoise
        The sensor's per-axis noise (default Nano17 class). Each sample is weighted by the
        noise of its residual propagated from it; what matters for the weights is the
        ratio of force to moment noise (the overall scale is taken from the residual).
    jackknife : bool or None
        Standard deviations also from refits leaving out one press at a time (the larger
        of those and the curvature's per parameter; one refit per press). None (default):
        only when the fit ends more than :data:`JACKKNIFE_SHIFT` from the start sphere,
        where the curvature's can understate the scatter.
    source : str
        Name used in error messages.

    Returns
    -------
    Calibration

    Raises
    ------
    ValueError
        A noise model without moment noise on some axis.
    InputError
        Unknown shape, too few presses, presses that do not excite enough directions (force
        direction does not turn within presses, presses not spread over the skin), or an
        ill-conditioned fit.
    """
    if shape not in SHAPES:
        raise InputError(f"unknown shape {shape!r}; expected one of {', '.join(SHAPES)}")
    model = _ALL_SHAPES[shape].press_model()
    if not min(noise.moment_std) > 0.0:
        raise ValueError(f"noise.moment_std must be positive on every axis (it sets the weights), got {noise.moment_std!r}")
    t = np.asarray(t, dtype=float)
    w = np.asarray(wrench, dtype=float)
    if t.ndim != 1 or w.shape != (len(t), 6):
        raise InputError(f"{source}: expected t (N,) and wrench (N, 6), got {t.shape} and {w.shape}")
    if len(t) == 0:
        raise InputError(f"{source}: no samples")
    w, tare = tare_probing_log(t, w, tare_duration, noise)
    f_all, m_all = w[:, :3], w[:, 3:]
    fn_all = np.linalg.norm(f_all, axis=1)

    presses = []
    n_skipped = 0
    # noise alone must not make presses: |noise| is about sqrt(Σ σ_f²) while untouched
    threshold = max(contact_threshold, 4.0 * math.sqrt(float(np.sum(np.square(noise.force_std)))))
    for idx in find_presses(fn_all, threshold):
        keep = idx[fn_all[idx] >= min_force]
        if len(keep) < 5:
            n_skipped += 1
            continue
        presses.append(keep)
    if len(presses) < MIN_PRESSES:
        raise _not_excited(
            f"{source} has {len(presses)} press(es) with at least 5 samples above {min_force:g} N; expected at least "
            f"{MIN_PRESSES}",
            model,
        )

    # start values: per press the point m = r × f pins (if the force turns), a sphere through them
    spread = np.array([force_spread(f_all[k]) for k in presses])
    located = np.flatnonzero(spread >= min_spread)
    if len(located) < MIN_PRESSES:
        raise _not_excited(
            f"in {len(located)} of {len(presses)} presses of {source} the force direction turns by more than "
            f"{math.degrees(math.asin(min_spread)):.0f}° (largest turn {math.degrees(math.asin(min(spread.max(), 1.0))):.1f}°); "
            f"expected at least {MIN_PRESSES}",
            model,
        )
    force_var = np.square(noise.force_std)
    points = np.array([_press_point(f_all[presses[k]], m_all[presses[k]], force_var) for k in located])
    c0, r0, r0_std = _sphere_fit(points)
    if not (math.isfinite(r0) and r0_std <= _MAX_START_SPREAD * r0):
        detail = f"±{r0_std * 1e3:.2g} mm on {r0 * 1e3:.3g} mm" if math.isfinite(r0) else "no sphere"
        raise _not_excited(
            f"the contact points of the {len(located)} presses in {source} that locate one lie too close to one spot "
            f"or one circle to fix a sphere (radius {detail})",
            model,
        )

    normals0 = np.array([_press_normal(f_all[k], m_all[k], c0, r0) for k in presses])
    keep = model.accepts(normals0)
    if not keep.all():
        n_skipped += int(np.count_nonzero(~keep))
        presses = [p for p, ok in zip(presses, keep) if ok]
        normals0 = normals0[keep]
        if len(presses) < MIN_PRESSES:
            raise _not_excited(f"{len(presses)} presses of {source} are {model.region}; expected at least {MIN_PRESSES}",
                               model)  # fmt: skip

    sol = _fit(f_all, m_all, presses, normals0, c0, r0, compliance, noise, model)
    tip = model.tip(sol["parameters"], source)
    start_shift = float(np.linalg.norm(sol["center"] - c0) / r0_std) if r0_std > 0 else 0.0
    x = sol.pop("x")
    std_method = "curvature"
    if jackknife or (jackknife is None and start_shift > JACKKNIFE_SHIFT):
        jk = _jackknife_std(f_all, m_all, presses, normals0, x, compliance, noise, model)
        # neither estimate is allowed to shrink the other: the larger of the two per parameter
        n_shape = len(model.names)
        sol["parameters_std"] = np.maximum(sol["parameters_std"], jk[:n_shape] * 1e-3)
        sol["center_std"] = sol["parameters_std"][:3]
        sol["radius_std"] = _radius(model, sol["parameters_std"])
        if compliance:
            sol["compliance_std"] = max(sol["compliance_std"], float(jk[n_shape]) * 1e-3)
        std_method = "jackknife"
    return Calibration(tip=tip, n_skipped=n_skipped, start_shift=start_shift, std_method=std_method, tare=tare, **sol)


def _radius(model: PressModel, values: NDArray) -> float:
    """The ``radius`` among the fitted parameters (m), NaN when the shape has none."""
    return float(values[model.names.index("radius")]) if "radius" in model.names else math.nan


def _press_normal(f: NDArray, m: NDArray, c: NDArray, radius: float) -> NDArray:
    """Mean soft-finger contact normal of a press on the trial sphere ``(c, radius)``."""
    out = sphere_kernel(*f.T, *m.T, radius, *c, NP)
    n = np.column_stack(out[3:6])[out[7]]
    if len(n) == 0:  # no pushing root on the trial sphere: the force direction is a fair guess
        n = -f / np.linalg.norm(f, axis=1, keepdims=True)
    n = n.mean(axis=0)
    return n / np.linalg.norm(n)


def _whiten(e: NDArray, u1: NDArray, u2: NDArray, r: NDArray, force_var: NDArray, moment_var: NDArray) -> NDArray:
    """Whitened tangential residuals, shape (2 N,): ``L⁻¹ (e·u1, e·u2)`` with ``L Lᵀ`` their noise covariance.

    The noise of ``e = m − r × f`` along a unit vector ``u`` is ``u·ε_m − (u × r)·ε_f``, so
    the 2 × 2 covariance of ``(e·u1, e·u2)`` is
    ``S_jl = Σ_a σ_m,a² u_j,a u_l,a + Σ_a σ_f,a² (u_j × r)_a (u_l × r)_a`` (per-axis
    variances ``force_var``, ``moment_var``; lengths in mm, moments in N·mm).
    """
    w1, w2 = _cross(u1, r), _cross(u2, r)
    a = (u1 * u1) @ moment_var + (w1 * w1) @ force_var
    b = (u1 * u2) @ moment_var + (w1 * w2) @ force_var
    c = (u2 * u2) @ moment_var + (w2 * w2) @ force_var
    e1, e2 = np.sum(e * u1, axis=1), np.sum(e * u2, axis=1)
    sa = np.sqrt(a)
    return np.concatenate((e1 / sa, (e2 - b / a * e1) / np.sqrt(c - b * b / a)))


def _objective(f_all, m_all, presses, normals0, compliance: bool, noise: SensorNoise, model: PressModel):
    """Whitened residual, its Jacobian and the parameter unpacking for the presses given.

    Parameters ``x``: the shape's (``model.names``: centre (3, mm), radius or semi-axes, mm),
    the indentation coefficient (mm/√N, with ``compliance``) and two tangential coordinates
    of each press's normal about ``normals0``.
    """
    k = len(presses)
    idx = np.concatenate(presses)
    press_of = np.concatenate([np.full(len(p), j) for j, p in enumerate(presses)])
    f = f_all[idx]
    m = m_all[idx] * 1e3  # N·mm
    force_var = np.square(noise.force_std)
    moment_var = np.square(np.asarray(noise.moment_std) * 1e3)  # (N·mm)²
    t1, t2 = _tangent_basis(normals0)
    n_shape = len(model.names)
    n_geo = n_shape + 1 if compliance else n_shape

    def unpack(x):
        geo = x[:n_shape]
        kappa = x[n_shape] if compliance else 0.0
        ab = x[n_geo:].reshape(k, 2)
        n = normals0 + ab[:, :1] * t1 + ab[:, 1:] * t2
        n = n / np.linalg.norm(n, axis=1, keepdims=True)
        return geo, kappa, n

    def residual(x, whiten=True):
        geo, kappa, n = unpack(x)
        ns = n[press_of]
        f_normal = np.maximum(-np.sum(f * ns, axis=1), 0.0)
        r = model.points(geo, ns, kappa * np.sqrt(f_normal))
        e = m - _cross(r, f)
        # tangent basis at the current normal: the spin (along n) is free
        u1 = t1[press_of] - np.sum(t1[press_of] * ns, axis=1, keepdims=True) * ns
        u1 /= np.linalg.norm(u1, axis=1, keepdims=True)
        u2 = _cross(ns, u1)
        if not whiten:
            return np.concatenate((np.sum(e * u1, axis=1), np.sum(e * u2, axis=1)))
        return _whiten(e, u1, u2, r, force_var, moment_var)

    # a press's normal moves only its own samples' residuals: central differences that
    # perturb one normal coordinate of every press at once (2 (n_geo + 2) evaluations)
    n_par = n_geo + 2 * k
    rows = np.arange(2 * len(idx))
    col_of_row = np.concatenate((press_of, press_of))

    def jacobian(x):
        jac = np.zeros((2 * len(idx), n_par))
        for j in range(n_geo + 2):
            step = np.zeros(n_par)
            if j < n_geo:
                step[j] = 1.0
            else:
                step[j::2][: k] = 1.0
            h = 1e-6 * max(1.0, float(np.max(np.abs(x[step > 0]))))
            d = (residual(x + h * step) - residual(x - h * step)) / (2.0 * h)
            if j < n_geo:
                jac[:, j] = d
            else:
                jac[rows, n_geo + 2 * col_of_row + (j - n_geo)] = d
        return jac

    return residual, jacobian, unpack, n_geo, len(idx)


def _jackknife_std(f_all, m_all, presses, normals0, x, compliance: bool, noise: SensorNoise, model: PressModel) -> NDArray:
    """Delete-one-press jackknife standard deviations of the geometry parameters (mm, mm/√N).

    Each press in turn is left out and the fit repeated from the full solution; the spread
    of the ``K`` refits, ``sqrt((K − 1)/K Σ (θ₋ₖ − θ̄)²)``, estimates the estimator's
    scatter without the local linearisation behind ``(JᵀJ)⁻¹``, which understates it where
    the presses excite little compared with the noise (the objective is far from
    quadratic over the range of the scatter).
    """
    k = len(presses)
    n_geo = len(model.names) + 1 if compliance else len(model.names)
    geo = []
    for j in range(k):
        keep = np.arange(k) != j
        sub = [p for p, ok in zip(presses, keep) if ok]
        residual, jacobian, _, _, _ = _objective(f_all, m_all, sub, normals0[keep], compliance, noise, model)
        x0 = np.concatenate((x[:n_geo], x[n_geo:].reshape(k, 2)[keep].ravel()))
        res = least_squares(residual, x0, method="lm", x_scale="jac", jac=jacobian, xtol=1e-8, ftol=1e-8, gtol=1e-8)
        geo.append(res.x[:n_geo])
    geo = np.array(geo)
    return np.sqrt((k - 1) / k * np.sum(np.square(geo - geo.mean(axis=0)), axis=0))


def _fit(f_all, m_all, presses, normals0, c0, r0, compliance: bool, noise: SensorNoise, model: PressModel) -> dict:
    """Noise-weighted nonlinear least squares; lengths in mm and moments in N·mm inside (scaled).

    Each sample's tangential residual is whitened by its noise covariance at the current
    parameters (the force noise enters through the lever arm ``r``), so the objective's
    expected noise share is the same (two per sample) for every trial geometry: the
    estimate is consistent, unlike plain least squares, which prefers a shorter lever arm.
    """
    k = len(presses)
    residual, jacobian, unpack, n_geo, n_samples = _objective(f_all, m_all, presses, normals0, compliance, noise, model)
    n_par = n_geo + 2 * k
    n_shape = len(model.names)
    x0 = np.concatenate((model.start(c0, r0), [0.1] if compliance else [], np.zeros(2 * k)))
    res = least_squares(residual, x0, method="lm", x_scale="jac", jac=jacobian, xtol=1e-12, ftol=1e-12, gtol=1e-12)
    jac = res.jac
    n_res = jac.shape[0]
    dof = max(n_res - n_par, 1)
    # the residuals are in units of the noise model: s² ≈ 1 when the model is right; the
    # covariance is scaled by it so that a noise model off by a constant factor (or model
    # error on top of the noise) still gives honest standard deviations
    s2 = float(res.fun @ res.fun) / dof
    jtj = jac.T @ jac
    cov = s2 * np.linalg.pinv(jtj)
    geo = cov[:n_geo, :n_geo]
    std = np.sqrt(np.maximum(np.diag(geo), 0.0))
    corr = geo / np.outer(std, std) if np.all(std > 0) else np.full_like(geo, np.nan)
    ev = np.linalg.eigvalsh(corr) if np.all(np.isfinite(corr)) else np.array([0.0, 1.0])
    condition = float(ev[-1] / ev[0]) if ev[0] > 0 else math.inf
    if not condition <= _MAX_CONDITION:
        names = [*model.names, "indentation"][:n_geo]
        vec = np.linalg.eigh(corr)[1][:, 0] if np.all(np.isfinite(corr)) else np.ones(n_geo)
        worst = ", ".join(names[i] for i in np.argsort(-np.abs(vec))[:2])
        raise _not_excited(f"the fit cannot separate {worst} (condition number {condition:.3g} > {_MAX_CONDITION:.0e})", model)
    geo, kappa, n = unpack(res.x)
    for name, value in zip(model.names[3:], geo[3:]):
        if not value > 0:
            raise _not_excited(f"the fitted {name} is {value:.3g} mm", model)
    parameters, parameters_std = geo * 1e-3, std[:n_shape] * 1e-3
    return {
        "center": parameters[:3],
        "radius": _radius(model, parameters),
        "compliance": float(kappa) * 1e-3,
        "center_std": parameters_std[:3],
        "radius_std": _radius(model, parameters_std),
        "compliance_std": float(std[n_shape]) * 1e-3 if compliance else 0.0,
        "parameters": parameters,
        "parameters_std": parameters_std,
        "residual_rms": math.sqrt(float(np.mean(np.square(residual(res.x, whiten=False))))) * 1e-3,
        "noise_ratio": math.sqrt(s2),
        "n_presses": k,
        "n_samples": n_samples,
        "condition": condition,
        "normals": n,
        "x": res.x,
    }


# --------------------------------------------------------------------------------------
# output


def write_fingertip_toml(cal: Calibration, path: str | os.PathLike[str], source: str = "") -> None:
    """Write the calibrated fingertip as a fingertip TOML file, atomically.

    The fit's standard deviations go in comments; a capsule's axis offset is its
    ``axis_offset`` key.

    Raises
    ------
    InputError
        ``path`` cannot be written (the destination is left untouched).
    """
    mm = 1e3
    header = [
        f"# softtip calibrate{(' ' + source) if source else ''}: {cal.n_presses} presses, {cal.n_samples} samples",
        f"# {cal.model.std_line(cal.parameters_std)}; residual {cal.residual_rms * mm:.4f} N·mm RMS",
    ]
    if cal.warning or cal.precision_warning():
        header.append(f"# warning: {cal.warning or cal.precision_warning()}")
    if getattr(cal.tip, "skin_thickness", None) is None:
        header.append(
            "# no skin_thickness: softtip estimate's depth compensation is off for this fingertip; add "
            "skin_thickness = <the soft skin's thickness, m> under [fingertip] to turn it on"
        )
    text = "\n".join(header) + "\n" + cal.tip.to_toml()
    atomic_write_text(path, text)
