"""ROS glue that needs no ROS: message stamps, the wrench message in, and what softtip
publishes for one sample (topics, payloads, RViz markers) as plain Python data.

The ROS 2 node (:mod:`softtip.ros.node`, run with ``python -m softtip.ros`` in a sourced ROS 2
environment) is a thin shell over these functions, and the bag writer
(:mod:`softtip.io.bag`) fills the same payloads into ``rosbags`` messages, so what a bag holds and
what the node publishes are the same. Everything here is tested without ROS.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

from softtip.estimator import SampleEstimate
from softtip.estimator.columns import TOPICS as COLUMN_TOPICS

__all__ = [
    "TOPICS",
    "MARKER_TOPIC",
    "DEFAULT_FRAME_ID",
    "seconds_from_stamp",
    "stamp_from_seconds",
    "wrench_sample",
    "Payloads",
    "payloads",
    "Marker",
    "markers",
    "contact_markers",
    "MARKER_ARROW",
    "MARKER_SPHERE",
    "MARKER_CUBE",
    "MARKER_LINE_LIST",
    "MARKER_ADD",
    "MARKER_DELETE",
]

#: Output topics, by what they carry (:data:`softtip.estimator.columns.TOPICS`: their message
#: types and the output columns each carries).
TOPICS = {t.key: t.name for t in COLUMN_TOPICS}
#: Topic of the RViz markers (``visualization_msgs/msg/MarkerArray``).
MARKER_TOPIC = "/softtip/markers"
#: ``header.frame_id`` when the input has none (a CSV log): RViz needs a frame to draw in.
DEFAULT_FRAME_ID = "ft_sensor"

# visualization_msgs/msg/Marker constants
MARKER_ARROW, MARKER_CUBE, MARKER_SPHERE, MARKER_LINE_LIST = 0, 1, 2, 5
MARKER_ADD, MARKER_DELETE = 0, 2


def seconds_from_stamp(sec: int, nanosec: int) -> float:
    """A ``builtin_interfaces/msg/Time`` as seconds."""
    return int(sec) + 1e-9 * int(nanosec)


def stamp_from_seconds(t: float) -> tuple[int, int]:
    """Seconds as ``(sec, nanosec)`` of a ``builtin_interfaces/msg/Time`` (nanosec in [0, 1e9))."""
    ns = round(float(t) * 1e9)
    return ns // 1_000_000_000, ns % 1_000_000_000


def wrench_sample(msg: Any, fallback_time: float | None = None) -> tuple[float, tuple[float, ...]]:
    """``(t, (fx, fy, fz, mx, my, mz))`` of a ``geometry_msgs/msg/WrenchStamped`` (SI).

    Any object with the message's attributes works (rclpy's, rosbags'). A zero stamp (a
    driver that leaves it unset) takes ``fallback_time`` (s, e.g. the receive time) when given.
    """
    st = msg.header.stamp
    t = seconds_from_stamp(st.sec, st.nanosec)
    if t == 0.0 and fallback_time is not None:
        t = float(fallback_time)
    f, m = msg.wrench.force, msg.wrench.torque
    return t, (float(f.x), float(f.y), float(f.z), float(m.x), float(m.y), float(m.z))


class Payloads(NamedTuple):
    """What softtip publishes for one sample; ``None`` where nothing is published."""

    wrench: tuple[float, ...] | None  #: tared (and filtered) wrench, N and N·m; None while taring
    state: str  #: ``none``, ``point``, ``line`` (or ``area``)
    contact_point: tuple[float, float, float] | None  #: m; in contact
    normal: tuple[float, float, float] | None  #: outward unit normal; in contact
    edge_direction: tuple[float, float, float] | None  #: unit axis; ``line`` only
    line_evidence: str | None = None  #: ``confirmed`` or ``unconfirmed``; ``line`` only
    angle_std: float | None = None  #: rad, standard deviation of the direction's angle; ``line`` only


def _finite(v) -> tuple[float, ...] | None:
    v = tuple(float(x) for x in v)
    return v if all(math.isfinite(x) for x in v) else None


def payloads(est: SampleEstimate) -> Payloads:
    """The payloads of one :class:`~softtip.SampleEstimate`."""
    contact = est.state != "none"
    return Payloads(
        wrench=None if est.taring else _finite(est.wrench),
        state=est.state,
        contact_point=_finite(est.point) if contact else None,
        normal=_finite(est.normal) if contact else None,
        edge_direction=_finite(est.direction) if est.state == "line" else None,
        line_evidence=(getattr(est, "line_evidence", "") or "unconfirmed") if est.state == "line" else None,
        angle_std=float(est.angle_std) if est.state == "line" and math.isfinite(est.angle_std) else None,
    )


class Marker(NamedTuple):
    """One ``visualization_msgs/msg/Marker`` as plain data (sensor frame, m)."""

    ns: str
    id: int
    type: int  #: :data:`MARKER_ARROW`, :data:`MARKER_SPHERE`, :data:`MARKER_LINE_LIST` or :data:`MARKER_CUBE`
    action: int  #: :data:`MARKER_ADD` or :data:`MARKER_DELETE`
    points: tuple[tuple[float, float, float], ...]  #: arrow: tail, head; line list: pairs
    position: tuple[float, float, float]  #: sphere or cube centre (origin otherwise)
    scale: tuple[float, float, float]  #: arrow: shaft Ø, head Ø, head length; sphere: Ø; line: width; cube: sides
    color: tuple[float, float, float, float]  #: RGBA in [0, 1]
    orientation: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)  #: x, y, z, w of the pose (a cube's)


_ORIGIN = (0.0, 0.0, 0.0)
_COLORS = {
    "contact_point": (1.0, 0.85, 0.1, 1.0),
    "normal": (0.2, 0.5, 1.0, 1.0),
    "edge_direction": (0.9, 0.1, 0.1, 1.0),
}


def markers(est: SampleEstimate, *, normal_length: float = 0.015, edge_length: float = 0.03) -> list[Marker]:
    """RViz markers of one sample: the contact point (sphere), the normal (arrow) and the edge
    direction (a line through the contact point, ``edge_length`` m long).

    Every marker is always present, added or deleted, so that a marker of an earlier sample
    never lingers in RViz when the state changes.
    """
    p = payloads(est)
    return contact_markers(p.contact_point, p.normal, p.edge_direction, normal_length=normal_length, edge_length=edge_length)


def contact_markers(
    contact_point: tuple[float, float, float] | None,
    normal: tuple[float, float, float] | None,
    edge_direction: tuple[float, float, float] | None,
    *,
    normal_length: float = 0.015,
    edge_length: float = 0.03,
) -> list[Marker]:
    """The three markers of :func:`markers` from plain values (m; unit vectors; ``None`` where
    undefined): the sphere and the arrow are deleted without a contact point and normal, the
    edge line without an edge direction."""
    def gone(ns: str, i: int, kind: int) -> Marker:
        return Marker(ns, i, kind, MARKER_DELETE, (), _ORIGIN, (1.0, 1.0, 1.0), (0.0, 0.0, 0.0, 0.0))

    out = []
    if contact_point is None or normal is None:
        out.append(gone("contact_point", 0, MARKER_SPHERE))
        out.append(gone("normal", 1, MARKER_ARROW))
    else:
        r = contact_point
        out.append(Marker("contact_point", 0, MARKER_SPHERE, MARKER_ADD, (), r, (0.002, 0.002, 0.002), _COLORS["contact_point"]))
        n = normal
        tip = (r[0] + normal_length * n[0], r[1] + normal_length * n[1], r[2] + normal_length * n[2])
        out.append(Marker("normal", 1, MARKER_ARROW, MARKER_ADD, (r, tip), _ORIGIN, (0.001, 0.002, 0.003), _COLORS["normal"]))
    if edge_direction is None or contact_point is None:
        out.append(gone("edge_direction", 2, MARKER_LINE_LIST))
    else:
        r, d, h = contact_point, edge_direction, 0.5 * edge_length
        a = (r[0] - h * d[0], r[1] - h * d[1], r[2] - h * d[2])
        b = (r[0] + h * d[0], r[1] + h * d[1], r[2] + h * d[2])
        out.append(Marker("edge_direction", 2, MARKER_LINE_LIST, MARKER_ADD, (a, b), _ORIGIN, (0.001, 0.0, 0.0), _COLORS["edge_direction"]))
    return out
