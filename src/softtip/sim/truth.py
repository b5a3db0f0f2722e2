"""Ground truth of a simulated grasp and the angle convention of the manual (§3.4)."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.core.spin import direction_angle, tangent_frame

__all__ = ["GroundTruth", "tangent_frame", "line_angle"]


def line_angle(direction: ArrayLike, normal: ArrayLike) -> NDArray[np.float64]:
    """Angle (rad) of the axis ``direction`` (..., 3) in the tangent frame of the manual (§3.4) at
    ``normal`` (..., 3): the estimator's own convention (:func:`softtip.core.spin.direction_angle`)."""
    return direction_angle(direction, normal)


@dataclass(frozen=True, eq=False)
class GroundTruth:
    """Per-sample truth of a simulated grasp (sensor frame, SI).

    Attributes
    ----------
    direction : (N, 3)
        Unit line direction of the object (edge, axis, fringe tangent) at the nominal
        contact point; NaN for a plane. An axis (sign is arbitrary).
    angle : (N,)
        Its angle (rad) in the tangent frame of the manual (§3.4) at the nominal contact normal,
        in ``(-π/2, π/2]``.
    contact_point : (N, 3)
        Nominal contact point: where the push axis meets the undeformed skin, m.
    contact_normal : (N, 3)
        Skin outward normal there.
    pressure_centre : (N, 3)
        Pressure-weighted mean of the compressed skin points (undeformed positions), m;
        NaN when not in contact.
    contact_area : (N,)
        Compressed skin area, m².
    depth : (N,)
        Largest compression, m.
    push : (N,)
        Object travel along the push axis from first touch, m (negative before contact).
    normal_force : (N,)
        True force along the push axis (into the fingertip), N.
    force_target : (N,)
        The grasp-force profile the push was solved for, N.
    in_contact : (N,) bool
        Whether any skin point is compressed.
    slip_fraction : (N,)
        Fraction of the contact area at the Coulomb limit.
    friction_depth : (N,)
        Depth below the undeformed skin at which the tangential (friction) tractions act,
        m: their compressions weighted by their part along the total tangential force,
        ``F_t · Σ δ_i F_t,i / |F_t|²`` (the lever of ``F_t`` about the surface point);
        NaN without contact or when ``|F_t|`` is below 1 % of the normal force.
    """

    direction: NDArray[np.float64]
    angle: NDArray[np.float64]
    contact_point: NDArray[np.float64]
    contact_normal: NDArray[np.float64]
    pressure_centre: NDArray[np.float64]
    contact_area: NDArray[np.float64]
    depth: NDArray[np.float64]
    push: NDArray[np.float64]
    normal_force: NDArray[np.float64]
    force_target: NDArray[np.float64]
    in_contact: NDArray[np.bool_]
    slip_fraction: NDArray[np.float64]
    friction_depth: NDArray[np.float64] | None = None

    def __post_init__(self) -> None:
        if self.friction_depth is None:
            object.__setattr__(self, "friction_depth", np.full(len(self.angle), np.nan))
        for f in fields(self):
            a = np.ascontiguousarray(getattr(self, f.name))
            a.setflags(write=False)
            object.__setattr__(self, f.name, a)

    @property
    def angle_deg(self) -> NDArray[np.float64]:
        """:attr:`angle` in degrees."""
        return np.degrees(self.angle)

    def as_dict(self) -> dict:
        """JSON-ready columns (NaN → None), keyed with their units."""
        units = {
            "direction": "unit",
            "angle": "deg",
            "contact_point": "m",
            "contact_normal": "unit",
            "pressure_centre": "m",
            "contact_area": "m2",
            "depth": "m",
            "push": "m",
            "normal_force": "N",
            "force_target": "N",
            "in_contact": "bool",
            "slip_fraction": "1",
            "friction_depth": "m",
        }
        out = {}
        for f in fields(self):
            a = self.angle_deg if f.name == "angle" else getattr(self, f.name)
            key = f"{f.name}_{units[f.name]}" if units[f.name] not in ("bool", "unit", "1") else f.name
            out[key] = _jsonable(a)
        return out


def _jsonable(a: NDArray) -> list:
    """Nested lists with NaN/inf replaced by None (JSON has no NaN)."""

    def fix(v):
        if isinstance(v, list):
            return [fix(x) for x in v]
        return None if (isinstance(v, float) and not math.isfinite(v)) else v

    return fix(np.asarray(a).tolist())
