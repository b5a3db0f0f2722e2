"""The papers' two-fingered hand with both fingertips simulated on one object.

The object sits at the hand's origin between the two fingertips, which close along the
hand's ``x`` axis (:meth:`~softtip.sim.scenario.HandFrame.paper`: the right finger on ``+x``,
the left on ``−x``, each touching at its apex). Each finger is simulated by
:func:`~softtip.sim.simulate.simulate_grasp` with the papers' grasp seen from its side
(``paper_scenario(side=...)``): the same rotations of the object in the hand (the finger
joints' about ``y``, gravity's about ``x``), each finger carrying half the weight. The two
contacts are solved independently — each finger's push settles on its own — so the object's
pose is common up to the skin's compression (a few tenths of a millimetre along ``x``).
Because they are independent, another contact model can simulate each finger from the same
scenarios (``simulate``: the benchmarks pass Drake's hydroelastic contact).

What each finger touches is given per finger: the two edges of a plate pinched across its
width, a stick's two sides, or an edge on one finger and a plane on the other (an
inconsistent reading for a plate-pinch model, see :mod:`softtip.fusion`). Instead of the
papers' disturbances alone, the object can be rocked about two axes (``rock``) or loaded
through friction during the hold (:class:`FrictionLoad`: the same load vector in the hand at
both fingertips, each finger's :func:`~softtip.sim.scenario.friction_scenario`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from softtip.core.fingertip import Fingertip
from softtip.sim.foundation import ContactParams
from softtip.sim.objects import RigidObject
from softtip.sim.pose import Pose
from softtip.sim.scenario import Disturbance, HandFrame, friction_scenario, paper_scenario, rock_scenario
from softtip.sim.sensor import SensorModel
from softtip.sim.simulate import SimLog, simulate_grasp

__all__ = ["SIDES", "FrictionLoad", "TwoFingerGrasp", "simulate_two_finger", "sensor_pose_in_hand"]

SIDES = ("right", "left")


def sensor_pose_in_hand(tip: Fingertip, side: str, width: float, finger_pitch: float = 0.0) -> Pose:
    """Pose of a finger's sensor frame in the hand frame, its apex touching the object's
    side at ``x = ±width / 2`` (right ``+``, left ``−``)."""
    rot = HandFrame.paper(finger_pitch, side).rotation.T  # sensor → hand
    centre, radius = tip.bounding_sphere
    apex = tip.project(centre + np.array([0.0, 0.0, 4.0 * radius]))
    contact = np.array([0.5 * width if side == "right" else -0.5 * width, 0.0, 0.0])
    return Pose(rot, contact - rot @ apex)


@dataclass(frozen=True, eq=False)
class TwoFingerGrasp:
    """Both fingers' simulated logs and the hand geometry (hand frame: the common frame)."""

    logs: dict[str, SimLog]  #: ``right`` and ``left``
    sensor_poses: dict[str, Pose]  #: each sensor frame in the hand frame
    width: float  #: m, distance between the nominal contacts along the hand's x
    object_mass: float  #: kg
    gravity: NDArray[np.float64] = field(default_factory=lambda: np.array([0.0, 0.0, -9.80665]))

    @property
    def t(self) -> NDArray[np.float64]:
        return self.logs["right"].t

    def truth_direction(self, side: str) -> NDArray[np.float64]:
        """(N, 3) the line under ``side``'s finger in the hand frame (NaN for a plane)."""
        return self.logs[side].truth.direction @ self.sensor_poses[side].rotation.T

    def truth_point(self, side: str) -> NDArray[np.float64]:
        """(N, 3) ``side``'s nominal contact point in the hand frame, m."""
        return self.sensor_poses[side].apply(self.logs[side].truth.contact_point)

    def truth_line(self, projected: bool = True) -> NDArray[np.float64]:
        """(N, 3) the object's line: the axial mean of both fingers' true lines (one where
        the other touches a plane).

        ``projected`` (default): projected on the plane across the grasp (normal to the line
        between the contacts), as each fingertip measures it in its tangent plane. The
        object's tilt toward the fingers — the very rotation about the axis across the strip
        that makes ``h`` observable, a few degrees in the papers' grasp — is in neither
        fingertip's measurement.
        """
        a, b = self.truth_direction("right"), self.truth_direction("left")
        b = np.where((np.sum(a * b, axis=-1) < 0)[:, None], -b, b)
        m = np.where(np.isfinite(a), a, 0.0) + np.where(np.isfinite(b), b, 0.0)
        if projected:
            base = self.truth_point("left") - self.truth_point("right")
            base /= np.linalg.norm(base, axis=-1, keepdims=True)
            m = m - np.sum(m * base, axis=-1, keepdims=True) * base
        with np.errstate(invalid="ignore"):
            return m / np.linalg.norm(m, axis=-1, keepdims=True)

    def truth_plane_normal(self) -> NDArray[np.float64]:
        """(N, 3) normal of the plane through both true contact lines (a plate's face)."""
        base = self.truth_point("left") - self.truth_point("right")
        c = np.cross(self.truth_line(projected=False), base)
        with np.errstate(invalid="ignore"):
            return c / np.linalg.norm(c, axis=-1, keepdims=True)


def simulate_two_finger(
    tip: Fingertip,
    objects: RigidObject | dict[str, RigidObject],
    angle: float = 0.0,
    *,
    width: float = 0.03,
    rng: int = 0,
    object_mass: float = 0.01,
    n_elements: int | None = None,
    model=None,
    rock: bool = False,
    sensor: SensorModel | None = None,
    params: ContactParams | None = None,
    load: FrictionLoad | None = None,
    simulate: Callable[..., SimLog] | None = None,
    **scenario_kwargs,
) -> TwoFingerGrasp:
    """Simulate the papers' grasp with both fingertips.

    Parameters
    ----------
    tip : Fingertip
        Both fingertips (capsule or sphere).
    objects : RigidObject or {"right": ..., "left": ...}
        What each fingertip touches (one object: the same kind under both, e.g. a plate's
        two edges).
    angle : float
        rad; the line's direction at the right finger's apex (the manual §3.4 angle); the left
        finger sees it at ``−angle`` (its sensor ``y`` is the hand's ``−y``).
    width : float
        m, the object's width between the contacts.
    rng : int
        Seed; the left finger uses ``rng + 1``.
    object_mass : float
        kg; each finger carries half the weight.
    n_elements : int, optional
        Skin elements (default that of :func:`~softtip.sim.simulate.simulate_grasp`).
    model : ContactModel, optional
        A prebuilt skin model of ``tip``, reused for both fingers (skips the discretisation).
    rock : bool
        After the grasp, rock the object about two axes and in a figure-eight
        (:func:`~softtip.sim.scenario.rock_scenario`: the same rotations in the hand for both
        fingers), which lets each fingertip tell a line from an area.
    sensor : SensorModel, optional
        Both sensors' model (rate, noise, bias, resolution; default Nano17 class at 50 Hz);
        each draws its own noise.
    params : ContactParams, optional
        Both skins' material (default :class:`~softtip.sim.foundation.ContactParams`; not with
        ``model``, which has its own).
    load : FrictionLoad, optional
        A friction load during the hold (:func:`~softtip.sim.scenario.friction_scenario`, as
        seen at the right fingertip: ``across`` its line or along it), the same vector in the
        hand for both fingertips (the object pushed or slid as one), on top of the weight
        (a ``slip`` moves the object kinematically, from the start: what moves it holds its
        weight, and the grasp's ``object_mass`` is 0); not with ``rock``.
    simulate : callable, optional
        The contact model of each finger, called as ``simulate(tip, obj, scenario, sensor,
        rng=seed)`` and returning a :class:`~softtip.sim.simulate.SimLog` (default:
        :func:`~softtip.sim.simulate.simulate_grasp` with ``n_elements``, ``model`` or ``params``,
        which a custom model does not take).
    **scenario_kwargs
        Other :func:`~softtip.sim.scenario.paper_scenario` (or, rocked,
        :func:`~softtip.sim.scenario.rock_scenario`) arguments.
    """
    if not (math.isfinite(width) and width > 0):
        raise ValueError(f"width must be a positive length in m, got {width!r}")
    objs = objects if isinstance(objects, dict) else {"right": objects, "left": objects}
    if set(objs) != set(SIDES):
        raise ValueError(f"objects must name 'right' and 'left', got {sorted(objs)}")
    kw = {} if n_elements is None else {"n_elements": n_elements}
    if model is not None:
        if params is not None:
            raise ValueError("give the skin's params or a prebuilt model, not both")
        kw = {"model": model}
    elif params is not None:
        kw["params"] = params
    if load is not None and rock:
        raise ValueError("a friction load goes with the papers' grasp, not with rocking")
    if simulate is None:
        simulate = simulate_grasp
    elif kw:
        raise ValueError("n_elements, model and params are simulate_grasp's skin: give them to your simulate instead")
    pitch = scenario_kwargs.get("finger_pitch", 0.0)
    poses = {side: sensor_pose_in_hand(tip, side, width, pitch) for side in SIDES}
    if load is not None:
        scenarios = _friction_scenarios(tip, angle, load, object_mass, poses, scenario_kwargs)
    else:
        make = rock_scenario if rock else paper_scenario
        scenarios = {
            side: make(angle if side == "right" else -angle, side=side, object_mass=object_mass, **scenario_kwargs)
            for side in SIDES
        }
    logs = {
        side: simulate(tip, objs[side], scenarios[side], sensor, rng=rng + k, **kw) for k, side in enumerate(SIDES)
    }
    # a slip moves the object kinematically: the fingers carry none of its weight
    carried = 0.0 if load is not None and load.profile == "slip" else float(object_mass)
    return TwoFingerGrasp(logs, poses, float(width), carried)


@dataclass(frozen=True)
class FrictionLoad:
    """A friction load on the grasped object (:func:`~softtip.sim.scenario.friction_scenario`).

    Parameters
    ----------
    ratio : float
        Tangential load at each fingertip, a fraction of the grasp force (``push``, ``drag``).
    across : bool
        Across the line at the right fingertip (``n × d``) or along it.
    profile : {"push", "drag", "slip"}
    slip_distance : float
        m, for ``slip``.
    """

    ratio: float = 0.25
    across: bool = True
    profile: str = "push"
    slip_distance: float = 1.5e-3


def _friction_scenarios(tip, angle, load: FrictionLoad, object_mass, poses, scenario_kwargs) -> dict:
    """Each finger's scenario under ``load``: the right finger's load (or slide), a sensor
    frame vector of :func:`~softtip.sim.scenario.friction_scenario`, turned into the left
    sensor's frame through the hand, so that both carry one vector in the hand."""
    right = friction_scenario(
        tip, angle, load.ratio, across=load.across, profile=load.profile, slip_distance=load.slip_distance,
        side="right", **scenario_kwargs,
    )  # fmt: skip
    turn = {"right": np.eye(3), "left": poses["left"].rotation.T @ poses["right"].rotation}
    mass = 0.0 if load.profile == "slip" else object_mass
    out = {}
    for side in SIDES:
        a = angle if side == "right" else -angle
        base = paper_scenario(a, side=side, object_mass=mass, name=right.name, **scenario_kwargs)
        if load.profile == "slip":
            # the slide moves the object kinematically (what moves it holds its weight too)
            slide = next(d for d in right.disturbances if d.label == "slip")
            moved = dataclasses.replace(slide, translation=tuple(turn[side] @ np.asarray(slide.translation)))
            out[side] = dataclasses.replace(base, disturbances=base.disturbances + (moved,), tangential_force=None)
        else:
            # the load over its own interval, on top of the weight (which ramps with the grasp)
            push = Disturbance(load=tuple(turn[side] @ np.asarray(right.tangential_force)), start=right.load_start,
                               end=right.load_end, label="friction-load")  # fmt: skip
            out[side] = dataclasses.replace(base, disturbances=base.disturbances + (push,))
    return out


# -- files ---------------------------------------------------------------------------------------

#: Frame names of the hand bag written by :func:`write_two_finger_bag`.
HAND_FRAME, PALM_FRAME = "hand", "palm"
#: Palm frame in the hand frame (a fixed offset, so that the left finger's pose is a chain).
PALM_OFFSET = (0.0, 0.0, -0.05)


def _quat_wxyz(rotation) -> tuple[float, float, float, float]:
    from scipy.spatial.transform import Rotation

    x, y, z, w = Rotation.from_matrix(np.asarray(rotation)).as_quat()
    return float(w), float(x), float(y), float(z)


def hand_toml(grasp: TwoFingerGrasp) -> str:
    """The hand file of :func:`softtip.fusion.read_hand_file` for this grasp (right, left)."""
    out = [f'[hand]\nframe = "{HAND_FRAME}"\n']
    for side in SIDES:
        p = grasp.sensor_poses[side]
        t = ", ".join(repr(float(v)) for v in p.translation)
        q = ", ".join(repr(v) for v in _quat_wxyz(p.rotation))
        out.append(f"[finger.{side}]\ntranslation = [{t}]\nquaternion = [{q}]\n")
    return "\n".join(out)


def truth_hand_dict(grasp: TwoFingerGrasp) -> dict:
    """Hand-frame truth per sample (JSON-ready; NaN → None)."""

    def col(a):
        return [[None if not np.isfinite(v) else float(v) for v in row] for row in np.asarray(a)]

    return {
        "format": "softtip-sim-hand-truth/1",
        "frame": f"{HAND_FRAME} (x: grasp axis, y: joint axes, z: up; gravity along -z)",
        "units": "SI (m)",
        "width_m": grasp.width,
        "object_mass_kg": grasp.object_mass,
        "objects": {side: grasp.logs[side].obj.describe() for side in SIDES},
        "sensor_poses": {side: grasp.sensor_poses[side].as_dict() for side in SIDES},
        "samples": {
            "t_s": grasp.t.tolist(),
            "line_direction": col(grasp.truth_line()),
            "plane_normal": col(grasp.truth_plane_normal()),
            **{f"contact_point_{side}": col(grasp.truth_point(side)) for side in SIDES},
        },
    }


def write_two_finger(grasp: TwoFingerGrasp, out_dir) -> list:
    """Write ``right.csv``, ``left.csv`` (each finger's raw log), ``hand.toml`` (the sensor
    poses) and ``truth.json`` (hand-frame truth) into the new directory ``out_dir`` (all of
    them or, on any failure, none). Returns the paths written."""
    import json
    import os
    import shutil
    from pathlib import Path

    from softtip.io.atomic import partial_dir
    from softtip.sim.simulate import write_log_csv

    out = Path(out_dir)
    if out.exists():
        raise FileExistsError(f"{out}: exists; expected a new directory")
    # written in a hidden folder beside it and renamed into place: all files or none
    tmp = partial_dir(out)  # mode from the umask, like mkdir
    try:
        for side in SIDES:
            write_log_csv(grasp.logs[side], tmp / f"{side}.csv")
        (tmp / "hand.toml").write_text(hand_toml(grasp), encoding="utf-8")
        (tmp / "truth.json").write_text(json.dumps(truth_hand_dict(grasp), indent=1, allow_nan=False) + "\n", encoding="utf-8")
        os.rename(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return [out / "right.csv", out / "left.csv", out / "hand.toml", out / "truth.json"]


def write_two_finger_bag(grasp: TwoFingerGrasp, dest, tf_rate: float = 25.0) -> None:
    """Write both fingers' wrenches and their poses as a rosbag2 (MCAP): topics
    ``/right/wrench`` and ``/left/wrench`` (``geometry_msgs/msg/WrenchStamped``, frame ids
    ``right_sensor`` and ``left_sensor``), ``/tf_static`` with ``hand → right_sensor`` and
    ``hand → palm``, and ``/tf`` with ``palm → left_sensor`` at ``tf_rate`` Hz (a moving
    edge, as a robot's joint states would give). ``dest`` must not exist."""
    from pathlib import Path

    from softtip.io.bag import default_typestore, import_rosbags

    import_rosbags()
    from rosbags.rosbag2 import StoragePlugin, Writer

    ts = default_typestore()
    T = ts.types
    Header, Time = T["std_msgs/msg/Header"], T["builtin_interfaces/msg/Time"]
    V3, Q = T["geometry_msgs/msg/Vector3"], T["geometry_msgs/msg/Quaternion"]
    Wrench, WrenchStamped = T["geometry_msgs/msg/Wrench"], T["geometry_msgs/msg/WrenchStamped"]
    Transform, TransformStamped = T["geometry_msgs/msg/Transform"], T["geometry_msgs/msg/TransformStamped"]
    TFMessage = T["tf2_msgs/msg/TFMessage"]
    t0 = 1_700_000_000 * 1_000_000_000  # an epoch-like origin, as a robot's clock gives

    def header(ns, frame):
        return Header(stamp=Time(sec=int(ns // 1_000_000_000), nanosec=int(ns % 1_000_000_000)), frame_id=frame)

    def tf(ns, parent, child, rotation, translation):
        w, x, y, z = _quat_wxyz(rotation)
        tr = Transform(translation=V3(x=float(translation[0]), y=float(translation[1]), z=float(translation[2])), rotation=Q(x=x, y=y, z=z, w=w))
        return TransformStamped(header=header(ns, parent), child_frame_id=child, transform=tr)

    right, left = grasp.sensor_poses["right"], grasp.sensor_poses["left"]
    palm = np.asarray(PALM_OFFSET)
    dest = Path(dest)
    with Writer(dest, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conn = {
            "/right/wrench": writer.add_connection("/right/wrench", "geometry_msgs/msg/WrenchStamped", typestore=ts),
            "/left/wrench": writer.add_connection("/left/wrench", "geometry_msgs/msg/WrenchStamped", typestore=ts),
            "/tf_static": writer.add_connection("/tf_static", "tf2_msgs/msg/TFMessage", typestore=ts),
            "/tf": writer.add_connection("/tf", "tf2_msgs/msg/TFMessage", typestore=ts),
        }
        static = TFMessage(transforms=[
            tf(t0, HAND_FRAME, "right_sensor", right.rotation, right.translation),
            tf(t0, HAND_FRAME, PALM_FRAME, np.eye(3), palm),
        ])  # fmt: skip
        writer.write(conn["/tf_static"], t0, ts.serialize_cdr(static, "tf2_msgs/msg/TFMessage"))
        t = grasp.t
        for ti in np.arange(t[0], t[-1] + 1.0 / tf_rate, 1.0 / tf_rate):
            ns = t0 + int(round(ti * 1e9))
            msg = TFMessage(transforms=[tf(ns, PALM_FRAME, "left_sensor", left.rotation, left.translation - palm)])
            writer.write(conn["/tf"], ns, ts.serialize_cdr(msg, "tf2_msgs/msg/TFMessage"))
        for side, frame in (("right", "right_sensor"), ("left", "left_sensor")):
            for ti, w in zip(t, grasp.logs[side].wrench):
                ns = t0 + int(round(ti * 1e9))
                msg = WrenchStamped(
                    header=header(ns, frame),
                    wrench=Wrench(force=V3(x=w[0], y=w[1], z=w[2]), torque=V3(x=w[3], y=w[4], z=w[5])),
                )
                writer.write(conn[f"/{side}/wrench"], ns, ts.serialize_cdr(msg, "geometry_msgs/msg/WrenchStamped"))
