"""The online depth stage (after the contact point, before the measurement), batch and
stream side by side.

Friction acts inside the skin, at a depth ``δ`` below the contact point ``r`` on the
undeformed surface, so the moment is taken about the effective point ``r − δ n``. With
``depth_compensation="online"`` the depth of each contact is ``δ = κ δ₀(F_n)``: ``δ₀`` the skin
law's depth at the normal force (the prior), ``κ`` a factor learnt from the contact's own
data under the line-contact model (the maths is in :mod:`softtip.core.depth`).

Window sums of the per-sample products (:func:`softtip.core.depth.depth_products`) are kept
over the last ``depth_window`` seconds of a *segment*: the run of samples in contact with
one and the same contact point (a new segment at contact onset and whenever the point
changes: during the latch's first rise, at a re-latch, at a move of ``line-fit`` mode). The
window is solved on a grid of ``depth_window / 10`` from the segment's start (and at its
first sample); the factor held is the solved window of the segment with the smallest
variance aged by ``depth_drift``, combined with the prior ``1 ± depth_prior_std`` (at each
solve; the factor and its relative standard deviation hold until the next). Between
solves only the sums and ``δ₀`` are updated, so the stream costs O(1) per sample.

``depth_compensation="law"`` is the fixed law (``κ = 1``, no standard deviation); ``"off"`` the
papers' undeformed point (``δ = 0``).

:func:`depth_points` does it for a whole log, :class:`DepthTracker` one sample at a time.
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from softtip.core._blocks import blockwise
from softtip.core._jit import jit_enabled
from softtip.core._xp import NP, PY
from softtip.core.depth import (
    MIN_DEPTH_SAMPLES,
    MURAKAMI2006_DEPTH,
    N_DEPTH_SUMS,
    DepthLaw,
    depth_frame_kernel,
    depth_kernel,
    depth_noise_kernel,
    depth_products,
    depth_solve_kernel,
    skin_depth_law,
)
from softtip.core.fingertip import Fingertip
from softtip.core.noise import SensorNoise
from softtip.estimator.config import EstimatorConfig
from softtip.estimator.sequential import contact_window_sums_kernel, running_best_kernel

__all__ = ["tip_depth_law", "asked_skin_law", "resolve_depth", "depth_points", "DepthPoints", "DepthTracker", "SOLVES_PER_WINDOW"]


class DepthPoints(NamedTuple):
    """What :func:`depth_points` gives for a whole log (N samples)."""

    depth: NDArray  #: (N,) m, friction acts at ``r − depth · n`` (0 with the papers' method or no point)
    depth_std: NDArray  #: (N,) m, its standard deviation (0 where the depth is not estimated)
    from_data: NDArray  #: (N,) bool, the data outweighed the skin law's prior

#: Solves per window length (the grid of the window solves).
SOLVES_PER_WINDOW = 10
#: Gauss–Newton steps of a window solve.
DEPTH_ITERATIONS = 4


def tip_depth_law(tip: Fingertip) -> DepthLaw | None:
    """The fingertip's skin law: from its ``skin_thickness`` (the murakami2006 preset has
    5 mm, giving :data:`softtip.core.depth.MURAKAMI2006_DEPTH`), ``None`` without one."""
    h = getattr(tip, "skin_thickness", None)
    return None if h is None else skin_depth_law(h)


def asked_skin_law(mode: str, law: DepthLaw | None, tip: Fingertip | None) -> DepthLaw | None:
    """The skin law of a depth compensation asked for by a user (``softtip`` options, ROS parameters):
    ``law`` when given, and when not, with ``mode`` ``online`` or ``law`` and a fingertip that has no skin
    of its own (or none known yet), the murakami2006 skin; otherwise ``None`` (:func:`resolve_depth`
    takes the fingertip's)."""
    if law is None and mode in ("online", "law") and (tip is None or tip_depth_law(tip) is None):
        return MURAKAMI2006_DEPTH
    return law


def resolve_depth(config: EstimatorConfig, tip: Fingertip) -> EstimatorConfig:
    """``config`` with ``depth_compensation`` decided (``online``, ``law`` or ``off``) and ``skin_law``
    the law it uses (``None`` when off). ``auto`` is ``online`` with a law in ``latch``
    mode; in ``track`` and ``line-fit`` mode it is ``law`` when ``config.skin_law`` is given,
    else ``off``.

    Raises
    ------
    ValueError
        ``online`` or ``law`` asked for with neither ``config.skin_law`` nor a fingertip skin
        thickness.
    """
    mode = config.depth_compensation
    if mode == "auto" and config.contact_point != "latch":
        # track mode has no tangential spin torque; line-fit mode moves the point under a
        # tangential load (a slide), where the depth prior alone turned a measured slide
        # case by 26°: both keep the papers' point unless asked (a law given is used as is)
        mode = "off" if config.skin_law is None else "law"
    if mode == "off":
        return dataclasses.replace(config, skin_law=None, depth_compensation="off")
    law = config.skin_law if config.skin_law is not None else tip_depth_law(tip)
    if law is None:
        if mode == "auto":
            return dataclasses.replace(config, depth_compensation="off")
        raise ValueError(
            f"depth_compensation={mode!r} needs a skin law: give config.skin_law, or a fingertip with a skin_thickness"
        )
    return dataclasses.replace(config, skin_law=law, depth_compensation="online" if mode == "auto" else mode)


def _combine(kappa_h, var_h, prior_std, xp):
    """``(κ, relative std, from_data)`` from the held factor (NaN and inf: none) and the prior."""
    w0 = 1.0 / (prior_std * prior_std)
    wh = xp.where(var_h < math.inf, xp.div(1.0, var_h), 0.0)
    kappa = xp.where(wh > 0.0, xp.div(wh * kappa_h + w0, wh + w0), 1.0)
    return xp.maximum(kappa, 0.0), xp.sqrt(xp.div(1.0, wh + w0)), wh > w0


def depth_points(t, c, contact, point, normal, config: EstimatorConfig, noise: SensorNoise, corr) -> DepthPoints:
    """The depth of every sample (resolved ``config``, see :func:`resolve_depth`).

    ``c`` are the six wrench components, ``point`` and ``normal`` (N, 3) the contact points
    of the contact-point stage (NaN where none). Returns :class:`DepthPoints`; the depth is 0 with the papers' method and where there is no point.
    """
    n = len(t)
    law = config.skin_law
    zero = np.zeros(n)
    if law is None:
        return DepthPoints(zero, zero.copy(), np.zeros(n, dtype=bool))
    has = contact & np.all(np.isfinite(point), axis=-1)
    if config.depth_compensation == "law":
        fx, fy, fz = c[0], c[1], c[2]
        d0 = depth_kernel(-(fx * normal[:, 0] + fy * normal[:, 1] + fz * normal[:, 2]), law, NP)
        return DepthPoints(np.where(has, d0, 0.0), zero.copy(), np.zeros(n, dtype=bool))

    def per_sample(fx, fy, fz, mx, my, mz, rx, ry, rz, nx, ny, nz, ok):
        d0 = np.where(ok, depth_kernel(-(fx * nx + fy * ny + fz * nz), law, NP), 0.0)
        return (d0, *depth_products(fx, fy, fz, mx, my, mz, depth_frame_kernel(rx, ry, rz, nx, ny, nz, NP), d0))

    with np.errstate(invalid="ignore"):
        out = blockwise(per_sample, (*c, *point.T, *normal.T, has), stacked=True)
    d0, prods = out[0], out[1:]
    kappa = np.ones(n)
    rel = np.full(n, config.depth_prior_std)
    from_data = np.zeros(n, dtype=bool)
    same = np.zeros(n, dtype=bool)
    same[1:] = has[1:] & has[:-1] & np.all(point[1:] == point[:-1], axis=-1)
    seg_start = has & ~same
    # the sums run from contact onset (as the stream's), windows start no earlier than
    # their segment
    idx = np.arange(n)
    onset = contact & ~np.concatenate(([False], contact[:-1]))
    onset_of = np.maximum.accumulate(np.where(onset, idx, 0))
    seg_of = np.maximum.accumulate(np.where(seg_start, idx, -1))
    seg_of = np.where(seg_of >= onset_of, seg_of, -1)  # a segment of this contact, or none yet
    t_seg = np.where(seg_of >= 0, t[np.maximum(seg_of, 0)], np.nan)
    # solve on the grid of the segment: at its first sample and when a new cell starts
    step = config.depth_window / SOLVES_PER_WINDOW
    cell = np.floor((t - t_seg) / step)
    prev = np.concatenate(([np.nan], cell[:-1]))
    prev[onset] = np.nan
    solve = has & (seg_start | (cell != prev))
    del cell, prev
    k = np.flatnonzero(solve)
    first = np.maximum(np.searchsorted(t, t[k] - config.depth_window, side="right"), seg_of[k])
    count = (k + 1 - first).astype(float)
    # windows too short to inform the depth are not solved (as in the stream)
    big = count >= MIN_DEPTH_SAMPLES
    kb = k[big]
    kw = np.full(len(k), np.nan)
    var = np.full(len(k), np.inf)
    if len(kb):
        sums = _window_sums(onset, has, prods, kb, first[big])
        frame = depth_frame_kernel(*point[kb].T, *normal[kb].T, NP)
        cov = depth_noise_kernel(frame, noise)
        kw[big], var[big] = depth_solve_kernel(sums, count[big], cov, corr, DEPTH_ITERATIONS, NP)
    d0 = d0.copy()  # a view of out would keep all of it (the products) to the end
    del prods, out, first, count, big, kb
    # held: the solved window of the segment with the smallest aged variance; it
    # replaces the one held when var − drift² (t − t_segment) sets a new minimum
    tk, tsk = t[k], t_seg[k]
    del t_seg, onset_of
    with np.errstate(invalid="ignore"):
        key = np.where(var < np.inf, var - config.depth_drift**2 * (tk - tsk), np.inf)
    held = _running_best(seg_of[k], key, n)
    del seg_of
    # the combination at each solve holds until the next one (of the same segment)
    got = held >= 0
    hi = held[got]
    kh = np.full(len(k), np.nan)
    vh = np.full(len(k), np.inf)
    kh[got] = kw[hi]
    vh[got] = key[hi] + config.depth_drift**2 * (tk[got] - tsk[got])
    kc, rc, fc = _combine(kh, vh, config.depth_prior_std, NP)
    last_solve = np.maximum.accumulate(np.where(solve, idx, -1))
    del idx
    pos = np.searchsorted(k, last_solve[has])
    del last_solve
    kappa[has], rel[has], from_data[has] = kc[pos], rc[pos], fc[pos]
    delta = kappa * d0
    delta = np.where(delta > law.max_depth, law.max_depth, delta)
    return DepthPoints(np.where(has, delta, 0.0), np.where(has, rel * d0, 0.0), from_data & has)


def _window_sums(onset, has, prods, k, first):
    """Sums of ``prods`` (M, N) over samples ``first .. k`` (each within one contact) as
    differences of masked running sums from the contact's onset: ``(M, len(k))``."""
    if jit_enabled(onset.shape[0]):
        return contact_window_sums_kernel(onset, has, prods, k, first, np.empty((len(prods), len(k))))
    sums = np.empty((len(prods), len(k)))
    starts = np.flatnonzero(onset)
    which = np.searchsorted(starts, k, side="right") - 1  # the contact of each window
    for w in np.unique(which):
        s = starts[w]
        q = np.flatnonzero(which == w)
        e = k[q[-1]] + 1
        ok = has[s:e]
        for r, p in enumerate(prods):
            cz = np.concatenate(([0.0], np.cumsum(np.where(ok, p[s:e], 0.0))))
            sums[r, q] = cz[k[q] + 1 - s] - cz[first[q] - s]
    return sums


def _running_best(group, key, n: int):
    """Index of the smallest ``key`` so far within each run of equal ``group`` (replaced
    only by a strictly smaller one; -1 before any finite one); ``n`` the log's length."""
    held = np.full(len(key), -1)
    if jit_enabled(n):
        return running_best_kernel(group, key, held)
    cuts = np.flatnonzero(np.diff(group)) + 1
    for a, b in zip(np.r_[0, cuts], np.r_[cuts, len(key)]):
        kk = key[a:b]
        if not np.isfinite(kk).any():
            continue
        best = np.concatenate(([np.inf], np.minimum.accumulate(kk)[:-1]))
        held[a:b] = np.maximum.accumulate(np.where(kk < best, np.arange(a, b), -1))
    return held


class DepthTracker:
    """The online depth of :func:`depth_points`, one sample at a time (O(1) per sample).

    Running sums of the products since contact onset and, for each sample of the current
    segment within the last ``depth_window`` seconds, its time and the sums before it:
    window sums are differences, as in the batch.
    """

    def __init__(self, config: EstimatorConfig, noise: SensorNoise, corr: float):
        self.config = config
        self.law = config.skin_law
        self.online = config.depth_compensation == "online"
        self.noise = noise
        self.corr = corr
        self._step = config.depth_window / SOLVES_PER_WINDOW
        self._window = config.depth_window
        self._sqrt_law = self.law is not None and self.law.exponent == 2.0
        self.start_contact()

    def start_contact(self) -> None:
        """At contact onset."""
        self._cum = (0.0,) * N_DEPTH_SUMS
        self._point = None
        self._hist: deque = deque()

    def gap(self) -> None:
        """A sample in contact without a contact point: the next one starts a segment."""
        self._point = None

    def step(self, t: float, x: list[float], point, normal):
        """``(depth, depth_std, from_data)`` of a sample in contact with contact point
        ``point`` and its normal ``normal``.

        The hot path is written out (the same operations, in the same order, as
        :func:`softtip.core.depth.depth_kernel` and :func:`softtip.core.depth.depth_products`):
        plain float arithmetic is several times cheaper than calls and ``map``."""
        law = self.law
        fx, fy, fz, mx, my, mz = x
        nx, ny, nz = normal
        if self._sqrt_law:
            f_normal = -(fx * nx + fy * ny + fz * nz)
            d0 = math.sqrt(f_normal / law.stiffness) if f_normal > 0.0 else 0.0
            if d0 > law.max_depth:
                d0 = law.max_depth
        else:
            d0 = depth_kernel(-(fx * nx + fy * ny + fz * nz), law, PY)
        if not self.online:
            return d0, 0.0, False
        if point != self._point:  # a new segment
            self._new_segment(t, point, normal)
        cum = self._cum
        hist = self._hist
        hist.append((t, cum))
        t1x, t1y, t1z, t2x, t2y, t2z, a1x, a1y, a1z, a2x, a2y, a2z = self._frame
        h1 = t1x * mx + t1y * my + t1z * mz - (a1x * fx + a1y * fy + a1z * fz)
        h2 = t2x * mx + t2y * my + t2z * mz - (a2x * fx + a2y * fy + a2z * fz)
        g1 = -d0 * (t2x * fx + t2y * fy + t2z * fz)
        g2 = d0 * (t1x * fx + t1y * fy + t1z * fz)
        c0, c1, c2, c3, c4, c5, c6, c7, c8, c9, c10, c11 = cum
        self._cum = (
            c0 + h1 * h1, c1 + h1 * h2, c2 + h2 * h2, c3 + h1 * g1, c4 + h1 * g2, c5 + h2 * g1, c6 + h2 * g2,
            c7 + g1 * g1, c8 + g1 * g2, c9 + g2 * g2, c10 + d0, c11 + d0 * d0,
        )  # fmt: skip
        start = t - self._window
        while hist and hist[0][0] <= start:
            hist.popleft()
        cell = math.floor((t - self._t_seg) / self._step)
        if cell != self._cell:
            self._cell = cell
            self._solve(t)
        kappa, rel, from_data = self._held
        delta = kappa * d0
        return (law.max_depth if delta > law.max_depth else delta), rel * d0, from_data

    def _new_segment(self, t: float, point, normal) -> None:
        self._point = point
        self._frame = depth_frame_kernel(*point, *normal, PY)
        self._cov = depth_noise_kernel(self._frame, self.noise)
        self._hist.clear()
        self._t_seg = t
        self._cell = None
        self._key = math.inf
        self._kappa = math.nan

    def _solve(self, t: float) -> None:
        cfg = self.config
        hist = self._hist
        kw, var = math.nan, math.inf
        if len(hist) >= MIN_DEPTH_SAMPLES:  # shorter windows cannot inform the depth
            old = hist[0][1]
            sums = [a - b for a, b in zip(self._cum, old)]
            kw, var = depth_solve_kernel(sums, float(len(hist)), self._cov, self.corr, DEPTH_ITERATIONS, PY)
        drift2 = cfg.depth_drift**2
        key = var - drift2 * (t - self._t_seg) if var < math.inf else math.inf
        if key < self._key:
            self._key, self._kappa = key, kw
        var_h = self._key + drift2 * (t - self._t_seg) if self._key < math.inf else math.inf
        self._held = _combine(self._kappa, var_h, cfg.depth_prior_std, PY)
