"""softtip.ros: the ROS glue that needs no ROS (the node's shell needs a ROS 2 install)."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import softtip
import softtip.ros as sr
from softtip.ros.node import PARAMETERS, config_from_parameters


@given(st.integers(0, 2**31 - 1), st.integers(0, 999_999_999))
def test_stamp_round_trip(sec, nanosec):
    s, ns = sr.stamp_from_seconds(sr.seconds_from_stamp(sec, nanosec))
    assert 0 <= ns < 1_000_000_000
    # a float64 second holds a 2^31 s stamp to within 2^31 · 2^-52 s ≈ 0.5 µs
    assert abs((s - sec) * 1_000_000_000 + (ns - nanosec)) <= 512


def _wrench_msg(sec, nanosec, w):
    pytest.importorskip("rosbags")
    from rosbags.typesys import Stores, get_typestore

    T = get_typestore(Stores.ROS2_HUMBLE).types
    V = T["geometry_msgs/msg/Vector3"]
    header = T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=sec, nanosec=nanosec), frame_id="ft")
    wrench = T["geometry_msgs/msg/Wrench"](force=V(x=w[0], y=w[1], z=w[2]), torque=V(x=w[3], y=w[4], z=w[5]))
    return T["geometry_msgs/msg/WrenchStamped"](header=header, wrench=wrench)


def test_wrench_sample_reads_a_message_and_falls_back_on_a_zero_stamp():
    w = (0.1, -0.2, -3.0, 1e-3, 2e-3, -3e-4)
    t, got = sr.wrench_sample(_wrench_msg(12, 500_000_000, w))
    assert t == 12.5 and got == w
    t, _ = sr.wrench_sample(_wrench_msg(0, 0, w), fallback_time=99.25)
    assert t == 99.25
    t, _ = sr.wrench_sample(_wrench_msg(0, 0, w))
    assert t == 0.0


@pytest.fixture(scope="module")
def stream():
    log = softtip.load_example()
    return softtip.Estimator("murakami2006").process(log.t, log.wrench)


def test_payloads_publish_only_what_is_defined(stream):
    seen = set()
    for est in stream:
        p = sr.payloads(est)
        seen.add(p.state)
        assert p.state == est.state
        assert (p.wrench is None) == est.taring
        assert (p.contact_point is None) == (est.state == "none")
        assert (p.normal is None) == (est.state == "none")
        assert (p.edge_direction is None) == (est.state != "line")
        assert (p.line_evidence in ("confirmed", "unconfirmed")) == (est.state == "line")
        assert (p.angle_std is not None) == (est.state == "line" and math.isfinite(est.angle_std))
        if p.angle_std is not None:
            assert p.angle_std == est.angle_std > 0
        if p.edge_direction is not None:
            assert math.isclose(np.linalg.norm(p.edge_direction), 1.0, rel_tol=1e-12)
            assert abs(np.dot(p.edge_direction, p.normal)) < 1e-12
    assert seen == {"none", "point", "line"}


def test_markers_are_always_three_and_follow_the_estimate(stream):
    line = next(e for e in stream if e.state == "line")
    none = stream[0]
    for est in (line, none):
        ms = sr.markers(est)
        assert [(m.ns, m.id) for m in ms] == [("contact_point", 0), ("normal", 1), ("edge_direction", 2)]
    assert all(m.action == sr.MARKER_DELETE for m in sr.markers(none))
    point, normal, edge = sr.markers(line, normal_length=0.01, edge_length=0.04)
    assert point.action == normal.action == edge.action == sr.MARKER_ADD
    assert np.allclose(point.position, line.point)
    tail, head = np.array(normal.points)
    assert np.allclose(tail, line.point) and np.allclose(head - tail, 0.01 * np.array(line.normal))
    a, b = np.array(edge.points)
    assert np.allclose((a + b) / 2, line.point)
    assert np.allclose(b - a, 0.04 * np.array(line.direction))


def test_node_parameters_default_to_the_estimators_defaults():
    assert config_from_parameters({}) == softtip.EstimatorConfig()
    cfg = config_from_parameters({"lowpass_hz": 30.0, "sample_rate": 1000.0, "force_noise": 0.01})
    assert cfg.lowpass_hz == 30.0 and cfg.sample_rate == 1000.0 and cfg.noise.force_std == (0.01,) * 3
    assert set(PARAMETERS) >= {"tip", "wrench_topic", "frame_id", "lowpass_hz", "contact_point"}
    assert config_from_parameters({"noise_from_tare": True, "tare_duration": 1.0}).noise_from_tare == "on"
    assert config_from_parameters({"noise_from_tare": "off"}).noise_from_tare == "off"


@pytest.mark.parametrize(
    "params, match",
    [
        ({"lowpas_hz": 30.0}, "unknown parameter.*lowpas_hz"),
        ({"lowpass_hz": 30.0}, "sample_rate"),
        ({"lowpass_hz": -1.0}, "non-negative"),
        ({"force_noise": -0.1}, "force_noise"),
        ({"contact_point": "latched"}, "contact_point"),
        ({"noise_from_tare": "false"}, "noise_from_tare must be one of auto, on, off"),
        ({"noise_from_tare": True, "tare_duration": 0.0}, "noise_from_tare='on' needs a tare"),
        ({"line_fit_window": 0.0}, "line_fit_window must be a number > 0 s"),
        ({"fallback_samples": 2.5}, "fallback_samples must be an integer"),
        ({"latch_window": [1.0]}, "latch_window must be 2 numbers"),
        ({"latch_window": [3.0, 1.0]}, "latch_window"),
        ({"rocked": [1.0, 2.0, 3.0]}, "rocked must be pairs"),
        ({"skin_law": [2e6, 2.0]}, "skin_law must be 3 numbers"),
        ({"sensor": "nano99"}, "sensor must be one of"),
        ({"relatch_distance": -1.0}, "relatch_distance must be non-negative"),
    ],
)
def test_node_parameters_are_checked(params, match):
    with pytest.raises(ValueError, match=match):
        config_from_parameters(params)


def test_node_parameters_are_the_settings_in_si(tmp_path):
    """Every estimator setting is a parameter of its field's name, in SI (angles in rad, lengths in m),
    tuples as flat lists; the noise preset, its overrides and a bias file as the ``softtip`` options."""
    from softtip.core.depth import DepthLaw
    from softtip.core.noise import NANO25
    from softtip.estimator.tare import bias_to_toml

    bias = tmp_path / "bias.toml"
    bias.write_text(bias_to_toml([0.1, 0.2, 0.3, 1e-3, 2e-3, 3e-3], "test"))
    cfg = config_from_parameters({
        "line_fit_max_angle_std": math.radians(3.0), "relatch_distance": 3e-3, "latch_window": [1.0, 4.0],
        "rocked": [1.0, 2.0, 5.0, 6.5], "skin_law": [1e6, 1.5, 4e-3], "depth_compensation": "law",
        "sensor": "nano25", "moment_noise": 2e-5, "bias": str(bias), "line_evidence": False, "line_fit_iterations": 3,
    })  # fmt: skip
    assert cfg.line_fit_max_angle_std == math.radians(3.0) and cfg.relatch_distance == 3e-3
    assert cfg.latch_window == (1.0, 4.0) and cfg.rocked == ((1.0, 2.0), (5.0, 6.5))
    assert cfg.skin_law == DepthLaw(1e6, 1.5, 4e-3) and cfg.depth_compensation == "law"
    assert cfg.noise.force_std == NANO25.force_std and cfg.noise.moment_std == (2e-5,) * 3
    assert cfg.bias == pytest.approx((0.1, 0.2, 0.3, 1e-3, 2e-3, 3e-3))
    assert not cfg.line_evidence and cfg.line_fit_iterations == 3
    # compensation asked for without any skin law: the murakami2006 skin, as on the command line
    from softtip.core.depth import MURAKAMI2006_DEPTH

    assert config_from_parameters({"depth_compensation": "online"}).skin_law == MURAKAMI2006_DEPTH


def test_node_without_ros_says_what_to_do():
    pytest.importorskip("rosbags")
    try:
        import rclpy  # noqa: F401
    except ImportError:
        from softtip.ros.node import main

        with pytest.raises(SystemExit, match="source your ROS 2 installation"):
            main([])
    else:  # pragma: no cover - a machine with ROS 2
        pytest.skip("rclpy is installed here")


def test_payload_needs_an_orientation_topic():
    with pytest.raises(ValueError, match="payload and orientation_topic go together"):
        config_from_parameters({"payload": "payload.toml"})
    config_from_parameters({"payload": "p.toml", "orientation_topic": "/ft_sensor/orientation"})
