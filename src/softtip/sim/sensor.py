"""Six-axis F/T sensor model: sample rate, constant bias, Gaussian noise, quantisation."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.core.noise import SensorNoise

__all__ = ["SensorModel", "NANO17_SENSOR"]

_FORCE_RES = 1.0 / 160.0  # N
_TORQUE_RES = 1.0 / 32.0 * 1e-3  # N·m (1/32 N·mm)


def _six(value: ArrayLike, name: str, positive: bool = True) -> tuple[float, ...]:
    a = np.broadcast_to(np.asarray(value, dtype=float), (6,))
    if not np.all(np.isfinite(a)) or (positive and np.any(a < 0.0)):
        raise ValueError(f"{name} must be 6 finite{' non-negative' if positive else ''} numbers, got {value!r}")
    return tuple(float(v) for v in a)


@dataclass(frozen=True)
class SensorModel:
    """What the F/T sensor does to the true wrench, per axis ``fx, fy, fz, mx, my, mz``.

    ``measured = quantise(true + bias + noise)``, with ``noise ~ N(0, noise_std²)``
    independent per axis and sample, and ``quantise(x) = resolution * round(x / resolution)``
    (no quantisation on axes whose resolution is 0).

    Parameters
    ----------
    rate : float
        Sample rate, Hz (the papers: 20 ms cycle, 50 Hz).
    noise_std : 6 floats
        Standard deviation, N and N·m. Default: 3 mN on forces, 0.02 N·mm on moments
        (ATI Nano17 class at 50 Hz, about half a count).
    bias : 6 floats
        Constant offset left after taring, N and N·m (default 0).
    resolution : 6 floats
        Quantisation step, N and N·m. Default ATI Nano17 (SI-25-0.25): 1/160 N and
        1/32 N·mm.
    """

    rate: float = 50.0
    noise_std: tuple[float, ...] = (3e-3, 3e-3, 3e-3, 2e-5, 2e-5, 2e-5)
    bias: tuple[float, ...] = (0.0,) * 6
    resolution: tuple[float, ...] = (_FORCE_RES,) * 3 + (_TORQUE_RES,) * 3

    def __post_init__(self) -> None:
        if not (math.isfinite(self.rate) and self.rate > 0.0):
            raise ValueError(f"rate must be a positive frequency in Hz, got {self.rate!r}")
        object.__setattr__(self, "noise_std", _six(self.noise_std, "noise_std"))
        object.__setattr__(self, "bias", _six(self.bias, "bias", positive=False))
        object.__setattr__(self, "resolution", _six(self.resolution, "resolution"))

    @classmethod
    def ideal(cls, rate: float = 50.0) -> SensorModel:
        """A perfect sensor: no noise, bias or quantisation."""
        return cls(rate=rate, noise_std=(0.0,) * 6, bias=(0.0,) * 6, resolution=(0.0,) * 6)

    def times(self, duration: float) -> NDArray[np.float64]:
        """Sample times ``k / rate`` for ``k = 0 .. round(duration * rate) - 1``, s."""
        n = int(round(duration * self.rate))
        if n < 1:
            raise ValueError(f"duration {duration!r} s gives no sample at {self.rate} Hz")
        return np.arange(n) / self.rate

    def measure(self, wrench: ArrayLike, rng: np.random.Generator) -> NDArray[np.float64]:
        """Apply bias, noise and quantisation to ``wrench`` (..., 6), SI; returns the same shape."""
        w = np.asarray(wrench, dtype=float)
        if w.shape[-1:] != (6,):
            raise ValueError(f"wrench must have shape (..., 6), got {w.shape}")
        out = w + np.asarray(self.bias) + rng.standard_normal(w.shape) * np.asarray(self.noise_std)
        res = np.asarray(self.resolution)
        step = np.where(res > 0.0, res, 1.0)
        return np.where(res > 0.0, np.round(out / step) * step, out)

    def noise_model(self) -> SensorNoise:
        """What to tell the estimator about this sensor: per axis the standard deviation of
        the noise with the quantisation's share, ``sqrt(noise_std² + resolution² / 12)``
        (N and N·m; the bias is left out, a tare removes it)."""
        q = np.hypot(self.noise_std, np.asarray(self.resolution) / math.sqrt(12.0))
        return SensorNoise(tuple(float(v) for v in q[:3]), tuple(float(v) for v in q[3:]))

    def as_dict(self) -> dict:
        """JSON-ready, SI."""
        return {
            "rate_hz": self.rate,
            "noise_std": list(self.noise_std),
            "bias": list(self.bias),
            "resolution": list(self.resolution),
            "axes": ["fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm"],
        }


#: The default simulated sensor (ATI Nano17 class, 50 Hz): a :class:`SensorModel` (noise, bias,
#: resolution, rate), not the estimator's noise model :data:`softtip.NANO17`.
NANO17_SENSOR = SensorModel()
