"""The estimator over a whole log: :func:`estimate`.

The stages whose state crosses a cut of the log (tare, low-pass filter, contact tracking) run
first; the per-contact stages then run in the compiled loops of
:mod:`softtip.estimator.pipeline` (the closed-form fingertips), or stage after stage with numpy
between them (:func:`_staged_columns`: any fingertip, and the steps run as Python): the same bits.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.core._blocks import blockwise
from softtip.core._xp import NP
from softtip.core.filtering import lowpass_sos, sosfilt_state
from softtip.core.fingertip import Fingertip, load_fingertip
from softtip.core.location import contact_arrays
from softtip.core.noise import SensorNoise
from softtip.core.units import PLAUSIBLE_RATE_HZ
from softtip.estimator.config import EstimatorConfig
from softtip.estimator.contact import (
    ContactTrack,
    TrackState,
    drift_message,
    first_contact_pulls,
    started_in_contact_message,
    track_contacts,
)
from softtip.estimator.depth import depth_points, resolve_depth
from softtip.estimator.evidence import evidence_states, twist_curvature
from softtip.estimator.latch import latch_points
from softtip.estimator.line_fit import line_fit_points
from softtip.estimator.measure import Measurement, effective_noise, measure, noise_correlation
from softtip.estimator.pipeline import fused_columns
from softtip.estimator.results import LINE, NONE, Estimates, EstimatorWarning
from softtip.estimator.tare import TareReport, noise_in_use, tare_log

__all__ = ["Carry", "estimate"]


@dataclass
class Carry:
    """The pipeline's state between pieces of one log (see :func:`estimate`, ``carry``).

    Empty before the first piece; :func:`estimate` fills it in at the end of each piece.
    """

    tare: TareReport | None = None  #: the tare of the first piece (its bias, and any noise model it measured, used from then on)
    zi: NDArray | None = None  #: the low-pass filter's state after the last piece
    track: TrackState | None = None  #: the contact tracker's state after the last piece
    had_latch: bool = False  #: a contact so far had a latched point (the next one starts re-latched)


def time_type_error(t: ArrayLike) -> ValueError | None:
    """The error for time stamps given as numpy's or pandas' dates or durations (one or an
    array), whose unit is not seconds; None for anything else."""
    kind = np.asarray(t).dtype.kind
    if kind not in "mM":
        return None
    fix = "(t - t[0]) / np.timedelta64(1, 's')" if kind == "M" else "t / np.timedelta64(1, 's')"
    return ValueError(f"t holds {'dates' if kind == 'M' else 'durations'} ({np.asarray(t).dtype}); expected seconds "
                      f"as floats, e.g. {fix}")  # fmt: skip


def validate_log(t: ArrayLike, wrench: ArrayLike) -> tuple[NDArray, NDArray]:
    """``t`` (N,) and ``wrench`` (N, 6) as float arrays, checked: finite, time non-decreasing."""
    err = time_type_error(t)
    if err is not None:
        raise err
    if np.asarray(wrench).dtype.kind == "c":
        raise ValueError("wrench holds complex numbers; expected real N and N·m")
    t = np.asarray(t, dtype=float)
    w = np.asarray(wrench, dtype=float)
    if t.ndim != 1 or w.shape != (len(t), 6):
        raise ValueError(f"expected t of shape (N,) and wrench of shape (N, 6), got {t.shape} and {w.shape}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(w))):
        bad_t, bad_w = ~np.isfinite(t), ~np.isfinite(w).all(axis=1)
        i = int(np.argmax(bad_t | bad_w))
        what = f"t = {float(t[i])!r}" if bad_t[i] else f"wrench = {w[i].tolist()!r}"
        raise ValueError(f"t and wrench must be finite: sample {i} (from 0) has {what}")
    back = np.flatnonzero(np.diff(t) < 0)
    if len(back):
        i = int(back[0]) + 1
        raise ValueError(f"time must not go back: sample {i} at {float(t[i])!r} s follows {float(t[i - 1])!r} s")
    return t, w


def infer_rate(t: NDArray) -> float:
    """Sample rate, Hz, from the median of the positive time steps (repeated stamps ignored),
    to 9 significant digits: stamps at a constant rate then give the same rate from any
    stretch of the log (a log processed in pieces designs the filter from its first block)."""
    dt = np.diff(t)
    dt = dt[dt > 0]
    if not len(dt):
        raise ValueError("a low-pass filter needs at least two distinct sample times to infer the sample rate")
    return float(f"{1.0 / float(np.median(dt)):.9g}")


#: A configured sample rate this far (relative) from the stamps' is warned about.
SAMPLE_RATE_TOLERANCE = 0.1
#: The stamps the rate checks look at: the first ones, in the batch as in the stream.
RATE_CHECK_SAMPLES = 21


def _first_rate(t: ArrayLike) -> float | None:
    """Hz: the rate of the first :data:`RATE_CHECK_SAMPLES` stamps (their median positive step),
    as the stream has them once it has that many; None before, or with fewer than 10 distinct."""
    first = np.asarray(t, dtype=float)[:RATE_CHECK_SAMPLES]
    dt = np.diff(first)
    dt = dt[dt > 0]
    if len(first) < RATE_CHECK_SAMPLES or len(dt) < 9:
        return None
    return 1.0 / float(np.median(dt))


def implausible_rate(t: ArrayLike) -> str | None:
    """The warning when the stamps ``t`` (the first :data:`RATE_CHECK_SAMPLES`) step at no force/torque
    sensor's rate (:data:`PLAUSIBLE_RATE_HZ`): t in ms, µs or ns taken as seconds, which puts
    every time window (the tare, the line evidence, the filter) off by that factor."""
    rate = _first_rate(t)
    if rate is None:
        return None
    low, high = PLAUSIBLE_RATE_HZ
    if low <= rate <= high:
        return None
    return (
        f"t steps at {rate:.4g} Hz (the median of its first steps), no force/torque sensor's rate ({low:g} Hz to "
        f"{high / 1e3:g} kHz): is t in {'milliseconds or microseconds' if rate < low else 'another unit'}? Every time "
        "window (the tare, the line evidence, the filter) is in seconds; give t in seconds"
    )


def sample_rate_mismatch(t: ArrayLike, sample_rate: float | None) -> str | None:
    """The warning when ``config.sample_rate`` (Hz) contradicts the stamps ``t`` (s, the first
    :data:`RATE_CHECK_SAMPLES`, :func:`_first_rate`) more than :data:`SAMPLE_RATE_TOLERANCE` away;
    None when they agree, or before there are enough stamps."""
    rate = None if sample_rate is None else _first_rate(t)
    if rate is None:
        return None
    if abs(rate / sample_rate - 1.0) <= SAMPLE_RATE_TOLERANCE:
        return None
    return (
        f"config.sample_rate is {sample_rate:g} Hz but the stamps step at {rate:.4g} Hz (median): the low-pass filter "
        f"and every rate-based setting are designed for {sample_rate:g} Hz; give sample_rate={rate:.4g} (or None to "
        "take it from the stamps)"
    )


class _Sequential(NamedTuple):
    """The stages whose state crosses a cut (tare, low-pass filter, contact tracking) over a
    piece of a log (:func:`_sequential_stages`): what the per-contact stages start from."""

    bias: NDArray  #: (6,) N and N·m
    taring: NDArray  #: (N,) bool, the samples the tare used
    tare_report: TareReport
    sos: NDArray | None  #: the low-pass filter's sections (None without one)
    noise: SensorNoise  #: the noise in use, after any filter
    ct: ContactTrack
    later: bool  #: a later piece of a log (the first piece's tare, not this one's)
    zi: NDArray | None  #: the low-pass filter's state after the piece's last sample

    def advance(self, carry: Carry) -> None:
        """Bring ``carry`` past the piece (all but ``had_latch``, which the per-contact stages give)."""
        carry.tare, carry.zi, carry.track = self.tare_report, self.zi, self.ct.state


def _sequential_stages(t: NDArray, w: NDArray, config: EstimatorConfig, carry: Carry | None, *,
                      cut_from: int | None = None) -> _Sequential | None:  # fmt: skip
    """The stages whose state crosses a cut over ``t`` (N,) s and ``w`` (N, 6) N and N·m
    (validated, ``config`` resolved), from ``carry`` (not changed: :meth:`_Sequential.advance`).

    ``cut_from``: the stages over the samples up to the first one at or after ``cut_from``,
    and after the tare, where the log may be cut (the estimator out of contact, nothing
    pending, the drift following; the next piece starts there): ``len(result.taring)``
    samples, the bits of these stages run over those samples alone. None when there is no
    such sample yet (a contact, or the tare, goes on past the samples given). Finding the cut
    and running the piece's stages is then one pass (:mod:`softtip.apps.chunked`).
    """
    n = len(t)
    later = carry is not None and carry.tare is not None
    if later:  # a later piece: the first piece's bias, no tare
        tare_report = carry.tare
        bias, taring = tare_report.bias, np.zeros(n, dtype=bool)
    else:
        bias, taring, tare_report = tare_log(t, w, config)
    tared = bool(np.all(np.isfinite(bias)))
    if cut_from is not None and not tared:
        return None  # still taring
    start = int(np.count_nonzero(taring))
    first = None if cut_from is None else min(max(start + 1, cut_from), n)  # the first sample a cut may fall on
    x, sub = w, bias  # the tracker subtracts the bias (no tared copy) unless the filter needs it first

    sos = None
    zf = zc = None
    if config.lowpass_hz is not None:
        rate = config.sample_rate or infer_rate(t)
        sos = lowpass_sos(config.lowpass_hz, rate, config.lowpass_order)
        if tared:
            # in two parts, at the first sample a cut may fall on, keeping the state there (zc):
            # the state at the cut is then the filter over the samples from there alone (causal,
            # the same bits piece by piece)
            d = w - bias
            x, zf = sosfilt_state(sos, d[:first], carry.zi if later else None)
            if first is not None:
                zc = zf
                rest, zf = sosfilt_state(sos, d[first:], zc)
                x = np.concatenate((x, rest))
            sub = None
    noise = effective_noise(noise_in_use(config, tare_report), sos)
    ct = track_contacts(t, x, start, config, noise, carry.track if later else None, sub, cut_from=first)
    if ct is None:
        return None
    m = len(ct.contact)
    if m < n:  # cut: the filter's state after the piece
        taring = taring[:m]
        if zc is not None:
            _, zf = sosfilt_state(sos, d[first:m], zc)
    return _Sequential(bias, taring, tare_report, sos, noise, ct, later, zf)


def estimate(
    t: ArrayLike,
    wrench: ArrayLike,
    tip: Fingertip | str = "murakami2006",
    config: EstimatorConfig | None = None,
    *,
    carry: Carry | None = None,
) -> Estimates:
    """Run the estimator over a whole log (or a piece of one: ``carry``).

    Parameters
    ----------
    t : array-like, shape (N,)
        Sample times, s, non-decreasing (repeated stamps are accepted and counted in
        :attr:`Estimates.repeated_stamps`).
    wrench : array-like, shape (N, 6)
        Raw sensor wrench ``fx, fy, fz`` (N), ``mx, my, mz`` (N·m), sensor frame.
    tip : Fingertip or str
        Fingertip, preset name or TOML path.
    config : EstimatorConfig, optional
    carry : Carry, optional
        For a log processed piece by piece (``softtip estimate`` on a log larger than
        memory): the state the previous piece left (an empty :class:`Carry` for the first),
        updated in place. A piece must start at a sample where the previous piece's
        estimator was out of contact, no contact pending, the drift following (see
        :func:`softtip.apps.chunked.estimate_pieces`), and give ``config.sample_rate`` when it
        low-pass filters; then every piece gives the bits of the whole log's run over its
        samples. Warnings of the first piece's tare are given with the first piece only.

    Returns
    -------
    Estimates

    Examples
    --------
    >>> from softtip import estimate, load_example
    >>> log = load_example()
    >>> est = estimate(log.t, log.wrench, "murakami2006")
    >>> sorted(set(est.state_names.tolist()))
    ['line', 'none', 'point']
    """
    est = _estimate(t, wrench, tip, config, carry)
    for msg in est.warnings:
        warnings.warn(msg, EstimatorWarning, stacklevel=2)
    return est


def _estimate(t: ArrayLike, wrench: ArrayLike, tip: Fingertip | str, config: EstimatorConfig | None,
              carry: Carry | None, stages: _Sequential | None = None) -> Estimates:  # fmt: skip
    """:func:`estimate` without issuing its warnings (they are in :attr:`Estimates.warnings`): what
    a thread may call (``warnings.catch_warnings`` is not thread-safe).

    ``stages``: the piece's :func:`_sequential_stages` from ``carry``, already run (and ``carry``
    brought past them by the caller; only ``carry.had_latch`` is read and written here). Their
    wrench and drift arrays are this call's to change."""
    tip = load_fingertip(tip)
    config = resolve_depth(config or EstimatorConfig(), tip)
    t, w = validate_log(t, wrench)

    if stages is None:
        stages = _sequential_stages(t, w, config, carry)
        if carry is not None:
            stages.advance(carry)
    bias, taring, tare_report, sos, noise, ct, later, _ = stages
    had_latch = carry is not None and carry.had_latch
    # the closed-form fingertips: the per-contact stages in compiled loops (softtip.estimator.pipeline)
    cols = fused_columns(t, ct.wrench, ct.drift, ct.contact, taring, tip, config, noise, noise_correlation(sos), had_latch)
    if cols is None:
        cols = _staged_columns(t, ct, taring, tip, config, noise, sos, had_latch)
    if carry is not None and config.contact_point != "track":
        carry.had_latch = cols.pop("had_latch")
    cols.pop("had_latch", None)
    pulling = cols["pulling"]
    started_in_contact = tare_report.source == "tare" and first_contact_pulls(t, pulling, ct.contact_id)
    warn = [] if later else list(tare_report.warnings)
    mismatch = None if later else sample_rate_mismatch(t, config.sample_rate)
    if mismatch:
        warn.append(mismatch)
    odd_rate = None if later else implausible_rate(t)
    if odd_rate:
        warn.append(odd_rate)
    if started_in_contact:
        warn.append(started_in_contact_message(config))
    if ct.drift_alarm >= 0:
        warn.append(drift_message(config, float(t[ct.drift_alarm])))
    return Estimates(
        t=t,
        taring=taring,
        bias=bias,
        tare_force_std=float(np.nanmax(tare_report.force_std)) if np.any(np.isfinite(tare_report.force_std)) else math.nan,
        repeated_stamps=int(np.count_nonzero(np.diff(t) == 0)),
        contact_id=ct.contact_id,
        tare=tare_report,
        started_in_contact=started_in_contact,
        drift_alarm=ct.drift_alarm >= 0,
        warnings=tuple(warn),
        **cols,
    )


def _staged_columns(t, ct, taring, tip: Fingertip, config: EstimatorConfig, noise, sos, had_latch: bool) -> dict:
    """The per-contact stages one after the other over the whole log, numpy between them (any
    fingertip, and steps run as Python); the columns of :func:`softtip.estimator.pipeline.fused_columns`."""
    n = len(t)
    x = ct.wrench

    c = [np.ascontiguousarray(x[:, i]) for i in range(6)]
    f_norm = np.sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2])
    contact = ct.contact
    relatched = np.zeros(n, dtype=bool)
    joint_stats = None  # (4, N), allocated at the end unless the line fit gives them
    joint_fb = np.zeros(n, dtype=bool)
    with np.errstate(invalid="ignore", divide="ignore"):
        sc = contact_arrays(tip, *c)
        if config.contact_point == "track":
            point = np.stack(sc.point, axis=-1)
            normal = np.stack(sc.normal, axis=-1)
            has = np.asarray(sc.valid, dtype=bool)
            latched = fallback = np.zeros(n, dtype=bool)
        else:
            point, latched, fallback, relatched = latch_points(t, f_norm, contact, sc, tip, config, had_latch)
            had_latch = had_latch or bool(latched.any())
            if config.contact_point == "line-fit":
                point, joint_stats, _, moved = line_fit_points(
                    t, c, contact, sc, point, relatched, tip, config, noise, noise_correlation(sos)
                )
                latched, fallback, joint_fb = latched & ~moved, fallback & ~moved, contact & ~moved
            normal = tip.normal(point)
            has = np.all(np.isfinite(point), axis=-1)
        del sc, f_norm  # not needed from here on (bounds the peak memory)
        # depth: friction acts at r − δ n, inside the skin
        delta, delta_std, from_data = depth_points(t, c, contact, point, normal, config, noise, noise_correlation(sos))
        # h is written straight into its (N, 3) output; no depth column (the moment is
        # taken about the point moved by the depth here, not by a law in measure)
        h = np.empty((n, 3))
        ms = Measurement(*blockwise(
            lambda fx, fy, fz, mx, my, mz, px, py, pz, nx, ny, nz, d, d_std: measure(
                fx, fy, fz, mx, my, mz, px - d * nx, py - d * ny, pz - d * nz, nx, ny, nz,
                noise, config.h_sigmas, config.h_min, None, NP, d_std,
            )[:-1],
            (*c, *point.T, *normal.T, delta, delta_std),
            out=(None, *h.T) + (None,) * 9,
        ), None)  # fmt: skip

    del c
    located = contact & has & ms.pushing
    pulling = contact & ~located
    # line or area (evidence window): segments start at contact onset and at every re-latch
    begin = contact & ~np.concatenate(([False], contact[:-1])) | (relatched & contact)
    ev = evidence_states(t, located, begin, point, normal, h, x[:, :3], ms, noise, noise_correlation(sos), config, delta,
                         twist_curvature(tip))
    state = np.where(located, ev.state, NONE).astype(np.int8)
    is_line = state == LINE
    if joint_stats is None:
        joint_stats = np.full((4, n), np.nan)

    not_located, not_line = ~located, ~is_line  # inverted once, not per column

    def blank(a, off):
        # every array here is this function's own temporary: NaN written in place where off
        a = np.asarray(a, dtype=float)
        np.copyto(a, np.nan, where=off.reshape(off.shape + (1,) * (a.ndim - 1)))
        return a

    return dict(
        state=state,
        # the bias is not known while taring, so neither is the tared wrench (as in the stream)
        wrench=blank(x, taring),
        point=blank(point, not_located),
        normal=blank(normal, not_located),
        sigma=blank(ms.sigma, not_located),
        h=blank(h, not_located),
        h_norm=blank(ms.h_norm, not_located),
        h_std=blank(ms.h_std, not_located),
        direction=blank(ev.direction, not_line),
        angle=blank(ev.angle, not_line),
        angle_std=blank(ev.angle_std, not_line),
        angle_noise_std=blank(ev.angle_noise_std, not_line),
        latched=latched & located,
        latch_fallback=fallback & located,
        pulling=pulling,
        relatched=relatched,
        depth=blank(delta, not_located),
        line_fit_conditioning=blank(joint_stats[0], not_located),
        line_fit_angle_std=blank(joint_stats[1], not_located),
        line_fit_offset_std=blank(joint_stats[2], not_located),
        line_fit_residual=blank(joint_stats[3], not_located),
        line_fit_fallback=joint_fb & located,
        line_evidence=np.where(is_line, ev.evidence, 0).astype(np.int8),
        h_ratio=blank(ev.h_ratio, not_located),
        excitation_ratio=blank(ev.excitation_ratio, not_located),
        drift=blank(ct.drift, taring),
        depth_std=blank(delta_std, not_located),
        depth_from_data=from_data & located,
        had_latch=had_latch,
    )
