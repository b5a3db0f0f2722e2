"""The online depth stage (after the contact point, before the measurement): one step
function for the batch and the stream.

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
solves only the sums are updated: O(1) per sample.

``depth_compensation="law"`` is the fixed law (``κ = 1``, no standard deviation): the kernel
:func:`softtip.core.depth.depth_kernel` alone, no state; ``"off"`` the papers' undeformed point
(``δ = 0``).

One source, two drivers (:mod:`softtip.core._jit`):

- the **state record** (:func:`new_depth_state`): a float64 vector with named slots — the
  running sums of the products since contact onset, the segment's point, tangent frame and
  noise covariances, its start time and grid cell, the best window's key and factor, the
  combination held, and the head and length of a **ring buffer** ``(capacity, 13)`` of the
  window's samples: each row a sample's time and the running sums *before* it, so that a
  window's sums are the running sums less its oldest row's;
- :func:`depth_step`, one sample in contact with a contact point (compiled by numba, or the
  same source as Python); :func:`depth_start_contact` at contact onset and :func:`depth_gap`
  at a sample in contact without a point act on the same record;
- :func:`depth_points` (a whole log): ``δ₀`` vectorised (numpy), then :func:`depth_run`, one
  compiled loop over the log calling the step; :class:`DepthTracker` (the stream): ``δ₀``
  per sample, then the step.

The solve, the tangent frame and the noise covariances (:mod:`softtip.core.depth`, written with
the ``xp`` back ends) are called inside the step with :mod:`softtip.core._xp_scalar`, so the
stage is not split. Only ``δ₀`` is computed before the step: for a skin law's exponent other
than 2 it is numpy's power, which compiled code cannot reproduce to the bit.
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from softtip.core import _xp_scalar as XS
from softtip.core._blocks import TIME_EDGE, ring_capacity
from softtip.core._jit import jitable, lazy_jit
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

__all__ = [
    "tip_depth_law", "asked_skin_law", "resolve_depth", "depth_points", "DepthPoints", "DepthTracker", "SOLVES_PER_WINDOW",
    "depth_params", "new_depth_state", "depth_start_contact", "depth_gap", "depth_step", "depth_run",
]  # fmt: skip


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
    TypeError
        ``config`` is not an :class:`~softtip.estimator.config.EstimatorConfig` (a dict of settings, say).
    """
    if not isinstance(config, EstimatorConfig):
        example = f"EstimatorConfig(**{config!r})" if isinstance(config, dict) else "EstimatorConfig(lowpass_hz=20.0)"
        raise TypeError(f"config: expected an EstimatorConfig, e.g. {example}; got {type(config).__name__}")
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


# -- the state record -------------------------------------------------------------------------

#: Slots of the state vector: the running sums since contact onset (12), the segment's point
#: (3), whether a segment is open, its start time, its last grid cell (NaN: none yet), the
#: smallest aged variance of its windows and that window's factor, the combination held
#: (factor, relative std, from the data: 0/1), the ring's head and length, the segment's
#: tangent frame (12, :func:`softtip.core.depth.depth_frame_kernel`), its noise covariances
#: (10, :func:`softtip.core.depth.depth_noise_kernel`) and room for a window's sums (12).
_CUM = 0
_PX, _PY, _PZ = 12, 13, 14
_OPEN = 15
_T_SEG = 16
_CELL = 17
_KEY = 18
_KAPPA = 19
_HELD_KAPPA, _HELD_REL, _HELD_DATA = 20, 21, 22
_HEAD, _COUNT = 23, 24
_FRAME = 25
_COV = _FRAME + 12
_SUMS = _COV + 10
N_STATE = _SUMS + N_DEPTH_SUMS
#: Columns of a ring row: the sample's time, then the running sums before it.
RING_COLUMNS = 1 + N_DEPTH_SUMS
#: Rows of the stream's first ring (it doubles when full).
_RING_START = 64

#: Slots of the parameter vector (:func:`depth_params`).
_WINDOW, _CELL_STEP, _DRIFT2, _PRIOR_STD, _CORR, _MAX_DEPTH = 0, 1, 2, 3, 4, 5
_FORCE_STD, _MOMENT_STD = 6, 9
N_PARAMS = 12


def depth_params(config: EstimatorConfig, noise: SensorNoise, corr: float) -> NDArray[np.float64]:
    """The step's parameters (N_PARAMS,) from a resolved ``config`` with a skin law: the window
    (s) and its solve grid (s), ``depth_drift²`` (1/s), ``depth_prior_std``, the samples per
    independent noise sample ``corr``, the law's cap (m) and the noise's standard deviations
    (N, N·m)."""
    p = np.empty(N_PARAMS)
    p[_WINDOW] = config.depth_window
    p[_CELL_STEP] = config.depth_window / SOLVES_PER_WINDOW
    p[_DRIFT2] = config.depth_drift**2
    p[_PRIOR_STD] = config.depth_prior_std
    p[_CORR] = corr
    p[_MAX_DEPTH] = config.skin_law.max_depth
    p[_FORCE_STD : _FORCE_STD + 3] = noise.force_std
    p[_MOMENT_STD : _MOMENT_STD + 3] = noise.moment_std
    return p


@jitable
def new_depth_state():
    """A state record (N_STATE,) before any contact."""
    state = np.zeros(N_STATE)
    state[_CELL] = np.nan
    state[_KEY] = np.inf
    state[_KAPPA] = np.nan
    state[_HELD_KAPPA] = np.nan
    state[_HELD_REL] = np.nan
    return state


@jitable
def depth_start_contact(state) -> None:
    """At contact onset: the running sums restart, the next sample starts a segment."""
    for q in range(N_DEPTH_SUMS):
        state[_CUM + q] = 0.0
    state[_OPEN] = 0.0


@jitable
def depth_gap(state) -> None:
    """A sample in contact without a contact point: the next one starts a segment."""
    state[_OPEN] = 0.0


@jitable
def _combine(kappa_h, var_h, prior_std, xp):
    """``(κ, relative std, from_data)`` from the held factor (NaN and inf: none) and the prior."""
    w0 = 1.0 / (prior_std * prior_std)
    wh = xp.where(var_h < math.inf, xp.div(1.0, var_h), 0.0)
    kappa = xp.where(wh > 0.0, xp.div(wh * kappa_h + w0, wh + w0), 1.0)
    return xp.maximum(kappa, 0.0), xp.sqrt(xp.div(1.0, wh + w0)), wh > w0


@jitable
def _new_segment(state, params, t, rx, ry, rz, nx, ny, nz) -> None:
    """A segment starts at this sample (point ``r``, normal ``n``): an empty window."""
    state[_PX] = rx
    state[_PY] = ry
    state[_PZ] = rz
    state[_OPEN] = 1.0
    frame = depth_frame_kernel(rx, ry, rz, nx, ny, nz, XS)
    for q in range(12):
        state[_FRAME + q] = frame[q]
    cov = depth_noise_kernel(frame, params[_FORCE_STD : _FORCE_STD + 3], params[_MOMENT_STD : _MOMENT_STD + 3])
    for q in range(10):
        state[_COV + q] = cov[q]
    state[_HEAD] = 0.0
    state[_COUNT] = 0.0
    state[_T_SEG] = t
    state[_CELL] = np.nan
    state[_KEY] = np.inf
    state[_KAPPA] = np.nan


@jitable
def _solve(state, ring, params, t, head, count) -> None:
    """Solve the window (``count`` rows from ``head``), keep it if its aged variance is the
    segment's smallest, and combine the one kept with the prior."""
    kw = math.nan
    var = math.inf
    if count >= MIN_DEPTH_SAMPLES:  # shorter windows cannot inform the depth
        for q in range(N_DEPTH_SUMS):
            state[_SUMS + q] = state[_CUM + q] - ring[head, 1 + q]
        kw, var = depth_solve_kernel(state[_SUMS : _SUMS + N_DEPTH_SUMS], float(count), state[_COV : _COV + 10],
                                     params[_CORR], DEPTH_ITERATIONS, XS)  # fmt: skip
    drift2 = params[_DRIFT2]
    age = t - state[_T_SEG]
    key = var - drift2 * age if var < math.inf else math.inf
    if key < state[_KEY]:
        state[_KEY] = key
        state[_KAPPA] = kw
    held = state[_KEY]
    var_h = held + drift2 * age if held < math.inf else math.inf
    kappa, rel, from_data = _combine(state[_KAPPA], var_h, params[_PRIOR_STD], XS)
    state[_HELD_KAPPA] = kappa
    state[_HELD_REL] = rel
    state[_HELD_DATA] = 1.0 if from_data else 0.0


@lazy_jit(nogil=False)
def depth_step(state, ring, params, t, fx, fy, fz, mx, my, mz, rx, ry, rz, nx, ny, nz, d0):
    """One sample in contact with a contact point, online depth: ``(depth, depth_std, from_data)``.

    Parameters
    ----------
    state : (N_STATE,) float64
        The record (:func:`new_depth_state`), updated.
    ring : (capacity, RING_COLUMNS) float64
        The window's rows, updated; it must have room for one more (the window's length
        before this sample < capacity).
    params : (N_PARAMS,) float64
        :func:`depth_params`.
    t : float
        s.
    fx, fy, fz, mx, my, mz : float
        The tared wrench, N and N·m.
    rx, ry, rz, nx, ny, nz : float
        The contact point (m) and its outward normal; a point other than the last one's
        starts a segment.
    d0 : float
        The skin law's depth at the normal force, m (:func:`softtip.core.depth.depth_kernel`).

    Returns
    -------
    tuple
        ``depth`` (m, at most the law's cap), its standard deviation (m), and whether the
        data outweighed the law's prior.
    """
    if state[_OPEN] == 0.0 or rx != state[_PX] or ry != state[_PY] or rz != state[_PZ]:
        _new_segment(state, params, t, rx, ry, rz, nx, ny, nz)
    cap = ring.shape[0]
    head = int(state[_HEAD])
    count = int(state[_COUNT])
    row = head + count
    if row >= cap:
        row -= cap
    ring[row, 0] = t  # this sample's row: its time and the sums before it
    for q in range(N_DEPTH_SUMS):
        ring[row, 1 + q] = state[_CUM + q]
    count += 1
    prods = depth_products(fx, fy, fz, mx, my, mz, state[_FRAME : _FRAME + 12], d0)
    for q in range(N_DEPTH_SUMS):
        state[_CUM + q] = state[_CUM + q] + prods[q]
    start = t - params[_WINDOW] + TIME_EDGE
    while count > 0 and ring[head, 0] <= start:
        head += 1
        if head == cap:
            head = 0
        count -= 1
    state[_HEAD] = head
    state[_COUNT] = count
    cell = float(math.floor((t - state[_T_SEG] + TIME_EDGE) / params[_CELL_STEP]))
    if cell != state[_CELL]:  # on the grid of the segment (NaN: its first sample)
        state[_CELL] = cell
        _solve(state, ring, params, t, head, count)
    delta = state[_HELD_KAPPA] * d0
    cap_depth = params[_MAX_DEPTH]
    return (cap_depth if delta > cap_depth else delta), state[_HELD_REL] * d0, state[_HELD_DATA] != 0.0


@lazy_jit
def depth_run(t, contact, fx, fy, fz, mx, my, mz, point, normal, d0, params, depth, depth_std, from_data):
    """The online depth of a whole log in one loop: :func:`depth_step` at every sample in
    contact with a finite contact point, :func:`depth_start_contact` at contact onset,
    :func:`depth_gap` in contact without a point.

    ``t`` (N,) s; ``contact`` (N,) bool; ``fx .. mz`` (N,) the tared wrench; ``point``,
    ``normal`` (N, 3); ``d0`` (N,) the skin law's depth, m; ``params`` :func:`depth_params`;
    ``depth``, ``depth_std`` (N,) float and ``from_data`` (N,) bool written (0 and False where
    the depth is not estimated). Returns ``depth``.
    """
    n = t.shape[0]
    state = new_depth_state()
    ring = np.empty((ring_capacity(t, params[_WINDOW]), RING_COLUMNS))
    for i in range(n):
        depth[i] = 0.0
        depth_std[i] = 0.0
        from_data[i] = False
        if not contact[i]:
            continue
        if i == 0 or not contact[i - 1]:
            depth_start_contact(state)
        rx, ry, rz = point[i, 0], point[i, 1], point[i, 2]
        if not (math.isfinite(rx) and math.isfinite(ry) and math.isfinite(rz)):
            depth_gap(state)
            continue
        d, d_std, data = depth_step(state, ring, params, t[i], fx[i], fy[i], fz[i], mx[i], my[i], mz[i],
                                    rx, ry, rz, normal[i, 0], normal[i, 1], normal[i, 2], d0[i])  # fmt: skip
        depth[i] = d
        depth_std[i] = d_std
        from_data[i] = data
    return depth


def depth_points(t, c, contact, point, normal, config: EstimatorConfig, noise: SensorNoise, corr) -> DepthPoints:
    """The depth of every sample (resolved ``config``, see :func:`resolve_depth`).

    ``c`` are the six wrench components, ``point`` and ``normal`` (N, 3) the contact points
    of the contact-point stage (NaN where none). Returns :class:`DepthPoints`; the depth is 0 with
    the papers' method and where there is no point.
    """
    n = len(t)
    law = config.skin_law
    if law is None:
        return DepthPoints(np.zeros(n), np.zeros(n), np.zeros(n, dtype=bool))
    fx, fy, fz = c[0], c[1], c[2]
    with np.errstate(invalid="ignore"):
        d0 = depth_kernel(-(fx * normal[:, 0] + fy * normal[:, 1] + fz * normal[:, 2]), law, NP)
    if config.depth_compensation == "law":
        has = contact & np.all(np.isfinite(point), axis=-1)
        return DepthPoints(np.where(has, d0, 0.0), np.zeros(n), np.zeros(n, dtype=bool))
    depth, depth_std, from_data = np.empty(n), np.empty(n), np.empty(n, dtype=bool)
    depth_run.function(n)(
        np.ascontiguousarray(t, dtype=float), np.ascontiguousarray(contact, dtype=bool),
        *(np.ascontiguousarray(x, dtype=float) for x in c), np.ascontiguousarray(point, dtype=float),
        np.ascontiguousarray(normal, dtype=float), d0, depth_params(config, noise, corr), depth, depth_std, from_data,
    )  # fmt: skip
    return DepthPoints(depth, depth_std, from_data)


class DepthTracker:
    """The depth of :func:`depth_points`, one sample at a time: the state record and
    :func:`depth_step` (compiled when numba is used), O(1) per sample."""

    def __init__(self, config: EstimatorConfig, noise: SensorNoise, corr: float, *, expected_samples: int | None = None):
        self.config = config
        self.law = config.skin_law
        self.online = config.depth_compensation == "online"
        self._params = depth_params(config, noise, corr) if self.online else None
        self._state = new_depth_state()
        self._ring = np.empty((_RING_START, RING_COLUMNS))
        self._step = depth_step.function(expected_samples) if self.online else None

    def start_contact(self) -> None:
        """At contact onset."""
        depth_start_contact(self._state)

    def gap(self) -> None:
        """A sample in contact without a contact point: the next one starts a segment."""
        depth_gap(self._state)

    def step(self, t: float, x, point, normal) -> tuple[float, float, bool]:
        """``(depth, depth_std, from_data)`` of a sample in contact (wrench ``x``, 6 floats)
        with contact point ``point`` and its normal ``normal`` (3 floats each)."""
        fx, fy, fz, mx, my, mz = x
        nx, ny, nz = normal
        d0, params, state, ring = self.ready(fx, fy, fz, nx, ny, nz)
        if not self.online:
            return d0, 0.0, False
        rx, ry, rz = point
        return self._step(state, ring, params, t, fx, fy, fz, mx, my, mz, rx, ry, rz, nx, ny, nz, d0)

    def ready(self, fx: float, fy: float, fz: float, nx: float, ny: float, nz: float):
        """Before a sample in contact with a contact point of normal ``n`` is stepped elsewhere
        (:func:`softtip.estimator.pipeline.located_step`): ``(d0, params, state, ring)``, the skin
        law's depth at the normal force (m) and the online stage's records (None when not
        online), its ring with room for one more."""
        d0 = depth_kernel(-(fx * nx + fy * ny + fz * nz), self.law, PY)
        if not self.online:
            return d0, None, None, None
        return (d0, *self.records())

    def records(self) -> tuple[NDArray, NDArray, NDArray]:
        """The online stage's ``(params, state, ring)``, its ring with room for one more sample."""
        if self._state[_COUNT] >= len(self._ring):
            self._grow()
        return self._params, self._state, self._ring

    def _grow(self) -> None:
        """A ring twice as long, the window's rows first (oldest first)."""
        old, state = self._ring, self._state
        head, count = int(state[_HEAD]), int(state[_COUNT])
        ring = np.empty((2 * len(old), RING_COLUMNS))
        ring[:count] = np.roll(old, -head, axis=0)[:count]
        self._ring = ring
        state[_HEAD] = 0.0
