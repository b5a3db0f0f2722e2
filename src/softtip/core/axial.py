"""Statistics of axial angles: directions where ``a`` and ``a + π`` are the same axis."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["axial_difference", "axial_mean", "axial_median"]


def axial_difference(a: ArrayLike, b: ArrayLike) -> NDArray[np.float64]:
    """Signed difference ``a − b`` of axial angles, rad, wrapped into ``[−π/2, π/2)``."""
    d = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
    return (d + 0.5 * np.pi) % np.pi - 0.5 * np.pi


def axial_mean(angles: ArrayLike) -> float:
    """Mean axis of ``angles`` (rad, NaN ignored): half the circular mean of the doubled angle."""
    a = np.asarray(angles, dtype=float)
    a = a[np.isfinite(a)]
    if a.size == 0:
        return float("nan")
    return float(0.5 * np.arctan2(np.mean(np.sin(2 * a)), np.mean(np.cos(2 * a))))


def axial_median(angles: ArrayLike) -> float:
    """Median axis of ``angles`` (rad, NaN ignored), in ``(−π/2, π/2]``.

    The median of the deviations from the axial mean, added back to it: robust to outliers
    and free of the ±90° wrap.
    """
    a = np.asarray(angles, dtype=float)
    a = a[np.isfinite(a)]
    if a.size == 0:
        return float("nan")
    centre = axial_mean(a)
    m = centre + float(np.median(axial_difference(a, centre)))
    return float(m - np.pi if m > 0.5 * np.pi else m + np.pi if m <= -0.5 * np.pi else m)
