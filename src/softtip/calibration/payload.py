"""Gravity compensation of the fingertip's own weight.

The F/T sensor carries the fingertip: its weight is an external force on the sensor like
the contact's. With the sensor frame's orientation ``R`` in a gravity-aligned world frame
(world ``z`` up; ``v_world = R v_sensor``), the fingertip of mass ``m`` with centre of mass
``c`` (sensor frame, m) adds, in the manual's convention (§1) (what acts on the fingertip)::

    f_g = m g_s,    m_g = c × f_g,    g_s = Rᵀ (0, 0, −9.80665)

Taring at one orientation removes it only at that orientation; a rotating hand then sees a
spurious wrench of up to ``2 m g`` and ``2 m g |c|`` (0.4 N and 8 N·mm for 20 g at 20 mm).
:func:`compensate_payload` subtracts it before the estimator (so its tare then removes only
the true sensor bias); :class:`PayloadCompensator` does the same for one sample with plain
floats for the stream.

:func:`calibrate_payload` estimates ``m``, ``c`` and the sensor bias from contact-free
samples in varied orientations by linear least squares (force rows: bias and ``m``; moment
rows: bias and ``m c``), with standard deviations from the residual variance.

Orientation input: columns ``qw, qx, qy, qz`` (unit quaternion, scalar first) in the log.
Payload files are TOML::

    [payload]
    mass = 0.02            # kg
    com = [0, 0, 0.02]     # m, sensor frame
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from softtip.core.units import STANDARD_GRAVITY
from softtip.errors import InputError
from softtip.io.tomlfile import read_toml_table

__all__ = [
    "QUATERNION_COLUMNS",
    "Payload",
    "PayloadFit",
    "PayloadCompensator",
    "load_payload",
    "gravity_in_sensor",
    "payload_wrench",
    "compensate_payload",
    "calibrate_payload",
    "read_orientation",
    "compensate_log",
    "CompensatedSource",
    "replay_source",
]

#: Orientation columns of a log: the sensor frame in the world frame, scalar first.
QUATERNION_COLUMNS = ("qw", "qx", "qy", "qz")
#: Largest accepted deviation of a quaternion's norm from 1.
UNIT_TOLERANCE = 1e-3
# Refuse a payload fit whose column-scaled design matrix has a condition number above this.
# It grows as 1 / (angular spread of gravity in the sensor frame): 50 is about 8° of spread,
# where the centre of mass is still determined to a few tenths of a mm at Nano17 noise.
_MAX_CONDITION = 50.0


@dataclass(frozen=True)
class Payload:
    """The fingertip's mass (kg) and centre of mass (m, sensor frame)."""

    mass: float
    com: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        m = float(self.mass)
        if not (math.isfinite(m) and m >= 0.0):
            raise ValueError(f"mass must be a non-negative number of kg, got {self.mass!r}")
        c = np.asarray(self.com, dtype=float)
        if c.shape != (3,) or not np.all(np.isfinite(c)):
            raise ValueError(f"com must be 3 finite numbers (m), got {self.com!r}")
        object.__setattr__(self, "mass", m)
        object.__setattr__(self, "com", tuple(float(v) for v in c))

    def to_toml(self) -> str:
        """The payload as a TOML file (kg, m)."""
        com = ", ".join(repr(v) for v in self.com)
        return f"[payload]\nmass = {self.mass!r}  # kg\ncom = [{com}]  # m, sensor frame\n"


def load_payload(path: str | os.PathLike[str] | Payload) -> Payload:
    """Read a payload TOML file (``[payload] mass = kg, com = [x, y, z] m``).

    Raises
    ------
    InputError
        Missing or unreadable file, malformed TOML, missing, unknown or invalid keys; the
        message names the file and the key.
    """
    if isinstance(path, Payload):
        return path
    name = os.fspath(path)
    table = read_toml_table(name, "payload", ("mass", "com"), "mass (kg) and com (m)")
    if "mass" not in table:
        raise InputError(f"{name}: [payload] missing key mass (kg)")
    mass = table["mass"]
    if isinstance(mass, bool) or not isinstance(mass, (int, float)):
        raise InputError(f"{name}: [payload] mass = {mass!r} is not a number of kg")
    com = table.get("com", [0.0, 0.0, 0.0])
    if not (isinstance(com, list) and len(com) == 3 and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in com)):
        raise InputError(f"{name}: [payload] com = {com!r} is not a list of 3 numbers in metres")
    try:
        return Payload(float(mass), tuple(com))
    except ValueError as exc:
        raise InputError(f"{name}: [payload] {exc}") from None


# --------------------------------------------------------------------------------------
# the gravity wrench


def gravity_in_sensor(orientation: ArrayLike) -> NDArray[np.float64]:
    """Gravity (m/s²) in the sensor frame, ``g_s = Rᵀ (0, 0, −9.80665)``.

    Parameters
    ----------
    orientation : array-like, shape (..., 4)
        Unit quaternions ``qw, qx, qy, qz``: the sensor frame in the world frame (z up).

    Returns
    -------
    ndarray, shape (..., 3)
    """
    q = np.asarray(orientation, dtype=float)
    if q.shape[-1:] != (4,):
        raise ValueError(f"orientation must have shape (..., 4) (qw, qx, qy, qz), got {q.shape}")
    flat = q.reshape(-1, 4)
    if len(flat) == 0:
        return np.zeros((*q.shape[:-1], 3))
    g = Rotation.from_quat(flat, scalar_first=True).inv().apply([0.0, 0.0, -STANDARD_GRAVITY])
    return g.reshape(*q.shape[:-1], 3)


def payload_wrench(orientation: ArrayLike, payload: Payload) -> NDArray[np.float64]:
    """The payload's gravity wrench on the sensor, ``(m g_s, c × m g_s)``, shape (..., 6), N and N·m."""
    fg = payload.mass * gravity_in_sensor(orientation)
    c = np.asarray(payload.com)
    mg = np.stack(
        (c[1] * fg[..., 2] - c[2] * fg[..., 1], c[2] * fg[..., 0] - c[0] * fg[..., 2], c[0] * fg[..., 1] - c[1] * fg[..., 0]),
        axis=-1,
    )
    return np.concatenate((fg, mg), axis=-1)


def compensate_payload(wrench: ArrayLike, orientation: ArrayLike, payload: Payload) -> NDArray[np.float64]:
    """Remove the payload's gravity wrench: ``wrench − (m g_s, c × m g_s)``.

    Parameters
    ----------
    wrench : array-like, shape (..., 6)
        Raw wrench, N and N·m, sensor frame.
    orientation : array-like, shape (..., 4)
        ``qw, qx, qy, qz`` per sample (broadcast against ``wrench``).
    payload : Payload

    Returns
    -------
    ndarray, shape (..., 6)
        The wrench without the fingertip's weight (the sensor bias is still in it: the
        estimator's tare removes that).
    """
    w = np.asarray(wrench, dtype=float)
    if w.shape[-1:] != (6,):
        raise ValueError(f"wrench must have shape (..., 6), got {w.shape}")
    return w - payload_wrench(orientation, payload)


class PayloadCompensator:
    """Per-sample gravity compensation with plain floats (no numpy): for the stream.

    >>> comp = PayloadCompensator(Payload(0.02, (0.0, 0.0, 0.02)))
    >>> fx, fy, fz, mx, my, mz = comp((0.0, 0.0, -0.196133, 0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0))
    >>> round(fz, 9)
    0.0
    """

    __slots__ = ("_m", "_cx", "_cy", "_cz")

    def __init__(self, payload: Payload) -> None:
        self._m = payload.mass * STANDARD_GRAVITY
        self._cx, self._cy, self._cz = payload.com

    def __call__(self, wrench, q) -> tuple[float, float, float, float, float, float]:
        """``wrench`` (6 floats, N, N·m) and ``q = (qw, qx, qy, qz)`` (unit) -> compensated wrench."""
        w, x, y, z = q
        # third row of R(q): world z in sensor coordinates; g_s = −g · that
        s = -self._m
        fx = s * 2.0 * (x * z - w * y)
        fy = s * 2.0 * (y * z + w * x)
        fz = s * (1.0 - 2.0 * (x * x + y * y))
        cx, cy, cz = self._cx, self._cy, self._cz
        return (
            wrench[0] - fx,
            wrench[1] - fy,
            wrench[2] - fz,
            wrench[3] - (cy * fz - cz * fy),
            wrench[4] - (cz * fx - cx * fz),
            wrench[5] - (cx * fy - cy * fx),
        )


# --------------------------------------------------------------------------------------
# estimating the payload


@dataclass(frozen=True)
class PayloadFit:
    """Result of :func:`calibrate_payload`. SI.

    Attributes
    ----------
    payload : Payload
    bias : ndarray, shape (6,)
        Sensor bias, N and N·m.
    mass_std : float
        kg.
    com_std : ndarray, shape (3,)
        m.
    bias_std : ndarray, shape (6,)
    force_rms, moment_rms : float
        Residual RMS per axis, N and N·m.
    n_samples : int
    gravity_spread_deg : float
        Largest angle between the gravity direction of any sample and their mean, degrees.
    condition : float
        Condition number of the (column-scaled) moment design matrix.
    """

    payload: Payload
    bias: NDArray[np.float64]
    mass_std: float
    com_std: NDArray[np.float64]
    bias_std: NDArray[np.float64]
    force_rms: float
    moment_rms: float
    n_samples: int
    gravity_spread_deg: float
    condition: float

    def summary(self) -> str:
        """Human-readable report (g, mm, N, N·mm)."""
        c, cs = np.asarray(self.payload.com) * 1e3, self.com_std * 1e3
        b, bs = self.bias.copy(), self.bias_std.copy()
        b[3:] *= 1e3
        bs[3:] *= 1e3
        return "\n".join(
            [
                f"payload from {self.n_samples} samples, gravity direction spread {self.gravity_spread_deg:.0f}°, "
                f"condition {self.condition:.3g}",
                f"  mass  {self.payload.mass * 1e3:.3f} ± {self.mass_std * 1e3:.3f} g",
                "  com   " + ", ".join(f"{v:+.3f} ± {s:.3f}" for v, s in zip(c, cs)) + " mm",
                "  bias  force " + ", ".join(f"{v:+.4f} ± {s:.4f}" for v, s in zip(b[:3], bs[:3])) + " N; moment "
                + ", ".join(f"{v:+.3f} ± {s:.3f}" for v, s in zip(b[3:], bs[3:])) + " N·mm",
                f"  residual {self.force_rms * 1e3:.2f} mN, {self.moment_rms * 1e3:.4f} N·mm RMS per axis",
            ]
        )


def _solve_block(a: NDArray, b: NDArray) -> tuple[NDArray, NDArray, float, float]:
    """Least squares ``a x ≈ b`` over rows ``x, y, z`` of each sample, each axis weighted by its noise.

    The sensor's noise differs per axis (an ATI Nano25's ``fz`` noise is three times its
    ``fx``), so one pooled residual variance would make some standard deviations too small
    and others too large. Two passes: ordinary least squares, then per-axis residual
    variances ``s_a²`` weight the rows (feasible generalised least squares) and the
    covariance is ``(Aᵀ W A)⁻¹`` with ``W = diag(1 / s_a²)``.

    Returns
    -------
    x, covariance, RMS residual per axis (unweighted), condition number of the column-scaled ``a``.
    """
    scale = np.linalg.norm(a, axis=0)
    scale = np.where(scale > 0, scale, 1.0)
    s = np.linalg.svd(a / scale, compute_uv=False)
    cond = float(s[0] / s[-1]) if s[-1] > 0 else math.inf
    x, *_ = np.linalg.lstsq(a, b, rcond=None)
    n = len(b) // 3
    dof = max(n - a.shape[1] / 3.0, 1.0)
    var = np.sum(np.square(b - a @ x).reshape(n, 3), axis=0) / dof
    var = np.maximum(var, 1e-30 + 1e-12 * float(var.max()))
    wt = np.tile(1.0 / np.sqrt(var), n)
    x, *_ = np.linalg.lstsq(a * wt[:, None], b * wt, rcond=None)
    r = b - a @ x
    var = np.sum(np.square(r).reshape(n, 3), axis=0) / dof
    var = np.maximum(var, 1e-30 + 1e-12 * float(var.max()))
    wt = np.tile(1.0 / np.sqrt(var), n)
    aw = a * wt[:, None]
    cov = np.linalg.pinv(aw.T @ aw)
    return x, cov, math.sqrt(float(r @ r) / len(b)), cond


def calibrate_payload(wrench: ArrayLike, orientation: ArrayLike, source: str = "<log>") -> PayloadFit:
    """Estimate the fingertip's mass, centre of mass and the sensor bias from contact-free samples.

    Model: ``wrench = bias + (m g_s, c × m g_s)``, linear in ``(bias_f, m)`` (force rows) and
    ``(bias_m, m c)`` (moment rows: ``c × m g_s = −[g_s]× (m c)``), solved separately.

    Parameters
    ----------
    wrench : array-like, shape (N, 6)
        Raw wrench, N and N·m; nothing may touch the fingertip.
    orientation : array-like, shape (N, 4)
        ``qw, qx, qy, qz`` (unit): sensor frame in the world frame, world z up.
    source : str
        Name for error messages.

    Returns
    -------
    PayloadFit

    Raises
    ------
    InputError
        Shapes, too few samples, orientations that do not vary enough (the design is
        ill-conditioned), or a mass that is not significantly positive.
    """
    w = np.asarray(wrench, dtype=float)
    q = np.asarray(orientation, dtype=float)
    if w.ndim != 2 or w.shape[1] != 6 or q.shape != (len(w), 4):
        raise InputError(f"{source}: expected wrench (N, 6) and orientation (N, 4), got {w.shape} and {q.shape}")
    n = len(w)
    if n < 10:
        raise InputError(f"{source}: {n} samples; expected at least 10 contact-free samples in varied orientations")
    g = gravity_in_sensor(q)
    gu = g / STANDARD_GRAVITY
    mean = gu.mean(axis=0)
    mean_dir = mean / np.linalg.norm(mean) if np.linalg.norm(mean) > 1e-9 else np.array([0.0, 0.0, 1.0])
    spread = float(np.degrees(np.arccos(np.clip(gu @ mean_dir, -1.0, 1.0))).max())

    eye = np.tile(np.eye(3), (n, 1))
    a_f = np.column_stack((eye, g.reshape(-1)))
    gx = np.zeros((n, 3, 3))  # −[g]×
    gx[:, 0, 1], gx[:, 0, 2] = g[:, 2], -g[:, 1]
    gx[:, 1, 0], gx[:, 1, 2] = -g[:, 2], g[:, 0]
    gx[:, 2, 0], gx[:, 2, 1] = g[:, 1], -g[:, 0]
    a_m = np.column_stack((eye, gx.reshape(-1, 3)))
    xf, cov_f, rms_f, cond_f = _solve_block(a_f, w[:, :3].reshape(-1))
    xm, cov_m, rms_m, cond_m = _solve_block(a_m, w[:, 3:].reshape(-1))
    cond = max(cond_f, cond_m)
    if not cond <= _MAX_CONDITION:
        raise InputError(
            f"{source}: the orientations do not vary enough to separate the payload from the sensor bias "
            f"(gravity direction in the sensor frame spans only {spread:.1f}° around its mean; condition number "
            f"{cond:.3g} > {_MAX_CONDITION:g}); rotate the finger through ±45° or more about at least two axes"
        )
    mass, mass_var = float(xf[3]), float(cov_f[3, 3])
    if not mass > 3.0 * math.sqrt(mass_var):
        raise InputError(
            f"{source}: the estimated mass {mass * 1e3:.3g} ± {math.sqrt(mass_var) * 1e3:.2g} g is not significantly "
            "positive; expected a fingertip of a few grams or more (was something touching it?)"
        )
    mc = xm[3:]
    com = mc / mass
    com_var = (np.diag(cov_m)[3:] + com**2 * mass_var) / mass**2  # first order; the two blocks are independent
    bias = np.concatenate((xf[:3], xm[:3]))
    bias_std = np.sqrt(np.concatenate((np.diag(cov_f)[:3], np.diag(cov_m)[:3])))
    return PayloadFit(
        payload=Payload(mass, tuple(com)),
        bias=bias,
        mass_std=math.sqrt(mass_var),
        com_std=np.sqrt(com_var),
        bias_std=bias_std,
        force_rms=rms_f,
        moment_rms=rms_m,
        n_samples=n,
        gravity_spread_deg=spread,
        condition=cond,
    )


# --------------------------------------------------------------------------------------
# logs and the stream


def _header_line(source: str) -> int | None:
    """1-based line of a CSV file's header (the first line not blank and not a comment)."""
    try:
        with open(source, encoding="utf-8-sig", newline="") as fh:
            for k, line in enumerate(fh, start=1):
                s = line.strip()
                if s and not s.startswith("#"):
                    return k
    except (OSError, UnicodeDecodeError):
        return None
    return None


def _to_float(cell: str) -> float:
    try:
        return float(cell)
    except ValueError:
        return math.nan


def read_orientation(log, tolerance: float = UNIT_TOLERANCE) -> NDArray[np.float64]:
    """The ``qw, qx, qy, qz`` columns of a log as unit quaternions, shape (N, 4).

    Parameters
    ----------
    log : softtip.io.tables.Log
        Read by :func:`softtip.io.tables.read_log`; the quaternion columns are among its extra
        columns.
    tolerance : float
        Largest accepted ``| |q| − 1 |``; accepted quaternions are normalised.

    Raises
    ------
    InputError
        A column missing, a cell empty, non-numeric or not finite, or a quaternion that is
        not a unit quaternion; names the file, the line and the column.
    """
    missing = [c for c in QUATERNION_COLUMNS if c not in log.extra]
    if missing:
        have = ", ".join(log.extra) or "none"
        raise InputError(
            f"{log.source}: missing orientation column(s) {', '.join(missing)}; gravity compensation needs "
            f"qw, qx, qy, qz (unit quaternion of the sensor frame in a z-up world frame); extra columns present: {have}"
        )
    csv_file = os.path.isfile(log.source) and not log.source.lower().endswith(".parquet")
    header = _header_line(log.source) if csv_file else None  # Parquet: rows by number

    def where(i: int, col: str) -> str:
        line = f"{log.source}:{header + 1 + i}" if header is not None else f"{log.source}: data row {i + 1}"
        return f"{line}: column {col!r}"

    n = len(log.t)
    q = np.empty((n, 4))
    for j, col in enumerate(QUATERNION_COLUMNS):
        cells = log.extra[col]
        try:
            q[:, j] = np.array(cells, dtype=float)
        except ValueError:  # cell by cell, to find the first bad one
            q[:, j] = [_to_float(c) for c in cells]
        bad = ~np.isfinite(q[:, j])
        if bad.any():
            i = int(np.argmax(bad))
            cell = cells[i]
            try:
                float(cell)
                what = f"expected a finite number, got {cell!r}"
            except ValueError:
                what = "empty cell; expected a number" if not cell.strip() else f"expected a number, got {cell!r}"
            raise InputError(f"{where(i, col)}: {what}")
    norm = np.linalg.norm(q, axis=1)
    bad = np.abs(norm - 1.0) > tolerance
    if bad.any():
        i = int(np.argmax(bad))
        raise InputError(
            f"{where(i, 'qw')}: qw, qx, qy, qz = {', '.join(str(log.extra[c][i]).strip() for c in QUATERNION_COLUMNS)} "
            f"has norm {norm[i]:.6g}; expected a unit quaternion (norm within {tolerance:g} of 1)"
        )
    return q / norm[:, None]


def compensate_log(log, payload: Payload | str | os.PathLike[str]):
    """A copy of ``log`` with the payload's gravity wrench removed (orientation from its columns).

    Parameters
    ----------
    log : softtip.io.tables.Log
    payload : Payload or path of a payload TOML file

    Returns
    -------
    softtip.io.tables.Log
    """
    payload = load_payload(payload)
    q = read_orientation(log)
    return replace(log, wrench=compensate_payload(log.wrench, q, payload))


class CompensatedSource:
    """A live source with the payload's gravity removed from every sample (plain floats).

    Parameters
    ----------
    source : iterable of Reading or (t, wrench)
        The raw source (its ``rate_hz``, ``name`` and ``close`` are passed through).
    orientations : iterable of 4 floats, or a callable
        ``qw, qx, qy, qz`` of each sample, in step with ``source``; or a function of the
        sample's time ``t`` (s) returning them — the robot's current sensor orientation from
        its joint states, an IMU, or a transform listener.
    payload : Payload
    """

    def __init__(self, source, orientations: Iterable | Callable[[float], Sequence[float]], payload: Payload) -> None:
        self.source = source
        self.orientations = orientations
        self.compensate = PayloadCompensator(payload)
        self.rate_hz = getattr(source, "rate_hz", None)
        self.name = getattr(source, "name", "source")

    def __iter__(self) -> Iterator:
        from softtip.io.sources import readings

        comp = self.compensate
        if callable(self.orientations):
            orientation = self.orientations
            for reading in readings(self.source):
                yield reading._replace(wrench=comp(reading.wrench, orientation(reading.t)))
            return
        for reading, q in zip(readings(self.source), self.orientations):
            yield reading._replace(wrench=comp(reading.wrench, q))

    def close(self) -> None:
        """Close the wrapped source, if it can be."""
        if hasattr(self.source, "close"):
            self.source.close()


def replay_source(path: str | os.PathLike[str], units: str, speed: float, payload: Payload | str | os.PathLike[str]) -> CompensatedSource:
    """``softtip stream --replay LOG --payload FILE``: the log replayed with per-sample compensation."""
    from softtip.io.sources import LogSource
    from softtip.io.tables import read_log

    payload = load_payload(payload)
    log = read_log(path, units=units)
    q = read_orientation(log)
    src = LogSource(log.t, log.wrench, speed=speed, name=os.path.basename(log.source))
    return CompensatedSource(src, [tuple(row) for row in q.tolist()], payload)
