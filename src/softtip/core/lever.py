"""Where the force acts: a check that the log's units and the fingertip fit together.

A contact force acts at a point of the skin, so its line of action passes within the
fingertip's reach of the sensor origin: the distance of that line from the origin,
``|f × m| / |f|²`` (the moment-to-force ratio, m), is at most the distance of the farthest
skin point, ``|centre| + radius`` of the fingertip's bounding sphere (plus a few mm of
spin torque). A log in kgf and kgf·mm read as N and N·m has its moments 1000/9.80665 ≈ 102
times too large for its forces, so the force seems to act ~100 times too far away: on the
example grasp, 2.2 m from the sensor instead of 2.2 mm. :func:`check_force_lever` stops
such a run instead of returning confident wrong directions.

The opposite mistake (an SI log read as kgf-mm) puts every force ~100 times closer to the
origin; a line through the origin is a possible contact (a push along the finger's axis),
so that mistake cannot be told from the data this way.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from softtip.core.fingertip import Fingertip
from softtip.errors import InputError

__all__ = ["LEVER_MARGIN", "ForceLever", "force_lever", "check_force_lever", "lever_distances", "LeverVote", "fingertip_reach"]

#: How far beyond the fingertip's reach the median line of action may lie before the
#: log is refused (a factor on the reach; covers noise, spin torque and a fingertip a
#: little larger than the one given).
LEVER_MARGIN = 2.0


@dataclass(frozen=True)
class ForceLever:
    """Distance of the force's line of action from the sensor origin.

    Attributes
    ----------
    median : float
        Median distance over the samples used, m (NaN when none).
    n_samples : int
        Samples with ``|f|`` at least the force limit.
    reach : float
        Farthest skin point from the sensor origin, m.
    """

    median: float
    n_samples: int
    reach: float

    @property
    def plausible(self) -> bool:
        """Whether the force acts within ``LEVER_MARGIN`` times the fingertip's reach (True when undecided)."""
        return not (self.n_samples >= 5 and self.median > LEVER_MARGIN * self.reach)


def force_lever(wrench: ArrayLike, fingertip: Fingertip, *, min_force: float = 0.1) -> ForceLever:
    """Median distance of the line of action of ``f`` from the sensor origin.

    Parameters
    ----------
    wrench : array-like, shape (N, 6)
        Tared wrench, N and N·m, sensor frame.
    fingertip : Fingertip
    min_force : float
        Only samples with ``|f|`` at least this (N) count: below it the noise decides the ratio.

    Returns
    -------
    ForceLever
    """
    distance = lever_distances(wrench, min_force)
    median = float(np.median(distance)) if len(distance) else float("nan")
    return ForceLever(median, len(distance), fingertip_reach(fingertip))


def fingertip_reach(fingertip: Fingertip) -> float:
    """Farthest skin point from the sensor origin, m (of the bounding sphere)."""
    centre, radius = fingertip.bounding_sphere
    return float(np.linalg.norm(centre) + radius)


def lever_distances(wrench: ArrayLike, min_force: float = 0.1) -> np.ndarray:
    """Distance of the force's line of action from the sensor origin, m, for each sample of
    ``wrench`` (N, 6) with ``|f|`` at least ``min_force`` (N) (the ones :func:`force_lever`
    takes the median of)."""
    w = np.asarray(wrench, dtype=float).reshape(-1, 6)
    f, m = w[:, :3], w[:, 3:]
    f2 = np.einsum("ij,ij->i", f, f)
    use = np.isfinite(f2) & (f2 >= min_force**2) & np.all(np.isfinite(m), axis=1)
    return np.linalg.norm(np.cross(f[use], m[use]), axis=1) / f2[use]


class LeverVote:
    """Whether the median of :func:`lever_distances` over a log given in pieces exceeds a
    limit, decided exactly as ``np.median(all) > limit`` without keeping the distances:
    counts above the limit, and the nearest distance on each side of it."""

    def __init__(self, limit: float) -> None:
        self.limit, self.n, self.above = limit, 0, 0
        self.below_max, self.above_min = -np.inf, np.inf

    def add(self, distance: np.ndarray) -> None:
        """Count a piece's distances."""
        up = distance > self.limit
        self.n += len(distance)
        self.above += int(np.count_nonzero(up))
        if up.any():
            self.above_min = min(self.above_min, float(distance[up].min()))
        if not up.all():
            self.below_max = max(self.below_max, float(distance[~up].max()))

    def median_above(self) -> bool:
        """``np.median(all distances) > limit`` (False without any)."""
        n, k = self.n, self.above
        if n == 0:
            return False
        if n % 2:
            return k >= (n + 1) // 2
        if k != n // 2:
            return k > n // 2
        return (self.below_max + self.above_min) / 2 > self.limit  # the two middle values straddle the limit


def check_force_lever(
    wrench: ArrayLike, fingertip: Fingertip, *, units: str, source: str = "", min_force: float = 0.1
) -> ForceLever:
    """:func:`force_lever`, raising when the force acts far outside the fingertip.

    Parameters
    ----------
    wrench, fingertip, min_force
        As :func:`force_lever`.
    units : str
        The units the log was read in (``"si"`` or ``"kgf-mm"``), for the message.
    source : str
        The log's name, for the message.

    Raises
    ------
    InputError
        The median line of action lies more than ``LEVER_MARGIN`` times the fingertip's
        reach from the sensor origin; the message suggests ``--units`` (and ``--tip``).
    """
    lever = force_lever(wrench, fingertip, min_force=min_force)
    if not lever.plausible:
        where = f"{source}: " if source else ""
        hint = (
            "is the log in kgf and kgf·mm? Then give --units kgf-mm"
            if units == "si"
            else "are the wrench columns really in kgf and kgf·mm (--units kgf-mm)?"
        )
        raise InputError(
            f"{where}the forces act {lever.median * 1e3:.4g} mm from the sensor origin (median of the moment-to-force "
            f"ratio over {lever.n_samples} samples with |f| ≥ {min_force:g} N), but the fingertip reaches only "
            f"{lever.reach * 1e3:.3g} mm: {hint}; or is the fingertip (--tip) the wrong one? Expected moments in N·m "
            "about the sensor origin"
        )
    return lever
