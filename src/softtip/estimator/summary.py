"""Per-contact summaries of a run: what a user reads at the end of ``softtip estimate``.

A run's samples pooled over several contacts mean nothing (a −45° grasp then a +45° one have
no "median direction"), so the summary is per contact: from its first to its last sample in
contact, its peak force, the share of each state, the latched point and the direction of its
``line`` samples with their spread.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from softtip.core.axial import axial_difference, axial_median
from softtip.estimator import STATES, Estimates

__all__ = ["ContactSummary", "contact_segments", "summarise_contacts", "format_summary"]


@dataclass(frozen=True)
class ContactSummary:
    """One contact of a run (SI; angles in rad)."""

    index: int  #: 1, 2, … in time order
    start: float  #: s, first sample in contact
    end: float  #: s, last sample in contact
    samples: int
    peak_force: float  #: N
    shares: dict[str, float]  #: fraction of the contact's samples in each state
    point: tuple[float, float, float]  #: m, the contact point at the end (the latched one in latch mode)
    latched: bool  #: whether that point is a latch
    direction: float  #: rad, axial median of the line samples' angles (NaN without any)
    direction_spread: float  #: rad, median absolute axial deviation of those angles
    direction_std: float  #: rad, median reported standard deviation of those angles


def contact_segments(est: Estimates) -> list[tuple[int, int]]:
    """``[(first, stop), ...]`` sample ranges of each contact (``stop`` exclusive).

    A contact is a run of samples not ``none``; when the estimates carry contact ids
    (``contact_id``), those are used instead, so that a brief release inside one grasp does
    not split it.
    """
    ids = getattr(est, "contact_id", None)
    if ids is not None:
        ids = np.asarray(ids)
        out = []
        for k in np.unique(ids[ids > 0]):
            idx = np.flatnonzero(ids == k)
            out.append((int(idx[0]), int(idx[-1]) + 1))
        return out
    inside = est.state != 0
    edges = np.diff(np.concatenate(([False], inside, [False])).astype(np.int8))
    return list(zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist()))


def summarise_contacts(est: Estimates) -> list[ContactSummary]:
    """One :class:`ContactSummary` per contact of ``est``."""
    out = []
    line_code = STATES.index("line")
    for k, (a, b) in enumerate(contact_segments(est), start=1):
        s = est.state[a:b]
        f = np.linalg.norm(np.nan_to_num(est.wrench[a:b, :3]), axis=-1)
        shares = {name: float(np.mean(s == code)) for code, name in enumerate(STATES) if name != "none"}
        located = np.flatnonzero(s != 0)
        last = a + (located[-1] if len(located) else b - a - 1)
        line = s == line_code
        ang = est.angle[a:b][line]
        if len(ang):
            med = axial_median(ang)
            spread = float(np.median(np.abs(axial_difference(ang, med))))
            std = float(np.median(est.angle_std[a:b][line]))
        else:
            med = spread = std = math.nan
        out.append(
            ContactSummary(
                index=k,
                start=float(est.t[a]),
                end=float(est.t[b - 1]),
                samples=b - a,
                peak_force=float(f.max()) if len(f) else math.nan,
                shares=shares,
                point=tuple(float(v) for v in est.point[last]),
                latched=bool(est.latched[last]),
                direction=float(med),
                direction_spread=spread,
                direction_std=std,
            )
        )
    return out


def format_summary(contacts: list[ContactSummary]) -> list[str]:
    """Human-readable lines, one per contact (mm, degrees)."""
    if not contacts:
        return ["no contact"]
    lines = []
    for c in contacts:
        shares = ", ".join(f"{name} {100 * v:.0f} %" for name, v in c.shares.items() if v > 0)
        p = ", ".join(f"{1e3 * v:+.2f}" for v in c.point)
        where = f"{'latched' if c.latched else 'last'} point ({p}) mm" if all(map(math.isfinite, c.point)) else "no point"
        # (a contact with no located sample, a pull, has no share to list)
        text = f"contact {c.index}: {c.start:.3f}–{c.end:.3f} s, peak {c.peak_force:.2f} N{', ' if shares else ''}{shares}; {where}"
        if math.isfinite(c.direction):
            text += (
                f"; direction {math.degrees(c.direction):+.1f}° (spread {math.degrees(c.direction_spread):.1f}°, "
                f"reported std {math.degrees(c.direction_std):.1f}°)"
            )
        else:
            text += "; no direction"
        lines.append(text)
    return lines
