"""Spin torque, its tangential component and the direction of the touched geometry.

Paper Eqs. 1–3 and manual §3.1, §3.3, §3.4:

- spin torque (moment about the contact point) ``q = m − r × f``;
- tangential spin torque ``h = q − (q · n) n``;
- direction of the edge / strip ``d = n × h / |n × h|``, an axis (``d ≡ −d``);
- its angle in the tangent frame ``e1 = normalise(x − (x·n) n)`` (``y`` instead when
  ``|x × n| < 0.1``), ``e2 = n × e1``, ``atan2(d·e2, d·e1)`` wrapped into ``(−π/2, π/2]``.

Batch functions take arrays with any leading shape; the ``*_kernel`` functions take per-axis
components (numpy arrays or floats, see :mod:`softtip.core._xp`) and are what the streaming
estimator calls.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.core._jit import jitable
from softtip.core._xp import NP

__all__ = [
    "spin_torque",
    "tangential_spin_torque",
    "edge_direction",
    "tangent_frame",
    "direction_angle",
]

_HALF_PI = 0.5 * math.pi


@jitable
def spin_torque_kernel(fx, fy, fz, mx, my, mz, rx, ry, rz):
    """``q = m − r × f`` component-wise."""
    return (
        mx - (ry * fz - rz * fy),
        my - (rz * fx - rx * fz),
        mz - (rx * fy - ry * fx),
    )


@jitable
def tangential_kernel(qx, qy, qz, nx, ny, nz):
    """``σ = q · n`` and ``h = q − σ n`` component-wise; returns ``(σ, hx, hy, hz)``."""
    sigma = qx * nx + qy * ny + qz * nz
    return sigma, qx - sigma * nx, qy - sigma * ny, qz - sigma * nz


@jitable
def direction_kernel(hx, hy, hz, nx, ny, nz, xp):
    """``|h|`` and ``d = n × h / |n × h|``; returns ``(|h|, dx, dy, dz)``.

    ``h`` is tangential, so ``|n × h| = |h|``; the normalisation uses the cross product's
    own norm so that ``d`` is a unit vector even when ``h`` carries a rounding-size normal
    part.
    """
    cx = ny * hz - nz * hy
    cy = nz * hx - nx * hz
    cz = nx * hy - ny * hx
    cn = xp.sqrt(cx * cx + cy * cy + cz * cz)
    hn = xp.sqrt(hx * hx + hy * hy + hz * hz)
    return hn, xp.div(cx, cn), xp.div(cy, cn), xp.div(cz, cn)


@jitable
def tangent_frame_kernel(nx, ny, nz, xp):
    """Tangent frame ``(e1, e2)`` at normal ``n`` (manual §3.4); returns 6 components."""
    # |x × n| = sqrt(ny² + nz²); below 0.1 the projected x axis is ill-defined, use y
    use_y = ny * ny + nz * nz < 0.01
    ax = xp.where(use_y, 0.0 * nx, 1.0 + 0.0 * nx)
    ay = 1.0 - ax
    dot = ax * nx + ay * ny
    ux, uy, uz = ax - dot * nx, ay - dot * ny, -dot * nz
    un = xp.sqrt(ux * ux + uy * uy + uz * uz)
    e1x, e1y, e1z = xp.div(ux, un), xp.div(uy, un), xp.div(uz, un)
    e2x = ny * e1z - nz * e1y
    e2y = nz * e1x - nx * e1z
    e2z = nx * e1y - ny * e1x
    return e1x, e1y, e1z, e2x, e2y, e2z


@jitable
def angle_kernel(dx, dy, dz, e1x, e1y, e1z, e2x, e2y, e2z, xp):
    """Axial angle of ``d`` in the tangent frame ``(e1, e2)``, radians in ``(−π/2, π/2]``."""
    a = xp.atan2(dx * e2x + dy * e2y + dz * e2z, dx * e1x + dy * e1y + dz * e1z)
    # d and −d are the same axis
    return a - math.pi * (a > _HALF_PI) + math.pi * (a <= -_HALF_PI)


# -- batch API -------------------------------------------------------------------------------


def _comp(a: ArrayLike, name: str, n: int = 3) -> list[NDArray]:
    a = np.asarray(a, dtype=float)
    if a.shape[-1:] != (n,):
        raise ValueError(f"{name} must have shape (..., {n}), got {a.shape}")
    return [a[..., i] for i in range(n)]


def spin_torque(wrench: ArrayLike, point: ArrayLike) -> NDArray[np.float64]:
    """Moment about the contact point, ``q = m − r × f`` (paper Eq. 1).

    Parameters
    ----------
    wrench : array-like, shape (..., 6)
        ``fx, fy, fz`` (N), ``mx, my, mz`` (N·m) about the sensor origin.
    point : array-like, shape (..., 3)
        Contact point ``r``, m.

    Returns
    -------
    array, shape (..., 3)
        ``q`` in N·m.
    """
    return np.stack(spin_torque_kernel(*_comp(wrench, "wrench", 6), *_comp(point, "point")), axis=-1)


def tangential_spin_torque(q: ArrayLike, normal: ArrayLike) -> NDArray[np.float64]:
    """Tangential component of the spin torque, ``h = q − (q · n) n`` (paper Eq. 3).

    Parameters
    ----------
    q : array-like, shape (..., 3)
        Spin torque, N·m.
    normal : array-like, shape (..., 3)
        Outward unit skin normal at the contact point.

    Returns
    -------
    array, shape (..., 3)
        ``h`` in N·m.
    """
    return np.stack(tangential_kernel(*_comp(q, "q"), *_comp(normal, "normal"))[1:], axis=-1)


def edge_direction(h: ArrayLike, normal: ArrayLike) -> NDArray[np.float64]:
    """Direction of the touched edge, stick, plate or fringe, ``d = n × h / |n × h|``.

    ``d`` is an axis: ``d`` and ``−d`` mean the same. NaN where ``h = 0``.

    Parameters
    ----------
    h : array-like, shape (..., 3)
        Tangential spin torque, N·m.
    normal : array-like, shape (..., 3)
        Outward unit skin normal.

    Returns
    -------
    array, shape (..., 3)
        Unit direction.
    """
    _, dx, dy, dz = direction_kernel(*_comp(h, "h"), *_comp(normal, "normal"), NP)
    return np.stack((dx, dy, dz), axis=-1)


def tangent_frame(normal: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The manual §3.4 tangent frame ``(e1, e2)`` at ``normal``, each shape ``(..., 3)``."""
    c = tangent_frame_kernel(*_comp(normal, "normal"), NP)
    return np.stack(c[:3], axis=-1), np.stack(c[3:], axis=-1)


def direction_angle(direction: ArrayLike, normal: ArrayLike, *, unit: str = "rad") -> NDArray[np.float64]:
    """Angle of the axis ``direction`` in the tangent frame at ``normal``.

    At the fingertip's tip (``n = z``) this is the angle from the sensor x axis, as in the
    papers' figures.

    Parameters
    ----------
    direction : array-like, shape (..., 3)
        Unit tangent direction ``d`` (sign ignored).
    normal : array-like, shape (..., 3)
        Outward unit normal.
    unit : {"rad", "deg"}

    Returns
    -------
    array, shape (...,)
        Angle in ``(−π/2, π/2]`` (or ``(−90°, 90°]``).
    """
    if unit not in ("rad", "deg"):
        raise ValueError(f"unit must be 'rad' or 'deg', got {unit!r}")
    frame = tangent_frame_kernel(*_comp(normal, "normal"), NP)
    a = angle_kernel(*_comp(direction, "direction"), *frame, NP)
    return np.degrees(a) if unit == "deg" else np.asarray(a)
