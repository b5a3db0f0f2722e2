"""What a Net F/T or Axia says about itself: its ``/netftapi2.xml`` page (calibration, units, rate)."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from softtip.core.units import find_unit
from softtip.io.sources import SourceError

__all__ = ["COUNTS_PER_UNIT_RANGE", "FORCE_UNITS_SI", "RDT_RATE_RANGE", "TORQUE_UNITS_SI", "DeviceInfo", "parse_device_xml"]

#: SI value (N) of one force unit, by the name the device (or pynetft) gives it: the device's
#: spellings, their sizes from softtip's unit registry (:data:`softtip.core.units.UNITS`).
FORCE_UNITS_SI = {name: find_unit(name, "force").si for name in ("N", "lbf", "klbf", "kN", "kgf")}
#: SI value (N·m) of one torque unit, by the name the device (or pynetft) gives it.
TORQUE_UNITS_SI = {
    name: find_unit(name, "moment").si for name in ("N-m", "Nm", "N-mm", "Nmm", "lbf-in", "lbf-ft", "kgf-cm", "kN-m", "kNm")
}

@dataclass(frozen=True)


class DeviceInfo:
    """What the device said about itself.

    Attributes
    ----------
    product : str
    force_unit, torque_unit : str
        Units of the calibrated data, as the device names them (``N``, ``Nmm``, ...).
    counts_per_force, counts_per_torque : float
        Counts per force / torque unit.
    rate_hz : float or None
        RDT output rate (``comrdtrate``), None when the device did not say.
    """

    product: str
    force_unit: str
    torque_unit: str
    counts_per_force: float
    counts_per_torque: float
    rate_hz: float | None


#: What a real Net F/T or Axia reports: counts per force or torque unit (ATI's calibrations use
#: 1e3–1e7 counts per unit) and RDT output rates (at most 7 kHz on a Net F/T, 7.8 kHz on an Axia);
#: values outside these ranges (a corrupted or hostile configuration page) are refused.
COUNTS_PER_UNIT_RANGE = (1.0, 1e9)
RDT_RATE_RANGE = (1.0, 1e5)


def _field(text: str, name: str) -> str | None:
    m = re.search(rf"<{name}>\s*([^<]*?)\s*</{name}>", text)
    return m.group(1) if m else None


def _number(text: str, name: str) -> float | None:
    value = _field(text, name)
    if value is None:
        return None
    m = re.match(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?", value)  # first of a list, if a list
    try:
        x = float(m.group(0)) if m else math.nan
    except ValueError:  # pragma: no cover - the pattern only matches numbers
        return None
    return x if math.isfinite(x) and x > 0 else None


def parse_device_xml(text: str, where: str = "device") -> DeviceInfo:
    """The calibration and rate in a ``netftapi2.xml`` document.

    Raises
    ------
    SourceError
        A counts-per-unit field missing or not positive, or a unit softtip does not know.
    """
    cpf, cpt = _number(text, "cfgcpf"), _number(text, "cfgcpt")
    fu, tu = _field(text, "scfgfu"), _field(text, "scfgtu")
    if cpf is None or cpt is None or fu is None or tu is None:
        raise SourceError(
            f"{where}: /netftapi2.xml lacks the calibration (cfgcpf, cfgcpt, scfgfu, scfgtu as positive "
            "numbers and unit names); expected a Net F/T or Axia"
        )
    if fu not in FORCE_UNITS_SI or tu not in TORQUE_UNITS_SI:
        raise SourceError(
            f"{where}: calibration in units {fu!r} / {tu!r}; expected force in "
            f"{', '.join(FORCE_UNITS_SI)} and torque in {', '.join(TORQUE_UNITS_SI)}"
        )
    rate = _number(text, "comrdtrate")
    checks = [("cfgcpf (counts per force unit)", cpf, COUNTS_PER_UNIT_RANGE), ("cfgcpt (counts per torque unit)", cpt, COUNTS_PER_UNIT_RANGE)]
    if rate is not None:
        checks.append(("comrdtrate (RDT output rate, Hz)", rate, RDT_RATE_RANGE))
    for setting, value, (low, high) in checks:
        if not low <= value <= high:
            raise SourceError(
                f"{where}: /netftapi2.xml reports {setting} = {value:g}, outside any Net F/T's or Axia's "
                f"range [{low:g}, {high:g}]; refusing to believe it (check the sensor's configuration page)"
            )
    return DeviceInfo(
        product=_field(text, "prodname") or "Net F/T",
        force_unit=fu,
        torque_unit=tu,
        counts_per_force=cpf,
        counts_per_torque=cpt,
        rate_hz=rate,
    )
