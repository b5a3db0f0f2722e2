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
  ``area``** while more than ``area_share`` of the window's samples span both axes (a
  sustained spread: a transient one, as a new rock begins while the window still holds the
  last one, does not make an area), and for one ``evidence_window`` after the last sample
  whose window read it, unless a window confirms a line by its load meanwhile: the window
  after an area reading holds the end of the two-axis spread sliding out, often one rocking
  axis only, which a plane gives as a line does (both give ``h`` on one axis); a window later
  the reading is the current window's again, so a transient cannot lock an area;
* it **confirms a line** when the contact was excited about two axes, as the tangential load
  shows (its own ``minor`` beyond the noise, at least ``excitation_ratio`` times its
  ``major`` and at least ``excitation_min²``) or as the user states (the window wholly inside
  an interval of ``rocked``, not while an area is kept: a stated window that saw one axis cannot
  tell a plane from a line either), ``h`` varied beyond the noise and ``ratio < area_ratio[1]``;
  a confirmed line stays confirmed until the window reads an area;
* it **resolves an axis** when ``h`` varied along one axis (``major`` beyond the noise and at
  least ``h_min²``, ``ratio < area_ratio[1]``) with an angle standard deviation at most
  ``evidence_max_angle_std``.

Where the contact reads ``area`` the sample is ``area`` (no direction). Otherwise it is a
``line`` where ``|h|`` is significant or the current window resolves an axis (``h`` passing
through zero while the object rocks does not make a line a point), and ``point`` elsewhere,
except inside a confirmed line with a window direction held. Significance has hysteresis:
once above the measurement's threshold, ``|h|`` stays significant down to :data:`SIG_LEAVE`
of it; and at high sample rates the samples of the segment's last ``significance_window``
seconds vote (most above the threshold: significant; most below its leaving share: not; else
unchanged), so noise near the threshold does not flicker (at 50 Hz the window holds one
sample: each decides alone).

The direction: the current window's where it resolves an axis (``d = n × principal axis``),
with the model error ``evidence_model_std`` in quadrature where that window itself confirms the
line with the load turned about two axes, and ``window_model_std`` where it does not, also
where only a stated rocking confirms it (a one-axis window's rolling bias follows its own
excitation, whether or not the line was confirmed before); in a confirmed line whose current
window resolves none (``h`` held still, or passing through zero), the latest window of this
segment that confirmed it and resolved an axis (``h`` on one axis, varied by at least
``h_min``), with ``evidence_model_std`` where its load turned about two axes and
``unconfirmed_model_std`` where only a stated rocking confirmed it (held for later samples, it
carries what the window saw of the roll); the sample's own elsewhere. The current window is
preferred to the confirming one: a confirming window is a moment of two-axis load, often where
one rock ends and the next begins, and it can carry the contact's response to a roll about the
line's own axis (on a stiffer, smaller hydroelastic tip: 8° off where the current windows are 1.3°
off in the median). A sample's own angle standard deviation counts the window's across-axis spread
beyond the noise as model error, ``sqrt(σ_d² + minor / |h|²)``, plus ``unconfirmed_model_std``
unless a confirming window whose load turned about two axes is held. The share of the standard
deviation that is the sensor noise's alone (``angle_noise_std``: the window's noise term, or
the sample's ``σ_d``) is kept apart: two sensors share the model error, not their noise
(:mod:`softtip.fusion`).

Every ``line`` sample's standard deviation also counts, in quadrature, the **twist** of the
contact, ``atan(|σ| / (R F_n))`` with ``σ = q · n`` the moment about the normal, ``F_n`` the
normal force and ``R`` the skin's radius at the contact (:func:`twist_curvature`): a line
pressed into a cap of radius ``R`` whose ``h`` comes from its tilt lies out of the tangent
plane by ``|h| / (R F_n)``, so a twist about the *object's* own axis (friction on the faces
of a plate sunk into the skin: Drake's hydroelastic contact with SAP friction, 5–13 N·mm on
1–2 mm plates) shows in the tangent plane as ``σ`` times that tilt, along the line, and turns
``h`` by ``atan(σ / (R F_n))``; a twist in the skin's own surface (softtip's Winkler shear
layer) turns nothing. The wrench does not say which of the two it is (manual §3.7, friction
depth). Not counted with ``line_evidence`` off (the papers' noise only) or on a fingertip
without a known radius.

The stage is one step, :func:`evidence_step`, over a state record (:func:`new_evidence_state`):
running sums of the products (:func:`~softtip.core.evidence.evidence_products`) since the
segment's start and a ring buffer of the segment's latest located samples (their time, the
running sums before them, their significance side and whether they spread over both axes),
from which the three windows (the evidence window's sums, its area votes, and the
significance votes) are read as differences and counts: O(1) per sample.
:func:`evidence_states` runs it over a whole log in one compiled loop (:func:`evidence_run`),
:class:`EvidenceTracker` one sample at a time; the same source runs compiled (numba) or as
Python (:mod:`softtip.core._jit`). Each rule is written once: the window's readings in
:func:`window_reading`, the verdict and the held window in :func:`_update_verdict`, the
significance in :func:`_significance`, the sample's output in :func:`_choose`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from softtip.core import _xp_scalar as XS
from softtip.core._blocks import TIME_EDGE, ring_rows
from softtip.core._jit import lazy_jit
from softtip.core._xp import NP
from softtip.core.evidence import (
    N_SUMS,
    _div,
    evidence_products,
    noise_constants,
    tangent_noise_kernel,
    window_constants,
    window_direction,
    window_eigen,
)  # fmt: skip
from softtip.core.noise import SensorNoise, line_threshold_kernel, noise_variances, sample_direction_kernel
from softtip.core.spin import tangent_frame_kernel
from softtip.estimator.config import EstimatorConfig
from softtip.estimator.floats import PointGeometry

__all__ = [
    "evidence_states", "EvidenceStates", "EvidenceTracker", "evidence_params", "new_evidence_state", "evidence_start",
    "evidence_step", "evidence_run", "twist_curvature",
]  # fmt: skip


class EvidenceStates(NamedTuple):
    """What :func:`evidence_states` gives for a whole log (N samples)."""

    state: NDArray  #: (N,) int8, POINT, LINE or AREA (where located)
    evidence: NDArray  #: (N,) int8, 1 unconfirmed, 2 confirmed (lines)
    direction: NDArray  #: (N, 3) unit line direction (the current or the confirming window's, or the sample's; NaN unless line)
    angle: NDArray  #: (N,) rad, the direction's angle in the tangent frame
    angle_std: NDArray  #: (N,) rad, its standard deviation
    angle_noise_std: NDArray  #: (N,) rad, the sensor noise's share of it (the rest is model error)
    h_ratio: NDArray  #: (N,) minor / major eigenvalue of h's covariance in the window
    excitation_ratio: NDArray  #: (N,) the same for the tangential force (how far it turned)


#: A significant ``|h|`` stays significant down to this share of the threshold (hysteresis).
SIG_LEAVE = 2.0 / 3.0
#: Verdicts of a segment.
_UNKNOWN, _LINE, _AREA = 0, 1, 2
#: The sample's state codes (:data:`~softtip.estimator.results.STATES`) and evidence codes.
_POINT_CODE, _LINE_CODE, _AREA_CODE = 1, 2, 3
_UNCONFIRMED, _CONFIRMED = 1, 2
_NAN = math.nan

# -- the parameters: a float64 vector (evidence_params) ----------------------------------------------
_ON = 0  # line_evidence (1.0 or 0.0)
_WINDOW = 1  # evidence_window, s
_H_SIGMAS = 2
_H_MIN = 3  # N·m
_ENTER = 4  # area_ratio
_LEAVE = 5
_FMIN2 = 6  # excitation_min², N²
_HMIN2 = 7  # h_min², N²·m²
_F_RATIO = 8  # excitation_ratio
_MAX_STD = 9  # evidence_max_angle_std, rad
_MODEL_VAR = 10  # evidence_model_std², rad²
_UNCONF_VAR = 11  # unconfirmed_model_std², rad²
_RESET2 = 12  # evidence_reset_distance², m²
_VOTE_WINDOW = 13  # significance_window, s
_AREA_SHARE = 14
_NOISE = 15  # the sensor noise's variances (after any filter): fx, fy, fz (N²), mx, my, mz (N²·m²)
_INV_RADIUS = 21  # 1 / R of the twist term (twist_curvature), 1/m; 0: not counted
_WIN_VAR = 22  # window_model_std², rad²
_N_ROCKED = 23  # how many stated rocking intervals follow
_ROCKED = 24  # (start, end) of each, s

# -- the state record: a float64 vector, an int64 vector of counters, a ring buffer ------------------
_CUM = 0  # N_SUMS running sums of the products since the segment's start
_ANCHOR = _CUM + N_SUMS  # 3: the located point where the segment's window started, m
_HAS_ANCHOR = _ANCHOR + 3
_VERDICT = _HAS_ANCHOR + 1  # _UNKNOWN, _LINE or _AREA
_HAS_HELD = _VERDICT + 1  # a confirming window of this segment (since its last area reading) is held
_HELD_ANGLE = _HAS_HELD + 1  # its direction, rad
_HELD_STD = _HELD_ANGLE + 1  # its standard deviation with the model error of its kind, rad
_HELD_NOISE = _HELD_STD + 1  # the noise's share, rad
_HELD_SEEN = _HELD_NOISE + 1  # 1.0: its load turned about both axes (not only a stated rocking)
_SIG = _HELD_SEEN + 1  # |h| significant (the last decided vote)
_AREA_T = _SIG + 1  # s: the latest sample whose window read an area (kept one window after it)
_N_STATE = _AREA_T + 1

_HEAD = 0  # the ring's slot of the latest sample
_N_WIN = 1  # samples in the evidence window (t_i > t − evidence_window; may be none)
_N_AREA = 2  # samples of the area vote (the evidence window, at least the latest)
_N_SPREAD = 3  # of them spread over both axes
_N_VOTE = 4  # samples of the significance vote (t_i > t − significance_window, at least the latest)
_N_ABOVE = 5  # of them above the threshold
_N_BELOW = 6  # of them below its leaving share
_N_COUNTERS = 7

_R_T = 0  # ring columns: the sample's time, s
_R_CUM = 1  # N_SUMS: the running sums before it
_R_SIDE = _R_CUM + N_SUMS  # its significance side: 1 above, 0 below the leaving share, −1 between
_R_SPREAD = _R_SIDE + 1  # 1.0: its window spread over both axes (an area vote)
_R_WIDTH = _R_SPREAD + 1


def twist_curvature(tip) -> float:
    """``1 / R`` (1/m) of the twist term of the standard deviation (module docs), ``R`` the
    fingertip's :attr:`~softtip.core.shape.Fingertip.twist_radius` (a sphere's, a capsule's);
    0.0 (no term) for shapes whose curvature along the line is not one number."""
    radius = tip.twist_radius
    return 0.0 if radius is None else 1.0 / radius


def evidence_params(config: EstimatorConfig, noise: SensorNoise, inv_radius: float = 0.0) -> NDArray[np.float64]:
    """The step's parameters (float64 vector) from the configuration, the noise model (after
    any filter) and the twist term's ``1 / R`` (:func:`twist_curvature`, 1/m; 0: none); the
    stated rocking intervals (:attr:`EstimatorConfig.rocked`) at its end."""
    rocked = [float(x) for ab in config.rocked for x in ab]
    p = np.zeros(_ROCKED + len(rocked))
    enter, leave = config.area_ratio
    p[_ON] = 1.0 if config.line_evidence else 0.0
    p[_WINDOW] = config.evidence_window
    p[_H_SIGMAS], p[_H_MIN] = config.h_sigmas, config.h_min
    p[_ENTER], p[_LEAVE] = enter, leave
    p[_FMIN2] = config.excitation_min * config.excitation_min
    p[_HMIN2] = config.h_min * config.h_min
    p[_F_RATIO] = config.excitation_ratio
    p[_MAX_STD] = config.evidence_max_angle_std
    p[_MODEL_VAR] = config.evidence_model_std * config.evidence_model_std
    p[_UNCONF_VAR] = config.unconfirmed_model_std * config.unconfirmed_model_std
    p[_RESET2] = float(config.evidence_reset_distance) * float(config.evidence_reset_distance)
    p[_VOTE_WINDOW] = config.significance_window
    p[_AREA_SHARE] = config.area_share
    p[_NOISE : _NOISE + 6] = noise_variances(noise)
    p[_INV_RADIUS] = float(inv_radius)
    p[_WIN_VAR] = config.window_model_std * config.window_model_std
    p[_N_ROCKED] = len(config.rocked)
    p[_ROCKED:] = rocked
    return p


def new_evidence_state(capacity: int, corr: float):
    """``(state, counts, ring, wconst)``: an empty state record whose ring holds ``capacity``
    samples (at least one more than any window will), and the window constants
    (:func:`~softtip.core.evidence.window_constants`) by window length ``0 … capacity``, (capacity + 1, 3)."""
    ring = np.zeros((capacity, _R_WIDTH))
    wconst = np.ascontiguousarray(np.stack(window_constants(np.arange(capacity + 1), corr), axis=-1))
    return np.zeros(_N_STATE), np.zeros(_N_COUNTERS, dtype=np.int64), ring, wconst


@lazy_jit(nogil=False)
def evidence_start(state, counts):
    """A new segment (contact onset, re-latch, a moved point): empty windows, no verdict, no held window."""
    for q in range(N_SUMS):
        state[_CUM + q] = 0.0
    state[_HAS_ANCHOR] = 0.0
    state[_VERDICT] = _UNKNOWN
    state[_HAS_HELD] = 0.0
    state[_SIG] = 0.0
    for q in range(_N_COUNTERS):
        counts[q] = 0


@lazy_jit
def _oldest(counts, ring, n):
    """The ring's slot of the oldest of the latest ``n ≥ 1`` samples."""
    cap = ring.shape[0]
    return (counts[_HEAD] + 1 - n + cap) % cap


@lazy_jit
def _stated(params, t):
    """The evidence window ending at ``t`` lies wholly inside a stated two-axis rocking
    interval (:attr:`EstimatorConfig.rocked`: its start ``t − evidence_window`` at or after
    the interval's start, ``t`` at or before its end)."""
    start = t - params[_WINDOW] + TIME_EDGE
    for k in range(int(params[_N_ROCKED])):
        if start >= params[_ROCKED + 2 * k] and t - TIME_EDGE <= params[_ROCKED + 2 * k + 1]:
            return True
    return False


@lazy_jit
def window_reading(major, minor, h_noise, f_major, f_minor, f_noise, hn, thr, params):
    """What the window says: ``(h_ratio, f_ratio, spread, one_axis, excited)``.

    ``spread``: the window spans both axes at a sample whose ``|h|`` is significant (``hn >
    thr``), provided the load turned about its weaker axis too or ``minor ≥ h_min²`` (an
    area vote); ``one_axis``: ``h`` varied along one axis; ``excited``: the load shows a
    two-axis excitation. NaN comparisons are False."""
    varied = major > h_noise
    h_ratio = _div(minor, major) if varied else _NAN
    f_ratio = _div(f_minor, f_major) if f_major > f_noise else _NAN
    # a two-axis h counts when the load turned about its weaker axis too, or when h's spread
    # about that axis exceeds the model's error floor h_min (a point gone stale, whatever the
    # load); below it, without a turning load, it is the model's error (a grasp force
    # settling); and only where |h| itself is significant: sub-threshold h wanders about both
    # axes with the model's error once a low-pass has removed the noise
    turned = f_minor > f_noise and f_minor >= params[_FMIN2]
    spread = minor > h_noise and h_ratio >= params[_ENTER] and hn > thr and (turned or minor >= params[_HMIN2])
    one_axis = varied and h_ratio < params[_LEAVE]
    excited = f_minor > f_noise and f_minor >= params[_F_RATIO] * f_major and f_minor >= params[_FMIN2]
    return h_ratio, f_ratio, spread, one_axis, excited


@lazy_jit
def _update_verdict(state, params, t, area, one_axis, excited, e, s2, nu):
    """The segment's verdict and held confirming window after this sample's window (``e``:
    :func:`~softtip.core.evidence.window_eigen`); returns ``(axis, confirming, angle,
    angle_std, angle_noise_std)``: the window resolves an axis (its direction, without model
    error), and confirms the line with the load turned about two axes."""
    if area:
        # a confirmed line stays confirmed until the window reads an area
        state[_VERDICT] = _AREA
        state[_AREA_T] = t
        state[_HAS_HELD] = 0.0
        return False, False, _NAN, _NAN, _NAN
    # excited about two axes: the load shows it, or the user says so (where the load is locked
    # to h, as on a frictionless round skin, it cannot); a statement does not overturn an area
    # the data showed within the last window (_kept_area): a stated window that saw one axis
    # cannot tell a plane from a line either
    line_now = one_axis and (excited or (not _kept_area(state, params, t) and _stated(params, t)))
    if line_now:
        state[_VERDICT] = _LINE
    if not one_axis:
        return False, False, _NAN, _NAN, _NAN
    angle, angle_std, noise_std = window_direction(e[0], e[1], e[2], e[3], e[4], e[5], e[6], e[7], e[8], e[9], s2, nu)
    if not angle_std <= params[_MAX_STD]:
        return False, False, angle, angle_std, noise_std
    # h varied along one axis with an eigen-gap beyond the noise and by at least h_min: the
    # window's principal axis is the direction, confirmed or not (one axis of excitation
    # leaves a rolling bias, which the one-axis window's model error covers)
    axis = e[0] >= params[_HMIN2]
    confirming = False
    if line_now and axis:
        # a confirmed line's direction comes from two-axis windows only, with the two-axis
        # model error where the load showed the two axes (a stated window may have seen one
        # axis of the rocking, and on a frictionless cap it also carries the roll about the
        # line's own axis)
        confirming = excited
        model = params[_MODEL_VAR] if excited else params[_UNCONF_VAR]
        state[_HAS_HELD] = 1.0
        state[_HELD_ANGLE] = angle
        state[_HELD_STD] = math.sqrt(angle_std * angle_std + model)
        state[_HELD_NOISE] = noise_std
        state[_HELD_SEEN] = 1.0 if excited else 0.0
    return axis, confirming, angle, angle_std, noise_std


@lazy_jit
def _kept_area(state, params, t):
    """An area read within the last ``evidence_window`` s and not overturned since (the verdict
    still area): the window after an area reading holds the end of the two-axis spread sliding
    out, often one rocking axis only, which a plane gives as a line does; a window later the
    reading is the current window's again (a transient does not lock an area)."""
    return state[_VERDICT] == _AREA and t - state[_AREA_T] <= params[_WINDOW]


@lazy_jit
def _significance(state, counts, ring, params, t, hn, thr):
    """``|h|`` significant, with hysteresis (down to :data:`SIG_LEAVE` of the threshold) and
    the vote of the segment's samples of the last ``significance_window`` s (most above: yes;
    most below the leaving share: no; else unchanged)."""
    side = 1 if hn > thr else (0 if hn <= SIG_LEAVE * thr else -1)
    if params[_VOTE_WINDOW] > 0.0:
        head = counts[_HEAD]
        ring[head, _R_SIDE] = side
        counts[_N_VOTE] += 1
        counts[_N_ABOVE] += 1 if side == 1 else 0
        counts[_N_BELOW] += 1 if side == 0 else 0
        start = t - params[_VOTE_WINDOW] + TIME_EDGE
        while counts[_N_VOTE] > 1:
            j = _oldest(counts, ring, counts[_N_VOTE])
            if ring[j, _R_T] > start:
                break
            counts[_N_ABOVE] -= 1 if ring[j, _R_SIDE] == 1.0 else 0
            counts[_N_BELOW] -= 1 if ring[j, _R_SIDE] == 0.0 else 0
            counts[_N_VOTE] -= 1
        m = counts[_N_VOTE]
        side = 1 if 2 * counts[_N_ABOVE] > m else (0 if 2 * counts[_N_BELOW] > m else -1)
    if side >= 0:
        state[_SIG] = 1.0 if side == 1 else 0.0
    return state[_SIG] != 0.0


@lazy_jit
def _own(hx, hy, hz, ex, ey, ez, nx, ny, nz, e1x, e1y, e1z, e2x, e2y, e2z, params):
    """The sample's own direction, ``(dx, dy, dz, angle, angle_std)``
    (:func:`~softtip.core.noise.sample_direction_kernel`)."""
    return sample_direction_kernel(
        hx, hy, hz, ex, ey, ez, nx, ny, nz, e1x, e1y, e1z, e2x, e2y, e2z, params[_NOISE], params[_NOISE + 1],
        params[_NOISE + 2], params[_NOISE + 3], params[_NOISE + 4], params[_NOISE + 5], XS,
    )[1:]  # fmt: skip


@lazy_jit(nogil=False)
def evidence_step(state, counts, ring, params, wconst, t, px, py, pz, nx, ny, nz, e1x, e1y, e1z, e2x, e2y, e2z,
                  ex, ey, ez, hx, hy, hz, fx, fy, fz, hn, h_std, sg):  # fmt: skip
    """One located sample through the stage.

    Parameters
    ----------
    state, counts, ring : arrays
        The state record (:func:`new_evidence_state`), updated; the ring holds at least one
        more sample than the largest of the three windows before the call.
    params : (P,) float
        :func:`evidence_params`.
    wconst : (capacity + 1, 3) float
        The window constants by window length (:func:`new_evidence_state`).
    t : float
        s.
    px, py, pz, nx, ny, nz : float
        The contact point (m) and its unit normal.
    e1x, e1y, e1z, e2x, e2y, e2z : float
        The tangent frame at the normal (:func:`~softtip.core.spin.tangent_frame_kernel`).
    ex, ey, ez : float
        m, the point ``h`` is taken about (the point, or the effective point under the depth).
    hx, hy, hz, fx, fy, fz : float
        ``h`` (N·m) and the force (N).
    hn, h_std : float
        ``|h|`` and ``h``'s noise level (N·m) of the measurement stage.
    sg : float
        ``σ = q · n``, the moment about the normal (N·m) of the measurement stage: the
        twist term of the standard deviation (module docs).

    Returns
    -------
    tuple
        ``(state, evidence, dx, dy, dz, angle, angle_std, angle_noise_std, h_ratio, f_ratio)``:
        the state code (1 point, 2 line, 3 area), the evidence code (0, 1 unconfirmed, 2
        confirmed), the direction and its angle (rad), standard deviation and noise share
        (NaN unless line), and the window ratios.
    """
    thr = line_threshold_kernel(h_std, params[_H_SIGMAS], params[_H_MIN], XS)  # the measurement's
    if params[_ON] == 0.0:  # the papers' per-sample line test
        if hn > thr:
            dx, dy, dz, angle, a = _own(hx, hy, hz, ex, ey, ez, nx, ny, nz, e1x, e1y, e1z, e2x, e2y, e2z, params)
            return _LINE_CODE, _UNCONFIRMED, dx, dy, dz, angle, a, a, _NAN, _NAN
        return _POINT_CODE, 0, _NAN, _NAN, _NAN, _NAN, _NAN, _NAN, _NAN, _NAN
    # the contact point moved farther than evidence_reset_distance from where the window
    # started (e.g. a line-fit point found): a new segment
    if state[_HAS_ANCHOR] != 0.0:
        dx, dy, dz = px - state[_ANCHOR], py - state[_ANCHOR + 1], pz - state[_ANCHOR + 2]
        if dx * dx + dy * dy + dz * dz > params[_RESET2]:
            evidence_start(state, counts)
    if state[_HAS_ANCHOR] == 0.0:
        state[_ANCHOR], state[_ANCHOR + 1], state[_ANCHOR + 2] = px, py, pz
        state[_HAS_ANCHOR] = 1.0

    # the sample joins the ring (its time and the running sums before it) and the sums
    cap = ring.shape[0]
    head = (counts[_HEAD] + 1) % cap
    counts[_HEAD] = head
    ring[head, _R_T] = t
    h1 = hx * e1x + hy * e1y + hz * e1z
    h2 = hx * e2x + hy * e2y + hz * e2z
    f1 = fx * e1x + fy * e1y + fz * e1z
    f2 = fx * e2x + fy * e2y + fz * e2z
    prods = evidence_products(h1, h2, f1, f2)
    for q in range(N_SUMS):
        ring[head, _R_CUM + q] = state[_CUM + q]
        state[_CUM + q] = state[_CUM + q] + prods[q]
    # the evidence window: the segment's samples with t_i > t − evidence_window; its sums are
    # differences of the running sums
    start = t - params[_WINDOW] + TIME_EDGE
    n = counts[_N_WIN] + 1
    while n > 0 and ring[_oldest(counts, ring, n), _R_T] <= start:
        n -= 1
    counts[_N_WIN] = n
    if n > 0:  # the running sums before the window's first sample
        o, ob = ring[_oldest(counts, ring, n)], _R_CUM
    else:  # an empty window (t − evidence_window rounds to t): no sums, 0 / 0 covariances
        o, ob = state, _CUM
    h11, h12, h22, f11, f12, f22 = tangent_noise_kernel(
        px, py, pz, e1x, e1y, e1z, e2x, e2y, e2z, params[_NOISE], params[_NOISE + 1], params[_NOISE + 2],
        params[_NOISE + 3], params[_NOISE + 4], params[_NOISE + 5],
    )  # fmt: skip
    s_big, s2, f_n = noise_constants(h11, h12, h22, f11, f12, f22)
    tail, keep, nu = wconst[n, 0], wconst[n, 1], wconst[n, 2]
    e = window_eigen(
        state[_CUM] - o[ob], state[_CUM + 1] - o[ob + 1], state[_CUM + 2] - o[ob + 2], state[_CUM + 3] - o[ob + 3],
        state[_CUM + 4] - o[ob + 4], state[_CUM + 5] - o[ob + 5], state[_CUM + 6] - o[ob + 6],
        state[_CUM + 7] - o[ob + 7], state[_CUM + 8] - o[ob + 8], state[_CUM + 9] - o[ob + 9], float(n),
        h11, h12, h22, f11, f12, f22, keep,
    )  # fmt: skip
    major, minor = e[0], e[1]
    h_ratio, f_ratio, spread, one_axis, excited = window_reading(
        major, minor, tail * s_big, e[10], e[11], tail * f_n, hn, thr, params
    )
    # area: more than area_share of the evidence window's samples spread over both axes (a
    # sustained spread: a transient one does not make an area), kept one window (_kept_area)
    ring[head, _R_SPREAD] = 1.0 if spread else 0.0
    counts[_N_AREA] += 1
    counts[_N_SPREAD] += 1 if spread else 0
    while counts[_N_AREA] > 1:
        j = _oldest(counts, ring, counts[_N_AREA])
        if ring[j, _R_T] > start:
            break
        counts[_N_SPREAD] -= 1 if ring[j, _R_SPREAD] == 1.0 else 0
        counts[_N_AREA] -= 1
    area = counts[_N_SPREAD] > params[_AREA_SHARE] * counts[_N_AREA]
    axis, confirming, w_angle, w_std, w_noise = _update_verdict(state, params, t, area, one_axis, excited, e, s2, nu)
    sig = _significance(state, counts, ring, params, t, hn, thr)
    r = _choose(state, params, area or _kept_area(state, params, t), axis, confirming, sig, w_angle, w_std, w_noise, minor, h_ratio, f_ratio,
                hx, hy, hz, hn, ex, ey, ez, nx, ny, nz, e1x, e1y, e1z, e2x, e2y, e2z)  # fmt: skip
    if r[0] != _LINE_CODE or params[_INV_RADIUS] == 0.0:
        return r
    # the twist about the object's own axis, seen through the line's tilt (module docs)
    tw = math.atan(abs(sg) * params[_INV_RADIUS] / -(fx * nx + fy * ny + fz * nz))
    return r[0], r[1], r[2], r[3], r[4], r[5], math.sqrt(r[6] * r[6] + tw * tw), r[7], r[8], r[9]


@lazy_jit
def _choose(state, params, area, axis, confirming, sig, w_angle, w_std, w_noise, minor, h_ratio, f_ratio,
            hx, hy, hz, hn, ex, ey, ez, nx, ny, nz, e1x, e1y, e1z, e2x, e2y, e2z):  # fmt: skip
    """The sample's state and direction (the returns of :func:`evidence_step`)."""
    if area:
        return _AREA_CODE, 0, _NAN, _NAN, _NAN, _NAN, _NAN, _NAN, h_ratio, f_ratio
    confirmed = state[_VERDICT] == _LINE
    held = confirmed and state[_HAS_HELD] != 0.0
    if held and not axis:
        # a confirmed line whose current window resolves no axis (h held still, or passing
        # through zero): the latest window of this segment that confirmed it
        angle, angle_std, noise_std = state[_HELD_ANGLE], state[_HELD_STD], state[_HELD_NOISE]
    elif not sig and not axis:
        return _POINT_CODE, 0, _NAN, _NAN, _NAN, _NAN, _NAN, _NAN, h_ratio, f_ratio
    elif axis:
        # the current window resolves the axis: its direction with the model error of its kind
        # (two-axis where this window confirms the line by its load, else one-axis)
        angle, noise_std = w_angle, w_noise
        angle_std = math.sqrt(w_std * w_std + (params[_MODEL_VAR] if confirming else params[_WIN_VAR]))
    else:
        # the sample's own direction, the window's across-axis spread counted as model error,
        # and the one-axis one unless a window whose load turned about two axes confirmed the line
        dx, dy, dz, angle, a = _own(hx, hy, hz, ex, ey, ez, nx, ny, nz, e1x, e1y, e1z, e2x, e2y, e2z, params)
        by_load = held and state[_HELD_SEEN] != 0.0
        v = a * a + _div(minor, hn * hn) + (0.0 if by_load else params[_UNCONF_VAR])
        ev = _CONFIRMED if confirmed else _UNCONFIRMED
        return _LINE_CODE, ev, dx, dy, dz, angle, (math.sqrt(v) if v >= 0.0 else _NAN), a, h_ratio, f_ratio
    ca, sa = math.cos(angle), math.sin(angle)
    dx, dy, dz = ca * e1x + sa * e2x, ca * e1y + sa * e2y, ca * e1z + sa * e2z
    ev = _CONFIRMED if confirmed else _UNCONFIRMED
    return _LINE_CODE, ev, dx, dy, dz, angle, angle_std, noise_std, h_ratio, f_ratio


@lazy_jit
def evidence_run(t, located, begin, point, normal, e1x, e1y, e1z, e2x, e2y, e2z, depth, h, force, h_norm, h_std,
                 sigma, params, wconst, state, counts, ring, code, evidence, direction, out):  # fmt: skip
    """:func:`evidence_step` over a log of N samples: a new segment at every ``begin``, the
    located samples stepped, the others written as not located (state 1, evidence 0, NaN).

    ``point``, ``normal``, ``h``, ``force`` (N, 3); ``e1x … e2z``, ``depth`` (m), ``h_norm``,
    ``h_std``, ``sigma`` (N,); ``code``, ``evidence`` (N,) int8, ``direction`` (N, 3) and ``out`` (N, 5:
    angle, angle_std, angle_noise_std, h_ratio, f_ratio) written.
    """
    for i in range(t.shape[0]):
        if begin[i]:
            evidence_start(state, counts)
        if not located[i]:
            code[i], evidence[i] = _POINT_CODE, 0
            for k in range(3):
                direction[i, k] = _NAN
            for k in range(5):
                out[i, k] = _NAN
            continue
        nx, ny, nz = normal[i, 0], normal[i, 1], normal[i, 2]
        d = depth[i]
        px, py, pz = point[i, 0], point[i, 1], point[i, 2]
        r = evidence_step(
            state, counts, ring, params, wconst, t[i], px, py, pz, nx, ny, nz, e1x[i], e1y[i], e1z[i], e2x[i],
            e2y[i], e2z[i], px - d * nx, py - d * ny, pz - d * nz, h[i, 0], h[i, 1], h[i, 2], force[i, 0],
            force[i, 1], force[i, 2], h_norm[i], h_std[i], sigma[i],
        )  # fmt: skip
        code[i], evidence[i] = r[0], r[1]
        direction[i, 0], direction[i, 1], direction[i, 2] = r[2], r[3], r[4]
        out[i, 0], out[i, 1], out[i, 2], out[i, 3], out[i, 4] = r[5], r[6], r[7], r[8], r[9]


def evidence_states(t, located, begin, point, normal, h, force, ms, noise: SensorNoise, corr: float,
                    config: EstimatorConfig, depth=None, inv_radius: float = 0.0):  # fmt: skip
    """The evidence stage over a whole log: :func:`evidence_step` in one loop (:func:`evidence_run`).

    Parameters
    ----------
    t : (N,) s, non-decreasing
    located : (N,) bool
        Samples with a contact point and a pushing force (the window's samples).
    begin : (N,) bool
        Segment starts: contact onset and re-latch.
    point, normal : (N, 3)
        Contact point (m) and normal the measurement used.
    h : (N, 3)
        Tangential spin torque, N·m, taken about ``point − depth · normal``.
    force : (N, 3)
        Force, N.
    ms : Measurement
        The measurement stage's output (its ``h_norm``, ``h_std``, and ``sigma`` with the twist
        term).
    noise : SensorNoise
        Per-sample noise (after any filter).
    corr : float
        Samples per independent noise sample.
    config : EstimatorConfig
    depth : (N,) m, optional
        The depth ``h`` is taken under (default none).
    inv_radius : float
        ``1 / R`` of the twist term (:func:`twist_curvature`), 1/m; 0: none.

    Returns
    -------
    tuple
        :class:`EvidenceStates`: state codes of :data:`~softtip.estimator.results.STATES`
        (``point`` / ``line`` / ``area`` on located samples), evidence codes of
        :data:`~softtip.estimator.results.EVIDENCE`, the direction and its angle, standard
        deviation and the noise's share of it (NaN unless ``line``) and the window ratios.
    """
    n = len(t)
    t = np.ascontiguousarray(t, dtype=float)
    capacity = int(ring_rows.function(n)(t, max(config.evidence_window, config.significance_window)))
    state, counts, ring, wconst = new_evidence_state(capacity, corr)
    frame = tangent_frame_kernel(*(np.ascontiguousarray(normal[:, k]) for k in range(3)), NP)
    depth = np.zeros(n) if depth is None else np.ascontiguousarray(depth, dtype=float)
    code, evidence = np.empty(n, dtype=np.int8), np.empty(n, dtype=np.int8)
    direction, out = np.empty((n, 3)), np.empty((n, 5))
    evidence_run.function(len(t))(
        t, np.ascontiguousarray(located, dtype=bool), np.ascontiguousarray(begin, dtype=bool), point, normal,
        *(np.ascontiguousarray(e, dtype=float) for e in frame), depth, h, force,
        np.ascontiguousarray(ms.h_norm, dtype=float), np.ascontiguousarray(ms.h_std, dtype=float),
        np.ascontiguousarray(ms.sigma, dtype=float) if inv_radius else np.zeros(n),
        evidence_params(config, noise, inv_radius), wconst, state, counts, ring, code, evidence, direction, out,
    )  # fmt: skip
    return EvidenceStates(code, evidence, direction, out[:, 0], out[:, 1], out[:, 2], out[:, 3], out[:, 4])


_STATE_NAMES = ("", "point", "line", "area")
_EVIDENCE_NAMES = ("", "unconfirmed", "confirmed")


class EvidenceTracker:
    """The stage of :func:`evidence_states`, one sample at a time: :func:`evidence_step` on its
    state record, whose ring grows (oldest first) when a window would fill it."""

    def __init__(
        self, config: EstimatorConfig, noise: SensorNoise, corr: float, inv_radius: float = 0.0, *,
        expected_samples: int | None = None,
    ):  # fmt: skip
        self.config = config
        self.noise = noise
        self.corr = corr
        self._params = evidence_params(config, noise, inv_radius)
        self._state, self._counts, self._ring, self._wconst = new_evidence_state(64, corr)
        self._step = evidence_step.function(expected_samples)
        self._start = evidence_start.function(expected_samples)
        self._python = self._step is evidence_step.python  # its floats read from arrays: numpy's

    def start_segment(self) -> None:
        """At contact onset and at a re-latch: empty window, no verdict, no held direction."""
        self._start(self._state, self._counts)

    def _grow(self) -> None:
        """Twice the ring, its samples oldest first."""
        old, c = self._ring, self._counts
        m = int(max(c[_N_AREA], c[_N_VOTE]))
        cap = old.shape[0]
        state, counts, ring, wconst = new_evidence_state(2 * cap, self.corr)
        idx = (int(c[_HEAD]) + 1 - m + np.arange(m)) % cap
        ring[:m] = old[idx]
        c[_HEAD] = m - 1 if m else 0
        self._ring, self._wconst = ring, wconst

    def ready(self):
        """Before a located sample is stepped elsewhere (:func:`softtip.estimator.pipeline.located_step`):
        ``(params, wconst, state, counts, ring)``, the ring with room for one more."""
        c = self._counts
        if max(c[_N_AREA], c[_N_VOTE]) + 1 >= self._ring.shape[0]:
            self._grow()
        return self._params, self._wconst, self._state, c, self._ring

    def step(self, t, geo: PointGeometry, ex, ey, ez, hx, hy, hz, fx, fy, fz, hn, h_std, sg=0.0):
        """``(state, evidence, direction, angle, angle_std, angle_noise_std, h_ratio, f_ratio)`` of a located
        sample at the contact point of ``geo``, with ``h`` (N·m) taken about ``e`` (m; the
        point, or the effective point under the depth), the force ``f`` (N), ``hn = |h|``
        and ``h_std`` ``h``'s noise level (N·m) of the measurement stage; ``sg`` its moment about
        the normal (N·m), for the twist term."""
        _, _, _, c, _ = self.ready()
        p = geo.point
        e1x, e1y, e1z, e2x, e2y, e2z = geo.frame
        code, ev, dx, dy, dz, angle, angle_std, noise_std, h_ratio, f_ratio = self._step(
            self._state, c, self._ring, self._params, self._wconst, t, p[0], p[1], p[2], geo.nx, geo.ny, geo.nz,
            e1x, e1y, e1z, e2x, e2y, e2z, ex, ey, ez, hx, hy, hz, fx, fy, fz, hn, h_std, sg,
        )  # fmt: skip
        if self._python:
            dx, dy, dz, angle, angle_std, noise_std = float(dx), float(dy), float(dz), float(angle), float(angle_std), float(noise_std)
            h_ratio, f_ratio = float(h_ratio), float(f_ratio)
        return _STATE_NAMES[code], _EVIDENCE_NAMES[ev], (dx, dy, dz), angle, angle_std, noise_std, h_ratio, f_ratio
