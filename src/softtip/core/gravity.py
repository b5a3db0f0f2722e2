"""The fingertip's weight on the sensor: the payload and its gravity wrench.

The F/T sensor carries the fingertip: its weight is an external force on the sensor like
the contact's. With the sensor frame's orientation ``R`` in a gravity-aligned world frame
(world ``z`` up; ``v_world = R v_sensor``), the fingertip of mass ``m`` with centre of mass
``c`` (sensor frame, m) adds, in the manual's convention (§1) (what acts on the fingertip)::

    f_g = m g_s,    m_g = c × f_g,    g_s = Rᵀ (0, 0, −9.80665)

Taring at one orientation removes it only at that orientation; a rotating hand then sees a
spurious wrench of up to ``2 m g`` and ``2 m g |c|`` (0.4 N and 8 N·mm for 20 g at 20 mm).
:func:`compensate_payload` subtracts it before the estimator (so its tare then removes only
the true sensor bias); :class:`PayloadCompensator` does the same for one sample with plain
floats for the stream. The payload is fitted by :func:`softtip.calibration.payload.calibrate_payload`;
logs and live sources are compensated by :mod:`softtip.io.payload`.

Payload files are TOML::

    [payload]
    mass = 0.02            # kg
    com = [0, 0, 0.02]     # m, sensor frame
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from softtip.core.shape import SIZE_RANGE
from softtip.core.units import STANDARD_GRAVITY
from softtip.errors import InputError
from softtip.tomlfile import read_toml_table

__all__ = ["Payload", "PayloadCompensator", "load_payload", "gravity_in_sensor", "payload_wrench", "compensate_payload"]


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
        payload = Payload(float(mass), tuple(com))
    except ValueError as exc:
        raise InputError(f"{name}: [payload] {exc}") from None
    check_payload(payload, f"{name}: [payload]")
    return payload


#: kg: the heaviest fingertip a payload may have (a mass of a few grams written in g as kg
#: reads 1000 times too large: beyond this from 1 g on)
MAX_PAYLOAD_MASS = 1.0


def check_payload(payload: Payload, source: str, *, mass_hint: str = "a mass in g written as kg?",
                  com_hint: str = "lengths in mm written as m?") -> None:  # fmt: skip
    """Refuse a payload no fingertip has: heavier than :data:`MAX_PAYLOAD_MASS`, or its centre
    of mass farther from the sensor than a fingertip's largest size
    (:data:`~softtip.core.shape.SIZE_RANGE`): a units mistake, which ``mass_hint`` and
    ``com_hint`` name (a file's by default; a fit's is its log's units).

    Raises
    ------
    InputError
        Naming ``source``, the value and the likely mistake.
    """
    if payload.mass > MAX_PAYLOAD_MASS:
        raise InputError(
            f"{source} mass = {payload.mass:.6g} kg; expected a fingertip's, at most {MAX_PAYLOAD_MASS:g} kg ({mass_hint})"
        )
    reach = float(np.linalg.norm(payload.com))
    if reach > SIZE_RANGE[1]:
        raise InputError(
            f"{source} com is {reach:.4g} m from the sensor; expected a fingertip's centre of mass, within "
            f"{SIZE_RANGE[1]:g} m ({com_hint})"
        )


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
