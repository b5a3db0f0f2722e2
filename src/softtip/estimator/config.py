"""Settings of the estimator (:class:`EstimatorConfig`)."""

from __future__ import annotations

import inspect
import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.core.depth import DepthLaw
from softtip.core.filtering import lowpass_sos
from softtip.core.noise import NANO17, SensorNoise
from softtip.core.units import KGF

__all__ = ["CONTACT_POINT_MODES", "DEPTH_MODES", "TARE_METHODS", "EstimatorConfig"]

#: Values of :attr:`EstimatorConfig.contact_point`.
CONTACT_POINT_MODES = ("latch", "track", "line-fit")
#: Former names of :attr:`EstimatorConfig.contact_point` values, still accepted.
CONTACT_POINT_ALIASES = {"joint": "line-fit"}
#: Values of :attr:`EstimatorConfig.tare_method`.
TARE_METHODS = ("robust", "median", "mean")
#: Values of :attr:`EstimatorConfig.depth_mode`.
DEPTH_MODES = ("auto", "online", "law", "off")


@dataclass(frozen=True)
class EstimatorConfig:
    """Settings of the pipeline. SI units.

    Parameters
    ----------
    contact_point : {"latch", "track", "line-fit"}
        How the contact point is obtained (module docstring). ``"joint"`` is accepted as the
        former name of ``"line-fit"`` (the joint estimate of the line's angle and offset over a
        window; its settings and output columns keep the ``joint_`` prefix).
    contact_threshold : float
        N; in contact while ``|f|`` (tared, filtered) is at least this.
    latch_force_range : (float, float)
        N; the light-force range ``|f|`` must lie in for a sample to be latched (default
        0.2–0.5 kgf; the papers' "window" of force). ``latch_window=`` is accepted as its
        former name.
    stall_time : float
        s; the first rise ends when ``|f|`` has set no new maximum for this long.
    fallback_samples : int
        Samples averaged for a latch when the rise has no sample in the window.
    noise : SensorNoise
        Standard deviations of the unfiltered sensor noise (with ``noise_from_tare``: the
        model the tare's samples are checked against, and the fallback).
    h_sigmas, h_min : float
        ``|h|`` is significant (a ``line`` contact) above ``max(h_sigmas · h_std, h_min)``;
        ``h_min`` in N·m (default 0.5 N·mm).
    lowpass_hz : float or None
        Cutoff of the causal Butterworth low-pass, Hz; ``None`` for no filter.
    lowpass_order : int
    sample_rate : float or None
        Hz. Needed with ``lowpass_hz``; :func:`estimate` infers it from the median time step
        when absent.
    bias : 6 floats or None
        Sensor bias (N, N·m) to subtract; ``None`` to tare from the first samples.
    tare_duration : float
        s of samples averaged for the bias when ``bias`` is ``None``; 0 disables taring
        (the input is already tared).
    relatch_distance : float or None
        m; re-latch when, with the latch held and ``|f|`` inside ``latch_force_range``, the
        soft-finger solution lies farther than this from the latched point. ``None``
        (default, the papers'): only on contact loss. A few mm (e.g. 3 mm) is beyond the
        soft-finger bias of the papers' line contacts at light force (≈ ``|h| / |f|`` ≤ 1 mm).
    depth : DepthLaw or None
        Skin law of the depth compensation (:mod:`softtip.core.depth`): the fixed law of
        ``depth_mode="law"``, the prior of ``"online"``. ``None`` (default): the
        fingertip's own (:func:`softtip.estimator.depth.tip_depth_law`: the murakami2006
        preset and any fingertip file with a ``skin_thickness``).
    depth_mode : {"auto", "online", "law", "off"}
        ``online``: the depth learnt per contact from the data, the law its prior
        (:mod:`softtip.estimator.depth`); ``law``: the law's depth at the normal force
        (fixed); ``off``: the papers' undeformed contact point. ``auto`` (default):
        ``online`` in ``latch`` mode when there is a law (``depth`` or the fingertip's),
        else ``off``; in ``track`` and ``line-fit`` mode ``law`` when ``depth`` is given, else
        ``off``.
    depth_window : float
        s; sliding window of the online depth (default 1 s).
    depth_prior_std : float
        Standard deviation of the prior depth factor (mean 1), relative (default 0.5: one law
        does not fit every object; a thin plate sinks about 1.5 times deeper than a round stick).
    depth_drift : float
        1/√s; how fast the held factor of a contact ages (default 0.02/√s): the factor held
        is the window with the smallest ``variance + depth_drift² · age``.
    joint_window : float
        s; length of the sliding window of ``line-fit`` mode (default 1 s: 50 samples at the
        papers' 50 Hz).
    joint_max_angle_std, joint_max_offset_std : float
        ``line-fit`` mode accepts a window when the standard deviations of its line angle (rad,
        default 2°) and of its offset across the line (m, default 0.2 mm) are at most these.
    joint_max_residual : float
        ... and the RMS residual of its fit is at most this many noise standard deviations.
    joint_drift : float
        m/√s; how fast the contact may wander unseen: the point held is the accepted window
        with the smallest ``offset_std² + joint_drift² · age`` (default 0.03 mm/√s), so a
        precise window is kept over later, weaker ones, but not for ever (positive, at most 1).
    joint_iterations : int
        Gauss–Newton steps of each window's solve.
    tare_method : {"robust", "median", "mean"}
        How the tare samples make the bias: ``robust`` (default), the mean of the samples that
        are not spikes (farther than 8 standard deviations from the median; the plain mean
        when there is none); ``median``, per component; ``mean``, of all samples (a −20 N
        spike among ten samples moves it by 2 N).
    contact_hysteresis : float
        Contact starts at ``|f| ≥ contact_threshold`` and ends below the release threshold
        ``max(contact_threshold − contact_hysteresis · σ_f, min(contact_threshold, 2.5 σ_f))``,
        with ``σ_f`` the noise of ``|f|`` (root sum of squares of the force noise model, after
        the filter; an untouched sensor's ``|f|`` is below ``2.5 σ_f`` 90 % of the time);
        0 for a single threshold.
    contact_min_duration : float
        s; a contact is reported once ``|f|`` has stayed above the release threshold for this
        long since it first reached ``contact_threshold``, each sample counting for its
        sampling interval (default 5 ms: at once at 50 Hz, five samples at 1 kHz; 0: at
        once). A spike shorter than this is not a contact.
    drift_time_constant : float
        s; while untouched (no contact pending or held) the bias is tracked by an exponential moving average with this time constant (default 10 s: a
        drift of r N/s is followed with a lag of r · 10 s; a touch that builds up slower than
        that is taken for drift).
    track_drift : bool
        Subtract the tracked drift (default). ``False`` (the papers' comparison): the drift
        is still estimated and reported, not subtracted.
    line_evidence : bool
        Tell a line from an area over a sliding window (:mod:`softtip.estimator.evidence`;
        default on). ``False``: the papers' per-sample behaviour (``line`` whenever ``|h|``
        is significant, marked ``unconfirmed``; never ``area``).
    evidence_window : float
        s; length of that window (default 2 s: 100 samples at 50 Hz, two periods of a 1 Hz
        rocking motion).
    area_ratio : (float, float)
        ``(enter, leave)``: the contact becomes ``area`` when the smaller eigenvalue of
        ``h``'s window covariance is beyond the noise and at least ``enter`` times the
        larger, and a confirmed ``line`` again only when the ratio is below ``leave``
        (hysteresis; default 0.2, 0.1).
    area_share : float
        The contact reads ``area`` while more than this share of the evidence window's samples
        show ``h`` spread over both tangent axes (the ``enter`` test of ``area_ratio``), and
        stops reading it as soon as the sliding window no longer does (default 0.5: a sustained
        spread, at the default window a second of it; a transient spread while a new rock
        begins, when the window holds the end of one excitation and the start of the next,
        does not make an area). A reading of the current window, not a verdict.
    rocked : sequence of (float, float)
        s, in the log's time: intervals during which the user rocked the object about two
        tangent axes (in turn or at once), stated because the wrench cannot always show it: on
        a frictionless round skin the tangential load stays locked to ``h`` (manual §3.5), so
        a line rocked about its own axis leaves no trace in the load. A window wholly inside
        one of them (its start ``t − evidence_window`` at or after the interval's start, ``t``
        at or before its end) counts as excited about two axes: ``h`` still on one axis there
        confirms a line, and a plane shows its spread as an area. State only an interval in
        which every window of ``evidence_window`` seconds saw both axes. Default none.
    excitation_ratio : float
        The contact counts as excited about two tangent axes when the tangential load's
        window covariance has its smaller eigenvalue beyond the noise and at least this
        times the larger (default 0.5: turned about the two axes nearly alike; a window
        excited mostly about one axis biases the line's axis).
    excitation_min : float
        N; ... and that smaller eigenvalue at least this squared (the load's standard
        deviation about its weaker axis; default 0.01 N): a load turning by less is not
        taken for the trace of a tilt (a low-pass's slow transients are not excitation).
    evidence_max_angle_std : float
        rad; a window's line direction is used (and held) only when its own standard
        deviation (without ``evidence_model_std``) is at most this (default 10°).
    evidence_model_std : float
        rad; the model error of a direction from a window excited about two axes (a window
        that confirms the line), which no window shows, added in quadrature to its standard
        deviation (default 0.4°). The axis of ``h``'s variation turns a little
        with the pattern of excitation (the contact's small nonlinearity: on the simulator's
        rocked lines, 0.2–1.5° between rocking about two axes in turn and in a figure-eight),
        while the window's own standard deviation shrinks with the number of samples; without
        this term a window at 1–7 kHz claims a precision the physics does not give.
    unconfirmed_model_std : float
        rad; model error of a line direction taken from one axis of excitation (an
        ``unconfirmed`` line's, and a confirmed line's where the current window was excited
        about one axis), added in quadrature to the sample's standard
        deviation (default 5°). The line's small resistance to rolling about its own edge
        follows the same excitation and turns the axis by an amount no window of it shows: on
        the simulator's papers' grasps of plates ≤ 3 mm, wedges and Ø 4–6 mm cylinders the
        median errors were 2.5–7.7°, while the sensor noise alone accounted for about 3.3° at
        any rate unfiltered and 0.3–0.7° behind a 20 Hz low-pass. A bound more than a
        calibration (thin plates are off by less, thin cylinders at times by more); 0: the
        noise only. Not applied with ``line_evidence`` off (the papers' behaviour).
    evidence_reset_distance : float
        m; the evidence starts afresh (window, verdict, held direction) when the contact
        point moves farther than this from where it started (default 1 mm): what a window
        said about another point does not hold for the new one.
    significance_window : float
        s; ``|h|`` turns significant (a line) when most of the segment's samples of the last
        this many seconds are above the line threshold, and not significant when most are
        below its leaving share (:data:`~softtip.estimator.evidence.SIG_LEAVE`); otherwise it
        stays as it was. Default 15 ms: shorter than a sample period at 50 Hz, so there each
        sample decides alone (the papers' test); at 1–7 kHz a vote of 15–105 samples, so
        sensor noise near the threshold does not make a line flicker to ``point``. 0: each
        sample alone at every rate.
    noise_from_tare : bool
        Measure the noise model from the tare: the standard deviation of each axis over the
        tare's samples (spikes left out) replaces ``noise`` for everything after the tare
        (thresholds, every reported standard deviation): the presets are about one
        resolution count, not this sensor's noise. Needs a tare
        (``tare_duration`` > 0, no ``bias``) of at least
        :data:`~softtip.estimator.tare.NOISE_MIN_SAMPLES` samples (its standard deviations
        then known to about 13 %; e.g. 1 s at 50 Hz); with fewer, with a tare that looks
        touched, or on an axis that did not vary at all, ``noise`` is kept and a warning
        says so; an axis read in steps of ``q`` is taken as at least ``q / √12`` (its
        rounding). Default off.
    """

    contact_point: Literal["latch", "track", "line-fit", "joint"] = "latch"
    contact_threshold: float = 0.05
    latch_force_range: tuple[float, float] = (0.2 * KGF, 0.5 * KGF)
    stall_time: float = 0.1
    fallback_samples: int = 5
    noise: SensorNoise = field(default=NANO17)
    h_sigmas: float = 3.0
    h_min: float = 5e-4
    lowpass_hz: float | None = None
    lowpass_order: int = 2
    sample_rate: float | None = None
    bias: tuple[float, ...] | None = None
    tare_duration: float = 0.2
    relatch_distance: float | None = None
    depth: DepthLaw | None = None
    joint_window: float = 1.0
    joint_max_angle_std: float = math.radians(2.0)
    joint_max_offset_std: float = 2e-4
    joint_max_residual: float = 3.0
    joint_drift: float = 3e-5
    joint_iterations: int = 2
    tare_method: Literal["robust", "median", "mean"] = "robust"
    contact_hysteresis: float = 3.0
    contact_min_duration: float = 0.005
    drift_time_constant: float = 10.0
    track_drift: bool = True
    depth_mode: Literal["auto", "online", "law", "off"] = "auto"
    depth_window: float = 1.0
    depth_prior_std: float = 0.5
    depth_drift: float = 0.02
    line_evidence: bool = True
    evidence_window: float = 2.0
    area_ratio: tuple[float, float] = (0.2, 0.1)
    area_share: float = 0.35
    rocked: tuple[tuple[float, float], ...] = ()
    excitation_ratio: float = 0.5
    excitation_min: float = 0.01
    evidence_max_angle_std: float = math.radians(10.0)
    evidence_model_std: float = math.radians(0.4)
    unconfirmed_model_std: float = math.radians(5.0)
    evidence_reset_distance: float = 1e-3
    significance_window: float = 0.015
    noise_from_tare: bool = False

    def stated_excitation(self, t):
        """Whether the evidence window ending at ``t`` (s, float or array) lies wholly inside a
        stated two-axis rocking interval (:attr:`rocked`)."""
        inside = False if np.ndim(t) == 0 else np.zeros(np.shape(t), dtype=bool)
        for a, b in self.rocked:
            inside = inside | ((t - self.evidence_window >= a) & (t <= b))
        return inside

    def line_threshold(self, h_std: ArrayLike) -> NDArray[np.float64]:
        """The ``|h|`` above which a contact is a line: ``max(h_sigmas · h_std, h_min)``.

        Parameters
        ----------
        h_std : array of shape (...,), N·m
            The noise level of ``h`` (:attr:`Estimates.h_std`).

        Returns
        -------
        array of shape (...,), N·m
        """
        return np.maximum(self.h_sigmas * np.asarray(h_std, dtype=float), self.h_min)

    def __post_init__(self) -> None:
        if self.depth_mode not in DEPTH_MODES:
            raise ValueError(f"depth_mode must be one of {', '.join(DEPTH_MODES)}, got {self.depth_mode!r}")
        for name in ("depth_window", "depth_prior_std", "depth_drift"):
            v = float(getattr(self, name))
            if not (math.isfinite(v) and v > 0.0):
                raise ValueError(f"{name} must be a positive number, got {getattr(self, name)!r}")
            object.__setattr__(self, name, v)
        object.__setattr__(self, "contact_point", CONTACT_POINT_ALIASES.get(self.contact_point, self.contact_point))
        if self.contact_point not in CONTACT_POINT_MODES:
            raise ValueError(f"contact_point must be one of {', '.join(CONTACT_POINT_MODES)}, got {self.contact_point!r}")
        if self.relatch_distance is not None:
            v = float(self.relatch_distance)
            if not (math.isfinite(v) and v > 0.0):
                raise ValueError(f"relatch_distance must be a positive distance in m or None, got {self.relatch_distance!r}")
            object.__setattr__(self, "relatch_distance", v)
        if self.depth is not None and not isinstance(self.depth, DepthLaw):
            raise ValueError(f"depth must be a softtip.core.depth.DepthLaw or None, got {self.depth!r}")
        lo, hi = (float(v) for v in self.latch_force_range)
        if not (0.0 <= lo < hi):
            raise ValueError(
                f"latch_force_range must be (low, high) with 0 <= low < high, in N; got {self.latch_force_range!r}"
            )
        object.__setattr__(self, "latch_force_range", (lo, hi))
        for name in ("joint_window", "joint_max_angle_std", "joint_max_offset_std", "joint_max_residual", "joint_drift"):
            v = float(getattr(self, name))
            if not (math.isfinite(v) and v > 0.0):
                raise ValueError(f"{name} must be a positive number, got {getattr(self, name)!r}")
            object.__setattr__(self, name, v)
        if self.joint_drift > 1.0:
            raise ValueError(f"joint_drift must be at most 1 m/√s, got {self.joint_drift!r}")
        if self.contact_point == "line-fit" and not any(self.noise.force_std + self.noise.moment_std):
            raise ValueError("contact_point='line-fit' needs a sensor noise model (noise is all zero)")
        if int(self.joint_iterations) < 1:
            raise ValueError(f"joint_iterations must be at least 1, got {self.joint_iterations!r}")
        object.__setattr__(self, "joint_iterations", int(self.joint_iterations))
        if self.tare_method not in TARE_METHODS:
            raise ValueError(f"tare_method must be one of {', '.join(TARE_METHODS)}, got {self.tare_method!r}")
        v = float(self.drift_time_constant)
        if not (math.isfinite(v) and v > 0.0):
            raise ValueError(f"drift_time_constant must be a positive number of s, got {self.drift_time_constant!r}")
        object.__setattr__(self, "drift_time_constant", v)
        object.__setattr__(self, "track_drift", bool(self.track_drift))
        for name in ("contact_threshold", "stall_time", "h_sigmas", "h_min", "tare_duration", "contact_hysteresis",
                     "contact_min_duration", "significance_window", "evidence_model_std",
                     "unconfirmed_model_std"):  # fmt: skip
            v = float(getattr(self, name))
            if not (math.isfinite(v) and v >= 0.0):
                raise ValueError(f"{name} must be a non-negative number, got {getattr(self, name)!r}")
            object.__setattr__(self, name, v)
        for name in ("evidence_window", "evidence_max_angle_std", "excitation_ratio", "excitation_min",
                     "evidence_reset_distance"):  # fmt: skip
            v = float(getattr(self, name))
            if not (math.isfinite(v) and v > 0.0):
                raise ValueError(f"{name} must be a positive number, got {getattr(self, name)!r}")
            object.__setattr__(self, name, v)
        enter, leave = (float(v) for v in self.area_ratio)
        if not (0.0 < leave <= enter <= 1.0):
            raise ValueError(f"area_ratio must be (enter, leave) with 0 < leave <= enter <= 1, got {self.area_ratio!r}")
        object.__setattr__(self, "area_ratio", (enter, leave))
        try:
            rocked = tuple((float(a), float(b)) for a, b in self.rocked)
        except (TypeError, ValueError):
            raise ValueError(f"rocked must be (start, end) pairs of times in s, got {self.rocked!r}") from None
        for a, b in rocked:
            if not (math.isfinite(a) and math.isfinite(b) and a < b):
                raise ValueError(f"rocked intervals must be finite with start < end, got ({a!r}, {b!r})")
        object.__setattr__(self, "rocked", rocked)
        v = float(self.area_share)
        if not (0.0 < v < 1.0):
            raise ValueError(f"area_share must be a share between 0 and 1 (exclusive), got {self.area_share!r}")
        object.__setattr__(self, "area_share", v)
        object.__setattr__(self, "line_evidence", bool(self.line_evidence))
        object.__setattr__(self, "noise_from_tare", bool(self.noise_from_tare))
        if self.noise_from_tare and (self.bias is not None or self.tare_duration <= 0.0):
            raise ValueError(
                "noise_from_tare needs a tare to measure the noise from: tare_duration > 0 (--tare-duration) and no "
                "bias given (--bias)"
            )
        if int(self.fallback_samples) < 1:
            raise ValueError(f"fallback_samples must be at least 1, got {self.fallback_samples!r}")
        if self.bias is not None:
            b = np.asarray(self.bias, dtype=float)
            if b.shape != (6,) or not np.all(np.isfinite(b)):
                raise ValueError(f"bias must be 6 finite numbers (N, N·m), got {self.bias!r}")
            object.__setattr__(self, "bias", tuple(float(v) for v in b))
        if self.lowpass_hz is not None and self.sample_rate is not None:
            lowpass_sos(self.lowpass_hz, self.sample_rate, self.lowpass_order)  # validates




_dataclass_init = EstimatorConfig.__init__


def _init(self, *args, latch_window=None, **kwargs):
    # ``latch_window`` is the former name of ``latch_force_range`` (a force range, not a time
    # window like ``joint_window``); given, it wins (dataclasses.replace passes both)
    if latch_window is not None:
        kwargs["latch_force_range"] = latch_window
    _dataclass_init(self, *args, **kwargs)


_init.__doc__ = _dataclass_init.__doc__
_init.__signature__ = inspect.signature(_dataclass_init)
EstimatorConfig.__init__ = _init
EstimatorConfig.latch_window = property(
    lambda self: self.latch_force_range, doc="Former name of :attr:`latch_force_range`, N."
)
