"""The measurement stage, shared by batch and stream: from the wrench and a contact point to
the spin torque, ``h``, its noise level, the line test, the direction and its angle.

:func:`measure` is component-wise: the batch calls it on numpy arrays (back end
:data:`softtip.core._xp.NP`), the stream on Python floats (:data:`softtip.core._xp.PY`), so both agree
to rounding.
"""

from __future__ import annotations

from typing import Any, NamedTuple

from softtip.core._jit import jitable
from softtip.core.depth import DepthLaw, depth_kernel
from softtip.core.filtering import noise_gain
from softtip.core.noise import (
    SensorNoise,
    h_std_parts_kernel,
    line_threshold_kernel,
    noise_moment_part,
    noise_variances,
    sample_direction_kernel,
)
from softtip.core.spin import spin_torque_kernel, tangent_frame_kernel, tangential_kernel

__all__ = ["Measurement", "measure", "measure_kernel", "effective_noise", "noise_correlation"]


class Measurement(NamedTuple):
    """One measurement, component-wise (floats or arrays of one shape). SI units."""

    sigma: Any  #: spin torque about the normal, N·m
    hx: Any  #: tangential spin torque ``h``, N·m
    hy: Any
    hz: Any
    h_norm: Any  #: ``|h|``, N·m
    h_std: Any  #: standard deviation of ``h`` (``sqrt(trace Σ_h)``: the noise's and the depth's), N·m
    dx: Any  #: unit direction ``n × h / |n × h|`` (an axis)
    dy: Any
    dz: Any
    angle: Any  #: angle of ``d`` in the tangent frame, rad
    angle_std: Any  #: its first-order standard deviation from the sensor noise, rad
    line: Any  #: ``|h|`` significant: ``|h| > max(h_sigmas · h_std, h_min)``
    pushing: Any  #: the force pushes into the skin (``f · n < 0``)
    depth: Any  #: depth ``δ`` of the point the moment is taken about, m (0 without a law)


@jitable
def measure_kernel(fx, fy, fz, mx, my, mz, ex, ey, ez, nx, ny, nz, e1x, e1y, e1z, e2x, e2y, e2z, m1, m2,
                   sfx, sfy, sfz, depth_var, xp):  # fmt: skip
    """The measurement about the point ``e`` (m) where the load acts, at the unit normal ``n``:
    ``(σ, hx, hy, hz, |h|, h_std)``, N·m.

    ``q = m − e × f``, ``σ = q · n``, ``h = q − σ n`` and ``h``'s uncertainty
    ``sqrt(trace Σ_h)`` in the tangent frame ``(e1, e2)``: the sensor noise's, whose moment
    parts ``m1``, ``m2`` (:func:`~softtip.core.noise.noise_moment_part`) depend on the normal
    alone (a stream or a compiled loop keeps them while the normal holds; ``sf*`` the force
    variances, N²), and the depth's: ``e = r − δ n`` with ``δ`` known to a variance
    ``depth_var`` (m²) moves ``h`` by ``δ n × f``, of variance ``depth_var · |n × f|²`` (a
    depth from the skin's law before the data give one: a tangential load on a tip whose
    friction acts elsewhere then does not read as a line). The one composition of the stage:
    :func:`measure` (arrays), the stream (floats) and the batch's compiled loop
    (:mod:`softtip.estimator.pipeline`) call it.
    """
    qx, qy, qz = spin_torque_kernel(fx, fy, fz, mx, my, mz, ex, ey, ez)
    sigma, hx, hy, hz = tangential_kernel(qx, qy, qz, nx, ny, nz)
    hn = xp.sqrt(hx * hx + hy * hy + hz * hz)
    fn = fx * nx + fy * ny + fz * nz
    tangential2 = xp.maximum(fx * fx + fy * fy + fz * fz - fn * fn, 0.0)  # |n × f|²
    h_std = h_std_parts_kernel(m1, m2, ex, ey, ez, e1x, e1y, e1z, e2x, e2y, e2z, sfx, sfy, sfz, depth_var * tangential2, xp)
    return sigma, hx, hy, hz, hn, h_std


def measure(
    fx, fy, fz, mx, my, mz, rx, ry, rz, nx, ny, nz,
    noise: SensorNoise, h_sigmas: float, h_min: float, law: DepthLaw | None, xp, depth_std=0.0,
) -> Measurement:  # fmt: skip
    """Spin torque, ``h``, noise, direction and the line test for a contact point ``r``
    with outward normal ``n``.

    With a depth law the moment is taken about ``r − δ n`` (friction acts inside the skin);
    ``depth_std`` (m) the uncertainty of a depth the caller moved ``r`` by (:func:`measure_kernel`).
    """
    pushing = fx * nx + fy * ny + fz * nz < 0.0
    if law is None:
        delta = 0.0 * fx
    else:
        delta = depth_kernel(-(fx * nx + fy * ny + fz * nz), law, xp)
        rx, ry, rz = rx - delta * nx, ry - delta * ny, rz - delta * nz
    frame = tangent_frame_kernel(nx, ny, nz, xp)
    variances = noise_variances(noise)
    m1, m2 = noise_moment_part(*frame[:3], *variances[3:]), noise_moment_part(*frame[3:], *variances[3:])
    sigma, hx, hy, hz, hn, h_std = measure_kernel(
        fx, fy, fz, mx, my, mz, rx, ry, rz, nx, ny, nz, *frame, m1, m2, *variances[:3], depth_std * depth_std, xp
    )
    _, dx, dy, dz, angle, angle_std = sample_direction_kernel(hx, hy, hz, rx, ry, rz, nx, ny, nz, *frame, *variances, xp)
    line = hn > line_threshold_kernel(h_std, h_sigmas, h_min, xp)
    return Measurement(sigma, hx, hy, hz, hn, h_std, dx, dy, dz, angle, angle_std, line, pushing, delta)


def effective_noise(noise: SensorNoise, sos) -> SensorNoise:
    """The sensor noise after the low-pass ``sos`` (unchanged without one)."""
    return noise if sos is None else noise.scaled(noise_gain(sos))


def noise_correlation(sos) -> float:
    """Samples per independent noise sample after the filter ``sos`` (1 without one)."""
    return 1.0 if sos is None else 1.0 / noise_gain(sos) ** 2
