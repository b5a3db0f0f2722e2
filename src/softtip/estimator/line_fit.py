"""The ``line-fit`` contact-point stage, batch and stream side by side.

The latch, then the contact point moved across the line to where a window of the last
``line_fit_window`` seconds fits the line-contact model (the maths is in
:mod:`softtip.core.line_fit`). A window is accepted when its standard deviations of line angle and
offset are below ``line_fit_max_angle_std`` and ``line_fit_max_offset_std`` and its fit residual
below ``line_fit_max_residual`` noise standard deviations. The point held is the accepted
window since contact onset (or the last re-latch) with the smallest standard deviation aged
by ``line_fit_drift``; before the first one the latched point is used. The coordinate along
the line is the latch's: a line contact does not tell it.

:func:`line_fit_points` does it for a whole log, :class:`LineFitTracker` one sample at a time.
"""

from __future__ import annotations

import math
from collections import deque
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from softtip.core._xp import NP, PY
from softtip.core.depth import depth_kernel
from softtip.core.fingertip import Fingertip
from softtip.core.line_fit import N_SUMS, line_fit_products, line_fit_solve_kernel
from softtip.core.location import SoftFinger, contact_kernel
from softtip.core.noise import SensorNoise
from softtip.core.spin import spin_torque_kernel
from softtip.estimator.config import EstimatorConfig

__all__ = ["line_fit_points", "LineFitPoints", "LineFitTracker", "line_fit_accept", "line_fit_moment"]

_NAN4 = (math.nan,) * 4


class LineFitPoints(NamedTuple):
    """What :func:`line_fit_points` gives for a whole log (N samples)."""

    point: NDArray  #: (N, 3) m, the contact point: the accepted window's, else the latch's
    stats: NDArray  #: (4, N) the window ending at each sample: conditioning, angle std (rad), offset std (m), residual (σ)
    use: NDArray  #: (N,) bool, the window ending here became the one held
    moved: NDArray  #: (N,) bool, the point is a window's, not the latch's


def line_fit_moment(fx, fy, fz, mx, my, mz, nx, ny, nz, ax, ay, az, law, xp):
    """Moment about the anchor ``a`` that enters the line-fit sums, component-wise.

    With a depth law the moment is first moved to the undeformed surface, ``m + δ n × f``,
    so that the surface point is fitted; ``n`` is the normal at the latched point (the
    sample's own soft-finger normal before there is one), which carries no sensor noise.
    """
    if law is not None:
        delta = depth_kernel(-(fx * nx + fy * ny + fz * nz), law, xp)
        mx = mx + delta * (ny * fz - nz * fy)
        my = my + delta * (nz * fx - nx * fz)
        mz = mz + delta * (nx * fy - ny * fx)
    return spin_torque_kernel(fx, fy, fz, mx, my, mz, ax, ay, az)


def line_fit_accept(cond, angle_std, offset_std, residual, config: EstimatorConfig):
    # written so that NaN (undefined window) is never accepted, in both back ends
    return (
        (angle_std <= config.line_fit_max_angle_std)
        & (offset_std <= config.line_fit_max_offset_std)
        & (residual <= config.line_fit_max_residual)
        & (cond >= 0.0)
    )



def line_fit_points(t, c, contact, sc, base, relatched, tip: Fingertip, config: EstimatorConfig, noise: SensorNoise, corr) -> LineFitPoints:
    """``line-fit`` mode over a whole log, vectorised within each contact.

    ``c`` are the six wrench components, ``sc`` the soft-finger solutions, ``base`` the
    latched points (N, 3) (start of each solve; their coordinate along the line is kept).
    Returns ``(point (N, 3), stats (4, N), used (N,), moved (N,))``: ``used`` marks the
    windows that became the held point, ``moved`` the samples whose point is a line-fit one
    (the latched one elsewhere).
    """
    n = len(t)
    valid = contact & np.asarray(sc.valid, dtype=bool)
    stats = np.full((4, n), np.nan)
    jp = np.full((n, 3), np.nan)
    edges = np.diff(np.concatenate(([False], contact, [False])).astype(np.int8))
    for s, e in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)):
        v = np.flatnonzero(valid[s:e]) + s
        if not len(v):
            continue
        anchor = [float(c[v[0]]) for c in sc.point]  # first soft-finger point of the contact
        normal = np.stack([c[v] for c in sc.normal], axis=-1)
        if config.skin_law is not None:
            has = np.all(np.isfinite(base[v]), axis=-1)
            normal[has] = tip.normal(base[v][has])
        qa = line_fit_moment(*(ci[v] for ci in c), *normal.T, *anchor, config.skin_law, NP)
        tv = t[v]
        # window of sample k: the valid samples i with t_i > t_k − T (the stream's test)
        first = np.searchsorted(tv, tv - config.line_fit_window, side="right")
        last = np.arange(1, len(v) + 1)
        sums = []
        for p in line_fit_products(c[0][v], c[1][v], c[2][v], *qa):
            cz = np.concatenate(([0.0], np.cumsum(p)))  # sequential, as the stream's running sums
            sums.append(cz[last] - cz[first])
        ok = np.all(np.isfinite(base[v]), axis=-1)
        count = (last - first).astype(float)
        out = line_fit_solve_kernel(sums, count, *base[v].T, *anchor, tip, config.line_fit_iterations, noise, corr, NP)
        jp[v[ok]] = np.stack(out[:3], axis=-1)[ok]
        stats[:, v[ok]] = np.stack(out[6:10])[:, ok]
    with np.errstate(invalid="ignore"):
        accept = valid & line_fit_accept(*stats, config) & np.all(np.isfinite(jp), axis=-1)
    # the point held is the accepted window with the smallest offset_std² + drift² · age: an
    # accepted window replaces it when key = offset_std² − drift² (t − t_segment) sets a new
    # minimum (as the stream decides, sample by sample). A segment starts at contact onset
    # and at every re-latch.
    begin = np.concatenate((contact[:1], contact[1:] & ~contact[:-1])) | (relatched & contact)
    use = np.zeros(n, dtype=bool)
    held_at = np.full(n, -1)
    starts = np.flatnonzero(begin)
    for a, b in zip(starts, np.append(starts[1:], n)):
        with np.errstate(invalid="ignore"):
            key = np.where(accept[a:b], stats[2, a:b] ** 2 - config.line_fit_drift**2 * (t[a:b] - t[a]), np.inf)
        best = np.concatenate(([np.inf], np.minimum.accumulate(key)[:-1]))
        use[a:b] = key < best
        held_at[a:b] = np.maximum.accumulate(np.where(use[a:b], np.arange(a, b), -1))
    moved = contact & (held_at >= 0)
    point = base.copy()
    point[moved] = jp[held_at[moved]]
    return LineFitPoints(point, stats, use, moved)


class LineFitTracker:
    """The ``line-fit`` stage of :func:`line_fit_points`, one sample at a time.

    Running sums of the line-fit products since contact onset and, for each valid sample of the
    last ``line_fit_window`` seconds, its time and the sums before it: window sums are
    differences, as in the batch.
    """

    def __init__(self, tip: Fingertip, config: EstimatorConfig, noise: SensorNoise, corr: float):
        self.tip = tip
        self.config = config
        self.noise = noise
        self.corr = corr

    def start_contact(self) -> None:
        """At contact onset: empty sums and window."""
        self._anchor: tuple[float, float, float] | None = None
        self._cum = [0.0] * N_SUMS
        self._hist: deque[tuple[float, list[float]]] = deque()

    def start_segment(self, t: float) -> None:
        """At contact onset and at a re-latch: no window held yet."""
        self._held: tuple[float, float, float] | None = None
        self._key = math.inf
        self._t_segment = t

    def step(self, t: float, x: list[float], point, sc):
        """``(point, (conditioning, angle_std, offset_std, residual), moved)`` of a sample in
        contact whose latch stage gave ``point`` (or ``None``); ``sc`` as in
        :meth:`softtip.estimator.latch.LatchTracker.step`."""
        cfg = self.config
        stats = _NAN4
        if sc is None:
            sc = SoftFinger(*contact_kernel(self.tip, *x, xp=PY))
        if sc.valid:
            if self._anchor is None:
                self._anchor = sc.point
            ax, ay, az = self._anchor
            nx, ny, nz = sc.normal
            if cfg.skin_law is not None and point is not None:
                nx, ny, nz = self.tip._normal_kernel(*point, PY)
            qa = line_fit_moment(*x, nx, ny, nz, ax, ay, az, cfg.skin_law, PY)
            hist = self._hist
            hist.append((t, self._cum))
            self._cum = [c + p for c, p in zip(self._cum, line_fit_products(x[0], x[1], x[2], *qa))]
            start = t - cfg.line_fit_window
            while hist and hist[0][0] <= start:
                hist.popleft()
            if point is not None:
                # an empty window (t − T rounds to t) has zero sums, as in the batch
                sums = [c - o for c, o in zip(self._cum, hist[0][1] if hist else self._cum)]
                out = line_fit_solve_kernel(
                    sums, float(len(hist)), *point, ax, ay, az, self.tip, cfg.line_fit_iterations, self.noise,
                    self.corr, PY,
                )  # fmt: skip
                stats = out[6:10]
                if line_fit_accept(*stats, cfg) and math.isfinite(out[0] + out[1] + out[2]):
                    key = stats[2] ** 2 - cfg.line_fit_drift**2 * (t - self._t_segment)
                    if key < self._key:
                        self._key, self._held = key, out[:3]
        if self._held is not None:
            return self._held, stats, True
        return point, stats, False
