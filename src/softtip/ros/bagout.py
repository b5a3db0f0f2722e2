"""Bags a lab can play: rosbag2 in the format of a ROS 2 distribution, or a ROS 1 ``.bag``.

Needs the pure-Python ``rosbags`` package (``pip install rosbags``), not a ROS installation.

Each ROS 2 distribution's ``ros2 bag`` reads and writes one rosbag2 metadata version by
default, and one storage; a newer ``metadata.yaml`` is not readable by an older distribution
(Humble parses ``offered_qos_profiles`` as a string, version 9 writes it as a list). What
:data:`DISTROS` holds was read from the ``ros2/rosbag2`` sources of each distribution's branch
(``rosbag2_storage/include/rosbag2_storage/bag_metadata.hpp``: ``int version``;
``rosbag2_storage/src/rosbag2_storage/default_storage_id.cpp``: the default storage; the sqlite3
plugin's ``SqliteStorage::initialize``: the database schema):

=========  ================  ==============  ============================================
distro     metadata version  storage         written by
=========  ================  ==============  ============================================
humble     5                 sqlite3         softtip (schema 3 of Humble's sqlite3 plugin)
iron       7                 mcap            rosbags (MCAP), ``metadata.yaml`` by softtip
jazzy      9                 mcap            rosbags (MCAP), ``metadata.yaml`` by softtip
rolling    9                 mcap            as jazzy (rosbag2 ``rolling`` of October 2024)
noetic     (ROS 1 bag 2.0)   ``.bag`` file   rosbags' rosbag1 writer
=========  ================  ==============  ============================================

:class:`BagWriter` writes any messages (built from the distribution's message definitions
with :meth:`BagWriter.message`) to a temporary name beside the destination and renames it
into place on success: a failure leaves nothing behind.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import sqlite3
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.errors import InputError

__all__ = [
    "DEFAULT_DISTRO",
    "DISTROS",
    "HUMBLE_SQLITE_SCHEMA",
    "ROS1_TIME_MIN",
    "BagFormat",
    "BagWriter",
    "bag_format",
    "import_rosbags",
    "metadata_yaml",
    "remove_bag",
]


def import_rosbags():
    """Import ``rosbags`` or raise an :class:`ImportError` that names the extra to install."""
    try:
        import rosbags.highlevel
        import rosbags.rosbag2
        import rosbags.typesys
    except ImportError as exc:
        raise ImportError(
            "ROS bag input and output need the 'rosbags' package: pip install 'rosbags>=0.11' "
            "(or, from a softtip checkout, pip install -e '.[ros]')"
        ) from exc
    return rosbags


@dataclass(frozen=True)
class BagFormat:
    """What one ROS distribution's bag tools read and write by default."""

    distro: str
    ros_version: int  #: 1 or 2
    storage: str  #: ``sqlite3``, ``mcap`` or ``rosbag1``
    metadata_version: int | None  #: rosbag2 ``metadata.yaml`` version (None for ROS 1)
    sqlite_schema: int | None  #: schema version of the sqlite3 storage (None unless sqlite3)
    store: str  #: name of the ``rosbags.typesys.Stores`` member with its message definitions


#: The default storage and metadata version of each distribution (see the module docstring).
DISTROS: dict[str, BagFormat] = {
    "humble": BagFormat("humble", 2, "sqlite3", 5, 3, "ROS2_HUMBLE"),
    "iron": BagFormat("iron", 2, "mcap", 7, None, "ROS2_IRON"),
    "jazzy": BagFormat("jazzy", 2, "mcap", 9, None, "ROS2_JAZZY"),
    "rolling": BagFormat("rolling", 2, "mcap", 9, None, "LATEST"),
    "noetic": BagFormat("noetic", 1, "rosbag1", None, None, "ROS1_NOETIC"),
}
DEFAULT_DISTRO = "humble"
#: ns: ROS 1's ``ros::TIME_MIN``; rosbag refuses, and its views skip, record times before it
ROS1_TIME_MIN = 1

#: The sqlite3 database of a Humble bag: ``SqliteStorage::initialize`` of rosbag2's ``humble``
#: branch (``rosbag2_storage_default_plugins/src/rosbag2_storage_default_plugins/sqlite/
#: sqlite_storage.cpp``), schema version 3 (``kDBSchemaVersion_``).
HUMBLE_SQLITE_SCHEMA = (
    "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY,ros_distro TEXT NOT NULL);",
    "CREATE TABLE metadata(id INTEGER PRIMARY KEY,metadata_version INTEGER NOT NULL,metadata TEXT NOT NULL);",
    (
        "CREATE TABLE topics(id INTEGER PRIMARY KEY,name TEXT NOT NULL,type TEXT NOT NULL,"
        "serialization_format TEXT NOT NULL,offered_qos_profiles TEXT NOT NULL);"
    ),
    "CREATE TABLE messages(id INTEGER PRIMARY KEY,topic_id INTEGER NOT NULL,timestamp INTEGER NOT NULL, data BLOB NOT NULL);",
    "CREATE INDEX timestamp_idx ON messages (timestamp ASC);",
)


def bag_format(dest: str | os.PathLike[str], distro: str | None = None) -> BagFormat:
    """The format to write ``dest`` in: ``distro``, or ROS 1 for a name ending in ``.bag``,
    else :data:`DEFAULT_DISTRO`.

    Raises
    ------
    InputError
        An unknown distribution, or a ``.bag`` name with a ROS 2 distribution (a rosbag2 is a
        directory), or a ROS 1 bag whose name does not end in ``.bag``.
    """
    ros1_name = Path(dest).suffix.lower() == ".bag"
    if distro is None:
        distro = "noetic" if ros1_name else DEFAULT_DISTRO
    if distro not in DISTROS:
        raise InputError(f"--ros-distro {distro}: unknown; expected one of {', '.join(DISTROS)}")
    fmt = DISTROS[distro]
    if ros1_name and fmt.ros_version == 2:
        raise InputError(
            f"--to-bag {dest}: a name ending in .bag is a ROS 1 bag, but --ros-distro {distro} is ROS 2; "
            "expected a directory name for a rosbag2 (or --ros-distro noetic)"
        )
    if fmt.ros_version == 1 and not ros1_name:
        raise InputError(f"--to-bag {dest}: a ROS 1 bag is one file; expected a name ending in .bag")
    return fmt


def remove_bag(path: str | os.PathLike[str]) -> None:
    """Remove a bag written by :class:`BagWriter` (a rosbag2 directory or a ROS 1 file)."""
    p = Path(path)
    if p.is_dir():
        shutil.rmtree(p, ignore_errors=True)
    elif p.exists():
        p.unlink()


def _default(ts, spec, cache: dict) -> Any:
    """The default value of one field of a rosbags message definition (shared, never mutated)."""
    from rosbags.typesys.store import Nodetype

    kind, rest = spec
    if kind == Nodetype.BASE:
        name = rest[0]
        if name == "string":
            return ""
        if name == "bool":
            return False
        return 0.0 if name.startswith("float") else 0
    if kind == Nodetype.NAME:
        return _build(ts, rest, {}, cache)
    sub, count = rest
    if sub[0] == Nodetype.BASE and sub[1][0] != "string":
        dtype = {"bool": np.bool_, "byte": np.uint8, "char": np.uint8, "octet": np.uint8}.get(sub[1][0], sub[1][0])
        return np.zeros(count if kind == Nodetype.ARRAY else 0, dtype=dtype)
    return [_default(ts, sub, cache) for _ in range(count if kind == Nodetype.ARRAY else 0)]


def _build(ts, msgtype: str, fields: dict[str, Any], cache: dict) -> Any:
    """A message of ``msgtype``; fields not given take their defaults (cached per type in
    ``cache``: building them is most of the cost of a marker)."""
    defaults = cache.get(msgtype)
    if defaults is None:
        _, defs = ts.fielddefs[msgtype]
        defaults = cache[msgtype] = {name: _default(ts, spec, cache) for name, spec in defs}
    if not fields.keys() <= defaults.keys():
        raise TypeError(f"{msgtype} has no field(s) {', '.join(sorted(set(fields) - set(defaults)))}")
    return ts.types[msgtype](**{**defaults, **fields})


class BagWriter:
    """Write messages to a bag in one distribution's default format, atomically.

    Use as a context manager: the bag appears at ``dest`` when the block ends without an
    error, and nothing appears otherwise.

    Parameters
    ----------
    dest : str or path-like
        The rosbag2 directory, or the ROS 1 ``.bag`` file, to create; it must not exist.
    distro : str, optional
        ``humble`` (default), ``iron``, ``jazzy``, ``rolling`` or ``noetic`` (ROS 1); default
        ROS 1 for a name ending in ``.bag`` (:func:`bag_format`).

    Examples
    --------
    >>> with BagWriter("out", "humble") as bag:                       # doctest: +SKIP
    ...     state = bag.add_topic("/softtip/state", "std_msgs/msg/String")
    ...     bag.write(state, 1_700_000_000_000_000_000, bag.message("std_msgs/msg/String", data="line"))
    """

    def __init__(self, dest: str | os.PathLike[str], distro: str | None = None) -> None:
        import_rosbags()
        from rosbags.typesys import Stores, get_typestore

        self.dest = Path(dest)
        self.format = bag_format(self.dest, distro)
        if self.dest.exists() or self.dest.is_symlink():
            raise InputError(f"{self.dest}: exists already; expected a new name for the output bag")
        self.typestore = get_typestore(getattr(Stores, self.format.store))
        self._defaults: dict[str, dict[str, Any]] = {}
        self._topics: list[tuple[str, str, Any]] = []  # topic, type, connection
        self._counts: list[int] = []
        self._start, self._end = 2**63 - 1, 0
        self._tmp: Path | None = None
        self._impl: Any = None

    # --- messages ---------------------------------------------------------------------
    def message(self, msgtype: str, **fields: Any) -> Any:
        """A message of ``msgtype`` (e.g. ``geometry_msgs/msg/PointStamped``) in this bag's
        message definitions; fields not given take their defaults (0, "", empty)."""
        return _build(self.typestore, msgtype, fields, self._defaults)

    def stamps(self, stamps_ns: ArrayLike) -> NDArray[np.int64]:
        """The stamps (ns) as this bag writes them, header stamps and record times alike.

        A ROS 1 bag cannot record before :data:`ROS1_TIME_MIN`, and a header stamp of 0 reads
        as "not stamped" (:func:`softtip.io.bag.read_bag` then takes the record time): a log
        that starts before it (a CSV log's ``t = 0``) is moved later as a whole, so that its
        first sample is not 1 ns apart from the others when read back. Elsewhere unchanged.
        """
        s = np.asarray(stamps_ns, dtype=np.int64)
        if self.format.ros_version == 1 and len(s) and s.min() < ROS1_TIME_MIN:
            return s + (ROS1_TIME_MIN - s.min())
        return s

    def header(self, stamp_ns: int, frame_id: str) -> Any:
        """A ``std_msgs/msg/Header`` (ROS 1's ``seq`` left 0)."""
        stamp = self.message("builtin_interfaces/msg/Time", sec=int(stamp_ns // 1_000_000_000), nanosec=int(stamp_ns % 1_000_000_000))
        return self.message("std_msgs/msg/Header", stamp=stamp, frame_id=frame_id)

    def marker_array(self, markers, header) -> Any:
        """A ``visualization_msgs/msg/MarkerArray`` of :class:`softtip.ros.Marker` (plain data)
        under ``header``."""
        msg = self.message

        def point(p):
            return msg("geometry_msgs/msg/Point", x=float(p[0]), y=float(p[1]), z=float(p[2]))

        out = []
        for m in markers:
            pose = msg(
                "geometry_msgs/msg/Pose",
                position=point(m.position),
                orientation=msg("geometry_msgs/msg/Quaternion", x=m.orientation[0], y=m.orientation[1], z=m.orientation[2], w=m.orientation[3]),
            )
            out.append(
                msg(
                    "visualization_msgs/msg/Marker",
                    header=header, ns=m.ns, id=m.id, type=m.type, action=m.action, pose=pose,
                    scale=msg("geometry_msgs/msg/Vector3", x=m.scale[0], y=m.scale[1], z=m.scale[2]),
                    color=msg("std_msgs/msg/ColorRGBA", r=m.color[0], g=m.color[1], b=m.color[2], a=m.color[3]),
                    points=[point(p) for p in m.points],
                )
            )
        return msg("visualization_msgs/msg/MarkerArray", markers=out)

    # --- writing ----------------------------------------------------------------------
    def __enter__(self) -> BagWriter:
        parent = self.dest.parent if str(self.dest.parent) else Path(".")
        try:
            self._tmp = Path(tempfile.mkdtemp(prefix=f".{self.dest.name}.", suffix=".partial", dir=parent))
        except OSError as exc:
            raise InputError(
                f"{self.dest}: cannot create the bag there ({exc.strerror or exc}); expected a writable directory"
            ) from None
        target = self._tmp / self.dest.name
        try:
            if self.format.storage == "sqlite3":
                target.mkdir()
                self._file = f"{self.dest.name}_0.db3"
                self._impl = sqlite3.connect(target / self._file)
                self._impl.executescript("\n".join(HUMBLE_SQLITE_SCHEMA))
                self._impl.execute(
                    "INSERT INTO schema (schema_version, ros_distro) VALUES (?, ?)", (self.format.sqlite_schema, self.format.distro)
                )
            elif self.format.storage == "mcap":
                from rosbags.rosbag2 import StoragePlugin, Writer

                # rosbags writes versions 8 and 9; the channels' QoS strings of 8 are those of 7
                self._impl = Writer(target, version=9 if self.format.metadata_version >= 9 else 8, storage_plugin=StoragePlugin.MCAP)
                self._impl.open()
            else:
                from rosbags.rosbag1 import Writer as Writer1

                self._impl = Writer1(target)
                self._impl.open()
        except (OSError, sqlite3.Error) as exc:
            shutil.rmtree(self._tmp, ignore_errors=True)
            raise InputError(f"{self.dest}: cannot write the bag ({getattr(exc, 'strerror', None) or exc})") from None
        return self

    def add_topic(self, topic: str, msgtype: str) -> int:
        """Register a topic; returns its key for :meth:`write`."""
        if self.format.storage == "sqlite3":
            self._impl.execute(
                "INSERT INTO topics (name, type, serialization_format, offered_qos_profiles) VALUES (?, ?, ?, ?)",
                (topic, msgtype, "cdr", ""),
            )
            conn = len(self._topics) + 1  # the topics table's id
        else:
            conn = self._impl.add_connection(topic, msgtype, typestore=self.typestore)
        self._topics.append((topic, msgtype, conn))
        self._counts.append(0)
        return len(self._topics) - 1

    def write(self, key: int, stamp_ns: int, msg: Any) -> None:
        """Write one message (recorded at ``stamp_ns``, ns since the epoch)."""
        _, msgtype, conn = self._topics[key]
        if self.format.ros_version == 1:
            data = self.typestore.serialize_ros1(msg, msgtype)
        else:
            data = self.typestore.serialize_cdr(msg, msgtype)
        if self.format.storage == "sqlite3":
            self._impl.execute("INSERT INTO messages (timestamp, topic_id, data) VALUES (?, ?, ?)", (int(stamp_ns), conn, data))
        elif self.format.ros_version == 1:
            # rosbag refuses record times before ros::TIME_MIN; a log's stamps are moved as a
            # whole by stamps(), this only keeps a caller's stray 0 writable
            self._impl.write(conn, max(int(stamp_ns), ROS1_TIME_MIN), data)
        else:
            self._impl.write(conn, int(stamp_ns), data)
        self._counts[key] += 1
        self._start, self._end = min(self._start, int(stamp_ns)), max(self._end, int(stamp_ns))

    def __exit__(self, exc_type, exc, tb) -> None:
        target = self._tmp / self.dest.name
        try:
            if exc_type is not None:
                with contextlib.suppress(Exception):
                    if self.format.storage == "sqlite3":
                        self._impl.close()
                    elif hasattr(self._impl, "abort"):  # rosbag2; a ROS 1 writer is only closed
                        self._impl.abort()
                    else:
                        self._impl.close()
                if isinstance(exc, (OSError, sqlite3.Error)):
                    raise self._cannot_write(exc) from None
                return
            try:
                if self.format.storage == "sqlite3":
                    self._impl.commit()
                    self._impl.close()
                    (target / "metadata.yaml").write_text(self._metadata([self._file]), encoding="utf-8")
                elif self.format.storage == "mcap":
                    self._impl.close()
                    files = sorted(p.name for p in target.iterdir() if p.suffix == ".mcap")
                    (target / "metadata.yaml").write_text(self._metadata(files), encoding="utf-8")
                else:
                    self._impl.close()
                os.rename(target, self.dest)
            except (OSError, sqlite3.Error) as err:
                raise self._cannot_write(err) from None
        finally:
            shutil.rmtree(self._tmp, ignore_errors=True)

    def _cannot_write(self, err: BaseException) -> InputError:
        """The error to report; sqlite3 says only "disk I/O error", so the reason the system
        gives for writing one more block to the (discarded) database file is reported."""
        reason = getattr(err, "strerror", None) or str(err)
        if isinstance(err, sqlite3.Error) and self.format.storage == "sqlite3":
            try:
                with open(self._tmp / self.dest.name / self._file, "ab") as probe:
                    probe.write(bytes(1 << 16))
                    probe.flush()
                    os.fsync(probe.fileno())
            except OSError as why:
                reason = f"{why.strerror or why}; sqlite3: {err}"
        return InputError(f"{self.dest}: cannot write the bag ({reason})")

    def _metadata(self, files: list[str]) -> str:
        count = sum(self._counts)
        start = self._start if count else 0
        duration = self._end - self._start if count else 0
        topics = []
        for (name, msgtype, _), n in zip(self._topics, self._counts):
            digest = self.typestore.hash_rihs01(msgtype) if self.format.metadata_version >= 7 else ""
            topics.append((name, msgtype, digest, n))
        return metadata_yaml(self.format, files=files, topics=topics, start_ns=start, duration_ns=duration)


def _q(s: str) -> str:
    """A YAML double-quoted scalar (JSON's escapes are YAML's)."""
    import json

    return json.dumps(s)


def metadata_yaml(
    fmt: BagFormat, *, files: list[str], topics: list[tuple[str, str, str, int]], start_ns: int, duration_ns: int
) -> str:
    """The ``metadata.yaml`` of a rosbag2 in ``fmt``'s metadata version, laid out as rosbag2 writes it.

    Parameters
    ----------
    fmt : BagFormat
        A ROS 2 format of :data:`DISTROS`.
    files : list of str
        The storage files, relative to the bag directory (one, uncompressed).
    topics : list of (name, type, type_description_hash, message_count)
    start_ns, duration_ns : int
        First recording time (ns since the epoch) and the span to the last (ns).

    Notes
    -----
    Fields by version, as each branch's ``rosbag2_storage`` decodes them: 5 (Humble) has
    ``offered_qos_profiles`` as a string and per-file ``files``; 6 adds ``custom_data``; 7
    (Iron) adds each topic's ``type_description_hash``; 8 adds ``ros_distro``; 9 (Jazzy,
    Rolling) writes ``offered_qos_profiles`` as a list. No QoS profiles are recorded (empty),
    so ``ros2 bag play`` offers its default (reliable, volatile, depth 10).
    """
    v = fmt.metadata_version
    count = sum(t[3] for t in topics)
    out = [
        "rosbag2_bagfile_information:",
        f"  version: {v}",
        f"  storage_identifier: {fmt.storage}",
        "  duration:",
        f"    nanoseconds: {duration_ns}",
        "  starting_time:",
        f"    nanoseconds_since_epoch: {start_ns}",
        f"  message_count: {count}",
        "  topics_with_message_count:" + ("" if topics else " []"),
    ]
    for name, msgtype, digest, n in topics:
        out += [
            "    - topic_metadata:",
            f"        name: {_q(name)}",
            f"        type: {msgtype}",
            "        serialization_format: cdr",
            "        offered_qos_profiles: " + ("[]" if v >= 9 else '""'),
        ]
        if v >= 7:
            out.append(f"        type_description_hash: {_q(digest)}")
        out.append(f"      message_count: {n}")
    out += ['  compression_format: ""', '  compression_mode: ""', "  relative_file_paths:"]
    out += [f"    - {_q(f)}" for f in files]
    out.append("  files:")
    for f in files:
        out += [
            f"    - path: {_q(f)}",
            "      starting_time:",
            f"        nanoseconds_since_epoch: {start_ns}",
            "      duration:",
            f"        nanoseconds: {duration_ns}",
            f"      message_count: {count}",
        ]
    if v >= 6:
        out.append("  custom_data: ~")
    if v >= 8:
        out.append(f"  ros_distro: {fmt.distro}")
    return "\n".join(out) + "\n"
