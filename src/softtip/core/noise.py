"""Sensor noise model and its propagation to the tangential spin torque and the angle.

The F/T sensor's noise is modelled as independent zero-mean Gaussians per axis with
standard deviations ``force_std`` (N) and ``moment_std`` (N·m). With the contact point
``r`` and normal ``n`` held fixed (the latched point), ``h = P (m − [r]× f)`` with
``P = I − n nᵀ`` is linear in the wrench, so its covariance is

``Σ_h = P Σ_m P + P [r]× Σ_f [r]×ᵀ P``.

For a unit tangent vector ``v``, ``vᵀ Σ_h v = Σ_i σ_m,i² v_i² + Σ_i σ_f,i² (v × r)_i²``.
softtip reports

- ``h_std = sqrt(trace Σ_h)``: the root-mean-square magnitude of the noise in ``h``, i.e.
  what ``|h|`` looks like when the true ``h`` is zero; ``|h|`` is significant above
  ``max(k · h_std, h_min)`` (manual §3.5, ``k = 3``);
- ``angle_std = sqrt(tᵀ Σ_h t) / |h|`` with ``t = d``: the first-order standard deviation of
  the direction angle, radians.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.core._jit import jitable
from softtip.core._xp import NP
from softtip.core.spin import angle_kernel, direction_kernel, tangent_frame_kernel

__all__ = [
    "SensorNoise", "NANO17", "NANO25", "MINI40", "SENSOR_CLASSES", "NOISE_PRESETS", "MAD_TO_STD", "tangential_spin_torque_std",
    "direction_angle_std",
]  # fmt: skip


@dataclass(frozen=True)
class SensorNoise:
    """Per-axis standard deviations of the F/T sensor's noise, sensor frame.

    Parameters
    ----------
    force_std : tuple of 3 floats
        N, for ``fx, fy, fz``.
    moment_std : tuple of 3 floats
        N·m, for ``mx, my, mz``.
    """

    force_std: tuple[float, float, float]
    moment_std: tuple[float, float, float]

    def __post_init__(self) -> None:
        for name in ("force_std", "moment_std"):
            v = np.asarray(getattr(self, name), dtype=float)
            if v.shape == ():
                v = np.full(3, float(v))
            if v.shape != (3,) or not np.all(np.isfinite(v)) or np.any(v < 0):
                raise ValueError(f"{name} must be 3 non-negative finite numbers, got {getattr(self, name)!r}")
            object.__setattr__(self, name, tuple(float(x) for x in v))

    def scaled(self, factor: float) -> SensorNoise:
        """The same model with every standard deviation multiplied by ``factor``."""
        return SensorNoise(
            tuple(factor * s for s in self.force_std), tuple(factor * s for s in self.moment_std)
        )


# Noise presets: about one count of ATI's published resolution per axis (SI calibrations,
# unfiltered). ATI states a resolution, not a noise standard deviation; measure your own
# sensor (the standard deviation of each axis while untouched) when it matters. Sources:
# ATI's product pages (https://www.ati-ia.com/products/ft/ft_models.aspx?id=Nano17, ...id=Nano25,
# ...id=Mini40), whose calibration tables we could read only as quoted in public projects:
# Nano17 SI-12-0.12 1/320 N and 1/64 N·mm, SI-25-0.25 1/160 N (its torque step, 1/32 N·mm,
# follows from the doubled range); Nano25 SI-125-3 1/48 N (fx, fy) and 1/16 N (fz) (≈ 0.021
# and 0.063 N); Mini40 SI-20-1 1/200 N, fz 1/100 N, 1/8000 N·m, so SI-40-2 (twice the
# ranges) 1/100 N, fz 1/50 N, 1/4000 N·m by the same scaling. Not checked against ATI's
# page itself: the Nano25's torque step (1/1320 N·m) and the Mini40 SI-40-2 row.

#: ATI Nano17-class defaults (SI-25-0.25 calibration: resolution 1/160 N and 1/32 N·mm):
#: about one resolution count of noise per axis, unfiltered.
NANO17 = SensorNoise(force_std=(0.006, 0.006, 0.006), moment_std=(3.0e-5, 3.0e-5, 3.0e-5))
#: ATI Nano25 class (SI-125-3: 1/48 N, fz 1/16 N, 1/1320 N·m), one count per axis.
NANO25 = SensorNoise(force_std=(1 / 48, 1 / 48, 1 / 16), moment_std=(1 / 1320, 1 / 1320, 1 / 1320))
#: ATI Mini40 class (SI-40-2: 1/100 N, fz 1/50 N, 1/4000 N·m), one count per axis.
MINI40 = SensorNoise(force_std=(1 / 100, 1 / 100, 1 / 50), moment_std=(1 / 4000, 1 / 4000, 1 / 4000))
#: The presets by name.
SENSOR_CLASSES = {"Nano17": NANO17, "Nano25": NANO25, "Mini40": MINI40}
#: The presets by the name ``--sensor`` and the ROS parameter ``sensor`` take: the one list of them.
NOISE_PRESETS = {name.lower(): preset for name, preset in SENSOR_CLASSES.items()}
#: A normal variable's standard deviation over its median absolute deviation (1 / Φ⁻¹(3/4)):
#: the robust spreads of the tare and of the unit check.
MAD_TO_STD = 1.482602218505602


@jitable
def noise_variances(noise: SensorNoise) -> tuple[float, float, float, float, float, float]:
    """``(σ_fx², σ_fy², σ_fz², σ_mx², σ_my², σ_mz²)`` of ``noise`` (N², N²·m²): what the
    kernels below take (a compiled step cannot read a :class:`SensorNoise`)."""
    (fx, fy, fz), (mx, my, mz) = noise.force_std, noise.moment_std
    return fx * fx, fy * fy, fz * fz, mx * mx, my * my, mz * mz


@jitable
def noise_moment_part(vx, vy, vz, smx, smy, smz):
    """The moment-noise part of ``vᵀ Σ_h v`` (``sm*`` the moment variances, N²·m²): the same at
    every contact point, so a stream keeps it while a point is held."""
    return smx * vx * vx + smy * vy * vy + smz * vz * vz


@jitable
def noise_quad_from(part, vx, vy, vz, rx, ry, rz, sfx, sfy, sfz):
    """``vᵀ Σ_h v`` from its moment-noise part ``part`` (:func:`noise_moment_part`): plus the
    force-noise part at the contact point ``r`` (m; ``sf*`` the force variances, N²)."""
    cx = vy * rz - vz * ry
    cy = vz * rx - vx * rz
    cz = vx * ry - vy * rx
    return part + sfx * cx * cx + sfy * cy * cy + sfz * cz * cz


@jitable
def noise_quad(vx, vy, vz, rx, ry, rz, sfx, sfy, sfz, smx, smy, smz):
    """``vᵀ Σ_h v`` for a tangent vector ``v`` at the contact point ``r`` (m), from the sensor
    noise's variances per axis (N², N²·m²; :func:`noise_variances`). The one form: every
    noise level of ``h`` (``h_std``, the angle's, the evidence window's and the line fit's)
    is made of it."""
    return noise_quad_from(noise_moment_part(vx, vy, vz, smx, smy, smz), vx, vy, vz, rx, ry, rz, sfx, sfy, sfz)


def h_std_kernel(rx, ry, rz, e1x, e1y, e1z, e2x, e2y, e2z, sfx, sfy, sfz, smx, smy, smz, xp):
    """``sqrt(trace Σ_h)`` component-wise, from any orthonormal tangent frame ``(e1, e2)`` and the
    noise's variances (:func:`noise_variances`)."""
    m1, m2 = noise_moment_part(e1x, e1y, e1z, smx, smy, smz), noise_moment_part(e2x, e2y, e2z, smx, smy, smz)
    return h_std_parts_kernel(m1, m2, rx, ry, rz, e1x, e1y, e1z, e2x, e2y, e2z, sfx, sfy, sfz, 0.0, xp)


@jitable
def h_std_parts_kernel(m1, m2, rx, ry, rz, e1x, e1y, e1z, e2x, e2y, e2z, sfx, sfy, sfz, extra, xp):
    """:func:`h_std_kernel` given the moment-noise parts ``m1``, ``m2`` of the frame
    (:func:`noise_moment_part`, which a stream keeps while a contact point is held), with
    ``extra`` (N²·m²) added to ``trace Σ_h`` (the uncertain depth's part: :func:`~softtip.estimator.measure.measure_kernel`)."""
    v1 = noise_quad_from(m1, e1x, e1y, e1z, rx, ry, rz, sfx, sfy, sfz)
    return xp.sqrt(v1 + noise_quad_from(m2, e2x, e2y, e2z, rx, ry, rz, sfx, sfy, sfz) + extra)


@jitable
def line_threshold_kernel(h_std, h_sigmas, h_min, xp):
    """The ``|h|`` above which ``h`` is significant (a line): ``max(h_sigmas · h_std, h_min)``
    (N·m; manual §3.5). The one form of the test: the measurement's, the line evidence's
    compiled step's and :meth:`~softtip.estimator.config.EstimatorConfig.line_threshold`."""
    return xp.maximum(h_sigmas * h_std, h_min)


@jitable
def angle_std_kernel(dx, dy, dz, h_norm, rx, ry, rz, sfx, sfy, sfz, smx, smy, smz, xp):
    """First-order standard deviation of the direction angle, radians."""
    return xp.div(xp.sqrt(noise_quad(dx, dy, dz, rx, ry, rz, sfx, sfy, sfz, smx, smy, smz)), h_norm)


@jitable
def sample_direction_kernel(hx, hy, hz, rx, ry, rz, nx, ny, nz, e1x, e1y, e1z, e2x, e2y, e2z,
                            sfx, sfy, sfz, smx, smy, smz, xp):  # fmt: skip
    """A sample's own direction from its ``h`` (N·m, taken about ``r``, m) at the normal ``n``:
    ``(|h|, dx, dy, dz, angle, angle_std)``, ``d = n × h / |n × h|``
    (:func:`~softtip.core.spin.direction_kernel`), its angle in the tangent frame ``(e1, e2)``
    (:func:`~softtip.core.spin.angle_kernel`) and the angle's first-order standard deviation
    from the noise's variances (:func:`angle_std_kernel`), rad. The measurement stage's on
    arrays (``xp`` :data:`~softtip.core._xp.NP`), the line evidence's in its compiled step
    (:mod:`softtip.core._xp_scalar`: the C library's ``atan2``, numpy's on arrays, so the angle
    may differ between the two in the last bit)."""
    hn, dx, dy, dz = direction_kernel(hx, hy, hz, nx, ny, nz, xp)
    angle = angle_kernel(dx, dy, dz, e1x, e1y, e1z, e2x, e2y, e2z, xp)
    return hn, dx, dy, dz, angle, angle_std_kernel(dx, dy, dz, hn, rx, ry, rz, sfx, sfy, sfz, smx, smy, smz, xp)


def _split3(a: ArrayLike, name: str) -> list[NDArray]:
    a = np.asarray(a, dtype=float)
    if a.shape[-1:] != (3,):
        raise ValueError(f"{name} must have shape (..., 3), got {a.shape}")
    return [a[..., i] for i in range(3)]


def tangential_spin_torque_std(point: ArrayLike, normal: ArrayLike, noise: SensorNoise = NANO17) -> NDArray[np.float64]:
    """Noise level of ``h``: ``sqrt(trace Σ_h)``, N·m, shape ``(...,)``.

    Parameters
    ----------
    point : array-like, shape (..., 3)
        Contact point, m.
    normal : array-like, shape (..., 3)
        Unit normal.
    noise : SensorNoise
    """
    frame = tangent_frame_kernel(*_split3(normal, "normal"), NP)
    return np.asarray(h_std_kernel(*_split3(point, "point"), *frame, *noise_variances(noise), NP))


def direction_angle_std(
    direction: ArrayLike, h_norm: ArrayLike, point: ArrayLike, noise: SensorNoise = NANO17
) -> NDArray[np.float64]:
    """First-order standard deviation of the direction angle, radians, shape ``(...,)``.

    Parameters
    ----------
    direction : array-like, shape (..., 3)
        Unit direction ``d``.
    h_norm : array-like, shape (...,)
        ``|h|``, N·m.
    point : array-like, shape (..., 3)
        Contact point, m.
    noise : SensorNoise
    """
    return np.asarray(
        angle_std_kernel(
            *_split3(direction, "direction"), np.asarray(h_norm, float), *_split3(point, "point"), *noise_variances(noise), NP
        )
    )
