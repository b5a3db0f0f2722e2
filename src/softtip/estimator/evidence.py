"""The line-evidence stage: ``line`` or ``area``, and the direction from the window; batch and
stream side by side (the window maths is in :mod:`softtip.core.evidence`).

Over a sliding window of ``evidence_window`` seconds (restarted at contact onset, at every
re-latch and when the contact point has moved farther than ``evidence_reset_distance`` from
where the window started, e.g. a ``line-fit`` point found) of the located samples, with ``major ≥ minor`` the eigenvalues of ``h``'s
covariance (noise removed) and ``ratio = minor / major``:

* the window **spans both axes** when ``minor`` is beyond the noise and
  ``ratio ≥ area_ratio[0]``, at a sample whose ``|h|`` is significant, provided the load
  turned about its weaker axis too (its ``minor`` beyond the noise and at least
  ``excitation_min²``) or ``minor ≥ h_min²`` (a point gone stale). The contact **reads
  ``area``** while more than ``area_share`` of the window's samples span both axes: a reading
  of the current window, revisited as it slides (a transient spread, as a new rock begins
  while the window still holds the last one, neither makes nor locks an area);
* it **confirms a line** when the contact was excited about two axes, as the tangential load
  shows (its own ``minor`` beyond the noise, at least ``excitation_ratio`` times its
  ``major`` and at least ``excitation_min²``) or as the user states (the window wholly inside
  an interval of ``rocked``), ``h`` varied beyond the noise and ``ratio < area_ratio[1]``; a
  confirmed line stays confirmed until the window reads an area;
* it **resolves an axis** when ``h`` varied along one axis (``major`` beyond the noise and at
  least ``h_min²``, ``ratio < area_ratio[1]``) with an angle standard deviation at most
  ``evidence_max_angle_std``.

Where the window reads ``area`` the sample is ``area`` (no direction). Otherwise it is a
``line`` where ``|h|`` is significant or the current window resolves an axis (``h`` passing
through zero while the object rocks does not make a line a point), and ``point`` elsewhere,
except inside a confirmed line with a window direction held. Significance has hysteresis:
once above the measurement's threshold, ``|h|`` stays significant down to :data:`SIG_LEAVE`
of it; and at high sample rates the samples of the segment's last ``significance_window``
seconds vote (most above the threshold: significant; most below its leaving share: not; else
unchanged), so noise near the threshold does not flicker (at 50 Hz the window holds one
sample: each decides alone).

The direction: the current window's where it resolves an axis (``d = n × principal axis``),
with the model error ``evidence_model_std`` in quadrature where that window itself confirms
the line with the load turned about two axes, and ``unconfirmed_model_std`` where it does
not, also where only a stated rocking confirms it (a one-axis window's rolling bias follows
its own excitation, whether or not the line was confirmed before); in a confirmed line whose
current window resolves none (``h`` held still, or passing through zero), the latest window
of this segment that confirmed it (``h`` on one axis), with the model error of its kind; the
sample's own elsewhere. The current window is preferred to the confirming one: a confirming
window is a moment of two-axis load, often where one rock ends and the next begins, and it
can carry the contact's response to a roll about the line's own axis (on a stiffer, smaller
hydroelastic tip: 8° off where the current windows were within 1°). A sample's own angle
standard deviation counts the window's across-axis spread beyond the noise as model error,
``sqrt(σ_d² + minor / |h|²)``, plus ``unconfirmed_model_std`` while unconfirmed. The share of
the standard deviation that is the sensor noise's alone (``angle_noise_std``: the window's
noise term, or the sample's ``σ_d``) is kept apart: two sensors share the model error, not
their noise (:mod:`softtip.fusion`).

:func:`evidence_states` does it for a whole log, :class:`EvidenceTracker` one sample at a
time (running sums, O(1) per sample, as :mod:`softtip.estimator.line_fit`).
"""

from __future__ import annotations

import math
from collections import deque
from math import cos, sin, sqrt
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

import softtip.core._blocks
from softtip.core._blocks import blockwise
from softtip.core._jit import jit_enabled
from softtip.core._xp import NP
from softtip.core.evidence import (
    N_SUMS,
    _div,
    evidence_products,
    noise_constants,
    tangent_noise_kernel,
    window_constants,
    window_direction_floats,
    window_kernel,
)  # fmt: skip
from softtip.core.noise import SensorNoise
from softtip.core.spin import tangent_frame_kernel
from softtip.estimator.config import EstimatorConfig
from softtip.estimator.floats import NoiseSquares, PointGeometry, sample_direction
from softtip.estimator.sequential import point_moves_kernel, vote_kernel, window_sums_kernel

__all__ = ["evidence_states", "EvidenceStates", "EvidenceTracker"]


class EvidenceStates(NamedTuple):
    """What :func:`evidence_states` gives for a whole log (N samples)."""

    state: NDArray  #: (N,) int8, POINT, LINE or AREA (where located)
    evidence: NDArray  #: (N,) int8, 1 unconfirmed, 2 confirmed (lines)
    direction: NDArray  #: (N, 3) unit line direction (the current or the confirming window's, or the sample's)
    angle: NDArray  #: (N,) rad, the direction's angle in the tangent frame
    angle_std: NDArray  #: (N,) rad, its standard deviation
    angle_noise_std: NDArray  #: (N,) rad, the sensor noise's share of it (the rest is model error)
    h_ratio: NDArray  #: (N,) minor / major eigenvalue of h's covariance in the window
    excitation_ratio: NDArray  #: (N,) the same for the tangential force (how far it turned)

#: A significant ``|h|`` stays significant down to this share of the threshold (hysteresis).
SIG_LEAVE = 2.0 / 3.0
#: Verdicts of a segment.
_UNKNOWN, _LINE, _AREA = 0, 1, 2
_NAN3 = (math.nan, math.nan, math.nan)


def _decide(win, config: EstimatorConfig, xp, stated=False):
    """``(area_now, line_now, resolved, axis_now, h_ratio, f_ratio, seen)`` of a window (component-wise);
    ``stated``: the window lies in a stated two-axis rocking (:attr:`EstimatorConfig.rocked`)."""
    enter, leave = config.area_ratio
    h_ratio = xp.where(win.h_major > win.h_noise, xp.div(win.h_minor, win.h_major), xp.nan)
    f_ratio = xp.where(win.f_major > win.f_noise, xp.div(win.f_minor, win.f_major), xp.nan)
    # comparisons written so that NaN is False in both back ends
    varied = win.h_major > win.h_noise
    # a two-axis h counts when the load turned about its weaker axis too, or when h's spread
    # about that axis exceeds the model's error floor h_min (a point gone stale, whatever the
    # load); below it, without a turning load, it is the model's error (a grasp force settling)
    turned = (win.f_minor > win.f_noise) & (win.f_minor >= config.excitation_min * config.excitation_min)
    area_now = (win.h_minor > win.h_noise) & (h_ratio >= enter) & (turned | (win.h_minor >= config.h_min * config.h_min))
    one_axis = varied & (h_ratio < leave)
    excited = (
        (win.f_minor > win.f_noise)
        & (win.f_minor >= config.excitation_ratio * win.f_major)
        & (win.f_minor >= config.excitation_min * config.excitation_min)
    )
    # excited about two axes: the load shows it, or the user says so (where the load is locked
    # to h, as on a frictionless round skin, it cannot)
    line_now = (excited | stated) & one_axis
    # h varied along one axis with an eigen-gap beyond the noise and by at least h_min: the
    # window's principal axis is the direction, confirmed or not (one axis of excitation
    # leaves a rolling bias, which the unconfirmed model error covers), and the contact a line
    # while the window shows it, also where h passes through zero
    sharp = win.angle_std <= config.evidence_max_angle_std
    axis_now = one_axis & sharp & (win.h_major >= config.h_min * config.h_min)
    # a confirmed line's direction comes from two-axis windows only (a line's small
    # resistance to rolling about its own edge follows the excitation)
    resolved = line_now & sharp
    # resolved with the load showing the two axes (not only stated): a direction with the
    # two-axis model error (a stated window may have seen one axis of the rocking, and on a
    # frictionless cap it also carries the roll about the line's own axis)
    seen = excited & one_axis & sharp
    return area_now, line_now, resolved, axis_now, h_ratio, f_ratio, seen


def _frame_terms(nx, ny, nz, hx, hy, hz, fx, fy, fz, xp):
    """``h`` and the tangential load in the tangent frame: ``(h1, h2, f1, f2)``."""
    e1x, e1y, e1z, e2x, e2y, e2z = tangent_frame_kernel(nx, ny, nz, xp)
    h1 = hx * e1x + hy * e1y + hz * e1z
    h2 = hx * e2x + hy * e2y + hz * e2z
    f1 = fx * e1x + fy * e1y + fz * e1z
    f2 = fx * e2x + fy * e2y + fz * e2z
    return h1, h2, f1, f2


def _frame_noise(px, py, pz, nx, ny, nz, noise, xp):
    """The noise covariances of ``h`` and of the load in the tangent frame at ``p``
    (:func:`~softtip.core.evidence.tangent_noise_kernel`)."""
    return tangent_noise_kernel(px, py, pz, *tangent_frame_kernel(nx, ny, nz, xp), noise)


def _sample_std(angle_std, h_norm, minor, model_var, xp):
    """The sample's angle standard deviation with the window's across-axis spread and a model
    error variance (rad², the unconfirmed line's; 0 otherwise) added."""
    return xp.sqrt(angle_std * angle_std + xp.div(minor, h_norm * h_norm) + model_var)


def _segment_starts(begin):
    """``(idx, seg_start)``: the sample indices and the start of each sample's segment."""
    idx = np.arange(len(begin))
    return idx, np.maximum.accumulate(np.where(begin, idx, 0))


def _vote(t, located, seg_start, side, window: float, share: float = 0.5):
    """``side`` (1 above the threshold, 0 below its leaving share, −1 between) of each located
    sample replaced by the vote of the located samples of its segment in the last ``window``
    s (``t_j > t − window``, and itself): 1 or 0 when more than ``share`` of them are on that
    side, else −1."""
    if window <= 0.0:
        return side
    if jit_enabled(len(t)):
        seg = np.ascontiguousarray(seg_start, dtype=np.int64)
        return vote_kernel(t, located, seg, np.ascontiguousarray(side, dtype=np.int64), float(window), float(share),
                           np.empty(len(t), dtype=np.int64))  # fmt: skip
    loc = np.flatnonzero(located)
    tl = t[loc]
    pos = np.arange(len(loc))
    # first located sample of each sample's segment (positions in loc; a segment may begin
    # at a sample that is not located)
    first = np.searchsorted(loc, seg_start[loc])
    # the sample itself always votes (a window below the stamps' rounding keeps just it)
    lo = np.maximum(np.minimum(np.searchsorted(tl, tl - window, side="right"), pos), first)
    m = pos + 1 - lo
    out = np.full_like(side, -1)
    c = side[loc]
    vote = np.full(len(loc), -1, dtype=side.dtype)
    for v in (0, 1):
        cum = np.concatenate(([0], np.cumsum(c == v)))
        vote[cum[pos + 1] - cum[lo] > share * m] = v
    out[loc] = vote
    return out


def _point_moves(begin, located, point, distance: float):
    """``begin`` with a new segment wherever the contact point has moved farther than
    ``distance`` from the first located point of its segment (one pass per move)."""
    if jit_enabled(len(begin)):
        px, py, pz = (np.ascontiguousarray(point[:, i]) for i in range(3))
        return point_moves_kernel(begin, located, px, py, pz, float(distance) * float(distance), np.empty_like(begin))
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


class _Held(NamedTuple):
    """What the evidence stage keeps of the windows, per sample."""

    h_minor: np.ndarray
    angle: np.ndarray
    angle_std: np.ndarray
    angle_noise_std: np.ndarray
    seen: np.ndarray  #: the window resolved the line with the load turned about two axes


def _window_sum_blocks(t, located, begin, prods, window: float, block: int, sums=None, count=None):
    """Yield ``(slice, sums (N_SUMS, k), count (k,))`` of :func:`_window_sums` block by
    block (compiled; the running sums carried across blocks); into ``sums`` and ``count``
    (N_SUMS, N) and (N,) when given."""
    n = len(t)
    cum, cum_first, state = np.zeros(N_SUMS), np.zeros(N_SUMS), np.zeros(3, dtype=np.int64)
    for s in range(0, n, block):
        e = min(n, s + block)
        sb = np.empty((N_SUMS, e - s)) if sums is None else sums[:, s:e]
        cb = np.empty(e - s) if count is None else count[s:e]
        window_sums_kernel(t, located, begin, prods, float(window), s, e, cum, cum_first, state, sb, cb)
        yield slice(s, e), sb, cb


def _window_sums(t, located, begin, prods, window: float):
    """``(sums (N_SUMS, N), count (N,))``: the products summed over the window of each
    located sample (NaN elsewhere): the located samples ``i`` of its segment with
    ``t_i > t_k − window``, as differences of running sums from the segment's start;
    ``prods`` (N_SUMS, N) or a sequence of N_SUMS arrays (N,)."""
    n = len(t)
    if jit_enabled(n):
        sums, count = np.empty((N_SUMS, n)), np.empty(n)
        for _ in _window_sum_blocks(t, located, begin, np.asarray(prods), window, max(n, 1), sums, count):
            pass
        return sums, count
    sums = np.full((N_SUMS, n), np.nan)
    count = np.full(n, np.nan)
    seg_id = np.cumsum(begin)
    v_all = np.flatnonzero(located)
    cuts = np.flatnonzero(np.diff(seg_id[v_all])) + 1
    for v in np.split(v_all, cuts):
        tv = t[v]
        # window of sample k: the located samples i of its segment with t_i > t_k − T
        first = np.searchsorted(tv, tv - window, side="right")
        last = np.arange(1, len(v) + 1)
        for j, p in enumerate(prods):
            cz = np.concatenate(([0.0], np.cumsum(p[v])))  # sequential, as the stream's running sums
            sums[j, v] = cz[last] - cz[first]
        count[v] = last - first
    return sums, count


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
        :class:`EvidenceStates`: state codes of :data:`~softtip.estimator.results.STATES`
        (``point`` / ``line`` / ``area`` on located samples), evidence codes of
        :data:`~softtip.estimator.results.EVIDENCE`, the direction and its angle, standard
        deviation and the noise's share of it (NaN unless ``line``) and the window ratios.
    """
    n = len(t)
    sig = located & np.asarray(ms.line, dtype=bool)
    if config.line_evidence:
        begin = _point_moves(begin, located, point, config.evidence_reset_distance)
    if not config.line_evidence:
        d = np.stack((ms.dx, ms.dy, ms.dz), axis=-1)
        nan = np.full(n, np.nan)
        return EvidenceStates(np.where(sig, 2, 1).astype(np.int8), np.where(sig, 1, 0).astype(np.int8), d, ms.angle,
                              ms.angle_std, ms.angle_std, nan, nan)  # fmt: skip

    with np.errstate(invalid="ignore"):
        prods = blockwise(lambda *a: evidence_products(*_frame_terms(*a, NP)), (*normal.T, *h.T, *force.T), stacked=True)
    verdict = np.zeros(n, dtype=np.int8)
    win = None
    if np.any(located):

        def per_window(*a):
            # the sample's noise is computed here, block by block, not kept for the whole log
            nz = _frame_noise(*a[N_SUMS + 1 : N_SUMS + 7], noise, NP)
            w = window_kernel(a[:N_SUMS], a[N_SUMS], *nz, corr, NP)
            stated = config.stated_excitation(a[N_SUMS + 7]) if config.rocked else False
            *verdicts, seen = _decide(w, config, NP, stated)
            return (*verdicts, w.h_minor, w.angle, w.angle_std, w.angle_noise_std, seen)

        with np.errstate(invalid="ignore", divide="ignore"):
            if jit_enabled(n):  # window sums block by block, never the whole log's
                res = None
                for b, sb, cb in _window_sum_blocks(t, located, begin, prods, config.evidence_window, softtip.core._blocks.BLOCK):
                    r = per_window(*sb, cb, *(np.ascontiguousarray(z[b]) for z in (*point.T, *normal.T, t)))
                    if res is None:
                        res = [np.empty(n, dtype=np.asarray(x).dtype) for x in r]
                    for dst, x in zip(res, r):
                        dst[b] = x
            else:
                sums, count = _window_sums(t, located, begin, prods, config.evidence_window)
                res = blockwise(per_window, (*sums, count, *point.T, *normal.T, t))
                del sums, count
        del prods
        area_now, line_now, resolved, axis_now, h_ratio, f_ratio, *rest = res
        win = _Held(*rest)
        del res, rest  # temporaries are dropped as soon as done with: they set the peak memory
        # an area only where |h| itself is significant: sub-threshold h wanders about both axes
        # with the model's error (a grasp force settling) once a low-pass has removed the noise
        with np.errstate(invalid="ignore"):
            above = np.asarray(ms.h_norm, dtype=float) > config.line_threshold(ms.h_std)
        idx, seg_start = _segment_starts(begin)
        # area is a reading of the current window: more than area_share of the window's samples
        # show h spread over both axes (a transient spread as a new rock begins does not make
        # one, and the reading ends when the window no longer shows it)
        area = _vote(t, located, seg_start, (area_now & above).astype(np.int64), config.evidence_window, config.area_share) == 1
        area &= located
        del area_now, above
        event = np.where(area, _AREA, np.where(line_now, _LINE, _UNKNOWN))
        del line_now
        # the verdict is the latest event of the segment (a confirmed line stays confirmed until
        # the window reads an area), the held windows the latest since the last area reading
        ev_at = np.maximum.accumulate(np.where(located & (event > 0), idx, -1))
        ok = ev_at >= seg_start
        verdict[ok] = event[ev_at[ok]]
        del ev_at, ok, event
        floor = np.maximum(seg_start, np.maximum.accumulate(np.where(area, idx, -1)) + 1)
        hd_at = np.maximum.accumulate(np.where(located & resolved, idx, -1))
        held = np.where(hd_at >= floor, hd_at, -1)
        del hd_at, floor, resolved
    else:
        del prods
        held = np.full(n, -1)
        area = axis_now = np.zeros(n, dtype=bool)
        h_ratio, f_ratio = np.full(n, np.nan), np.full(n, np.nan)
        idx, seg_start = _segment_starts(begin)
    # in place: h_ratio and f_ratio are this function's own arrays
    out_of = ~located
    verdict[out_of] = 0
    np.copyto(h_ratio, np.nan, where=out_of)
    np.copyto(f_ratio, np.nan, where=out_of)
    del out_of

    # significance with hysteresis: a line stays significant down to SIG_LEAVE × threshold,
    # decided by the vote of the last significance_window s
    with np.errstate(invalid="ignore"):
        thr = config.line_threshold(ms.h_std)
        hn = np.asarray(ms.h_norm, dtype=float)
        sig_ev = np.where(hn > thr, 1, np.where(hn <= SIG_LEAVE * thr, 0, -1))
    sig_ev = _vote(t, located, seg_start, sig_ev, config.significance_window)
    sig_at = np.maximum.accumulate(np.where(located & (sig_ev >= 0), idx, -1))
    sig = located & (sig_at >= seg_start) & (sig_ev[np.maximum(sig_at, 0)] == 1)
    del sig_ev, sig_at, seg_start, idx
    has_held = held >= 0
    hi = np.where(has_held, held, 0)
    minor = np.zeros(n) if win is None else np.where(located, win.h_minor, 0.0)
    confirmed = located & (verdict == _LINE)
    uv = config.unconfirmed_model_std * config.unconfirmed_model_std
    with np.errstate(invalid="ignore", divide="ignore"):
        # a sample's own direction carries the one-axis model error unless the line was
        # confirmed by a window whose load turned about two axes
        by_load = confirmed & has_held & (False if win is None else win.seen[hi])
        own_std = _sample_std(ms.angle_std, ms.h_norm, minor, np.where(by_load, 0.0, uv), NP)
        del by_load
    del minor
    use_win = confirmed & has_held
    line = ((sig | (axis_now & located)) & ~area) | use_win
    # the held confirming window only where the current one resolves no axis: a confirming
    # window is a moment of two-axis load, often where one rock ends and the next begins, and
    # it can carry the response to a roll about the line's own axis
    use_win &= ~axis_now
    # the current window confirms the line itself (its direction is the held one)
    confirming = has_held & (held == np.arange(n))
    del held, has_held
    state = np.where(area, 3, np.where(line, 2, 1)).astype(np.int8)
    evidence = np.where(line, np.where(confirmed, 2, 1), 0).astype(np.int8)
    if win is None:
        angle, angle_std, angle_noise_std = ms.angle, own_std, ms.angle_std
    else:
        # the current window's direction wherever h varied along one axis within it (in a
        # confirmed line too), with the model error of its kind; the held confirming window's
        # where it resolves none; the sample's own where neither is there
        use_axis = line & ~use_win & axis_now
        w = np.where(use_win, hi, np.arange(n))
        w_std = win.angle_std[w]
        use = use_win | use_axis
        mv = config.evidence_model_std * config.evidence_model_std
        angle = np.where(use, win.angle[w], ms.angle)
        # the model error of the window's kind: two-axis (a confirming window whose load
        # turned about both axes) or one-axis (a rolling bias no window shows, whether or not
        # the line was confirmed before, by the load or by the user)
        two_axis = (use_win | confirming) & win.seen[w]
        angle_std = np.where(use, np.sqrt(w_std * w_std + np.where(two_axis, mv, uv)), own_std)
        # the sample's own direction: its noise; a window's: the window's noise term
        angle_noise_std = np.where(use, win.angle_noise_std[w], ms.angle_std)
        del w, w_std, use_axis, confirming, two_axis
        use_win = use
    del win, hi, own_std, axis_now
    # the held window's direction, in the tangent frame of the sample
    d = np.stack((ms.dx, ms.dy, ms.dz), axis=-1)
    u = np.flatnonzero(use_win)
    e1x, e1y, e1z, e2x, e2y, e2z = tangent_frame_kernel(*normal[u].T, NP)
    ca, sa = np.cos(angle[u]), np.sin(angle[u])
    d[u] = np.stack((ca * e1x + sa * e2x, ca * e1y + sa * e2y, ca * e1z + sa * e2z), axis=-1)
    return EvidenceStates(state, evidence, d, angle, angle_std, angle_noise_std, h_ratio, f_ratio)


class EvidenceTracker:
    """The stage of :func:`evidence_states`, one sample at a time.

    Running sums of the products since the segment's start and, for each sample of the last
    ``evidence_window`` seconds, its time and the sums before it: window sums are
    differences, as in the batch. Plain float arithmetic (:func:`softtip.core.evidence.window_floats`
    written out: the same operations, so the same results to rounding), O(1) per sample.
    """

    def __init__(self, config: EstimatorConfig, noise: SensorNoise, corr: float):
        self.config = config
        self.noise = noise
        self.corr = corr
        self._sq = NoiseSquares(noise)
        self._geo: PointGeometry | None = None
        self._constants: dict[float, tuple[float, float, float]] = {}
        enter, leave = config.area_ratio
        self._enter, self._leave = enter, leave
        self._on = config.line_evidence
        self._window = config.evidence_window
        self._h_sigmas, self._h_min = config.h_sigmas, config.h_min
        self._fmin2 = config.excitation_min * config.excitation_min
        self._hmin2 = config.h_min * config.h_min
        self._f_ratio = config.excitation_ratio
        self._max_std = config.evidence_max_angle_std
        self._model_var = config.evidence_model_std * config.evidence_model_std
        self._unconfirmed_var = config.unconfirmed_model_std * config.unconfirmed_model_std
        self._reset2 = config.evidence_reset_distance * config.evidence_reset_distance
        self._vote_window = config.significance_window
        self._area_share = config.area_share
        self._rocked = config.rocked
        self.start_segment()

    def start_segment(self) -> None:
        """At contact onset and at a re-latch: empty window, no verdict, no held direction."""
        self._cum = (0.0,) * N_SUMS
        self._hist: deque[tuple[float, tuple]] = deque()
        self._verdict = _UNKNOWN
        # angle, its std, the noise's share, and whether the load showed the two axes
        self._held: tuple[float, float, float, bool] | None = None
        self._sig = False
        self._anchor: tuple | None = None
        # the segment's samples of the last significance_window s: (t, side), and how many
        # are above the threshold and below its leaving share
        self._votes: deque[tuple[float, int]] = deque()
        self._n_above = self._n_below = 0
        # the segment's samples of the last evidence_window s: (t, h spread over both axes)
        # and how many are
        self._areas: deque[tuple[float, bool]] = deque()
        self._n_area = 0

    def step(self, t, geo: PointGeometry, ex, ey, ez, hx, hy, hz, fx, fy, fz, hn, h_std):
        """``(state, evidence, direction, angle, angle_std, angle_noise_std, h_ratio, f_ratio)`` of a located
        sample at the contact point of ``geo``, with ``h`` (N·m) taken about ``e`` (m; the
        point, or the effective point under the depth), the force ``f`` (N), ``hn = |h|``
        and ``h_std`` ``h``'s noise level (N·m) of the measurement stage."""
        if not self._on:
            thr = self._h_sigmas * h_std
            if hn > (self._h_min if self._h_min > thr else thr):  # the measurement's line test
                dx, dy, dz, angle, a = sample_direction(hx, hy, hz, hn, ex, ey, ez, geo, self._sq)
                return "line", "unconfirmed", (dx, dy, dz), angle, a, a, math.nan, math.nan
            return "point", "", _NAN3, math.nan, math.nan, math.nan, math.nan, math.nan
        point = geo.point
        anchor = self._anchor
        if anchor is None:
            self._anchor = point
        elif point is not anchor:
            dx, dy, dz = point[0] - anchor[0], point[1] - anchor[1], point[2] - anchor[2]
            if dx * dx + dy * dy + dz * dz > self._reset2:  # the contact moved: a new segment
                self.start_segment()
                self._anchor = point
        if geo is not self._geo:  # per point: once per latch
            self._geo = geo
            self._noise_terms = tangent_noise_kernel(*point, *geo.frame, self.noise)
            self._noise_k = noise_constants(self._noise_terms)
        e1x, e1y, e1z, e2x, e2y, e2z = geo.frame
        h1 = hx * e1x + hy * e1y + hz * e1z
        h2 = hx * e2x + hy * e2y + hz * e2z
        f1 = fx * e1x + fy * e1y + fz * e1z
        f2 = fx * e2x + fy * e2y + fz * e2z
        hist = self._hist
        c0, c1, c2, c3, c4, c5, c6, c7, c8, c9 = cum = self._cum
        hist.append((t, cum))
        c0, c1, c2, c3, c4 = c0 + h1, c1 + h2, c2 + h1 * h1, c3 + h1 * h2, c4 + h2 * h2
        c5, c6, c7, c8, c9 = c5 + f1, c6 + f2, c7 + f1 * f1, c8 + f1 * f2, c9 + f2 * f2
        self._cum = (c0, c1, c2, c3, c4, c5, c6, c7, c8, c9)
        start = t - self._window
        while hist and hist[0][0] <= start:
            hist.popleft()
        count = float(len(hist))
        k = self._constants.get(count)
        if k is None:
            k = self._constants[count] = window_constants(count, self.corr)
        tail, keep, nu = k
        s_big, s2, f_n = self._noise_k
        h11, h12, h22, f11, f12, f22 = self._noise_terms
        # the covariances and eigenvalues of window_kernel; window sums are differences
        if hist:
            o = hist[0][1]
            s1, s2_, s11, s12, s22 = c0 - o[0], c1 - o[1], c2 - o[2], c3 - o[3], c4 - o[4]
            t1, t2, t11, t12, t22 = c5 - o[5], c6 - o[6], c7 - o[7], c8 - o[8], c9 - o[9]
            m1, m2 = s1 / count, s2_ / count
            c11 = s11 / count - m1 * m1 - keep * h11
            c12 = s12 / count - m1 * m2 - keep * h12
            c22 = s22 / count - m2 * m2 - keep * h22
            n1, n2 = t1 / count, t2 / count
            g11 = t11 / count - n1 * n1 - keep * f11
            g12 = t12 / count - n1 * n2 - keep * f12
            g22 = t22 / count - n2 * n2 - keep * f22
        else:  # an empty window (t − T rounds to t): no covariance, as the batch's 0 / 0
            c11 = c12 = c22 = g11 = g12 = g22 = math.nan
        half = 0.5 * (c11 - c22)
        mean = 0.5 * (c11 + c22)
        root = sqrt(half * half + c12 * c12)
        major, minor = mean + root, mean - root
        gh = 0.5 * (g11 - g22)
        gm = 0.5 * (g11 + g22)
        gr = sqrt(gh * gh + g12 * g12)
        f_major, f_minor = gm + gr, gm - gr
        # clamped at zero (NaN too)
        if not major > 0.0:
            major = 0.0
        if not minor > 0.0:
            minor = 0.0
        if not f_major > 0.0:
            f_major = 0.0
        if not f_minor > 0.0:
            f_minor = 0.0
        h_noise, f_noise = tail * s_big, tail * f_n
        # _decide, unrolled (NaN comparisons are False, as in the batch)
        varied = major > h_noise
        if varied:
            h_ratio = minor / major if major != 0.0 else _div(minor, major)
        else:
            h_ratio = math.nan
        if f_major > f_noise:
            f_ratio = f_minor / f_major if f_major != 0.0 else _div(f_minor, f_major)
        else:
            f_ratio = math.nan
        thr = self._h_sigmas * h_std
        thr = thr if thr > self._h_min else self._h_min
        spread = (
            minor > h_noise and h_ratio >= self._enter and hn > thr
            and ((f_minor > f_noise and f_minor >= self._fmin2) or minor >= self._hmin2)
        )  # fmt: skip
        # area: more than area_share of the window's samples spread over both axes (the batch's vote)
        areas = self._areas
        areas.append((t, spread))
        self._n_area += spread
        start = t - self._window
        while len(areas) > 1 and areas[0][0] <= start:
            self._n_area -= areas.popleft()[1]
        area = self._n_area > self._area_share * len(areas)
        axis = None  # the current window's direction, where h varied along one axis
        confirming = False  # the current window confirms the line (two-axis excitation)
        if area:
            self._verdict = _AREA
            self._held = None
        else:
            one_axis = varied and h_ratio < self._leave
            excited = f_minor > f_noise and f_minor >= self._f_ratio * f_major and f_minor >= self._fmin2
            line_now = one_axis and (excited or (bool(self._rocked) and bool(self.config.stated_excitation(t))))
            if line_now:
                self._verdict = _LINE
            if one_axis:
                e = (major, minor, c11, c12, c22, root, g11, g12, f_major, f_minor, g22, half)
                w_angle, w_std, w_noise = window_direction_floats(e, s2, nu)
                if w_std <= self._max_std:
                    if major >= self._hmin2:
                        axis = (w_angle, w_std, w_noise)
                    if line_now:
                        # the two-axis model error where the load showed the two axes
                        confirming = excited
                        model = self._model_var if excited else self._unconfirmed_var
                        self._held = (w_angle, math.sqrt(w_std * w_std + model), w_noise, excited)
        side = 1 if hn > thr else (0 if hn <= SIG_LEAVE * thr else -1)
        if self._vote_window > 0.0:
            votes = self._votes
            votes.append((t, side))
            self._n_above += side == 1
            self._n_below += side == 0
            start = t - self._vote_window
            while len(votes) > 1 and votes[0][0] <= start:
                old = votes.popleft()[1]
                self._n_above -= old == 1
                self._n_below -= old == 0
            m = len(votes)
            side = 1 if 2 * self._n_above > m else (0 if 2 * self._n_below > m else -1)
        if side >= 0:
            self._sig = side == 1
        verdict = self._verdict
        if area:
            return "area", "", _NAN3, math.nan, math.nan, math.nan, h_ratio, f_ratio
        if verdict == _LINE and self._held is not None and axis is None:
            angle, angle_std, noise_std, _ = self._held
            ca, sa = cos(angle), sin(angle)
            d = (ca * e1x + sa * e2x, ca * e1y + sa * e2y, ca * e1z + sa * e2z)
            return "line", "confirmed", d, angle, angle_std, noise_std, h_ratio, f_ratio
        if not self._sig and axis is None:
            return "point", "", _NAN3, math.nan, math.nan, math.nan, h_ratio, f_ratio
        evidence = "confirmed" if verdict == _LINE else "unconfirmed"
        if axis is not None:  # the current window resolves the axis
            angle, w_std, noise_std = axis
            ca, sa = cos(angle), sin(angle)
            d = (ca * e1x + sa * e2x, ca * e1y + sa * e2y, ca * e1z + sa * e2z)
            v = w_std * w_std + (self._model_var if confirming else self._unconfirmed_var)
            return "line", evidence, d, angle, sqrt(v), noise_std, h_ratio, f_ratio
        # the sample's own direction, the window's across-axis spread counted as model error
        dx, dy, dz, angle, a = sample_direction(hx, hy, hz, hn, ex, ey, ez, geo, self._sq)
        v = hn * hn
        held = self._held
        by_load = verdict == _LINE and held is not None and held[3]
        v = a * a + (minor / v if v != 0.0 else _div(minor, v)) + (0.0 if by_load else self._unconfirmed_var)
        return "line", evidence, (dx, dy, dz), angle, sqrt(v) if v >= 0.0 else math.nan, a, h_ratio, f_ratio
