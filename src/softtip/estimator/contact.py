"""Contact onset and release with hysteresis, contact counting, and bias drift tracking.

Per sample after the tare, with ``b`` the drift tracked so far and ``f`` the force of the
tared (filtered) wrench minus ``b`` (minus nothing when ``drift_tracking`` is off):

- **Hysteresis.** A contact starts when ``|f| ≥ contact_threshold`` (the onset threshold)
  and ends at the first sample with ``|f|`` below the release threshold
  ``max(contact_threshold − contact_hysteresis · σ_f, min(contact_threshold, 2.5 σ_f))``,
  ``σ_f`` the noise of ``|f|`` from the noise model (root sum of squares of the force
  noise, after the filter): the release threshold stays where an untouched sensor's noise
  lies below it 90 % of the time. A rising grasp force crossing
  the onset threshold in noise no longer makes several contacts, each resetting the latch.
- **Minimum duration.** From the first sample at or above the onset threshold the contact is
  pending (reported ``none``) until ``|f|`` has stayed above the release threshold for
  ``min_contact_duration`` s, each sample counting for its sampling interval (so at 50 Hz
  one sample covers the default 5 ms, at 1 kHz five samples are needed); a spike shorter
  than that is not a contact.
- **Contact count.** Each contact gets the next number, 1, 2, … (``contact_id``; 0 out of
  contact): contacts as a user would count them.
- **Drift.** While untouched (no contact pending or held: the drift-corrected force below
  the onset threshold, or below the release threshold since a contact), ``b ← b + α (w − b)`` with ``α = min(Δt / drift_time_constant,
  0.5)``: an exponential moving average of the untouched wrench, all six components. It is
  reported per sample (the ``b`` subtracted from that sample) and, with ``drift_tracking``,
  subtracted. A drift of the force beyond the contact threshold since the last tare is
  flagged (:attr:`ContactTrack.drift_alarm`).

:func:`track_contacts` does it for a whole log: with ``drift_tracking``, long logs in one
compiled pass (:func:`softtip.estimator.sequential.track_kernel`), otherwise vectorised
(one iteration per contact, per run of samples between the thresholds, and per block of
~4000 untouched samples), both the same bits; :class:`ContactTracker` one sample at a time
with O(1) float work.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from math import sqrt
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from softtip.core._jit import jit_enabled
from softtip.core.noise import SensorNoise
from softtip.estimator.config import EstimatorConfig
from softtip.estimator.sequential import track_kernel

__all__ = [
    "RELEASE_FLOOR", "contact_thresholds", "ContactTrack", "TrackState", "track_contacts", "ContactTracker",
    "START_PULL_TIME",
]  # fmt: skip

#: The release threshold is at least this many ``σ_f``: an untouched sensor's ``|f|`` (noise
#: only, a χ distribution with 3 degrees of freedom) is below it 90 % of the time.
RELEASE_FLOOR = 2.5
#: Largest weight of one sample in the drift average.
_MAX_ALPHA = 0.5
#: The drift average runs in blocks of untouched samples (a block ends at a sample that is
#: not untouched, after _BLOCK samples, or once the product of the (1 − α) falls below
#: _TINY), in the closed form ``b_j = P_j (b_0 + Σ_{k ≤ j} α_k w_k / P_k)``,
#: ``P_j = Π_{k ≤ j} (1 − α_k)``: only products, quotients and running sums, so the batch
#: (cumprod, cumsum) and the stream give the same bits.
_BLOCK = 4096
_TINY = 1e-100
#: s; the first contact after a tare that pulls (no pushing contact point) this long says the
#: fingertip was touched while taring (the release then reads as a pull).
START_PULL_TIME = 0.1


def contact_thresholds(config: EstimatorConfig, noise: SensorNoise) -> tuple[float, float]:
    """The onset and release thresholds of ``|f|``, N, for the (filtered) noise ``noise``."""
    on = config.contact_threshold
    sigma = math.sqrt(sum(s * s for s in noise.force_std))
    return on, max(on - config.contact_hysteresis * sigma, min(on, RELEASE_FLOOR * sigma))


def drift_weights(t: NDArray, config: EstimatorConfig, t_before: float | None = None) -> NDArray:
    """``α`` per sample (the first sample has none, unless ``t_before``, the time of the
    sample before it, is given)."""
    a = np.zeros(len(t))
    a[1:] = np.minimum(np.diff(t) / config.drift_time_constant, _MAX_ALPHA)
    if t_before is not None and len(t):
        a[0] = min((t[0] - t_before) / config.drift_time_constant, _MAX_ALPHA)
    return a


@dataclass
class TrackState:
    """What :func:`track_contacts` carries from one piece of a log to the next.

    A log may be tracked piece by piece, cut only at samples that are untouched (no contact
    pending or held, the drift following: ``~ContactTrack.busy``); with this state the
    pieces give the same bits as the whole log. SI units.
    """

    t_last: float | None = None  #: s, time of the last sample tracked (None: none yet)
    drift: NDArray[np.float64] = field(default_factory=lambda: np.zeros(6))  #: N, N·m, after the last sample
    open: bool = False  #: a block of the drift average is open (its closed form goes on)
    b0: NDArray[np.float64] = field(default_factory=lambda: np.zeros(6))  #: the open block's start
    p0: float = 1.0  #: the open block's product of (1 − α)
    acc0: NDArray[np.float64] = field(default_factory=lambda: np.zeros(6))  #: the open block's sums
    block: int = 0  #: samples in the open block
    count: int = 0  #: contacts so far
    alarmed: bool = False  #: the drift alarm went off in an earlier piece


class ContactTrack(NamedTuple):
    """Contacts and drift of a whole log (:func:`track_contacts`)."""

    wrench: NDArray[np.float64]  #: (N, 6) the wrench with the drift subtracted (as given without tracking)
    drift: NDArray[np.float64]  #: (N, 6) drift tracked before each sample, N and N·m
    contact: NDArray[np.bool_]  #: (N,) in contact (onset confirmed, not released)
    contact_id: NDArray[np.int64]  #: (N,) 1, 2, … per contact; 0 out of contact
    drift_alarm: int  #: first sample whose drift force exceeds the contact threshold; -1 if none (or in an earlier piece)
    busy: NDArray[np.bool_] | None = None  #: (N,) a contact pending or held, the drift not following
    state: TrackState | None = None  #: the state after the last sample, for the next piece


class _DriftAverage:
    """The drift average of :class:`ContactTracker` over a whole log, in chunks.

    :meth:`follow` tries the closed form of :data:`_BLOCK` on the next samples as if all were
    untouched; :meth:`keep` keeps the first ``k`` of them (all: the block goes on; fewer: the
    sample after them is not untouched and ends the block, as in the stream). Chunks start
    small after such an event and double, so the work is proportional to the samples.
    """

    def __init__(self, x: NDArray, alpha: NDArray, state: TrackState | None = None):
        self.x, self.alpha = x, alpha
        self.b = np.zeros(6)
        self.open = False
        self.size = 32
        if state is not None:
            self.b, self.open = np.array(state.drift, dtype=float), state.open
            if state.open:
                self.b0, self.p0, self.acc0, self.count = state.b0, state.p0, np.array(state.acc0), state.block

    @staticmethod
    def pack(state: TrackState) -> NDArray:
        """``state``'s drift average as the compiled kernel's float state (see
        :func:`softtip.estimator.sequential.track_kernel`)."""
        avg = np.zeros(19)
        avg[0:6], avg[18] = state.drift, 1.0
        if state.open:
            avg[6:12], avg[12:18], avg[18] = state.b0, state.acc0, state.p0
        return avg

    @staticmethod
    def unpack(state: TrackState, avg: NDArray, iavg: NDArray) -> None:
        """Store the compiled kernel's state into ``state`` (as :meth:`save` does)."""
        state.drift, state.open, state.count = avg[0:6].copy(), bool(iavg[0]), int(iavg[2])
        if state.open:
            state.b0, state.acc0, state.p0, state.block = avg[6:12].copy(), avg[12:18].copy(), float(avg[18]), int(iavg[1])

    def save(self, state: TrackState) -> None:
        """Store the average's state into ``state`` (the end of a piece)."""
        state.drift, state.open = self.b.copy(), self.open
        if self.open:
            state.b0, state.p0, state.acc0, state.block = self.b0, self.p0, self.acc0.copy(), self.count

    def follow(self, i: int, n: int) -> tuple[int, NDArray]:
        """``(e, before)``: the drift before each sample of ``[i, e)`` if all are untouched."""
        if not self.open:
            self.b0, self.p0, self.acc0, self.count, self.open = self.b, 1.0, np.zeros(6), 0, True
        e = min(n, i + self.size, i + _BLOCK - self.count)
        a = self.alpha[i:e]
        p = np.cumprod(np.concatenate(([self.p0], 1.0 - a)))[1:]
        small = p < _TINY
        if small.any():
            k = int(np.argmax(small)) + 1
            e, a, p = i + k, a[:k], p[:k]
        acc = np.cumsum(np.concatenate((self.acc0[None, :], (a / p)[:, None] * self.x[i:e])), axis=0)[1:]
        self._p, self._acc = p, acc
        self._after = after = p[:, None] * (self.b0 + acc)
        return e, np.concatenate((self.b[None, :], after[:-1]), axis=0)

    def keep(self, k: int) -> None:
        """Keep the first ``k`` samples of the last :meth:`follow`."""
        if k == len(self._p):
            self.b, self.p0, self.acc0 = self._after[-1], float(self._p[-1]), self._acc[-1]
            self.count += k
            if self.count >= _BLOCK or self.p0 < _TINY:
                self.open = False
            self.size = min(2 * self.size, _BLOCK)
        else:
            if k:
                self.b = self._after[k - 1]
            self.open = False
            self.size = 32


def _first(cond, a: int, n: int) -> int:
    """First index ``j ≥ a`` where ``cond(lo, hi)`` (a boolean array over ``[lo, hi)``) holds, or ``n``."""
    size = 1024
    while a < n:
        hi = min(n, a + size)
        c = cond(a, hi)
        if c.any():
            return a + int(np.argmax(c))
        a, size = hi, size * 2
    return n


def _norm3(v: NDArray) -> NDArray:
    return np.sqrt(v[:, 0] * v[:, 0] + v[:, 1] * v[:, 1] + v[:, 2] * v[:, 2])


def _follow_drift(
    t: NDArray, x: NDArray, start: int, alpha: NDArray, on: float, busy: NDArray, state: TrackState | None
) -> NDArray:
    """The drift alone (``drift_tracking`` off): it follows every sample whose force is within
    ``on`` of it; the others are marked in ``busy``."""
    n = len(t)
    drift = np.zeros((n, 6))
    avg = _DriftAverage(x, alpha, state)
    i = start
    while i < n:
        e, before = avg.follow(i, n)
        far = _norm3(x[i:e, :3] - before[:, :3]) >= on
        k = int(np.argmax(far)) if far.any() else e - i
        drift[i : i + k] = before[:k]
        avg.keep(k)
        if k == e - i:
            i = e
            continue
        j = i + k
        b = avg.b
        i = _first(lambda lo, hi, b=b: _norm3(x[lo:hi, :3] - b[:3]) < on, j + 1, n)
        drift[j:i] = b
        busy[j:i] = True
    if state is not None:
        avg.save(state)
    return drift


def _held(t: NDArray, dt: NDArray, j: int, m: int, min_dur: float) -> NDArray:
    """Samples of ``[j, m)`` by which ``|f|`` has stayed up ``min_dur`` since sample ``j``,
    each sample counting for its interval ``dt``."""
    return (t[j:m] - t[j]) + dt[j:m] >= min_dur


def _hysteresis(
    t: NDArray, dt: NDArray, f: NDArray, start: int, on: float, off: float, min_dur: float, cid: NDArray,
    busy: NDArray, count: int = 0,
) -> int:
    """Contacts of a given ``|f|`` (N,), from ``start`` on, numbered into ``cid`` after
    ``count`` earlier ones; pending or held samples marked in ``busy``. Returns the count."""
    n, i = len(t), start
    while i < n:
        j = _first(lambda lo, hi: f[lo:hi] >= on, i, n)
        if j >= n:
            break
        m = _first(lambda lo, hi: f[lo:hi] < off, j + 1, n)
        ok = _held(t, dt, j, m, min_dur)
        if ok.any():
            count += 1
            cid[j + int(np.argmax(ok)) : m] = count
        busy[j:m] = True
        i = m
    return count


def track_contacts(
    t: NDArray, x: NDArray, start: int, config: EstimatorConfig, noise: SensorNoise, state: TrackState | None = None
) -> ContactTrack:
    """Contacts and drift of the tared (filtered) wrench ``x`` (N, 6) at ``t`` (N,), from
    sample ``start`` on (the samples before it are the tare's: no contact, no drift).

    ``state``: a piece of a longer log that goes on from an earlier piece, cut where that
    one's samples were untouched; ``state`` (from that piece's :attr:`ContactTrack.state`)
    is where it left off. Pieces tracked so give the bits of the whole log tracked at once.
    """
    n = len(t)
    on, off = contact_thresholds(config, noise)
    min_dur = config.min_contact_duration
    state = TrackState() if state is None else TrackState(**vars(state))
    alpha = drift_weights(t, config, state.t_last)
    dt = np.zeros(n)
    dt[1:] = np.diff(t)
    if state.t_last is not None and n:
        dt[0] = t[0] - state.t_last
    cid = np.zeros(n, dtype=np.int64)
    busy = np.zeros(n, dtype=bool)
    if not config.drift_tracking:
        drift = _follow_drift(t, x, start, alpha, on, busy, state)
        state.count = _hysteresis(t, dt, _norm3(x[:, :3]), start, on, off, min_dur, cid, busy, state.count)
        y = x
    elif jit_enabled(n):  # the same loop compiled: one pass, no Python iteration per contact
        drift, y = np.zeros((n, 6)), np.empty((n, 6))
        y[:start] = x[:start]
        avg, iavg = _DriftAverage.pack(state), np.array([state.open, state.block, state.count], dtype=np.int64)
        track_kernel(t, dt, x, alpha, start, on, off, min_dur, _BLOCK, _TINY, avg, iavg, cid, busy, drift, y)
        _DriftAverage.unpack(state, avg, iavg)
    else:
        # the contact decisions see the drift subtracted, and the drift follows only while
        # untouched: one loop, an iteration per contact and per chunk of untouched samples
        drift = np.zeros((n, 6))
        avg = _DriftAverage(x, alpha, state)
        count = state.count

        def force_norm(lo, hi):  # |f| with the drift held at avg.b
            return _norm3(x[lo:hi, :3] - avg.b[:3])

        i = start
        while i < n:
            e, before = avg.follow(i, n)
            far = _norm3(x[i:e, :3] - before[:, :3]) >= on
            k = int(np.argmax(far)) if far.any() else e - i
            drift[i : i + k] = before[:k]
            avg.keep(k)
            if k == e - i:
                i = e
                continue
            j = i + k
            # onset at j; the drift is held while the contact is pending or held
            m = _first(lambda lo, hi: force_norm(lo, hi) < off, j + 1, n)
            drift[j:m] = avg.b
            busy[j:m] = True
            ok = _held(t, dt, j, m, min_dur)
            if ok.any():
                count += 1
                cid[j + int(np.argmax(ok)) : m] = count
            i = m
        y = x - drift
        avg.save(state)
        state.count = count
    over = _norm3(drift[:, :3]) > on
    alarm = int(np.argmax(over)) if over.any() and not state.alarmed else -1
    state.alarmed = state.alarmed or alarm >= 0
    if n:
        state.t_last = float(t[-1])
    return ContactTrack(y, drift, cid > 0, cid, alarm, busy, state)


class ContactTracker:
    """:func:`track_contacts` one sample at a time.

    Call :meth:`step` for every sample after the tare; :meth:`reset` after a (re-)tare.
    """

    def __init__(self, config: EstimatorConfig, noise: SensorNoise):
        self.config = config
        self.set_noise(noise)
        self.count = 0  #: contacts so far (not reset by a re-tare)
        self.reset()

    def set_noise(self, noise: SensorNoise) -> None:
        """Thresholds for the (filtered) noise model ``noise`` (a tare that measured it)."""
        self.on, self.off = contact_thresholds(self.config, noise)

    def reset(self) -> None:
        """Forget the drift and the contact (a new tare)."""
        self.drift = self.drift_before = (0.0,) * 6
        self._block = 0  # samples in the open block of the drift average (0: none open)
        self.in_contact = False
        self.contact_id = 0
        self._pending: float | None = None
        self.drift_alarm = False

    def step(self, t: float, dt: float, x: list[float]) -> tuple[tuple[float, ...] | list[float], int]:
        """Sample ``x`` (tared, filtered) at ``t``, ``dt`` s after the previous sample.

        Returns the wrench with the drift subtracted (when tracked) and ``0`` (no contact),
        ``1`` (in contact) or ``2`` (a new contact starts at this sample).
        """
        cfg = self.config
        self.drift_before = b = self.drift
        if not self.drift_alarm and b[0] * b[0] + b[1] * b[1] + b[2] * b[2] > self.on * self.on:
            self.drift_alarm = True
        fx, fy, fz = x[0] - b[0], x[1] - b[1], x[2] - b[2]
        dev = sqrt(fx * fx + fy * fy + fz * fz)
        track = cfg.drift_tracking
        if track:
            y = (fx, fy, fz, x[3] - b[3], x[4] - b[4], x[5] - b[5])
            f = dev
        else:
            y = x
            f = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2])
        code = 0
        if self.in_contact:
            if f >= self.off:
                code = 1
            else:
                self.in_contact = False
                self.contact_id = 0
        elif self._pending is not None:
            if f < self.off:
                self._pending = None
            elif (t - self._pending) + dt >= cfg.min_contact_duration:
                code = self._start()
        elif f >= self.on:
            self._pending = t
            if dt >= cfg.min_contact_duration:  # (t − t) + dt, as in the batch
                code = self._start()
        if (not code and self._pending is None) if track else dev < self.on:  # untouched
            self._follow(min(dt / cfg.drift_time_constant, _MAX_ALPHA), x)
        elif self._block:
            self._block = 0
        return y, code

    def _follow(self, a: float, x: list[float]) -> None:
        if not self._block:
            self._b0, self._p, self._acc = self.drift, 1.0, [0.0] * 6
        self._block += 1
        self._p = p = self._p * (1.0 - a)
        w = a / p
        acc, b0 = self._acc, self._b0
        acc[0] += w * x[0]
        acc[1] += w * x[1]
        acc[2] += w * x[2]
        acc[3] += w * x[3]
        acc[4] += w * x[4]
        acc[5] += w * x[5]
        self.drift = (p * (b0[0] + acc[0]), p * (b0[1] + acc[1]), p * (b0[2] + acc[2]),
                      p * (b0[3] + acc[3]), p * (b0[4] + acc[4]), p * (b0[5] + acc[5]))  # fmt: skip
        if self._block >= _BLOCK or p < _TINY:
            self._block = 0

    def _start(self) -> int:
        self._pending = None
        self.in_contact = True
        self.count += 1
        self.contact_id = self.count
        return 2


def first_contact_pulls(t: NDArray, pulling: NDArray, contact_id: NDArray) -> bool:
    """The first contact after the tare pulls from its onset on for at least
    :data:`START_PULL_TIME` s (the stream raises the flag at the same sample): the signature
    of a tare taken in contact, whose release reads as a pull."""
    idx = np.flatnonzero(contact_id == 1)
    if not len(idx):
        return False
    lead = pulling[idx]
    run = len(lead) if lead.all() else int(np.argmin(lead))
    return run > 0 and bool(t[idx[run - 1]] - t[idx[0]] >= START_PULL_TIME)


def started_in_contact_message(config: EstimatorConfig) -> str:
    """The warning for a log or stream that (probably) started in contact."""
    return (
        f"the first contact after the tare pulls (no contact point where the force pushes in) for {START_PULL_TIME:g} s "
        "or more: the fingertip was probably in contact while taring, so the tare holds the contact force and the "
        "release reads as a pull. Tare with the fingertip untouched (Estimator.tare(), the t key of the live view), "
        "or give a bias (--bias FILE)"
    )


def drift_message(config: EstimatorConfig, t: float) -> str:
    """The warning for a drift of the force beyond the contact threshold since the tare."""
    what = "tracked and subtracted" if config.drift_tracking else "not subtracted (drift_tracking off): contacts may be false"
    return (
        f"the sensor bias drifted by more than the contact threshold ({config.contact_threshold:g} N) since the tare "
        f"(at t = {t:.6g} s); the drift is {what}; re-tare when you can"
    )
