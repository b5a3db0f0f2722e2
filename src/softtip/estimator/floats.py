"""What the stream keeps per contact point, and the evidence stage's per-sample direction on floats.

What depends only on the contact point (its normal, the tangent frame, the moment-noise part of
``h``'s noise level) is computed once per point in :class:`PointGeometry`, from the kernels of
the batch (:mod:`softtip.core.spin`, :mod:`softtip.core.noise`): while a latch holds, once per
contact. :func:`sample_direction` is the evidence stage's.
"""

from __future__ import annotations

import math

from softtip.core._jit import lazy_jit
from softtip.core._xp import PY
from softtip.core.evidence import _div
from softtip.core.fingertip import Fingertip
from softtip.core.noise import SensorNoise, _quad_moment_kernel, noise_quad
from softtip.core.spin import tangent_frame_kernel

__all__ = ["NoiseSquares", "PointGeometry", "sample_direction"]

_PI = math.pi
_HALF_PI = 0.5 * math.pi


class NoiseSquares:
    """The variances of a :class:`~softtip.core.noise.SensorNoise` (N², N²·m²), as the noise
    kernels of :mod:`softtip.core.noise` form them (``s * s``)."""

    __slots__ = ("fx", "fy", "fz", "mx", "my", "mz", "noise")

    def __init__(self, noise: SensorNoise):
        self.noise = noise
        self.fx, self.fy, self.fz = (s * s for s in noise.force_std)
        self.mx, self.my, self.mz = (s * s for s in noise.moment_std)


class PointGeometry:
    """What the stages need of a contact point ``point`` (m) with outward normal ``normal``:
    the tangent frame ``e1, e2`` (manual §3.4) and the moment-noise parts ``m1``, ``m2`` of
    ``vᵀ Σ_h v`` for ``v = e1, e2`` (:func:`softtip.core.noise._quad_moment_kernel`, which
    does not depend on the point; :func:`softtip.core.noise.h_std_parts_kernel` adds the rest).

    Stages that keep their own per-point terms recompute them when handed a geometry that
    ``is not`` the last one.
    """

    __slots__ = ("point", "normal", "nx", "ny", "nz", "frame", "e1x", "e1y", "e1z", "e2x", "e2y", "e2z", "m1", "m2")

    def __init__(self, point: tuple[float, float, float], normal: tuple[float, float, float], sq: NoiseSquares):
        self.point = point
        self.normal = normal
        nx, ny, nz = self.nx, self.ny, self.nz = normal
        self.frame = tangent_frame_kernel(nx, ny, nz, PY)
        e1x, e1y, e1z, e2x, e2y, e2z = self.e1x, self.e1y, self.e1z, self.e2x, self.e2y, self.e2z = self.frame
        self.m1 = _quad_moment_kernel(e1x, e1y, e1z, sq.noise)
        self.m2 = _quad_moment_kernel(e2x, e2y, e2z, sq.noise)

    @classmethod
    def on_tip(cls, tip: Fingertip, point: tuple[float, float, float], sq: NoiseSquares) -> PointGeometry:
        """The geometry of a point on the skin of ``tip`` (its normal from the tip)."""
        return cls(point, tip._normal_kernel(point[0], point[1], point[2], PY), sq)


@lazy_jit
def sample_direction(hx, hy, hz, hn, rx, ry, rz, nx, ny, nz, e1x, e1y, e1z, e2x, e2y, e2z, sfx, sfy, sfz, smx, smy, smz):
    """A sample's own direction ``d = n × h / |n × h|``, its angle in the tangent frame
    ``(e1, e2)`` at the normal ``n`` and the angle's first-order standard deviation from the
    sensor noise (rad; ``sf*``, ``sm*`` its variances per axis, N², N²·m²), with ``h`` taken
    about ``r`` (m) and ``hn = |h|``: ``(dx, dy, dz, angle, angle_std)`` as
    :func:`softtip.estimator.measure.measure` gives them (its ``atan2`` is numpy's there, the
    C library's here: the angle may differ in the last bit). Compiled with the evidence step."""
    cx = ny * hz - nz * hy
    cy = nz * hx - nx * hz
    cz = nx * hy - ny * hx
    cn = math.sqrt(cx * cx + cy * cy + cz * cz)
    dx, dy, dz = _div(cx, cn), _div(cy, cn), _div(cz, cn)
    a = math.atan2(dx * e2x + dy * e2y + dz * e2z, dx * e1x + dy * e1y + dz * e1z)
    angle = a - _PI * (a > _HALF_PI) + _PI * (a <= -_HALF_PI)
    q = noise_quad(dx, dy, dz, rx, ry, rz, sfx, sfy, sfz, smx, smy, smz)
    s = math.sqrt(q) if q >= 0.0 else math.nan
    return dx, dy, dz, angle, _div(s, hn)
