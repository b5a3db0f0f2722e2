"""The fused grasp (:class:`softtip.fusion.FusedGrasp`) as standard ROS messages.

Per time step, in the common frame (all stamped with one ``frame_id``, m):

===============================  =================================  ===========================================
topic                            type                               when
===============================  =================================  ===========================================
``/softtip/fused/grasp``         std_msgs/msg/String                every step: the grasp reading (none, single,
                                                                    parallel_lines, crossing_lines, line_and_face,
                                                                    faces), then the evidence and flags, space-separated
``/softtip/fused/contact_a``     geometry_msgs/msg/PointStamped     the first fingertip in contact
``/softtip/fused/contact_b``     geometry_msgs/msg/PointStamped     the second fingertip in contact
``/softtip/fused/line``          geometry_msgs/msg/PoseStamped      a line: its x axis along the (common) direction,
                                                                    through the middle of both contacts
                                                                    (parallel_lines) or the line's contact
``/softtip/fused/line2``         geometry_msgs/msg/PoseStamped      crossing_lines: the second line, at its contact
``/softtip/fused/plane``         geometry_msgs/msg/PoseStamped      parallel_lines: the plane through both lines,
                                                                    z axis its normal, x axis the direction
``/softtip/fused/markers``       visualization_msgs/msg/MarkerArray every step: contacts, lines, plane (deleted
                                                                    when undefined)
===============================  =================================  ===========================================

A line is an axis: its pose's x axis may point either way along it.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.ros import (
    MARKER_ADD,
    MARKER_CUBE,
    MARKER_DELETE,
    MARKER_LINE_LIST,
    MARKER_SPHERE,
    Marker,
)

__all__ = ["FUSED_TOPICS", "FusedPoses", "fused_markers", "fused_poses", "quaternions_from_axes", "write_fused_bag"]

FUSED_TOPICS = {
    "grasp": "/softtip/fused/grasp",
    "contact_a": "/softtip/fused/contact_a",
    "contact_b": "/softtip/fused/contact_b",
    "line": "/softtip/fused/line",
    "line2": "/softtip/fused/line2",
    "plane": "/softtip/fused/plane",
    "markers": "/softtip/fused/markers",
}


def quaternions_from_axes(x: ArrayLike, z: ArrayLike | None = None) -> NDArray[np.float64]:
    """Orientations whose x axis is ``x`` (and whose z axis is ``z`` made perpendicular to it).

    Parameters
    ----------
    x : array-like, shape (..., 3)
        Direction of the x axis (need not be unit); NaN rows give NaN.
    z : array-like, shape (..., 3), optional
        Direction of the z axis, projected perpendicular to ``x``. Default: the sensor axis
        least aligned with ``x``, made perpendicular (any choice fits a line, an axis).

    Returns
    -------
    array, shape (..., 4)
        Unit quaternions ``x, y, z, w`` (ROS's order); NaN where ``x`` (or ``z``) is NaN,
        zero or parallel to the other.
    """
    from scipy.spatial.transform import Rotation

    x = np.asarray(x, dtype=float)
    shape = x.shape[:-1]
    x = x.reshape(-1, 3)
    with np.errstate(invalid="ignore", divide="ignore"):
        xu = x / np.linalg.norm(x, axis=-1, keepdims=True)
        if z is None:
            k = np.argmin(np.abs(np.nan_to_num(xu, nan=1.0)), axis=-1)
            z = np.eye(3)[k]
        else:
            z = np.asarray(z, dtype=float).reshape(-1, 3)
        zp = z - np.sum(z * xu, axis=-1, keepdims=True) * xu
        zn = np.linalg.norm(zp, axis=-1, keepdims=True)
        zu = zp / zn
        yu = np.cross(zu, xu)
    good = np.all(np.isfinite(xu), axis=-1) & np.all(np.isfinite(zu), axis=-1) & (zn[:, 0] > 1e-9)
    out = np.full((len(x), 4), np.nan)
    if good.any():
        m = np.stack([xu[good], yu[good], zu[good]], axis=-1)  # columns: the axes
        out[good] = Rotation.from_matrix(m).as_quat()
    return out.reshape(*shape, 4)


class FusedPoses:
    """Positions (N, 3) and orientations (N, 4, ``x, y, z, w``) of the fused line, second
    line and plane; NaN where undefined."""

    def __init__(self, line, line_q, line2, line2_q, plane, plane_q, point_a, point_b):
        self.line, self.line_q = line, line_q
        self.line2, self.line2_q = line2, line2_q
        self.plane, self.plane_q = plane, plane_q
        self.point_a, self.point_b = point_a, point_b


def fused_poses(fused, line_a: ArrayLike) -> FusedPoses:
    """The poses of :data:`FUSED_TOPICS` from a fused grasp.

    Parameters
    ----------
    fused : FusedGrasp
    line_a : array-like of bool, shape (N,)
        Whether the first fingertip is in a ``line`` contact at each step (its own state: the
        steps of a fused grasp are its samples), to place a single line at its contact.
    """
    grasp = fused.grasp_names
    line_a = np.asarray(line_a, dtype=bool)
    pa, pb = fused.point_a, fused.point_b
    parallel = (grasp == "parallel_lines")[:, None]
    crossing = (grasp == "crossing_lines")[:, None]
    at = np.where(parallel, 0.5 * (pa + pb), np.where(line_a[:, None], pa, pb))
    has_line = np.all(np.isfinite(fused.direction), axis=-1)[:, None]
    line = np.where(has_line, at, np.nan)
    line_q = quaternions_from_axes(fused.direction)
    line2 = np.where(crossing & np.all(np.isfinite(fused.direction_b), axis=-1)[:, None], pb, np.nan)
    line2_q = np.where(np.isfinite(line2[:, :1]), quaternions_from_axes(fused.direction_b), np.nan)
    has_plane = np.all(np.isfinite(fused.plane_normal), axis=-1)[:, None]
    plane = np.where(has_plane, 0.5 * (pa + pb), np.nan)
    plane_q = np.where(has_plane, quaternions_from_axes(fused.direction, fused.plane_normal), np.nan)
    return FusedPoses(line, line_q, line2, line2_q, plane, plane_q, pa, pb)


_FUSED_COLORS = {
    "contact_a": (1.0, 0.85, 0.1, 1.0),
    "contact_b": (1.0, 0.5, 0.0, 1.0),
    "line": (0.9, 0.1, 0.1, 1.0),
    "line2": (0.6, 0.1, 0.9, 1.0),
    "plane": (0.2, 0.7, 0.3, 0.4),
}


def _finite(v) -> bool:
    return bool(np.all(np.isfinite(v)))


def fused_markers(poses: FusedPoses, k: int, *, line_length: float = 0.04, plane_size: float = 0.03) -> list[Marker]:
    """RViz markers of step ``k``: both contacts (spheres), the line(s) (``line_length`` m
    through their point) and the plane (a thin square ``plane_size`` m wide); always five,
    deleted where undefined."""

    def gone(ns: str, i: int, kind: int) -> Marker:
        return Marker(ns, i, kind, MARKER_DELETE, (), (0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (0.0, 0.0, 0.0, 0.0))

    def tup(v) -> tuple[float, float, float]:
        return (float(v[0]), float(v[1]), float(v[2]))

    out = []
    for i, name in enumerate(("contact_a", "contact_b")):
        p = getattr(poses, "point_a" if i == 0 else "point_b")[k]
        out.append(
            Marker(name, i, MARKER_SPHERE, MARKER_ADD, (), tup(p), (0.003,) * 3, _FUSED_COLORS[name]) if _finite(p) else gone(name, i, MARKER_SPHERE)
        )
    from scipy.spatial.transform import Rotation

    for i, name in ((2, "line"), (3, "line2")):
        p, q = getattr(poses, name)[k], getattr(poses, f"{name}_q")[k]
        if _finite(p) and _finite(q):
            d = Rotation.from_quat(q).apply((0.5 * line_length, 0.0, 0.0))
            ends = (tup(p - d), tup(p + d))
            out.append(Marker(name, i, MARKER_LINE_LIST, MARKER_ADD, ends, (0.0, 0.0, 0.0), (0.0015, 0.0, 0.0), _FUSED_COLORS[name]))
        else:
            out.append(gone(name, i, MARKER_LINE_LIST))
    p, q = poses.plane[k], poses.plane_q[k]
    if _finite(p) and _finite(q):
        out.append(
            Marker(
                "plane", 4, MARKER_CUBE, MARKER_ADD, (), tup(p), (plane_size, plane_size, 0.0005), _FUSED_COLORS["plane"],
                (float(q[0]), float(q[1]), float(q[2]), float(q[3])),
            )
        )
    else:
        out.append(gone("plane", 4, MARKER_CUBE))
    return out


def write_fused_bag(
    dest: str | os.PathLike[str],
    fused,
    fingers: Sequence[Any],
    stamps_ns: ArrayLike,
    frame_id: str,
    *,
    distro: str | None = None,
) -> None:
    """Write a fused grasp as the messages of :data:`FUSED_TOPICS`, atomically.

    Parameters
    ----------
    dest : str or path-like
        The rosbag2 directory (or ROS 1 ``.bag`` file) to create; it must not exist.
    fused : FusedGrasp
    fingers : the two :class:`softtip.fusion.Finger` fused (the first one's states place a single line)
    stamps_ns : array-like of int, shape (N,)
        The stamp of each fused step, ns since the epoch.
    frame_id : str
        The common frame.
    distro : str, optional
        As :func:`softtip.io.bag.write_estimates_bag`.
    """
    from softtip.ros.bagout import BagWriter

    n = len(fused)
    stamps = np.asarray(stamps_ns, dtype=np.int64)
    if stamps.shape != (n,):
        raise ValueError(f"expected {n} stamps, got shape {stamps.shape}")
    poses = fused_poses(fused, fingers[0].estimates.state_names == "line")
    labels = [" ".join(w for w in words if w) for words in zip(fused.grasp_names.tolist(), fused.evidence.tolist(), fused.flag.tolist())]
    with BagWriter(dest, distro) as bag:
        stamps = bag.stamps(stamps)
        msg = bag.message
        topic = {
            key: bag.add_topic(FUSED_TOPICS[key], msgtype)
            for key, msgtype in (
                ("grasp", "std_msgs/msg/String"),
                ("contact_a", "geometry_msgs/msg/PointStamped"),
                ("contact_b", "geometry_msgs/msg/PointStamped"),
                ("line", "geometry_msgs/msg/PoseStamped"),
                ("line2", "geometry_msgs/msg/PoseStamped"),
                ("plane", "geometry_msgs/msg/PoseStamped"),
                ("markers", "visualization_msgs/msg/MarkerArray"),
            )
        }

        def point(v):
            return msg("geometry_msgs/msg/Point", x=float(v[0]), y=float(v[1]), z=float(v[2]))

        def pose(h, p, q):
            quat = msg("geometry_msgs/msg/Quaternion", x=float(q[0]), y=float(q[1]), z=float(q[2]), w=float(q[3]))
            return msg("geometry_msgs/msg/PoseStamped", header=h, pose=msg("geometry_msgs/msg/Pose", position=point(p), orientation=quat))

        for k in range(n):
            ns = int(stamps[k])
            h = bag.header(ns, frame_id)
            bag.write(topic["grasp"], ns, msg("std_msgs/msg/String", data=labels[k]))
            for key, p in (("contact_a", poses.point_a[k]), ("contact_b", poses.point_b[k])):
                if _finite(p):
                    bag.write(topic[key], ns, msg("geometry_msgs/msg/PointStamped", header=h, point=point(p)))
            for key in ("line", "line2", "plane"):
                p, q = getattr(poses, key)[k], getattr(poses, f"{key}_q")[k]
                if _finite(p) and _finite(q):
                    bag.write(topic[key], ns, pose(h, p, q))
            bag.write(topic["markers"], ns, bag.marker_array(fused_markers(poses, k), h))
