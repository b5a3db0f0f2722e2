"""Reading what is readable of a damaged MCAP or ROS 1 bag, record by record.

``rosbags`` opens a bag from its summary (MCAP's footer, ROS 1's index at the end of the
file); a bag cut short (a recorder killed, a copy interrupted) has neither, although every
message before the cut is intact. :func:`scan_messages` walks the file from its start
instead, through the records (uncompressed, zstd or lz4 chunks) as far as they are whole,
and yields the messages of one topic; it says where and why it stopped. It is used by
:func:`softtip.io.bag.read_bag` with ``allow_partial`` only.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["ScanResult", "scan_messages", "MCAP_MAGIC", "ROS1_MAGIC"]

MCAP_MAGIC = b"\x89MCAP0\r\n"
ROS1_MAGIC = b"#ROSBAG V2.0\n"

_U16, _U32, _U64 = struct.Struct("<H"), struct.Struct("<I"), struct.Struct("<Q")


@dataclass
class ScanResult:
    """What a scan found: ``topics`` (name -> message type, ROS 2 style ``pkg/msg/Type``),
    ``messages`` (log time ns, raw bytes) of the topic asked for, ``damage`` (why it stopped),
    ``ros_version`` (1 or 2)."""

    ros_version: int
    topics: dict[str, str] = field(default_factory=dict)
    messages: list[tuple[int, bytes]] = field(default_factory=list)
    damage: str = ""


class _Truncated(Exception):
    pass


def _need(buf: bytes | memoryview, pos: int, n: int) -> None:
    if pos + n > len(buf):
        raise _Truncated


def _decompress(kind: str, data: bytes, size: int) -> bytes:
    if kind in ("", "none"):
        return data
    if kind == "zstd":
        import zstandard

        return zstandard.ZstdDecompressor().decompress(data, max_output_size=size)
    if kind == "lz4":
        import lz4.frame

        return lz4.frame.decompress(data)
    if kind == "bz2":
        import bz2

        return bz2.decompress(data)
    raise ValueError(f"unknown compression {kind!r}")


# -- MCAP ---------------------------------------------------------------------------------


def _mcap_string(buf, pos: int) -> tuple[str, int]:
    _need(buf, pos, 4)
    (n,) = _U32.unpack_from(buf, pos)
    _need(buf, pos + 4, n)
    return bytes(buf[pos + 4 : pos + 4 + n]).decode("utf-8", "replace"), pos + 4 + n


def _mcap_records(buf, result: ScanResult, topic: str | None, schemas: dict, channels: dict, wanted: set, inner: bool) -> None:
    """Parse MCAP records from ``buf`` into ``result``; raise :class:`_Truncated` at a cut."""
    pos = 0
    while pos < len(buf):
        _need(buf, pos, 9)
        op = buf[pos]
        (length,) = _U64.unpack_from(buf, pos + 1)
        start = pos + 9
        if start + length > len(buf):
            if op == 0x06 and not inner:  # a cut chunk: the messages inside up to the cut (uncompressed only)
                _mcap_cut_chunk(buf[start:], result, topic, schemas, channels, wanted)
            raise _Truncated
        body = buf[start : start + length]
        if op == 0x03:  # Schema: id, name, encoding, data
            (sid,) = _U16.unpack_from(body, 0)
            name, _ = _mcap_string(body, 2)
            schemas[sid] = name
        elif op == 0x04:  # Channel: id, schema id, topic, encoding, metadata
            cid, sid = _U16.unpack_from(body, 0)[0], _U16.unpack_from(body, 2)[0]
            name, _ = _mcap_string(body, 4)
            msgtype = schemas.get(sid, "")
            channels[cid] = name
            result.topics.setdefault(name, msgtype)
            if name == topic:
                wanted.add(cid)
        elif op == 0x05:  # Message: channel, sequence, log time, publish time, data
            (cid,) = _U16.unpack_from(body, 0)
            if cid in wanted:
                (log_time,) = _U64.unpack_from(body, 6)
                result.messages.append((log_time, bytes(body[22:])))
        elif op == 0x06:  # Chunk: start, end, uncompressed size, crc, compression, records
            (size,) = _U64.unpack_from(body, 16)
            kind, p = _mcap_string(body, 28)
            (n,) = _U64.unpack_from(body, p)
            data = bytes(body[p + 8 : p + 8 + n])
            _mcap_records(memoryview(_decompress(kind, data, size)), result, topic, schemas, channels, wanted, True)
        elif op == 0x0F or op == 0x02:  # DataEnd, Footer: the data section is whole
            return
        pos = start + length


def _mcap_cut_chunk(body, result, topic, schemas, channels, wanted) -> None:
    try:
        (size,) = _U64.unpack_from(body, 16)
        kind, p = _mcap_string(body, 28)
        if kind not in ("", "none"):
            return
        _need(body, p, 8)
        _mcap_records(memoryview(bytes(body[p + 8 :])), result, topic, schemas, channels, wanted, True)
    except (_Truncated, struct.error):
        pass


# -- ROS 1 --------------------------------------------------------------------------------


def _ros1_header(buf, pos: int, length: int) -> dict[str, bytes]:
    fields, end = {}, pos + length
    while pos < end:
        (n,) = _U32.unpack_from(buf, pos)
        item = bytes(buf[pos + 4 : pos + 4 + n])
        key, _, value = item.partition(b"=")
        fields[key.decode("ascii", "replace")] = value
        pos += 4 + n
    return fields


def _ros1_records(buf, result: ScanResult, topic: str | None, wanted: set, inner: bool) -> None:
    pos = 0
    while pos < len(buf):
        _need(buf, pos, 4)
        (hlen,) = _U32.unpack_from(buf, pos)
        _need(buf, pos + 4, hlen + 4)
        header = _ros1_header(buf, pos + 4, hlen)
        (dlen,) = _U32.unpack_from(buf, pos + 4 + hlen)
        start = pos + 8 + hlen
        op = header.get("op", b"\x00")[:1]
        if start + dlen > len(buf):
            if op == b"\x05" and not inner and header.get("compression", b"none") == b"none":
                try:  # a cut uncompressed chunk: its messages up to the cut
                    _ros1_records(memoryview(bytes(buf[start:])), result, topic, wanted, True)
                except (_Truncated, struct.error):
                    pass
            raise _Truncated
        data = buf[start : start + dlen]
        if op == b"\x07":  # connection: header conn, topic; data: the connection header (type=...)
            conn = _U32.unpack_from(header["conn"])[0]
            name = header.get("topic", b"").decode("utf-8", "replace")
            info = _ros1_header(data, 0, dlen)
            pkg, _, typ = info.get("type", b"").decode("utf-8", "replace").partition("/")
            result.topics.setdefault(name, f"{pkg}/msg/{typ}")
            if name == topic:
                wanted.add(conn)
        elif op == b"\x02":  # message data: header conn, time (sec, nsec)
            conn = _U32.unpack_from(header["conn"])[0]
            if conn in wanted:
                sec, nsec = struct.unpack("<II", header["time"])
                result.messages.append((sec * 1_000_000_000 + nsec, bytes(data)))
        elif op == b"\x05":  # chunk
            kind = header.get("compression", b"none").decode("ascii", "replace")
            size = _U32.unpack_from(header["size"])[0]
            _ros1_records(memoryview(_decompress(kind, bytes(data), size)), result, topic, wanted, True)
        pos = start + dlen


# -----------------------------------------------------------------------------------------


def scan_messages(path: str | Path, topic: str | None) -> ScanResult:
    """Every readable message of ``topic`` in an MCAP or ROS 1 bag file, from its start to the damage.

    Parameters
    ----------
    path : str or Path
        An ``.mcap`` or ROS 1 ``.bag`` file.
    topic : str or None
        The topic whose messages to collect (None: only list the topics).

    Returns
    -------
    ScanResult

    Raises
    ------
    ValueError
        Not an MCAP or ROS 1 bag (its magic bytes).
    """
    data = Path(path).read_bytes()
    buf = memoryview(data)
    if data.startswith(MCAP_MAGIC):
        result = ScanResult(2)
        try:
            _mcap_records(buf[len(MCAP_MAGIC) :], result, topic, {}, {}, set(), False)
        except (_Truncated, struct.error):
            result.damage = "the file is cut short (no MCAP footer); the messages before the cut were read"
        except Exception as exc:  # noqa: BLE001 - a damaged record can fail in many ways
            result.damage = f"a damaged record ({exc}); the messages before it were read"
        return result
    if data.startswith(ROS1_MAGIC):
        result = ScanResult(1)
        try:
            _ros1_records(buf[len(ROS1_MAGIC) :], result, topic, set(), False)
        except (_Truncated, struct.error, KeyError):
            result.damage = "the file is cut short (no index); the messages before the cut were read"
        except Exception as exc:  # noqa: BLE001
            result.damage = f"a damaged record ({exc}); the messages before it were read"
        return result
    raise ValueError("not an MCAP or ROS 1 bag (unknown magic bytes)")


def iter_topics(result: ScanResult) -> Iterator[tuple[str, str]]:
    """(topic, type) pairs found by a scan, sorted."""
    yield from sorted(result.topics.items())
