"""The softtip ROS 2 node: ``python -m softtip.ros`` in a sourced ROS 2 environment.

Subscribes to a ``geometry_msgs/msg/WrenchStamped`` topic, runs the streaming estimator on
every message (about 25 µs each in CPython) and publishes the topics of :data:`softtip.ros.TOPICS` and
RViz markers on :data:`softtip.ros.MARKER_TOPIC` (with each line its direction's standard
deviation, ``angle_std`` in rad, and its ``line_evidence``); the service ``~/tare``
(``std_srvs/srv/Trigger``) re-tares from the next samples (keep the fingertip untouched).

Parameters (``--ros-args -p name:=value``), see :data:`PARAMETERS`.

rclpy comes with ROS 2, not from PyPI, so it is imported only when the node starts. The node is
a thin shell over :mod:`softtip.ros` (messages as plain data) and
:func:`config_from_parameters`, which are tested without ROS; the shell itself has not been
run against a ROS 2 installation by softtip's tests.
"""

from __future__ import annotations

from typing import Any

from softtip.core.noise import NANO17, SensorNoise
from softtip.estimator import EstimatorConfig

__all__ = ["PARAMETERS", "config_from_parameters", "main"]

#: Node parameters and their defaults.
PARAMETERS: dict[str, Any] = {
    "tip": "murakami2006",  # preset name or fingertip TOML path
    "wrench_topic": "/ft_sensor/wrench",
    "frame_id": "",  # "" → the input's frame_id, or "ft_sensor" when that is empty
    "contact_point": "latch",  # latch | track | line-fit (joint: its former name)
    "lowpass_hz": 0.0,  # 0 → no filter
    "sample_rate": 0.0,  # Hz; needed with lowpass_hz
    "tare_duration": 0.2,  # s
    "force_noise": 0.0,  # N per axis; 0 → Nano17-class default
    "moment_noise": 0.0,  # N·m per axis; 0 → Nano17-class default
    "noise_from_tare": False,  # measure the noise model from the tare (≥ 30 samples)
    "publish_markers": True,
    "payload": "",  # payload TOML (softtip calibrate-payload): remove the fingertip's weight
    "orientation_topic": "",  # geometry_msgs/msg/QuaternionStamped: the sensor frame in a z-up world
}


def config_from_parameters(params: dict[str, Any]) -> EstimatorConfig:
    """The estimator settings from node parameters (unknown names are an error).

    Raises
    ------
    ValueError
        An unknown parameter or a value out of range, naming the parameter.
    """
    unknown = set(params) - set(PARAMETERS)
    if bool(params.get("payload")) != bool(params.get("orientation_topic")):
        raise ValueError("payload and orientation_topic go together: the weight's direction needs the orientation")
    if unknown:
        raise ValueError(f"unknown parameter(s) {', '.join(sorted(unknown))}; expected some of {', '.join(PARAMETERS)}")
    p = {**PARAMETERS, **params}
    lowpass = float(p["lowpass_hz"])
    rate = float(p["sample_rate"])
    if lowpass < 0 or rate < 0:
        raise ValueError("lowpass_hz and sample_rate must be non-negative (0: off / unknown)")
    if lowpass > 0 and rate <= 0:
        raise ValueError("lowpass_hz needs sample_rate (Hz) for the streaming filter")
    force_noise, moment_noise = float(p["force_noise"]), float(p["moment_noise"])
    if force_noise < 0 or moment_noise < 0:
        raise ValueError("force_noise and moment_noise must be non-negative (0: the Nano17-class default)")
    if not isinstance(p["noise_from_tare"], bool):
        raise ValueError(f"noise_from_tare must be true or false, got {p['noise_from_tare']!r}")
    noise = SensorNoise(
        force_std=(force_noise,) * 3 if force_noise > 0 else NANO17.force_std,
        moment_std=(moment_noise,) * 3 if moment_noise > 0 else NANO17.moment_std,
    )
    return EstimatorConfig(
        contact_point=str(p["contact_point"]),
        lowpass_hz=lowpass if lowpass > 0 else None,
        sample_rate=rate if rate > 0 else None,
        tare_duration=float(p["tare_duration"]),
        noise=noise,
        noise_from_tare=p["noise_from_tare"],
    )


def main(args: list[str] | None = None) -> None:  # pragma: no cover - needs a ROS 2 installation
    """Run the node until shut down."""
    try:
        import rclpy
        from geometry_msgs.msg import PointStamped, QuaternionStamped, Vector3Stamped, WrenchStamped
        from rclpy.node import Node
        from std_msgs.msg import Float64, String
        from std_srvs.srv import Trigger
        from visualization_msgs.msg import Marker as MarkerMsg
        from visualization_msgs.msg import MarkerArray
    except ImportError as exc:
        raise SystemExit(
            f"softtip.ros needs ROS 2 (rclpy and the geometry_msgs, std_msgs, std_srvs, visualization_msgs "
            f"packages): source your ROS 2 installation first ({exc})"
        ) from None
    import softtip.ros as sr
    from softtip.estimator import Estimator
    from softtip.estimator.columns import TOPICS as COLUMN_TOPICS

    class SofttipNode(Node):
        def __init__(self):
            super().__init__("softtip")
            for name, default in PARAMETERS.items():
                self.declare_parameter(name, default)
            params = {name: self.get_parameter(name).value for name in PARAMETERS}
            self.estimator = Estimator(params["tip"], config_from_parameters(params))
            self.frame_id = params["frame_id"]
            self.publish_markers = bool(params["publish_markers"])
            types = {"geometry_msgs/msg/WrenchStamped": WrenchStamped, "std_msgs/msg/String": String,
                     "geometry_msgs/msg/PointStamped": PointStamped, "geometry_msgs/msg/Vector3Stamped": Vector3Stamped,
                     "std_msgs/msg/Float64": Float64}  # fmt: skip
            self.pub = {t.key: self.create_publisher(types[t.msgtype], t.name, 10) for t in COLUMN_TOPICS}
            self.pub["markers"] = self.create_publisher(MarkerArray, sr.MARKER_TOPIC, 10)
            self.compensate = self.orientation = None
            if params["payload"]:
                from softtip.core.gravity import PayloadCompensator, load_payload

                self.compensate = PayloadCompensator(load_payload(params["payload"]))
                self.create_subscription(QuaternionStamped, params["orientation_topic"], self.on_orientation, 10)
            self.create_subscription(WrenchStamped, params["wrench_topic"], self.on_wrench, 100)
            self.create_service(Trigger, "~/tare", self.on_tare)

        def on_tare(self, request, response):
            self.estimator.tare()
            response.success = True
            response.message = "re-taring from the next samples: keep the fingertip untouched"
            return response

        def on_orientation(self, msg):
            q = msg.quaternion
            self.orientation = (q.w, q.x, q.y, q.z)

        def on_wrench(self, msg):
            now = self.get_clock().now().nanoseconds * 1e-9
            t, w = sr.wrench_sample(msg, fallback_time=now)
            if self.compensate is not None:
                if self.orientation is None:
                    self.get_logger().warning("no orientation yet: sample skipped (payload compensation)", once=True)
                    return
                w = self.compensate(w, self.orientation)
            try:
                est = self.estimator.update(t, w)
            except ValueError as exc:  # time going back: a restarted bag or driver
                self.get_logger().warning(f"sample skipped: {exc}")
                return
            header = msg.header
            header.frame_id = self.frame_id or header.frame_id or sr.DEFAULT_FRAME_ID
            p = sr.payloads(est)
            self.pub["state"].publish(String(data=p.state))
            if p.wrench is not None:
                out = WrenchStamped(header=header)
                (out.wrench.force.x, out.wrench.force.y, out.wrench.force.z,
                 out.wrench.torque.x, out.wrench.torque.y, out.wrench.torque.z) = p.wrench  # fmt: skip
                self.pub["wrench"].publish(out)
            if p.contact_point is not None:
                out = PointStamped(header=header)
                out.point.x, out.point.y, out.point.z = p.contact_point
                self.pub["contact_point"].publish(out)
                out = Vector3Stamped(header=header)
                out.vector.x, out.vector.y, out.vector.z = p.normal
                self.pub["normal"].publish(out)
            if p.edge_direction is not None:
                out = Vector3Stamped(header=header)
                out.vector.x, out.vector.y, out.vector.z = p.edge_direction
                self.pub["edge_direction"].publish(out)
                self.pub["line_evidence"].publish(String(data=p.line_evidence))
                if p.angle_std is not None:
                    self.pub["angle_std"].publish(Float64(data=p.angle_std))
            if self.publish_markers:
                arr = MarkerArray()
                for m in sr.markers(est):
                    mk = MarkerMsg(header=header, ns=m.ns, id=m.id, type=m.type, action=m.action)
                    mk.pose.position.x, mk.pose.position.y, mk.pose.position.z = m.position
                    (mk.pose.orientation.x, mk.pose.orientation.y, mk.pose.orientation.z,
                     mk.pose.orientation.w) = m.orientation  # fmt: skip
                    mk.scale.x, mk.scale.y, mk.scale.z = m.scale
                    mk.color.r, mk.color.g, mk.color.b, mk.color.a = m.color
                    for x, y, z in m.points:
                        pt = type(mk.pose.position)()
                        pt.x, pt.y, pt.z = x, y, z
                        mk.points.append(pt)
                    arr.markers.append(mk)
                self.pub["markers"].publish(arr)

    rclpy.init(args=args)
    node = SofttipNode()
    try:
        rclpy.spin(node)
    except KeyboardInterrupt:
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
