"""Settings of the estimator (:class:`EstimatorConfig`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.core._xp import NP
from softtip.core.depth import MURAKAMI2006_DEPTH, DepthLaw
from softtip.core.filtering import lowpass_sos
from softtip.core.noise import NANO17, SensorNoise, line_threshold_kernel
from softtip.core.units import KGF
from softtip.estimator.settings import Setting, check_value, setting, settings_of

__all__ = ["CONTACT_POINT_MODES", "DEPTH_MODES", "NOISE_FROM_TARE", "TARE_METHODS", "EstimatorConfig"]

#: Values of :attr:`EstimatorConfig.contact_point`.
CONTACT_POINT_MODES = ("latch", "track", "line-fit")
#: Values of :attr:`EstimatorConfig.tare_method`.
TARE_METHODS = ("robust", "median", "mean")
#: ``noise_from_tare``: raise the noise model to what the tare shows, replace it, or keep it
NOISE_FROM_TARE = ("auto", "on", "off")
#: Values of :attr:`EstimatorConfig.depth_compensation`.
DEPTH_MODES = ("auto", "online", "law", "off")


@dataclass(frozen=True)
class EstimatorConfig:
    """Settings of the pipeline. SI units.

    Each field carries its :class:`~softtip.estimator.settings.Setting` (unit, range, help) in
    its metadata: the ``softtip`` options (``--`` + the name, ``_`` → ``-``) and the ROS node's
    parameters (the name) are made from them.

    Parameters
    ----------
    contact_point : {"latch", "track", "line-fit"}
        How the contact point is obtained (module docstring). ``"line-fit"``: the estimate of
        the line's angle and offset over a sliding window (its settings have the ``line_fit_``
        prefix; its output columns, for now, the ``joint_`` one).
    contact_threshold : float
        N; in contact while ``|f|`` (tared, filtered) is at least this, and at least 4.5
        standard deviations ``σ_f`` of the noise of ``|f|`` (the root sum of squares of the
        force noise model, after the filter; :data:`~softtip.estimator.contact.ONSET_FLOOR`,
        about what the default is for the Nano17 preset): with a noisier sensor, a threshold
        inside its noise would start contacts on noise alone.
    latch_window : (float, float)
        N; the light-force range ``|f|`` must lie in for a sample to be latched (default
        0.2–0.5 kgf; the papers' "window" of force).
    stall_time : float
        s; the first rise ends when ``|f|`` has set no new maximum for this long.
    fallback_samples : int
        When the rise has no sample in the window: the least number of soft-finger solutions
        averaged (weighted by ``|f|²``) for the latch, the rise's and those after it.
    noise : SensorNoise
        Standard deviations of the unfiltered sensor noise: the model the tare's samples are
        checked against, and the one in use unless the tare measures another
        (``noise_from_tare``).
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
        m; re-latch when, with the latch held and ``|f|`` inside ``latch_window``, the
        soft-finger solution lies farther than this from the latched point. ``None``
        (default, the papers'): only on contact loss. A few mm (e.g. 3 mm) is beyond the
        soft-finger bias of the papers' line contacts at light force (≈ ``|h| / |f|`` ≤ 1 mm).
    skin_law : DepthLaw or None
        Skin law of the depth compensation (:mod:`softtip.core.depth`): the fixed law of
        ``depth_compensation="law"``, the prior of ``"online"``. ``None`` (default): the
        fingertip's own (:func:`softtip.estimator.depth.tip_depth_law`: the murakami2006
        preset and any fingertip file with a ``skin_thickness``).
    depth_compensation : {"auto", "online", "law", "off"}
        ``online``: the depth learnt per contact from the data, the law its prior
        (:mod:`softtip.estimator.depth`); ``law``: the law's depth at the normal force
        (fixed); ``off``: the papers' undeformed contact point. ``auto`` (default):
        ``online`` in ``latch`` mode when there is a law (``skin_law`` or the fingertip's),
        else ``off``; in ``track`` and ``line-fit`` mode ``law`` when ``skin_law`` is given, else
        ``off``.
    depth_window : float
        s; sliding window of the online depth (default 1 s).
    depth_prior_std : float
        Standard deviation of the prior depth factor (mean 1), relative (default 0.5: one law
        does not fit every object; a thin plate sinks about 1.5 times deeper than a round stick).
    depth_drift : float
        1/√s; how fast the held factor of a contact ages (default 0.02/√s): the factor held
        is the window with the smallest ``variance + depth_drift² · age``.
    line_fit_window : float
        s; length of the sliding window of ``line-fit`` mode (default 1 s: 50 samples at the
        papers' 50 Hz).
    line_fit_max_angle_std, line_fit_max_offset_std : float
        ``line-fit`` mode accepts a window when the standard deviations of its line angle (rad,
        default 2°) and of its offset across the line (m, default 0.2 mm) are at most these.
    line_fit_max_residual : float
        ... and the RMS residual of its fit is at most this many noise standard deviations.
    line_fit_drift : float
        m/√s; how fast the contact may wander unseen: the point held is the accepted window
        with the smallest ``offset_std² + line_fit_drift² · age`` (default 0.03 mm/√s), so a
        precise window is kept over later, weaker ones, but not for ever (positive, at most 1).
    line_fit_iterations : int
        Gauss–Newton steps of each window's solve.
    tare_method : {"robust", "median", "mean"}
        How the tare samples make the bias: ``robust`` (default), the mean of the samples that
        are not spikes (farther than 8 standard deviations from the median; the plain mean
        when there is none); ``median``, per component; ``mean``, of all samples (a −20 N
        spike among ten samples moves it by 2 N).
    contact_hysteresis : float
        Contact starts at ``|f| ≥ on``, ``on = max(contact_threshold, 4.5 σ_f)``, and ends below
        the release threshold ``max(on − contact_hysteresis · σ_f, min(on, 2.5 σ_f))``, with
        ``σ_f`` the noise of ``|f|`` (root sum of squares of the force noise model, after the
        filter; an untouched sensor's ``|f|`` is below ``2.5 σ_f`` 99.97 % of the time); 0 for
        a single threshold.
    min_contact_duration : float
        s; a contact is reported once ``|f|`` has stayed above the release threshold for this
        long since it first reached ``contact_threshold``, each sample counting for its
        sampling interval (default 5 ms: at once at 50 Hz, five samples at 1 kHz; 0: at
        once). A spike shorter than this is not a contact.
    drift_time_constant : float
        s; while untouched (no contact pending or held) the bias is tracked by an exponential moving average with this time constant (default 10 s: a
        drift of r N/s is followed with a lag of r · 10 s; a touch that builds up slower than
        that is taken for drift).
    drift_tracking : bool
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
        show ``h`` spread over both tangent axes (the ``enter`` test of ``area_ratio``; default
        0.25: a sustained spread, at the default window 0.5 s of it; a transient spread while a
        new rock begins, when the window holds the end of one excitation and the start of the
        next, does not make an area), and for one ``evidence_window`` after the last sample
        whose window read it, unless a window confirms a line by its load (the load turned about
        two axes while ``h`` stayed on one; a stated ``rocked`` window does not overturn it): the
        window after an area reading holds the two-axis spread sliding out, often one rocking
        axis only, which a plane gives as a line does. A window later the reading is the current
        window's again: a transient spread cannot lock an area for the rest of the contact. Set on the
        benchmarks' rocked grasps on both contact models and checked on the held-out ones (a
        stiffer, smaller tip, twice the noise at 1 kHz, 7 kHz): from 0.35, the rocked planes read
        ``line`` on none of their samples where they read up to 7 %, the 15 mm plates on up to 12 %
        where they read up to 20 %, while the rocked thin lines' shares stay within 3 points.
        Keeping the area a window brought the rocked 15 mm plates and planes to ``line`` on none
        of their samples on both contact models at the default settings, on the stiffer tip and
        at 7 kHz, where they read it on up to 42 % of a grasp's samples before (while the window
        held one rocking axis after two); at three times the noise at 1 kHz Drake's 15 mm plate at
        −35° still reads it on 17 %. The 10 mm plate on Drake's contact, whose wrench is a thin
        line's, reads ``line`` throughout at the default settings.
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
        rad; the model error of a direction from a window whose load turned about two axes
        (a window that confirms the line from the load, not only by ``rocked``), which no
        window shows, added in quadrature to its standard deviation (default 0.4°). The axis of ``h``'s variation turns a little
        with the pattern of excitation (the contact's small nonlinearity: on the simulator's
        rocked lines, 0.2–1.5° between rocking about two axes in turn and in a figure-eight),
        while the window's own standard deviation shrinks with the number of samples; without
        this term a window at 1–7 kHz claims a precision the physics does not give.
    unconfirmed_model_std : float
        rad; model error of a line direction taken from the sample's own ``h`` where no
        window whose load turned about two axes confirmed the line (``h`` held after one
        tilt, as in the papers' grasp), and of a confirming window that saw one axis, held for
        the samples after it, added in quadrature to the sample's standard
        deviation (default 5°). The line's small resistance to rolling about its own edge
        follows the same excitation and turns the axis by an amount no window of it shows, and
        that amount depends on the object and the skin: in the papers' single tilt on softtip's
        Winkler skin it grows with the object's bluntness and as the line turns from across the
        joint axis toward it (median errors 1.5–1.8° with the line across the joint axis; 45°
        from it 2.2–2.9° on 1–2 mm plates and up to 10.1° on a 120° wedge), on Drake's
        hydroelastic contact it is 1.5–3.2° up to 60° from across for every object. Set on the
        Winkler skin's single tilts at the benchmarks' four line angles (RMS error / standard
        deviation at most 1.5 per object group there) and checked on Drake, where the
        single tilts are conservative (0.45–0.59) and the friction loads within 0.78–1.22; no
        value suits every group of both (docs/benchmarks/two-physics.md, "the one-axis model
        errors"). A bound more than a calibration; 0: the noise only. Not applied with
        ``line_evidence`` off (the papers' behaviour).
    window_model_std : float
        rad; model error of a line direction from a window in which ``h`` varied along one
        axis (its principal axis) while the load did not turn about two (a rock about one
        axis; every rocked line on a frictionless round skin, whose load cannot show the
        second axis), added in quadrature to the window's standard deviation (default 2°).
        Measured apart from ``unconfirmed_model_std``: the rocked thin lines are 0.6°
        (softtip's Winkler skin) and 1.2° (Drake's hydroelastic contact) off in the median,
        the held ``h`` of the papers' single tilt up to 7.5° on a blunt wedge. Set where every
        rocked line group of both physics lies within RMS error / standard deviation 0.7–1.5
        or on its conservative side (Drake 0.97, Winkler 0.61–0.74), and checked on a stiffer,
        smaller tip, at twice the noise and at 7 kHz, no group above 1.5
        (docs/benchmarks/two-physics.md, "the one-axis model errors"). Not applied with
        ``line_evidence`` off.
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
    noise_from_tare : {"auto", "on", "off"}
        Measure the noise from the tare: the standard deviation of each axis over the tare's
        samples (spikes left out), used for everything after the tare (thresholds, every
        reported standard deviation). The presets are about one resolution count, not this
        sensor's noise, and a model that is too small makes noise look like signal: the
        evidence window then reads the noise's spread as an ``area``.

        ``"auto"`` (default): each axis's model is raised to what the tare shows, never
        lowered below ``noise`` (a model given larger than the sensor's noise, for vibration
        say, is kept), where the tare has at least
        :data:`~softtip.estimator.tare.RAISE_MIN_SAMPLES` samples (spikes left out: the
        default 0.2 s from 50 Hz on) and does not look touched (an axis whose samples are all
        alike raises nothing, a tare with a NaN sample nothing at all); otherwise ``noise`` is
        used as given, without a warning (no tare, a given ``bias``, a shorter tare). A tare
        that varies more than :data:`~softtip.estimator.tare.TOUCHED_RATIO` times the model
        looks touched only if it varies slowly next to the sample period, as a press does;
        one that varies from one sample to the next as independent noise does
        (:data:`~softtip.estimator.tare.WHITE_RATIO`) is a sensor that much noisier, measured
        from :data:`~softtip.estimator.tare.NOISE_MIN_SAMPLES` samples or more (spikes left
        out), with a warning that says so; from fewer it is kept, and the warning says to tare
        longer.
        ``"on"``: the measured model replaces ``noise`` on every axis, also below it (its
        standard deviations known to about 13 % from 30 samples); needs a tare
        (``tare_duration`` > 0, no ``bias``); with fewer samples, with a tare that looks
        touched, or on an axis that did not vary at all, ``noise`` is kept and a warning says
        so; an axis read in steps of ``q`` is taken as at least ``q / √12`` (its rounding).
        ``"off"``: ``noise`` as given. ``True`` and ``False`` are taken as ``"on"`` and
        ``"off"``.
    """

    # -- contact: when the fingertip is touched ------------------------------------------------
    contact_point: Literal["latch", "track", "line-fit"] = setting(
        "latch", "latch: measure the contact point in the light-force window at the start of the grasp and hold it "
        "(the papers'); track: the soft-finger solution every sample (h is then zero: no directions); line-fit: latch, "
        "then move the point across the line to where a sliding window (--line-fit-window) fits the line-contact "
        "model (flagged line_fit_fallback until one does).", choices=CONTACT_POINT_MODES, group="contact")
    contact_threshold: float = setting(
        0.05, "In contact while |f| is at least this (and 4.5 standard deviations of its noise).", unit="N", low=0.0,
        cli_unit="force", metavar="FORCE",
        group="contact")
    contact_hysteresis: float = setting(
        3.0, "Contact ends below --contact-threshold minus this many standard deviations of the noise of |f| (after "
        "the low-pass), but not below the smaller of the threshold and 2.5 of them; 0: one threshold.",
        unit="noise standard deviations", low=0.0,
        metavar="SIGMAS", group="contact")
    min_contact_duration: float = setting(
        0.005, "A contact is reported once |f| has stayed above the release threshold this long, each sample counting "
        "for its sampling interval (a shorter spike is no contact).", unit="s", low=0.0, metavar="S", group="contact")
    # -- tare and drift ----------------------------------------------------------------------------
    tare_duration: float = setting(
        0.2, "Take the first S seconds (fingertip untouched) as the sensor bias; 0 if the wrench is already tared.",
        unit="s", low=0.0, metavar="S", group="tare")
    tare_method: Literal["robust", "median", "mean"] = setting(
        "robust", "How the tare samples make the bias: robust (the mean of the samples that are not spikes), median, "
        "or mean (of all: a spike moves it).", choices=TARE_METHODS, group="tare")
    bias: tuple[float, ...] | None = setting(
        None, "Sensor bias to subtract instead of taring (N, N·m).", kind="composite", options=("--bias",),
        group="tare")
    drift_time_constant: float = setting(
        10.0, "While untouched, follow the sensor's bias drift with a moving average of this time constant.",
        unit="s", low=0.0, low_open=True, metavar="S", group="tare")
    drift_tracking: bool = setting(
        True, "Subtract the drift followed while untouched (off: report it only, the papers').",
        group="tare")
    # -- filter and noise --------------------------------------------------------------------------
    lowpass_hz: float | None = setting(
        None, "Causal Butterworth low-pass cutoff (default: no filter).", unit="Hz", low=0.0, low_open=True,
        metavar="HZ", group="filter")
    lowpass_order: int = setting(2, "Order of the low-pass Butterworth filter.", low=1, metavar="N", group="filter")
    sample_rate: float | None = setting(
        None, "Sample rate of the input, needed with the low-pass (the commands take it from the data).", unit="Hz",
        low=0.0, low_open=True, cli=False, group="filter")
    noise: SensorNoise = setting(
        NANO17, "Standard deviations of the unfiltered sensor noise per axis (N, N·m).", kind="composite",
        options=("--sensor", "--force-noise", "--moment-noise"), group="noise")
    noise_from_tare: Literal["auto", "on", "off"] = setting(
        "auto", "Measure the noise from the tare's samples (each axis's standard deviation): auto raises "
        "--force-noise/--moment-noise (or the --sensor preset) to what a tare of at least 10 samples shows (30 "
        "beyond 5 times the model, where a spread that changes slowly reads as a touch) and keeps them otherwise; "
        "on replaces them by it (at least 30 samples, --tare-duration 0.6 at 50 Hz); off keeps them as given.",
        choices=NOISE_FROM_TARE, group="noise")
    h_sigmas: float = setting(
        3.0, "|h| is significant (a line) above this many of its noise standard deviations (or --h-min).",
        unit="noise standard deviations", low=0.0, metavar="SIGMAS", group="noise")
    h_min: float = setting(
        5e-4, "Smallest |h| reported as a line contact.", unit="N·m", low=0.0, cli_unit="N·mm", metavar="N·mm",
        group="noise")
    # -- latch: the papers' contact point -----------------------------------------------------------
    latch_window: tuple[float, float] = setting(
        (0.2 * KGF, 0.5 * KGF), "Light-force window for latching the contact point.",
        unit="N", parts=(Setting("", unit="N", low=0.0, cli_unit="force", metavar="LOW"),
                         Setting("", unit="N", low=0.0, cli_unit="force", metavar="HIGH")),
        cli_default="0.2kgf 0.5kgf", metavar="LOW HIGH", group="latch")  # fmt: skip
    stall_time: float = setting(
        0.1, "The first rise ends when |f| has set no new maximum for this long.", unit="s", low=0.0, metavar="S",
        group="latch")
    fallback_samples: int = setting(
        5, "When the rise has no sample in the window, its soft-finger solutions are averaged for the latch, weighted by "
        "|f|², and at least this many (the samples after the rise too).", low=1,
        metavar="N", group="latch")
    relatch_distance: float | None = setting(
        None, "Latch again when, at light force, the soft-finger contact point moves farther than this from the "
        "latched one. Default: only when contact is lost and regained, the papers'.", unit="m", low=0.0, low_open=True, cli_unit="mm", metavar="LENGTH", group="latch")
    # -- line-fit: the point and line over a sliding window -------------------------------------------
    line_fit_window: float = setting(
        1.0, "Sliding window of --contact-point line-fit.", unit="s", low=0.0, low_open=True, metavar="S",
        group="line-fit")
    line_fit_max_angle_std: float = setting(
        math.radians(2.0), "--contact-point line-fit accepts a window when the standard deviation of its line angle "
        "is at most this ...", unit="rad", low=0.0, low_open=True, cli_unit="deg", metavar="DEG", group="line-fit")
    line_fit_max_offset_std: float = setting(
        2e-4, "... and that of its offset across the line at most this ...", unit="m",
        low=0.0, low_open=True, cli_unit="mm", metavar="LENGTH", group="line-fit")
    line_fit_max_residual: float = setting(
        3.0, "... and the RMS residual of its fit at most this many noise standard deviations.",
        unit="noise standard deviations", low=0.0, low_open=True, metavar="SIGMAS", group="line-fit")
    line_fit_drift: float = setting(
        3e-5, "How fast the contact may wander unseen: the point held is the accepted window with the smallest "
        "offset_std² + drift² · age.", unit="m/√s", low=0.0, high=1.0, low_open=True, cli_unit="mm/√s",
        metavar="MM/√S", group="line-fit")
    line_fit_iterations: int = setting(
        2, "Gauss–Newton steps of each window's solve.", low=1, metavar="N", group="line-fit")
    # -- depth: friction inside the skin ---------------------------------------------------------------
    depth_compensation: Literal["auto", "online", "law", "off"] = setting(
        "auto", "Take the moment about the point inside the skin where friction acts. online: its depth learnt per "
        "contact from the data, the skin law (--skin-law) the prior; law: the skin law's depth as it is; off: the "
        "papers' method; auto: online in latch mode when the fingertip gives a skin (the murakami2006 preset, a file "
        "with skin_thickness), else off.", choices=DEPTH_MODES, group="depth")
    skin_law: DepthLaw | None = setting(
        None, "Skin law of the depth compensation: normal force = K·depth^P (N, m), depth at most MAX_DEPTH "
        "(default: the fingertip's skin; else the murakami2006 skin, "
        f"{MURAKAMI2006_DEPTH.stiffness:g} {MURAKAMI2006_DEPTH.exponent:g} {MURAKAMI2006_DEPTH.max_depth * 1e3:g}mm).",
        parts=(Setting("", unit="N/m^P", low=0.0, low_open=True, metavar="K"),
               Setting("", low=0.0, low_open=True, metavar="P"),
               Setting("", unit="m", low=0.0, low_open=True, cli_unit="mm", metavar="MAX_DEPTH")),
        make=DepthLaw, metavar="K P MAX_DEPTH", group="depth")  # fmt: skip
    depth_window: float = setting(
        1.0, "Sliding window of the online depth.", unit="s", low=0.0, low_open=True, metavar="S", group="depth")
    depth_prior_std: float = setting(
        0.5, "Standard deviation of the prior depth factor (mean 1), relative.", low=0.0, low_open=True,
        metavar="STD", group="depth")
    depth_drift: float = setting(
        0.02, "How fast the held depth factor of a contact ages.", unit="1/√s", low=0.0, low_open=True,
        metavar="RATE", group="depth")
    # -- evidence: line or area ------------------------------------------------------------------------
    line_evidence: bool = setting(
        True, "Tell a line from an area over a sliding window (state area while the window shows h spread over both "
        "tangent axes, and one window after; line_evidence confirmed once the contact was excited about two tangent axes, by the load or "
        "--rocked, and h stayed on one, else unconfirmed; the direction from the window wherever h varied along one "
        "axis); off: the papers' per-sample line/point.", group="evidence")
    evidence_window: float = setting(
        2.0, "Sliding window of the line evidence.", unit="s", low=0.0, low_open=True, metavar="S", group="evidence")
    significance_window: float = setting(
        0.015, "|h| turns significant (line) when most samples of the last S seconds are above the line threshold, "
        "and not when most are below 2/3 of it (0, or a sample period longer than S: each sample alone, the papers').",
        unit="s", low=0.0, metavar="S", group="evidence")
    area_ratio: tuple[float, float] = setting(
        (0.2, 0.1), "area when the smaller/larger eigenvalue ratio of h's window covariance (noise removed) reaches "
        "ENTER; a confirmed line again only below LEAVE.",
        parts=(Setting("", unit="(eigenvalue ratio)", low=0.0, low_open=True, metavar="ENTER"),
               Setting("", unit="(eigenvalue ratio)", low=0.0, low_open=True, metavar="LEAVE")),
        metavar="ENTER LEAVE", group="evidence")  # fmt: skip
    area_share: float = setting(
        0.25, "area while more than this share of the evidence window's samples show h spread over both tangent axes, "
        "and one window after (unless the load confirms a line).", unit="(share of the window)", low=0.0,
        high=1.0, low_open=True, high_open=True, metavar="SHARE", group="evidence")
    rocked: tuple[tuple[float, float], ...] = setting(
        (), "The object was rocked about two tangent axes from START to END (the log's time; repeat for more): a "
        "window wholly inside counts as excited about two axes, so h on one axis there confirms a line (for a skin "
        "on which the load cannot show it, manual §3.5).", kind="tuples",
        parts=(Setting("", unit="s", metavar="START"), Setting("", unit="s", metavar="END")),
        metavar="START END", group="evidence")  # fmt: skip
    excitation_ratio: float = setting(
        0.5, "Excited about two tangent axes when the tangential load's window covariance has its smaller eigenvalue "
        "beyond the noise and at least this times the larger ...", unit="(eigenvalue ratio)", low=0.0,
        low_open=True, metavar="RATIO", group="evidence")
    excitation_min: float = setting(
        0.01, "... and at least this squared (the load's standard deviation about its weaker axis).", unit="N",
        low=0.0, low_open=True, metavar="N", group="evidence")
    evidence_max_angle_std: float = setting(
        math.radians(10.0), "A window's line direction is used only when its standard deviation is at most this.",
        unit="rad", low=0.0, low_open=True, cli_unit="deg", metavar="DEG", group="evidence")
    evidence_model_std: float = setting(
        math.radians(0.4), "Model error of the line direction of a window whose load turned about two axes (what no "
        "window shows), added in quadrature to its standard deviation (0: none).", unit="rad", low=0.0, cli_unit="deg", metavar="DEG", group="evidence")
    unconfirmed_model_std: float = setting(
        math.radians(5.0), "Model error of a line direction from a held h (one tilt: its rolling bias), added in "
        "quadrature to its standard deviation (0: none).", unit="rad", low=0.0, cli_unit="deg",
        metavar="DEG", group="evidence")
    window_model_std: float = setting(
        math.radians(2.0), "Model error of a line direction from a window in which h varied along one axis and the "
        "load did not turn about two (a rock about one axis), added in quadrature to its standard deviation "
        "(0: none).", unit="rad", low=0.0,
        cli_unit="deg", metavar="DEG", group="evidence")
    evidence_reset_distance: float = setting(
        1e-3, "The line evidence starts afresh when the contact point moves farther than this.", unit="m", low=0.0, low_open=True, cli_unit="mm", metavar="LENGTH", group="evidence")

    def line_threshold(self, h_std: ArrayLike) -> NDArray[np.float64]:
        """The ``|h|`` above which a contact is a line: ``max(h_sigmas · h_std, h_min)``
        (:func:`~softtip.core.noise.line_threshold_kernel`).

        Parameters
        ----------
        h_std : array of shape (...,), N·m
            The noise level of ``h`` (:attr:`Estimates.h_std`).

        Returns
        -------
        array of shape (...,), N·m
        """
        return line_threshold_kernel(np.asarray(h_std, dtype=float), self.h_sigmas, self.h_min, NP)

    def __post_init__(self) -> None:
        if isinstance(self.noise_from_tare, (bool, np.bool_)):  # the switch it was
            object.__setattr__(self, "noise_from_tare", "on" if self.noise_from_tare else "off")
        # each value against its Setting (field metadata): kind, range, choices
        for s in settings_of(EstimatorConfig):
            object.__setattr__(self, s.name, check_value(s, getattr(self, s.name)))
        # what one field's range cannot say: the relations between values
        if self.skin_law is not None and not isinstance(self.skin_law, DepthLaw):
            raise ValueError(f"skin_law must be a softtip.core.depth.DepthLaw or None, got {self.skin_law!r}")
        try:
            lo, hi = (float(v) for v in self.latch_window)
        except (TypeError, ValueError):
            lo = hi = math.nan
        if not (0.0 <= lo < hi < math.inf):
            raise ValueError(f"latch_window must be (low, high) with 0 <= low < high, in N; got {self.latch_window!r}")
        object.__setattr__(self, "latch_window", (lo, hi))
        if self.contact_point == "line-fit" and not any(self.noise.force_std + self.noise.moment_std):
            raise ValueError("contact_point='line-fit' needs a sensor noise model (noise is all zero)")
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
        if self.noise_from_tare == "on" and (self.bias is not None or self.tare_duration <= 0.0):
            raise ValueError(
                "noise_from_tare='on' needs a tare to measure the noise from: tare_duration > 0 (--tare-duration) and "
                "no bias given (--bias); 'auto' measures it only where there is one"
            )
        if self.bias is not None:
            b = np.asarray(self.bias, dtype=float)
            if b.shape != (6,) or not np.all(np.isfinite(b)):
                raise ValueError(f"bias must be 6 finite numbers (N, N·m), got {self.bias!r}")
            object.__setattr__(self, "bias", tuple(float(v) for v in b))
        if self.lowpass_hz is not None and self.sample_rate is not None:
            lowpass_sos(self.lowpass_hz, self.sample_rate, self.lowpass_order)  # validates
