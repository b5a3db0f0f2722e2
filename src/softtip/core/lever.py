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
so that mistake cannot be told from the lever. The sensor's noise tells it:
:func:`check_wrench_units` also compares the noise while taring with the sensor's
(:class:`~softtip.core.noise.SensorNoise`), and stops a run whose units put that noise 5 or
more times off when one of the unit pairs F/T software writes (:data:`UNIT_PAIRS`) puts
both the lever and the noise right. Either message names the pairs that fit the data.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from softtip.core.fingertip import Fingertip, load_fingertip
from softtip.core.noise import MAD_TO_STD, SensorNoise
from softtip.core.units import find_unit
from softtip.errors import InputError

__all__ = [
    "LEVER_MARGIN", "UNIT_PAIRS", "ForceLever", "force_lever", "check_force_lever", "check_wrench_units", "lever_distances",
    "LeverVote", "fingertip_reach", "noise_ratio", "pair_scales", "pairs_that_fit", "describe_pairs",
]

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


#: The (force, moment) unit pairs force/torque software writes: the candidates a units message names.
UNIT_PAIRS: tuple[tuple[str, str], ...] = (("N", "N*m"), ("N", "N*mm"), ("kgf", "kgf*mm"), ("lbf", "lbf*in"))
#: The noise read in the given units may be this many times off the sensor's before another unit pair is looked for.
NOISE_OFF = 5.0
#: ... and a unit pair fits when it puts the noise within this factor of the sensor's.
NOISE_FITS = 3.0


def noise_ratio(quiet: ArrayLike, noise: SensorNoise) -> tuple[float, float] | None:
    """Measured over expected noise, force and moment, of untouched samples (the tare window).

    Parameters
    ----------
    quiet : array-like, shape (N, 6)
        Wrench samples while untouched, N and N·m (N ≥ 6).
    noise : SensorNoise
        The sensor's noise standard deviations.

    Returns
    -------
    tuple of float or None
        ``(σ_f / σ_f,sensor, σ_m / σ_m,sensor)``, each a median over the three axes of a robust
        standard deviation (from the median absolute difference of successive samples, so a
        slow drift does not count; on a quantised axis, where successive samples repeat (2 % or
        more of them), from their mean absolute difference);
        None with fewer than 6 samples or a constant axis group.
    """
    w = np.asarray(quiet, dtype=float).reshape(-1, 6)
    w = w[np.isfinite(w).all(axis=1)]
    if len(w) < 6:
        return None
    step = np.diff(w, axis=0)
    dev = np.abs(step - np.median(step, axis=0))
    sigma = np.median(dev, axis=0) * MAD_TO_STD / np.sqrt(2.0)
    # A quantised sensor repeats its value: the differences take discrete values and their
    # median lands on one of them, a multiple of the quantum (0 from a quantum of 2σ on: the
    # check was then skipped, and a log read in impossible units passed; 0.8–1.8 σ from a
    # quantum of σ). Their mean absolute deviation, √(2/π) times a normal difference's σ,
    # measures the noise within 5 % up to a quantum of 2σ (measured on simulated draws).
    # Continuous data (no repeats) keep the median, which ignores spikes.
    coarse = np.mean(step == 0.0, axis=0) >= 0.02
    if coarse.any():
        sigma[coarse] = dev[:, coarse].mean(axis=0) * np.sqrt(np.pi / 2.0) / np.sqrt(2.0)
    f, m = float(np.median(sigma[:3])), float(np.median(sigma[3:]))
    f0, m0 = float(np.median(noise.force_std)), float(np.median(noise.moment_std))
    if not (f > 0 and m > 0 and f0 > 0 and m0 > 0):
        return None
    return f / f0, m / m0


def _pair_option(force: str, moment: str, given: tuple[str, str]) -> str:
    if (force, moment) == ("kgf", "kgf*mm"):
        return "--units kgf-mm"
    if (force, moment) == ("N", "N*m"):
        return "the default: no --units, --force-units or --moment-units"
    parts = [f"--force-units {force}"] if force != given[0] or force != "N" else []
    return " ".join([*parts, f"--moment-units {moment}"])


def pair_scales(force_unit: str, moment_unit: str) -> dict[tuple[str, str], tuple[float, float]]:
    """For each of :data:`UNIT_PAIRS`, the factors ``(kf, km)`` by which a force and a moment
    read in ``force_unit`` and ``moment_unit`` grow when read in that pair instead (a lever
    read in the given units is ``km / kf`` times the pair's)."""
    f_unit, m_unit = find_unit(force_unit, "force"), find_unit(moment_unit, "moment")
    if f_unit is None or m_unit is None:
        raise ValueError(f"unknown units {force_unit!r}, {moment_unit!r}")
    return {
        (force, moment): (find_unit(force, "force").si / f_unit.si, find_unit(moment, "moment").si / m_unit.si)  # type: ignore[union-attr]
        for force, moment in UNIT_PAIRS
    }


def _ranked_pairs(lever_fits: dict[tuple[str, str], bool], ratio: tuple[float, float] | None, force_unit: str,
                 moment_unit: str) -> list[tuple[float, tuple[str, str]]]:  # fmt: skip
    """The unit pairs other than the given one whose lever fits (``lever_fits``, by pair), nearest
    first, each with how far it puts the tare's noise ``ratio`` (:func:`noise_ratio` in the given
    units) from the sensor's: the larger of the force's and the moment's ``|log|`` (0 without a
    ratio)."""
    given = (find_unit(force_unit, "force").name, find_unit(moment_unit, "moment").name)  # type: ignore[union-attr]
    ranked = [
        (0.0 if ratio is None else max(abs(np.log(ratio[0] * kf)), abs(np.log(ratio[1] * km))), pair)
        for pair, (kf, km) in pair_scales(force_unit, moment_unit).items()
        if lever_fits[pair] and pair != given
    ]
    return sorted(ranked)


def pairs_that_fit(lever_fits: dict[tuple[str, str], bool], ratio: tuple[float, float] | None, force_unit: str,
                   moment_unit: str) -> list[tuple[str, str]]:  # fmt: skip
    """The unit pairs other than the given one that fit a log, best first: those whose lever
    fits (``lever_fits``, by pair) and, with the tare's noise ``ratio`` (:func:`noise_ratio`
    in the given units), that put the noise within :data:`NOISE_FITS` of the sensor's."""
    return [pair for off, pair in _ranked_pairs(lever_fits, ratio, force_unit, moment_unit) if off <= np.log(NOISE_FITS)]


def describe_pairs(named: list[tuple[str, str]], given: tuple[str, str], lead: str = "the data fit ", *,
                   options: bool = True) -> str:  # fmt: skip
    """What a units message says of the pairs that fit (:func:`pairs_that_fit`), with their options
    (``lead`` before them; ``options`` False: without them, for units a file gives, which no
    option overrides)."""
    if not named:
        return "no unit pair F/T software writes fits the data"
    pairs = [
        f"forces in {find_unit(fo, 'force').label} with moments in {find_unit(mo, 'moment').label}"  # type: ignore[union-attr]
        + (f" ({_pair_option(fo, mo, given)})" if options else "")
        for fo, mo in named
    ]
    return lead + ", or ".join(pairs)


def lever_pairs_text(lever_fits: dict[tuple[str, str], bool], ratio: tuple[float, float] | None, force_unit: str,
                     moment_unit: str, *, options: bool = True) -> str:  # fmt: skip
    """What the message of a lever beyond the fingertip's reach says of the units: the pairs that
    fit (:func:`pairs_that_fit`) with their options; where the tare's noise ``ratio`` puts none of
    the pairs the lever fits within :data:`NOISE_FITS` of the sensor's (10 samples at 50 Hz; a
    quiet, quantised or noise-free log is not the model), every pair the lever fits, saying so:
    the lever rules the units read out by a factor of about 1000, the noise by a few. ``options``:
    as :func:`describe_pairs`."""
    given = (find_unit(force_unit, "force").name, find_unit(moment_unit, "moment").name)  # type: ignore[union-attr]
    named = pairs_that_fit(lever_fits, ratio, force_unit, moment_unit)
    if named or ratio is None:
        return describe_pairs(named, given, options=options)
    lever_only = [pair for _, pair in _ranked_pairs(lever_fits, ratio, force_unit, moment_unit)]
    return describe_pairs(lever_only, given, f"the noise while taring fits no unit pair within {NOISE_FITS:g} times "
                          "the sensor's (--force-noise, --moment-noise); the lever fits ", options=options)  # fmt: skip


def check_wrench_units(
    wrench: ArrayLike,
    fingertip: Fingertip | str,
    *,
    force_unit: str = "N",
    moment_unit: str = "N*m",
    quiet: ArrayLike | None = None,
    noise: SensorNoise | None = None,
    source: str = "",
    min_force: float = 0.1,
    options: bool = True,
) -> ForceLever:
    """Stop a log whose units make the fingertip geometry or the sensor's noise impossible.

    Parameters
    ----------
    wrench : array-like, shape (N, 6)
        Tared wrench as read, converted to N and N·m from ``force_unit`` and ``moment_unit``.
    fingertip : Fingertip or str
        The fingertip, or a preset's name or a fingertip file (:func:`~softtip.core.fingertip.load_fingertip`).
    force_unit, moment_unit : str
        The units the log was read in (names of :data:`softtip.core.units.UNITS`).
    quiet : array-like, shape (M, 6), optional
        Untouched samples (the tare window), N and N·m, for the noise check.
    noise : SensorNoise, optional
        The sensor's noise; without it (or ``quiet``) only the lever is checked.
    source : str
        The log's name, for the message.
    min_force : float
        As :func:`force_lever`, N.
    options : bool
        Name the command-line options that read the log in each pair that fits; False where
        the file gives the units (no option overrides them).

    Returns
    -------
    ForceLever

    Raises
    ------
    InputError
        The median line of action lies beyond ``LEVER_MARGIN`` times the fingertip's reach,
        or the noise is :data:`NOISE_OFF` times off the sensor's while another pair of
        :data:`UNIT_PAIRS` fits both; the message names the pairs that fit and their options.
    ValueError
        ``wrench`` or ``quiet`` is not of shape (N, 6).
    """
    fingertip = load_fingertip(fingertip)  # a preset's name too
    for name, value in (("wrench", wrench), ("quiet", quiet)):
        shape = np.shape(value) if value is not None else (0, 6)
        if len(shape) != 2 or shape[1] != 6:  # a (6, N) array reshaped to (N, 6) read as a wrench nobody measured
            raise ValueError(f"check_wrench_units: expected {name} of shape (N, 6), got {shape}")
    lever = force_lever(wrench, fingertip, min_force=min_force)
    ratio = noise_ratio(quiet, noise) if quiet is not None and noise is not None else None
    f_unit, m_unit = find_unit(force_unit, "force"), find_unit(moment_unit, "moment")
    if f_unit is None or m_unit is None:
        raise ValueError(f"unknown units {force_unit!r}, {moment_unit!r}")
    given = (f_unit.name, m_unit.name)
    limit = LEVER_MARGIN * lever.reach
    lever_fits = {pair: not (lever.n_samples >= 5 and not lever.median * km / kf <= limit)
                  for pair, (kf, km) in pair_scales(force_unit, moment_unit).items()}  # fmt: skip
    named = pairs_that_fit(lever_fits, ratio, force_unit, moment_unit)
    labels = {u: find_unit(u, q).label for u, q in ((f_unit.name, "force"), (m_unit.name, "moment"))}  # type: ignore[union-attr]
    read_in = f"{labels[f_unit.name]} and {labels[m_unit.name]}"

    lead = "the data fit "

    def fit_text() -> str:
        return describe_pairs(named, given, lead, options=options)

    where = f"{source}: " if source else ""
    if not lever.plausible:
        raise InputError(
            f"{where}the forces act {lever.median * 1e3:.4g} mm from the sensor origin (median of the moment-to-force "
            f"ratio over {lever.n_samples} samples with |f| ≥ {min_force:g} N, read in {read_in}), but the fingertip "
            f"reaches only {lever.reach * 1e3:.3g} mm: {lever_pairs_text(lever_fits, ratio, force_unit, moment_unit, options=options)}; "
            "or is the fingertip (--tip) the wrong one? Expected moments in N·m about the sensor origin"
        )
    off = max(abs(np.log(ratio[0])), abs(np.log(ratio[1]))) if ratio is not None else 0.0
    if off > np.log(NOISE_OFF) and not named:
        # No pair puts the noise within NOISE_FITS of the sensor's: a short tare measures it
        # roughly (10 samples at 50 Hz). A pair NOISE_OFF times nearer than the units read is
        # still the answer: no noise model is off by both factors (an SI log read as kgf-mm:
        # 500 times off, SI 5 times).
        ranked = _ranked_pairs(lever_fits, ratio, force_unit, moment_unit)
        if ranked and off - ranked[0][0] > np.log(NOISE_OFF):
            named = [ranked[0][1]]
            lead = f"no unit pair puts it within {NOISE_FITS:g} times the sensor's; {np.exp(off - ranked[0][0]):.3g} times nearer: "
    if off > np.log(NOISE_OFF) and named:
        f0, m0 = float(np.median(noise.force_std)), float(np.median(noise.moment_std))  # type: ignore[union-attr]
        raise InputError(
            f"{where}read in {read_in}, the noise while taring is {ratio[0] * f0:.3g} N and {ratio[1] * m0 * 1e3:.3g} N·mm "
            f"({ratio[1] * m0:.3g} N·m), "
            f"but the sensor's is {f0:.3g} N and {m0 * 1e3:.3g} N·mm (--force-noise, --moment-noise): {fit_text()}. "
            f"If the sensor really is this {'noisy' if max(ratio, key=lambda r: abs(np.log(r))) > 1.0 else 'quiet'}, "
            "give its --force-noise and "
            "--moment-noise"
        )
    return lever
