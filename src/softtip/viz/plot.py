"""Figures laid out like the papers': force, moment, ``|h|`` and the measured direction vs time."""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np

from softtip.core.units import KGF, KGF_MM
from softtip.estimator import LINE, Estimates
from softtip.viz.style import LINESTYLES, MARKERS, NEUTRAL, PALETTE, TRUTH, XYZ, label, legend_outside, styled

__all__ = ["plot_estimates", "plot_direction_chart", "plot_position_error", "figure_formats"]

_UNITS = {
    "si": (1.0, 1e3, "N", "N·mm"),
    "kgf-mm": (1.0 / KGF, 1.0 / KGF_MM, "kgf", "kgf·mm"),
}


def figure_module():
    """``matplotlib.pyplot`` on a backend that needs no display unless one is asked for (``MPLBACKEND``)."""
    import matplotlib

    if os.environ.get("MPLBACKEND") is None:
        matplotlib.use("Agg")  # files only; no display needed
    import matplotlib.pyplot as plt

    return plt


@styled
def plot_estimates(
    estimates: Estimates | Sequence[Estimates],
    path: str | os.PathLike | None = None,
    *,
    labels: Sequence[str] | None = None,
    units: str = "si",
    title: str | None = None,
    h_threshold: float | np.ndarray | None = None,
    reference_angles: Sequence[float] | None = None,
    fmt: str | None = None,
    detail: int = 0,
):
    """Draw the four panels of the papers' figures (e.g. 2006 Figs. 8–11).

    Upper left force, lower left moment (of log ``detail``, per axis; named in the panels'
    titles when there are several logs), upper right ``|h|`` (missing while the contact
    point is being latched, where it is zero by construction; that interval is shaded),
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
    fmt : str, optional
        File format (e.g. ``"png"``); default from the extension of ``path``.
    detail : int
        Index of the log whose force and moment are drawn (default the first).
    reference_angles : sequence of float, optional
        True directions (degrees), one per log, drawn as dashed lines in its colour.
    h_threshold : float or array of shape (N,), optional
        The ``|h|`` significance level (N·m) of the first log, drawn dashed: a constant or
        per sample (``max(h_sigmas · h_std, h_min)``).

    Returns
    -------
    matplotlib.figure.Figure
    """
    plt = figure_module()
    runs = [estimates] if isinstance(estimates, Estimates) else list(estimates)
    if not runs:
        raise ValueError("nothing to plot")
    if units not in _UNITS:
        raise ValueError(f"units must be one of {', '.join(_UNITS)}, got {units!r}")
    fscale, mscale, funit, munit = _UNITS[units]
    fig = plt.figure(figsize=(10, 7.0), constrained_layout=True)
    grid = fig.add_gridspec(3, 2, height_ratios=[1.0, 1.0, 0.12 + 0.08 * len(runs)])
    ax_f = fig.add_subplot(grid[0, 0])
    ax_m = fig.add_subplot(grid[1:, 0], sharex=ax_f)
    ax_h = fig.add_subplot(grid[0, 1], sharex=ax_f)
    ax_d = fig.add_subplot(grid[1, 1], sharex=ax_f)
    ax_s = fig.add_subplot(grid[2, 1], sharex=ax_f)

    first = runs[detail]
    for i, (name, color) in enumerate(zip("xyz", XYZ)):
        ax_f.plot(first.t, first.wrench[:, i] * fscale, color=color, ls=LINESTYLES[i], label=f"f{name}")
        ax_m.plot(first.t, first.wrench[:, 3 + i] * mscale, color=color, ls=LINESTYLES[i], label=f"m{name}")
    ax_f.set_ylabel(label("force", funit))
    ax_m.set_ylabel(label("moment", munit))
    whose = f" of the {labels[detail]} grasp" if len(runs) > 1 and labels is not None else ""
    legend_outside(ax_f, title=f"force{whose}, sensor frame", alignment="left")
    legend_outside(ax_m, title=f"moment{whose}, sensor frame", alignment="left")

    from matplotlib.lines import Line2D

    for k, est in enumerate(runs):
        name = labels[k] if labels is not None else None
        # while the point is being latched it is the sample's own soft-finger solution, where
        # h is zero by construction: no measurement, so drawn as missing (and shaded below)
        h_norm = np.where(latching(est), np.nan, est.h_norm)
        (line,) = ax_h.plot(est.t, h_norm * mscale, ls=LINESTYLES[k % len(LINESTYLES)], label=name)
        angle = np.where(est.state == LINE, np.degrees(est.angle), np.nan)
        std = np.degrees(est.angle_std)
        ax_d.plot(est.t, angle, MARKERS[k % len(MARKERS)], ms=2.5, mfc="none" if k else line.get_color(), mew=0.6,
                  color=line.get_color(), label=name)  # fmt: skip
        ax_d.fill_between(est.t, angle - std, angle + std, color=line.get_color(), alpha=0.15, lw=0)
        if reference_angles is not None:  # the truth: black for one log, the log's colour for several
            draw_truth(ax_d, reference_angles[k], lw=1.0, color=TRUTH if len(runs) == 1 else line.get_color(), zorder=3)
    shade = latching(first)
    if shade.any():
        ax_h.fill_between(
            first.t, 0.0, 1.0, where=shade, transform=ax_h.get_xaxis_transform(), color="0.88", lw=0,
            label="latching: |h| not measured",
        )  # fmt: skip
    if h_threshold is not None:
        level = np.broadcast_to(np.asarray(h_threshold, dtype=float), first.t.shape)
        ax_h.plot(first.t, level * mscale, ls="--", color=NEUTRAL, lw=1, label="significance level")
    ax_h.set_ylabel(label("|h| tangential spin torque", munit))
    ax_d.set_ylabel(label("measured direction", "deg"))
    ax_d.set_ylim(-95, 95)  # a true direction at ±90° stays off the frame
    ax_d.set_yticks([-90, -45, 0, 45, 90])
    if labels is None:
        legend_outside(ax_h, ncol=2)
        handles = [Line2D([], [], ls="none", marker=MARKERS[0], ms=3, color=ax_h.lines[0].get_color(), label="direction ±1σ")]
        if reference_angles is not None:
            handles.append(Line2D([], [], ls="--", color=TRUTH, label=f"truth ({reference_angles[0]:g}°)"))
        legend_outside(ax_d, handles=handles)
    else:  # one entry per log above |h|; the direction panel says what its dashes are
        legend_outside(ax_h, ncol=min(len(runs) + 2, 6))
        if reference_angles is not None:
            legend_outside(ax_d, handles=[Line2D([], [], ls="--", color="0.3", label="truth, in each log's colour")])
    state_band(ax_s, runs, labels)
    for ax in (ax_m, ax_s):
        ax.set_xlabel(label("time", "s"))
    ax_d.tick_params(labelbottom=False)
    if title:
        fig.suptitle(title)
    save_figure(fig, plt, path)
    return fig


def draw_truth(ax, degrees: float, **kwargs) -> None:
    """A true direction (degrees), dashed across the direction chart (−95°…95°): a direction is
    axial (θ and θ ± 180° are one), so one near ±90° is drawn on both edges, where its
    measurements fall on either side."""
    for y in float(degrees) + np.array([-180.0, 0.0, 180.0]):
        if abs(y) <= 95.0:
            ax.axhline(y, ls="--", **kwargs)


def latching(est: Estimates) -> np.ndarray:
    """Samples in contact whose point is not (yet) a latched one, shape (N,) bool.

    There the contact point is the sample's own soft-finger solution, so ``h`` is zero by
    construction: not a measurement (plots show it as missing).
    """
    return (est.state > 0) & ~np.asarray(est.latched, dtype=bool)


#: Colours of the state band: none, point, line (unconfirmed), line (confirmed), area.
#: (white, light grey and three of :data:`softtip.viz.style.PALETTE`'s colour-blind-safe colours)
STATE_COLORS = ("white", "0.82", "#56B4E9", "#0072B2", "#E69F00")
STATE_BAND_LABELS = ("none", "point", "line unconfirmed", "line confirmed", "area")


def state_band(ax, runs: Sequence[Estimates], labels: Sequence[str] | None = None) -> None:
    """The contact state over time as a colour band, one row per log (line split into
    unconfirmed and confirmed evidence; :data:`STATE_COLORS`)."""
    from matplotlib.colors import BoundaryNorm, ListedColormap
    from matplotlib.patches import Patch

    cmap = ListedColormap(STATE_COLORS)
    norm = BoundaryNorm(np.arange(-0.5, len(STATE_COLORS)), cmap.N)
    for k, est in enumerate(runs):
        code = np.where(est.state == 3, 4, np.where((est.state == 2) & (est.line_evidence == 2), 3, est.state))
        t = est.t
        if len(t) < 2:
            continue
        mid = 0.5 * (t[1:] + t[:-1])
        edges = np.concatenate(([t[0]], mid, [t[-1]]))
        ax.pcolormesh(edges, [k, k + 1], code[None, :].astype(float), cmap=cmap, norm=norm, shading="flat")
    ax.set_ylim(len(runs), 0)
    ax.set_yticks(np.arange(len(runs)) + 0.5)
    ax.set_yticklabels(list(labels) if labels is not None else [""] * len(runs), fontsize=7)
    ax.set_ylabel("state", fontsize=8)
    handles = [Patch(facecolor=c, edgecolor="0.5", label=n) for c, n in zip(STATE_COLORS, STATE_BAND_LABELS)]
    # compact: the five entries must fit over a narrow band (a half-width panel in the gallery)
    ax.legend(handles=handles, loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=5, fontsize=7, frameon=False, borderaxespad=0.1,
              columnspacing=0.9, handlelength=1.4, handletextpad=0.4)  # fmt: skip


@styled
def plot_line_or_area(
    rows: Sequence[tuple[str, Estimates] | tuple[str, Estimates, float | None]],
    path=None,
    *,
    title: str | None = None,
    t_from: float = 4.0,
):
    """Line or area, one row per log: ``h`` in the tangent plane as a trace (left; N·mm,
    tangent frame at the contact point: a line for a strip, a blob for an area contact) and
    its components and the state over time (right, with the state band below).

    Parameters
    ----------
    rows : sequence of (label, Estimates) or (label, Estimates, true direction in degrees)
        With a true direction d (a strip contact; None for none), the line where h of that
        line contact lies, n × d, is dashed on the left.
    path : str or PathLike, optional
    title : str, optional
    t_from : float
        s; the trace starts here (after the grasp force rise).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from softtip.core._xp import NP
    from softtip.core.spin import tangent_frame_kernel

    plt = figure_module()
    if not rows:
        raise ValueError("nothing to plot")
    fig = plt.figure(figsize=(10, 2.3 * len(rows) + 0.8), constrained_layout=True)
    grid = fig.add_gridspec(2 * len(rows), 2, width_ratios=[1.0, 2.6], height_ratios=[1.0, 0.22] * len(rows))
    ax_last = None
    for k, (name, est, *truth) in enumerate(rows):
        ax_tr = fig.add_subplot(grid[2 * k : 2 * k + 2, 0])
        ax_ts = fig.add_subplot(grid[2 * k, 1], sharex=ax_last)
        ax_st = fig.add_subplot(grid[2 * k + 1, 1], sharex=ax_ts)
        ax_last = ax_ts
        sel = (est.t >= t_from) & (est.state > 0)
        with np.errstate(invalid="ignore"):
            e1x, e1y, e1z, e2x, e2y, e2z = tangent_frame_kernel(*est.normal.T, NP)
            h1 = (est.h[:, 0] * e1x + est.h[:, 1] * e1y + est.h[:, 2] * e1z) * 1e3
            h2 = (est.h[:, 0] * e2x + est.h[:, 1] * e2y + est.h[:, 2] * e2z) * 1e3
        ax_tr.plot(h1[sel], h2[sel], lw=0.6, color=PALETTE[4])
        ax_tr.plot([0], [0], "+", color=TRUTH)
        lim = max(1.0, float(np.nanmax(np.abs(np.concatenate((h1[sel], h2[sel]))))) if sel.any() else 1.0) * 1.1
        if truth and truth[0] is not None and np.isfinite(truth[0]):  # n × d: d turned by +90° in the tangent plane
            across = np.radians(truth[0]) + np.pi / 2
            ax_tr.plot([-lim * np.cos(across), lim * np.cos(across)], [-lim * np.sin(across), lim * np.sin(across)],
                       ls="--", lw=0.9, color=TRUTH, zorder=1)  # fmt: skip
        ax_tr.set_xlim(-lim, lim)
        ax_tr.set_ylim(-lim, lim)
        ax_tr.set_aspect("equal")
        ax_tr.set_xlabel(label("h·e1", "N·mm"))
        ax_tr.set_ylabel(label("h·e2", "N·mm"))
        ax_tr.set_title(name, fontsize=9)
        ax_ts.plot(est.t, h1, color=PALETTE[0], label="h·e1")
        ax_ts.plot(est.t, h2, color=PALETTE[1], ls="--", label="h·e2")
        ax_ts.set_ylabel(label("h", "N·mm"))
        ax_ts.tick_params(labelbottom=False)
        if k == 0:
            legend_outside(ax_ts)
        state_band(ax_st, [est])
        ax_st.set_yticks([])
        if k != len(rows) - 1:
            ax_st.get_legend().remove()
            ax_st.tick_params(labelbottom=False)
        else:
            ax_st.set_xlabel(label("time", "s"))
    with_truth = any(len(r) > 2 and r[2] is not None for r in rows)
    fig.text(
        0.01, 0.0,
        "h: the tangential spin torque; e1, e2: the tangent frame at the contact point (e1: the sensor's x axis "
        "projected on the tangent plane,\nits y axis where x is nearly normal; e2 = n × e1). "
        f"Left: h in that plane from {t_from:g} s on, a line for a strip contact, a blob for an area"
        + (";\ndashed: where h of the true line lies (n × d, d its true direction)." if with_truth else "."),
        fontsize=8, ha="left", va="bottom",
    )  # fmt: skip
    fig.get_layout_engine().set(rect=(0, 0.05 if with_truth else 0.035, 1, 0.95 if with_truth else 0.965))
    if title:
        fig.suptitle(title)
    save_figure(fig, plt, path)
    return fig


def figure_formats() -> set[str]:
    """File name extensions (without the dot) that the figures can be saved as."""
    plt = figure_module()
    fig = plt.figure()
    try:
        return set(fig.canvas.get_supported_filetypes())
    finally:
        plt.close(fig)


def save_figure(fig, plt, path, fmt: str | None = None) -> None:
    """Save ``fig`` to ``path`` (format from its name, or ``fmt``) and close it; ``path`` None: leave it open."""
    if path is not None:
        fig.savefig(path, dpi=110, format=fmt)
        plt.close(fig)


@styled
def plot_direction_chart(
    rows: Sequence[tuple[str, Sequence[Estimates], Sequence[str], Sequence[float]]],
    path: str | os.PathLike | None = None,
    *,
    title: str | None = None,
):
    """The papers' per-object charts (2006 Figs. 14–17, 19–22): one row per object, ``|h|``
    (N·mm) on the left and the measured direction (degrees) on the right, a trace per angle
    with its true direction dashed. Each angle has its own colour, line style and marker, and
    its markers are drawn on every n-th sample (n angles, offset), so that angles measured
    alike (a thick plate reads every angle as 0°) do not hide one another.

    Parameters
    ----------
    rows : sequence of (name, estimates, labels, true angles in degrees)
    path : str or PathLike, optional
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.lines import Line2D

    plt = figure_module()
    fig, axes = plt.subplots(len(rows), 2, figsize=(10, 2.1 * len(rows) + 0.9), sharex=True, squeeze=False, constrained_layout=True)
    handles: dict[str, Line2D] = {}
    for (name, runs, labels, truths), (ax_h, ax_d) in zip(rows, axes):
        for k, (est, lab, truth) in enumerate(zip(runs, labels, truths)):
            # each angle its own line style and (open) marker as well as its colour: where the
            # traces coincide (a thick plate reads every angle as 0°) none hides another
            (ln,) = ax_h.plot(est.t, est.h_norm * 1e3, ls=LINESTYLES[k % len(LINESTYLES)], lw=1.1)
            angle = np.where(est.state == LINE, np.degrees(est.angle), np.nan)
            marker = MARKERS[k % len(MARKERS)]
            # each angle's markers on every n-th sample, offset: where angles coincide all show
            ax_d.plot(est.t, angle, marker, ms=3.5, mfc="none", mew=0.8, color=ln.get_color(), markevery=(k, len(runs)))
            draw_truth(ax_d, truth, lw=0.9, color=ln.get_color(), zorder=3)
            handles.setdefault(lab, Line2D([], [], color=ln.get_color(), ls=LINESTYLES[k % len(LINESTYLES)], marker=marker,
                                           mfc="none", ms=4, label=lab))  # fmt: skip
        ax_h.set_ylabel(label("|h|", "N·mm"))
        ax_h.set_title(name, fontsize=9, loc="left")
        ax_d.set_ylim(-95, 95)  # a true direction at ±90° stays off the frame
        ax_d.set_yticks([-90, -45, 0, 45, 90])
        ax_d.set_ylabel(label("direction", "deg"))
    handles["truth"] = Line2D([], [], ls="--", color="0.3", label="truth (dashed, in the angle's colour)")
    fig.legend(handles=list(handles.values()), loc="outside lower center", ncol=len(handles), frameon=False)
    axes[-1, 0].set_xlabel(label("time", "s"))
    axes[-1, 1].set_xlabel(label("time", "s"))
    if title:
        fig.suptitle(title)
    save_figure(fig, plt, path)
    return fig


@styled
def plot_position_error(
    runs: Sequence[tuple[str, np.ndarray, np.ndarray]],
    path: str | os.PathLike | None = None,
    *,
    bound: float | None = None,
    title: str | None = None,
):
    """Contact-position error against pushing force (2006 Fig. 7).

    Parameters
    ----------
    runs : sequence of (label, ``|f|`` in N (N,), position error in m (N,))
    path : str or PathLike, optional
    bound : float, optional
        An error bound to draw, m. The papers judge it above 0.2 kgf (1.96 N), shaded below.
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    plt = figure_module()
    fig, ax = plt.subplots(figsize=(8, 4.2), constrained_layout=True)
    for k, (lab, f_norm, err) in enumerate(runs):
        ok = np.isfinite(err) & (f_norm > 0)
        ax.plot(f_norm[ok], err[ok] * 1e3, MARKERS[k % len(MARKERS)], ms=3, mfc="none", mew=0.7, label=lab)
    if bound is not None:
        ax.axhline(bound * 1e3, ls="--", color=TRUTH, lw=1, label=f"the papers' bound, {bound * 1e3:g} mm")
    ax.axvspan(0.0, 0.2 * KGF, color="0.9", lw=0, zorder=0, label=f"below 0.2 kgf = {0.2 * KGF:.2f} N: not judged")
    ax.set_xlim(left=0.0)
    ax.set_ylim(bottom=0.0)
    ax.set_xlabel(label("pushing force |f|", "N"))
    ax.set_ylabel(label("contact position error", "mm"))
    legend_outside(ax, where="right")
    if title:
        fig.suptitle(title)
    save_figure(fig, plt, path)
    return fig
