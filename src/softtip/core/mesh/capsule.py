"""A generated mesh: the capsule fingertip, optionally with a nail, as a closed triangle mesh.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

__all__ = ["capsule_mesh"]


def capsule_mesh(
    radius: float,
    length: float,
    *,
    segments: int = 160,
    spacing: float | None = None,
    nail_height: float = 0.0,
    nail_half_width_deg: float = 50.0,
    nail_z: tuple[float, float] = (0.008, 0.0),
    nail_edge: float = 0.0015,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """A closed triangle mesh of a capsule fingertip, optionally with a nail (sensor frame, m).

    The capsule of :class:`~softtip.core.fingertip.Capsule` (cylinder of ``radius`` along +z from
    ``z = 0``, hemisphere at ``(0, 0, length)``), closed by a flat base at ``z = 0``. A nail
    is a raised plate of ``nail_height`` (m) on the back (``−x`` side), ``nail_half_width_deg``
    to either side, from ``z = nail_z[0]`` to ``nail_z[1]`` m past the cap's equator along the
    surface, with smooth edges of width ``nail_edge`` (m).

    Parameters
    ----------
    radius, length : float
        Capsule radius and cylinder length, m.
    segments : int
        Vertices around the axis.
    spacing : float, optional
        Target edge length along the profile, m (default: the spacing around the axis).

    Returns
    -------
    vertices : array, shape (V, 3)
    faces : array of int, shape (F, 3), counter-clockwise seen from outside.
    """
    h = spacing if spacing is not None else 2.0 * math.pi * radius / segments
    # profile arc length s: base disc (ρ 0→R), side (z 0→L), cap (angle 0→π/2)
    s_base, s_side, s_cap = radius, length, 0.5 * math.pi * radius
    n_base = max(2, round(s_base / (2.0 * h)))
    n_side = max(1, round(s_side / h))
    n_cap = max(2, round(s_cap / h))
    s_list = np.concatenate(
        (
            np.linspace(0.0, s_base, n_base + 1)[1:],
            s_base + np.linspace(0.0, s_side, n_side + 1)[1:],
            s_base + s_side + np.linspace(0.0, s_cap, n_cap + 1)[1:-1],
        )
    )
    phi = 2.0 * math.pi * np.arange(segments) / segments
    rings = []
    for s in s_list:
        if s <= s_base:
            rho, z, nr, nz = s, 0.0, 0.0, -1.0
        elif s <= s_base + s_side:
            rho, z, nr, nz = radius, s - s_base, 1.0, 0.0
        else:
            a = (s - s_base - s_side) / radius
            rho, z, nr, nz = radius * math.cos(a), length + radius * math.sin(a), math.cos(a), math.sin(a)
        x, y = rho * np.cos(phi), rho * np.sin(phi)
        ring = np.column_stack((x, y, np.full(segments, z)))
        if nail_height > 0.0 and nz > -0.5:
            w = _nail_weight(phi, s - s_base, radius, length, nail_half_width_deg, nail_z, nail_edge)
            ring = ring + nail_height * w[:, None] * np.column_stack((nr * np.cos(phi), nr * np.sin(phi), np.full(segments, nz)))
        rings.append(ring)
    bottom = np.array([[0.0, 0.0, 0.0]])
    top = np.array([[0.0, 0.0, length + radius + nail_height * float(
        _nail_weight(np.array([math.pi]), s_side + s_cap, radius, length, nail_half_width_deg, nail_z, nail_edge)[0]
    )]])
    vertices = np.concatenate([bottom] + rings + [top])
    nr_rings = len(rings)
    j = np.arange(segments)
    jn = (j + 1) % segments
    faces = []
    # base fan (outward normal −z): seen from below, counter-clockwise is decreasing φ
    first = 1
    faces.append(np.column_stack((np.zeros(segments, dtype=np.int64), first + jn, first + j)))
    for r in range(nr_rings - 1):
        a = 1 + r * segments
        b = a + segments
        faces.append(np.column_stack((a + j, a + jn, b + jn)))
        faces.append(np.column_stack((a + j, b + jn, b + j)))
    last = 1 + (nr_rings - 1) * segments
    apex = len(vertices) - 1
    faces.append(np.column_stack((last + j, last + jn, np.full(segments, apex))))
    return vertices, np.concatenate(faces).astype(np.int64)


def _nail_weight(phi, s_side, radius, length, half_width_deg, nail_z, edge):
    """0..1 height profile of the nail over (azimuth, arc length from the base rim)."""
    # angular distance from the back (φ = π), as arc length on the skin
    dphi = np.abs(np.angle(np.exp(1j * (phi - math.pi))))
    across = radius * (math.radians(half_width_deg) - dphi)
    z0, past = nail_z
    s_end = length + past
    along = np.minimum(s_side - z0, s_end - s_side)

    def smooth(x):
        u = np.clip(x / edge + 0.5, 0.0, 1.0)
        return u * u * (3.0 - 2.0 * u)

    return smooth(across) * smooth(along)
