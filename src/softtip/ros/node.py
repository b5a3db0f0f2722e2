"""The softtip ROS 2 node: ``python -m softtip.ros`` in a sourced ROS 2 environment.

Subscribes to a ``geometry_msgs/msg/WrenchStamped`` topic, runs the streaming estimator on
every message (about 25 µs each in CPython) and publishes the topics of :data:`softtip.ros.TOPICS` and
RViz markers on :data:`softtip.ros.MARKER_TOPIC` (with each line its direction's standard
deviation, ``angle_std`` in rad, and its ``line_evidence``); the service ``~/tare``
(``std_srvs/srv/Trigger``) re-tares from the next samples (keep the fingertip untouched).

Parameters (``--ros-args -p name:=value``), see :data:`PARAMETERS`: the node's own, then one per
estimator setting, named as the field of :class:`~softtip.estimator.EstimatorConfig` (the
``softtip`` option without its dashes), in SI (angles in rad, lengths in m), generated from the
config's field metadata (:mod:`softtip.estimator.settings`).

rclpy comes with ROS 2, not from PyPI, so it is imported only when the node starts. The node is
a thin shell over :mod:`softtip.ros` (messages as plain data) and
:func:`config_from_parameters`, which are tested without ROS; the shell itself has not been
run against a ROS 2 installation by softtip's tests.
"""

from __future__ import annotations

import re
from typing import Any

from softtip.core.noise import NOISE_PRESETS, SensorNoise
from softtip.estimator import EstimatorConfig
from softtip.estimator.settings import Setting, range_text, settings_of

__all__ = ["PARAMETERS", "UNSET_PARAMETERS", "config_from_parameters", "describe_parameter", "params_yaml", "main"]

#: The node's own parameters (not estimator settings), their defaults and what they are.
NODE_PARAMETERS: dict[str, tuple[Any, str]] = {
    "tip": ("murakami2006", "preset name, or the path of a fingertip TOML file"),
    "wrench_topic": ("/ft_sensor/wrench", "geometry_msgs/msg/WrenchStamped in, SI, sensor frame"),
    "frame_id": ("", '"": the input\'s frame_id ("ft_sensor" when that is empty)'),
    "publish_markers": (True, "RViz markers on /softtip/markers"),
    "payload": ("", "payload TOML (softtip calibrate-payload): remove the fingertip's weight"),
    "orientation_topic": ("", "geometry_msgs/msg/QuaternionStamped (sensor frame in a z-up world), needed with payload"),
}

#: The parameters of the composite settings (:attr:`Setting.options`, the ``softtip`` options'
#: names): the noise preset and per-axis overrides, the bias file.
COMPOSITE_PARAMETERS: dict[str, tuple[Any, str]] = {
    "sensor": ("nano17", f"noise preset: {', '.join(NOISE_PRESETS)} (ATI class, per axis)"),
    "force_noise": (0.0, "N per axis; 0: the sensor preset's"),
    "moment_noise": (0.0, "N·m per axis; 0: the sensor preset's"),
    "bias": ("", "bias TOML file (softtip estimate --save-bias) to subtract instead of taring; \"\": tare"),
}


def _ros_default(s: Setting) -> Any:
    """A setting's default as a ROS parameter value: SI, ``0.0`` for an optional number that is
    off, tuples as flat lists of floats, ``None`` when it has no value (declared unset)."""
    default = getattr(EstimatorConfig, s.name)
    if s.kind == "float":
        return 0.0 if default is None else float(default)
    if s.kind in ("tuple", "tuples"):
        if default is None or len(default) == 0:
            return None
        return [float(v) for v in default]
    return default


def _estimator_parameters() -> dict[str, Any]:
    out: dict[str, Any] = {}
    for s in settings_of(EstimatorConfig):
        if s.kind == "composite":
            out.update({name: COMPOSITE_PARAMETERS[name][0] for name in _composite_names(s)})
        elif s.ros:
            out[s.name] = _ros_default(s)
    return out


def _composite_names(s: Setting) -> list[str]:
    return [o.removeprefix("--").replace("-", "_") for o in s.options]


_ALL = {**{k: v for k, (v, _) in NODE_PARAMETERS.items()}, **_estimator_parameters()}
#: Node parameters and their defaults: the node's own, then one per estimator setting (the field's
#: name, its SI value; see :func:`describe_parameter`) in the config's order.
PARAMETERS: dict[str, Any] = {k: v for k, v in _ALL.items() if v is not None}
#: Parameters declared without a default (a ROS 2 parameter file cannot hold an empty list):
#: name → ROS type. Unset, the setting has its default (none).
UNSET_PARAMETERS: dict[str, str] = {k: "double_array" for k, v in _ALL.items() if v is None}


def describe_parameter(name: str) -> str:
    """One line on a node parameter: what it is, its unit and range (the ROS value is SI)."""
    if name in NODE_PARAMETERS:
        return NODE_PARAMETERS[name][1]
    if name in COMPOSITE_PARAMETERS:
        return COMPOSITE_PARAMETERS[name][1]
    s = next(x for x in settings_of(EstimatorConfig) if x.name == name)
    text = re.sub(r"--([a-z][a-z-]*[a-z])", lambda m: m.group(1).replace("-", "_"), s.help)  # options → parameters
    if s.kind == "float":
        text += f" [{range_text(s)}{'; 0: none' if s.optional else ''}]"
    elif s.kind == "int":
        text += f" [{range_text(s).replace('a number', 'an integer')}]"
    elif s.kind == "choice":
        text += f" [{' | '.join(s.choices)}]"
    elif s.kind in ("tuple", "tuples"):
        parts = ", ".join(f"{p.name} {p.unit}".strip() for p in s.parts)
        text += f" [{'pairs of ' if s.kind == 'tuples' else ''}{parts}{'; unset: none' if _ALL[name] is None else ''}]"
    return text


def _yaml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return f'"{v}"'
    if isinstance(v, list):
        return "[" + ", ".join(_yaml_value(x) for x in v) + "]"
    text = repr(v)
    if isinstance(v, float) and "e" in text and "." not in text:  # 3e-05: a string to YAML 1.1 readers
        text = text.replace("e", ".0e")
    return text


def params_yaml() -> str:
    """The text of the ROS 2 package's ``config/params.yaml``: every parameter with its default and
    what it is (parameters without a default as comments). ``tests/test_ros_package.py`` keeps the
    file equal to this."""
    lines = [
        '# Parameters of the softtip node (node name "softtip"), with their defaults, SI units (angles in rad,',
        "# lengths in m): the node's own, then one per estimator setting, named as the softtip options",
        "# (--name-with-dashes). Written by softtip.ros.node.params_yaml (tests/test_ros_package.py keeps",
        "# the two equal). Override one at launch: ros2 run softtip_ros softtip_node --ros-args -p tip:=my_tip.toml",
        "softtip:",
        "  ros__parameters:",
    ]
    for name, value in _ALL.items():
        desc = describe_parameter(name).replace("\n", " ")
        if value is None:
            lines.append(f"    # {name}: []  # {desc}")
        else:
            lines.append(f"    {name}: {_yaml_value(value)}  # {desc}")
    return "\n".join(lines) + "\n"


def _number(name: str, v: Any) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ValueError(f"{name} must be a number, got {v!r}")
    return float(v)


def _setting_value(s: Setting, v: Any) -> Any:
    """A setting's value from its ROS parameter (SI), before the config checks its range."""
    if s.kind == "float":
        v = _number(s.name, v)
        if s.optional and v < 0.0:
            raise ValueError(f"{s.name} must be non-negative (0: none), got {v!r}")
        return None if s.optional and v == 0.0 else v
    if s.kind == "bool":
        if not isinstance(v, bool):
            raise ValueError(f"{s.name} must be true or false, got {v!r}")
        return v
    if s.kind == "int":
        if isinstance(v, bool) or not isinstance(v, int):
            raise ValueError(f"{s.name} must be an integer, got {v!r}")
        return v
    if s.kind == "choice":
        if isinstance(v, bool) and {"on", "off"} <= set(s.choices):  # a switch given as a bool
            return "on" if v else "off"
        return str(v)
    if s.kind in ("tuple", "tuples"):
        if v is None:
            return getattr(EstimatorConfig, s.name)
        values = [_number(s.name, x) for x in v]
        k = len(s.parts)
        if s.kind == "tuple":
            if len(values) != k:
                raise ValueError(f"{s.name} must be {k} numbers ({', '.join(p.name for p in s.parts)}), got {v!r}")
            return s.make(*values) if s.make is not None else tuple(values)
        if len(values) % k:
            raise ValueError(f"{s.name} must be pairs of numbers ({', '.join(p.name for p in s.parts)}), got {v!r}")
        return tuple(tuple(values[i : i + k]) for i in range(0, len(values), k))
    return v


def config_from_parameters(params: dict[str, Any], tip=None) -> EstimatorConfig:
    """The estimator settings from node parameters (unknown names are an error).

    Parameters
    ----------
    params : dict
        Parameter name → value, as the node read them (SI; the missing ones take
        :data:`PARAMETERS`' defaults; an unset :data:`UNSET_PARAMETERS` one may be absent or ``None``).
    tip : Fingertip, optional
        The node's fingertip, for the skin law of a depth compensation asked for
        (:func:`softtip.estimator.depth.asked_skin_law`).

    Raises
    ------
    ValueError
        An unknown parameter or a value out of range, naming the parameter.
    """
    from softtip.estimator.depth import asked_skin_law
    from softtip.estimator.tare import load_bias

    unknown = set(params) - set(_ALL)
    if bool(params.get("payload")) != bool(params.get("orientation_topic")):
        raise ValueError("payload and orientation_topic go together: the weight's direction needs the orientation")
    if unknown:
        raise ValueError(f"unknown parameter(s) {', '.join(sorted(unknown))}; expected some of {', '.join(_ALL)}")
    p = {**_ALL, **params}
    values = {}
    for s in settings_of(EstimatorConfig):
        if s.kind != "composite":
            values[s.name] = _setting_value(s, p[s.name])
    if values["lowpass_hz"] is not None and values["sample_rate"] is None:
        raise ValueError("lowpass_hz needs sample_rate (Hz) for the streaming filter")
    force_noise, moment_noise = _number("force_noise", p["force_noise"]), _number("moment_noise", p["moment_noise"])
    if force_noise < 0 or moment_noise < 0:
        raise ValueError("force_noise and moment_noise must be non-negative (0: the sensor preset's)")
    if p["sensor"] not in NOISE_PRESETS:
        raise ValueError(f"sensor must be one of {', '.join(NOISE_PRESETS)}, got {p['sensor']!r}")
    preset = NOISE_PRESETS[p["sensor"]]
    noise = SensorNoise(
        force_std=(force_noise,) * 3 if force_noise > 0 else preset.force_std,
        moment_std=(moment_noise,) * 3 if moment_noise > 0 else preset.moment_std,
    )
    values["skin_law"] = asked_skin_law(values["depth_compensation"], values["skin_law"], tip)
    bias = load_bias(p["bias"]) if p["bias"] else None
    return EstimatorConfig(**values, noise=noise, bias=bias)


def main(args: list[str] | None = None) -> None:  # pragma: no cover - needs a ROS 2 installation
    """Run the node until shut down."""
    try:
        import rclpy
        from geometry_msgs.msg import PointStamped, QuaternionStamped, Vector3Stamped, WrenchStamped
        from rcl_interfaces.msg import ParameterDescriptor
        from rclpy.exceptions import ParameterUninitializedException
        from rclpy.node import Node
        from rclpy.parameter import Parameter
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
    from softtip.core.fingertip import load_fingertip
    from softtip.estimator import Estimator
    from softtip.estimator.columns import TOPICS as COLUMN_TOPICS

    class SofttipNode(Node):
        def __init__(self):
            super().__init__("softtip")
            for name, default in PARAMETERS.items():
                self.declare_parameter(name, default, ParameterDescriptor(description=describe_parameter(name)))
            for name in UNSET_PARAMETERS:  # typed, without a default: a parameter file cannot hold []
                self.declare_parameter(
                    name, Parameter.Type.DOUBLE_ARRAY, ParameterDescriptor(description=describe_parameter(name))
                )
            params = {name: self.get_parameter(name).value for name in PARAMETERS}
            for name in UNSET_PARAMETERS:
                try:
                    params[name] = list(self.get_parameter(name).value)
                except ParameterUninitializedException:
                    pass
            params = {k: list(v) if k not in NODE_PARAMETERS and not isinstance(v, (str, bool, int, float)) else v
                      for k, v in params.items()}  # fmt: skip
            tip = load_fingertip(params["tip"])
            self.estimator = Estimator(tip, config_from_parameters(params, tip))
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
