"""ROS bags in and out: rosbag2 (sqlite3 or MCAP) and ROS 1, without a ROS installation.

Needs the pure-Python ``rosbags`` package (``pip install rosbags``; the ``ros`` extra).

**Reading** (:func:`read_bag`): the samples are the ``geometry_msgs/msg/WrenchStamped``
messages of one topic. The time of a sample is its ``header.stamp``, or the time the
message was recorded when the stamp is zero (drivers that do not stamp). ROS messages are
SI (REP-103), as softtip is.

**Writing** (:func:`write_estimates_bag`): a bag in the default format of a ROS distribution
(rosbag2 metadata version 5 with sqlite3 storage for Humble, the default; Iron, Jazzy, Rolling;
or a ROS 1 ``.bag``: :mod:`softtip.ros.bagout`) with standard message types, each message
stamped with its input sample's time and one ``frame_id`` (``ft_sensor`` by default):

=============================  ==================================  ==============================================
topic                          type                                when
=============================  ==================================  ==============================================
(the input topic)              geometry_msgs/msg/WrenchStamped     every sample: the raw wrench, copied
``/softtip/wrench``            geometry_msgs/msg/WrenchStamped     tared (and filtered), after taring
``/softtip/state``             std_msgs/msg/String                 every sample: none, point, line or area
``/softtip/line_evidence``     std_msgs/msg/String                 line contacts: confirmed or unconfirmed
``/softtip/contact_point``     geometry_msgs/msg/PointStamped      in contact (point, line); m
``/softtip/normal``            geometry_msgs/msg/Vector3Stamped    in contact: outward unit normal
``/softtip/edge_direction``    geometry_msgs/msg/Vector3Stamped    line contacts: unit direction (an axis)
``/softtip/markers``           visualization_msgs/msg/MarkerArray  up to 50 Hz and at state changes: RViz markers
=============================  ==================================  ==============================================

Nothing is published where a value is undefined (no NaN messages). The bag is written to a
temporary directory beside the destination and renamed into place: a failure leaves nothing.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.core.units import seconds_from_ns
from softtip.errors import InputError
from softtip.estimator import Estimates
from softtip.estimator.columns import TOPICS as COLUMN_TOPICS
from softtip.ros import DEFAULT_FRAME_ID
from softtip.ros import TOPICS as ROS_TOPICS
from softtip.ros.bagout import import_rosbags

__all__ = [
    "TOPICS",
    "WRENCH_TYPE",
    "BagLog",
    "import_rosbags",
    "is_bag",
    "read_bag",
    "write_estimates_bag",
]

WRENCH_TYPE = "geometry_msgs/msg/WrenchStamped"
#: Output topics of :func:`write_estimates_bag` (the raw wrench keeps its input topic): the
#: ROS 2 node's (:data:`softtip.ros.TOPICS`).
TOPICS = ROS_TOPICS
#: Topic of the raw wrench in an output bag when the input was not a bag.
DEFAULT_RAW_TOPIC = "/softtip/wrench_raw"
#: A file named so is read as a bag (:func:`is_bag`); ``-o`` refuses such a name (softtip.cli)
BAG_SUFFIXES = (".bag", ".mcap", ".db3")


def is_bag(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` looks like a bag: a rosbag2 directory, or a ``.bag``/``.mcap``/``.db3`` file."""
    p = Path(path)
    if p.is_dir():
        return (p / "metadata.yaml").is_file() or any(
            q.suffix in (".mcap", ".db3") for q in p.iterdir()
        )
    return p.suffix.lower() in BAG_SUFFIXES


@dataclass(frozen=True, eq=False)
class BagLog:
    """A force/torque log read from a bag.

    Attributes
    ----------
    t : (N,) s since the first sample (from the stamps; float64 seconds since the epoch
        would keep only ~0.2 µs and print badly)
    wrench : (N, 6) N and N·m
    stamps_ns : (N,) int64, the stamps as recorded (ns), for writing back
    frame_ids : tuple of str, the distinct ``header.frame_id`` values, in order of appearance
    topic, source : str
    record_time_used : int, samples whose stamp was zero (time of recording used instead)
    expected : int, the number of messages the bag's metadata lists for the topic
    repeated_stamps : int, samples whose stamp equals the previous one (kept)
    damage : str, why reading stopped early ("" when every listed message was read); only
        with ``allow_partial``, otherwise a damaged bag raises
    """

    t: NDArray[np.float64]
    wrench: NDArray[np.float64]
    stamps_ns: NDArray[np.int64]
    frame_ids: tuple[str, ...]
    topic: str
    source: str
    record_time_used: int
    expected: int = 0
    repeated_stamps: int = 0
    damage: str = ""

    @property
    def partial(self) -> bool:
        """Fewer messages were read than the metadata lists, or a damaged message ended the reading."""
        return bool(self.damage)

    @property
    def frame_id(self) -> str:
        """The first ``frame_id`` ("" when none)."""
        return self.frame_ids[0] if self.frame_ids else ""


def default_typestore():
    """The rosbags type store messages are read with (ROS 2 Humble's definitions of the standard messages)."""
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_HUMBLE)


def _topic_list(topics) -> str:
    if not topics:
        return "the bag has no topics"
    items = ", ".join(
        f"{name} ({info.msgtype}, {info.msgcount} messages)"
        for name, info in sorted(topics.items())
    )
    return f"the bag has: {items}"


#: Messages held in memory before growing (a metadata count is not trusted for the allocation).
_INITIAL_CAPACITY = 1 << 14


def read_bag(path: str | os.PathLike[str], topic: str | None = None, *, allow_partial: bool = False) -> BagLog:
    """Read the ``WrenchStamped`` messages of one topic of a bag.

    Parameters
    ----------
    path : str or path-like
        A rosbag2 directory (sqlite3 or MCAP storage), a single ``.mcap`` / ``.db3`` file, or
        a ROS 1 ``.bag`` file.
    topic : str, optional
        The wrench topic. Default: the bag's only ``WrenchStamped`` topic.
    allow_partial : bool
        Accept a damaged bag: keep the messages read before a message that cannot be
        read, and fewer messages than the metadata lists (``BagLog.damage`` says what was
        wrong). Default: a damaged bag raises.

    Returns
    -------
    BagLog

    Raises
    ------
    InputError
        Unreadable bag; topic missing or of another type (the message lists the bag's topics
        with their types); no messages; a message count in the metadata that is negative, or
        larger than the messages in the bag, or a message that cannot be read (unless
        ``allow_partial``); a stamp earlier than the one before (equal stamps are accepted and
        counted); non-finite values.
    """
    import_rosbags()
    from rosbags.highlevel import AnyReader

    source = os.fspath(path)
    p = Path(path)
    if not p.exists():
        raise InputError(
            f"{source}: no such file or directory; expected a ROS bag (rosbag2 directory, .mcap, .db3 or ROS 1 .bag)"
        )
    try:
        reader = AnyReader([p], default_typestore=default_typestore())
        reader.open()
    except Exception as exc:  # rosbags raises several unrelated types for a bad file
        if allow_partial:  # a bag cut short has no summary: read it record by record
            scanned = _read_scanned(p, source, topic, exc)
            if scanned is not None:
                return scanned
        elif _scannable(p):
            raise InputError(
                f"{source}: cannot read as a ROS bag ({exc}); the bag is damaged or was cut short "
                "(--allow-partial reads the messages before the damage)"
            ) from None
        raise InputError(
            f"{source}: cannot read as a ROS bag ({exc}); expected a rosbag2 directory (sqlite3 or MCAP), "
            "a .mcap or .db3 file, or a ROS 1 .bag file"
        ) from None
    try:
        try:
            topics = reader.topics
            counts = {name: int(info.msgcount) for name, info in topics.items()}
        except (TypeError, ValueError, AttributeError, KeyError) as exc:  # e.g. message_count: lots
            raise InputError(
                f"{source}: the bag's metadata is damaged ({exc}); expected whole message counts "
                "(metadata.yaml: message_count)"
            ) from None
        if topic is None:
            wrench_topics = [
                name for name, info in topics.items() if info.msgtype == WRENCH_TYPE
            ]
            if len(wrench_topics) != 1:
                raise InputError(
                    f"{source}: {'several' if wrench_topics else 'no'} {WRENCH_TYPE} topics; "
                    f"give one with --topic; {_topic_list(topics)}"
                )
            topic = wrench_topics[0]
        if topic not in topics:
            raise InputError(
                f"{source}: topic {topic!r} not found; expected a {WRENCH_TYPE} topic; {_topic_list(topics)}"
            )
        info = topics[topic]
        if info.msgtype != WRENCH_TYPE:
            raise InputError(
                f"{source}: topic {topic!r} has type {info.msgtype}; expected {WRENCH_TYPE}; {_topic_list(topics)}"
            )
        expected = counts[topic]
        if expected < 0:
            raise InputError(
                f"{source}: topic {topic!r}: the bag's metadata lists {expected} messages; expected a count of "
                "0 or more (the metadata is damaged)"
            )
        capacity = min(expected, _INITIAL_CAPACITY) or _INITIAL_CAPACITY
        wrench = np.empty((capacity, 6))
        stamps = np.empty(capacity, dtype=np.int64)
        frame_ids: dict[str, None] = {}
        record_time_used = 0
        damage = ""
        k = 0
        try:
            for conn, timestamp, raw in reader.messages(connections=info.connections):
                msg = reader.deserialize(raw, conn.msgtype)
                st = msg.header.stamp
                ns = st.sec * 1_000_000_000 + st.nanosec
                if ns == 0:  # driver did not stamp: fall back to the recording time
                    ns = timestamp
                    record_time_used += 1
                f, m = msg.wrench.force, msg.wrench.torque
                if k >= len(stamps):  # grow geometrically
                    wrench = np.concatenate((wrench, np.empty_like(wrench)))
                    stamps = np.concatenate((stamps, np.empty_like(stamps)))
                wrench[k] = (f.x, f.y, f.z, m.x, m.y, m.z)
                stamps[k] = ns
                frame_ids.setdefault(msg.header.frame_id, None)
                k += 1
        except Exception as exc:  # noqa: BLE001 - a corrupt message can fail in many ways
            damage = f"message {k + 1} cannot be read ({exc})"
            if not allow_partial:
                raise InputError(
                    f"{source}: topic {topic!r}: cannot read message {k + 1} ({exc}); the bag is damaged "
                    f"(--allow-partial uses the {k} messages before it)"
                ) from None
    finally:
        reader.close()
    wrench, stamps = wrench[:k], stamps[:k]
    if k == 0:
        raise InputError(
            f"{source}: topic {topic!r} has no messages; expected {WRENCH_TYPE} samples"
            + (f" ({damage})" if damage else "")
        )
    if k < expected and not damage:
        damage = f"{k} of the {expected} messages its metadata lists were found"
        if not allow_partial:
            raise InputError(
                f"{source}: topic {topic!r}: read {k} messages, but the bag's metadata lists {expected}; the bag "
                f"is damaged or was cut short (--allow-partial uses the {k} messages read)"
            )
    return _bag_log(wrench, stamps, frame_ids, topic, source, record_time_used, expected, damage)


def _bag_log(wrench, stamps, frame_ids, topic: str, source: str, record_time_used: bool, expected, damage) -> BagLog:
    """The messages read, checked (finite wrench, stamps that never go back) into a :class:`BagLog`."""
    bad = np.flatnonzero(~np.all(np.isfinite(wrench), axis=1))
    if len(bad):
        raise InputError(
            f"{source}: topic {topic!r}: message {bad[0] + 1} has a NaN or infinite wrench component; expected finite values"
        )
    step = np.diff(stamps)
    back = np.flatnonzero(step < 0)
    if len(back):
        i = back[0] + 1
        raise InputError(
            f"{source}: topic {topic!r}: message {i + 1} has time {stamps[i] * 1e-9:.9f} s, before message {i} "
            f"({stamps[i - 1] * 1e-9:.9f} s); expected non-decreasing header stamps"
        )
    return BagLog(
        t=seconds_from_ns(stamps),
        wrench=wrench,
        stamps_ns=stamps,
        frame_ids=tuple(frame_ids),
        topic=topic,
        source=source,
        record_time_used=record_time_used,
        expected=expected,
        repeated_stamps=int(np.count_nonzero(step == 0)),
        damage=damage,
    )


def write_estimates_bag(
    dest: str | os.PathLike[str],
    est: Estimates,
    raw_wrench: ArrayLike,
    stamps_ns: ArrayLike | None = None,
    frame_id: str = DEFAULT_FRAME_ID,
    raw_topic: str = DEFAULT_RAW_TOPIC,
    *,
    distro: str | None = None,
    markers: bool = True,
    marker_rate: float | None = 50.0,
) -> None:
    """Write estimates, RViz markers and the raw wrench as a bag a ROS distribution plays, atomically.

    Parameters
    ----------
    dest : str or path-like
        The rosbag2 directory (or ROS 1 ``.bag`` file) to create; it must not exist.
    est : Estimates
    raw_wrench : array-like, shape (N, 6)
        The input wrench, N and N·m (copied to ``raw_topic``).
    stamps_ns : array-like of int, shape (N,), optional
        Message stamps, ns; default ``round(est.t · 1e9)``.
    frame_id : str
        ``header.frame_id`` of every stamped message (default ``ft_sensor``).
    raw_topic : str
        Topic of the raw wrench (the input topic when the input was a bag).
    distro : str, optional
        ``humble`` (default: rosbag2 metadata version 5, sqlite3), ``iron``, ``jazzy``,
        ``rolling`` or ``noetic`` (ROS 1; the default for a name ending in ``.bag``); see
        :mod:`softtip.ros.bagout`.
    markers : bool
        Also write ``visualization_msgs/msg/MarkerArray`` on :data:`softtip.ros.MARKER_TOPIC`
        (contact point, normal, edge direction; deleted when undefined).
    marker_rate : float or None
        Hz: the markers at most this often (the first sample of each 1/rate interval of the
        stamps), and at every change of state, so that a marker appears and disappears
        with the contact; None: every sample. RViz draws at display rate, and markers
        cost twice the other messages to write.

    Raises
    ------
    InputError
        ``dest`` exists, its directory is missing or not writable, or the distribution is
        unknown or does not fit the name.
    """
    from softtip.ros import MARKER_TOPIC, contact_markers
    from softtip.ros.bagout import BagWriter

    n = len(est)
    stamps = (
        np.rint(est.t * 1e9).astype(np.int64)
        if stamps_ns is None
        else np.asarray(stamps_ns, dtype=np.int64)
    )
    raw = np.asarray(raw_wrench, dtype=float)
    if stamps.shape != (n,) or raw.shape != (n, 6):
        raise ValueError(
            f"expected {n} stamps and a ({n}, 6) raw wrench, got {stamps.shape} and {raw.shape}"
        )
    if markers and marker_rate is not None:
        if not marker_rate > 0:
            raise ValueError(f"marker_rate must be positive (Hz) or None, got {marker_rate!r}")
        interval = np.floor_divide(stamps - stamps[0], 1e9 / marker_rate) if n else np.zeros(0)
        marked = np.ones(n, dtype=bool)
        marked[1:] = (np.diff(interval) != 0) | (np.diff(est.state) != 0)
    else:
        marked = np.full(n, markers)
    names = est.state_names.tolist()
    evidence = est.columns()["line_evidence"].tolist()
    tared, point, normal, direction = (
        est.wrench.tolist(),
        est.point.tolist(),
        est.normal.tolist(),
        est.direction.tolist(),
    )
    with BagWriter(dest, distro) as bag:
        stamps = bag.stamps(stamps)
        msg = bag.message

        def wrench_msg(h, w):
            return msg(
                WRENCH_TYPE,
                header=h,
                wrench=msg(
                    "geometry_msgs/msg/Wrench",
                    force=msg("geometry_msgs/msg/Vector3", x=w[0], y=w[1], z=w[2]),
                    torque=msg("geometry_msgs/msg/Vector3", x=w[3], y=w[4], z=w[5]),
                ),
            )

        def vector(h, v):
            return msg("geometry_msgs/msg/Vector3Stamped", header=h, vector=msg("geometry_msgs/msg/Vector3", x=v[0], y=v[1], z=v[2]))

        topic = {
            key: bag.add_topic(name, msgtype)
            for key, name, msgtype in (
                ("raw", raw_topic, WRENCH_TYPE),
                *((t.key, TOPICS[t.key], t.msgtype) for t in COLUMN_TOPICS if t.in_bag),
            )
            + ((("markers", MARKER_TOPIC, "visualization_msgs/msg/MarkerArray"),) if markers else ())
        }
        for k in range(n):
            ns = int(stamps[k])
            h = bag.header(ns, frame_id)
            bag.write(topic["raw"], ns, wrench_msg(h, raw[k].tolist()))
            if not est.taring[k]:
                bag.write(topic["wrench"], ns, wrench_msg(h, tared[k]))
            bag.write(topic["state"], ns, msg("std_msgs/msg/String", data=names[k]))
            contact = names[k] != "none"
            if contact:
                x, y, z = point[k]
                bag.write(
                    topic["contact_point"], ns,
                    msg("geometry_msgs/msg/PointStamped", header=h, point=msg("geometry_msgs/msg/Point", x=x, y=y, z=z)),
                )  # fmt: skip
                bag.write(topic["normal"], ns, vector(h, normal[k]))
                if names[k] == "line":
                    bag.write(topic["line_evidence"], ns, msg("std_msgs/msg/String", data=evidence[k]))
                    bag.write(topic["edge_direction"], ns, vector(h, direction[k]))
            if marked[k]:
                marks = contact_markers(
                    _finite3(point[k]) if contact else None,
                    _finite3(normal[k]) if contact else None,
                    _finite3(direction[k]) if names[k] == "line" else None,
                )
                bag.write(topic["markers"], ns, bag.marker_array(marks, h))


def _scannable(p: Path) -> bool:
    """An MCAP or ROS 1 bag file (or a rosbag2 directory of one MCAP file), by its magic bytes."""
    from softtip.io.bagscan import MCAP_MAGIC, ROS1_MAGIC

    files = [p] if p.is_file() else sorted(q for q in p.iterdir() if q.suffix == ".mcap") if p.is_dir() else []
    if len(files) != 1:
        return False
    try:
        with open(files[0], "rb") as fh:
            head = fh.read(16)
    except OSError:
        return False
    return head.startswith(MCAP_MAGIC) or head.startswith(ROS1_MAGIC)


def _read_scanned(p: Path, source: str, topic: str | None, exc: BaseException) -> BagLog | None:
    """A damaged MCAP or ROS 1 bag read from its start (:mod:`softtip.io.bagscan`); None when it is neither."""
    from softtip.io.bagscan import scan_messages

    files = [p] if p.is_file() else sorted(q for q in p.iterdir() if q.suffix == ".mcap") if p.is_dir() else []
    if len(files) != 1:
        return None
    try:
        listing = scan_messages(files[0], None)
    except (ValueError, OSError):
        return None
    wrench_topics = [name for name, kind in listing.topics.items() if kind == WRENCH_TYPE]
    if topic is None:
        if len(wrench_topics) != 1:
            raise InputError(
                f"{source}: damaged bag ({exc}); {'several' if wrench_topics else 'no'} {WRENCH_TYPE} topics "
                f"found before the damage; give one with --topic ({', '.join(sorted(listing.topics)) or 'none'})"
            )
        topic = wrench_topics[0]
    elif topic not in wrench_topics:
        raise InputError(
            f"{source}: damaged bag ({exc}); no {WRENCH_TYPE} topic {topic!r} found before the damage "
            f"(found: {', '.join(sorted(listing.topics)) or 'none'})"
        )
    result = scan_messages(files[0], topic)
    if result.ros_version == 1:
        from rosbags.typesys import Stores, get_typestore

        store = get_typestore(Stores.ROS1_NOETIC)
        decode = lambda raw: store.deserialize_ros1(raw, WRENCH_TYPE)  # noqa: E731
    else:
        store = default_typestore()
        decode = lambda raw: store.deserialize_cdr(raw, WRENCH_TYPE)  # noqa: E731
    n = len(result.messages)
    wrench, stamps = np.empty((n, 6)), np.empty(n, dtype=np.int64)
    frame_ids: dict[str, None] = {}
    record_time_used = 0
    damage = result.damage
    k = 0
    for timestamp, raw in result.messages:
        try:
            msg = decode(raw)
        except Exception as err:  # noqa: BLE001 - a corrupt message can fail in many ways
            damage = f"message {k + 1} cannot be read ({err})"
            break
        st = msg.header.stamp
        ns = st.sec * 1_000_000_000 + st.nanosec
        if ns == 0:
            ns = timestamp
            record_time_used += 1
        f, m = msg.wrench.force, msg.wrench.torque
        wrench[k] = (f.x, f.y, f.z, m.x, m.y, m.z)
        stamps[k] = ns
        frame_ids.setdefault(msg.header.frame_id, None)
        k += 1
    if k == 0:
        raise InputError(f"{source}: damaged bag ({exc}); no readable {WRENCH_TYPE} message on {topic!r} before the damage")
    wrench, stamps = wrench[:k], stamps[:k]
    return _bag_log(wrench, stamps, frame_ids, topic, source, record_time_used, k, f"{damage or 'damaged'} ({exc})")


def _finite3(v) -> tuple[float, float, float] | None:
    return (v[0], v[1], v[2]) if all(np.isfinite(v)) else None
