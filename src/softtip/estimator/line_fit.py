"""The ``line-fit`` contact-point stage: one set of step functions for batch and stream.

The latch, then the contact point moved across the line to where a window of the last
``line_fit_window`` seconds fits the line-contact model (the maths is in
:mod:`softtip.core.line_fit`). A window is accepted when its standard deviations of line angle and
offset are below ``line_fit_max_angle_std`` and ``line_fit_max_offset_std`` and its fit residual
below ``line_fit_max_residual`` noise standard deviations. The point held is the accepted
window since contact onset (or the last re-latch) with the smallest standard deviation aged
by ``line_fit_drift``; before the first one the latched point is used. The coordinate along
the line is the latch's: a line contact does not tell it.

One source, split around the kernels that depend on the fingertip's shape (the normal at the
latched point with a depth law, and the window's solve, :func:`line_fit_solve_kernel`), which
are not compiled: one state record (:func:`new_line_fit_state`, and a ring buffer of the
window) and three steps over it,

1. :func:`line_fit_anchor_step`: the anchor of the sums, the contact's first soft-finger point;
2. (the moment about it and its 21 products, :func:`line_fit_moment`) then
   :func:`line_fit_window_step`: running sums since onset and the window's sums as their
   difference from those before the window's first sample;
3. (the solve and :func:`line_fit_accept`) then :func:`line_fit_hold_step`: the accepted window
   with the smallest aged offset standard deviation since the segment's start.

:class:`LineFitTracker` (the stream) calls them per sample with the kernels between
(``xp=PY``); :func:`line_fit_points` (the batch) runs each as a compiled loop over a block of
samples with the kernels vectorised between them (``xp=NP``), the state carried from block to
block.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from softtip.core._blocks import BLOCK, TIME_EDGE, ring_rows
from softtip.core._jit import jitable, lazy_jit
from softtip.core._xp import NP, PY
from softtip.core.depth import depth_kernel
from softtip.core.fingertip import Fingertip
from softtip.core.line_fit import N_SUMS, line_fit_products, line_fit_solve_kernel
from softtip.core.location import SoftFinger, contact_kernel
from softtip.core.noise import SensorNoise
from softtip.core.spin import spin_torque_kernel
from softtip.estimator.config import EstimatorConfig

__all__ = ["line_fit_points", "LineFitPoints", "LineFitTracker", "line_fit_accept", "line_fit_moment",
           "new_line_fit_state", "line_fit_anchor_step", "line_fit_window_step", "line_fit_hold_step"]  # fmt: skip

_NAN4 = (math.nan,) * 4

# the state record's slots
_HAS_ANCHOR = 0  # 1 once the contact had a valid soft-finger point
_AX, _AY, _AZ = 1, 2, 3  # m, the anchor
_HEAD = 4  # the ring buffer's oldest row
_COUNT = 5  # its rows in use: the valid samples of the window, each (t, running sums before it)
_HAS_HELD = 6  # 1 once a window is held in this segment
_HX, _HY, _HZ = 7, 8, 9  # m, its point
_KEY = 10  # its offset_std² − drift² · (t − t_segment)
_T_SEGMENT = 11  # s, the segment's start
_CUM = 12  # N_SUMS running sums of the products since onset
_N_STATE = _CUM + N_SUMS


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


@jitable
def line_fit_accept(cond, angle_std, offset_std, residual, config: EstimatorConfig):
    # written so that NaN (undefined window) is never accepted, in both back ends
    return (
        (angle_std <= config.line_fit_max_angle_std)
        & (offset_std <= config.line_fit_max_offset_std)
        & (residual <= config.line_fit_max_residual)
        & (cond >= 0.0)
    )


def new_line_fit_state() -> NDArray:
    """A line-fit state record before any contact (float64 vector)."""
    state = np.zeros(_N_STATE)
    state[_KEY] = math.inf
    return state


@lazy_jit(nogil=False)
def _start_anchor(state):  # pragma: no cover - compiled
    state[_HAS_ANCHOR] = 0.0


@lazy_jit(nogil=False)
def _start_window(state):  # pragma: no cover - compiled
    state[_HEAD] = 0.0
    state[_COUNT] = 0.0
    for q in range(N_SUMS):
        state[_CUM + q] = 0.0


@lazy_jit(nogil=False)
def line_fit_start_segment(state, t):  # pragma: no cover - compiled
    """At contact onset and at a re-latch (``t``, s): no window held yet."""
    state[_HAS_HELD] = 0.0
    state[_KEY] = np.inf
    state[_T_SEGMENT] = t


@lazy_jit(nogil=False)
def line_fit_anchor_step(state, valid, rx, ry, rz):  # pragma: no cover - compiled
    """The anchor of the sums, ``(ax, ay, az)`` m: the contact's first valid soft-finger point
    ``r`` (NaN before it)."""
    if valid and state[_HAS_ANCHOR] == 0.0:
        state[_HAS_ANCHOR] = 1.0
        state[_AX] = rx
        state[_AY] = ry
        state[_AZ] = rz
    if state[_HAS_ANCHOR] == 0.0:
        return np.nan, np.nan, np.nan
    return state[_AX], state[_AY], state[_AZ]


@lazy_jit(nogil=False)
def line_fit_window_step(state, ring, t, window, prods, sums):  # pragma: no cover - compiled
    """A valid sample at ``t`` (s) with products ``prods`` (N_SUMS,): ``sums`` (N_SUMS,) written
    with the sums of the window of ``window`` s ending here; returns its samples.

    ``ring`` (capacity, 1 + N_SUMS): per valid sample of the window, its time and the running
    sums before it (the oldest at ``_HEAD``); it must have a free row. The window's sums are
    the running sums less those before its first sample (an empty window, ``t − window``
    rounding to ``t``, has zero sums).
    """
    cap = ring.shape[0]
    head = int(state[_HEAD])
    count = int(state[_COUNT])
    k = (head + count) % cap
    ring[k, 0] = t
    for q in range(N_SUMS):
        ring[k, 1 + q] = state[_CUM + q]
        state[_CUM + q] = state[_CUM + q] + prods[q]
    count += 1
    start = t - window + TIME_EDGE
    while count > 0 and ring[head, 0] <= start:
        head = (head + 1) % cap
        count -= 1
    for q in range(N_SUMS):
        c = state[_CUM + q]
        sums[q] = c - (ring[head, 1 + q] if count > 0 else c)
    state[_HEAD] = head
    state[_COUNT] = count
    return count


@lazy_jit(nogil=False)
def line_fit_hold_step(state, t, accepted, offset_std, px, py, pz, drift2):  # pragma: no cover - compiled
    """A sample in contact at ``t`` (s) whose window gave the point ``p`` (m), accepted or not,
    with offset standard deviation ``offset_std`` (m); ``drift2`` is ``line_fit_drift²``.

    Returns ``(use, moved, hx, hy, hz)``: the window becomes the one held (its aged standard
    deviation the smallest of the segment's), a window is held, and its point (m).
    """
    use = False
    if accepted:
        key = offset_std * offset_std - drift2 * (t - state[_T_SEGMENT])
        if key < state[_KEY]:
            use = True
            state[_KEY] = key
            state[_HAS_HELD] = 1.0
            state[_HX] = px
            state[_HY] = py
            state[_HZ] = pz
    if state[_HAS_HELD] == 0.0:
        return use, False, np.nan, np.nan, np.nan
    return use, True, state[_HX], state[_HY], state[_HZ]


@lazy_jit
def _anchor_run(state, onset, valid, rx, ry, rz, anchor):  # pragma: no cover - compiled
    """:func:`line_fit_anchor_step` over a block; ``anchor`` (3, valid samples) written."""
    j = 0
    for i in range(onset.shape[0]):
        if onset[i]:
            _start_anchor(state)
        if valid[i]:
            anchor[0, j], anchor[1, j], anchor[2, j] = line_fit_anchor_step(state, True, rx[i], ry[i], rz[i])
            j += 1
    return anchor


@lazy_jit
def _window_run(state, ring, onset, valid, t, window, prods, sums, count):  # pragma: no cover - compiled
    """:func:`line_fit_window_step` over a block; ``prods`` (valid samples, N_SUMS) in, ``sums``
    (same shape) and ``count`` (valid samples,) written."""
    j = 0
    for i in range(onset.shape[0]):
        if onset[i]:
            _start_window(state)
        if valid[i]:
            count[j] = line_fit_window_step(state, ring, t[i], window, prods[j], sums[j])
            j += 1
    return count


@lazy_jit
def _hold_run(state, contact, begin, t, accepted, offset_std, jp, drift2, point, use, moved):  # pragma: no cover
    """:func:`line_fit_hold_step` over a block of samples; ``jp`` (3, n) the windows' points;
    ``point`` (n, 3) gets the held one where there is one, ``use`` and ``moved`` (n,) written."""
    for i in range(t.shape[0]):
        if not contact[i]:
            continue
        if begin[i]:
            line_fit_start_segment(state, t[i])
        u, m, hx, hy, hz = line_fit_hold_step(state, t[i], accepted[i], offset_std[i], jp[0, i], jp[1, i], jp[2, i],
                                              drift2)  # fmt: skip
        use[i] = u
        moved[i] = m
        if m:
            point[i, 0] = hx
            point[i, 1] = hy
            point[i, 2] = hz
    return moved


def line_fit_points(t, c, contact, sc, base, relatched, tip: Fingertip, config: EstimatorConfig, noise: SensorNoise, corr) -> LineFitPoints:
    """``line-fit`` mode over a whole log.

    ``c`` are the six wrench components, ``sc`` the soft-finger solutions, ``base`` the
    latched points (N, 3) (start of each solve; their coordinate along the line is kept).
    Returns ``(point (N, 3), stats (4, N), used (N,), moved (N,))``: ``used`` marks the
    windows that became the held point, ``moved`` the samples whose point is a line-fit one
    (the latched one elsewhere). Block by block: the three steps' loops with the shape's
    kernels vectorised between them.
    """
    n = len(t)
    t = np.ascontiguousarray(t, dtype=float)
    contact = np.ascontiguousarray(contact, dtype=bool)
    valid = contact & np.asarray(sc.valid, dtype=bool)
    onset = contact & ~np.concatenate(([False], contact[:-1]))
    begin = onset | (relatched & contact)
    r_sc = [np.ascontiguousarray(v, dtype=float) for v in sc.point]
    law, window, drift2 = config.skin_law, float(config.line_fit_window), float(config.line_fit_drift**2)
    state = new_line_fit_state()
    ring = np.zeros((int(ring_rows.function(len(t))(t, window)), 1 + N_SUMS))
    anchor_run, window_run, hold_run = _anchor_run.function(n), _window_run.function(n), _hold_run.function(n)
    point = base.copy()
    stats = np.full((4, n), np.nan)
    use, moved = np.zeros(n, dtype=bool), np.zeros(n, dtype=bool)
    for a in range(0, n, BLOCK):
        b = min(a + BLOCK, n)
        v = np.flatnonzero(valid[a:b]) + a
        anchor = anchor_run(state, onset[a:b], valid[a:b], *(r[a:b] for r in r_sc), np.empty((3, len(v))))
        normal = np.stack([ci[v] for ci in sc.normal], axis=-1)
        with np.errstate(invalid="ignore", divide="ignore"):
            if law is not None:
                has = np.all(np.isfinite(base[v]), axis=-1)
                normal[has] = tip.normal(base[v][has])
            qa = line_fit_moment(*(ci[v] for ci in c), *normal.T, *anchor, law, NP)
            prods = np.stack(line_fit_products(c[0][v], c[1][v], c[2][v], *qa), axis=-1)
            sums, count = np.empty_like(prods), np.empty(len(v))
            window_run(state, ring, onset[a:b], valid[a:b], t[a:b], window, prods, sums, count)
            del prods, qa, normal
            ok = np.all(np.isfinite(base[v]), axis=-1)  # solved: the samples with a latched point
            s = v[ok]
            out = line_fit_solve_kernel(list(sums[ok].T), count[ok], *base[s].T, *anchor[:, ok], tip,
                                        config.line_fit_iterations, noise, corr, NP)  # fmt: skip
            jp = np.full((3, b - a), np.nan)
            jp[:, s - a] = out[:3]
            # NaN as the compiled loops and the stream write it (numpy's square root of a
            # negative gives −NaN): a log's bytes must not depend on the path that ran it
            stats[:, s] = [np.where(np.isnan(v), np.nan, v) for v in out[6:10]]
            accepted = np.zeros(b - a, dtype=bool)
            accepted[s - a] = line_fit_accept(*out[6:10], config) & np.all(np.isfinite(jp[:, s - a]), axis=0)
        hold_run(state, contact[a:b], begin[a:b], t[a:b], accepted, stats[2, a:b], jp, drift2, point[a:b],
                 use[a:b], moved[a:b])  # fmt: skip
    return LineFitPoints(point, stats, use, moved)


class LineFitTracker:
    """The ``line-fit`` stage of :func:`line_fit_points`, one sample at a time (the same steps).

    The ring buffer of the window grows (doubling, oldest first) when full.
    """

    def __init__(
        self, tip: Fingertip, config: EstimatorConfig, noise: SensorNoise, corr: float, *, expected_samples: int | None = None
    ):
        self.tip = tip
        self.config = config
        self.noise = noise
        self.corr = corr
        self._window = float(config.line_fit_window)
        self._drift2 = float(config.line_fit_drift**2)
        self.state = new_line_fit_state()
        self._ring = np.zeros((64, 1 + N_SUMS))
        self._sums = np.zeros(N_SUMS)
        self._held: tuple[float, float, float] | None = None
        n = expected_samples
        self._anchor_step, self._window_step, self._hold_step = (
            line_fit_anchor_step.function(n), line_fit_window_step.function(n), line_fit_hold_step.function(n))  # fmt: skip
        self._start_anchor, self._start_window, self._start_segment = (
            _start_anchor.function(n), _start_window.function(n), line_fit_start_segment.function(n))  # fmt: skip

    def start_contact(self) -> None:
        """At contact onset: empty sums and window."""
        self._start_anchor(self.state)
        self._start_window(self.state)

    def start_segment(self, t: float) -> None:
        """At contact onset and at a re-latch (``t``, s): no window held yet."""
        self._start_segment(self.state, t)
        self._held = None

    def _grow(self) -> None:
        """The ring buffer (full) twice as large, its rows oldest first."""
        ring, state = self._ring, self.state
        head = int(state[_HEAD])
        self._ring = np.concatenate((ring[head:], ring[:head], np.zeros_like(ring)))
        state[_HEAD] = 0.0

    def step(self, t: float, x: list[float], point, sc):
        """``(point, (conditioning, angle_std, offset_std, residual), moved)`` of a sample in
        contact whose latch stage gave ``point`` (or ``None``); ``sc`` as in
        :meth:`softtip.estimator.latch.LatchTracker.step`."""
        cfg = self.config
        state = self.state
        stats = _NAN4
        if sc is None:
            sc = SoftFinger(*contact_kernel(self.tip, *x, xp=PY))
        accepted, offset_std, jx, jy, jz = False, math.nan, math.nan, math.nan, math.nan
        if sc.valid:
            ax, ay, az = self._anchor_step(state, True, sc.rx, sc.ry, sc.rz)
            nx, ny, nz = sc.normal
            if cfg.skin_law is not None and point is not None:
                nx, ny, nz = self.tip._normal_kernel(*point, PY)
            qa = line_fit_moment(*x, nx, ny, nz, ax, ay, az, cfg.skin_law, PY)
            if state[_COUNT] >= self._ring.shape[0]:
                self._grow()
            count = self._window_step(state, self._ring, t, self._window,
                                      np.array(line_fit_products(x[0], x[1], x[2], *qa)), self._sums)  # fmt: skip
            if point is not None:
                out = line_fit_solve_kernel(
                    self._sums.tolist(), float(count), *point, ax, ay, az, self.tip, cfg.line_fit_iterations, self.noise,
                    self.corr, PY,
                )  # fmt: skip
                stats = out[6:10]
                jx, jy, jz = out[:3]
                accepted = bool(line_fit_accept(*stats, cfg) and math.isfinite(jx + jy + jz))
                offset_std = stats[2]
        use, moved, hx, hy, hz = self._hold_step(state, t, accepted, offset_std, jx, jy, jz, self._drift2)
        if use:
            self._held = (hx, hy, hz)
        if moved:
            return self._held, stats, True
        return point, stats, False
