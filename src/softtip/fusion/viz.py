"""3-D view of a fused grasp with Rerun (``softtip fuse --rerun`` / ``--rerun-save FILE.rrd``).

Needs the ``rerun-sdk`` package (the ``viz`` extra). Everything is in the common (hand)
frame, metres, on the timeline ``t`` (s of the first finger's log):

* ``hand/<finger>``: each fingertip's sensor frame (its pose, per frame drawn), with the skin
  (``skin``, static in the sensor frame), its contact point, normal (1 cm) and force arrow
  (ending at the contact, ``force_scale`` m per N), and its edge line on the skin for a line
  contact, all in the sensor frame under the pose;
* ``hand/fused/line``: the fused line through the midpoint of the two contacts
  (``parallel_lines``), or each finger's line through its contact (``crossing_lines``), or
  the one line (``line_and_face``); ``hand/fused/plane``: the plane through both lines (a
  plate's face, ``parallel_lines``) as a translucent patch; ``hand/fused/face_normal``: the
  face's outward normal (``line_and_face``); cleared where they do not apply;
* ``hand/truth/...`` (when the truth is given, e.g. by the simulator): the object's true line
  through the true contacts and its plane;
* ``series/fused/...``: the fused direction's and plane normal's standard deviations
  (degrees), the grasp code (:data:`~softtip.fusion.fuse.GRASPS`), the force balance's χ².

``rerun FILE.rrd`` opens a saved recording.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.core.fingertip import Fingertip
from softtip.fusion.fuse import Finger, FusedGrasp
from softtip.viz.rerun import import_rerun, surface_mesh

__all__ = ["log_fused", "read_truth"]

_LINE_COLOUR = [40, 220, 90]
_TRUTH_COLOUR = [255, 255, 255]


def _edge_line(tip: Fingertip, r: NDArray, d: NDArray, half_length: float) -> NDArray:
    """(21, 3) the line ``r + s d``, ``|s| ≤ half_length``, projected on the skin (sensor frame)."""
    s = np.linspace(-half_length, half_length, 21)[:, None]
    return tip.project(np.asarray(r) + s * np.asarray(d))


def _plane_patch(centre: NDArray, d: NDArray, n: NDArray, half: float) -> NDArray:
    """(4, 3) corners of a square patch of half-size ``half`` in the plane (``d``, ``n × d``)."""
    e = np.cross(n, d)
    return np.array([centre + half * (sd * d + se * e) for sd, se in ((-1, -1), (1, -1), (1, 1), (-1, 1))])


def log_fused(
    fused: FusedGrasp,
    fingers: Sequence[Finger],
    tips: Fingertip | Sequence[Fingertip],
    *,
    save: str | os.PathLike[str] | None = None,
    spawn: bool = False,
    truth: Mapping[str, ArrayLike] | None = None,
    max_frames: int = 2000,
    line_half_length: float = 0.02,
    force_scale: float = 0.005,
    application_id: str = "softtip-fuse",
) -> None:
    """Log a fused grasp and both fingertips to Rerun, and close the recording.

    Parameters
    ----------
    fused : FusedGrasp
        From :func:`~softtip.fusion.fuse.fuse` (or :func:`~softtip.fusion.fuse_logs`).
    fingers : two Finger
        The fingers fused (their estimates in the sensor frame and their poses).
    tips : Fingertip or one per finger
        The fingertips' geometry (the skin drawn).
    save : path, optional
        Write a ``.rrd`` file.
    spawn : bool
        Open (or connect to) a Rerun viewer.
    truth : mapping, optional
        The object's truth at the fused time steps, hand frame: ``line`` (N, 3) its line
        direction, ``points`` (N, 2, 3) m the true contact points (the line is drawn through
        their midpoint), optional ``plane_normal`` (N, 3).
    max_frames : int
        The 3-D view gets at most this many evenly spaced time steps (the series get all).
    line_half_length : float
        m, half the length of the lines drawn (and the plane patch's half-size).
    force_scale : float
        m per N, the force arrows' length.
    """
    rr = import_rerun()
    if len(fingers) != 2:
        raise ValueError(f"log_fused takes two fingers, got {len(fingers)}")
    tips = list(tips) if isinstance(tips, (list, tuple)) else [tips, tips]
    n = len(fused)
    if truth is not None:
        for key, shape in (("line", (n, 3)), ("points", (n, 2, 3))):
            if key not in truth or np.shape(truth[key]) != shape:
                raise ValueError(f"truth[{key!r}] must have shape {shape}")
    rec = rr.RecordingStream(application_id)
    sinks = [rr.FileSink(os.fspath(save))] if save is not None else []
    if spawn:
        rec.spawn(connect=False)
        sinks.append(rr.GrpcSink())
    if sinks:
        rec.set_sinks(*sinks)
    rec.log("hand", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    names = [f.name for f in fingers]
    for name, tip in zip(names, tips):
        v, tri, nv = surface_mesh(tip)
        rec.log(
            f"hand/{name}/skin",
            rr.Mesh3D(vertex_positions=v, triangle_indices=tri, vertex_normals=nv, albedo_factor=[200, 200, 210, 110]),
            static=True,
        )

    # -- time series: every step ----------------------------------------------------------------
    times = [rr.TimeColumn("t", duration=fused.t)]
    series = {
        "series/fused/direction_std_deg": np.degrees(fused.direction_std),
        "series/fused/plane_normal_std_deg": np.degrees(fused.plane_normal_std),
        "series/fused/grasp": fused.grasp.astype(float),
        "series/fused/balance_chi2": fused.balance_chi2,
    }
    for path, values in series.items():
        rec.send_columns(path, indexes=times, columns=rr.Scalars.columns(scalars=np.asarray(values, dtype=float)))

    # -- 3-D: the fingers' poses and contacts, the fused geometry, the truth ----------------------
    step = max(1, math.ceil(n / max_frames))
    grasp = fused.grasp_names
    half = float(line_half_length)
    for k in range(0, n, step):
        tk = float(fused.t[k])
        rec.set_time("t", duration=tk)
        for j, (name, f, tip) in enumerate(zip(names, fingers, tips)):
            est = f.estimates
            i = k if j == 0 else int(np.clip(np.searchsorted(est.t, tk, side="right") - 1, 0, len(est) - 1))
            rot, tr = f.pose.at(np.array([est.t[i]]))
            rec.log(f"hand/{name}", rr.Transform3D(translation=tr[0], mat3x3=rot.as_matrix()[0]))
            _log_contact(rr, rec, f"hand/{name}", tip, str(est.state_names[i]), est.point[i], est.normal[i],
                         est.wrench[i, :3], est.direction[i], force_scale)  # fmt: skip
        a_is_line = str(fingers[0].estimates.state_names[k]) == "line"
        _log_geometry(rr, rec, fused, k, str(grasp[k]), half, a_is_line)
        if truth is not None:
            pts = np.asarray(truth["points"][k], dtype=float)
            line = np.asarray(truth["line"][k], dtype=float)
            if np.all(np.isfinite(pts)) and np.all(np.isfinite(line)):
                mid = pts.mean(axis=0)
                rec.log("hand/truth/line", rr.LineStrips3D([[mid - half * line, mid + half * line]], radii=0.0002, colors=[_TRUTH_COLOUR]))
                rec.log("hand/truth/contacts", rr.Points3D(pts, radii=0.0005, colors=[_TRUTH_COLOUR]))
                pn = truth.get("plane_normal")
                if pn is not None and np.all(np.isfinite(pn[k])):
                    quad = _plane_patch(mid, line, np.asarray(pn[k], dtype=float), half)
                    rec.log("hand/truth/plane", rr.LineStrips3D([np.vstack([quad, quad[:1]])], radii=0.0001, colors=[_TRUTH_COLOUR]))
    rec.flush()
    rec.disconnect()


def _log_contact(rr, rec, path, tip, state, r, n, f, d, force_scale) -> None:
    """One finger's contact in its sensor frame (under its pose)."""
    parts = ("contact", "normal", "force", "edge")
    if state == "none" or not np.all(np.isfinite(r)):
        for p in parts:
            rec.log(f"{path}/{p}", rr.Clear(recursive=False))
        return
    r, n, f = np.asarray(r), np.asarray(n), np.asarray(f)
    vf = f * force_scale
    rec.log(f"{path}/contact", rr.Points3D([r], radii=0.0008, colors=[[255, 200, 0]]))
    rec.log(f"{path}/normal", rr.Arrows3D(origins=[r], vectors=[0.01 * n], colors=[[80, 160, 255]]))
    rec.log(f"{path}/force", rr.Arrows3D(origins=[r - vf], vectors=[vf], colors=[[255, 60, 60]]))
    if state == "line" and np.all(np.isfinite(d)):
        _, radius = tip.bounding_sphere
        rec.log(f"{path}/edge", rr.LineStrips3D([_edge_line(tip, r, d, 0.5 * radius)], radii=0.0004, colors=[_LINE_COLOUR]))
    else:
        rec.log(f"{path}/edge", rr.Clear(recursive=False))


def _log_geometry(rr, rec, fused: FusedGrasp, k: int, grasp: str, half: float, a_is_line: bool) -> None:
    """The fused line(s), plane and face normal at time step ``k`` (hand frame)."""
    ra, rb = fused.point_a[k], fused.point_b[k]
    lines, plane, face = [], None, None
    if grasp == "parallel_lines":
        mid, d = 0.5 * (ra + rb), fused.direction[k]
        lines.append([mid - half * d, mid + half * d])
        pn = fused.plane_normal[k]
        if np.all(np.isfinite(pn)):
            plane = _plane_patch(mid, d, pn, half)
    elif grasp == "crossing_lines":
        for r, d in ((ra, fused.direction[k]), (rb, fused.direction_b[k])):
            lines.append([r - half * d, r + half * d])
    elif grasp == "line_and_face":
        d = fused.direction[k]
        face_n = fused.face_normal[k]
        r_line, r_face = (ra, rb) if a_is_line else (rb, ra)
        lines.append([r_line - half * d, r_line + half * d])
        face = (r_face, face_n)
    if lines:
        rec.log("hand/fused/line", rr.LineStrips3D(np.asarray(lines), radii=0.0005, colors=[_LINE_COLOUR]))
    else:
        rec.log("hand/fused/line", rr.Clear(recursive=False))
    if plane is not None:
        rec.log("hand/fused/plane", rr.Mesh3D(vertex_positions=plane, triangle_indices=[[0, 1, 2], [0, 2, 3]], albedo_factor=[40, 220, 90, 80]))
    else:
        rec.log("hand/fused/plane", rr.Clear(recursive=False))
    if face is not None and np.all(np.isfinite(face[1])):
        rec.log("hand/fused/face_normal", rr.Arrows3D(origins=[face[0]], vectors=[0.01 * face[1]], colors=[[80, 160, 255]]))
    else:
        rec.log("hand/fused/face_normal", rr.Clear(recursive=False))


def read_truth(path: str | os.PathLike[str], t: ArrayLike) -> dict[str, NDArray[np.float64]]:
    """The simulator's ``truth.json`` (``softtip simulate --hand two-finger``) at times ``t``.

    Parameters
    ----------
    path : path
        The ``truth.json`` written beside the logs (hand frame, SI).
    t : (N,) s
        The fused time steps; each takes the latest truth sample at or before it.

    Returns
    -------
    dict
        ``line`` (N, 3), ``plane_normal`` (N, 3), ``points`` (N, 2, 3) m (right, left): the
        ``truth`` argument of :func:`log_fused`.
    """
    import json

    from softtip.errors import InputError

    try:
        with open(path, encoding="utf-8") as fh:
            doc = json.load(fh)
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InputError(f"{path}: cannot read the truth file: {exc}") from None
    try:
        if doc.get("format") != "softtip-sim-hand-truth/1":
            raise ValueError(f"format {doc.get('format')!r}, expected 'softtip-sim-hand-truth/1'")
        s = doc["samples"]

        def col(key):
            return np.array([[np.nan] * 3 if row is None or None in row else row for row in s[key]], dtype=float).reshape(-1, 3)

        ts = np.asarray(s["t_s"], dtype=float)
        line, normal = col("line_direction"), col("plane_normal")
        points = np.stack([col("contact_point_right"), col("contact_point_left")], axis=1)
        if not (len(ts) == len(line) == len(normal) == len(points)) or len(ts) == 0:
            raise ValueError("samples of unequal length")
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise InputError(f"{path}: not a softtip two-finger truth file ({exc})") from None
    k = np.clip(np.searchsorted(ts, np.asarray(t, dtype=float), side="right") - 1, 0, len(ts) - 1)
    return {"line": line[k], "plane_normal": normal[k], "points": points[k]}
