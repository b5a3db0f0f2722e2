"""Grasp scenarios: how the object moves relative to the fingertip over time.

A scenario places the object's contact frame (see :mod:`softtip.sim.objects`) at the
*nominal contact point* ``r_c`` on the skin with its outward normal along the *push axis*
``u`` (into the fingertip) and its line direction at ``angle`` in the manual §3.4 tangent
frame. The object then

1. approaches along ``u`` at ``approach_speed`` and touches at ``t_contact``;
2. is pushed along ``u`` by a travel ``s(t)`` solved per sample so that the force along
   ``u`` follows the grasp profile (smoothstep from 0 at ``t_contact`` to ``force`` at
   ``t_stable``, held to ``duration``) — the papers' grasp;
3. meanwhile undergoes prescribed *disturbances*: rotations about given axes and
   translations, each ramped with the same smoothstep (or over its own interval).

The object's pose at time ``t`` is ``T(s u) ∘ D(t) ∘ B ∘ P``, where ``B`` is the placement,
``P`` the object's own pose (an offset in its contact frame, identity by default) and
``D(t) = D_k ∘ … ∘ D_1`` the disturbances, each a rotation about a line through its pivot
(default: ``r_c``) followed by a translation. With a ``tangential_force`` the object's
position across the push axis is solved as well (force balance), as in the papers' grasp.

The papers' hand (:func:`paper_scenario`, :class:`HandFrame`)
--------------------------------------------------------------
Two fingers, every joint axis parallel to the hand's ``y``, gravity along the hand's ``-z``;
the right fingertip touches the object at its apex (``n = z_s``) while the fingers close
along the hand's ``x``. The sensor frame of the right fingertip is mapped to the hand as

    sensor x = hand z (up),   sensor y = hand y (joint axes),   sensor z = -hand x,

so that a plate at 90° (manual §3.4: angle from sensor x at the tip) lies along the joint
axes, as in the paper. Disturbances come only from the joints (rotation about hand ``y``)
and gravity (rotation about the grasp axis, hand ``x``, from an off-axis centre of mass,
and half the object's weight as a tangential load along hand ``-z``): nothing rotates the
object about hand ``z``. A 90° plate therefore
gets no rotation about the in-plane axis perpendicular to it (hand ``z`` = sensor ``x``)
and shows almost no tangential spin torque — the paper's unobservable case, reproduced by
the physics rather than special-cased. ``misalignment`` (a fixed rotation about hand ``z``)
models the paper's "alignment error of the fingers and grasped object".

Timing
------
By default (``disturbance_timing="after_grasp"``) the object is kept still while the
fingers close and the grasp force builds (2 → 4 s), so the contact point is measured at
light force on an undisturbed contact (paper III-C, 2006 §IV steps 1–3); the joint
rotation and the gravity spin then ramp in over 4 → 5.5 s. ``"during_rise"`` (the earlier
behaviour) ramps them with the force; the pressure centre then moves along the strip while
the latch averages, and the latched point absorbs part of the tangential spin torque.

Amplitudes
----------
Tangential spin torque comes from the relative rotation about the joint axis; on the
murakami2006 tip at 0.5 kgf a 1–2 mm plate resists a rotation about the in-plane axis
across it with about 1.3 N·mm per degree (Winkler strip bending). The default 3.5°
(finger compliance and joint servo error of a few degrees) gives |h| ≈ 4.5 N·mm at 0° and
≈ 3.2 N·mm at ±45° (the papers' Figs. 8–10: roughly 0.3–1.5 kgf·mm), while the 90° plate
stays at ≈ 0.4 N·mm, below ``h_min``. The gravity spin (1°) and the mass (10 g, a light
plate; 0.05 N of tangential load per finger) are kept small: see the limits below.

Known limits of the contact model (measured, not fixed)
-------------------------------------------------------
* A rotation about hand ``y`` has a component about the strip's own axis (sin of the
  angle between them): at ±45° half of it tilts the plate about its cut edge. With the
  default elastic-foundation rule (``ContactParams(depth_rule="column")``: each spring is
  compressed to the deepest object point on its column) a 1–2 mm strip barely resists
  that tilt (≈ 0.4–2.5 N·mm/rad against ≈ 75 N·mm/rad across it), so the direction is
  measured within 3° at ±45°. The older ``"surface"`` rule compressed only springs whose
  skin point lies inside the object; it resisted the tilt with ``≈ F·δ`` ≈ 15 N·mm/rad and
  biased ±45° by 5–9°. Real rubber resists the tilt somewhat through the groove's walls.
* Thick plates: the strip turns "round" only around 10 mm here (3–4 mm plates still
  behave mostly like strips), where the papers saw large errors from 3 mm on.
* The Winkler layer has no side-wall stiffness across an embedded thin plate: only the
  shear layer holds it sideways (≈ 0.3 N/mm instead of ≈ 10 N/mm for rubber walls), so a
  tangential load across the strip shifts it and adds ``|f| × shift`` to ``h`` (the 10 g
  default weight shifts a 1 mm plate at 90° by ≈ 0.15 mm: |h| ≈ 0.48 N·mm about the
  nominal point, below the estimator's significance level of ≈ 0.9 N·mm). Heavier
  objects (≥ 50 g) therefore corrupt ±45° and 90° plates, and applying the weight only
  after the grasp (stuck strip) makes the lateral force solve fail at 90°; the weight
  ramps with the grasp force for that reason.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from softtip.core.fingertip import Fingertip
from softtip.core.units import KGF, STANDARD_GRAVITY
from softtip.sim.pose import Pose, unit
from softtip.sim.synthetic import smoothstep
from softtip.sim.truth import tangent_frame

__all__ = [
    "DISTURBANCE_RAMP",
    "DISTURBANCE_TIMINGS",
    "JOINT_ROTATION_DEG",
    "OBJECT_MASS",
    "Disturbance",
    "HandFrame",
    "GraspScenario",
    "FRICTION_PROFILES",
    "friction_scenario",
    "paper_scenario",
    "push_scenario",
    "rock_scenario",
    "ROCK_AMPLITUDE_DEG",
    "ROCK_LOAD",
    "smoothstep",
]

#: Default relative rotation about the joint axis in :func:`paper_scenario`, degrees.
JOINT_ROTATION_DEG = 3.5
#: Default object mass in :func:`paper_scenario`, kg.
OBJECT_MASS = 0.01


def _opt_vec(v: ArrayLike | None) -> tuple[float, float, float] | None:
    if v is None:
        return None
    a = np.asarray(v, dtype=float).reshape(3)
    if not np.all(np.isfinite(a)):
        raise ValueError(f"expected 3 finite numbers, got {v!r}")
    return (float(a[0]), float(a[1]), float(a[2]))


@dataclass(frozen=True)
class Disturbance:
    """A prescribed rotation and/or translation of the object relative to the fingertip.

    At full amplitude the object is rotated by ``angle`` (rad) about the line through
    ``pivot`` along ``axis`` and then translated by ``translation`` (m); both in the sensor
    frame. The amplitude ramps as ``smoothstep((t - start) / (end - start))``; with
    ``start == end`` it is a step at ``start``.

    Parameters
    ----------
    axis : 3 floats, optional
        Rotation axis (any length). None: no rotation.
    angle : float
        Rotation at full amplitude, rad.
    translation : 3 floats
        Translation at full amplitude, m.
    pivot : 3 floats, optional
        A point of the rotation axis, m; None: the nominal contact point.
    start, end : float, optional
        Ramp interval, s; None: the scenario's ``t_contact`` / ``t_stable``.
    label : str
        Name shown in ``truth.json``.
    period : float, optional
        s; a rocking motion instead of a ramp: the amplitude is
        ``sin(2π (t − start) / period)`` from ``start`` to ``end`` and zero outside (give
        both, ``end − start`` a whole number of periods so that it averages to zero).
    load : 3 floats
        Tangential load on the fingertip at full amplitude, N, sensor frame (the push that
        rocks the object); added to the scenario's ``tangential_force``.
    """

    axis: tuple[float, float, float] | None = None
    angle: float = 0.0
    translation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    pivot: tuple[float, float, float] | None = None
    start: float | None = None
    end: float | None = None
    label: str = ""
    period: float | None = None
    load: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        object.__setattr__(self, "axis", None if self.axis is None else tuple(unit(self.axis, "axis")))
        object.__setattr__(self, "translation", _opt_vec(self.translation))
        object.__setattr__(self, "pivot", _opt_vec(self.pivot))
        if not math.isfinite(self.angle):
            raise ValueError(f"angle must be finite, got {self.angle!r}")
        if self.start is not None and self.end is not None and self.end < self.start:
            raise ValueError(f"disturbance {self.label!r}: end {self.end} s is before start {self.start} s")
        object.__setattr__(self, "load", _opt_vec(self.load))
        if self.period is not None:
            if not (math.isfinite(self.period) and self.period > 0.0):
                raise ValueError(f"disturbance {self.label!r}: period must be positive (s), got {self.period!r}")
            if self.start is None or self.end is None:
                raise ValueError(f"disturbance {self.label!r}: a rocking motion (period) needs start and end")

    def amplitude(self, t: float, t_contact: float, t_stable: float) -> float:
        """Fraction of the full disturbance applied at time ``t`` (s)."""
        a = t_contact if self.start is None else self.start
        b = t_stable if self.end is None else self.end
        if self.period is not None:
            return math.sin(2.0 * math.pi * (t - a) / self.period) if a <= t < b else 0.0
        if b <= a:
            return 1.0 if t >= a else 0.0
        return float(smoothstep((t - a) / (b - a)))

    def pose(self, fraction: float, contact_point: ArrayLike) -> Pose:
        """The rigid motion at ``fraction`` of the full amplitude."""
        out = Pose.from_translation(fraction * np.asarray(self.translation))
        if self.axis is not None and self.angle != 0.0:
            pivot = contact_point if self.pivot is None else self.pivot
            out = out @ Pose.from_axis_angle(self.axis, fraction * self.angle, pivot)
        return out

    def as_dict(self) -> dict:
        """JSON-ready, SI (angle in rad and deg)."""
        return {
            "label": self.label,
            "axis": None if self.axis is None else list(self.axis),
            "angle_rad": self.angle,
            "angle_deg": math.degrees(self.angle),
            "translation_m": list(self.translation),
            "pivot_m": None if self.pivot is None else list(self.pivot),
            "start_s": self.start,
            "end_s": self.end,
            "period_s": self.period,
            "load_N": list(self.load),
        }


@dataclass(frozen=True, eq=False)
class HandFrame:
    """Axes of the papers' hand frame expressed in the right fingertip's sensor frame.

    Parameters
    ----------
    rotation : (3, 3)
        Columns: hand ``x`` (grasp axis, from the right finger toward the left), hand ``y``
        (joint axes) and hand ``z`` (up) in sensor coordinates; ``v_sensor = rotation @ v_hand``.
    """

    rotation: NDArray[np.float64]

    def __post_init__(self) -> None:
        r = np.array(self.rotation, dtype=float).reshape(3, 3)
        if np.abs(r.T @ r - np.eye(3)).max() > 1e-9 or np.linalg.det(r) < 0.0:
            raise ValueError("hand frame rotation must be a proper rotation matrix")
        r.setflags(write=False)
        object.__setattr__(self, "rotation", r)

    @classmethod
    def paper(cls, finger_pitch: float = 0.0, side: str = "right") -> HandFrame:
        """The mapping used for the papers' experiments.

        Right finger: ``sensor x = hand z``, ``sensor y = hand y``, ``sensor z = -hand x``
        when ``finger_pitch = 0``; ``finger_pitch`` (rad) rotates the finger about the joint
        axis (sensor ``y``), tilting the fingertip axis in the hand's x–z plane. The left
        finger faces it: ``sensor x = hand z``, ``sensor y = -hand y``, ``sensor z = hand x``.
        """
        if side not in ("right", "left"):
            raise ValueError(f"side must be 'right' or 'left', got {side!r}")
        base = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
        if side == "left":
            base = np.array([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]])
        c, s = math.cos(finger_pitch), math.sin(finger_pitch)
        pitch = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
        return cls(pitch @ base)

    @property
    def grasp_axis(self) -> NDArray[np.float64]:
        """Hand ``x`` in the sensor frame."""
        return self.rotation[:, 0].copy()

    @property
    def joint_axis(self) -> NDArray[np.float64]:
        """Hand ``y`` (every finger joint axis) in the sensor frame."""
        return self.rotation[:, 1].copy()

    @property
    def up(self) -> NDArray[np.float64]:
        """Hand ``z`` in the sensor frame."""
        return self.rotation[:, 2].copy()

    @property
    def gravity(self) -> NDArray[np.float64]:
        """Unit gravity direction (hand ``-z``) in the sensor frame."""
        return -self.up

    def as_dict(self) -> dict:
        """JSON-ready."""
        return {
            "hand_axes_in_sensor_frame": {
                "x": self.grasp_axis.tolist(),
                "y": self.joint_axis.tolist(),
                "z": self.up.tolist(),
            },
            "gravity": self.gravity.tolist(),
        }


@dataclass(frozen=True)
class GraspScenario:
    """A grasp: approach, force-controlled push and disturbances (see the module docs).

    Parameters
    ----------
    angle : float
        Line direction of the object at the nominal contact, rad, in the manual §3.4 tangent
        frame (at the apex: from the sensor x axis).
    force : float
        Held grasp force along the push axis, N (default 0.5 kgf).
    duration : float
        Recorded time, s.
    t_contact, t_stable : float
        First touch and end of the force ramp, s.
    approach_speed : float
        Speed of the object toward the fingertip before contact, m/s.
    contact_point : 3 floats, optional
        Nominal contact point, m (projected onto the skin); None: the fingertip's apex (of a
        mounted fingertip: the apex of the shape in its own frame, where the mount puts it).
    push_direction : 3 floats, optional
        Push axis, into the fingertip; None: minus the skin normal at the contact point.
    disturbances : tuple of Disturbance
        Applied in order.
    tangential_force : 3 floats, optional
        Tangential load the object puts on the fingertip at full grasp, N, sensor frame
        (its part along the push axis is ignored); ramped like the grasp force. When given,
        the object's position across the push axis is solved per sample so that the
        tangential force follows it (the object settles where the forces balance, as in a
        real grasp) and disturbance translations across the push axis have no effect.
        None (default): the position across the push axis is prescribed (kinematic).
    hand : HandFrame, optional
        The hand frame, recorded in the truth (the papers' scenario).
    name : str
        Label.
    load_start, load_end : float, optional
        Ramp interval of the ``tangential_force``, s (smoothstep; a step when equal).
        None (default): the load ramps with the grasp force, from ``t_contact`` to
        ``t_stable``.
    """

    angle: float = 0.0
    force: float = 0.5 * KGF
    duration: float = 10.0
    t_contact: float = 2.0
    t_stable: float = 4.0
    approach_speed: float = 0.005
    contact_point: tuple[float, float, float] | None = None
    push_direction: tuple[float, float, float] | None = None
    disturbances: tuple[Disturbance, ...] = field(default_factory=tuple)
    tangential_force: tuple[float, float, float] | None = None
    hand: HandFrame | None = None
    name: str = "push"
    load_start: float | None = None
    load_end: float | None = None

    def __post_init__(self) -> None:
        for nm in ("angle", "force", "duration", "t_contact", "t_stable", "approach_speed"):
            if not math.isfinite(getattr(self, nm)):
                raise ValueError(f"{nm} must be finite")
        if (self.load_start is None) != (self.load_end is None):
            raise ValueError("give both load_start and load_end, or neither")
        if self.load_start is not None:
            if not (math.isfinite(self.load_start) and math.isfinite(self.load_end)):
                raise ValueError("load_start and load_end must be finite")
            if self.load_end < self.load_start:
                raise ValueError(f"load_end {self.load_end} s is before load_start {self.load_start} s")
        if self.force <= 0.0:
            raise ValueError(f"force must be positive (N), got {self.force!r}")
        if not (0.0 <= self.t_contact < self.t_stable):
            raise ValueError(f"need 0 <= t_contact < t_stable, got {self.t_contact!r}, {self.t_stable!r} s")
        if self.duration <= self.t_contact:
            raise ValueError(f"duration {self.duration!r} s ends before contact at {self.t_contact!r} s")
        if self.approach_speed < 0.0:
            raise ValueError(f"approach_speed must be non-negative (m/s), got {self.approach_speed!r}")
        object.__setattr__(self, "contact_point", _opt_vec(self.contact_point))
        object.__setattr__(self, "push_direction", _opt_vec(self.push_direction))
        object.__setattr__(self, "tangential_force", _opt_vec(self.tangential_force))
        object.__setattr__(self, "disturbances", tuple(self.disturbances))

    def nominal_contact(self, tip: Fingertip) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """``(r_c, n_c, u)``: nominal contact point (m), skin normal there, push axis."""
        if self.contact_point is None:
            # the apex: the top of the shape in its own frame (a mounted shape's own z axis)
            guess = tip.apex_hint()
        else:
            guess = np.asarray(self.contact_point)
        r_c = tip.project(guess)
        n_c = tip.normal(r_c)
        u = -n_c if self.push_direction is None else unit(self.push_direction, "push_direction")
        if u @ n_c >= 0.0:
            raise ValueError("push_direction must point into the fingertip (against the skin normal)")
        return r_c, n_c, u

    def placement(self, tip: Fingertip) -> Pose:
        """Pose of the object's contact frame at first touch (before any disturbance)."""
        r_c, n_c, u = self.nominal_contact(tip)
        e1, e2 = tangent_frame(n_c)
        d = math.cos(self.angle) * e1 + math.sin(self.angle) * e2
        if abs(d @ u) > 0.999:
            raise ValueError("the line direction is parallel to the push axis")
        return Pose.from_frame(u, d, r_c)

    def force_target(self, t: ArrayLike) -> NDArray[np.float64]:
        """Grasp force profile along the push axis, N, at times ``t`` (s)."""
        return self.force * smoothstep((np.asarray(t, dtype=float) - self.t_contact) / (self.t_stable - self.t_contact))

    def load_ramp(self, t: ArrayLike) -> NDArray[np.float64]:
        """Fraction of ``tangential_force`` applied at times ``t`` (s)."""
        t = np.asarray(t, dtype=float)
        if self.load_start is None:
            return np.where(t >= self.t_contact, self.force_target(t) / self.force, 0.0)
        a, b = float(self.load_start), float(self.load_end)
        if b <= a:
            return np.where(t >= a, 1.0, 0.0)
        return smoothstep((t - a) / (b - a))

    def disturbance_load(self, t: float) -> NDArray[np.float64]:
        """Tangential load of the disturbances at time ``t`` (s), N, sensor frame."""
        out = np.zeros(3)
        for d in self.disturbances:
            if any(d.load):
                out += d.amplitude(t, self.t_contact, self.t_stable) * np.asarray(d.load)
        return out

    def disturbance_pose(self, t: float, contact_point: ArrayLike) -> Pose:
        """``D(t)``: all disturbances composed in order."""
        out = Pose.identity()
        for d in self.disturbances:
            out = d.pose(d.amplitude(t, self.t_contact, self.t_stable), contact_point) @ out
        return out

    def as_dict(self) -> dict:
        """JSON-ready, SI (angles also in degrees)."""
        return {
            "name": self.name,
            "angle_rad": self.angle,
            "angle_deg": math.degrees(self.angle),
            "force_N": self.force,
            "duration_s": self.duration,
            "t_contact_s": self.t_contact,
            "t_stable_s": self.t_stable,
            "approach_speed_m_per_s": self.approach_speed,
            "contact_point_m": None if self.contact_point is None else list(self.contact_point),
            "push_direction": None if self.push_direction is None else list(self.push_direction),
            "disturbances": [d.as_dict() for d in self.disturbances],
            "tangential_force_N": None if self.tangential_force is None else list(self.tangential_force),
            "hand": None if self.hand is None else self.hand.as_dict(),
            "load_start_s": self.load_start,
            "load_end_s": self.load_end,
        }


def push_scenario(angle: float = 0.0, **kwargs) -> GraspScenario:
    """A plain force-controlled push at the apex with no disturbance (``kwargs``: any
    :class:`GraspScenario` field)."""
    return GraspScenario(angle=angle, name=kwargs.pop("name", "push"), **kwargs)


#: Disturbance timings accepted by :func:`paper_scenario`.
DISTURBANCE_TIMINGS = ("after_grasp", "during_rise")
#: Default ramp time of the disturbances after the grasp is established, s.
DISTURBANCE_RAMP = 1.5


def paper_scenario(
    angle: float = 0.0,
    *,
    joint_rotation: float = math.radians(JOINT_ROTATION_DEG),
    gravity_spin: float = math.radians(1.0),
    object_mass: float = OBJECT_MASS,
    misalignment: float = 0.0,
    finger_pitch: float = 0.0,
    disturbance_timing: str = "after_grasp",
    disturbance_start: float | None = None,
    disturbance_end: float | None = None,
    side: str = "right",
    **kwargs,
) -> GraspScenario:
    """The papers' grasp with the right fingertip of the two-fingered hand (manual §5).

    Parameters
    ----------
    angle : float
        Object direction at the apex, rad (manual §3.4; 90° is along the joint axes).
    joint_rotation : float
        Rotation of the object relative to the fingertip about the joint axis (hand ``y``)
        once the object is released into the grasp (finger compliance, joint servo error),
        rad. Default: see :data:`JOINT_ROTATION_DEG`.
    gravity_spin : float
        Rotation about the grasp axis (hand ``x``) by the object's weight acting off the
        grasp axis, rad. Default 1°.
    object_mass : float
        Mass of the object, kg (default :data:`OBJECT_MASS`). Each finger carries half its
        weight: a tangential load along gravity (hand ``-z``), with the object's position
        across the push axis solved for it.
    misalignment : float
        Fixed alignment error: rotation of the object about hand ``z`` through the contact,
        rad (default 0), present from the start.
    finger_pitch : float
        See :meth:`HandFrame.paper`, rad.
    disturbance_timing : {"after_grasp", "during_rise"}
        When the joint rotation, the gravity spin and the weight come in.

        ``"after_grasp"`` (default, the papers' procedure, 2006 §IV): the object "is put
        into the open space and is kept still"; the fingers close, touch at ``t_contact``
        (the contact point is measured then, at light force) and build the grasp force
        to ``t_stable``; only then do the moments of the finger joints and of the weight
        rotate the object relative to the fingertip, ramping in from ``t_stable`` over
        :data:`DISTURBANCE_RAMP` s. The direction is read "at the end of this motion".
        (The weight's tangential load itself still ramps with the grasp force: applied
        to a fully stuck strip it makes the lateral force balance of a thin plate in the
        Winkler model fragile, see the module docs.)

        ``"during_rise"``: everything ramps together with the grasp force, from
        ``t_contact`` to ``t_stable`` (the behaviour before this option existed). This is
        the harder case for the latch: the pressure centre already moves along the strip
        while the contact point is being measured, so the latched point absorbs part of
        the tangential spin torque.
    disturbance_start, disturbance_end : float, optional
        Explicit ramp interval of the joint rotation and the gravity spin, s; override the
        ``disturbance_timing`` defaults (either may be given alone).
    side : {"right", "left"}
        Which finger of the hand (:meth:`HandFrame.paper`); the disturbances are the same
        rotations of the object in the hand, seen from that finger.
    **kwargs
        Other :class:`GraspScenario` fields (force, timing, ...).

    Notes
    -----
    The papers report none of the amplitudes; they are this project's choices (module
    docs, "Amplitudes"), small enough that the two fingers hold the object stably.
    """
    if not (math.isfinite(object_mass) and object_mass >= 0.0):
        raise ValueError(f"object_mass must be a non-negative mass in kg, got {object_mass!r}")
    if disturbance_timing not in DISTURBANCE_TIMINGS:
        raise ValueError(f"unknown disturbance_timing {disturbance_timing!r}; expected one of {', '.join(DISTURBANCE_TIMINGS)}")
    t_contact = float(kwargs.get("t_contact", GraspScenario.t_contact))
    t_stable = float(kwargs.get("t_stable", GraspScenario.t_stable))
    if disturbance_timing == "after_grasp":
        start, end = t_stable, t_stable + DISTURBANCE_RAMP
    else:
        start, end = t_contact, t_stable
    if disturbance_start is not None:
        start = float(disturbance_start)
        if disturbance_end is None:
            end = max(end, start)
    if disturbance_end is not None:
        end = float(disturbance_end)
    if not (math.isfinite(start) and math.isfinite(end) and start >= 0.0 and end >= start):
        raise ValueError(f"need 0 <= disturbance_start <= disturbance_end, got {start!r}, {end!r} s")
    hand = HandFrame.paper(finger_pitch, side)
    dist = [
        Disturbance(axis=tuple(hand.joint_axis), angle=joint_rotation, start=start, end=end, label="joint"),
        Disturbance(axis=tuple(hand.grasp_axis), angle=gravity_spin, start=start, end=end, label="gravity-spin"),
    ]
    if misalignment != 0.0:
        dist.insert(0, Disturbance(axis=tuple(hand.up), angle=misalignment, start=0.0, end=0.0, label="misalignment"))
    load = 0.5 * object_mass * STANDARD_GRAVITY * hand.gravity
    timing = {}
    return GraspScenario(
        angle=angle,
        disturbances=tuple(dist),
        tangential_force=tuple(load),
        hand=hand,
        name=kwargs.pop("name", "paper"),
        **timing,
        **kwargs,
    )


#: Load profiles accepted by :func:`friction_scenario`.
FRICTION_PROFILES = ("push", "drag", "slip")


def friction_scenario(
    tip: Fingertip,
    angle: float = 0.0,
    ratio: float = 0.25,
    *,
    across: bool = True,
    profile: str = "push",
    slip_distance: float = 1.5e-3,
    **kwargs,
) -> GraspScenario:
    """The papers' grasp (:func:`paper_scenario`, weightless object) with a friction load
    during the hold.

    After the joint disturbance has come in (4 → 5.5 s), the object is loaded tangentially,
    across the line (along ``n × d``) or along it (``d``), at the nominal contact normal
    ``n`` of ``tip``. Friction then acts inside the skin, at the depth recorded as
    :attr:`~softtip.sim.truth.GroundTruth.friction_depth`.

    Parameters
    ----------
    tip : Fingertip
        For the contact normal that defines "across" and "along".
    angle : float
        Line direction, rad (manual §3.4 tangent frame).
    ratio : float
        Tangential load as a fraction of the grasp force (``push`` and ``drag``).
    across : bool
        Load across the line (True) or along it.
    profile : {"push", "drag", "slip"}
        ``push``: the load ramps in over 6 → 6.5 s and is held. ``drag``: it ramps slowly,
        over 5.5 → 9.5 s. ``slip``: no force target across the push axis; the object is
        moved ``slip_distance`` (m) over 6 → 7 s, so the skin slides under it at the
        Coulomb limit, then sticks (the load is whatever friction gives, ``ratio`` unused).
    slip_distance : float
        m, for ``slip``.
    **kwargs
        Other :func:`paper_scenario` arguments (``force``, ``joint_rotation``, ...).
    """
    if profile not in FRICTION_PROFILES:
        raise ValueError(f"unknown friction profile {profile!r}; expected one of {', '.join(FRICTION_PROFILES)}")
    if not (math.isfinite(ratio) and ratio >= 0.0):
        raise ValueError(f"ratio must be a non-negative fraction of the grasp force, got {ratio!r}")
    kwargs.setdefault("object_mass", 0.0)
    base = paper_scenario(angle, name=f"friction-{profile}", **kwargs)
    _, n_c, _ = base.nominal_contact(tip)
    e1, e2 = tangent_frame(n_c)
    d = math.cos(angle) * e1 + math.sin(angle) * e2
    way = np.cross(n_c, d) if across else d
    if profile == "slip":
        slide = Disturbance(translation=tuple(slip_distance * way), start=6.0, end=7.0, label="slip")
        return GraspScenario(**{**_fields(base), "disturbances": base.disturbances + (slide,),
                                "tangential_force": None})  # fmt: skip
    start, end = (6.0, 6.5) if profile == "push" else (5.5, 9.5)
    load = ratio * base.force * way
    return GraspScenario(**{**_fields(base), "tangential_force": tuple(load), "load_start": start, "load_end": end})


def _fields(s: GraspScenario) -> dict:
    return {f: getattr(s, f) for f in s.__dataclass_fields__}


#: Default rocking amplitude of :func:`rock_scenario`, degrees.
ROCK_AMPLITUDE_DEG = 3.0
#: Default tangential load that accompanies the rocking in :func:`rock_scenario`, N.
ROCK_LOAD = 0.03


def rock_scenario(
    angle: float = 0.0,
    *,
    rock_amplitude: float = math.radians(ROCK_AMPLITUDE_DEG),
    rock_load: float = ROCK_LOAD,
    rock_period: float = 1.0,
    rock_axes: float = 0.0,
    rock_cycles: int = 2,
    **kwargs,
) -> GraspScenario:
    """The papers' grasp (:func:`paper_scenario`), then the object rocked about two tangent
    axes and in a figure-eight: the two-axis excitation that tells a line from an area.

    After the grasp and its disturbances have settled, the object is rocked (pivot: the
    nominal contact point) by ``± rock_amplitude``

    1. about the tangent axis ``a₁`` for ``rock_cycles`` periods,
    2. about ``a₂ = n × a₁`` for as long,
    3. in a figure-eight: about ``a₁`` at half the frequency and ``a₂`` at the full one,
       for ``2 rock_period · max(1, rock_cycles // 2)``,

    each segment a whole number of sine periods, so it averages to zero tilt. ``a₁`` is the
    tangent frame's ``e1`` (the sensor x axis projected on the tangent plane) turned by ``rock_axes`` about the normal. A tilt
    about ``a`` comes with a tangential load ``rock_load`` along ``n × a`` (the push that
    rocks the object; it turns with the tilt axis).

    Parameters
    ----------
    angle : float
        Object direction at the apex, rad.
    rock_amplitude : float
        rad (default :data:`ROCK_AMPLITUDE_DEG`).
    rock_load : float
        N (default :data:`ROCK_LOAD`).
    rock_period : float
        s, of segments 1 and 2.
    rock_axes : float
        rad.
    rock_cycles : int
        Periods per segment.
    **kwargs
        :func:`paper_scenario` arguments and :class:`GraspScenario` fields; ``duration``
        defaults to the end of the figure-eight plus 0.5 s.
    """
    if not (math.isfinite(rock_period) and rock_period > 0.0):
        raise ValueError(f"rock_period must be positive (s), got {rock_period!r}")
    if int(rock_cycles) < 1:
        raise ValueError(f"rock_cycles must be at least 1, got {rock_cycles!r}")
    for nm, v in (("rock_amplitude", rock_amplitude), ("rock_load", rock_load), ("rock_axes", rock_axes)):
        if not math.isfinite(v):
            raise ValueError(f"{nm} must be finite, got {v!r}")
    t_stable = float(kwargs.get("t_stable", GraspScenario.t_stable))
    start = kwargs.get("disturbance_end")
    start = t_stable + DISTURBANCE_RAMP if start is None else float(start)
    cycles = int(rock_cycles)
    seg = cycles * rock_period
    eight = 2.0 * rock_period * max(1, cycles // 2)
    end = start + 2.0 * seg + eight
    kwargs.setdefault("duration", end + 0.5)
    kwargs.setdefault("name", "rock")
    base = paper_scenario(angle, **kwargs)
    hand = base.hand
    n = -hand.grasp_axis  # outward normal at the apex, where the papers' grasp touches
    a1 = math.cos(rock_axes) * hand.up + math.sin(rock_axes) * hand.joint_axis
    a2 = np.cross(n, a1)

    def rock(axis, t0, t1, period, label):
        load = tuple(rock_load * np.cross(n, axis))
        return Disturbance(axis=tuple(axis), angle=rock_amplitude, start=t0, end=t1, period=period, load=load, label=label)

    t1, t2 = start + seg, start + 2.0 * seg
    rocking = (
        rock(a1, start, t1, rock_period, "rock-a1"),
        rock(a2, t1, t2, rock_period, "rock-a2"),
        rock(a1, t2, end, 2.0 * rock_period, "eight-a1"),
        rock(a2, t2, end, rock_period, "eight-a2"),
    )
    return replace(base, disturbances=base.disturbances + rocking)
