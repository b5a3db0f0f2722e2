"""A figure of a fused grasp, laid out like the papers': both fingertips' forces, the force
balance, the grasp reading over time, the fused direction and the plane normal (degrees, with
±1σ bands and the truth when known)."""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from softtip.fusion.fuse import GRASPS, Finger, FusedGrasp
from softtip.viz.style import LINESTYLES, NEUTRAL, PALETTE, TRUTH, label, legend_outside, styled

__all__ = ["across_grasp_angle", "plot_fused"]

#: Colours of the grasp reading (white, grey and :data:`softtip.viz.style.PALETTE`'s colour-blind-safe colours)
_GRASP_COLORS = {
    "none": "white",
    "single": "0.8",
    "parallel_lines": PALETTE[0],
    "crossing_lines": PALETTE[4],
    "line_and_face": PALETTE[1],
    "faces": PALETTE[3],
}
#: The balance χ² (3 degrees of freedom) at its 99.9 % quantile: fuse's default flag level
_CHI2_3_999 = 16.27


def across_grasp_angle(vectors: ArrayLike, base: ArrayLike, up: ArrayLike = (0.0, 0.0, 1.0)) -> np.ndarray:
    """Angle (rad, axial, in ``(−π/2, π/2]``) of vectors in the plane across the grasp.

    The plane is normal to the line between the contacts ``base`` (its mean direction); the
    angle is measured from ``up`` projected on it toward ``base × up``: for the papers' hand
    (base from the right fingertip to the left one, up the hand's z) this is the right
    fingertip's angle at its apex.
    """
    v = np.asarray(vectors, dtype=float)
    b = np.asarray(base, dtype=float)
    b = b / np.linalg.norm(b)
    e1 = np.asarray(up, dtype=float) - (np.dot(up, b)) * b
    if np.linalg.norm(e1) < 0.1:
        e1 = np.array([0.0, 1.0, 0.0]) - b[1] * b
    e1 = e1 / np.linalg.norm(e1)
    e2 = np.cross(b, e1)
    a = np.arctan2(v @ e2, v @ e1)
    return np.where(a > 0.5 * np.pi, a - np.pi, np.where(a <= -0.5 * np.pi, a + np.pi, a))


@styled
def plot_fused(
    fused: FusedGrasp,
    fingers: Sequence[Finger] | None = None,
    path: str | os.PathLike | None = None,
    *,
    truth_line: ArrayLike | None = None,
    truth_normal: ArrayLike | None = None,
    up: ArrayLike = (0.0, 0.0, 1.0),
    title: str | None = None,
):
    """Draw a fused grasp.

    Left, from the top: ``|f|`` of both fingertips (N; from ``fingers``, optional), the force
    balance χ² (3 degrees of freedom, with its 99.9 % level) and the grasp reading over time
    as a band; right: the fused line's and the plate plane normal's angles across the grasp
    (:func:`across_grasp_angle`, degrees, ±1σ), with the truth dashed when given (arrays
    (N, 3) or one vector, in the fused frame; ``softtip fuse --plot --truth``).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.colors import BoundaryNorm, ListedColormap
    from matplotlib.patches import Patch

    from softtip.viz.plot import figure_module, save_figure

    plt = figure_module()
    fig = plt.figure(figsize=(10, 6.8), layout="constrained")
    grid = fig.add_gridspec(3, 2, height_ratios=[1.0, 0.75, 0.22])
    ax_f = fig.add_subplot(grid[0, 0])
    ax_c = fig.add_subplot(grid[1, 0], sharex=ax_f)
    ax_g = fig.add_subplot(grid[2, 0], sharex=ax_f)
    ax_d = fig.add_subplot(grid[0, 1], sharex=ax_f)
    ax_n = fig.add_subplot(grid[1:, 1], sharex=ax_f)
    t = fused.t
    a, b = fused.names
    for k, finger in enumerate(fingers or ()):  # one colour and line style each: neither hides the other
        est = finger.estimates
        ax_f.plot(est.t, np.linalg.norm(est.wrench[:, :3], axis=-1), color=PALETTE[k % 2], ls=LINESTYLES[k % 2],
                  lw=1.6 - 0.6 * (k % 2), label=f"{finger.name} fingertip")  # fmt: skip
    ax_f.set_ylabel(label("|f|", "N"))
    legend_outside(ax_f, title="contact force", alignment="left")
    ax_f.tick_params(labelbottom=False)

    chi2 = np.asarray(fused.balance_chi2, dtype=float)
    ax_c.plot(t, chi2, color=PALETTE[4], lw=0.8, label="balance χ²")
    ax_c.axhline(_CHI2_3_999, ls="--", color=NEUTRAL, lw=1, label=f"99.9 % level ({_CHI2_3_999:g})")
    finite = chi2[np.isfinite(chi2)]
    top = max(2.0 * _CHI2_3_999, float(np.percentile(finite, 99.5)) * 1.2 if finite.size else 0.0)
    # linear below 1, logarithmic above: small residuals and the flag level both readable
    ax_c.set_yscale("symlog", linthresh=1.0, linscale=1.0)
    ax_c.set_ylim(0.0, top)
    ax_c.set_yticks([v for v in (0, 0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500, 1e3, 1e4, 1e5, 1e6) if v <= top])
    ax_c.yaxis.set_major_formatter("{x:g}")
    ax_c.yaxis.set_minor_locator(plt.NullLocator())
    over = np.isfinite(chi2) & (chi2 > top)
    if over.any():  # off the scale: marked at the top
        ax_c.plot(t[over], np.full(over.sum(), top), "^", color=PALETTE[4], ms=3, clip_on=False, label="above the scale")
    ax_c.set_ylabel(label("force balance χ² (3 dof)"))
    legend_outside(ax_c)
    ax_c.tick_params(labelbottom=False)

    names = np.asarray(fused.grasp_names)
    present = [g for g in GRASPS if (names == g).any()]
    if len(t) > 1:
        code = np.array([GRASPS.index(g) for g in names], dtype=float)
        edges = np.concatenate(([t[0]], 0.5 * (t[1:] + t[:-1]), [t[-1]]))
        cmap = ListedColormap([_GRASP_COLORS[g] for g in GRASPS])
        ax_g.pcolormesh(edges, [0, 1], code[None, :], cmap=cmap, norm=BoundaryNorm(np.arange(-0.5, len(GRASPS)), cmap.N))
    flagged = fused.flag != ""
    handles = [Patch(facecolor=_GRASP_COLORS[g], edgecolor="0.5", label=g.replace("_", " ")) for g in present]
    if flagged.any():
        ax_g.plot(t[flagged], np.full(flagged.sum(), 0.5), "|", color="black", ms=8)
        handles.append(plt.Line2D([], [], ls="none", marker="|", color="black", label="flagged"))
    ax_g.set_ylim(0, 1)
    ax_g.set_yticks([])
    ax_g.grid(False)
    ax_g.set_ylabel("grasp", fontsize=8)
    ax_g.set_xlabel(label("time", "s"))
    legend_outside(ax_g, handles=handles, ncol=min(len(handles), 4), title="grasp reading", alignment="left")

    valid = np.isfinite(fused.point_a).all(axis=-1) & np.isfinite(fused.point_b).all(axis=-1)
    base = np.nanmedian((fused.point_b - fused.point_a)[valid], axis=0) if valid.any() else np.array([1.0, 0.0, 0.0])
    for ax, vec, std, truth, what in (
        (ax_d, fused.direction, fused.direction_std, truth_line, "fused line"),
        (ax_n, fused.plane_normal, fused.plane_normal_std, truth_normal, "plate plane normal"),
    ):
        ang = np.degrees(across_grasp_angle(np.nan_to_num(vec), base, up))
        ang = np.where(np.isfinite(vec).all(axis=-1), ang, np.nan)
        sd = np.degrees(std)
        ax.plot(t, ang, "o", ms=2.5, color=PALETTE[2], label=f"{what} ±1σ")
        ax.fill_between(t, ang - sd, ang + sd, color=PALETTE[2], alpha=0.2, lw=0)
        if truth is not None:
            tv = np.broadcast_to(np.asarray(truth, dtype=float), vec.shape)
            ta = np.degrees(across_grasp_angle(np.nan_to_num(tv), base, up))
            ax.plot(t, np.where(np.isfinite(tv).all(axis=-1), ta, np.nan), "--", color=TRUTH, lw=1.0, zorder=3, label="truth")
        ax.set_ylim(-95, 95)
        ax.set_yticks([-90, -45, 0, 45, 90])
        ax.set_ylabel(label(f"{what} angle", "deg"))
    if fused.direction_b is not None and np.isfinite(fused.direction_b).any():
        ang = np.degrees(across_grasp_angle(np.nan_to_num(fused.direction_b), base, up))
        ax_d.plot(t, np.where(np.isfinite(fused.direction_b).all(axis=-1), ang, np.nan), "s", ms=2.5, mfc="none",
                  color=PALETTE[4], label="second line")  # fmt: skip
    legend_outside(ax_d)
    legend_outside(ax_n)
    ax_d.tick_params(labelbottom=False)
    ax_n.set_xlabel(label("time", "s"))
    fig.suptitle(title or f"Two fingertips fused: the grasped object from the {a} and {b} contacts")
    fig.text(
        0.01, 0.0,
        f"Angles in the plane across the grasp (normal to the line from the {a} to the {b} contact), "
        f"from up toward ({a} → {b}) × up:\nin the papers' hand, the {a} fingertip's angle at its apex.",
        fontsize=8, ha="left", va="bottom",
    )  # fmt: skip
    fig.get_layout_engine().set(rect=(0, 0.05, 1, 0.95))
    save_figure(fig, plt, path)
    return fig
