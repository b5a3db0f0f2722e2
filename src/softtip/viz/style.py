"""The figures' shared style: a colour-blind-safe palette, legends off the data, units on each axis.

Every figure softtip draws (:mod:`softtip.viz.plot`, :mod:`softtip.fusion.plot`) is made inside
:func:`styled`, takes its colours from :data:`PALETTE` (Okabe & Ito's eight colours, told
apart with every common colour-vision deficiency), labels each axis with :func:`label`
(quantity and unit) and puts its legends beside the axes with :func:`legend_outside`, never
on the traces.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any, TypeVar

__all__ = ["PALETTE", "XYZ", "TRUTH", "NEUTRAL", "MARKERS", "LINESTYLES", "RC", "styled", "label", "legend_outside"]

#: Okabe & Ito's colour-blind-safe palette without black and yellow (too light on white):
#: blue, orange, bluish green, vermillion, reddish purple, sky blue.
PALETTE = ("#0072B2", "#E69F00", "#009E73", "#D55E00", "#CC79A7", "#56B4E9")
#: The x, y, z components of a vector (force, moment): vermillion, bluish green, blue.
XYZ = ("#D55E00", "#009E73", "#0072B2")
#: Truth (a known direction or line): black, dashed.
TRUTH = "black"
#: Secondary traces and reference levels (significance, bounds).
NEUTRAL = "0.45"
#: Markers and line styles that tell traces apart where they overlap (the colour alone cannot).
MARKERS = ("o", "s", "^", "D", "v", "P")
LINESTYLES = ("-", "--", ":", "-.", (0, (5, 1, 1, 1)), (0, (1, 1)))

#: matplotlib settings of every softtip figure
RC: dict[str, Any] = {
    "axes.grid": True,
    "grid.alpha": 0.3,
    "grid.linewidth": 0.6,
    "axes.titlesize": 10,
    "axes.labelsize": 9,
    "xtick.labelsize": 8,
    "ytick.labelsize": 8,
    "legend.fontsize": 8,
    "legend.frameon": False,
    "lines.linewidth": 1.0,
    "lines.markersize": 3,
    "figure.titlesize": 11,
}

F = TypeVar("F", bound=Callable[..., Any])


def styled(fn: F) -> F:
    """Draw ``fn``'s figure with :data:`RC` and :data:`PALETTE` (the caller's settings are left as they were)."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        import matplotlib as mpl
        from cycler import cycler

        with mpl.rc_context({**RC, "axes.prop_cycle": cycler(color=PALETTE)}):
            return fn(*args, **kwargs)

    return wrapper  # type: ignore[return-value]


def label(quantity: str, unit: str | None = None) -> str:
    """An axis label: ``"force [N]"``; ``unit`` None for a dimensionless quantity.

    >>> label("force", "N"), label("χ²")
    ('force [N]', 'χ²')
    """
    return quantity if unit is None else f"{quantity} [{unit}]"


def legend_outside(ax, *, where: str = "above", ncol: int | None = None, handles=None, labels=None, **kwargs):
    """A legend beside the axes, off the data: ``"above"`` (one row, left-aligned) or ``"right"``.

    Returns the legend, or None when nothing is labelled.
    """
    if handles is None:
        handles, labels = ax.get_legend_handles_labels()
    elif labels is None:
        labels = [h.get_label() for h in handles]
    if not handles:
        return None
    if where == "above":
        opts = {"loc": "lower left", "bbox_to_anchor": (0.0, 1.0), "ncol": ncol or len(handles), "borderaxespad": 0.2,
                "handlelength": 1.6, "columnspacing": 1.0}  # fmt: skip
    elif where == "right":
        opts = {"loc": "upper left", "bbox_to_anchor": (1.01, 1.0), "ncol": ncol or 1, "borderaxespad": 0.0}
    else:
        raise ValueError(f"where must be 'above' or 'right', got {where!r}")
    return ax.legend(handles, labels, **{**opts, **kwargs})
