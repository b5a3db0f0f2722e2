"""Option value types of the ``softtip`` command: every number range-checked, with its unit.

A bad value exits 2 with click's ``Invalid value for '--OPTION'`` followed by what was
expected, unit included (``expected a number > 0 s``); NaN and infinity are refused
everywhere unless an option says otherwise. Every length option takes a unit (``3mm``,
``0.5cm``, ``2e-3m``; :class:`Length`), every force option ``N`` or ``kgf`` (:class:`Force`).
"""

from __future__ import annotations

import math

import click
import numpy as np

from softtip.core.units import FORCE_UNITS, LENGTH_UNITS, parse_quantity

__all__ = [
    "Number", "Scaled", "Length", "Force", "UnitName", "ColumnSpec", "Option", "option", "as_written", "PORT", "check_lowpass",
    "check_pair_increasing",
]

#: Lowest low-pass cutoff as a fraction of the Nyquist frequency: below it the Butterworth
#: sections lose their precision (the filter's initial state and its noise gain go wrong,
#: then the design itself fails with "Singular matrix").
MIN_LOWPASS_FRACTION = 1e-4

#: Largest magnitude any number option takes (in SI) when it names no bound of its own:
#: beyond every physical quantity softtip works with, and far enough from the float range
#: that squares and products of it stay finite (no overflow, no numpy RuntimeWarning).
MAX_MAGNITUDE = 1e15


class Number(click.ParamType):
    """A finite float in a range, reported with its unit.

    Parameters
    ----------
    unit : str
        Printed after the bounds (``"s"``, ``"N"``, ``"Hz"``, ``"deg"``; ``""`` for none).
    min, max : float, optional
        Bounds.
    min_open, max_open : bool
        Whether the bound itself is excluded.
    """

    name = "NUMBER"

    def __init__(
        self, unit: str = "", min: float | None = None, max: float | None = None, *, min_open: bool = False, max_open: bool = False
    ) -> None:
        self.unit, self.min, self.max, self.min_open, self.max_open = unit, min, max, min_open, max_open

    def expected(self) -> str:
        """What the option accepts, e.g. ``"a number in (0, 86400] s"``."""
        unit = f" {self.unit}" if self.unit else ""
        if self.min is not None and self.max is not None:
            lb, rb = "(" if self.min_open else "[", ")" if self.max_open else "]"
            return f"a number in {lb}{self.min:g}, {self.max:g}{rb}{unit}"
        if self.min is not None:
            return f"a number {'>' if self.min_open else '≥'} {self.min:g}{unit}"
        if self.max is not None:
            return f"a number {'<' if self.max_open else '≤'} {self.max:g}{unit}"
        return f"a finite number{unit}"

    def convert(self, value, param, ctx):
        if isinstance(value, float) and math.isfinite(value) and self._inside(value):
            return value
        try:
            v = float(value)
        except (TypeError, ValueError):
            self.fail(f"{value!r} is not a number; expected {self.expected()}", param, ctx)
        if not math.isfinite(v):
            self.fail(f"{value!r} is not a finite number; expected {self.expected()}", param, ctx)
        if not self._inside(v):
            self.fail(f"{value!r}; expected {self.expected()}", param, ctx)
        if abs(v) > MAX_MAGNITUDE:
            self.fail(f"{value!r} is beyond any plausible value; expected {self.expected()} of at most {MAX_MAGNITUDE:g}", param, ctx)
        return v

    def _inside(self, v: float) -> bool:
        if self.min is not None and (v < self.min or (self.min_open and v == self.min)):
            return False
        if self.max is not None and (v > self.max or (self.max_open and v == self.max)):
            return False
        return True

    def __repr__(self) -> str:
        return f"Number({self.expected()!r})"


class Scaled(Number):
    """A number typed in one unit and converted to SI by a factor: degrees to rad
    (``scale = π/180``), N·mm to N·m (``1e-3``). Bounds and messages in the typed unit; a
    default given as a float is taken as already in SI."""

    def __init__(self, unit: str, scale: float, min: float | None = None, max: float | None = None, *,
                 min_open: bool = False, max_open: bool = False) -> None:  # fmt: skip
        super().__init__(unit, min, max, min_open=min_open, max_open=max_open)
        self.scale = scale

    def convert(self, value, param, ctx):
        if isinstance(value, float) and math.isfinite(value):
            return value  # a default, in SI
        return super().convert(value, param, ctx) * self.scale


class _Quantity(Number):
    """A number with an optional unit suffix, converted to SI; range-checked in SI."""

    units: dict[str, float] = {}
    what = ""

    def __init__(self, bare: str, min: float | None = None, max: float | None = None, *, min_open: bool = False,
                 max_open: bool = False, bare_max: float | None = None) -> None:  # fmt: skip
        super().__init__("", min, max, min_open=min_open, max_open=max_open)
        self.bare, self.bare_max = bare, bare_max

    def expected(self) -> str:
        scale = self.units[self.bare]
        unit = "N" if self.bare == "n" else self.bare
        lo = None if self.min is None else self.min / scale
        hi = None if self.max is None else self.max / scale
        bound = Number(unit, lo, hi, min_open=self.min_open, max_open=self.max_open).expected()
        return bound.replace("a number", f"a {self.what}").replace("a finite number", f"a {self.what}") + (
            f" (a unit may follow: {', '.join(self.units)}; a bare number is in {unit})"
        )

    def convert(self, value, param, ctx):
        if isinstance(value, float) and math.isfinite(value) and self._inside(value):
            return value  # already converted (a default given as a number, in SI)
        try:
            v, with_unit = parse_quantity(value, self.units, self.what, self.bare)
        except ValueError as exc:
            self.fail(f"{exc}; expected {self.expected()}", param, ctx)
        if self.bare_max is not None and not with_unit and abs(v) >= self.bare_max:
            # "--size 2" would be a 2 m object, surely meant in mm
            self.fail(f"{value!r} is {v:g} {self.bare}; give a unit, e.g. '{value}mm'", param, ctx)
        if not self._inside(v):
            self.fail(f"{value!r}; expected {self.expected()}", param, ctx)
        if abs(v) > MAX_MAGNITUDE:
            self.fail(f"{value!r} is beyond any plausible value; expected {self.expected()} of at most {MAX_MAGNITUDE:g} in SI", param, ctx)
        return v


class Length(_Quantity):
    """A length option: ``3mm``, ``0.5 cm``, ``2e-3m``; converted to metres.

    Parameters
    ----------
    bare : str
        Unit of a number given without one (``"mm"`` for the estimator's options, ``"m"`` for
        ``simulate``'s), as the option's help says.
    min, max : float, optional
        Bounds in metres.
    bare_max : float, optional
        A bare number this large or larger (metres) is refused as ambiguous: give a unit.
    """

    name = "LENGTH"
    units = LENGTH_UNITS
    what = "length"


class Force(_Quantity):
    """A force option: ``0.5kgf``, ``2N``, ``2``; converted to newtons (bounds in N)."""

    name = "FORCE"
    units = FORCE_UNITS
    what = "force"

    def __init__(self, min: float | None = None, max: float | None = None, *, min_open: bool = False,
                 max_open: bool = False) -> None:  # fmt: skip
        super().__init__("n", min, max, min_open=min_open, max_open=max_open)


def as_written(value) -> str:
    """A default as a user types it: ``0.03`` (not ``0.030000000000000002``), ``1`` for 1.0, pairs space-separated."""
    if isinstance(value, (list, tuple)):
        return " ".join(as_written(v) for v in value)
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


class Option(click.Option):
    """A :class:`click.Option` whose help shows the default as a user would type it.

    Numbers print in the shortest form (:func:`as_written`), pairs space-separated as on the
    command line, and a ``show_default`` text without parentheses.
    """

    def get_help_extra(self, ctx: click.Context):
        extra = super().get_help_extra(ctx)
        if "default" in extra:
            if isinstance(self.show_default, str):
                extra["default"] = self.show_default
            elif not self.is_flag and not callable(self.default):
                extra["default"] = as_written(self.default)  # as declared: "0.2kgf", not its value in N
        return extra


class UnitName(click.ParamType):
    """A unit of ``quantity`` (force, moment, time) from :data:`softtip.core.units.UNITS`, any registered
    spelling (``N*mm``, ``N-mm``, ``Nmm``, ``N·mm``); converted to its canonical name."""

    name = "UNIT"

    def __init__(self, quantity: str) -> None:
        self.quantity = quantity

    def get_metavar(self, param, ctx=None) -> str:  # noqa: ARG002 - click's signature
        from softtip.core.units import unit_names

        return "|".join(unit_names(self.quantity))

    def convert(self, value, param, ctx):
        from softtip.core.units import find_unit, unit_names

        unit = find_unit(str(value), self.quantity)
        if unit is None:
            self.fail(f"{value!r}; expected a {self.quantity} unit: {', '.join(unit_names(self.quantity))}", param, ctx)
        return unit.name


class ColumnSpec(click.ParamType):
    """``ROLE=COLUMN,…``: which header column (or 1-based position) is ``t``, ``fx`` … ``mz``."""

    name = "ROLE=COLUMN,…"

    def convert(self, value, param, ctx):
        from softtip.io.formats import parse_column_spec

        if isinstance(value, dict):
            return value
        try:
            return parse_column_spec(str(value))
        except ValueError as exc:
            self.fail(f"{exc}; expected e.g. t=Time,fx=Fx,fy=Fy,fz=Fz,mx=Tx,my=Ty,mz=Tz", param, ctx)


def option(*param_decls: str, **attrs):
    """:func:`click.option` with :class:`Option`: every ``softtip`` option is declared through this."""
    return click.option(*param_decls, cls=Option, **attrs)


def dash_is_stdout(ctx, param, value):
    """An ``-o`` option's callback: ``-`` is standard output (None, the option's default), as
    for ``softtip estimate``, not a file named ``-``."""
    return None if value is not None and str(value) == "-" else value


#: A TCP/UDP port.
PORT = click.IntRange(1, 65535)


def check_pair_increasing(option: str, pair: tuple[float, float], unit: str) -> None:
    """``LOW HIGH`` with LOW < HIGH, or a :class:`click.BadParameter` naming the option."""
    low, high = pair
    if not low < high:
        raise click.BadParameter(f"{low:g} {high:g}; expected LOW < HIGH, {unit}", param_hint=f"'{option}'")


def check_lowpass(cutoff_hz: float | None, t_or_rate, option: str = "--lowpass-hz") -> None:
    """A low-pass cutoff between ``MIN_LOWPASS_FRACTION`` of the Nyquist frequency and the Nyquist frequency.

    Parameters
    ----------
    cutoff_hz : float or None
        The option's value, Hz (``None``: no filter, nothing to check).
    t_or_rate : array-like of sample times (s) or a sample rate (Hz)
    """
    if cutoff_hz is None:
        return
    if np.ndim(t_or_rate) == 0:
        rate = float(t_or_rate)
    else:
        dt = np.diff(np.asarray(t_or_rate, dtype=float))
        dt = dt[dt > 0]
        if not len(dt):
            return  # one sample, or no time step: the estimator says what is wrong
        rate = 1.0 / float(np.median(dt))
    nyquist = 0.5 * rate
    low = MIN_LOWPASS_FRACTION * nyquist
    if not (low <= cutoff_hz < nyquist):
        raise click.BadParameter(
            f"{cutoff_hz:g} Hz; expected a cutoff in [{low:.3g}, {nyquist:g}) Hz for this sample rate ({rate:g} Hz): "
            f"at most the Nyquist frequency, at least {MIN_LOWPASS_FRACTION:g} of it (lower cutoffs are not "
            "computed accurately)",
            param_hint=f"'{option}'",
        )
