"""The estimation pipeline: tare, filter, contact onset, latched contact point, measurement.

:func:`estimate` runs it over a whole log, vectorised; :class:`Estimator` runs it one sample
at a time for live use. Both call the same kernels (:mod:`softtip.contact`,
:mod:`softtip.spin`, :mod:`softtip.noise`) and agree to rounding.

Per sample (SPEC §3):

1. **Tare.** Unless a bias is given, the mean of the samples in the first ``tare_duration``
   seconds is the bias; those samples are reported as ``none`` (``taring``). The fingertip
   must not be touched then.
2. **Filter** (optional): causal Butterworth low-pass, steady state at the first sample.
3. **Contact** while ``|f| ≥ contact_threshold``.
4. **Contact point.** ``track``: the soft-finger solution of every sample. ``latch`` (the
   papers'): during the first rise of the force after onset (until ``|f|`` first exceeds the
   light-force window, or sets no new maximum for ``stall_time``), the soft-finger solutions
   of the samples inside the window are averaged; that mean, put back on the skin, is the
   contact point from then on, until contact ends. Before the first window sample the
   current soft-finger solution is used. With no window sample in the whole rise, the mean
   of the first ``fallback_samples`` solutions of the contact is latched and flagged.
5. **Measurement**: spin torque, its tangential part ``h``, the noise level of ``h``, the
   state ``point`` or ``line`` and, for ``line`` only, the direction and its angle with a
   standard deviation.

In ``track`` mode ``h`` is zero by construction (the soft-finger model puts all of ``q``
along ``n``), so only ``point`` contacts are reported: use ``latch`` for directions.

softtip's extensions (issue 5), each an :class:`EstimatorConfig` field:

- ``relatch_distance``: once the latch is held, a sample at light force (inside the
  window) whose soft-finger solution lies farther than this from the latched point starts
  a new latch (a new first rise, from that sample); ``relatched`` flags that sample, and
  the first sample of every contact that follows a latched one (contact lost and regained).
- ``depth``: a :class:`~softtip.depth.DepthLaw`; the moment is taken about the effective
  contact point ``r − δ(F_n) n`` inside the skin, where friction acts
  (:mod:`softtip.depth`); ``depth`` reports ``δ``.
- ``contact_point="joint"``: the latch of ``latch`` mode, then the contact point moved
  across the line to where a window of the last ``joint_window`` seconds fits the line
  contact model (:mod:`softtip.joint`). A window is accepted when its standard deviations
  of line angle and offset are below ``joint_max_angle_std`` and ``joint_max_offset_std``
  and its fit residual below ``joint_max_residual`` noise standard deviations. The point
  held is the accepted window since contact onset (or the last re-latch) with the
  smallest standard deviation aged by ``joint_drift``; before the first one the latched
  point is used and ``joint_fallback`` set. The coordinate along the line is the latch's:
  a line contact does not tell it.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field
from typing import Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip._xp import NP, PY
from softtip.contact import contact_arrays, contact_kernel
from softtip.depth import DepthLaw, depth_kernel
from softtip.joint import N_SUMS, joint_products, joint_solve_kernel
from softtip.filtering import SosStream, lowpass_sos, noise_gain, sosfilt_batch
from softtip.fingertip import Fingertip, load_fingertip
from softtip.noise import NANO17, SensorNoise, angle_std_kernel, h_std_kernel
from softtip.spin import angle_kernel, direction_kernel, spin_torque_kernel, tangent_frame_kernel, tangential_kernel
from softtip.units import KGF

__all__ = ["STATES", "CONTACT_POINT_MODES", "EstimatorConfig", "Estimates", "SampleEstimate", "Estimator", "estimate"]

#: Contact states, indexed by the integer codes in :attr:`Estimates.state`.
STATES = ("none", "point", "line")
NONE, POINT, LINE = 0, 1, 2
#: Values of :attr:`EstimatorConfig.contact_point`.
CONTACT_POINT_MODES = ("latch", "track", "joint")


@dataclass(frozen=True)
class EstimatorConfig:
    """Settings of the pipeline. SI units.

    Parameters
    ----------
    contact_point : {"latch", "track", "joint"}
        How the contact point is obtained (module docstring).
    contact_threshold : float
        N; in contact while ``|f|`` (tared, filtered) is at least this.
    latch_window : (float, float)
        N; light-force window of the latch (default 0.2–0.5 kgf).
    stall_time : float
        s; the first rise ends when ``|f|`` has set no new maximum for this long.
    fallback_samples : int
        Samples averaged for a latch when the rise has no sample in the window.
    noise : SensorNoise
        Standard deviations of the unfiltered sensor noise.
    h_sigmas, h_min : float
        ``|h|`` is significant (a ``line`` contact) above ``max(h_sigmas · h_std, h_min)``;
        ``h_min`` in N·m (default 0.5 N·mm).
    lowpass_hz : float or None
        Cutoff of the causal Butterworth low-pass, Hz; ``None`` for no filter.
    lowpass_order : int
    sample_rate : float or None
        Hz. Needed with ``lowpass_hz``; :func:`estimate` infers it from the median time step
        when absent.
    bias : 6 floats or None
        Sensor bias (N, N·m) to subtract; ``None`` to tare from the first samples.
    tare_duration : float
        s of samples averaged for the bias when ``bias`` is ``None``; 0 disables taring
        (the input is already tared).
    relatch_distance : float or None
        m; re-latch when, with the latch held and ``|f|`` inside ``latch_window``, the
        soft-finger solution lies farther than this from the latched point. ``None``
        (default, the papers'): only on contact loss. A few mm (e.g. 3 mm) is beyond the
        soft-finger bias of the papers' line contacts at light force (≈ |h| / |f| ≤ 1 mm).
    depth : DepthLaw or None
        Depth compensation (:mod:`softtip.depth`); ``None`` (default): off, the papers'
        undeformed contact point. :data:`softtip.depth.MURAKAMI2006_DEPTH` is the
        murakami2006 skin.
    joint_window : float
        s; length of the sliding window of ``joint`` mode (default 1 s: 50 samples at the
        papers' 50 Hz).
    joint_max_angle_std, joint_max_offset_std : float
        ``joint`` mode accepts a window when the standard deviations of its line angle (rad,
        default 2°) and of its offset across the line (m, default 0.2 mm) are at most these.
    joint_max_residual : float
        ... and the RMS residual of its fit is at most this many noise standard deviations.
    joint_drift : float
        m/√s; how fast the contact may wander unseen: the point held is the accepted window
        with the smallest ``offset_std² + joint_drift² · age`` (default 0.03 mm/√s), so a
        precise window is kept over later, weaker ones, but not for ever (positive, at most 1).
    joint_iterations : int
        Gauss–Newton steps of each window's solve.
    """

    contact_point: Literal["latch", "track", "joint"] = "latch"
    contact_threshold: float = 0.05
    latch_window: tuple[float, float] = (0.2 * KGF, 0.5 * KGF)
    stall_time: float = 0.1
    fallback_samples: int = 5
    noise: SensorNoise = field(default=NANO17)
    h_sigmas: float = 3.0
    h_min: float = 5e-4
    lowpass_hz: float | None = None
    lowpass_order: int = 2
    sample_rate: float | None = None
    bias: tuple[float, ...] | None = None
    tare_duration: float = 0.2
    relatch_distance: float | None = None
    depth: DepthLaw | None = None
    joint_window: float = 1.0
    joint_max_angle_std: float = math.radians(2.0)
    joint_max_offset_std: float = 2e-4
    joint_max_residual: float = 3.0
    joint_drift: float = 3e-5
    joint_iterations: int = 2

    def __post_init__(self) -> None:
        if self.contact_point not in CONTACT_POINT_MODES:
            raise ValueError(f"contact_point must be one of {', '.join(CONTACT_POINT_MODES)}, got {self.contact_point!r}")
        if self.relatch_distance is not None:
            v = float(self.relatch_distance)
            if not (math.isfinite(v) and v > 0.0):
                raise ValueError(f"relatch_distance must be a positive distance in m or None, got {self.relatch_distance!r}")
            object.__setattr__(self, "relatch_distance", v)
        if self.depth is not None and not isinstance(self.depth, DepthLaw):
            raise ValueError(f"depth must be a softtip.depth.DepthLaw or None, got {self.depth!r}")
        lo, hi = (float(v) for v in self.latch_window)
        if not (0.0 <= lo < hi):
            raise ValueError(f"latch_window must be (low, high) with 0 <= low < high, in N; got {self.latch_window!r}")
        object.__setattr__(self, "latch_window", (lo, hi))
        for name in ("joint_window", "joint_max_angle_std", "joint_max_offset_std", "joint_max_residual", "joint_drift"):
            v = float(getattr(self, name))
            if not (math.isfinite(v) and v > 0.0):
                raise ValueError(f"{name} must be a positive number, got {getattr(self, name)!r}")
            object.__setattr__(self, name, v)
        if self.joint_drift > 1.0:
            raise ValueError(f"joint_drift must be at most 1 m/√s, got {self.joint_drift!r}")
        if self.contact_point == "joint" and not any(self.noise.force_std + self.noise.moment_std):
            raise ValueError("contact_point='joint' needs a sensor noise model (noise is all zero)")
        if int(self.joint_iterations) < 1:
            raise ValueError(f"joint_iterations must be at least 1, got {self.joint_iterations!r}")
        object.__setattr__(self, "joint_iterations", int(self.joint_iterations))
        for name in ("contact_threshold", "stall_time", "h_sigmas", "h_min", "tare_duration"):
            v = float(getattr(self, name))
            if not (math.isfinite(v) and v >= 0.0):
                raise ValueError(f"{name} must be a non-negative number, got {getattr(self, name)!r}")
            object.__setattr__(self, name, v)
        if int(self.fallback_samples) < 1:
            raise ValueError(f"fallback_samples must be at least 1, got {self.fallback_samples!r}")
        if self.bias is not None:
            b = np.asarray(self.bias, dtype=float)
            if b.shape != (6,) or not np.all(np.isfinite(b)):
                raise ValueError(f"bias must be 6 finite numbers (N, N·m), got {self.bias!r}")
            object.__setattr__(self, "bias", tuple(float(v) for v in b))
        if self.lowpass_hz is not None and self.sample_rate is not None:
            lowpass_sos(self.lowpass_hz, self.sample_rate, self.lowpass_order)  # validates


@dataclass(frozen=True)
class Estimates:
    """Per-sample output of :func:`estimate`. SI units, sensor frame; ``N`` samples.

    Attributes
    ----------
    t : (N,) s
    state : (N,) int8 codes into :data:`STATES` (``none``, ``point``, ``line``)
    wrench : (N, 6) the tared (and filtered) wrench the estimates come from, N and N·m;
        NaN while taring
    point, normal : (N, 3) contact point (m) and outward normal; NaN when ``none``
    sigma : (N,) spin torque about the normal, N·m
    h : (N, 3) tangential spin torque, N·m; ``h_norm`` its magnitude
    h_std : (N,) noise level of ``h`` (``sqrt(trace Σ_h)``), N·m
    direction : (N, 3) unit direction of the edge / strip; NaN unless ``line``
    angle, angle_std : (N,) its angle in the SPEC §3.4 tangent frame and the angle's
        standard deviation, rad; NaN unless ``line``
    latched : (N,) the contact point is the latched one (not this sample's own solution)
    latch_fallback : (N,) that latch had no light-force sample (SPEC §3.6)
    pulling : (N,) in contact by force but no pushing contact point (reported ``none``)
    taring : (N,) sample used for the bias (reported ``none``)
    bias : (6,) the bias subtracted, N and N·m
    tare_force_std : float, N: the largest standard deviation of a force component over
        the tare samples (NaN without a tare). Far above the sensor noise, the fingertip
        was touched while taring and the bias is wrong.
    relatched : (N,) a new latch starts at this sample, replacing an earlier one (drift at
        light force, or contact regained after a latched contact); an event, not masked
    depth : (N,) depth compensation ``δ`` used, m (0 without a depth law); NaN when ``none``
    joint_conditioning, joint_angle_std, joint_offset_std, joint_residual : (N,) the
        ``joint`` window ending at this sample (:mod:`softtip.joint`): reciprocal condition
        number in [0, 1], standard deviations of its line angle (rad) and of its offset
        across the line (m), and the fit's RMS residual in units of the noise; NaN where no
        window was solved (other modes, ``none``, or no soft-finger solution)
    joint_fallback : (N,) ``joint`` mode: no window of this contact accepted yet, so the
        point is the latched one
    """

    t: NDArray[np.float64]
    state: NDArray[np.int8]
    wrench: NDArray[np.float64]
    point: NDArray[np.float64]
    normal: NDArray[np.float64]
    sigma: NDArray[np.float64]
    h: NDArray[np.float64]
    h_norm: NDArray[np.float64]
    h_std: NDArray[np.float64]
    direction: NDArray[np.float64]
    angle: NDArray[np.float64]
    angle_std: NDArray[np.float64]
    latched: NDArray[np.bool_]
    latch_fallback: NDArray[np.bool_]
    pulling: NDArray[np.bool_]
    taring: NDArray[np.bool_]
    bias: NDArray[np.float64]
    relatched: NDArray[np.bool_]
    depth: NDArray[np.float64]
    joint_conditioning: NDArray[np.float64]
    joint_angle_std: NDArray[np.float64]
    joint_offset_std: NDArray[np.float64]
    joint_residual: NDArray[np.float64]
    joint_fallback: NDArray[np.bool_]
    tare_force_std: float = math.nan

    def __len__(self) -> int:
        return len(self.t)

    @property
    def state_names(self) -> NDArray[np.str_]:
        """``state`` as strings, shape (N,)."""
        return np.asarray(STATES)[self.state]

    @property
    def n_pulling(self) -> int:
        """Samples in contact by force whose force pulls at every root (reported ``none``)."""
        return int(np.count_nonzero(self.pulling))

    def columns(self) -> dict[str, NDArray]:
        """The SPEC §4 output columns (SI, angles in degrees), in order, then softtip's extras."""
        w, p, n, h, d = self.wrench, self.point, self.normal, self.h, self.direction
        return {
            "t": self.t,
            "state": self.state_names,
            "fx": w[:, 0], "fy": w[:, 1], "fz": w[:, 2],
            "mx": w[:, 3], "my": w[:, 4], "mz": w[:, 5],
            "rx": p[:, 0], "ry": p[:, 1], "rz": p[:, 2],
            "nx": n[:, 0], "ny": n[:, 1], "nz": n[:, 2],
            "sigma": self.sigma,
            "hx": h[:, 0], "hy": h[:, 1], "hz": h[:, 2],
            "h_norm": self.h_norm,
            "dx": d[:, 0], "dy": d[:, 1], "dz": d[:, 2],
            "angle_deg": np.degrees(self.angle),
            "h_std": self.h_std,
            "angle_std_deg": np.degrees(self.angle_std),
            "latched": self.latched,
            "latch_fallback": self.latch_fallback,
            "relatched": self.relatched,
            "depth": self.depth,
            "joint_conditioning": self.joint_conditioning,
            "joint_angle_std_deg": np.degrees(self.joint_angle_std),
            "joint_offset_std": self.joint_offset_std,
            "joint_residual": self.joint_residual,
            "joint_fallback": self.joint_fallback,
        }  # fmt: skip


class SampleEstimate(NamedTuple):
    """One sample of :class:`Estimator` output; fields as in :class:`Estimates` (floats).

    A named tuple: cheap to create at sensor rate, immutable.
    """

    t: float
    state: str
    wrench: tuple[float, ...]
    point: tuple[float, float, float]
    normal: tuple[float, float, float]
    sigma: float
    h: tuple[float, float, float]
    h_norm: float
    h_std: float
    direction: tuple[float, float, float]
    angle: float
    angle_std: float
    latched: bool
    latch_fallback: bool
    pulling: bool
    taring: bool
    relatched: bool = False
    depth: float = math.nan
    joint_conditioning: float = math.nan
    joint_angle_std: float = math.nan
    joint_offset_std: float = math.nan
    joint_residual: float = math.nan
    joint_fallback: bool = False


# -- the measurement, shared by batch and stream ----------------------------------------------


def _measure(fx, fy, fz, mx, my, mz, rx, ry, rz, nx, ny, nz, noise, h_sigmas, h_min, law, xp):
    """Spin torque, ``h``, noise, direction and the line test for a contact point.

    With a depth law the moment is taken about ``r − δ n`` (friction acts inside the skin).
    """
    pushing = fx * nx + fy * ny + fz * nz < 0.0
    if law is None:
        delta = 0.0 * fx
    else:
        delta = depth_kernel(-(fx * nx + fy * ny + fz * nz), law, xp)
        rx, ry, rz = rx - delta * nx, ry - delta * ny, rz - delta * nz
    qx, qy, qz = spin_torque_kernel(fx, fy, fz, mx, my, mz, rx, ry, rz)
    sigma, hx, hy, hz = tangential_kernel(qx, qy, qz, nx, ny, nz)
    hn, dx, dy, dz = direction_kernel(hx, hy, hz, nx, ny, nz, xp)
    frame = tangent_frame_kernel(nx, ny, nz, xp)
    h_std = h_std_kernel(rx, ry, rz, *frame, noise, xp)
    line = hn > xp.maximum(h_sigmas * h_std, h_min)
    angle = angle_kernel(dx, dy, dz, *frame, xp)
    angle_std = angle_std_kernel(dx, dy, dz, hn, rx, ry, rz, noise, xp)
    return sigma, hx, hy, hz, hn, h_std, dx, dy, dz, angle, angle_std, line, pushing, delta


def _joint_moment(fx, fy, fz, mx, my, mz, nx, ny, nz, ax, ay, az, law, xp):
    """Moment about the anchor ``a`` that enters the joint sums, component-wise.

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


def _joint_accept(cond, angle_std, offset_std, residual, config: EstimatorConfig):
    # written so that NaN (undefined window) is never accepted, in both back ends
    return (
        (angle_std <= config.joint_max_angle_std)
        & (offset_std <= config.joint_max_offset_std)
        & (residual <= config.joint_max_residual)
        & (cond >= 0.0)
    )


def _effective_noise(config: EstimatorConfig, sos) -> SensorNoise:
    return config.noise if sos is None else config.noise.scaled(noise_gain(sos))


def _noise_correlation(sos) -> float:
    """Samples per independent noise sample after the filter (1 without one)."""
    return 1.0 if sos is None else 1.0 / noise_gain(sos) ** 2


def _infer_rate(t: NDArray) -> float:
    if len(t) < 2:
        raise ValueError("a low-pass filter needs at least two samples to infer the sample rate")
    return 1.0 / float(np.median(np.diff(t)))


# -- batch ---------------------------------------------------------------------------------------


def _validate_log(t: ArrayLike, wrench: ArrayLike) -> tuple[NDArray, NDArray]:
    t = np.asarray(t, dtype=float)
    w = np.asarray(wrench, dtype=float)
    if t.ndim != 1 or w.shape != (len(t), 6):
        raise ValueError(f"expected t of shape (N,) and wrench of shape (N, 6), got {t.shape} and {w.shape}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(w))):
        raise ValueError("t and wrench must be finite")
    if np.any(np.diff(t) <= 0):
        raise ValueError("t must be strictly increasing")
    return t, w


def _latch_segment(t, fn, valid, r_sc, tip: Fingertip, config: EstimatorConfig):
    """The latch of one segment (a contact, or its rest after a re-latch), vectorised.

    The segment's first sample starts a first rise. Returns ``(point (k, 3), latched (k,),
    fallback (k,), held (k,), latch point (3,))``, where ``held`` marks the samples that
    start with the latch already fixed (where a drift re-latch may happen).
    """
    k = len(t)
    lo, hi = config.latch_window
    idx = np.arange(k)
    prev_peak = np.concatenate(([-np.inf], np.maximum.accumulate(fn)[:-1]))
    t_peak = t[np.maximum.accumulate(np.where(fn > prev_peak, idx, 0))]
    rise_over = (fn > hi) | (t - t_peak > config.stall_time)
    end = int(np.argmax(rise_over)) if rise_over.any() else k
    win = (idx < end) & (fn >= lo) & (fn <= hi) & valid
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


def _latch_points(t, fn, contact, sc, tip: Fingertip, config: EstimatorConfig):
    """Contact point per sample in ``latch`` mode, with re-latching.

    Returns ``(point (N, 3), latched, fallback, relatched)``. One iteration per contact and
    per re-latch (a handful per log), vectorised within each.
    """
    n = len(t)
    point = np.full((n, 3), np.nan)
    latched = np.zeros(n, dtype=bool)
    fallback = np.zeros(n, dtype=bool)
    relatched = np.zeros(n, dtype=bool)
    valid = np.asarray(sc[7], dtype=bool)
    r_sc = np.where(valid[:, None], np.stack(sc[:3], axis=-1), np.nan)
    lo, hi = config.latch_window
    dist = config.relatch_distance
    edges = np.diff(np.concatenate(([False], contact, [False])).astype(np.int8))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    had_latch = False
    for s, e in zip(starts, stops):
        relatched[s] = had_latch  # contact regained after a latched one
        a = s
        while True:
            pe, lat, fbk, held, latch = _latch_segment(t[a:e], fn[a:e], valid[a:e], r_sc[a:e], tip, config)
            stop = e - a
            if dist is not None and held.any():
                fe = fn[a:e]
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
    return point, latched, fallback, relatched


def _joint_points(t, c, contact, sc, base, relatched, tip: Fingertip, config: EstimatorConfig, noise: SensorNoise, corr):
    """``joint`` mode over a whole log, vectorised within each contact.

    ``c`` are the six wrench components, ``sc`` the soft-finger solutions, ``base`` the
    latched points (N, 3) (start of each solve; their coordinate along the line is kept).
    Returns ``(point (N, 3), stats (4, N), used (N,), moved (N,))``: ``used`` marks the
    windows that became the held point, ``moved`` the samples whose point is a joint one
    (the latched one elsewhere).
    """
    n = len(t)
    valid = contact & np.asarray(sc[7], dtype=bool)
    stats = np.full((4, n), np.nan)
    jp = np.full((n, 3), np.nan)
    edges = np.diff(np.concatenate(([False], contact, [False])).astype(np.int8))
    for s, e in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)):
        v = np.flatnonzero(valid[s:e]) + s
        if not len(v):
            continue
        anchor = [float(sc[i][v[0]]) for i in range(3)]  # first soft-finger point of the contact
        normal = np.stack([sc[i][v] for i in (3, 4, 5)], axis=-1)
        if config.depth is not None:
            has = np.all(np.isfinite(base[v]), axis=-1)
            normal[has] = tip.normal(base[v][has])
        qa = _joint_moment(*(ci[v] for ci in c), *normal.T, *anchor, config.depth, NP)
        tv = t[v]
        # window of sample k: the valid samples i with t_i > t_k − T (the stream's test)
        first = np.searchsorted(tv, tv - config.joint_window, side="right")
        last = np.arange(1, len(v) + 1)
        sums = []
        for p in joint_products(c[0][v], c[1][v], c[2][v], *qa):
            cz = np.concatenate(([0.0], np.cumsum(p)))  # sequential, as the stream's running sums
            sums.append(cz[last] - cz[first])
        ok = np.all(np.isfinite(base[v]), axis=-1)
        count = (last - first).astype(float)
        out = joint_solve_kernel(sums, count, *base[v].T, *anchor, tip, config.joint_iterations, noise, corr, NP)
        jp[v[ok]] = np.stack(out[:3], axis=-1)[ok]
        stats[:, v[ok]] = np.stack(out[6:10])[:, ok]
    with np.errstate(invalid="ignore"):
        accept = valid & _joint_accept(*stats, config) & np.all(np.isfinite(jp), axis=-1)
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
            key = np.where(accept[a:b], stats[2, a:b] ** 2 - config.joint_drift**2 * (t[a:b] - t[a]), np.inf)
        best = np.concatenate(([np.inf], np.minimum.accumulate(key)[:-1]))
        use[a:b] = key < best
        held_at[a:b] = np.maximum.accumulate(np.where(use[a:b], np.arange(a, b), -1))
    moved = contact & (held_at >= 0)
    point = base.copy()
    point[moved] = jp[held_at[moved]]
    return point, stats, use, moved


def estimate(
    t: ArrayLike,
    wrench: ArrayLike,
    tip: Fingertip | str = "murakami2006",
    config: EstimatorConfig | None = None,
) -> Estimates:
    """Run the pipeline over a whole log.

    Parameters
    ----------
    t : array-like, shape (N,)
        Sample times, s, strictly increasing.
    wrench : array-like, shape (N, 6)
        Raw sensor wrench ``fx, fy, fz`` (N), ``mx, my, mz`` (N·m), sensor frame.
    tip : Fingertip or str
        Fingertip, preset name or TOML path.
    config : EstimatorConfig, optional

    Returns
    -------
    Estimates

    Examples
    --------
    >>> from softtip import estimate, load_example
    >>> log = load_example()
    >>> est = estimate(log.t, log.wrench, "murakami2006")
    >>> sorted(set(est.state_names))
    ['line', 'none', 'point']
    """
    tip = load_fingertip(tip)
    config = config or EstimatorConfig()
    t, w = _validate_log(t, wrench)
    n = len(t)

    taring = np.zeros(n, dtype=bool)
    tare_force_std = math.nan
    if config.bias is not None:
        bias = np.asarray(config.bias)
    elif config.tare_duration > 0 and n:
        # same comparison as the stream, so both agree on the boundary sample
        n_tare = int(np.count_nonzero(t - t[0] < config.tare_duration))
        taring[:n_tare] = True
        # a log that never leaves the tare period has no bias (as in the stream)
        bias = np.mean(w[:n_tare], axis=0) if n_tare < n else np.full(6, np.nan)
        tare_force_std = float(np.max(np.std(w[:n_tare, :3], axis=0)))
    else:
        bias = np.zeros(6)
    x = w - bias

    sos = None
    if config.lowpass_hz is not None:
        rate = config.sample_rate or _infer_rate(t)
        sos = lowpass_sos(config.lowpass_hz, rate, config.lowpass_order)
        x = sosfilt_batch(sos, x) if np.all(np.isfinite(bias)) else x
    noise = _effective_noise(config, sos)

    c = [np.ascontiguousarray(x[:, i]) for i in range(6)]
    fn = np.sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2])
    contact = (fn >= config.contact_threshold) & ~taring
    relatched = np.zeros(n, dtype=bool)
    joint_stats = np.full((4, n), np.nan)
    joint_fb = np.zeros(n, dtype=bool)
    with np.errstate(invalid="ignore", divide="ignore"):
        sc = contact_arrays(tip, *c)
        if config.contact_point == "track":
            point = np.stack(sc[:3], axis=-1)
            normal = np.stack(sc[3:6], axis=-1)
            has = np.asarray(sc[7], dtype=bool)
            latched = fallback = np.zeros(n, dtype=bool)
        else:
            point, latched, fallback, relatched = _latch_points(t, fn, contact, sc, tip, config)
            if config.contact_point == "joint":
                point, joint_stats, _, moved = _joint_points(
                    t, c, contact, sc, point, relatched, tip, config, noise, _noise_correlation(sos)
                )
                latched, fallback, joint_fb = latched & ~moved, fallback & ~moved, contact & ~moved
            normal = tip.normal(point)
            has = np.all(np.isfinite(point), axis=-1)
        sigma, hx, hy, hz, hn, h_std, dx, dy, dz, angle, angle_std, line, pushing, delta = _measure(
            *c, *point.T, *normal.T, noise, config.h_sigmas, config.h_min, config.depth, NP
        )

    located = contact & has & pushing
    pulling = contact & ~located
    is_line = located & line
    state = np.where(located, np.where(is_line, LINE, POINT), NONE).astype(np.int8)

    def keep(a, mask):
        a = np.asarray(a, dtype=float)
        return np.where(mask.reshape(mask.shape + (1,) * (a.ndim - 1)), a, np.nan)

    return Estimates(
        t=t,
        state=state,
        # the bias is not known while taring, so neither is the tared wrench (as in the stream)
        wrench=keep(x, ~taring),
        point=keep(point, located),
        normal=keep(normal, located),
        sigma=keep(sigma, located),
        h=keep(np.stack((hx, hy, hz), axis=-1), located),
        h_norm=keep(hn, located),
        h_std=keep(h_std, located),
        direction=keep(np.stack((dx, dy, dz), axis=-1), is_line),
        angle=keep(angle, is_line),
        angle_std=keep(angle_std, is_line),
        latched=latched & located,
        latch_fallback=fallback & located,
        pulling=pulling,
        taring=taring,
        bias=bias,
        tare_force_std=tare_force_std,
        relatched=relatched,
        depth=keep(delta, located),
        joint_conditioning=keep(joint_stats[0], located),
        joint_angle_std=keep(joint_stats[1], located),
        joint_offset_std=keep(joint_stats[2], located),
        joint_residual=keep(joint_stats[3], located),
        joint_fallback=joint_fb & located,
    )


# -- stream --------------------------------------------------------------------------------------

_NAN3 = (math.nan, math.nan, math.nan)
_NAN4 = (math.nan,) * 4


class Estimator:
    """The pipeline of :func:`estimate`, one sample at a time (live use).

    Parameters
    ----------
    tip : Fingertip or str
        Fingertip, preset name or TOML path.
    config : EstimatorConfig, optional
        With ``lowpass_hz`` set, ``config.sample_rate`` is required.

    Examples
    --------
    >>> from softtip import Estimator, load_example
    >>> log = load_example()
    >>> est = Estimator("murakami2006")
    >>> out = [est.update(t, w) for t, w in zip(log.t, log.wrench)]
    >>> out[-1].state
    'line'
    """

    def __init__(self, tip: Fingertip | str = "murakami2006", config: EstimatorConfig | None = None):
        self.tip = load_fingertip(tip)
        self.config = config or EstimatorConfig()
        cfg = self.config
        self._sos = None
        if cfg.lowpass_hz is not None:
            if cfg.sample_rate is None:
                raise ValueError("streaming with a low-pass filter needs config.sample_rate (Hz)")
            self._sos = lowpass_sos(cfg.lowpass_hz, cfg.sample_rate, cfg.lowpass_order)
        self._noise = _effective_noise(cfg, self._sos)
        self._corr = _noise_correlation(self._sos)
        self._track = cfg.contact_point == "track"
        self._joint = cfg.contact_point == "joint"
        self.reset()

    def reset(self) -> None:
        """Forget everything: bias (unless given), filter state and contact."""
        cfg = self.config
        self.bias: tuple[float, ...] | None = cfg.bias
        if self.bias is None and cfg.tare_duration <= 0:
            self.bias = (0.0,) * 6
        self._tare_buf: list[tuple[float, ...]] = []
        self._t0: float | None = None
        self._filter = SosStream(self._sos) if self._sos is not None else None
        self._in_contact = False
        self._had_latch = False
        self._t_prev: float | None = None

    def _start_contact(self, fn: float, t: float) -> None:
        """A new first rise: at contact onset, and at a re-latch."""
        self._in_contact = True
        self._rising = True
        self._peak = fn
        self._t_peak = t
        self._n_win = 0
        self._sum_win = [0.0, 0.0, 0.0]
        self._n_fb = 0
        self._sum_fb = [0.0, 0.0, 0.0]
        self._latch: tuple[float, float, float] | None = None
        self._latch_is_fallback = False
        self._joint_held: tuple[float, float, float] | None = None
        self._joint_key = math.inf
        self._t_segment = t

    def _start_joint(self) -> None:
        """At contact onset: running sums of the joint products, and for each valid sample
        of the last ``joint_window`` seconds its time and the sums before it (window sums
        are differences, as in the batch)."""
        self._anchor: tuple[float, float, float] | None = None
        self._cum = [0.0] * N_SUMS
        self._hist: deque[tuple[float, list[float]]] = deque()

    def update(self, t: float, wrench: ArrayLike) -> SampleEstimate:
        """Process one raw sample.

        Parameters
        ----------
        t : float
            s; must increase from call to call.
        wrench : array-like, shape (6,)
            Raw ``fx, fy, fz`` (N), ``mx, my, mz`` (N·m).
        """
        t = float(t)
        try:
            w = [float(v) for v in (wrench.tolist() if isinstance(wrench, np.ndarray) else wrench)]
        except (TypeError, ValueError):
            w = []
        if len(w) != 6 or not all(math.isfinite(v) for v in w) or not math.isfinite(t):
            raise ValueError(f"expected a finite time and 6 finite wrench components, got t={t!r}, wrench={wrench!r}")
        if self._t_prev is not None and t <= self._t_prev:
            raise ValueError(f"time must increase: {t!r} s after {self._t_prev!r} s")
        self._t_prev = t

        if self.bias is None:
            if self._t0 is None:
                self._t0 = t
            if t - self._t0 < self.config.tare_duration:
                self._tare_buf.append(tuple(w))
                return self._none(t, (math.nan,) * 6, taring=True)
            self.bias = tuple(np.mean(np.array(self._tare_buf), axis=0).tolist())
            if self._filter is not None:  # the tare samples prime the filter, as in the batch
                for b in self._tare_buf:
                    self._filter([v - bb for v, bb in zip(b, self.bias)])
            self._tare_buf = []
        x = [v - b for v, b in zip(w, self.bias)]
        if self._filter is not None:
            x = self._filter(x)
        return self._step(t, x)

    def _none(self, t, x, taring=False, pulling=False, relatched=False) -> SampleEstimate:
        nan = math.nan
        return SampleEstimate(
            t, "none", tuple(x), _NAN3, _NAN3, nan, _NAN3, nan, nan, _NAN3, nan, nan, False, False, pulling, taring,
            relatched,
        )  # fmt: skip

    def _latch_step(self, t: float, fn: float, x: list[float], sc):
        """The latch stage for a sample in contact: ``(point, latched, fallback, sc)``.

        ``sc`` (this sample's soft-finger solution) is computed only when needed and
        returned for reuse (None otherwise).
        """
        cfg = self.config
        point = self._latch
        if point is not None:
            return point, True, self._latch_is_fallback, sc
        if sc is None:
            sc = contact_kernel(self.tip, *x, xp=PY)
        fallback = False
        valid = sc[7]
        if valid and self._n_fb < cfg.fallback_samples:
            self._n_fb += 1
            self._sum_fb = [s + v for s, v in zip(self._sum_fb, sc[:3])]
        lo, hi = cfg.latch_window
        if self._rising and (fn > hi or t - self._t_peak > cfg.stall_time):
            self._rising = False
            if self._n_win > 0:
                self._latch = point = self._mean(self._sum_win, self._n_win)
        if self._rising:
            if valid and lo <= fn <= hi:
                self._n_win += 1
                self._sum_win = [s + v for s, v in zip(self._sum_win, sc[:3])]
            if self._n_win > 0:
                point = self._mean(self._sum_win, self._n_win)
            elif valid:
                point = (sc[0], sc[1], sc[2])
        elif point is None and self._n_fb > 0:
            point = self._mean(self._sum_fb, self._n_fb)
            fallback = True
            if self._n_fb >= cfg.fallback_samples:
                self._latch, self._latch_is_fallback = point, True
        latched = point is not None and (self._n_win > 0 or fallback)
        return point, latched, fallback, sc

    def _step(self, t: float, x: list[float]) -> SampleEstimate:
        cfg = self.config
        fx, fy, fz, mx, my, mz = x
        fn = math.sqrt(fx * fx + fy * fy + fz * fz)
        if fn < cfg.contact_threshold:
            self._in_contact = False
            return self._none(t, x)

        tip = self.tip
        latched = fallback = relatched = joint_fb = False
        stats = _NAN4
        if self._track:
            rx, ry, rz, nx, ny, nz, _, valid = contact_kernel(tip, *x, xp=PY)
            if not valid:
                return self._none(t, x, pulling=True)
        else:
            sc = None
            if not self._in_contact:
                relatched = self._had_latch  # contact regained after a latched one
                self._start_contact(fn, t)
                if self._joint:
                    self._start_joint()
            else:
                if self._rising and fn > self._peak:
                    self._peak, self._t_peak = fn, t
                dist = cfg.relatch_distance
                lo, hi = cfg.latch_window
                if self._latch is not None and dist is not None and lo <= fn <= hi:
                    # held latch at light force: has the contact moved away from it?
                    sc = contact_kernel(tip, *x, xp=PY)
                    if sc[7]:
                        lx, ly, lz = self._latch
                        dx, dy, dz = sc[0] - lx, sc[1] - ly, sc[2] - lz
                        if dx * dx + dy * dy + dz * dz > dist * dist:
                            relatched = True
                            self._start_contact(fn, t)
            point, latched, fallback, sc = self._latch_step(t, fn, x, sc)
            if latched:
                self._had_latch = True
            if self._joint:
                point, stats, moved = self._joint_step(t, x, point, sc)
                if moved:
                    latched = fallback = False
                joint_fb = not moved
            if point is None:
                return self._none(t, x, pulling=True, relatched=relatched)
            rx, ry, rz = point
            nx, ny, nz = tip._normal_kernel(rx, ry, rz, PY)

        sigma, hx, hy, hz, hn, h_std, dx, dy, dz, angle, angle_std, line, pushing, delta = _measure(
            fx, fy, fz, mx, my, mz, rx, ry, rz, nx, ny, nz, self._noise, cfg.h_sigmas, cfg.h_min, cfg.depth, PY
        )
        if not pushing:
            return self._none(t, x, pulling=True, relatched=relatched)
        if line:
            state, d = "line", (dx, dy, dz)
        else:
            state, d, angle, angle_std = "point", _NAN3, math.nan, math.nan
        return SampleEstimate(
            t, state, tuple(x), (rx, ry, rz), (nx, ny, nz), sigma, (hx, hy, hz), hn, h_std, d, angle, angle_std,
            latched, fallback, False, False, relatched, delta, *stats, joint_fb,
        )  # fmt: skip

    def _joint_step(self, t: float, x: list[float], point, sc):
        """The joint stage: ``(point, (conditioning, angle_std, offset_std, residual), moved)``."""
        cfg = self.config
        stats = _NAN4
        if sc is None:
            sc = contact_kernel(self.tip, *x, xp=PY)
        accepted = False
        if sc[7]:
            if self._anchor is None:
                self._anchor = (sc[0], sc[1], sc[2])
            ax, ay, az = self._anchor
            nx, ny, nz = sc[3], sc[4], sc[5]
            if cfg.depth is not None and point is not None:
                nx, ny, nz = self.tip._normal_kernel(*point, PY)
            qa = _joint_moment(*x, nx, ny, nz, ax, ay, az, cfg.depth, PY)
            hist = self._hist
            hist.append((t, self._cum))
            self._cum = [c + p for c, p in zip(self._cum, joint_products(x[0], x[1], x[2], *qa))]
            start = t - cfg.joint_window
            while hist and hist[0][0] <= start:
                hist.popleft()
            if point is not None:
                # an empty window (t − T rounds to t) has zero sums, as in the batch
                sums = [c - o for c, o in zip(self._cum, hist[0][1] if hist else self._cum)]
                out = joint_solve_kernel(
                    sums, float(len(hist)), *point, ax, ay, az, self.tip, cfg.joint_iterations, self._noise,
                    self._corr, PY,
                )  # fmt: skip
                stats = out[6:10]
                if _joint_accept(*stats, cfg) and math.isfinite(out[0] + out[1] + out[2]):
                    key = stats[2] ** 2 - cfg.joint_drift**2 * (t - self._t_segment)
                    if key < self._joint_key:
                        self._joint_key, self._joint_held = key, out[:3]
        if self._joint_held is not None:
            return self._joint_held, stats, True
        return point, stats, False

    def _mean(self, total: list[float], count: int) -> tuple[float, float, float]:
        return self.tip._project_kernel(total[0] / count, total[1] / count, total[2] / count, PY)

    def process(self, t: ArrayLike, wrench: ArrayLike) -> list[SampleEstimate]:
        """Feed a sequence of samples through :meth:`update`; returns one estimate each."""
        return [self.update(ti, wi) for ti, wi in zip(np.asarray(t, dtype=float), np.asarray(wrench, dtype=float))]

