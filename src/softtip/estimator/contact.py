"""Contact onset and release with hysteresis, contact counting, and bias drift tracking.

Per sample after the tare, with ``b`` the drift tracked so far and ``f`` the force of the
tared (filtered) wrench minus ``b`` (minus nothing when ``drift_tracking`` is off):

- **Hysteresis.** A contact starts when ``|f|`` reaches the onset threshold
  ``on = max(contact_threshold, 4.5 σ_f)`` and ends at the first sample with ``|f|`` below
  the release threshold ``max(on − contact_hysteresis · σ_f, min(on, 2.5 σ_f))``, ``σ_f``
  the noise of ``|f|`` from the noise model (root sum of squares of the force noise, after
  the filter; an untouched sensor's ``|f|`` is then ``σ_f / √3`` times a χ with 3 degrees of
  freedom, below ``2.5 σ_f`` 99.97 % of the time). The default 0.05 N is 4.8 ``σ_f`` of the
  Nano17 preset; :data:`ONSET_FLOOR` keeps that separation for a noisier sensor, whose
  threshold would otherwise lie inside its noise. A rising grasp force crossing the onset
  threshold in noise no longer makes several contacts, each resetting the latch.
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

One source for batch and stream: :func:`contact_step` does one sample on a state record
(:func:`new_contact_state`, a float64 vector with named slots) with the parameters of
:func:`contact_params`; :class:`ContactTracker` calls it per sample (compiled when numba is
allowed, as Python otherwise), :func:`track_contacts` runs it over a whole log in one loop
(:func:`contact_run`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from softtip.core._blocks import TIME_EDGE
from softtip.core._jit import lazy_jit, use_numba
from softtip.core.noise import SensorNoise
from softtip.estimator.config import EstimatorConfig

__all__ = [
    "ONSET_FLOOR", "RELEASE_FLOOR", "contact_thresholds", "ContactTrack", "TrackState", "track_contacts", "ContactTracker",
    "START_PULL_TIME", "contact_params", "new_contact_state", "contact_step", "contact_run",
]  # fmt: skip

#: The onset threshold is at least this many ``σ_f`` (the root sum of squares of the force noise
#: model, after the filter), about what the default 0.05 N is for the Nano17 preset (4.8): a
#: sensor noisier than that keeps the onset as far above its noise and the release. With a
#: sensor of 0.03 N per axis (``σ_f`` 0.052 N) measured by the tare, a 0.05 N onset read one
#: press of a synthetic grasp at 1 kHz as 13–26 contacts over six noise seeds (106–116 with the
#: preset kept); a 3 σ_f floor as 2–5; this one as 1.
ONSET_FLOOR = 4.5
#: The release threshold is at least this many ``σ_f``: an untouched sensor's ``|f|`` is below
#: it 99.97 % of the time.
RELEASE_FLOOR = 2.5
#: Largest weight of one sample in the drift average.
_MAX_ALPHA = 0.5
#: The drift average runs in blocks of untouched samples (a block ends at a sample that is
#: not untouched, after _BLOCK samples, or once the product of the (1 − α) falls below
#: _TINY), in the closed form ``b_j = P_j (b_0 + Σ_{k ≤ j} α_k w_k / P_k)``,
#: ``P_j = Π_{k ≤ j} (1 − α_k)``: only products, quotients and running sums.
_BLOCK = 4096
_TINY = 1e-100
#: s; the first contact after a tare that pulls (no pushing contact point) this long says the
#: fingertip was touched while taring (the release then reads as a pull).
START_PULL_TIME = 0.1

# --- the state record: slots of a float64 vector -------------------------------------------
_B = 0  #: 0:6, the drift after the last sample, N and N·m
_B0 = 6  #: 6:12, the open block's start
_ACC = 12  #: 12:18, the open block's running sums of α w / P
_P = 18  #: the open block's product of (1 − α)
_N_BLOCK = 19  #: samples in the open block (0: none open)
_T_PENDING = 20  #: s, the time of a pending onset (NaN: none pending)
_IN_CONTACT = 21  #: 1 in contact (onset confirmed, not released), else 0
_CONTACT_ID = 22  #: the contact's number (0 out of contact)
_COUNT = 23  #: contacts so far (not reset by a re-tare)
_ALARMED = 24  #: 1 once the drift alarm went off
_T_LAST = 25  #: s, the last sample's time in :func:`contact_run` (NaN: none yet)
_STATE_SIZE = 26

# --- the parameters: slots of a float64 vector ---------------------------------------------
_ON = 0  #: onset threshold, N
_OFF = 1  #: release threshold, N
_MIN_DUR = 2  #: minimum contact duration, s
_TAU = 3  #: drift time constant, s
_TRACK = 4  #: 1: subtract the drift (drift_tracking), 0: track it only
_PARAMS_SIZE = 5


def contact_thresholds(config: EstimatorConfig, noise: SensorNoise) -> tuple[float, float]:
    """The onset and release thresholds of ``|f|``, N, for the (filtered) noise ``noise``: the
    onset ``contact_threshold`` or :data:`ONSET_FLOOR` times ``σ_f``, whichever is larger
    (module docs)."""
    sigma = math.sqrt(sum(s * s for s in noise.force_std))
    on = max(config.contact_threshold, ONSET_FLOOR * sigma)
    return on, max(on - config.contact_hysteresis * sigma, min(on, RELEASE_FLOOR * sigma))


def contact_params(config: EstimatorConfig, noise: SensorNoise) -> NDArray[np.float64]:
    """The parameters of :func:`contact_step` (a float64 vector with named slots)."""
    p = np.zeros(_PARAMS_SIZE)
    p[_ON], p[_OFF] = contact_thresholds(config, noise)
    p[_MIN_DUR] = config.min_contact_duration
    p[_TAU] = config.drift_time_constant
    p[_TRACK] = 1.0 if config.drift_tracking else 0.0
    return p


def new_contact_state() -> NDArray[np.float64]:
    """A state record for :func:`contact_step`: no drift, no contact, none counted."""
    s = np.zeros(_STATE_SIZE)
    reset_contact_state(s)
    s[_COUNT] = 0.0
    s[_T_LAST] = math.nan
    return s


def reset_contact_state(state: NDArray[np.float64]) -> None:
    """Forget the drift, the contact and the drift alarm (a new tare); the count goes on."""
    state[_B : _P + 1] = 0.0
    state[_P] = 1.0
    state[_N_BLOCK] = 0.0
    state[_T_PENDING] = math.nan
    state[_IN_CONTACT] = 0.0
    state[_CONTACT_ID] = 0.0
    state[_ALARMED] = 0.0


@lazy_jit(nogil=False)
def contact_step(state, params, t, dt, x0, x1, x2, x3, x4, x5):  # pragma: no cover - compiled
    """One sample ``x`` (tared, filtered; N and N·m) at ``t``, ``dt`` s after the previous one.

    Parameters
    ----------
    state : (_STATE_SIZE,) float
        The state record (:func:`new_contact_state`), read and written.
    params : (_PARAMS_SIZE,) float
        :func:`contact_params`.
    t, dt : float
        s.
    x0, x1, x2, x3, x4, x5 : float
        The wrench.

    Returns
    -------
    code : int
        0 no contact (or pending), 1 in contact, 2 a new contact starts at this sample.
    contact_id : int
        The contact's number, 0 out of contact.
    followed : bool
        The drift average took this sample (the drift in ``state`` changed).
    busy : bool
        A contact pending or held, or the drift not following: a log may not be cut here.
    alarm : bool
        The drift alarm goes off at this sample: the drift before it exceeds the onset
        threshold in force, for the first time since the state was reset.
    y0, y1, y2, y3, y4, y5 : float
        The wrench with the drift before this sample subtracted (``x`` itself when the drift
        is only tracked).
    """
    on = params[_ON]
    off = params[_OFF]
    b0, b1, b2, b3, b4, b5 = state[_B], state[_B + 1], state[_B + 2], state[_B + 3], state[_B + 4], state[_B + 5]
    alarm = False
    if state[_ALARMED] == 0.0 and math.sqrt(b0 * b0 + b1 * b1 + b2 * b2) > on:
        state[_ALARMED] = 1.0
        alarm = True
    fx, fy, fz = x0 - b0, x1 - b1, x2 - b2
    dev = math.sqrt(fx * fx + fy * fy + fz * fz)
    track = params[_TRACK] != 0.0
    if track:
        y0, y1, y2, y3, y4, y5 = fx, fy, fz, x3 - b3, x4 - b4, x5 - b5
        f = dev
    else:
        y0, y1, y2, y3, y4, y5 = x0, x1, x2, x3, x4, x5
        f = math.sqrt(x0 * x0 + x1 * x1 + x2 * x2)
    code = 0
    pending = state[_T_PENDING]
    if state[_IN_CONTACT] != 0.0:
        if f >= off:
            code = 1
        else:
            state[_IN_CONTACT] = 0.0
            state[_CONTACT_ID] = 0.0
    elif pending == pending:  # pending (not NaN)
        if f < off:
            state[_T_PENDING] = math.nan
        elif (t - pending) + dt >= params[_MIN_DUR] - TIME_EDGE:
            code = 2
    elif f >= on:
        state[_T_PENDING] = t
        if dt >= params[_MIN_DUR] - TIME_EDGE:  # (t − t) + dt
            code = 2
    if code == 2:
        state[_T_PENDING] = math.nan
        state[_IN_CONTACT] = 1.0
        state[_COUNT] += 1.0
        state[_CONTACT_ID] = state[_COUNT]
    held = code != 0 or state[_T_PENDING] == state[_T_PENDING]
    followed = not held if track else dev < on  # untouched
    if followed:
        if state[_N_BLOCK] == 0.0:  # a new block of the drift average
            for q in range(6):
                state[_B0 + q] = state[_B + q]
                state[_ACC + q] = 0.0
            state[_P] = 1.0
        state[_N_BLOCK] += 1.0
        a = min(dt / params[_TAU], _MAX_ALPHA)
        p = state[_P] * (1.0 - a)
        state[_P] = p
        w = a / p
        state[_ACC] += w * x0
        state[_ACC + 1] += w * x1
        state[_ACC + 2] += w * x2
        state[_ACC + 3] += w * x3
        state[_ACC + 4] += w * x4
        state[_ACC + 5] += w * x5
        for q in range(6):
            state[_B + q] = p * (state[_B0 + q] + state[_ACC + q])
        if state[_N_BLOCK] >= _BLOCK or p < _TINY:
            state[_N_BLOCK] = 0.0
    else:
        state[_N_BLOCK] = 0.0
    return code, int(state[_CONTACT_ID]), followed, held or not followed, alarm, y0, y1, y2, y3, y4, y5


@lazy_jit
def contact_run(t, x, start, state, params, bias, cid, busy, drift, y, cut_from):  # pragma: no cover - compiled
    """:func:`contact_step` over a log: ``x − bias`` (``x`` (N, 6), ``bias`` (6,)) at ``t`` (N,) s,
    from sample ``start`` on (the bias subtracted here: no tared copy of a raw log).

    The samples before ``start`` (the tare's) only advance the time: ``y = x − bias``, no drift, no
    contact. ``state`` is read and written (its last time in the ``_T_LAST`` slot gives the
    first sample's interval); ``cid`` (N,) int, ``busy`` (N,) bool, ``drift`` (N, 6) (the
    drift before each sample) and ``y`` (N, 6) are written.

    ``cut_from``: the run stops at the first sample ``c ≥ cut_from`` that is not busy (a log
    may be cut there, :func:`track_contacts`), leaving ``state`` as it was after sample
    ``c − 1`` and the arrays written up to ``c − 1``; ``cut_from ≥ N``: no cut, every sample.

    Returns ``(alarm, done)``: the sample at which the drift alarm goes off (-1 if none) and the
    samples run (``c``, or N).
    """
    n = t.shape[0]
    alarm_at = -1
    t_last = state[_T_LAST]
    before = np.empty_like(state)  # the state before the sample a cut may fall on
    for i in range(n):
        dt = 0.0 if t_last != t_last else t[i] - t_last
        t_prev, t_last = t_last, t[i]
        x0, x1, x2 = x[i, 0] - bias[0], x[i, 1] - bias[1], x[i, 2] - bias[2]
        x3, x4, x5 = x[i, 3] - bias[3], x[i, 4] - bias[4], x[i, 5] - bias[5]
        if i < start:
            y[i, 0], y[i, 1], y[i, 2], y[i, 3], y[i, 4], y[i, 5] = x0, x1, x2, x3, x4, x5
            for q in range(6):
                drift[i, q] = 0.0
            cid[i] = 0
            busy[i] = False
            continue
        cutting = i >= cut_from
        if cutting:
            before[:] = state
        for q in range(6):
            drift[i, q] = state[_B + q]
        _, c, _, b, alarm, y0, y1, y2, y3, y4, y5 = contact_step(state, params, t[i], dt, x0, x1, x2, x3, x4, x5)
        if cutting and not b:  # untouched: the next piece starts here, from the state before it
            state[:] = before
            state[_T_LAST] = t_prev
            return alarm_at, i
        y[i, 0], y[i, 1], y[i, 2], y[i, 3], y[i, 4], y[i, 5] = y0, y1, y2, y3, y4, y5
        cid[i] = c
        busy[i] = b
        if alarm and alarm_at < 0:
            alarm_at = i
    state[_T_LAST] = t_last
    return alarm_at, n


@dataclass
class TrackState:
    """What :func:`track_contacts` carries from one piece of a log to the next: the state
    record of :func:`contact_step` after the piece's last sample.

    A log may be tracked piece by piece, cut only at samples that are untouched (no contact
    pending or held, the drift following: ``~ContactTrack.busy``); with this state the
    pieces give the same bits as the whole log. SI units.
    """

    state: NDArray[np.float64] = field(default_factory=new_contact_state)

    @property
    def count(self) -> int:
        """Contacts so far."""
        return int(self.state[_COUNT])


class ContactTrack(NamedTuple):
    """Contacts and drift of a whole log (:func:`track_contacts`)."""

    wrench: NDArray[np.float64]  #: (N, 6) the wrench with the drift subtracted (as given without tracking)
    drift: NDArray[np.float64]  #: (N, 6) drift tracked before each sample, N and N·m
    contact: NDArray[np.bool_]  #: (N,) in contact (onset confirmed, not released)
    contact_id: NDArray[np.int64]  #: (N,) 1, 2, … per contact; 0 out of contact
    drift_alarm: int  #: first sample whose drift force exceeds the contact threshold; -1 if none (or in an earlier piece)
    busy: NDArray[np.bool_] | None = None  #: (N,) a contact pending or held, the drift not following
    state: TrackState | None = None  #: the state after the last sample, for the next piece


def track_contacts(
    t: NDArray, x: NDArray, start: int, config: EstimatorConfig, noise: SensorNoise, state: TrackState | None = None,
    bias: NDArray | None = None, *, cut_from: int | None = None,
) -> ContactTrack | None:
    """Contacts and drift of the tared (filtered) wrench ``x`` (N, 6) at ``t`` (N,), from
    sample ``start`` on (the samples before it are the tare's: no contact, no drift); with
    ``bias`` (6,), of ``x − bias`` (a raw log and its bias: the same bits without a tared copy).

    ``state``: a piece of a longer log that goes on from an earlier piece, cut where that
    one's samples were untouched; ``state`` (from that piece's :attr:`ContactTrack.state`)
    is where it left off. Pieces tracked so give the bits of the whole log tracked at once.

    ``cut_from``: track only up to the first sample at or after ``cut_from`` where the log may
    be cut (untouched); the track is of the samples before it (``len(track.contact)`` of
    them) and its state is where the next piece starts. None when no sample from
    ``cut_from`` on is untouched (a contact goes on past the log's end).
    """
    n = len(t)
    rec = new_contact_state() if state is None else np.array(state.state, dtype=float)
    cid = np.zeros(n, dtype=np.int64)
    busy = np.zeros(n, dtype=bool)
    drift, y = np.empty((n, 6)), np.empty((n, 6))
    run = contact_run.compiled() if use_numba(n) else contact_run.python
    t = np.ascontiguousarray(t, dtype=float)
    x = np.ascontiguousarray(x, dtype=float)
    bias = np.zeros(6) if bias is None else np.ascontiguousarray(bias, dtype=float)
    alarm, done = run(t, x, int(start), rec, contact_params(config, noise), bias, cid, busy, drift, y,
                      n if cut_from is None else int(cut_from))  # fmt: skip
    if cut_from is not None:
        if done == n:
            return None
        y, drift, cid, busy = y[:done], drift[:done], cid[:done], busy[:done]
    return ContactTrack(y, drift, cid > 0, cid, int(alarm), busy, TrackState(rec))


class ContactTracker:
    """:func:`track_contacts` one sample at a time (:func:`contact_step` on a state record).

    Call :meth:`step` for every sample after the tare; :meth:`reset` after a (re-)tare.
    """

    def __init__(self, config: EstimatorConfig, noise: SensorNoise, *, expected_samples: int | None = None):
        self.config = config
        # compiled unless numba is off or missing, or the stream is short (then the same source as Python)
        self._step = contact_step.function(expected_samples)
        self.state = new_contact_state()
        self.set_noise(noise)
        self.reset()
        # load (or compile) the step now, on a scratch state, not at the first sample of a live run
        self._step(new_contact_state(), self.params, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)

    def set_noise(self, noise: SensorNoise) -> None:
        """Thresholds for the (filtered) noise model ``noise`` (a tare that measured it)."""
        self.params = contact_params(self.config, noise)
        self.on, self.off = float(self.params[_ON]), float(self.params[_OFF])

    def reset(self) -> None:
        """Forget the drift and the contact (a new tare); the count goes on."""
        reset_contact_state(self.state)
        self.drift = self.drift_before = (0.0,) * 6
        self.contact_id = 0
        self.drift_alarm = False

    @property
    def count(self) -> int:
        """Contacts so far (not reset by a re-tare)."""
        return int(self.state[_COUNT])

    @count.setter
    def count(self, value: int) -> None:
        self.state[_COUNT] = float(value)

    def step(self, t: float, dt: float, x: list[float]) -> tuple[tuple[float, ...], int]:
        """Sample ``x`` (tared, filtered) at ``t``, ``dt`` s after the previous sample.

        Returns the wrench with the drift subtracted (when tracked) and ``0`` (no contact),
        ``1`` (in contact) or ``2`` (a new contact starts at this sample).
        """
        x0, x1, x2, x3, x4, x5 = x
        return self.apply(self._step(self.state, self.params, t, dt, x0, x1, x2, x3, x4, x5))

    def apply(self, r: tuple) -> tuple[tuple[float, ...], int]:
        """What :meth:`step` returns and keeps of :func:`contact_step`'s returns ``r`` on this
        tracker's state (the step called here, or inside a compiled step that goes on with the
        sample: :func:`softtip.estimator.pipeline.sample_step`)."""
        self.drift_before = self.drift
        self.contact_id = r[1]
        if r[2]:  # the drift followed
            self.drift = tuple(self.state[_B : _B + 6].tolist())
        if r[4]:
            self.drift_alarm = True
        return r[5:], r[0]


def first_contact_pulls(t: NDArray, pulling: NDArray, contact_id: NDArray) -> bool:
    """The first contact after the tare pulls from its onset on for at least
    :data:`START_PULL_TIME` s (the stream raises the flag at the same sample): the signature
    of a tare taken in contact, whose release reads as a pull."""
    idx = np.flatnonzero(contact_id == 1)
    if not len(idx):
        return False
    lead = pulling[idx]
    run = len(lead) if lead.all() else int(np.argmin(lead))
    return run > 0 and bool(t[idx[run - 1]] - t[idx[0]] >= START_PULL_TIME - TIME_EDGE)


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
