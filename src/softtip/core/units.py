"""Unit conversions at the I/O boundary.

Everything inside softtip is SI (N, N·m, m, s, rad). The papers report force in kgf and
moment in kgf·mm; these helpers convert a wrench array of shape ``(..., 6)`` between the two.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

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


# --------------------------------------------------------------------------------------
# Units of an input log's columns: one registry for force, moment and time.


@dataclass(frozen=True)
class Unit:
    """A unit an input log's column may be in.

    Attributes
    ----------
    name : str
        The spelling options take and messages print (``"N*mm"``).
    quantity : {"force", "moment", "time"}
    si : float
        Its size in SI: N, N·m or s.
    label : str
        How it reads in prose (``"N·mm"``).
    aliases : tuple of str
        Other spellings, compared after :func:`_unit_key` (``"N-mm"``, ``"Nmm"``, ``"N.mm"``).
    """

    name: str
    quantity: str
    si: float
    label: str
    aliases: tuple[str, ...] = ()


#: lbf in N, and one inch and one foot in m (exact by definition).
LBF = 4.4482216152605
INCH = 0.0254
FOOT = 0.3048

#: Every unit a log's column may be in, each declared once.
UNITS: tuple[Unit, ...] = (
    Unit("N", "force", 1.0, "N", ("newton", "newtons")),
    # a force "in kg" or "in g" (ATI's F/T software offers Kilogram and Gram) is kilogram-force
    Unit("kgf", "force", KGF, "kgf", ("kg-f", "kilogram-force", "kp", "kg", "kilogram")),
    Unit("gf", "force", KGF * 1e-3, "gf", ("g", "gram", "gram-force")),
    Unit("kN", "force", 1e3, "kN", ("kilonewton",)),
    Unit("lbf", "force", LBF, "lbf", ("lb", "lbs", "pound-force", "pound")),
    Unit("klbf", "force", LBF * 1e3, "klbf", ("klb", "kip", "kilopound")),
    Unit("N*m", "moment", 1.0, "N·m", ("Nm", "newton-metre", "newton-meter")),
    Unit("N*mm", "moment", 1e-3, "N·mm", ("Nmm", "mN*m", "mNm", "newton-millimeter", "newton-millimetre")),
    Unit("kN*m", "moment", 1e3, "kN·m", ("kNm", "kilonewton-meter", "kilonewton-metre")),
    Unit("kgf*mm", "moment", KGF_MM, "kgf·mm", ("kgfmm",)),
    Unit("kgf*cm", "moment", KGF * 1e-2, "kgf·cm", ("kgfcm", "kg*cm", "kgcm", "kilogram-centimeter", "kilogram-centimetre")),
    Unit("lbf*in", "moment", LBF * INCH, "lbf·in", ("lbfin", "lb*in", "lbin", "in*lb", "in*lbf", "inlb", "inlbf", "pound-inch")),
    Unit("lbf*ft", "moment", LBF * FOOT, "lbf·ft", ("lbfft", "lb*ft", "lbft", "ft*lb", "ft*lbf", "ftlb", "pound-foot")),
    Unit("s", "time", 1.0, "s", ("sec", "secs", "second", "seconds")),
    Unit("ms", "time", 1e-3, "ms", ("msec", "millisecond", "milliseconds")),
    Unit("us", "time", 1e-6, "µs", ("µs", "μs", "usec", "microsecond", "microseconds")),
    Unit("ns", "time", 1e-9, "ns", ("nsec", "nanosecond", "nanoseconds")),
)

#: The ``--units`` presets: force and moment unit of each unit system.
UNIT_SYSTEM_UNITS = {"si": ("N", "N*m"), "kgf-mm": ("kgf", "kgf*mm")}


def _unit_key(text: str) -> str:
    """A unit's spelling reduced for comparison: lower case, ``·``/``-``/``.``/space as ``*``."""
    key = text.strip().lower().replace("μ", "µ")
    key = re.sub(r"\s*[·⋅\-.*×\s]\s*", "*", key)
    return key


def _unit_table() -> dict[tuple[str, str], Unit]:
    table: dict[tuple[str, str], Unit] = {}
    for unit in UNITS:
        for spelling in (unit.name, unit.label, *unit.aliases):
            table[(unit.quantity, _unit_key(spelling))] = unit
    return table


_UNIT_TABLE = _unit_table()


def unit_names(quantity: str) -> list[str]:
    """The names of the units of ``quantity`` (``"force"``, ``"moment"``, ``"time"``)."""
    return [u.name for u in UNITS if u.quantity == quantity]


def find_unit(text: str, quantity: str) -> Unit | None:
    """The unit of ``quantity`` spelled ``text`` (any registered spelling, any case,
    ``·``/``-``/``.``/``*``/space or nothing between its parts), or None."""
    key = _unit_key(text)
    unit = _UNIT_TABLE.get((quantity, key))
    if unit is None:
        flat = key.replace("*", "")
        unit = next((u for (q, k), u in _UNIT_TABLE.items() if q == quantity and k.replace("*", "") == flat), None)
    return unit


def get_unit(text: str, quantity: str) -> Unit:
    """:func:`find_unit`, raising ``ValueError`` naming the accepted spellings."""
    unit = find_unit(text, quantity)
    if unit is None:
        raise ValueError(f"unknown {quantity} unit {text!r}; expected one of: {', '.join(unit_names(quantity))}")
    return unit


def wrench_scale(force_unit: str, moment_unit: str) -> NDArray[np.float64]:
    """Factors taking ``fx, fy, fz, mx, my, mz`` in these units to N and N·m, shape (6,)."""
    f, m = get_unit(force_unit, "force").si, get_unit(moment_unit, "moment").si
    return np.array([f, f, f, m, m, m])


def seconds_from_ns(stamps_ns: ArrayLike, origin_ns: int | None = None) -> NDArray[np.float64]:
    """Integer stamps, ns, as seconds from ``origin_ns`` (default: the first stamp).

    ``(stamps - origin) / 1e9``: the division by an exact 1e9 is correctly rounded, so a stamp
    3.9 s after the origin gives the float ``3.9`` exactly as the text ``"3.9"`` does; a bag, a
    ``rostopic echo -p`` CSV of it and a CSV of its seconds give the same ``t`` to the last bit.
    """
    ns = np.asarray(stamps_ns, dtype=np.int64)
    if origin_ns is None:
        origin_ns = int(ns[0]) if len(ns) else 0
    return (ns - np.int64(origin_ns)).astype(np.float64) / 1e9


#: Hz: a force/torque log is sampled at this rate or more, and at most this (ATI's Net F/T
#: streams 7 kHz; DAQ systems some tens of kHz); outside, its t is not in seconds.
PLAUSIBLE_RATE_HZ = (2.0, 100e3)
