"""Bags a ROS distribution plays (softtip.ros.bagout): metadata version, storage and sqlite3
schema checked against excerpts of ros2/rosbag2's sources (tests/data/rosbag2/<branch>.txt);
ROS 1 bags; markers; frame_id; gravity from /tf. No ROS installation is used."""

import csv
import re
import sqlite3
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

pytest.importorskip("rosbags")
from rosbags.highlevel import AnyReader
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore
from ruamel.yaml import YAML
from scipy.spatial.transform import Rotation

import softtip.ros as sr
from softtip import estimate, load_example
from softtip.errors import InputError
from softtip.io.bag import TOPICS, write_estimates_bag
from softtip.ros.bagout import DISTROS, BagWriter, bag_format
from softtip.ros.fused import (
    FUSED_TOPICS,
    fused_markers,
    fused_poses,
    quaternions_from_axes,
    write_fused_bag,
)

SOFTTIP = str(Path(sys.executable).with_name("softtip"))
REFERENCE = Path(__file__).parent / "data" / "rosbag2"
T0_NS = 1_700_000_000_000_000_000
WRENCH = "geometry_msgs/msg/WrenchStamped"


def run(*args):
    return subprocess.run([SOFTTIP, *map(str, args)], capture_output=True, text=True, timeout=120)


def reference(distro):
    """Facts of one rosbag2 branch: metadata version, default storage, sqlite3 schema."""
    text = (REFERENCE / f"{distro}.txt").read_text()
    version = int(re.search(r"int version = (\d+);", text).group(1))
    storage = re.search(r'return "(\w+)";', text).group(1)
    schema_version = int(re.search(r"kDBSchemaVersion_ = (\d+);", text).group(1))
    body = text[text.index("SqliteStorage::initialize") :]
    statements, current = [], ""
    for piece in re.findall(r'"((?:[^"\\]|\\.)*)"', body):
        current += piece
        if current.endswith(";"):
            statements.append(current)
            current = ""
    return version, storage, schema_version, [s for s in statements if s.startswith("CREATE")]


def reader(path):
    return AnyReader([Path(path)], default_typestore=get_typestore(Stores.ROS2_HUMBLE))


@pytest.fixture(scope="module")
def example_estimates():
    log = load_example()
    return log, estimate(log.t, log.wrench, "murakami2006")


@pytest.fixture(scope="module")
def bags(tmp_path_factory, example_estimates):
    log, est = example_estimates
    root = tmp_path_factory.mktemp("bags")
    stamps = T0_NS + np.rint(log.t * 1e9).astype(np.int64)
    out = {}
    for distro in DISTROS:
        path = root / (f"{distro}.bag" if distro == "noetic" else distro)
        write_estimates_bag(path, est, log.wrench, stamps, distro=distro)
        out[distro] = path
    return out


@pytest.mark.parametrize("distro", ["humble", "iron", "jazzy", "rolling"])
def test_rosbag2_metadata_is_the_distributions(bags, distro):
    version, storage, _, _ = reference(distro)
    fmt = DISTROS[distro]
    assert (fmt.metadata_version, fmt.storage) == (version, storage)
    meta = YAML(typ="safe").load((bags[distro] / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert meta["version"] == version and meta["storage_identifier"] == storage
    files = [p.name for p in bags[distro].iterdir() if p.name != "metadata.yaml"]
    assert meta["relative_file_paths"] == files and [f["path"] for f in meta["files"]] == files
    assert Path(files[0]).suffix == {"sqlite3": ".db3", "mcap": ".mcap"}[storage]
    # the fields each branch's rosbag2_storage decodes for this version, with their types
    for topic in meta["topics_with_message_count"]:
        qos = topic["topic_metadata"]["offered_qos_profiles"]
        assert isinstance(qos, list if version >= 9 else str)  # Humble and Iron parse a string
        assert ("type_description_hash" in topic["topic_metadata"]) == (version >= 7)
        if version >= 7:
            assert topic["topic_metadata"]["type_description_hash"].startswith("RIHS01_")
    assert ("custom_data" in meta) == (version >= 6)
    assert meta.get("ros_distro") == (distro if version >= 8 else None)
    assert meta["message_count"] == sum(t["message_count"] for t in meta["topics_with_message_count"])


@pytest.mark.parametrize("distro", ["iron", "jazzy", "rolling"])
def test_mcap_files_read_with_the_mcap_library(bags, example_estimates, distro):
    """An independent reader (Foxglove's mcap and mcap-ros2-support, which decode with the
    message definitions in the file): CRCs, the ros2 profile, encodings, the QoS string of the
    metadata version, every message."""
    pytest.importorskip("mcap_ros2")
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    _, est = example_estimates
    version = DISTROS[distro].metadata_version
    (path,) = bags[distro].glob("*.mcap")
    with path.open("rb") as fh:
        r = make_reader(fh, decoder_factories=[DecoderFactory()], validate_crcs=True)
        assert r.get_header().profile == "ros2"
        summary = r.get_summary()
        for channel in summary.channels.values():
            assert channel.message_encoding == "cdr" and summary.schemas[channel.schema_id].encoding == "ros2msg"
            assert channel.metadata["offered_qos_profiles"] == ("[]" if version >= 9 else "")
        states = [m.data for _, _, _, m in r.iter_decoded_messages(topics=[TOPICS["state"]])]
        points = [m for _, _, _, m in r.iter_decoded_messages(topics=[TOPICS["contact_point"]])]
    assert states == est.state_names.tolist()
    contact = est.state != 0
    np.testing.assert_array_equal([[p.point.x, p.point.y, p.point.z] for p in points], est.point[contact])
    assert {p.header.frame_id for p in points} == {"ft_sensor"}


def test_humble_messages_decode_with_the_mcap_library(bags, example_estimates):
    """The CDR payloads of the Humble database decoded by mcap-ros2-support, with the message
    definitions the Jazzy MCAP file carries (these types have the same fields in both)."""
    pytest.importorskip("mcap_ros2")
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    _, est = example_estimates
    (path,) = bags["jazzy"].glob("*.mcap")
    with path.open("rb") as fh:
        schemas = {s.name: s for s in make_reader(fh).get_summary().schemas.values()}
    factory = DecoderFactory()
    (db,) = bags["humble"].glob("*.db3")
    with sqlite3.connect(db) as con:
        rows = con.execute(
            "SELECT topics.name, topics.type, data FROM messages JOIN topics ON messages.topic_id = topics.id "
            "ORDER BY messages.timestamp, messages.id"
        ).fetchall()
    decoded = {}
    for topic, msgtype, data in rows:
        decoder = factory.decoder_for("cdr", schemas[msgtype])
        decoded.setdefault(topic, []).append(decoder(data))
    assert [m.data for m in decoded[TOPICS["state"]]] == est.state_names.tolist()
    marker = decoded[sr.MARKER_TOPIC][-1].markers[0]
    assert marker.header.frame_id == "ft_sensor" and marker.ns == "contact_point"


def test_humble_sqlite_schema_is_rosbag2_humbles(bags):
    _, _, schema_version, statements = reference("humble")
    assert len(statements) == 5
    db = next(bags["humble"].glob("*.db3"))
    with sqlite3.connect(db) as got, sqlite3.connect(":memory:") as want:
        for stmt in statements:
            want.execute(stmt)
        listing = "SELECT type, name, tbl_name, sql FROM sqlite_master ORDER BY name"
        assert got.execute(listing).fetchall() == want.execute(listing).fetchall()
        assert got.execute("SELECT schema_version, ros_distro FROM schema").fetchall() == [(schema_version, "humble")]
        topics = got.execute("SELECT name, type, serialization_format, offered_qos_profiles FROM topics").fetchall()
    assert ("/softtip/state", "std_msgs/msg/String", "cdr", "") in topics


@pytest.mark.parametrize("distro", list(DISTROS))
def test_every_format_reads_back_the_same(bags, example_estimates, distro):
    log, est = example_estimates
    states, raw, frames, ts = [], [], set(), []
    with reader(bags[distro]) as r:
        for conn, t, data in r.messages():
            msg = r.deserialize(data, conn.msgtype)
            if conn.topic == TOPICS["state"]:
                states.append(msg.data)
            elif conn.topic == "/softtip/wrench_raw":
                raw.append([msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z,
                            msg.wrench.torque.x, msg.wrench.torque.y, msg.wrench.torque.z])  # fmt: skip
                ts.append((t, msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec))
            if hasattr(msg, "header"):
                frames.add(msg.header.frame_id)
    assert states == est.state_names.tolist()
    np.testing.assert_array_equal(raw, log.wrench)
    assert all(a == b for a, b in ts) and ts[0][0] == T0_NS
    assert frames == {"ft_sensor"}
    if distro == "noetic":
        data = bags[distro].read_bytes()
        assert bags[distro].is_file() and data[:13] == b"#ROSBAG V2.0\n"
        # ROS 1 names and md5sums, as `rosmsg md5` gives them on Noetic
        md5 = dict(re.findall(rb"type=([\w/]+).{1,8}?md5sum=([0-9a-f]{32})", data, re.S))
        assert {k.decode(): v.decode() for k, v in md5.items()} == {
            "geometry_msgs/WrenchStamped": "d78d3cb249ce23087ade7e7d0c40cfa7",
            "geometry_msgs/PointStamped": "c63aecb41bfdfd6b7e1fac37c7cbe7bf",
            "geometry_msgs/Vector3Stamped": "7b324c7325e683bf02a9b14b01090ec7",
            "std_msgs/String": "992ce8a1687cec8c8bd883ec73ca41d1",
            "visualization_msgs/MarkerArray": "d155b9ce5188fbaf89745847fd5882d7",
        }


def test_markers_in_the_bag_follow_the_state(bags, example_estimates):
    _, est = example_estimates
    names = est.state_names
    with reader(bags["humble"]) as r:
        arrays = [r.deserialize(d, c.msgtype) for c, _, d in r.messages() if c.topic == sr.MARKER_TOPIC]
    assert len(arrays) == len(est)  # a 50 Hz log: every sample
    for k in (0, int(np.flatnonzero(names == "point")[0]), int(np.flatnonzero(names == "line")[-1])):
        ms = arrays[k].markers
        assert [(m.ns, m.id) for m in ms] == [("contact_point", 0), ("normal", 1), ("edge_direction", 2)]
        assert {m.header.frame_id for m in ms} == {"ft_sensor"}
        actions = [m.action for m in ms]
        if names[k] == "none":
            assert actions == [sr.MARKER_DELETE] * 3
        else:
            assert actions[:2] == [sr.MARKER_ADD] * 2
            assert actions[2] == (sr.MARKER_ADD if names[k] == "line" else sr.MARKER_DELETE)
            sphere = ms[0].pose.position
            np.testing.assert_allclose((sphere.x, sphere.y, sphere.z), est.point[k], rtol=1e-12)
            assert ms[0].type == sr.MARKER_SPHERE and ms[1].type == sr.MARKER_ARROW
            tail, head = ([p.x, p.y, p.z] for p in ms[1].points)
            np.testing.assert_allclose(np.subtract(head, tail) / np.linalg.norm(np.subtract(head, tail)), est.normal[k], atol=1e-12)
        if names[k] == "line":
            a, b = (np.array([p.x, p.y, p.z]) for p in ms[2].points)
            np.testing.assert_allclose((b - a) / np.linalg.norm(b - a), est.direction[k], atol=1e-12)


def test_markers_are_thinned_to_their_rate_but_follow_every_state_change(tmp_path, example_estimates):
    log, est = example_estimates
    stamps = T0_NS + np.rint(log.t * 1e9).astype(np.int64)
    write_estimates_bag(tmp_path / "b", est, log.wrench, stamps, marker_rate=7.0)
    with reader(tmp_path / "b") as r:
        got = {t: r.deserialize(d, c.msgtype) for c, t, d in r.messages() if c.topic == sr.MARKER_TOPIC}
    changes = stamps[1:][np.diff(est.state) != 0]
    period = (stamps - stamps[0]) // (1e9 / 7.0)
    starts = stamps[np.r_[True, np.diff(period) != 0]]
    assert set(got) == set(changes) | set(starts) and len(changes) >= 2
    assert len(got) < len(est) / 5
    names = dict(zip(stamps.tolist(), est.state_names.tolist()))
    for t in changes.tolist():  # the sphere appears and disappears with the contact
        assert (got[t].markers[0].action == sr.MARKER_ADD) == (names[t] != "none")
    with pytest.raises(ValueError, match="marker_rate"):
        write_estimates_bag(tmp_path / "c", est, log.wrench, stamps, marker_rate=0.0)


def test_contact_markers_delete_what_is_undefined():
    r, n, d = (0.001, 0.0, 0.01), (0.0, 0.0, 1.0), (1.0, 0.0, 0.0)
    assert [m.action for m in sr.contact_markers(None, None, None)] == [sr.MARKER_DELETE] * 3
    assert [m.action for m in sr.contact_markers(r, n, None)] == [sr.MARKER_ADD, sr.MARKER_ADD, sr.MARKER_DELETE]
    sphere, arrow, line = sr.contact_markers(r, n, d, normal_length=0.02, edge_length=0.01)
    assert sphere.position == r and arrow.points == (r, (0.001, 0.0, 0.03))
    np.testing.assert_allclose(line.points, [(-0.004, 0.0, 0.01), (0.006, 0.0, 0.01)], atol=1e-15)


def test_bag_format_follows_the_name_and_refuses_a_mismatch(tmp_path):
    assert bag_format(tmp_path / "out").distro == "humble"
    assert bag_format(tmp_path / "out.bag").distro == "noetic"
    assert bag_format(tmp_path / "out", "jazzy").storage == "mcap"
    with pytest.raises(InputError, match="ROS 1 bag, but --ros-distro jazzy"):
        bag_format(tmp_path / "out.bag", "jazzy")
    with pytest.raises(InputError, match="expected a name ending in .bag"):
        bag_format(tmp_path / "out", "noetic")
    with pytest.raises(InputError, match="unknown; expected one of humble"):
        bag_format(tmp_path / "out", "foxy")


def test_a_failed_write_leaves_nothing(tmp_path):
    with pytest.raises(RuntimeError), BagWriter(tmp_path / "b", "humble") as bag:
        bag.add_topic("/x", "std_msgs/msg/String")
        raise RuntimeError("stop")
    assert list(tmp_path.iterdir()) == []


# --- the CLI --------------------------------------------------------------------------------


def test_cli_distro_and_frame_id(tmp_path):
    out = run("estimate", "--example", "--to-bag", tmp_path / "j", "--ros-distro", "jazzy", "--frame-id", "tip_link")
    assert out.returncode == 0, out.stderr
    meta = YAML(typ="safe").load((tmp_path / "j" / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert (meta["version"], meta["storage_identifier"]) == (9, "mcap")
    with reader(tmp_path / "j") as r:
        frames = {r.deserialize(d, c.msgtype).header.frame_id for c, _, d in r.messages() if c.msgtype != "std_msgs/msg/String"
                  and c.topic != sr.MARKER_TOPIC}  # fmt: skip
    assert frames == {"tip_link"}
    out = run("estimate", "--example", "--to-bag", tmp_path / "one.bag", "-q")
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "one.bag").read_bytes()[:13] == b"#ROSBAG V2.0\n"
    with reader(tmp_path / "one.bag") as r:  # the log moved to start at ros::TIME_MIN, stamps and record times alike
        raw = [(t, r.deserialize(d, c.msgtype).header.stamp) for c, t, d in r.messages() if c.topic == "/softtip/wrench_raw"]
    assert [t for t, _ in raw] == [st.sec * 10**9 + st.nanosec for _, st in raw] == (1 + np.rint(load_example().t * 1e9)).tolist()
    out = run("estimate", "--example", "--to-bag", tmp_path / "x.bag", "--ros-distro", "humble")
    assert out.returncode == 2 and "ROS 1 bag, but --ros-distro humble" in out.stderr, out.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["j", "one.bag"]


@pytest.mark.parametrize("distro", ["noetic", "jazzy"])
def test_a_bag_of_the_example_estimates_as_its_csv_does(tmp_path, distro):
    # a ROS 1 bag's first sample once kept header stamp 0 beside a 1 ns record time: read back,
    # the others sat 1 ns early, and the windows' edges moved angle_std_deg by up to 2.4°
    bag = tmp_path / ("x.bag" if distro == "noetic" else "x")
    assert run("estimate", "--example", "--to-bag", bag, "--ros-distro", distro, "-q").returncode == 0
    out = [run("estimate", *src, "-q", "-o", tmp_path / f"{name}.csv")
           for name, src in (("csv", ["--example"]), ("bag", [bag, "--topic", "/softtip/wrench_raw"]))]  # fmt: skip
    assert all(o.returncode == 0 for o in out), [o.stderr for o in out]
    plain, back = (list(csv.DictReader((tmp_path / f"{n}.csv").read_text().splitlines())) for n in ("csv", "bag"))
    assert set(back[0]) - set(plain[0]) == {"stamp_ns"}
    assert [{k: r[k] for k in plain[0]} for r in back] == plain  # the same text, column by column


@pytest.mark.parametrize("name", ["out.mcap", "out.bag", "out.DB3"])
def test_o_refuses_a_bags_name_and_says_to_bag(tmp_path, name):
    # -o writes tables: a bag's name used to get CSV text (exit 0), unreadable as the bag it looks like
    out = run("estimate", "--example", "-o", tmp_path / name)
    assert out.returncode == 2 and "named like a ROS bag" in out.stderr and f"--to-bag {tmp_path / name}" in out.stderr
    replay = run("stream", "--replay", load_example().source, "--speed", "0", "-o", tmp_path / name)
    assert replay.returncode == 2 and "named like a ROS bag" in replay.stderr and "--to-bag" not in replay.stderr
    assert list(tmp_path.iterdir()) == []


# --- gravity from /tf ---------------------------------------------------------------------


def _tilted_log_bag(path, log, payload, with_tf=True, tf_every=5):
    """The example grasp with a fingertip weight on a sensor that tilts about x and y over
    time (its /tf: world → wrist moving, wrist → ft_link static)."""
    from softtip.calibration.payload import Payload, payload_wrench

    n = len(log.t)
    rot = Rotation.from_euler("xy", np.stack([0.6 * np.sin(2.0 * log.t), 0.4 * np.cos(1.3 * log.t)], axis=-1))
    mount = Rotation.from_euler("z", 0.3)
    sensor = rot * mount  # ft_link in world
    x, y, z, w = sensor.as_quat().T
    q = np.stack([w, x, y, z], axis=-1)
    wrench = log.wrench + payload_wrench(q, Payload(*payload))
    ts = get_typestore(Stores.ROS2_HUMBLE)
    T = ts.types
    stamps = T0_NS + np.rint(log.t * 1e9).astype(np.int64)

    def header(ns, frame):
        return T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=int(ns // 10**9), nanosec=int(ns % 10**9)), frame_id=frame)

    def tf(ns, parent, child, r, t=(0.0, 0.0, 0.0)):
        qx, qy, qz, qw = r.as_quat()
        return T["geometry_msgs/msg/TransformStamped"](
            header=header(ns, parent), child_frame_id=child,
            transform=T["geometry_msgs/msg/Transform"](
                translation=T["geometry_msgs/msg/Vector3"](*t), rotation=T["geometry_msgs/msg/Quaternion"](qx, qy, qz, qw)
            ),
        )  # fmt: skip

    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as wr:
        cw = wr.add_connection("/ft_sensor/wrench", WRENCH, typestore=ts)
        if with_tf:
            ct = wr.add_connection("/tf", "tf2_msgs/msg/TFMessage", typestore=ts)
            cs = wr.add_connection("/tf_static", "tf2_msgs/msg/TFMessage", typestore=ts)
            wr.write(cs, int(stamps[0]), ts.serialize_cdr(T["tf2_msgs/msg/TFMessage"]([tf(int(stamps[0]), "wrist", "ft_link", mount, (0, 0, 0.05))]), "tf2_msgs/msg/TFMessage"))
        v = T["geometry_msgs/msg/Vector3"]
        for k in range(n):
            ns = int(stamps[k])
            if with_tf and k % tf_every == 0:  # /tf at a fraction of the wrench rate: interpolated
                wr.write(ct, ns, ts.serialize_cdr(T["tf2_msgs/msg/TFMessage"]([tf(ns, "world", "wrist", rot[k], (0.3, 0, 0.5))]), "tf2_msgs/msg/TFMessage"))
            msg = T[WRENCH](header=header(ns, "ft_link"), wrench=T["geometry_msgs/msg/Wrench"](force=v(*wrench[k, :3]), torque=v(*wrench[k, 3:])))
            wr.write(cw, ns, ts.serialize_cdr(msg, WRENCH))
    return q


def test_gravity_from_tf_removes_the_fingertips_weight(tmp_path):
    import csv

    log = load_example()
    payload = (0.012, (0.0, 0.001, 0.008))  # 12 g, its centre 8 mm up the tip
    q = _tilted_log_bag(tmp_path / "tilt", log, payload, tf_every=1)  # /tf at every stamp: exact
    (tmp_path / "p.toml").write_text(f"[payload]\nmass = {payload[0]}\ncom = {list(payload[1])}\n")
    out = run(
        "estimate", tmp_path / "tilt", "--payload", tmp_path / "p.toml", "--gravity-frame", "world", "-o", tmp_path / "c.csv",
        "--to-bag", tmp_path / "c_bag", "--frame-id", "sensor_2",
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    _tilted_log_bag(tmp_path / "weightless", log, (0.0, (0.0, 0.0, 0.0)))
    plain = run("estimate", tmp_path / "weightless", "-o", tmp_path / "e.csv", "--to-bag", tmp_path / "e_bag")
    assert plain.returncode == 0, plain.stderr

    def rows(name):
        return list(csv.DictReader((tmp_path / name).read_text().splitlines()))

    comp, ref = rows("c.csv"), rows("e.csv")
    fz = np.array([[float(r["fz"]) for r in x] for x in (comp, ref)])
    # the weight's change along z with the tilt, which the tare does not remove, ~0.02 N
    from softtip.calibration.payload import Payload, payload_wrench

    weight_fz = payload_wrench(q, Payload(*payload))[:, 2]
    assert np.ptp(weight_fz) > 0.015
    assert np.nanmax(np.abs(fz[0] - fz[1])) < 1e-6  # removed to rounding
    assert [r["state"] for r in comp] == [r["state"] for r in ref]
    # a bag input keeps its frame_id in the output bag unless --frame-id gives another
    for name, frame in (("e_bag", "ft_link"), ("c_bag", "sensor_2")):
        with reader(tmp_path / name) as r:
            frames = {r.deserialize(d, c.msgtype).header.frame_id for c, _, d in r.messages() if c.topic == TOPICS["contact_point"]}
        assert frames == {frame}


def test_gravity_orientations_interpolate_tf(tmp_path):
    from softtip.fusion.tf import gravity_orientations
    from softtip.io.bag import read_bag

    log = load_example()
    for every, tolerance_deg in ((1, 1e-5), (2, 1.0)):  # /tf at 50 and 25 Hz, the sensor turning up to ~1.3 rad/s
        path = tmp_path / f"tf{every}"
        q = _tilted_log_bag(path, log, (0.01, (0.0, 0.0, 0.0)), tf_every=every)
        b = read_bag(path)
        got = gravity_orientations(path, "world", b.frame_ids, b.stamps_ns)
        angle = np.degrees(2 * np.arccos(np.clip(np.abs(np.sum(q * got, axis=1)), 0, 1)))
        assert angle.max() < tolerance_deg


def test_gravity_frame_errors_name_the_frames(tmp_path):
    log = load_example()
    _tilted_log_bag(tmp_path / "tilt", log, (0.01, (0.0, 0.0, 0.0)))
    _tilted_log_bag(tmp_path / "notf", log, (0.01, (0.0, 0.0, 0.0)), with_tf=False)
    (tmp_path / "p.toml").write_text("[payload]\nmass = 0.01\n")
    out = run("estimate", tmp_path / "tilt", "--payload", tmp_path / "p.toml", "--gravity-frame", "map")
    assert out.returncode == 2 and "'ft_link' is not connected to 'map'" in out.stderr, out.stderr
    from softtip.fusion.tf import gravity_orientations
    from softtip.io.bag import read_bag

    b = read_bag(tmp_path / "notf")
    with pytest.raises(InputError, match="no /tf or /tf_static.*'world' → 'ft_link'"):
        gravity_orientations(tmp_path / "notf", "world", b.frame_ids, b.stamps_ns)
    with pytest.raises(InputError, match="empty header.frame_id; give the sensor frame with --frame-id"):
        gravity_orientations(tmp_path / "notf", "world", ("",), b.stamps_ns)
    with pytest.raises(InputError, match="several frame_ids"):
        gravity_orientations(tmp_path / "notf", "world", ("a", "b"), b.stamps_ns)
    out = run("estimate", "--example", "--payload", tmp_path / "p.toml", "--gravity-frame", "world")
    assert out.returncode == 2 and "--gravity-frame needs --payload and a bag INPUT" in out.stderr


# --- the fused grasp as messages -----------------------------------------------------------

HAND_X = np.array([1.0, 0.0, 0.0])
R_RIGHT = Rotation.from_matrix(np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]).T)
R_LEFT = Rotation.from_matrix(np.array([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]]).T)
vectors = st.lists(st.floats(-1.0, 1.0, allow_nan=False), min_size=3, max_size=3).filter(lambda v: np.linalg.norm(v) > 1e-3)


@settings(max_examples=60, deadline=None)
@given(vectors, vectors)
def test_quaternions_from_axes(x, z):
    x, z = np.array(x), np.array(z)
    q = quaternions_from_axes(x, z)
    if np.linalg.norm(np.cross(x, z)) < 1e-6 * np.linalg.norm(x) * np.linalg.norm(z):
        return  # parallel: no z axis across x
    m = Rotation.from_quat(q).as_matrix()
    np.testing.assert_allclose(m[:, 0], x / np.linalg.norm(x), atol=1e-9)
    zp = z - (z @ m[:, 0]) * m[:, 0]
    # z across x is as well defined as the angle between them: rounding grows as 1 / sin
    sin = np.linalg.norm(np.cross(x, z)) / (np.linalg.norm(x) * np.linalg.norm(z))
    np.testing.assert_allclose(m[:, 2], zp / np.linalg.norm(zp), atol=1e-9 + 1e-12 / sin)
    # without z: any z, but the x axis is x; a batch equals its rows; NaN stays NaN
    many = quaternions_from_axes(np.stack([x, 2 * x, [np.nan] * 3]))
    for row in many[:2]:
        np.testing.assert_allclose(Rotation.from_quat(row).as_matrix()[:, 0], x / np.linalg.norm(x), atol=1e-9)
    assert np.isnan(many[2]).all()


def _synthetic_pair(right_angle, left_angle):
    from softtip.fusion import PoseSeries, fuse_logs
    from softtip.sim.synthetic import synthetic_grasp

    logs = []
    for name, rot, angle, seed in (("right", R_RIGHT, right_angle, 1), ("left", R_LEFT, left_angle, 2)):
        g = synthetic_grasp(angle_deg=angle, seed=seed, tangential_ratio=0.0)
        side = 1.0 if name == "right" else -1.0
        logs.append((name, g.t, g.wrench, PoseSeries.fixed(rot, side * 0.015 * HAND_X - rot.apply(g.point), name)))
    return (*fuse_logs(logs, "murakami2006"), logs)


@pytest.mark.parametrize("angles, grasp", [((30.0, -30.0), "parallel_lines"), ((45.0, 45.0), "crossing_lines")])
def test_fused_bag_carries_the_line_and_plane_as_poses(tmp_path, angles, grasp):
    fused, fingers, _ = _synthetic_pair(*angles)
    stamps = T0_NS + np.rint(fused.t * 1e9).astype(np.int64)
    write_fused_bag(tmp_path / "f", fused, fingers, stamps, "palm", distro="iron")
    got = {}
    with reader(tmp_path / "f") as r:
        for c, t, d in r.messages():
            got.setdefault(c.topic, []).append((t, r.deserialize(d, c.msgtype)))
    names = fused.grasp_names
    assert [m.data.split()[0] for _, m in got[FUSED_TOPICS["grasp"]]] == names.tolist()
    assert len(got[FUSED_TOPICS["markers"]]) == len(fused)
    k = int(np.flatnonzero(names == grasp)[-1])
    stamp = int(stamps[k])
    line = dict(got[FUSED_TOPICS["line"]])[stamp]
    assert line.header.frame_id == "palm"
    o = line.pose.orientation
    axes = Rotation.from_quat([o.x, o.y, o.z, o.w]).as_matrix()
    assert abs(axes[:, 0] @ fused.direction[k]) == pytest.approx(1.0, abs=1e-9)
    p = line.pose.position
    if grasp == "parallel_lines":
        np.testing.assert_allclose([p.x, p.y, p.z], 0.5 * (fused.point_a[k] + fused.point_b[k]), atol=1e-12)
        plane = dict(got[FUSED_TOPICS["plane"]])[stamp].pose.orientation
        z = Rotation.from_quat([plane.x, plane.y, plane.z, plane.w]).as_matrix()[:, 2]
        assert abs(z @ fused.plane_normal[k]) == pytest.approx(1.0, abs=1e-9)
        assert len(got[FUSED_TOPICS["plane"]]) == np.count_nonzero(names == "parallel_lines")
        assert FUSED_TOPICS["line2"] not in got
    else:
        np.testing.assert_allclose([p.x, p.y, p.z], fused.point_a[k], atol=1e-12)
        second = dict(got[FUSED_TOPICS["line2"]])[stamp].pose.orientation
        x2 = Rotation.from_quat([second.x, second.y, second.z, second.w]).as_matrix()[:, 0]
        assert abs(x2 @ fused.direction_b[k]) == pytest.approx(1.0, abs=1e-9)
        assert FUSED_TOPICS["plane"] not in got
    ms = dict(got[FUSED_TOPICS["markers"]])[stamp].markers
    assert [m.ns for m in ms] == ["contact_a", "contact_b", "line", "line2", "plane"]
    assert [m.action == sr.MARKER_ADD for m in ms] == [True, True, True, grasp == "crossing_lines", grasp == "parallel_lines"]


def test_fused_markers_without_contact_are_deleted():
    fused, fingers, _ = _synthetic_pair(30.0, -30.0)
    poses = fused_poses(fused, fingers[0].estimates.state_names == "line")
    k = int(np.flatnonzero(fused.grasp_names == "none")[0])
    assert [m.action for m in fused_markers(poses, k)] == [sr.MARKER_DELETE] * 5


def test_fuse_command_writes_a_bag(tmp_path):
    from softtip.io.tables import write_table

    _, _, logs = _synthetic_pair(30.0, -30.0)
    hand = ['[hand]\nframe = "palm"\n']
    for name, t, w, pose in logs:
        cols = {"t": t, **{c: w[:, i] for i, c in enumerate(["fx", "fy", "fz", "mx", "my", "mz"])}}
        write_table(cols, tmp_path / f"{name}.csv", float_format="%.17g")
        rot, tr = pose.at(np.array([0.0]))
        (qx, qy, qz, qw), tr = rot.as_quat()[0].tolist(), tr[0].tolist()
        hand.append(f"[finger.{name}]\ntranslation = [{tr[0]!r}, {tr[1]!r}, {tr[2]!r}]\nquaternion = [{qw!r}, {qx!r}, {qy!r}, {qz!r}]\n")
    (tmp_path / "hand.toml").write_text("\n".join(hand))
    args = ("fuse", tmp_path / "right.csv", tmp_path / "left.csv", "--hand", tmp_path / "hand.toml")
    out = run(*args, "--to-bag", tmp_path / "fused.bag")
    assert out.returncode == 0, out.stderr
    assert out.stdout == ""  # the bag is the output
    with reader(tmp_path / "fused.bag") as r:
        assert set(r.topics) >= {FUSED_TOPICS["grasp"], FUSED_TOPICS["line"], FUSED_TOPICS["plane"], FUSED_TOPICS["markers"]}
        frames = {r.deserialize(d, c.msgtype).header.frame_id for c, _, d in r.messages() if c.topic == FUSED_TOPICS["line"]}
    assert frames == {"palm"}
    out = run(*args, "--ros-distro", "jazzy")
    assert out.returncode == 2 and "apply to --to-bag" in out.stderr


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX file size limit")
@pytest.mark.parametrize("name, distro", [("b", "jazzy"), ("b.bag", None)])
def test_a_bag_that_cannot_be_written_says_why_and_leaves_nothing(tmp_path, name, distro):
    import resource
    import signal

    def limit():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (30_000, 30_000))

    extra = ("--ros-distro", distro) if distro else ()
    out = subprocess.run(
        [SOFTTIP, "estimate", "--example", "-q", "--to-bag", str(tmp_path / name), *extra],
        capture_output=True, text=True, timeout=120, preexec_fn=limit,
    )  # fmt: skip
    assert out.returncode == 2 and "cannot write the bag (File too large)" in out.stderr and "Traceback" not in out.stderr
    assert list(tmp_path.iterdir()) == []
