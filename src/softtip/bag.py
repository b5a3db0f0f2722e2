"""ROS bags in and out: rosbag2 (sqlite3 or MCAP) and ROS 1, without a ROS installation.

Needs the pure-Python ``rosbags`` package (``pip install rosbags``; the ``ros`` extra).

**Reading** (:func:`read_bag`): the samples are the ``geometry_msgs/msg/WrenchStamped``
messages of one topic. The time of a sample is its ``header.stamp``, or the time the
message was recorded when the stamp is zero (drivers that do not stamp). ROS messages are
SI (REP-103), as softtip is.

**Writing** (:func:`write_estimates_bag`): a rosbag2 directory with MCAP storage and standard
message types, each message stamped with its input sample's time and ``frame_id``:

=============================  =============================  ==================================
topic                          type                           when
=============================  =============================  ==================================
(the input topic)              geometry_msgs/msg/WrenchStamped every sample: the raw wrench, copied
``/softtip/wrench``            geometry_msgs/msg/WrenchStamped tared (and filtered), after taring
``/softtip/state``             std_msgs/msg/String            every sample: none, point, line or area
``/softtip/line_evidence``     std_msgs/msg/String            line contacts: confirmed or unconfirmed
``/softtip/contact_point``     geometry_msgs/msg/PointStamped in contact (point, line); m
``/softtip/normal``            geometry_msgs/msg/Vector3Stamped in contact: outward unit normal
``/softtip/edge_direction``    geometry_msgs/msg/Vector3Stamped line contacts: unit direction (an axis)
=============================  =============================  ==================================

Nothing is published where a value is undefined (no NaN messages). The bag is written to a
temporary directory beside the destination and renamed into place: a failure leaves nothing.
"""

from __future__ import annotations

import os
import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.atomic import partial_dir
from softtip.errors import InputError
from softtip.ros import TOPICS as ROS_TOPICS
from softtip.pipeline import Estimates

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
_BAG_SUFFIXES = (".bag", ".mcap", ".db3")


def import_rosbags():
    """Import ``rosbags`` or raise an :class:`ImportError` that names the extra to install."""
    try:
        import rosbags.highlevel
        import rosbags.rosbag2
        import rosbags.typesys
    except ImportError as exc:
        raise ImportError(
            "ROS bag input and output need the 'rosbags' package: pip install 'rosbags>=0.10' "
            "(or, from a softtip checkout, pip install -e '.[ros]')"
        ) from exc
    return rosbags


def is_bag(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` looks like a bag: a rosbag2 directory, or a ``.bag``/``.mcap``/``.db3`` file."""
    p = Path(path)
    if p.is_dir():
        return (p / "metadata.yaml").is_file() or any(
            q.suffix in (".mcap", ".db3") for q in p.iterdir()
        )
    return p.suffix.lower() in _BAG_SUFFIXES


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


def _typestore():
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
        reader = AnyReader([p], default_typestore=_typestore())
        reader.open()
    except Exception as exc:  # rosbags raises several unrelated types for a bad file
        raise InputError(
            f"{source}: cannot read as a ROS bag ({exc}); expected a rosbag2 directory (sqlite3 or MCAP), "
            "a .mcap or .db3 file, or a ROS 1 .bag file"
        ) from None
    try:
        topics = reader.topics
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
        expected = int(info.msgcount)
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
        t=(stamps - stamps[0]) * 1e-9,
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
    frame_id: str = "",
    raw_topic: str = DEFAULT_RAW_TOPIC,
) -> None:
    """Write estimates and the raw wrench as a rosbag2 directory (MCAP storage), atomically.

    Parameters
    ----------
    dest : str or path-like
        The bag directory to create; it must not exist.
    est : Estimates
    raw_wrench : array-like, shape (N, 6)
        The input wrench, N and N·m (copied to ``raw_topic``).
    stamps_ns : array-like of int, shape (N,), optional
        Message stamps, ns; default ``round(est.t · 1e9)``.
    frame_id : str
        ``header.frame_id`` of every message (the input's).
    raw_topic : str
        Topic of the raw wrench (the input topic when the input was a bag).

    Raises
    ------
    InputError
        ``dest`` exists, or its directory is missing or not writable.
    """
    import_rosbags()
    from rosbags.rosbag2 import StoragePlugin, Writer

    dest = Path(dest)
    if dest.exists():
        raise InputError(
            f"{dest}: exists already; expected a new directory name for the output bag"
        )
    try:
        tmp = partial_dir(dest)  # mode from the umask, like mkdir
    except OSError as exc:
        raise InputError(
            f"{dest}: cannot create the bag there ({exc.strerror or exc}); expected a writable directory"
        ) from None
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
    ts = _typestore()
    T = ts.types
    Header, Time = T["std_msgs/msg/Header"], T["builtin_interfaces/msg/Time"]
    Vector3, Wrench = T["geometry_msgs/msg/Vector3"], T["geometry_msgs/msg/Wrench"]
    WrenchStamped, String = T[WRENCH_TYPE], T["std_msgs/msg/String"]
    PointStamped, Point = (
        T["geometry_msgs/msg/PointStamped"],
        T["geometry_msgs/msg/Point"],
    )
    Vector3Stamped = T["geometry_msgs/msg/Vector3Stamped"]
    ser = ts.serialize_cdr

    def header(ns: int):
        return Header(
            stamp=Time(sec=int(ns // 1_000_000_000), nanosec=int(ns % 1_000_000_000)),
            frame_id=frame_id,
        )

    def wrench_msg(ns: int, w) -> bytes:
        msg = WrenchStamped(
            header=header(ns),
            wrench=Wrench(
                force=Vector3(x=w[0], y=w[1], z=w[2]),
                torque=Vector3(x=w[3], y=w[4], z=w[5]),
            ),
        )
        return ser(msg, WRENCH_TYPE)

    names = est.state_names.tolist()
    evidence = est.columns()["line_evidence"].tolist()
    tared, point, normal, direction = (
        est.wrench.tolist(),
        est.point.tolist(),
        est.normal.tolist(),
        est.direction.tolist(),
    )
    try:
        with Writer(
            tmp / dest.name, version=9, storage_plugin=StoragePlugin.MCAP
        ) as writer:
            conn = {
                key: writer.add_connection(topic, msgtype, typestore=ts)
                for key, topic, msgtype in (
                    ("raw", raw_topic, WRENCH_TYPE),
                    ("wrench", TOPICS["wrench"], WRENCH_TYPE),
                    ("state", TOPICS["state"], "std_msgs/msg/String"),
                    (
                        "contact_point",
                        TOPICS["contact_point"],
                        "geometry_msgs/msg/PointStamped",
                    ),
                    ("normal", TOPICS["normal"], "geometry_msgs/msg/Vector3Stamped"),
                    (
                        "edge_direction",
                        TOPICS["edge_direction"],
                        "geometry_msgs/msg/Vector3Stamped",
                    ),
                    ("line_evidence", TOPICS["line_evidence"], "std_msgs/msg/String"),
                )
            }
            for k in range(n):
                ns = int(stamps[k])
                writer.write(conn["raw"], ns, wrench_msg(ns, raw[k].tolist()))
                if not est.taring[k]:
                    writer.write(conn["wrench"], ns, wrench_msg(ns, tared[k]))
                writer.write(
                    conn["state"], ns, ser(String(data=names[k]), "std_msgs/msg/String")
                )
                if names[k] != "none":
                    h = header(ns)
                    x, y, z = point[k]
                    writer.write(
                        conn["contact_point"],
                        ns,
                        ser(
                            PointStamped(header=h, point=Point(x=x, y=y, z=z)),
                            "geometry_msgs/msg/PointStamped",
                        ),
                    )
                    x, y, z = normal[k]
                    writer.write(
                        conn["normal"],
                        ns,
                        ser(
                            Vector3Stamped(header=h, vector=Vector3(x=x, y=y, z=z)),
                            "geometry_msgs/msg/Vector3Stamped",
                        ),
                    )
                    if names[k] == "line":
                        writer.write(
                            conn["line_evidence"], ns, ser(String(data=evidence[k]), "std_msgs/msg/String")
                        )
                        x, y, z = direction[k]
                        writer.write(
                            conn["edge_direction"],
                            ns,
                            ser(
                                Vector3Stamped(header=h, vector=Vector3(x=x, y=y, z=z)),
                                "geometry_msgs/msg/Vector3Stamped",
                            ),
                        )
        os.rename(tmp / dest.name, dest)
    except OSError as exc:
        raise InputError(
            f"{dest}: cannot write the bag ({exc.strerror or exc})"
        ) from None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
