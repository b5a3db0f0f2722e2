"""The latched contact point (paper III-C): one step function for batch and stream.

During the first rise of the force after onset (until ``|f|`` first exceeds the light-force
window, or sets no new maximum for ``stall_time``), the soft-finger solutions of the samples
inside the window are averaged; that mean, put back on the skin, is the contact point from
then on, until contact ends. Before the first window sample the current soft-finger solution
is used. With no window sample in the whole rise (a press that stays below the window, or
one that jumps past it between two samples), the mean of the rise's soft-finger solutions, and
of the samples after it up to ``fallback_samples`` in all, weighted by ``|f|²`` (a solution's
noise falls as ``1 / |f|``), is latched and flagged.

Re-latching (``relatch_distance``): once the latch is held, a sample at light force whose
soft-finger solution lies farther than this from the latched point starts a new first rise.

One source: :func:`latch_step` advances the state record (:func:`new_latch_state`) by one
sample in contact: the running sums, the rise, fallback and re-latch decisions. Putting a mean
back on the skin depends on the fingertip's shape (``tip._project_kernel``), so it is not in
the step: the step returns a code saying which point the sample has (none, the soft-finger
solution, the projection of the mean it returns, or the held latch) and the caller projects.
The re-latch test needs the held point projected; :class:`LatchTracker` (the stream) projects
a latch when it is fixed and hands it back (:func:`latch_hold`) before the next sample.
:func:`latch_points` (the batch) runs the step over the log in one compiled loop
(:func:`latch_run`) and projects the means afterwards, vectorised; with re-latching the loop
stops at the first re-latch test of a latch not yet projected, the wrapper projects it as the
stream does (``xp=PY``) and the loop goes on from that sample: the decisions are the stream's
to the bit.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from softtip.core._blocks import TIME_EDGE
from softtip.core._jit import jitable, lazy_jit
from softtip.core._xp import NP, PY
from softtip.core.fingertip import Fingertip
from softtip.core.location import SoftFinger, contact_kernel
from softtip.estimator.config import EstimatorConfig

__all__ = ["latch_points", "LatchedPoints", "LatchTracker", "latch_params", "new_latch_state", "latch_step",
           "latch_hold", "latch_run"]  # fmt: skip

# the state record's slots
_RISING = 0  # 1 during the first rise
_PEAK = 1  # N, the largest |f| of the rise so far
_T_PEAK = 2  # s, when it was set
_N_WIN = 3  # soft-finger solutions in the light-force window during the rise
_WX, _WY, _WZ = 4, 5, 6  # m, their sum
_N_FB = 7  # the fallback's valid soft-finger solutions: the rise's, and at least fallback_samples
_FX, _FY, _FZ = 8, 9, 10  # m·N², their sum weighted by |f|²
_HOLD = 11  # 0: no latch fixed; 1: fixed on the window mean; 2: on the fallback mean
_PENDING = 12  # 1: fixed, the held point not projected yet (_MX.. not yet put on the skin)
_MX, _MY, _MZ = 13, 14, 15  # m, the mean fixed
_LX, _LY, _LZ = 16, 17, 18  # m, the held point (the mean put back on the skin)
_HAD = 19  # 1 once any sample was latched (a contact regained after it starts re-latched)
_FW = 20  # N², the fallback's sum of weights |f|²
_N_STATE = 21

# the parameters' slots
_LO, _HI = 0, 1  # N, the light-force window
_STALL = 2  # s
_N_FALLBACK = 3
_DIST2 = 4  # m², relatch_distance squared; negative: no re-latching
_N_PARAMS = 5

# what point a sample has (the code latch_step returns)
NONE = 0  #: none (no valid soft-finger solution yet)
SOFT = 1  #: the sample's soft-finger solution
MEAN = 2  #: the mean returned, put back on the skin
FIX = 3  #: as MEAN, and the latch is fixed to it from here (the caller projects it, :func:`latch_hold`)
HELD = 4  #: the latch held
ASK_SC = 5  #: (nothing done) call again with the sample's soft-finger solution
ASK_HOLD = 6  #: (nothing done) project the mean returned, :func:`latch_hold` it, call again


class LatchedPoints(NamedTuple):
    """What :func:`latch_points` gives for a whole log (N samples)."""

    point: NDArray  #: (N, 3) m, the contact point held (NaN where there is none)
    latched: NDArray  #: (N,) bool, the samples the latch averaged
    fallback: NDArray  #: (N,) bool, latched on the first samples: no light-force phase
    relatched: NDArray  #: (N,) bool, a new latch starts here (re-latch, or a contact after a latched one)


def latch_params(config: EstimatorConfig) -> NDArray:
    """The latch's parameters from ``config``, a float64 vector (slots ``_LO`` ... ``_DIST2``)."""
    lo, hi = config.latch_window
    d = config.relatch_distance
    return np.array([lo, hi, config.stall_time, config.fallback_samples, -1.0 if d is None else d * d], dtype=float)


def new_latch_state(had_latch: bool = False) -> NDArray:
    """A latch's state record before any contact; ``had_latch``: an earlier contact (an earlier
    piece of the log) had a latched point."""
    state = np.zeros(_N_STATE)
    state[_HAD] = float(had_latch)
    return state


@lazy_jit
def latch_start(state, f_norm, t):  # pragma: no cover - compiled
    """A new first rise at force ``f_norm`` (N) and time ``t`` (s): at onset and at a re-latch."""
    state[_RISING] = 1.0
    state[_PEAK] = f_norm
    state[_T_PEAK] = t
    for k in range(_N_WIN, _LZ + 1):
        state[k] = 0.0
    state[_FW] = 0.0


@lazy_jit(nogil=False)
def latch_hold(state, px, py, pz):  # pragma: no cover - compiled
    """The fixed latch put back on the skin, ``p`` (m), handed to the state (after
    :data:`FIX` or :data:`ASK_HOLD`)."""
    state[_LX] = px
    state[_LY] = py
    state[_LZ] = pz
    state[_PENDING] = 0.0


@jitable
def latch_keeps(held, onset, f_norm, lo, hi, dist2):
    """A sample in contact at ``|f|`` ``f_norm`` (N) only keeps the latch: one is ``held``, the
    contact does not start here (``onset``) and no re-latch test is due (re-latching is off,
    ``dist2 < 0``, or ``f_norm`` is outside the light-force window ``[lo, hi]``, N). Then
    :func:`latch_step` returns :data:`HELD` and changes nothing: it tests this first, and the
    stream (:class:`LatchTracker`) before calling it."""
    return held and not onset and not (dist2 >= 0.0 and lo <= f_norm and f_norm <= hi)


@lazy_jit(nogil=False)
def latch_step(state, params, onset, t, f_norm, have_sc, valid, rx, ry, rz):  # pragma: no cover - compiled
    """One sample in contact.

    Parameters
    ----------
    state, params : float64 vectors
        :func:`new_latch_state` (updated) and :func:`latch_params`.
    onset : bool
        The contact starts at this sample.
    t, f_norm : float
        s, and ``|f|`` (N).
    have_sc : bool
        ``valid, r`` are the sample's soft-finger solution (else :data:`ASK_SC` when needed).
    valid : bool
    rx, ry, rz : float
        The soft-finger contact point, m.

    Returns
    -------
    tuple
        ``(code, mx, my, mz, latched, fallback, relatched, begin)``: which point the sample
        has (:data:`NONE` ... :data:`HELD`, or a request :data:`ASK_SC`, :data:`ASK_HOLD`),
        the mean to put back on the skin (m; for :data:`MEAN`, :data:`FIX`,
        :data:`ASK_HOLD`), whether the sample is latched, latched on the fallback, re-latched
        (a re-latch, or an onset after a latched contact), and whether a first rise begins.
    """
    nan = np.nan
    lo = params[_LO]
    hi = params[_HI]
    dist2 = params[_DIST2]
    hold = state[_HOLD]
    held = hold > 0.0
    if latch_keeps(held, onset, f_norm, lo, hi, dist2):  # (a held latch is never rising)
        return HELD, nan, nan, nan, True, hold == 2.0, False, False
    test = held and not onset  # here: a re-latch test is due
    if not have_sc:
        return ASK_SC, nan, nan, nan, False, False, False, False
    relatched = False
    begin = onset
    if onset:
        relatched = state[_HAD] > 0.0  # contact regained after a latched one
    elif test and valid:
        if state[_PENDING] > 0.0:
            return ASK_HOLD, state[_MX], state[_MY], state[_MZ], False, False, False, False
        dx, dy, dz = rx - state[_LX], ry - state[_LY], rz - state[_LZ]
        if dx * dx + dy * dy + dz * dz > dist2:
            relatched = True
            begin = True
    if begin:
        latch_start(state, f_norm, t)
    rising = state[_RISING] > 0.0
    if rising and f_norm > state[_PEAK]:
        state[_PEAK] = f_norm
        state[_T_PEAK] = t
    hold = state[_HOLD]
    if hold > 0.0:
        return HELD, nan, nan, nan, True, hold == 2.0, relatched, begin
    n_fb = state[_N_FB]
    if valid and (rising or n_fb < params[_N_FALLBACK]):
        # a solution's noise falls as 1 / |f|: weighted by |f|², the top of a rise that never
        # reached the window counts, not its first samples at the contact threshold
        w = f_norm * f_norm
        n_fb += 1.0
        state[_N_FB] = n_fb
        state[_FW] = state[_FW] + w
        state[_FX] = state[_FX] + w * rx
        state[_FY] = state[_FY] + w * ry
        state[_FZ] = state[_FZ] + w * rz
    code = NONE
    mx = my = mz = nan
    fallback = False
    if rising and (f_norm > hi or t - state[_T_PEAK] > params[_STALL] + TIME_EDGE):
        rising = False
        state[_RISING] = 0.0
        n = state[_N_WIN]
        if n > 0.0:
            mx, my, mz = state[_WX] / n, state[_WY] / n, state[_WZ] / n
            code = FIX
            state[_HOLD] = 1.0
    if rising:
        n = state[_N_WIN]
        if valid and lo <= f_norm and f_norm <= hi:
            n += 1.0
            state[_N_WIN] = n
            state[_WX] = state[_WX] + rx
            state[_WY] = state[_WY] + ry
            state[_WZ] = state[_WZ] + rz
        if n > 0.0:
            mx, my, mz = state[_WX] / n, state[_WY] / n, state[_WZ] / n
            code = MEAN
        elif valid:
            code = SOFT
    elif code == NONE and n_fb > 0.0:
        fw = state[_FW]
        mx, my, mz = state[_FX] / fw, state[_FY] / fw, state[_FZ] / fw
        fallback = True
        code = MEAN
        if n_fb >= params[_N_FALLBACK]:
            code = FIX
            state[_HOLD] = 2.0
    if code == FIX:
        state[_PENDING] = 1.0
        state[_MX] = mx
        state[_MY] = my
        state[_MZ] = mz
    latched = code != NONE and (state[_N_WIN] > 0.0 or fallback)
    if latched:
        state[_HAD] = 1.0
    return code, mx, my, mz, latched, fallback, relatched, begin


@lazy_jit
def latch_run(state, params, contact, t, f_norm, valid, rx, ry, rz, start, code, point, latched, fallback,
              relatched):  # pragma: no cover - compiled
    """:func:`latch_step` over the samples ``start ..`` of a log; returns where it stopped.

    Writes, per sample in contact, ``code`` (int8) and ``point`` (N, 3): the soft-finger point
    (:data:`SOFT`), the mean not yet put on the skin (:data:`MEAN`, :data:`FIX`), NaN
    otherwise; and the flags ``latched``, ``fallback``, ``relatched`` (N,) bool. Returns N when
    done, or the sample ``i`` whose re-latch test needs the held point: its mean is in
    ``point[i]``; project it, :func:`latch_hold` it and call again from ``i``.
    """
    n = t.shape[0]
    for i in range(start, n):
        if not contact[i]:
            continue
        onset = i == 0 or not contact[i - 1]
        c, mx, my, mz, lat, fb, rel, _ = latch_step(state, params, onset, t[i], f_norm[i], True, valid[i], rx[i],
                                                    ry[i], rz[i])  # fmt: skip
        if c == SOFT:
            mx, my, mz = rx[i], ry[i], rz[i]
        point[i, 0] = mx
        point[i, 1] = my
        point[i, 2] = mz
        if c == ASK_HOLD:
            return i
        code[i] = c
        latched[i] = lat
        fallback[i] = fb
        relatched[i] = rel
    return n


@lazy_jit
def _copy_held(code, point):  # pragma: no cover - compiled
    """``point`` at the samples :data:`HELD`: that of the last :data:`FIX` before them."""
    last = -1
    for i in range(code.shape[0]):
        if code[i] == FIX:
            last = i
        elif code[i] == HELD:
            point[i, 0] = point[last, 0]
            point[i, 1] = point[last, 1]
            point[i, 2] = point[last, 2]
    return point


def latch_points(t, f_norm, contact, sc, tip: Fingertip, config: EstimatorConfig, had_latch: bool = False) -> LatchedPoints:
    """Contact point per sample in ``latch`` mode, with re-latching.

    ``t`` (N,) s, ``f_norm`` (N,) N, ``contact`` (N,) bool, ``sc`` the soft-finger solutions
    (:func:`softtip.core.location.contact_arrays`). Returns :class:`LatchedPoints`: one pass of
    :func:`latch_run`, then the means put back on the skin at once. ``had_latch``: a contact
    before these samples (an earlier piece of the log) had a latch.
    """
    n = len(t)
    contact = np.ascontiguousarray(contact, dtype=bool)
    valid = np.ascontiguousarray(sc.valid, dtype=bool)
    rx, ry, rz = (np.where(valid, np.asarray(c, dtype=float), np.nan) for c in sc.point)
    state, params = new_latch_state(had_latch), latch_params(config)
    code = np.zeros(n, dtype=np.int8)
    point = np.full((n, 3), np.nan)
    latched, fallback, relatched = (np.zeros(n, dtype=bool) for _ in range(3))
    run, hold = latch_run.function(n), latch_hold.function(n)
    t, f_norm = np.ascontiguousarray(t, dtype=float), np.ascontiguousarray(f_norm, dtype=float)
    i = 0
    while (i := run(state, params, contact, t, f_norm, valid, rx, ry, rz, i, code, point, latched, fallback,
                    relatched)) < n:  # fmt: skip
        # a re-latch test of a latch not yet on the skin: projected as the stream does
        hold(state, *tip._project_kernel(*(float(v) for v in point[i]), PY))
    k = np.flatnonzero((code == MEAN) | (code == FIX))
    if len(k):
        point[k] = np.stack(tip._project_kernel(*point[k].T, NP), axis=-1)
    _copy_held.function(n)(code, point)
    return LatchedPoints(point, latched, fallback, relatched)


class LatchTracker:
    """The latch of :func:`latch_points` one sample at a time (the same :func:`latch_step`).

    Call :meth:`step` for every sample in contact; :meth:`reset` forgets every contact.
    Soft-finger solutions (``sc``, the 8-tuple of
    :func:`softtip.core.location.contact_kernel`) are computed only when the step needs them
    and handed back for reuse.
    """

    def __init__(
        self, tip: Fingertip, config: EstimatorConfig, *, expected_samples: int | None = None,
        soft_finger: Callable[..., tuple] | None = None,
    ):  # fmt: skip
        self.tip = tip
        self.config = config
        #: the soft-finger solution of a sample's six floats (the 8-tuple of
        #: :func:`~softtip.core.location.contact_kernel`; default the tip's own, as Python)
        self.soft_finger = soft_finger or (lambda *x: contact_kernel(tip, *x, xp=PY))
        self.params = latch_params(config)  #: the latch's parameter record (:func:`latch_params`)
        self._step, self._hold = latch_step.function(expected_samples), latch_hold.function(expected_samples)
        p = self.params.tolist()
        self.window = (p[_LO], p[_HI], p[_DIST2])  #: latch_keeps's window (N, N, m²), as floats
        self.reset()

    def reset(self) -> None:
        """No contact so far."""
        self.state = new_latch_state()
        self.point: tuple[float, float, float] | None = None  #: the latch held, m (None when none)
        self.fallback = False  #: the latch held is a fallback one

    def step(self, t: float, f_norm: float, x: list[float], sc, onset: bool):
        """A sample in contact at ``t`` (s) with tared wrench ``x`` and ``|f|`` ``f_norm`` (N);
        ``onset``: the contact starts here.

        Returns ``(point, latched, fallback, relatched, begin, sc)``: ``point`` (m) is ``None``
        when there is none yet (no valid soft-finger solution); ``begin``: a first rise starts
        (onset or re-latch).
        """
        if latch_keeps(self.point is not None, onset, f_norm, *self.window):
            # latch_step's first test, here: a compiled call less per sample of a held contact
            return self.point, True, self.fallback, False, False, sc
        state, params = self.state, self.params
        if sc is None:
            out = self._step(state, params, onset, t, f_norm, False, False, 0.0, 0.0, 0.0)
            if out[0] == ASK_SC:
                sc = SoftFinger(*self.soft_finger(*x))
        if sc is not None:
            out = self._step(state, params, onset, t, f_norm, True, sc.valid, sc.rx, sc.ry, sc.rz)
        code, mx, my, mz, latched, fallback, relatched, begin = out
        point = None
        if code == SOFT:
            point = sc.point
        elif code == MEAN or code == FIX:
            point = self.tip._project_kernel(mx, my, mz, PY)
            if code == FIX:
                self._hold(state, *point)
        return self.keep(code, point, fallback, begin), latched, fallback, relatched, begin, sc

    def keep(self, code: int, point: tuple[float, float, float] | None, fallback: bool, begin: bool):
        """What the tracker keeps of a :func:`latch_step` (``code``, the sample's ``point``, m,
        ``fallback``, ``begin``), here or in a compiled step that went on with the sample
        (:func:`softtip.estimator.pipeline.sample_step`); returns the sample's point: the latch
        held for :data:`HELD` (the same object from sample to sample)."""
        if begin:
            self.point = None
        if code == HELD:
            return self.point
        if code == FIX:
            self.point = point
            self.fallback = fallback
        return point
