"""The line-evidence stage: ``line`` or ``area``, and the direction from the window; batch and
stream side by side (the window maths is in :mod:`softtip.evidence`).

Over a sliding window of ``evidence_window`` seconds (restarted at contact onset, at every
re-latch and when the contact point has moved farther than ``evidence_reset_distance`` from
where the window started, e.g. a ``joint`` point found) of the located samples, with ``major ≥ minor`` the eigenvalues of ``h``'s
covariance (noise removed) and ``ratio = minor / major``:

* the window **spans both axes** when ``minor`` is beyond the noise and
  ``ratio ≥ area_ratio[0]``: the contact becomes ``area``;
* it **confirms a line** when the tangential load was excited about two axes (its own
  ``minor`` beyond the noise, at least ``excitation_ratio`` times its ``major`` and at least
  ``excitation_min²``), ``h``
  varied beyond the noise and ``ratio < area_ratio[1]``;
* otherwise the verdict stays what it was (hysteresis: between the two ratios nothing
  changes); before any verdict a line is ``unconfirmed``.

Once the verdict is ``area`` every sample is ``area`` (no direction) until the verdict
changes; otherwise a sample with significant ``|h|`` is ``line`` ``confirmed`` or ``line``
``unconfirmed``, and one below significance ``point``, except inside a confirmed line with a
window direction held: ``h`` passing through zero while the object rocks does not make a
line or an area a point. Significance has hysteresis too: once above the measurement's
threshold, ``|h|`` stays significant down to :data:`SIG_LEAVE` of it. In a confirmed line
the direction is the latest window's of this segment that confirmed the line (two-axis
excitation, ``h`` on one axis) with an angle standard deviation at most
``evidence_max_angle_std`` (``d = n × principal axis``); before there is one, the sample's
own. A window excited about one axis only would bias the axis: a line's small resistance to
rolling about its own edge follows the same excitation. A sample's own angle standard
deviation counts the window's across-axis spread beyond the noise as model error:
``sqrt(σ_d² + minor) / |h|``.

:func:`evidence_states` does it for a whole log, :class:`EvidenceTracker` one sample at a
time (running sums, O(1) per sample, as :mod:`softtip.estimator.joint`).
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

from softtip._xp import NP, PY
from softtip.estimator.config import EstimatorConfig
from softtip.evidence import (
    N_SUMS, _div, evidence_products, noise_constants, tangent_noise_kernel, window_constants, window_direction_floats,
    window_eigen_floats, window_kernel,
)  # fmt: skip
from softtip.noise import SensorNoise
from softtip.spin import tangent_frame_kernel

__all__ = ["evidence_states", "EvidenceTracker"]

#: A significant ``|h|`` stays significant down to this share of the threshold (hysteresis).
SIG_LEAVE = 2.0 / 3.0
#: Verdicts of a segment.
_UNKNOWN, _LINE, _AREA = 0, 1, 2
_NAN3 = (math.nan, math.nan, math.nan)


def _decide(win, config: EstimatorConfig, xp):
    """``(area_now, line_now, resolved, h_ratio, f_ratio)`` of a window (component-wise)."""
    enter, leave = config.area_ratio
    h_ratio = xp.where(win.h_major > win.h_noise, xp.div(win.h_minor, win.h_major), xp.nan)
    f_ratio = xp.where(win.f_major > win.f_noise, xp.div(win.f_minor, win.f_major), xp.nan)
    # comparisons written so that NaN is False in both back ends
    varied = win.h_major > win.h_noise
    area_now = (win.h_minor > win.h_noise) & (h_ratio >= enter)
    one_axis = varied & (h_ratio < leave)
    excited = (
        (win.f_minor > win.f_noise)
        & (win.f_minor >= config.excitation_ratio * win.f_major)
        & (win.f_minor >= config.excitation_min * config.excitation_min)
    )
    line_now = excited & one_axis
    # single-axis windows bias the axis (a line's small resistance to rolling about its own
    # edge follows the same excitation): only two-axis windows give the direction
    resolved = line_now & (win.angle_std <= config.evidence_max_angle_std)
    return area_now, line_now, resolved, h_ratio, f_ratio


def _frame_terms(px, py, pz, nx, ny, nz, hx, hy, hz, fx, fy, fz, noise, xp):
    e1x, e1y, e1z, e2x, e2y, e2z = tangent_frame_kernel(nx, ny, nz, xp)
    h1 = hx * e1x + hy * e1y + hz * e1z
    h2 = hx * e2x + hy * e2y + hz * e2z
    f1 = fx * e1x + fy * e1y + fz * e1z
    f2 = fx * e2x + fy * e2y + fz * e2z
    return (h1, h2, f1, f2), tangent_noise_kernel(px, py, pz, e1x, e1y, e1z, e2x, e2y, e2z, noise), (e1x, e1y, e1z, e2x, e2y, e2z)


def _sample_std(angle_std, h_norm, minor, xp):
    """The sample's angle standard deviation with the window's across-axis spread added."""
    return xp.sqrt(angle_std * angle_std + xp.div(minor, h_norm * h_norm))


def _point_moves(begin, located, point, distance: float):
    """``begin`` with a new segment wherever the contact point has moved farther than
    ``distance`` from the first located point of its segment (one pass per move)."""
    begin = begin.copy()
    idx = np.flatnonzero(begin | located)
    seg = np.cumsum(begin)[idx]
    block = 4096  # searched block by block: a move costs its distance to the next, not the log's length
    for part in np.split(idx, np.flatnonzero(np.diff(seg)) + 1):
        v = part[located[part]]
        while len(v):
            first = None
            for s in range(0, len(v), block):
                d = point[v[s : s + block]] - point[v[0]]
                far = np.flatnonzero(np.einsum("ij,ij->i", d, d) > distance * distance)
                if len(far):
                    first = s + int(far[0])
                    break
            if first is None:
                break
            begin[v[first]] = True
            v = v[first:]
    return begin


def evidence_states(t, located, begin, point, normal, h, force, ms, noise: SensorNoise, corr: float,
                    config: EstimatorConfig):  # fmt: skip
    """The evidence stage over a whole log, vectorised within each segment.

    Parameters
    ----------
    t : (N,) s
    located : (N,) bool
        Samples with a contact point and a pushing force (the window's samples).
    begin : (N,) bool
        Segment starts: contact onset and re-latch.
    point, normal : (N, 3)
        Contact point (m) and normal the measurement used.
    h : (N, 3)
        Tangential spin torque, N·m.
    force : (N, 3)
        Force, N.
    ms : Measurement
        The measurement stage's output (``line`` is the significance of ``|h|``).
    noise : SensorNoise
        Per-sample noise (after any filter).
    corr : float
        Samples per independent noise sample.
    config : EstimatorConfig

    Returns
    -------
    tuple
        ``(state, evidence, direction (N, 3), angle, angle_std, h_ratio, f_ratio)``: state
        codes of :data:`~softtip.estimator.results.STATES` (``point`` / ``line`` / ``area``
        on located samples), evidence codes of
        :data:`~softtip.estimator.results.EVIDENCE`, the direction and its angle and
        standard deviation (NaN unless ``line``) and the window ratios.
    """
    n = len(t)
    sig = located & np.asarray(ms.line, dtype=bool)
    if config.line_evidence:
        begin = _point_moves(begin, located, point, config.evidence_reset_distance)
    if not config.line_evidence:
        d = np.stack((ms.dx, ms.dy, ms.dz), axis=-1)
        nan = np.full(n, np.nan)
        return np.where(sig, 2, 1).astype(np.int8), np.where(sig, 1, 0).astype(np.int8), d, ms.angle, ms.angle_std, nan, nan
    with np.errstate(invalid="ignore"):
        terms, nz, frame = _frame_terms(*point.T, *normal.T, *h.T, *force.T, noise, NP)
    prods = evidence_products(*terms)
    sums = np.full((N_SUMS, n), np.nan)
    count = np.full(n, np.nan)
    seg_id = np.cumsum(begin)
    v_all = np.flatnonzero(located)
    verdict = np.zeros(n, dtype=np.int8)
    held = np.full(n, -1)
    win = None
    if len(v_all):
        ids = seg_id[v_all]
        cuts = np.flatnonzero(np.diff(ids)) + 1
        for v in np.split(v_all, cuts):
            tv = t[v]
            # window of sample k: the located samples i of its segment with t_i > t_k − T
            first = np.searchsorted(tv, tv - config.evidence_window, side="right")
            last = np.arange(1, len(v) + 1)
            for j, p in enumerate(prods):
                cz = np.concatenate(([0.0], np.cumsum(p[v])))  # sequential, as the stream's running sums
                sums[j, v] = cz[last] - cz[first]
            count[v] = last - first
        with np.errstate(invalid="ignore", divide="ignore"):
            win = window_kernel(sums, count, *nz, corr, NP)
            area_now, line_now, resolved, h_ratio, f_ratio = _decide(win, config, NP)
        event = np.where(area_now, _AREA, np.where(line_now, _LINE, _UNKNOWN))
        # the verdict is the latest event of the segment, and the held window the latest
        # resolved one (forward fill within each segment)
        idx = np.arange(n)
        start = np.maximum.accumulate(np.where(begin, idx, 0))  # segment start of each sample
        ev_at = np.maximum.accumulate(np.where(located & (event > 0), idx, -1))
        ok = ev_at >= start
        verdict[ok] = event[ev_at[ok]]
        hd_at = np.maximum.accumulate(np.where(located & resolved, idx, -1))
        held = np.where(hd_at >= start, hd_at, -1)
    else:
        h_ratio = f_ratio = np.full(n, np.nan)
    verdict = np.where(located, verdict, 0)
    h_ratio = np.where(located, h_ratio, np.nan)
    f_ratio = np.where(located, f_ratio, np.nan)

    # significance with hysteresis: a line stays significant down to SIG_LEAVE × threshold
    with np.errstate(invalid="ignore"):
        thr = config.line_threshold(ms.h_std)
        hn = np.asarray(ms.h_norm, dtype=float)
        sig_ev = np.where(hn > thr, 1, np.where(hn <= SIG_LEAVE * thr, 0, -1))
    idx = np.arange(n)
    seg_start = np.maximum.accumulate(np.where(begin, idx, 0))
    sig_at = np.maximum.accumulate(np.where(located & (sig_ev >= 0), idx, -1))
    sig = located & (sig_at >= seg_start) & (sig_ev[np.maximum(sig_at, 0)] == 1)
    has_held = held >= 0
    hi = np.where(has_held, held, 0)
    minor = np.zeros(n) if win is None else np.where(located, win.h_minor, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        own_std = _sample_std(ms.angle_std, ms.h_norm, minor, NP)
    confirmed = located & (verdict == _LINE)
    use_win = confirmed & has_held
    line = (sig & (verdict != _AREA)) | use_win
    area = located & (verdict == _AREA)
    state = np.where(area, 3, np.where(line, 2, 1)).astype(np.int8)
    evidence = np.where(line, np.where(confirmed, 2, 1), 0).astype(np.int8)
    angle = np.where(use_win, win.angle[hi] if win is not None else np.nan, ms.angle)
    angle_std = np.where(use_win, win.angle_std[hi] if win is not None else np.nan, own_std)
    e1x, e1y, e1z, e2x, e2y, e2z = frame
    ca, sa = np.cos(angle), np.sin(angle)
    wd = np.stack((ca * e1x + sa * e2x, ca * e1y + sa * e2y, ca * e1z + sa * e2z), axis=-1)
    d = np.where(use_win[:, None], wd, np.stack((ms.dx, ms.dy, ms.dz), axis=-1))
    return state, evidence, d, angle, angle_std, h_ratio, f_ratio


class EvidenceTracker:
    """The stage of :func:`evidence_states`, one sample at a time.

    Running sums of the products since the segment's start and, for each sample of the last
    ``evidence_window`` seconds, its time and the sums before it: window sums are
    differences, as in the batch. Plain float arithmetic (:func:`softtip.evidence.window_floats`),
    O(1) per sample.
    """

    def __init__(self, config: EstimatorConfig, noise: SensorNoise, corr: float):
        self.config = config
        self.noise = noise
        self.corr = corr
        self._at: tuple | None = None
        self._point: tuple | None = None
        self._frame: tuple = ()
        self._noise_terms: tuple = ()
        self._constants: dict[float, tuple[float, float, float]] = {}
        enter, leave = config.area_ratio
        self._enter, self._leave = enter, leave
        self._fmin2 = config.excitation_min * config.excitation_min
        self._reset2 = config.evidence_reset_distance * config.evidence_reset_distance
        self.start_segment()

    def start_segment(self) -> None:
        """At contact onset and at a re-latch: empty window, no verdict, no held direction."""
        self._cum = (0.0,) * N_SUMS
        self._hist: deque[tuple[float, tuple]] = deque()
        self._verdict = _UNKNOWN
        self._held: tuple[float, float] | None = None
        self._sig = False
        self._anchor: tuple | None = None

    def step(self, t, point, normal, h, force, ms):
        """``(state, evidence, direction, angle, angle_std, h_ratio, f_ratio)`` of a located
        sample; ``ms`` is its :class:`~softtip.estimator.measure.Measurement`."""
        cfg = self.config
        if not cfg.line_evidence:
            if ms.line:
                return "line", "unconfirmed", (ms.dx, ms.dy, ms.dz), ms.angle, ms.angle_std, math.nan, math.nan
            return "point", "", _NAN3, math.nan, math.nan, math.nan, math.nan
        anchor = self._anchor
        if anchor is None:
            self._anchor = point
        else:
            dx, dy, dz = point[0] - anchor[0], point[1] - anchor[1], point[2] - anchor[2]
            if dx * dx + dy * dy + dz * dz > self._reset2:  # the contact moved: a new segment
                self.start_segment()
                self._anchor = point
        if normal != self._at or point != self._point:  # the point is held: once per latch
            self._at, self._point = normal, point
            self._frame = tangent_frame_kernel(*normal, PY)
            self._noise_terms = tangent_noise_kernel(*point, *self._frame, self.noise)
            self._noise_k = noise_constants(self._noise_terms)
        e1x, e1y, e1z, e2x, e2y, e2z = self._frame
        hx, hy, hz = h
        fx, fy, fz = force
        h1 = hx * e1x + hy * e1y + hz * e1z
        h2 = hx * e2x + hy * e2y + hz * e2z
        f1 = fx * e1x + fy * e1y + fz * e1z
        f2 = fx * e2x + fy * e2y + fz * e2z
        hist = self._hist
        cum = self._cum
        hist.append((t, cum))
        c = self._cum = (
            cum[0] + h1, cum[1] + h2, cum[2] + h1 * h1, cum[3] + h1 * h2, cum[4] + h2 * h2,
            cum[5] + f1, cum[6] + f2, cum[7] + f1 * f1, cum[8] + f1 * f2, cum[9] + f2 * f2,
        )  # fmt: skip
        start = t - cfg.evidence_window
        while hist and hist[0][0] <= start:
            hist.popleft()
        if hist:
            o = hist[0][1]
            sums = (
                c[0] - o[0], c[1] - o[1], c[2] - o[2], c[3] - o[3], c[4] - o[4],
                c[5] - o[5], c[6] - o[6], c[7] - o[7], c[8] - o[8], c[9] - o[9],
            )  # fmt: skip
        else:  # an empty window (t − T rounds to t) has zero sums, as in the batch
            sums = (0.0,) * N_SUMS
        count = float(len(hist))
        k = self._constants.get(count)
        if k is None:
            k = self._constants[count] = window_constants(count, self.corr)
        tail, keep, nu = k
        s_big, s2, f_n = self._noise_k
        e = window_eigen_floats(sums, count, self._noise_terms, keep)
        major, minor, f_major, f_minor = e[0], e[1], e[8], e[9]
        h_noise, f_noise = tail * s_big, tail * f_n
        # _decide, unrolled (NaN comparisons are False, as in the batch)
        varied = major > h_noise
        h_ratio = _div(minor, major) if varied else math.nan
        f_ratio = _div(f_minor, f_major) if f_major > f_noise else math.nan
        if minor > h_noise and h_ratio >= self._enter:
            self._verdict = _AREA
        elif (
            varied and h_ratio < self._leave and f_minor > f_noise
            and f_minor >= cfg.excitation_ratio * f_major and f_minor >= self._fmin2
        ):  # fmt: skip
            self._verdict = _LINE
            w_angle, w_std = window_direction_floats(e, s2, nu, self.corr)
            if w_std <= cfg.evidence_max_angle_std:
                self._held = (w_angle, w_std)
        hn = ms.h_norm
        thr = cfg.h_sigmas * ms.h_std
        thr = thr if thr > cfg.h_min else cfg.h_min
        if hn > thr:
            self._sig = True
        elif hn <= SIG_LEAVE * thr:
            self._sig = False
        verdict = self._verdict
        if verdict == _AREA:
            return "area", "", _NAN3, math.nan, math.nan, h_ratio, f_ratio
        if verdict == _LINE and self._held is not None:
            angle, angle_std = self._held
            ca, sa = math.cos(angle), math.sin(angle)
            d = (ca * e1x + sa * e2x, ca * e1y + sa * e2y, ca * e1z + sa * e2z)
            return "line", "confirmed", d, angle, angle_std, h_ratio, f_ratio
        if not self._sig:
            return "point", "", _NAN3, math.nan, math.nan, h_ratio, f_ratio
        a = ms.angle_std
        v = a * a + _div(minor, hn * hn)
        std = math.sqrt(v) if v >= 0.0 else math.nan
        return (
            "line", "confirmed" if verdict == _LINE else "unconfirmed", (ms.dx, ms.dy, ms.dz), ms.angle, std, h_ratio,
            f_ratio,
        )  # fmt: skip
