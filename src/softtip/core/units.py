"""Unit conversions at the I/O boundary.

Everything inside softtip is SI (N, N·m, m, s, rad). The papers report force in kgf and
moment in kgf·mm; these helpers convert a wrench array of shape ``(..., 6)`` between the two.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Standard gravity, m/s². One kilogram-force is this many newtons.
STANDARD_GRAVITY = 9.80665
#: One kgf in N.
KGF = STANDARD_GRAVITY
#: One kgf·mm in N·m.
KGF_MM = STANDARD_GRAVITY * 1e-3

UNIT_SYSTEMS = ("si", "kgf-mm")

_SCALE = {
    "si": np.array([1.0, 1.0, 1.0, 1.0, 1.0, 1.0]),
    "kgf-mm": np.array([KGF, KGF, KGF, KGF_MM, KGF_MM, KGF_MM]),
}


def _scale(units: str) -> NDArray[np.float64]:
    try:
        return _SCALE[units]
    except KeyError:
        raise ValueError(f"unknown units {units!r}; expected one of {', '.join(UNIT_SYSTEMS)}") from None


def wrench_to_si(wrench: ArrayLike, units: str) -> NDArray[np.float64]:
    """Convert a wrench from ``units`` to SI.

    Parameters
    ----------
    wrench : array-like, shape (..., 6)
        ``fx, fy, fz, mx, my, mz`` in ``units``.
    units : {"si", "kgf-mm"}
        ``"kgf-mm"``: force in kgf, moment in kgf·mm (the papers' units).

    Returns
    -------
    array, shape (..., 6)
        Force in N, moment in N·m.
    """
    return np.asarray(wrench, dtype=float) * _scale(units)


def wrench_from_si(wrench: ArrayLike, units: str) -> NDArray[np.float64]:
    """Convert an SI wrench, shape ``(..., 6)``, to ``units`` (inverse of :func:`wrench_to_si`)."""
    return np.asarray(wrench, dtype=float) / _scale(units)
