"""Figures laid out like the papers': force, moment, ``|h|`` and the measured direction vs time."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Sequence

import numpy as np

from softtip.pipeline import LINE, Estimates
from softtip.units import KGF, KGF_MM

__all__ = ["plot_estimates"]

_UNITS = {
    "si": (1.0, 1e3, "N", "N·mm"),
    "kgf-mm": (1.0 / KGF, 1.0 / KGF_MM, "kgf", "kgf·mm"),
}


def _figure_module():
    import matplotlib

    if os.environ.get("MPLBACKEND") is None:
        matplotlib.use("Agg")  # files only; no display needed
    import matplotlib.pyplot as plt

    return plt


def plot_estimates(
    estimates: Estimates | Sequence[Estimates],
    path: str | os.PathLike | None = None,
    *,
    labels: Sequence[str] | None = None,
    units: str = "si",
    title: str | None = None,
    h_threshold: float | np.ndarray | None = None,
):
    """Draw the four panels of the papers' figures (e.g. 2006 Figs. 8–11).

    Upper left force, lower left moment (the first log's, per axis), upper right ``|h|``,
    lower right the measured direction in degrees (``line`` samples only, with its ±1σ
    band). Several logs (e.g. one per plate angle) share the right-hand panels, one trace
    each.

    Parameters
    ----------
    estimates : Estimates or sequence of Estimates
    path : str or PathLike, optional
        Where to save (PNG, PDF, SVG by extension); the figure is returned either way.
    labels : sequence of str, optional
        One per log, for the legend.
    units : {"si", "kgf-mm"}
        Plot force in N and moment in N·mm, or kgf and kgf·mm as in the papers.
    title : str, optional
    h_threshold : float or array of shape (N,), optional
        The ``|h|`` significance level (N·m) of the first log, drawn dashed: a constant or
        per sample (``max(h_sigmas · h_std, h_min)``).

    Returns
    -------
    matplotlib.figure.Figure
    """
    plt = _figure_module()
    runs = [estimates] if isinstance(estimates, Estimates) else list(estimates)
    if not runs:
        raise ValueError("nothing to plot")
    if units not in _UNITS:
        raise ValueError(f"units must be one of {', '.join(_UNITS)}, got {units!r}")
    fscale, mscale, funit, munit = _UNITS[units]
    fig, axes = plt.subplots(2, 2, figsize=(10, 6.5), sharex=True, constrained_layout=True)
    (ax_f, ax_h), (ax_m, ax_d) = axes

    first = runs[0]
    for i, (name, color) in enumerate(zip("xyz", ("tab:red", "tab:green", "tab:blue"))):
        ax_f.plot(first.t, first.wrench[:, i] * fscale, color=color, lw=1, label=f"force {name}")
        ax_m.plot(first.t, first.wrench[:, 3 + i] * mscale, color=color, lw=1, label=f"moment {name}")
    ax_f.set_ylabel(f"force [{funit}]")
    ax_m.set_ylabel(f"moment [{munit}]")
    ax_f.legend(loc="upper left", fontsize=8)
    ax_m.legend(loc="upper left", fontsize=8)

    for k, est in enumerate(runs):
        label = labels[k] if labels is not None else None
        (line,) = ax_h.plot(est.t, est.h_norm * mscale, lw=1, label=label)
        angle = np.where(est.state == LINE, np.degrees(est.angle), np.nan)
        std = np.degrees(est.angle_std)
        ax_d.plot(est.t, angle, ".", ms=2.5, color=line.get_color(), label=label)
        ax_d.fill_between(est.t, angle - std, angle + std, color=line.get_color(), alpha=0.2, lw=0)
    if h_threshold is not None:
        level = np.broadcast_to(np.asarray(h_threshold, dtype=float), first.t.shape)
        ax_h.plot(first.t, level * mscale, ls="--", color="0.4", lw=1, label="significance")
    ax_h.set_ylabel(f"|h| tangential spin torque [{munit}]")
    ax_d.set_ylabel("measured direction [deg]")
    ax_d.set_ylim(-90, 90)
    ax_d.set_yticks([-90, -45, 0, 45, 90])
    if labels is not None or h_threshold is not None:
        ax_h.legend(loc="upper left", fontsize=8)
    for ax in (ax_m, ax_d):
        ax.set_xlabel("time [s]")
    for ax in axes.flat:
        ax.grid(True, alpha=0.3)
    if title:
        fig.suptitle(title)
    if path is not None:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=110)
        plt.close(fig)
    return fig
