"""ROS bags in and out (softtip[ros]): bags the tests write themselves with rosbags."""

import csv
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rosbags")
from rosbags.highlevel import AnyReader
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

from softtip import load_example
from softtip.errors import InputError
from softtip.io.bag import TOPICS, read_bag
from softtip.io.tables import read_log, write_table

SOFTTIP = str(Path(sys.executable).with_name("softtip"))
WRENCH = "geometry_msgs/msg/WrenchStamped"
T0_NS = 1_700_000_000_123_456_789  # an absolute stamp, as a real bag has


def run(*args):
    return subprocess.run(
        [SOFTTIP, *map(str, args)], capture_output=True, text=True, timeout=120
    )


def stamps_ns(t):
    return T0_NS + np.rint(np.asarray(t) * 1e9).astype(np.int64)


def wrench_msgs(ts, log, zero_stamp_every=0):
    T = ts.types
    for k, (ns, w) in enumerate(zip(stamps_ns(log.t).tolist(), log.wrench.tolist())):
        stamp_ns = 0 if zero_stamp_every and k % zero_stamp_every == 0 else ns
        kw = (
            {"seq": k} if "seq" in T["std_msgs/msg/Header"].__dataclass_fields__ else {}
        )
        header = T["std_msgs/msg/Header"](
            **kw,
            stamp=T["builtin_interfaces/msg/Time"](
                sec=stamp_ns // 10**9, nanosec=stamp_ns % 10**9
            ),
            frame_id="ft_link",
        )
        v = T["geometry_msgs/msg/Vector3"]
        msg = T[WRENCH](
            header=header,
            wrench=T["geometry_msgs/msg/Wrench"](force=v(*w[:3]), torque=v(*w[3:])),
        )
        yield ns, msg


def write_bag2(path, log, plugin, zero_stamp_every=0, extra_topic=True):
    ts = get_typestore(Stores.ROS2_HUMBLE)
    with Writer(path, version=9, storage_plugin=plugin) as w:
        c = w.add_connection("/ft_sensor/wrench", WRENCH, typestore=ts)
        if extra_topic:
            s = w.add_connection("/chatter", "std_msgs/msg/String", typestore=ts)
            w.write(
                s,
                T0_NS,
                ts.serialize_cdr(
                    ts.types["std_msgs/msg/String"](data="hi"), "std_msgs/msg/String"
                ),
            )
        for ns, msg in wrench_msgs(ts, log, zero_stamp_every):
            w.write(c, ns, ts.serialize_cdr(msg, WRENCH))
    return path


def write_bag1(path, log):
    ts = get_typestore(Stores.ROS1_NOETIC)
    with Writer1(path) as w:
        c = w.add_connection("/ft_sensor/wrench", WRENCH, typestore=ts)
        for ns, msg in wrench_msgs(ts, log):
            w.write(c, ns, ts.serialize_ros1(msg, WRENCH))
    return path


@pytest.fixture(scope="module")
def example():
    return load_example()


@pytest.fixture(scope="module")
def csv_twin(tmp_path_factory, example):
    """The bag's data as a CSV log: relative t from the same stamps, and the stamp column."""
    st = stamps_ns(example.t)
    path = tmp_path_factory.mktemp("csv") / "grasp.csv"
    cols = {"t": (st - st[0]) / 1e9}  # as the bag reader makes t (seconds_from_ns)
    cols.update(
        {
            n: example.wrench[:, i]
            for i, n in enumerate(["fx", "fy", "fz", "mx", "my", "mz"])
        }
    )
    cols["stamp_ns"] = st
    write_table(cols, path, float_format="%.17g")
    out = run("estimate", path)
    assert out.returncode == 0, out.stderr
    return out.stdout


@pytest.mark.parametrize("kind", ["sqlite3", "mcap", "mcap-file", "ros1"])
def test_bag_equals_csv(tmp_path, example, csv_twin, kind):
    if kind == "ros1":
        bag = write_bag1(tmp_path / "grasp.bag", example)
    else:
        plugin = StoragePlugin.SQLITE3 if kind == "sqlite3" else StoragePlugin.MCAP
        bag = write_bag2(tmp_path / "grasp", example, plugin)
        if kind == "mcap-file":  # a bare .mcap, as copied out of a bag directory
            bag = next(bag.glob("*.mcap"))
    out = run("estimate", bag, "--topic", "/ft_sensor/wrench")
    assert out.returncode == 0, out.stderr
    assert out.stdout == csv_twin
    assert "'ft_link'" in out.stderr  # frame_id reported


def test_only_wrench_topic_is_the_default(tmp_path, example):
    bag = write_bag2(tmp_path / "b", example, StoragePlugin.MCAP)
    log = read_bag(bag)
    assert log.topic == "/ft_sensor/wrench" and log.frame_ids == ("ft_link",)
    np.testing.assert_array_equal(log.wrench, example.wrench)
    np.testing.assert_array_equal(log.stamps_ns, stamps_ns(example.t))


def test_zero_stamps_fall_back_to_record_time(tmp_path, example):
    bag = write_bag2(tmp_path / "b", example, StoragePlugin.SQLITE3, zero_stamp_every=7)
    log = read_bag(bag, "/ft_sensor/wrench")
    assert log.record_time_used == len(range(0, len(example.t), 7))
    np.testing.assert_array_equal(log.stamps_ns, stamps_ns(example.t))


def test_missing_topic_and_wrong_type_list_the_topics(tmp_path, example):
    bag = write_bag2(tmp_path / "b", example, StoragePlugin.MCAP)
    out = run("estimate", bag, "--topic", "/ft_sensor/wrnch")
    assert out.returncode == 2
    assert "'/ft_sensor/wrnch' not found" in out.stderr
    assert f"/ft_sensor/wrench ({WRENCH}, 500 messages)" in out.stderr
    assert "/chatter (std_msgs/msg/String, 1 messages)" in out.stderr
    out = run("estimate", bag, "--topic", "/chatter")
    assert out.returncode == 2
    assert (
        "has type std_msgs/msg/String; expected geometry_msgs/msg/WrenchStamped"
        in out.stderr
    )
    assert out.stdout == ""


def test_unreadable_bag(tmp_path):
    junk = tmp_path / "junk.bag"
    junk.write_bytes(b"not a bag at all\n" * 10)
    with pytest.raises(InputError, match="cannot read as a ROS bag"):
        read_bag(junk)
    out = run("estimate", junk)
    assert (
        out.returncode == 2
        and "junk.bag" in out.stderr
        and "expected a rosbag2 directory" in out.stderr
    )


def test_to_bag_round_trip(tmp_path, example, csv_twin):
    bag = write_bag2(tmp_path / "in", example, StoragePlugin.MCAP)
    out_bag = tmp_path / "out"
    out = run("estimate", bag, "--to-bag", out_bag, "-o", tmp_path / "est.csv")
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "est.csv").read_text() == csv_twin
    rows = list(csv.DictReader(csv_twin.splitlines()))
    states = [r["state"] for r in rows]
    msgs = {}
    with AnyReader([out_bag], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        assert {n: i.msgtype for n, i in reader.topics.items()} == {
            "/softtip/markers": "visualization_msgs/msg/MarkerArray",
            "/ft_sensor/wrench": WRENCH,
            TOPICS["wrench"]: WRENCH,
            TOPICS["state"]: "std_msgs/msg/String",
            TOPICS["contact_point"]: "geometry_msgs/msg/PointStamped",
            TOPICS["normal"]: "geometry_msgs/msg/Vector3Stamped",
            TOPICS["edge_direction"]: "geometry_msgs/msg/Vector3Stamped",
            TOPICS["line_evidence"]: "std_msgs/msg/String",
        }
        assert "db3" in {p.suffix.lstrip(".") for p in out_bag.iterdir()}  # Humble's default: sqlite3
        for conn, ts, raw in reader.messages():
            msgs.setdefault(conn.topic, []).append(
                (ts, reader.deserialize(raw, conn.msgtype))
            )
    assert [m.data for _, m in msgs[TOPICS["state"]]] == states
    in_contact = [r for r in rows if r["state"] != "none"]
    pts = msgs[TOPICS["contact_point"]]
    assert len(pts) == len(in_contact)
    for (ts, m), r in zip(pts, in_contact):
        assert m.header.frame_id == "ft_link"
        assert (
            ts
            == int(r["stamp_ns"])
            == m.header.stamp.sec * 10**9 + m.header.stamp.nanosec
        )
        assert (m.point.x, m.point.y, m.point.z) == pytest.approx(
            (float(r["rx"]), float(r["ry"]), float(r["rz"])), rel=1e-9, abs=1e-12
        )
    lines = [r for r in rows if r["state"] == "line"]
    dirs = msgs[TOPICS["edge_direction"]]
    assert len(dirs) == len(lines) > 0
    assert dirs[-1][1].vector.x == pytest.approx(float(lines[-1]["dx"]), abs=1e-9)
    assert [m.data for _, m in msgs[TOPICS["line_evidence"]]] == [r["line_evidence"] for r in lines]
    raw = msgs["/ft_sensor/wrench"]
    assert np.array_equal([m.wrench.force.z for _, m in raw], example.wrench[:, 2])
    # the written bag reads back as input, with the same result
    again = run("estimate", out_bag, "--topic", "/ft_sensor/wrench")
    assert again.returncode == 0 and again.stdout == csv_twin


def test_to_bag_is_atomic(tmp_path, example):
    bag = write_bag2(tmp_path / "in", example, StoragePlugin.MCAP)
    (tmp_path / "exists").mkdir()
    out = run("estimate", bag, "--to-bag", tmp_path / "exists")
    assert out.returncode == 2 and "exists already" in out.stderr
    # a failure after the bag was written (an unwritable CSV) removes it again
    out = run(
        "estimate",
        bag,
        "--to-bag",
        tmp_path / "new",
        "-o",
        tmp_path / "no" / "dir" / "est.csv",
    )
    assert out.returncode == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["exists", "in"]


def test_csv_input_to_bag(tmp_path):
    out = run("estimate", "--example", "--to-bag", tmp_path / "ex")
    assert out.returncode == 0, out.stderr
    assert out.stdout == ""  # the bag is the output
    with AnyReader([tmp_path / "ex"], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        assert reader.topics["/softtip/wrench_raw"].msgcount == 500
        frames = {reader.deserialize(raw, c.msgtype).header.frame_id for c, _, raw in reader.messages() if c.topic != TOPICS["state"]
                  and c.msgtype != "std_msgs/msg/String" and c.msgtype != "visualization_msgs/msg/MarkerArray"}
    assert frames == {"ft_sensor"}  # a CSV has no frame: RViz needs one


def test_a_ros_export_keeps_its_stamps_in_the_bag(tmp_path):
    """A ``rostopic echo -p`` export's header stamps (ns since the epoch) are the bag's message
    stamps, as from the bag it was exported from: the robot's other logs still line up."""
    src = Path(__file__).parent / "data" / "foreign" / "rostopic_echo_p.csv"
    stamps = read_log(src).stamps_ns
    out = run("estimate", src, "--to-bag", tmp_path / "b", "-q")
    assert out.returncode == 0, out.stderr
    with AnyReader([tmp_path / "b"], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        raw = [(ts, reader.deserialize(m, c.msgtype)) for c, ts, m in reader.messages() if c.topic == "/softtip/wrench_raw"]
    np.testing.assert_array_equal([ts for ts, _ in raw], stamps)
    np.testing.assert_array_equal([m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec for _, m in raw], stamps)


# --- damaged bags, repeated stamps (issue 13, items 11 and 13) ----------------------------


def _with_t(example, t):
    from types import SimpleNamespace

    return SimpleNamespace(t=np.asarray(t), wrench=example.wrench)


def test_repeated_stamps_are_kept_and_counted_and_a_stamp_going_back_is_an_error(tmp_path, example):
    t = example.t.copy()
    t[100] = t[99]  # a driver that stamped two samples alike
    log = read_bag(write_bag2(tmp_path / "dup", _with_t(example, t), StoragePlugin.MCAP))
    assert len(log.t) == len(example.t) and log.repeated_stamps == 1
    np.testing.assert_array_equal(log.wrench, example.wrench)
    t[200] = t[198]  # a header stamp back in time (recorded in order)
    ts = get_typestore(Stores.ROS2_HUMBLE)
    with Writer(tmp_path / "back", version=9, storage_plugin=StoragePlugin.MCAP) as w:
        c = w.add_connection("/ft_sensor/wrench", WRENCH, typestore=ts)
        for k, (_, msg) in enumerate(wrench_msgs(ts, _with_t(example, t))):
            w.write(c, T0_NS + k, ts.serialize_cdr(msg, WRENCH))
    with pytest.raises(InputError, match=r"message 201 has time .* before message 200 .*non-decreasing"):
        read_bag(tmp_path / "back")


def _drop_half_of_the_rows(bag):
    import sqlite3

    (db,) = bag.glob("*.db3")
    with sqlite3.connect(db) as con:
        con.execute("DELETE FROM messages WHERE id % 2 = 0 AND topic_id = (SELECT id FROM topics WHERE name = '/ft_sensor/wrench')")
    con.close()


def _skip_one_mcap_record(bag, stamp_ns):
    """Damage the opcode of the MCAP message record logged at ``stamp_ns``: readers skip it."""
    import struct

    (mcap,) = bag.glob("*.mcap")
    data = bytearray(mcap.read_bytes())
    at = data.find(struct.pack("<Q", stamp_ns) * 2)  # log_time, publish_time
    opcode = at - 15  # opcode (1), record length (8), channel id (2), sequence (4)
    assert at > 0 and data[opcode] == 0x05
    data[opcode] = 0x7E
    mcap.write_bytes(bytes(data))


@pytest.mark.parametrize("kind", ["sqlite3", "mcap"])
def test_damaged_bag_stops_unless_allow_partial(tmp_path, example, kind):
    if kind == "sqlite3":
        bag = write_bag2(tmp_path / "b", example, StoragePlugin.SQLITE3)
        _drop_half_of_the_rows(bag)
        n = 250
    else:
        bag = write_bag2(tmp_path / "b", example, StoragePlugin.MCAP)
        _skip_one_mcap_record(bag, int(stamps_ns(example.t)[321]))
        n = 499
    out = run("estimate", bag, "-o", tmp_path / "e.csv")
    assert out.returncode == 2, out.stderr
    assert f"read {n} messages, but the bag's metadata lists 500" in out.stderr and "--allow-partial" in out.stderr
    assert not (tmp_path / "e.csv").exists()
    out = run("estimate", bag, "--allow-partial", "-o", tmp_path / "e.csv")
    assert out.returncode == 0, out.stderr
    assert f"damaged bag, {n} samples used" in out.stderr
    with open(tmp_path / "e.csv") as fh:
        assert len(fh.readlines()) == n + 1


def test_unreadable_message_stops_unless_allow_partial(tmp_path, example):
    bag = write_bag2(tmp_path / "b", example, StoragePlugin.SQLITE3, extra_topic=False)
    import sqlite3

    (db,) = bag.glob("*.db3")
    with sqlite3.connect(db) as con:
        con.execute("UPDATE messages SET data = X'00ff00ff' WHERE id = 301")
    con.close()
    with pytest.raises(InputError, match=r"cannot read message 301 .*--allow-partial uses the 300 messages before it"):
        read_bag(bag)
    log = read_bag(bag, allow_partial=True)
    assert len(log.t) == 300 and log.partial and "message 301" in log.damage
    np.testing.assert_array_equal(log.wrench, example.wrench[:300])


@pytest.mark.parametrize("count", ["-5", "10000000000000000000", "100000000000"])
def test_metadata_message_count_negative_or_huge(tmp_path, example, count):
    bag = write_bag2(tmp_path / "b", example, StoragePlugin.MCAP, extra_topic=False)
    meta = bag / "metadata.yaml"
    meta.write_text(meta.read_text().replace("message_count: 500", f"message_count: {count}"))
    out = run("estimate", bag)
    assert out.returncode == 2, out.stderr
    assert "Traceback" not in out.stderr and "metadata" in out.stderr and count in out.stderr


def test_bag_with_a_repeated_stamp_is_estimated_whole(tmp_path, example):
    t = example.t.copy()
    t[100] = t[99]
    bag = write_bag2(tmp_path / "dup", _with_t(example, t), StoragePlugin.MCAP)
    out = run("estimate", bag, "-o", tmp_path / "e.csv")
    assert out.returncode == 0, out.stderr
    assert "1 message(s) repeat the previous header.stamp" in out.stderr
    with open(tmp_path / "e.csv") as fh:
        assert len(fh.readlines()) == len(t) + 1


def test_bag_equals_the_plain_csv_and_its_ros_exports(tmp_path, example):
    """issue 28: the same samples from a rosbag2, from the CSV of their seconds and from ``ros2 topic echo
    --csv`` / ``rostopic echo -p`` exports give byte-identical estimates (stamps in ns divided by an exact
    1e9 are the floats the text of the seconds gives)."""
    bag = write_bag2(tmp_path / "grasp", example, StoragePlugin.SQLITE3, extra_topic=False)
    from_bag = run("estimate", bag)
    assert from_bag.returncode == 0, from_bag.stderr
    st = stamps_ns(example.t)
    plain = tmp_path / "plain.csv"
    write_table({"t": example.t, **{n: example.wrench[:, i] for i, n in enumerate(["fx", "fy", "fz", "mx", "my", "mz"])}},
                plain, float_format="%.17g")  # fmt: skip
    from_csv = run("estimate", plain)
    assert from_csv.returncode == 0, from_csv.stderr
    ros2 = tmp_path / "echo.csv"
    ros2.write_text("".join(
        f"{s // 10**9},{s % 10**9},ft_link,{','.join(repr(v) for v in w)}\n" for s, w in zip(st.tolist(), example.wrench.tolist())
    ))  # fmt: skip
    from_echo = run("estimate", ros2)
    assert from_echo.returncode == 0, from_echo.stderr

    def table(text):  # the estimates' columns, without the input's extra ones
        rows = list(csv.reader(text.splitlines()))
        keep = [j for j, name in enumerate(rows[0]) if name not in ("stamp_ns", "header.frame_id")]
        return [[r[j] for j in keep] for r in rows]

    assert table(from_bag.stdout) == table(from_csv.stdout) == table(from_echo.stdout)
