"""A figure of a fused grasp, laid out like the papers': both fingertips' forces, the grasp
reading over time, the fused direction and the plane normal (degrees, with ±1σ bands)."""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from softtip.fusion.fuse import GRASPS, Finger, FusedGrasp

__all__ = ["across_grasp_angle", "plot_fused"]

_GRASP_COLORS = {
    "none": "0.9",
    "single": "0.75",
    "parallel_lines": "tab:green",
    "crossing_lines": "tab:purple",
    "line_and_face": "tab:orange",
    "faces": "tab:brown",
}


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

    Upper left: ``|f|`` of both fingertips (N; from ``fingers``, optional) and the force
    balance χ²; lower left: the grasp reading over
    time; right: the fused line's and the plate plane normal's angles across the grasp
    (:func:`across_grasp_angle`, degrees, ±1σ), with the truth dashed when given (arrays
    (N, 3) or one vector).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from softtip.viz.plot import figure_module, save_figure

    plt = figure_module()
    fig, ((ax_f, ax_d), (ax_g, ax_n)) = plt.subplots(2, 2, figsize=(10, 6.5), sharex=True, constrained_layout=True)
    t = fused.t
    a, b = fused.names
    for finger, color in zip(fingers or (), ("tab:red", "tab:blue")):
        est = finger.estimates
        ax_f.plot(est.t, np.linalg.norm(est.wrench[:, :3], axis=-1), color=color, lw=1, label=f"|f| {finger.name}")
    ax_f.set_ylabel("force [N]")
    chi = ax_f.twinx()
    chi.plot(t, fused.balance_chi2, color="0.5", lw=0.8, label="balance χ²")
    chi.set_ylabel("balance χ² (3 dof)", color="0.4")
    chi.set_yscale("symlog", linthresh=1.0)
    if fingers:
        ax_f.legend(loc="upper left", fontsize=8)

    names = fused.grasp_names
    for g in GRASPS:
        sel = names == g
        if sel.any():
            ax_g.fill_between(t, 0, 0.7, where=sel, step="mid", color=_GRASP_COLORS[g], lw=0, label=g)
    flagged = fused.flag != ""
    if flagged.any():
        ax_g.plot(t[flagged], np.full(flagged.sum(), 0.75), "|", color="tab:red", ms=6, label="flagged")
    ax_g.set_ylim(0, 1.15)
    ax_g.set_yticks([])
    ax_g.set_ylabel("grasp reading")
    ax_g.legend(loc="upper left", fontsize=7, ncol=3)

    valid = np.isfinite(fused.point_a).all(axis=-1) & np.isfinite(fused.point_b).all(axis=-1)
    base = np.nanmedian((fused.point_b - fused.point_a)[valid], axis=0) if valid.any() else np.array([1.0, 0.0, 0.0])
    for ax, vec, std, truth, label in (
        (ax_d, fused.direction, fused.direction_std, truth_line, "fused line direction"),
        (ax_n, fused.plane_normal, fused.plane_normal_std, truth_normal, "plane normal"),
    ):
        ang = np.degrees(across_grasp_angle(np.nan_to_num(vec), base, up))
        ang = np.where(np.isfinite(vec).all(axis=-1), ang, np.nan)
        sd = np.degrees(std)
        ax.plot(t, ang, ".", ms=2.5, color="tab:green", label=label)
        ax.fill_between(t, ang - sd, ang + sd, color="tab:green", alpha=0.2, lw=0)
        if truth is not None:
            tv = np.broadcast_to(np.asarray(truth, dtype=float), vec.shape)
            ax.plot(t, np.degrees(across_grasp_angle(np.nan_to_num(tv), base, up)), "--", color="0.3", lw=0.9, label="truth")
        ax.set_ylim(-95, 95)
        ax.set_yticks([-90, -45, 0, 45, 90])
        ax.set_ylabel(f"{label} [deg]")
        ax.legend(loc="lower left", fontsize=8)
    if fused.direction_b is not None and np.isfinite(fused.direction_b).any():
        ang = np.degrees(across_grasp_angle(np.nan_to_num(fused.direction_b), base, up))
        ax_d.plot(t, np.where(np.isfinite(fused.direction_b).all(axis=-1), ang, np.nan), ".", ms=2.5, color="tab:purple", label="second line")
    for ax in (ax_g, ax_n):
        ax.set_xlabel("time [s]")
    for ax in (ax_f, ax_d, ax_n):
        ax.grid(True, alpha=0.3)
    fig.suptitle(title or f"fused grasp ({a}, {b}): angles across the grasp, from up toward ({a} → {b}) × up")
    save_figure(fig, plt, path)
    return fig
