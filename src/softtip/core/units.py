"""Unit conversions at the I/O boundary.

Everything inside softtip is SI (N, N·m, m, s, rad). The papers report force in kgf and
moment in kgf·mm; these helpers convert a wrench array of shape ``(..., 6)`` between the two.
"""

from __future__ import annotations

import math
import re

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


#: Length units accepted by :func:`parse_length`, in metres.
LENGTH_UNITS = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "µm": 1e-6}
#: Force units accepted by :func:`parse_force`, in newtons.
FORCE_UNITS = {"n": 1.0, "kgf": KGF}
_QUANTITY = re.compile(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([a-zA-Zµ]*)\s*")


def parse_quantity(text: str, units: dict[str, float], what: str, bare: str) -> tuple[float, bool]:
    """A number with an optional unit in SI, and whether the unit was given.

    Parameters
    ----------
    text : str
        ``"2mm"``, ``"0.5 cm"``, ``"40e-3"``.
    units : dict
        Accepted unit names (lower case) and their size in SI.
    what : str
        ``"length"``, ``"force"``: named in the error.
    bare : str
        Unit of a number given without one (a key of ``units``).

    Raises
    ------
    ValueError
        Not a number with one of ``units``, or not finite.
    """
    m = _QUANTITY.fullmatch(str(text))
    unit = m.group(2).lower() if m else ""
    if not m or (unit and unit not in units):
        raise ValueError(f"{text!r} is not a {what} (a number with an optional unit: {', '.join(units)})")
    value = float(m.group(1)) * units[unit or bare]
    if not math.isfinite(value):
        raise ValueError(f"{text!r} is not a finite {what}")
    return value, bool(unit)


def parse_length(text: str, bare: str = "m") -> float:
    """``"2mm"`` → 0.002 (m). A bare number is in ``bare`` (metres unless told)."""
    return parse_quantity(text, LENGTH_UNITS, "length", bare)[0]


def parse_force(text: str, bare: str = "n") -> float:
    """``"0.5kgf"`` → 4.903325 (N). A bare number is in ``bare`` (newtons unless told)."""
    return parse_quantity(text, FORCE_UNITS, "force", bare)[0]
