"""What the stream keeps per contact point: :class:`PointGeometry`.

What depends only on the contact point (its normal, the tangent frame, the moment-noise part of
``h``'s noise level) is computed once per point, from the kernels of the batch
(:mod:`softtip.core.spin`, :mod:`softtip.core.noise`): while a latch holds, once per contact.
"""

from __future__ import annotations

from softtip.core._xp import PY
from softtip.core.fingertip import Fingertip
from softtip.core.noise import noise_moment_part
from softtip.core.spin import tangent_frame_kernel

__all__ = ["PointGeometry"]


class PointGeometry:
    """What the stages need of a contact point ``point`` (m) with outward normal ``normal``:
    the tangent frame ``e1, e2`` (manual §3.4) and the moment-noise parts ``m1``, ``m2`` of
    ``vᵀ Σ_h v`` for ``v = e1, e2`` (:func:`softtip.core.noise.noise_moment_part`, which
    does not depend on the point; :func:`softtip.core.noise.h_std_parts_kernel` adds the rest),
    for the noise's variances ``variances`` (:func:`softtip.core.noise.noise_variances`).

    Stages that keep their own per-point terms recompute them when handed a geometry that
    ``is not`` the last one.
    """

    __slots__ = ("point", "normal", "nx", "ny", "nz", "frame", "e1x", "e1y", "e1z", "e2x", "e2y", "e2z", "m1", "m2")

    def __init__(self, point: tuple[float, float, float], normal: tuple[float, float, float], variances: tuple[float, ...]):
        self.point = point
        self.normal = normal
        nx, ny, nz = self.nx, self.ny, self.nz = normal
        self.frame = tangent_frame_kernel(nx, ny, nz, PY)
        e1x, e1y, e1z, e2x, e2y, e2z = self.e1x, self.e1y, self.e1z, self.e2x, self.e2y, self.e2z = self.frame
        _, _, _, smx, smy, smz = variances
        self.m1 = noise_moment_part(e1x, e1y, e1z, smx, smy, smz)
        self.m2 = noise_moment_part(e2x, e2y, e2z, smx, smy, smz)

    @classmethod
    def on_tip(cls, tip: Fingertip, point: tuple[float, float, float], variances: tuple[float, ...]) -> PointGeometry:
        """The geometry of a point on the skin of ``tip`` (its normal from the tip)."""
        return cls(point, tip._normal_kernel(point[0], point[1], point[2], PY), variances)
