"""The full-scale range of a six-axis F/T sensor: what a reading can plausibly be.

A wrench beyond the sensor's calibrated range is not a measurement: the gauges saturate,
and a value such as ``fz = 1e30`` is a corrupted row, not a contact. :func:`check_full_scale`
refuses (with the sample, its time and the axis) a log holding one, before any estimate is
made. The bound is the sensor's rated range per axis (ATI's calibrations; ``fx``/``fy`` and
``fz`` differ), preset per sensor in :data:`SENSOR_RANGES`, or given as numbers
(:func:`parse_full_scale`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from softtip.errors import InputError

__all__ = ["FullScale", "SENSOR_RANGES", "DEFAULT_SENSOR", "ANY_SENSOR", "COARSE_MARGIN", "parse_full_scale", "check_full_scale", "full_scale_error"]

_AXES = ("fx", "fy", "fz", "mx", "my", "mz")


@dataclass(frozen=True)
class FullScale:
    """Rated range of each axis: ``|f_x|, |f_y| ≤ force_xy``, ``|f_z| ≤ force_z`` (N), ``|m_i| ≤ moment`` (N·m).

    Parameters
    ----------
    force_xy, force_z : float
        N.
    moment : float
        N·m.
    name : str
        How the range was given (a preset's name, or the numbers), for messages.
    """

    force_xy: float
    force_z: float
    moment: float
    name: str = ""

    def __post_init__(self) -> None:
        for what in ("force_xy", "force_z", "moment"):
            v = getattr(self, what)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ValueError(f"{what} must be a positive finite number, got {v!r}")

    @property
    def bounds(self) -> np.ndarray:
        """(6,) bound per axis, N and N·m."""
        return np.array([self.force_xy, self.force_xy, self.force_z, self.moment, self.moment, self.moment])


#: Rated ranges of common ATI sensors (calibrations SI-50-0.5, SI-250-6, SI-80-4, SI-580-20,
#: SI-130-10, Axia80 M20), N and N·m.
SENSOR_RANGES: dict[str, FullScale] = {
    "nano17": FullScale(50.0, 70.0, 0.5, "nano17"),
    "nano25": FullScale(250.0, 1000.0, 6.0, "nano25"),
    "mini40": FullScale(80.0, 240.0, 4.0, "mini40"),
    "mini45": FullScale(580.0, 1160.0, 20.0, "mini45"),
    "gamma": FullScale(130.0, 400.0, 10.0, "gamma"),
    "axia80": FullScale(500.0, 900.0, 20.0, "axia80"),
}

#: ``--full-scale off``: no sensor's range, but still no value no sensor can give (which
#: would also overflow the computations: squares of 1e154 and more).
ANY_SENSOR = FullScale(1e9, 1e9, 1e9, "off, i.e. any sensor's")

#: The sensor softtip's defaults are set for (its noise model is a Nano17's).
DEFAULT_SENSOR = "nano17"


def parse_full_scale(text: str) -> FullScale | None:
    """A range as the ``--full-scale`` option takes it.

    Parameters
    ----------
    text : str
        A preset (:data:`SENSOR_RANGES`), ``FORCE,MOMENT`` (N and N·m, the force bound for
        every force axis), or ``off`` (no bound).

    Returns
    -------
    FullScale
        :data:`ANY_SENSOR` for ``off``.

    Raises
    ------
    ValueError
        Anything else, saying what is expected.
    """
    key = text.strip().lower()
    if key == "off":
        return ANY_SENSOR
    if key in SENSOR_RANGES:
        return SENSOR_RANGES[key]
    parts = key.split(",")
    expected = f"expected a sensor ({', '.join(SENSOR_RANGES)}), FORCE,MOMENT in N and N·m (e.g. 100,2), or off"
    if len(parts) != 2:
        raise ValueError(f"{text!r}: {expected}")
    try:
        force, moment = (float(p) for p in parts)
    except ValueError:
        raise ValueError(f"{text!r}: {expected}") from None
    if not all(math.isfinite(v) and 0 < v <= 1e9 for v in (force, moment)):
        raise ValueError(f"{text!r}: {expected}, both positive, finite and at most 1e9")
    return FullScale(force, force, moment, f"{force:g},{moment:g}")


#: ``margin`` of the check made before any estimate: values this far beyond the range are refused
#: at once (a corrupted row, an overflow to come); those just beyond it after the units check,
#: which names a wrong unit better.
COARSE_MARGIN = 1000.0


def check_full_scale(
    t: ArrayLike, wrench: ArrayLike, full_scale: FullScale | None, source: str, *, first_sample: int = 0,
    option: str = "--full-scale", units: str | None = None, margin: float = 1.0,
) -> None:
    """Raise :func:`full_scale_error`'s error, if any (same parameters)."""
    err = full_scale_error(
        t, wrench, full_scale, source, first_sample=first_sample, option=option, units=units, margin=margin
    )
    if err is not None:
        raise err


def full_scale_error(
    t: ArrayLike, wrench: ArrayLike, full_scale: FullScale | None, source: str, *, first_sample: int = 0,
    option: str = "--full-scale", units: str | None = None, margin: float = 1.0,
) -> InputError | None:
    """The error for a wrench outside the sensor's range (exit 2 on the command line), or None.

    Parameters
    ----------
    t : array-like, shape (N,)
        s, for the message.
    wrench : array-like, shape (N, 6)
        N and N·m (SI), sensor frame, as read (before any tare).
    full_scale : FullScale or None
        None: nothing is checked.
    source : str
        The log's name, for the message.
    first_sample : int
        Index of ``wrench[0]`` in the whole log (a piece of a log read in pieces).
    option : str
        The option that sets the range, named in the message.
    units : str, optional
        The units the log was read in: for ``"si"``, a log that would fit the range in
        kgf and kgf·mm is pointed to ``--units kgf-mm``.
    margin : float
        Only values beyond ``margin`` times the range count (:data:`COARSE_MARGIN`).

    Returns
    -------
    InputError or None
        Naming the first sample beyond the range: its number (1-based), time, axis and value.
    """
    if full_scale is None:
        return None
    w = np.asarray(wrench, dtype=float)
    if not len(w):
        return None
    over = np.abs(w) > full_scale.bounds * margin
    rows = np.flatnonzero(over.any(axis=1))
    if not len(rows):
        return None
    i = int(rows[0])
    j = int(np.flatnonzero(over[i])[0])
    unit = "N" if j < 3 else "N·m"
    bound = full_scale.bounds[j]
    more = f" (and {len(rows) - 1} more sample(s))" if len(rows) > 1 else ""
    if units == "si":
        from softtip.core.units import KGF

        # |w| · scale > bound as |w| > bound / scale: no overflow near the float range
        kgf = not np.any(np.abs(w) > full_scale.bounds / np.array([KGF] * 3 + [KGF * 1e-3] * 3))
        # the forces in N and the moments in N·mm (a common export); whatever fits in kgf and
        # kgf·mm fits so too, and range alone cannot tell the two apart: both are named then
        nmm = not np.any(np.abs(w) > full_scale.bounds / np.array([1.0] * 3 + [1e-3] * 3))
        if nmm:
            fix = (
                "every sample fits it in kgf and kgf·mm, and with the moments in N·mm: wrong units? Give --units "
                "kgf-mm, or --moment-units 'N*mm' for a log in N and N·mm"
                if kgf else "every sample fits it with the moments in N·mm: wrong units? Give --moment-units 'N*mm'"
            )
            return InputError(
                f"{source}: sample {first_sample + i + 1} (t = {float(np.asarray(t)[i]):g} s): {_AXES[j]} = {w[i, j]:g} "
                f"{unit} is beyond the sensor's full-scale range (±{bound:g} {unit}, {option} {full_scale.name}){more}, "
                f"but {fix}"
            )
    return InputError(
        f"{source}: sample {first_sample + i + 1} (t = {float(np.asarray(t)[i]):g} s): {_AXES[j]} = {w[i, j]:g} {unit} "
        f"is beyond the sensor's full-scale range (±{bound:g} {unit}, {option} {full_scale.name}){more}; expected a "
        f"wrench the sensor can measure (a corrupted row?). For a larger sensor give {option} with its name "
        f"({', '.join(SENSOR_RANGES)}) or FORCE,MOMENT; {option} off allows any sensor's"
    )
