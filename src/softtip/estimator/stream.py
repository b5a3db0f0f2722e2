"""The estimator one sample at a time, for live use: :class:`Estimator`.

Each stage is the stream form of the batch stage beside it (:mod:`~softtip.estimator.tare`,
:mod:`~softtip.estimator.latch`, :mod:`~softtip.estimator.line_fit`,
:mod:`~softtip.estimator.measure`), so :class:`Estimator` and
:func:`~softtip.estimator.batch.estimate` give the same bits. Each stateful stage (contact
tracking, the low-pass filter, the latch, the line fit, the depth, the line evidence) is one
step function over a state record, called here once per sample and by the batch in a compiled
loop (:mod:`softtip.core._jit`). A located sample's depth, measurement and line evidence are
one call, :func:`~softtip.estimator.pipeline.located_step`, the one the batch's compiled tail
loop makes per sample. Where the steps are compiled (``latch`` mode without the line fit, or
``track`` mode; a skin law of exponent 2 or none; not while the first contact after a tare may
still be a release), every sample in contact but a contact's onset is one compiled call of those
steps in this order, :func:`~softtip.estimator.pipeline.sample_step`: the contact tracking's
step, then the latch's keep test and the located step at a held latch (nearly every sample of a
contact) or, on a closed-form fingertip, the soft-finger solution (the shape's compiled kernel),
the latch's step and the located step at the point it gives (the first rise, a re-latch test,
``track`` mode). The onset, and every sample of another configuration, goes through the stages
in turn (the soft-finger solution compiled on a closed-form fingertip:
:func:`~softtip.estimator.pipeline.soft_finger_function`).
"""

from __future__ import annotations

import math
import warnings
from math import isfinite, sqrt

import numpy as np
from numpy.typing import ArrayLike

from softtip.core._blocks import TIME_EDGE
from softtip.core._jit import use_numba
from softtip.core.filtering import SosStream, lowpass_sos
from softtip.core.fingertip import Fingertip, load_fingertip
from softtip.core.noise import SensorNoise, noise_variances
from softtip.core.spin import tangent_frame
from softtip.estimator.batch import RATE_CHECK_SAMPLES, implausible_rate, sample_rate_mismatch, time_type_error
from softtip.estimator.config import EstimatorConfig
from softtip.estimator.contact import (
    START_PULL_TIME,
    ContactTracker,
    drift_message,
    started_in_contact_message,
)
from softtip.estimator.depth import RING_COLUMNS, DepthTracker, new_depth_state, resolve_depth
from softtip.estimator.evidence import _EVIDENCE_NAMES, _STATE_NAMES, EvidenceTracker, twist_curvature
from softtip.estimator.floats import PointGeometry
from softtip.estimator.latch import FIX, HELD, LatchTracker
from softtip.estimator.line_fit import LineFitTracker
from softtip.estimator.measure import effective_noise, noise_correlation
from softtip.estimator.pipeline import (
    DEPTH_LAW,
    DEPTH_OFF,
    DEPTH_ONLINE,
    STEP_HELD,
    STEP_NO_POINT,
    STEP_NOT_DONE,
    held_record,
    located_step,
    sample_setup,
    sample_step,
    shape_record,
    soft_finger_function,
)
from softtip.estimator.results import EstimatorWarning, SampleEstimate
from softtip.estimator.tare import StreamTare, TareReport, noise_in_use

__all__ = ["Estimator"]

#: (fingertip class, configuration) pairs whose steps a warm-up loaded in this process: the same
#: pair calls the same compiled steps, so a sensor's Estimator built again skips it.
_WARMED: set = set()
_NAN3 = (math.nan, math.nan, math.nan)
_NAN4 = (math.nan,) * 4
_NAN6 = (math.nan,) * 6
_NO_HELD = np.zeros(0)  # sample_step's held record when no latch is held
_new_estimate = tuple.__new__  # SampleEstimate with every field given, without its __new__'s frame


class Estimator:
    """The estimator of :func:`~softtip.estimate`, one sample at a time (live use).

    Parameters
    ----------
    tip : Fingertip or str
        Fingertip, preset name or TOML path.
    config : EstimatorConfig, optional
        With ``lowpass_hz`` set, ``config.sample_rate`` is required.
    expected_samples : int, optional
        How many samples the stream will see, when known (a replayed log). Below
        :data:`~softtip.core._jit.STEP_MIN_SAMPLES` the steps run as Python unless numba is loaded
        already: loading it and the compiled steps (about 0.7 s of CPU) costs more than they save
        (the same bits either way). None (a sensor): compiled.

    Attributes
    ----------
    repeated_stamps : int
        Samples whose time equalled the previous one's (accepted).
    warnings : list of str
        Warnings so far, as in :attr:`softtip.Estimates.warnings` (each also issued once as
        :class:`~softtip.estimator.results.EstimatorWarning`).
    started_in_contact, drift_alarm : bool
        As in :class:`~softtip.Estimates`, since the last tare.

    Examples
    --------
    >>> from softtip import Estimator, load_example
    >>> log = load_example()
    >>> est = Estimator("murakami2006")
    >>> out = [est.update(t, w) for t, w in zip(log.t, log.wrench)]
    >>> out[-1].state
    'line'
    """

    def __init__(
        self, tip: Fingertip | str = "murakami2006", config: EstimatorConfig | None = None, *,
        expected_samples: int | None = None,
    ):  # fmt: skip
        self._build(tip, config, expected_samples)
        if expected_samples is None and use_numba(None) and (type(self.tip), self.config) not in _WARMED:
            self.warm_up()

    def _build(self, tip: Fingertip | str, config: EstimatorConfig | None, expected_samples: int | None) -> None:
        self._n = expected_samples
        self.tip = load_fingertip(tip)
        self.config = resolve_depth(config or EstimatorConfig(), self.tip)
        cfg = self.config
        self._sos = None
        if cfg.lowpass_hz is not None:
            if cfg.sample_rate is None:
                raise ValueError("streaming with a low-pass filter needs config.sample_rate (Hz)")
            self._sos = lowpass_sos(cfg.lowpass_hz, cfg.sample_rate, cfg.lowpass_order)
        self._track = cfg.contact_point == "track"
        self._tare = StreamTare(cfg)
        # the soft-finger solution of a sample (the latch's first rise, track mode): compiled on a
        # closed-form fingertip, the batch's kernel (softtip.estimator.pipeline.points_run)
        self._latch = LatchTracker(self.tip, cfg, expected_samples=self._n,
                                   soft_finger=soft_finger_function(self.tip, expected_samples))  # fmt: skip
        self._soft = self._latch.soft_finger
        self._contacts = ContactTracker(cfg, effective_noise(cfg.noise, self._sos), expected_samples=self._n)
        self._use_noise(cfg.noise)
        self._measured_noise = False  # a tare replaced the configured noise model
        self.reset()

    def warm_up(self) -> None:
        """Load every compiled step this estimator's configuration calls, now rather than at
        the first contact: a made-up press (a tare, a push at the skin's apex with a tangential
        load and a moment rocked about two axes, a release) through a throwaway estimator of the
        same fingertip and configuration; this estimator's state is untouched.

        numba compiles or loads a step at its first call: at a sensor's first touch that was
        16.5 ms from the disk cache and 6.0 s of compiling the first time after installing,
        while the samples queued up (manual §3.7, "The pipeline"). Built for a sensor
        (``expected_samples`` None) with numba, :class:`Estimator` calls it itself, once per
        process for each fingertip class and configuration.
        """
        cfg = self.config
        rate = cfg.sample_rate or 1000.0
        probe = Estimator.__new__(Estimator)  # built as this one was, without a warm-up of its own
        probe._build(self.tip, cfg, self._n)
        tip = probe.tip
        r = tip.project(tip.apex_hint())
        n = tip.normal(r)
        if not (np.isfinite(r).all() and np.isfinite(n).all()):  # a skin its own projection misses: load at the first touch
            return
        e1, e2 = tangent_frame(n)
        quiet = cfg.tare_duration if cfg.bias is None else 0.0
        t = np.arange(int(math.ceil((quiet + 0.5) * rate))) / rate
        s = np.clip((t - quiet - 0.02) / 0.05, 0.0, 1.0) * (t < quiet + 0.4)  # press, hold, release
        f = 2.0 * s[:, None] * (-n + 0.1 * e1)
        rock = np.sin(2.0 * math.pi * 5.0 * t)[:, None] * e1 + np.cos(2.0 * math.pi * 7.0 * t)[:, None] * e2
        m = np.cross(r, f) + 1e-3 * s[:, None] * rock
        noise = np.concatenate((cfg.noise.force_std, cfg.noise.moment_std))
        w = np.concatenate((f, m), axis=1) + np.random.default_rng(0).normal(size=(len(t), 6)) * noise
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", EstimatorWarning)
            try:
                for ti, wi in zip(t.tolist(), w.tolist()):
                    probe.update(ti, wi)
            except (ValueError, ArithmeticError):  # the made-up press is not this skin's: load at the first touch
                return
        _WARMED.add((type(self.tip), cfg))

    def _use_noise(self, noise: SensorNoise) -> None:
        """Build the stages that depend on the (unfiltered) noise model ``noise``: at the
        start, and after a tare that measured it (``noise_from_tare``), when no contact is
        under way."""
        cfg = self.config
        corr = noise_correlation(self._sos)
        self._noise = effective_noise(noise, self._sos)
        self._evidence = EvidenceTracker(cfg, self._noise, corr, twist_curvature(self.tip), expected_samples=self._n)
        self._line_fit = None
        if cfg.contact_point == "line-fit":
            self._line_fit = LineFitTracker(self.tip, cfg, self._noise, corr, expected_samples=self._n)
        self._contacts.set_noise(self._noise)
        self._var = noise_variances(self._noise)
        self._force_var = self._var[:3]
        self._geo = PointGeometry((math.nan,) * 3, (0.0, 0.0, 1.0), self._var)  # none yet
        self._depth = None if cfg.skin_law is None else DepthTracker(cfg, self._noise, corr, expected_samples=self._n)
        self._located = located_step.function(self._n)
        self._python = self._located is located_step.python
        self._no_depth = (np.zeros(1), new_depth_state(), np.empty((1, RING_COLUMNS)))  # the step's records, unused
        depth = self._depth
        self._depth_mode = DEPTH_OFF if depth is None else DEPTH_ONLINE if depth.online else DEPTH_LAW
        # a sample in contact in one compiled call (contact, latch, located: sample_step) where the
        # stages between are the latch's alone and the skin law is one compiled code computes: a
        # held latch's samples on any fingertip, the others on a closed-form one (its soft-finger
        # solution compiled)
        law = cfg.skin_law
        self._sample = None
        if self._line_fit is None and not self._python and (law is None or law.exponent == 2.0):
            self._sample = sample_step.function(self._n)
        self._setup = sample_setup(self._track, shape_record(self.tip), self._var, law, self._latch.params)
        self._held_rec = _NO_HELD  # sample_step's record of self._geo (a held latch's point)

    @property
    def bias(self) -> tuple[float, ...] | None:
        """The sensor bias subtracted (N, N·m); ``None`` while taring. The tracked drift
        (:attr:`drift`) comes on top."""
        return self._tare.bias

    @property
    def tare_report(self) -> TareReport | None:
        """What the last tare did and its checks; ``None`` while taring."""
        return self._tare.report

    @property
    def drift(self) -> tuple[float, ...]:
        """Bias drift tracked since the last tare (N, N·m)."""
        return self._contacts.drift

    @property
    def contacts(self) -> int:
        """Contacts so far (onsets, each counted once)."""
        return self._contacts.count

    def reset(self) -> None:
        """Forget everything: bias (unless given), filter state, drift, contacts, and a noise
        model a tare measured (the configured one again)."""
        if self._measured_noise:  # a re-tare's model would outlive it where no tare follows
            self._use_noise(self.config.noise)
            self._measured_noise = False
        self._tare.reset()
        self._filter = SosStream(self._sos, expected_samples=self._n) if self._sos is not None else None
        self._contacts.reset()
        self._contacts.count = 0
        self._latch.reset()
        self._t_prev: float | None = None
        self._rate_t: list[float] | None = []  # the first stamps, for the rate checks
        self.repeated_stamps = 0
        self.warnings: list[str] = []
        self._after_tare()

    def tare(self, duration: float | None = None) -> None:
        """Tare again from the next samples (the fingertip untouched), even with a given bias.

        Parameters
        ----------
        duration : float, optional
            s of samples to tare from; default ``config.tare_duration`` (0.2 s when that is 0).
            Those samples are reported as ``none`` (``taring``); the filter, the contact and
            the drift start again, the contact count goes on. The noise model is measured
            again from those samples (``noise_from_tare``: under ``"auto"`` the configured
            model raised to it, or the configured one as it is; under ``"on"`` the measured
            one, or the configured one if they cannot give it, as the warning then says).
        """
        d = (self.config.tare_duration or 0.2) if duration is None else float(duration)
        if not (math.isfinite(d) and d > 0.0):
            raise ValueError(f"tare duration must be a positive number of s, got {duration!r}")
        self._tare.reset(d)
        self._filter = SosStream(self._sos, expected_samples=self._n) if self._sos is not None else None
        self._contacts.reset()
        self._after_tare()

    def _after_tare(self) -> None:
        self.started_in_contact = False
        self._first_contact = 0  # id of the first contact after the tare (0: none yet)
        self._lead = False  # in the first contact after the tare, pulling since its onset
        self._t_pull: float | None = None

    @property
    def drift_alarm(self) -> bool:
        """The tracked drift of the force exceeded the contact threshold since the last tare."""
        return self._contacts.drift_alarm

    def _warn(self, msg: str) -> None:
        self.warnings.append(msg)
        warnings.warn(msg, EstimatorWarning, stacklevel=3)

    def update(self, t: float, wrench: ArrayLike) -> SampleEstimate:
        """Process one raw sample.

        Parameters
        ----------
        t : float
            s; must not go back from call to call (a repeated time is accepted and counted
            in :attr:`repeated_stamps`).
        wrench : array-like, shape (6,)
            Raw ``fx, fy, fz`` (N), ``mx, my, mz`` (N·m).
        """
        try:
            if isinstance(t, (str, bytes)):  # float("12") would take it
                raise TypeError
            t = float(t)
        except (TypeError, ValueError):
            raise time_type_error(t) or ValueError(f"expected t as a number of s, got {t!r}") from None
        try:
            if type(wrench) is np.ndarray:
                w0, w1, w2, w3, w4, w5 = wrench.tolist()
            elif isinstance(wrench, (str, bytes, dict, set)):  # six characters or keys would unpack
                raise TypeError
            else:
                w0, w1, w2, w3, w4, w5 = wrench
            w = [float(w0), float(w1), float(w2), float(w3), float(w4), float(w5)]
        except (TypeError, ValueError):
            w = []
        # one test for the common case: a sum of finite numbers is finite unless it
        # overflows, which the per-component test then tells apart
        if not (len(w) == 6 and isfinite(w[0] + w[1] + w[2] + w[3] + w[4] + w[5] + t)) and not (
            len(w) == 6 and all(isfinite(v) for v in w) and isfinite(t)
        ):
            raise ValueError(f"expected a finite time and 6 finite wrench components, got t={t!r}, wrench={wrench!r}")
        dt = 0.0
        t_prev = self._t_prev
        if t_prev is not None:
            if t < t_prev:
                raise ValueError(f"time must not go back: {t!r} s after {t_prev!r} s")
            if t == t_prev:
                self.repeated_stamps += 1
            dt = t - t_prev
        self._t_prev = t
        if self._rate_t is not None:  # once, after 21 samples: does config.sample_rate fit the stamps? do seconds?
            self._rate_t.append(t)
            if len(self._rate_t) >= RATE_CHECK_SAMPLES:
                for msg in (sample_rate_mismatch(self._rate_t, self.config.sample_rate), implausible_rate(self._rate_t)):
                    if msg:
                        self._warn(msg)
                self._rate_t = None

        tare = self._tare
        bias = tare.bias
        if bias is None:
            bias = tare.update(t, w)
            if bias is None:
                return self._none(t, (math.nan,) * 6, taring=True)
            for msg in tare.report.warnings:
                self._warn(msg)
            if self.config.noise_from_tare != "off":  # the model this tare measured, or the given one again
                self._use_noise(noise_in_use(self.config, tare.report))
                self._measured_noise = True
            if self._filter is not None:  # the tare samples prime the filter, as in the batch
                for b in tare.release():
                    self._filter([v - bb for v, bb in zip(b, bias)])
        x = [w[0] - bias[0], w[1] - bias[1], w[2] - bias[2], w[3] - bias[3], w[4] - bias[4], w[5] - bias[5]]
        if self._filter is not None:
            x = self._filter(x)
        return self._step(t, dt, x)

    def _none(self, t, x, taring=False, pulling=False, relatched=False) -> SampleEstimate:
        nan = math.nan
        cid = self._contacts.contact_id
        if self._lead:
            if cid:
                self._pulled(t, pulling)
            else:  # the first contact ended
                self._lead = False
        return SampleEstimate(
            t, "none", tuple(x), _NAN3, _NAN3, nan, _NAN3, nan, nan, _NAN3, nan, nan, False, False, pulling, taring,
            relatched, nan, nan, nan, nan, nan, False, cid, _NAN6 if taring else self._contacts.drift_before,
        )  # fmt: skip

    def _pulled(self, t: float, pulling: bool) -> None:
        """A sample of the first contact after the tare, still pulling from its onset on: is
        it a release (the tare taken in contact)?"""
        if not pulling:
            self._lead = False
            return
        if self._t_pull is None:
            self._t_pull = t
        if t - self._t_pull >= START_PULL_TIME - TIME_EDGE:
            self._lead = False
            self.started_in_contact = True
            self._warn(started_in_contact_message(self.config))

    def _step(self, t: float, dt: float, x: list[float]) -> SampleEstimate:
        contacts = self._contacts
        alarm = contacts.drift_alarm
        latch = self._latch
        status = STEP_NOT_DONE
        if self._sample is not None and not self._lead:
            dp, ds, dr = self._depth.records() if self._depth_mode == DEPTH_ONLINE else self._no_depth
            c, status, lcode, point, normal, flags, r = self._sample(
                contacts.state, contacts.params, t, dt, *x, self._held_rec if latch.point is self._geo.point else _NO_HELD,
                self._setup, latch.state, self._depth_mode, dp, ds, dr, *self._evidence.ready(),
            )  # fmt: skip
            x, code = contacts.apply(c)
        else:
            x, code = contacts.step(t, dt, x)
        if contacts.drift_alarm and not alarm:
            self._warn(drift_message(self.config, t))
        if status == STEP_HELD:
            return self._estimate(t, x, latch.point, self._geo.normal, r, True, latch.fallback, False)
        if status != STEP_NOT_DONE:
            return self._risen(t, x, status, lcode, point, normal, flags, r)
        return self._after_contact(t, x, code)

    def _risen(self, t: float, x: tuple[float, ...], status: int, lcode: int, point: tuple[float, float, float],
               normal: tuple[float, float, float], flags: tuple[bool, ...], r: tuple) -> SampleEstimate:  # fmt: skip
        """A sample :func:`~softtip.estimator.pipeline.sample_step` did at a point that is not a
        held latch's: what the latch keeps of it (:class:`~softtip.estimator.latch.LatchTracker`'s
        point, as its step keeps it), then the estimate."""
        latched, fallback, relatched, begin = flags
        if not self._track:
            latch = self._latch
            point = latch.keep(lcode, point, fallback, begin)
            if lcode == FIX or (lcode == HELD and point is not self._geo.point):
                # a latch held from here: its geometry and sample_step's record
                geo = self._geo = PointGeometry.on_tip(self.tip, point, self._var)
                self._held_rec = held_record(latch.window, geo)
        if status == STEP_NO_POINT:
            return self._none(t, x, pulling=True, relatched=relatched)
        return self._estimate(t, x, point, normal, r, latched, fallback, relatched)

    def _after_contact(self, t: float, x: tuple[float, ...], code: int) -> SampleEstimate:
        """A sample after the contact tracking's step (``code``: 0 none, 1 in contact, 2 onset)."""
        contacts = self._contacts
        if not code:
            return self._none(t, x)
        if code == 2 and not self._first_contact:
            self._first_contact = contacts.contact_id
            self._lead = self._tare.report.source == "tare"
        fx, fy, fz, mx, my, mz = x
        f_norm = sqrt(fx * fx + fy * fy + fz * fz)
        depth = self._depth
        if depth is not None and code == 2:
            depth.start_contact()

        tip = self.tip
        latched = fallback = relatched = joint_fb = False
        j0 = j1 = j2 = j3 = math.nan
        if self._track:
            if code == 2:
                self._evidence.start_segment()
            rx, ry, rz, nx, ny, nz, _, valid = self._soft(*x)
            point, normal = (rx, ry, rz), (nx, ny, nz)
            if not valid:
                if depth is not None and depth.online:  # as the batch (pipeline.tail_run)
                    if isfinite(rx) and isfinite(ry) and isfinite(rz):  # a point, not a valid solution: it learns
                        depth.step(t, x, point, normal)
                    else:
                        depth.gap()
                return self._none(t, x, pulling=True)
        else:
            if code == 2 and self._line_fit is not None:
                self._line_fit.start_contact()
            point, latched, fallback, relatched, begin, sc = self._latch.step(t, f_norm, x, None, code == 2)
            if begin:  # a new first rise: at contact onset, and at a re-latch
                self._evidence.start_segment()
                if self._line_fit is not None:
                    self._line_fit.start_segment(t)
            if self._line_fit is not None:
                point, (j0, j1, j2, j3), moved = self._line_fit.step(t, x, point, sc)
                if moved:
                    latched = fallback = False
                joint_fb = not moved
            if point is None:
                if depth is not None:
                    depth.gap()
                return self._none(t, x, pulling=True, relatched=relatched)
            if type(point) is not tuple:
                point = tuple(point)
            rx, ry, rz = point

        geo = self._geo
        if point is not geo.point:  # a new point (while a latch holds: once per contact)
            if self._track:
                geo = self._geo = PointGeometry(point, normal, self._var)
            else:
                geo = self._geo = PointGeometry.on_tip(tip, point, self._var)
                if point is self._latch.point and self._sample is not None:  # a latch held: sample_step's record
                    self._held_rec = held_record(self._latch.window, geo)
        nx, ny, nz = geo.nx, geo.ny, geo.nz
        # the depth, the measurement about the effective point and the line evidence: one step
        # (compiled), the batch's (softtip.estimator.pipeline.tail_run)
        d0, dp, ds, dr = 0.0, None, None, None
        if depth is not None:
            d0, dp, ds, dr = depth.ready(fx, fy, fz, nx, ny, nz)
        if dp is None:
            dp, ds, dr = self._no_depth
        sfx, sfy, sfz = self._force_var
        r = self._located(
            t, fx, fy, fz, mx, my, mz, rx, ry, rz, nx, ny, nz, geo.e1x, geo.e1y, geo.e1z, geo.e2x, geo.e2y, geo.e2z,
            geo.m1, geo.m2, sfx, sfy, sfz, self._depth_mode, d0, dp, ds, dr, *self._evidence.ready(),
        )  # fmt: skip
        return self._estimate(t, x, point, geo.normal, r, latched, fallback, relatched, (j0, j1, j2, j3), joint_fb)

    def _estimate(
        self, t: float, x: tuple[float, ...], point: tuple[float, float, float], normal: tuple[float, float, float],
        r: tuple, latched: bool, fallback: bool, relatched: bool, joint: tuple[float, ...] = _NAN4,
        joint_fb: bool = False,
    ) -> SampleEstimate:  # fmt: skip
        """The estimate of a sample in contact at ``point`` of normal ``normal`` from :func:`located_step`'s returns ``r``."""
        (located, delta, delta_std, from_data, sigma, hx, hy, hz, hn, h_std, code, ev, dx, dy, dz, angle, angle_std,
         noise_std, h_ratio, f_ratio) = r  # fmt: skip
        if not located:  # not pushing
            return self._none(t, x, pulling=True, relatched=relatched)
        contacts = self._contacts
        if self._python:  # read from the records' arrays: numpy's floats
            sigma, hx, hy, hz, hn, h_std, delta, delta_std = (float(v) for v in (sigma, hx, hy, hz, hn, h_std, delta, delta_std))
            dx, dy, dz, angle, angle_std, noise_std = float(dx), float(dy), float(dz), float(angle), float(angle_std), float(noise_std)
            h_ratio, f_ratio, from_data = float(h_ratio), float(f_ratio), bool(from_data)
        h = (hx, hy, hz)
        state, evidence, d = _STATE_NAMES[code], _EVIDENCE_NAMES[ev], (dx, dy, dz)
        if self._lead:
            self._lead = False
        return _new_estimate(SampleEstimate, (
            t, state, tuple(x), point, normal, sigma, h, hn, h_std, d,
            angle, angle_std, latched, fallback, False, False, relatched, delta, *joint, joint_fb,
            contacts.contact_id, contacts.drift_before, delta_std, from_data, evidence, h_ratio, f_ratio, noise_std,
        ))  # fmt: skip

    def process(self, t: ArrayLike, wrench: ArrayLike) -> list[SampleEstimate]:
        """Feed a sequence of samples through :meth:`update`; returns one estimate each.

        Raises
        ------
        ValueError
            ``t`` and ``wrench`` hold different numbers of samples.
        """
        t, wrench = np.asarray(t, dtype=float), np.asarray(wrench, dtype=float)
        if t.ndim != 1 or wrench.shape != (len(t), 6):  # zip would drop the samples of the longer one
            raise ValueError(f"expected t of shape (N,) and wrench of shape (N, 6), got {t.shape} and {wrench.shape}")
        return [self.update(ti, wi) for ti, wi in zip(t, wrench)]
