"""The latched contact point (paper III-C), batch and stream side by side.

During the first rise of the force after onset (until ``|f|`` first exceeds the light-force
window, or sets no new maximum for ``stall_time``), the soft-finger solutions of the samples
inside the window are averaged; that mean, put back on the skin, is the contact point from
then on, until contact ends. Before the first window sample the current soft-finger solution
is used. With no window sample in the whole rise, the mean of the first ``fallback_samples``
solutions of the contact is latched and flagged.

Re-latching (``relatch_distance``): once the latch is held, a sample at light force whose
soft-finger solution lies farther than this from the latched point starts a new first rise.

:func:`latch_points` does it for a whole log (vectorised within each contact);
:class:`LatchTracker` one sample at a time.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from softtip.core._jit import jit_enabled
from softtip.core._xp import NP, PY
from softtip.core.fingertip import Fingertip
from softtip.core.location import SoftFinger, contact_kernel
from softtip.estimator.config import EstimatorConfig
from softtip.estimator.sequential import latch_scan_kernel

__all__ = ["latch_points", "LatchedPoints", "LatchTracker"]


class LatchedPoints(NamedTuple):
    """What :func:`latch_points` gives for a whole log (N samples)."""

    point: NDArray  #: (N, 3) m, the contact point held (NaN where there is none)
    latched: NDArray  #: (N,) bool, the samples the latch averaged
    fallback: NDArray  #: (N,) bool, latched on the first samples: no light-force phase
    relatched: NDArray  #: (N,) bool, a new latch starts here (re-latch, or a contact after a latched one)


def _latch_segment(t, f_norm, valid, r_sc, tip: Fingertip, config: EstimatorConfig):
    """The latch of one segment (a contact, or its rest after a re-latch), vectorised.

    The segment's first sample starts a first rise. Returns ``(point (k, 3), latched (k,),
    fallback (k,), held (k,), latch point (3,))``, where ``held`` marks the samples that
    start with the latch already fixed (where a drift re-latch may happen).
    """
    k = len(t)
    lo, hi = config.latch_window
    idx = np.arange(k)
    prev_peak = np.concatenate(([-np.inf], np.maximum.accumulate(f_norm)[:-1]))
    t_peak = t[np.maximum.accumulate(np.where(f_norm > prev_peak, idx, 0))]
    rise_over = (f_norm > hi) | (t - t_peak > config.stall_time)
    end = int(np.argmax(rise_over)) if rise_over.any() else k
    win = (idx < end) & (f_norm >= lo) & (f_norm <= hi) & valid
    n_win = np.cumsum(win)
    sum_win = np.cumsum(np.where(win[:, None], r_sc, 0.0), axis=0)
    fb = valid & (np.cumsum(valid) <= config.fallback_samples)
    n_fb = np.cumsum(fb)
    sum_fb = np.cumsum(np.where(fb[:, None], r_sc, 0.0), axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean_win = tip.project(sum_win / n_win[:, None])
        mean_fb = tip.project(sum_fb / n_fb[:, None])
    total_win = n_win[end - 1] if end > 0 else 0
    rising = idx < end
    pe = np.where((rising & (n_win > 0))[:, None], mean_win, r_sc)
    if total_win > 0:
        pe[~rising] = mean_win[end - 1]
        lat = rising & (n_win > 0) | ~rising
        fbk = np.zeros(k, dtype=bool)
        fixed, latch = end, mean_win[end - 1]
    else:
        after = ~rising
        pe[after] = np.where((n_fb[after] > 0)[:, None], mean_fb[after], np.nan)
        lat = after & (n_fb > 0)
        fbk = lat
        # the stream fixes the fallback latch once it has all its samples
        done = after & (n_fb >= config.fallback_samples)
        fixed = int(np.argmax(done)) if done.any() else k
        latch = mean_fb[fixed] if fixed < k else np.full(3, np.nan)
    return pe, lat, fbk, idx > fixed, latch


def latch_points(t, f_norm, contact, sc, tip: Fingertip, config: EstimatorConfig, had_latch: bool = False) -> LatchedPoints:
    """Contact point per sample in ``latch`` mode, with re-latching.

    Returns :class:`LatchedPoints`. Long logs: one compiled pass
    over all contacts (:func:`_latch_compiled`); short ones: one iteration per contact and
    per re-latch, vectorised within each. ``had_latch``: a contact before these samples (an
    earlier piece of the log) had a latch.
    """
    n = len(t)
    if jit_enabled(n):
        return _latch_compiled(t, f_norm, contact, sc, tip, config, had_latch)
    point = np.full((n, 3), np.nan)
    latched = np.zeros(n, dtype=bool)
    fallback = np.zeros(n, dtype=bool)
    relatched = np.zeros(n, dtype=bool)
    valid = np.asarray(sc.valid, dtype=bool)
    r_sc = np.where(valid[:, None], np.stack(sc.point, axis=-1), np.nan)
    lo, hi = config.latch_window
    dist = config.relatch_distance
    edges = np.diff(np.concatenate(([False], contact, [False])).astype(np.int8))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    for s, e in zip(starts, stops):
        relatched[s] = had_latch  # contact regained after a latched one
        a = s
        while True:
            pe, lat, fbk, held, latch = _latch_segment(t[a:e], f_norm[a:e], valid[a:e], r_sc[a:e], tip, config)
            stop = e - a
            if dist is not None and held.any():
                fe = f_norm[a:e]
                dx, dy, dz = (r_sc[a:e, i] - latch[i] for i in range(3))
                with np.errstate(invalid="ignore"):
                    drift = held & valid[a:e] & (fe >= lo) & (fe <= hi) & (dx * dx + dy * dy + dz * dz > dist * dist)
                if drift.any():
                    stop = int(np.argmax(drift))
            point[a : a + stop], latched[a : a + stop], fallback[a : a + stop] = pe[:stop], lat[:stop], fbk[:stop]
            if stop == e - a:
                break
            a += stop
            relatched[a] = True
        had_latch = had_latch or bool(latched[s:e].any())
    return LatchedPoints(point, latched, fallback, relatched)



def _projected_means(tip: Fingertip, sums, counts, use):
    """``(k, means)``: the samples ``use`` (indices, increasing) and ``sums / counts`` there
    put back on the skin, (len(k), 3) (only where used: no (N, 3) array)."""
    k = np.flatnonzero(use)
    with np.errstate(invalid="ignore", divide="ignore"):
        return k, np.stack(tip._project_kernel(*(sums[:, k] / counts[k]), NP), axis=-1)


def _means_at(k, means, rows):
    """The means of :func:`_projected_means` at the samples ``rows``, (len(rows), 3) (NaN
    at samples it did not use)."""
    out = np.full((len(rows), 3), np.nan)
    if len(k):
        pos = np.minimum(np.searchsorted(k, rows), len(k) - 1)
        hit = k[pos] == rows
        out[hit] = means[pos[hit]]
    return out


def _latch_compiled(t, f_norm, contact, sc, tip: Fingertip, config: EstimatorConfig, had_latch: bool = False):
    """:func:`latch_points` over all contacts at once: the running sums of every segment in
    one compiled pass, the projections and the choices vectorised; with re-latching, one
    more pass for each re-latch that follows another in the same contact."""
    n = len(t)
    valid = np.asarray(sc.valid, dtype=bool)
    rx, ry, rz = (np.where(valid, np.asarray(c, dtype=float), np.nan) for c in sc.point)
    lo, hi = config.latch_window
    dist = config.relatch_distance
    onset = contact & ~np.concatenate(([False], contact[:-1]))
    begin = onset.copy()
    idx = np.arange(n)
    if not onset.any():
        return LatchedPoints(np.full((n, 3), np.nan), np.zeros(n, dtype=bool), np.zeros(n, dtype=bool), np.zeros(n, dtype=bool))
    while True:
        n_win = np.zeros(n, dtype=np.int64)
        n_fb = np.zeros(n, dtype=np.int64)
        sum_win = np.zeros((3, n))
        sum_fb = np.zeros((3, n))
        rising = np.zeros(n, dtype=bool)
        n_seg = int(np.count_nonzero(begin))
        seg_end, seg_fixed, seg_total, seg_stop = (np.zeros(n_seg, dtype=np.int64) for _ in range(4))
        latch_scan_kernel(
            begin, contact, t, f_norm, valid, rx, ry, rz, float(lo), float(hi), float(config.stall_time),
            int(config.fallback_samples), n_win, sum_win, n_fb, sum_fb, rising, seg_end, seg_fixed, seg_total, seg_stop,
        )  # fmt: skip
        # the latch of each segment: the rise's window mean, else the fallback mean once fixed
        by_window = seg_total > 0
        fb_fixed = ~by_window & (seg_fixed < seg_stop)
        sid = np.where(contact, np.cumsum(begin) - 1, 0)  # segment of each sample in contact
        win_seg = by_window[sid]
        after = contact & ~rising
        # the means, projected on the skin, where they are used
        use_win = contact & rising & (n_win > 0)
        use_win[seg_end[by_window] - 1] = True
        use_fb = after & ~win_seg & (n_fb > 0)
        use_fb[seg_fixed[fb_fixed]] = True
        mean_win = _projected_means(tip, sum_win, n_win, use_win)
        mean_fb = _projected_means(tip, sum_fb, n_fb, use_fb)
        del sum_win, sum_fb, use_win, use_fb  # (N, 3) temporaries set the peak memory
        latch = np.full((n_seg, 3), np.nan)
        latch[by_window] = _means_at(*mean_win, seg_end[by_window] - 1)
        latch[fb_fixed] = _means_at(*mean_fb, seg_fixed[fb_fixed])
        # the point assembled in place, each choice over the one before (as nested np.where)
        point = None  # the last pass's, dropped first
        point = np.stack((rx, ry, rz), axis=-1)
        m = np.flatnonzero(rising & (n_win > 0))
        point[m] = _means_at(*mean_win, m)
        m = after & win_seg
        point[m] = latch[sid[m]]
        m = np.flatnonzero(after & ~win_seg)
        v = _means_at(*mean_fb, m)
        v[n_fb[m] == 0] = np.nan
        point[m] = v
        del mean_win, mean_fb, m, v
        latched = np.where(win_seg, rising & (n_win > 0) | after, after & (n_fb > 0)) & contact
        fallback = latched & ~win_seg
        if dist is None:
            break
        held = contact & (idx > seg_fixed[sid])
        with np.errstate(invalid="ignore"):
            dx, dy, dz = rx - latch[sid, 0], ry - latch[sid, 1], rz - latch[sid, 2]
            drift = held & valid & (f_norm >= lo) & (f_norm <= hi) & (dx * dx + dy * dy + dz * dz > dist * dist)
        # the first drift of each segment starts a new one (a re-latch)
        d = np.flatnonzero(drift)
        new = d[np.r_[True, sid[d][1:] != sid[d][:-1]]] if len(d) else d
        if not len(new):
            break
        begin[new] = True
    point[~contact] = np.nan
    relatched = begin & ~onset
    # contact regained after a latched one
    had = (np.concatenate(([0], np.cumsum(latched)))[np.flatnonzero(onset)] > 0) | had_latch
    relatched[np.flatnonzero(onset)] = had
    return LatchedPoints(point, latched, fallback, relatched)


class LatchTracker:
    """The latch of :func:`latch_points` for one contact, one sample at a time.

    Call :meth:`start` at contact onset (and at a re-latch), then :meth:`step` for every
    sample in contact. Soft-finger solutions (``sc``, the 8-tuple of
    :func:`softtip.core.location.contact_kernel`) are computed only when needed and handed back
    for reuse.
    """

    def __init__(self, tip: Fingertip, config: EstimatorConfig):
        self.tip = tip
        self.config = config
        self.point: tuple[float, float, float] | None = None
        self.is_fallback = False

    def start(self, f_norm: float, t: float) -> None:
        """A new first rise at force ``f_norm`` (N) and time ``t`` (s)."""
        self.rising = True
        self._peak = f_norm
        self._t_peak = t
        self._n_win = 0
        self._sum_win = [0.0, 0.0, 0.0]
        self._n_fb = 0
        self._sum_fb = [0.0, 0.0, 0.0]
        self.point = None  # the latched point once fixed
        self.is_fallback = False

    def drifted(self, f_norm: float, x: list[float], sc):
        """Re-latch test of a held latch: ``(moved, sc)``; ``moved`` when, at light force,
        this sample's soft-finger solution lies farther than ``relatch_distance`` from it."""
        dist = self.config.relatch_distance
        lo, hi = self.config.latch_window
        if self.point is None or dist is None or not lo <= f_norm <= hi:
            return False, sc
        sc = SoftFinger(*contact_kernel(self.tip, *x, xp=PY))
        if not sc.valid:
            return False, sc
        lx, ly, lz = self.point
        dx, dy, dz = sc.rx - lx, sc.ry - ly, sc.rz - lz
        return dx * dx + dy * dy + dz * dz > dist * dist, sc

    def step(self, t: float, f_norm: float, x: list[float], sc):
        """The contact point of a sample in contact: ``(point, latched, fallback, sc)``.

        ``point`` is ``None`` when there is none yet (no valid soft-finger solution)."""
        cfg = self.config
        if self.rising and f_norm > self._peak:
            self._peak, self._t_peak = f_norm, t
        point = self.point
        if point is not None:
            return point, True, self.is_fallback, sc
        if sc is None:
            sc = SoftFinger(*contact_kernel(self.tip, *x, xp=PY))
        fallback = False
        valid = sc.valid
        if valid and self._n_fb < cfg.fallback_samples:
            self._n_fb += 1
            self._sum_fb = [s + v for s, v in zip(self._sum_fb, sc.point)]
        lo, hi = cfg.latch_window
        if self.rising and (f_norm > hi or t - self._t_peak > cfg.stall_time):
            self.rising = False
            if self._n_win > 0:
                self.point = point = self._mean(self._sum_win, self._n_win)
        if self.rising:
            if valid and lo <= f_norm <= hi:
                self._n_win += 1
                self._sum_win = [s + v for s, v in zip(self._sum_win, sc.point)]
            if self._n_win > 0:
                point = self._mean(self._sum_win, self._n_win)
            elif valid:
                point = sc.point
        elif point is None and self._n_fb > 0:
            point = self._mean(self._sum_fb, self._n_fb)
            fallback = True
            if self._n_fb >= cfg.fallback_samples:
                self.point, self.is_fallback = point, True
        latched = point is not None and (self._n_win > 0 or fallback)
        return point, latched, fallback, sc

    def _mean(self, total: list[float], count: int) -> tuple[float, float, float]:
        return self.tip._project_kernel(total[0] / count, total[1] / count, total[2] / count, PY)
