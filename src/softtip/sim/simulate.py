"""Time-stepped simulation of a grasp, and the log / truth writers.

Per sample the object's travel along the push axis (and, with a tangential load, its
offset across it) is solved — Newton steps with the Winkler tangent stiffness, warm-started
by extrapolating the previous samples, with a bracketing fallback for the push and a coupled
Newton solve (difference Jacobian) when those steps stall — so that the true force
follows the scenario's grasp profile; the friction state is committed once per sample, so
the tangential tractions follow the motion history.

Speed: the skin is culled to a ball around the nominal contact (grown automatically if
the contact ever reaches its rim), and that to the elements that can touch the object while
it stays within a small window of a reference pose (the signed distance is 1-Lipschitz;
the reference is renewed when the object leaves the window), so only a few hundred
quadrature points are evaluated per solver step.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from softtip.core.fingertip import Fingertip, load_fingertip
from softtip.core.units import wrench_from_si
from softtip.sim.foundation import ContactModel, ContactParams, ContactResult, FrictionState
from softtip.sim.objects import RigidObject, make_object
from softtip.sim.pose import Pose
from softtip.sim.scenario import (
    JOINT_ROTATION_DEG,
    OBJECT_MASS,
    ROCK_AMPLITUDE_DEG,
    ROCK_LOAD,
    GraspScenario,
    friction_scenario,
    paper_scenario,
    push_scenario,
    rock_scenario,
)
from softtip.sim.sensor import SensorModel
from softtip.sim.skin import DEFAULT_ELEMENTS, discretise_skin
from softtip.sim.truth import GroundTruth, line_angle, tangent_frame

__all__ = ["SimLog", "simulate_grasp", "write_log_csv", "write_truth_json", "run_simulation"]

_WINDOW = 5e-4  # m: travel window of one per-sample cull
_FTOL = 2e-5  # N: force tolerance of the solve (the sensor resolves 6 mN)
_XTOL = 1e-11  # m
_FD_STEP = 1e-8  # m: difference step of the Jacobian (≈ 5e-5 N at the push stiffness)
_FTOL_JUMP = 1e-3  # N: residual accepted at a discontinuity of the contact force (below the sensor's resolution)
_NEWTON_ITER = 30  # coupled Newton steps before giving up
_BACKTRACK = 12  # step halvings per Newton step


@dataclass(frozen=True, eq=False)
class SimLog:
    """A simulated grasp.

    Attributes
    ----------
    t : (N,)
        Sample times, s.
    wrench : (N, 6)
        Sensor output (bias, noise and quantisation applied), N and N·m.
    wrench_true : (N, 6)
        Noise-free wrench of the contact model, N and N·m.
    truth : GroundTruth
        Per-sample ground truth.
    tip, obj, scenario, sensor, params
        What was simulated (``obj`` with its own pose offset, before placement).
    n_elements, quadrature : int
        Skin resolution.
    seed : int or None
        Seed of the noise generator, when known.
    """

    t: NDArray[np.float64]
    wrench: NDArray[np.float64]
    wrench_true: NDArray[np.float64]
    truth: GroundTruth
    tip: Fingertip
    obj: RigidObject
    scenario: GraspScenario
    sensor: SensorModel
    params: ContactParams
    n_elements: int
    quadrature: int
    seed: int | None = None

    def metadata(self) -> dict:
        """Everything but the per-sample arrays, JSON-ready."""
        try:
            tip = self.tip.to_toml()
        except ValueError:
            tip = repr(self.tip)
        return {
            "format": "softtip-sim-truth/1",
            "frame": "sensor (origin at the F/T sensor, z along the finger toward the tip)",
            "units": "SI (m, N, N·m, s); angles in degrees where the key says deg",
            "fingertip": tip,
            "object": self.obj.describe(),
            "scenario": self.scenario.as_dict(),
            "sensor": self.sensor.as_dict(),
            "skin": {**self.params.as_dict(), "n_elements": self.n_elements, "quadrature": self.quadrature},
            "seed": self.seed,
        }


class _Cull:
    """The skin elements that can touch the object near a reference pose.

    Reused while every point of the ball moves by less than ``_WINDOW`` in the object's
    frame since the reference pose (the signed distance is 1-Lipschitz), recomputed
    otherwise.
    """

    def __init__(self, model: ContactModel, obj: RigidObject, ball: NDArray[np.intp],
                 centre: NDArray[np.float64], radius: float):
        self.model, self.obj, self.ball, self.centre, self.radius = model, obj, ball, centre, radius
        self.pose: Pose | None = None
        self.sub: NDArray[np.intp] = ball

    def __call__(self, pose: Pose) -> NDArray[np.intp]:
        if self.pose is not None:
            r0, r1 = self.pose.rotation, pose.rotation
            shift = r1.T @ (self.centre - pose.translation) - r0.T @ (self.centre - self.pose.translation)
            if np.linalg.norm(r1 - r0) * self.radius + np.linalg.norm(shift) <= _WINDOW:
                return self.sub
        self.pose = pose
        self.sub = self.model.candidates_touching(self.obj, pose, 2.0 * _WINDOW, self.ball)
        return self.sub


class _Sample:
    """Contact of one sample as a function of the object offset ``x = (s, a, b)``.

    ``s`` is the travel along the push axis ``u``; ``a, b`` the offsets along ``t1, t2``
    across it.
    """

    def __init__(self, model: ContactModel, obj: RigidObject, pre: Pose, state: FrictionState,
                 cull: _Cull, axes: NDArray[np.float64]):
        self.model, self.obj, self.pre, self.state, self.cull, self.axes = model, obj, pre, state, cull, axes

    def pose(self, x: NDArray[np.float64]) -> Pose:
        return Pose._trusted(self.pre.rotation, self.pre.translation + x @ self.axes)

    def __call__(self, x: NDArray[np.float64]) -> ContactResult:
        pose = self.pose(x)
        return self.model.evaluate(self.obj, pose, self.state, self.cull(pose))

    def residual(self, res: ContactResult, target: NDArray[np.float64], n_free: int) -> NDArray[np.float64]:
        return (self.axes[:n_free] @ res.force) - target[:n_free]

    def bracket_push(self, x: NDArray[np.float64], target: float) -> tuple[NDArray[np.float64], ContactResult]:
        """Solve the travel ``s`` alone (offsets fixed): bracketing + Illinois regula falsi."""
        u = self.axes[0]

        def g(s: float) -> tuple[float, ContactResult]:
            y = x.copy()
            y[0] = s
            r = self(y)
            return float(r.force @ u) - target, r

        a = float(x[0])
        ga, ra = g(a)
        if abs(ga) <= _FTOL:
            return x, ra
        step = math.copysign(1e-5, -ga)
        for _ in range(60):
            b = a + step
            gb, rb = g(b)
            if abs(gb) <= _FTOL or (gb > 0.0) != (ga > 0.0):
                break
            a, ga = b, gb
            step *= 2.0
        else:
            raise RuntimeError(f"could not bracket the push travel for a force of {target} N")
        side = 0
        for _ in range(200):
            if abs(gb) <= _FTOL:
                break
            c = b - gb * (b - a) / (gb - ga)
            gc, rc = g(c)
            if abs(gc) <= _FTOL or abs(b - a) <= _XTOL:
                b, rb = c, rc
                break
            if (gc > 0.0) == (gb > 0.0):
                b, gb, rb = c, gc, rc
                if side == -1:
                    ga *= 0.5
                side = -1
            else:
                a, ga = c, gc
                if side == 1:
                    gb *= 0.5
                side = 1
        y = x.copy()
        y[0] = b
        return y, rb

    def jacobian(self, x: NDArray[np.float64], res: ContactResult, n_free: int) -> NDArray[np.float64]:
        """``∂(force along axis i)/∂x_j`` for ``i, j < n_free``, N/m, by forward differences.

        The same committed friction state for every column, so it is the tangent of the
        very function the solve zeroes (cross terms included: a tilted object pressed
        deeper pushes sideways, one moved sideways presses deeper on one flank).
        """
        f0 = self.axes[:n_free] @ res.force
        jac = np.empty((n_free, n_free))
        for j in range(n_free):  # n_free <= 3 evaluations of one sample
            y = x.copy()
            y[j] += _FD_STEP
            jac[:, j] = (self.axes[:n_free] @ self(y).force - f0) / _FD_STEP
        return jac

    def newton(self, x: NDArray[np.float64], res: ContactResult, target: NDArray[np.float64],
               n_free: int) -> tuple[NDArray[np.float64], ContactResult]:
        """Coupled Newton solve of all ``n_free`` offsets from ``x`` (whose contact is ``res``).

        Full difference Jacobian, steps limited to the cull window, backtracking until the
        largest residual decreases. When no step decreases it any more, ``x`` is kept if its
        residual is below ``_FTOL_JUMP``: the contact force is only piecewise continuous (a
        quadrature point's coverage can switch, e.g. ≈ 8e-5 N for the rocked 3 mm plate),
        and a root inside such a jump is as close as the model gets (the push-only bracket
        accepts the same at ``_XTOL``). Otherwise, or after ``_NEWTON_ITER`` steps, raises
        RuntimeError (a load the contact cannot hold: the force stops growing with the offset).
        """
        r = self.residual(res, target, n_free)
        for _ in range(_NEWTON_ITER):
            step = np.linalg.lstsq(self.jacobian(x, res, n_free), -r, rcond=None)[0]
            big = float(np.abs(step).max())
            if big > _WINDOW:
                step *= _WINDOW / big  # keep the direction, bound the length
            norm = float(np.abs(r).max())
            for _ in range(_BACKTRACK):
                y = x.copy()
                y[:n_free] += step
                ry_res = self(y)
                ry = self.residual(ry_res, target, n_free)
                if float(np.abs(ry).max()) < norm:
                    break
                step *= 0.5
            else:
                if norm <= _FTOL_JUMP:
                    return x, res
                break
            x, res, r = y, ry_res, ry
            if np.all(np.abs(r) <= _FTOL):
                return x, res
        raise RuntimeError(self._no_equilibrium(target))

    @staticmethod
    def _no_equilibrium(target: NDArray[np.float64]) -> str:
        return (
            f"force solve did not converge (target {target.tolist()} N along the push axis and across it); "
            "no offset of the object carries this load on this skin (a load beyond friction times the grasp "
            "force cannot be held, and a soft shear layer stops short of that)"
        )

    def solve(self, x0: NDArray[np.float64], target: NDArray[np.float64], n_free: int) -> tuple[NDArray[np.float64], ContactResult]:
        """Offsets ``x`` whose force along the first ``n_free`` axes equals ``target``.

        Newton steps with the Winkler tangent stiffness (``E/h × contact area`` along the
        push, ``G/h × sticking area`` across it); a robust bracketing solve of the push
        whenever there is no contact yet or Newton is slow. That diagonal stiffness ignores
        the cross terms, and the force is only piecewise continuous, so with a load across
        the push the steps can cycle without reaching the tolerance (a rocked 3 mm plate at
        60°: period two at 3e-5 N, around a jump of 8e-5 N); when three steps bring no
        progress, the coupled :meth:`newton` takes over.
        """
        prm = self.model.params
        x = x0.copy()
        norms: list[float] = []
        for it in range(60):
            res = self(x)
            r = self.residual(res, target, n_free)
            if np.all(np.abs(r) <= _FTOL):
                return x, res
            area = res.contact_area
            norms.append(float(np.abs(r).max()))
            if n_free > 1 and area > 0.0 and it >= 8 and min(norms[-3:]) >= min(norms[:-3]):
                # no progress in three steps: cycling (across a jump of the force, or with
                # the diagonal stiffness off by 2× or more); a slow descent keeps this path
                return self.newton(x, res, target, n_free)
            if area <= 0.0 or it >= 8:
                x, res = self.bracket_push(x, float(target[0]))
                if n_free == 1:
                    return x, res
                r = self.residual(res, target, n_free)
                if np.all(np.abs(r) <= _FTOL):
                    return x, res
                area = res.contact_area
            else:
                x[0] -= float(np.clip(r[0] / (prm.normal_stiffness * area), -_WINDOW, _WINDOW))
            if n_free > 1 and area > 0.0:
                # sliding points resist a step back like sticking ones, so never use less
                # than half the contact area as the tangent stiffness
                stick = max(float(res.area[~res.slip].sum()), 0.5 * area)
                x[1:n_free] -= np.clip(r[1:] / (prm.tangential_stiffness * stick), -_WINDOW, _WINDOW)
        res = self(x)
        if n_free > 1 and res.contact_area > 0.0:
            return self.newton(x, res, target, n_free)  # a descent too slow for 60 steps
        raise RuntimeError(self._no_equilibrium(target))


def simulate_grasp(
    tip: Fingertip,
    obj: RigidObject,
    scenario: GraspScenario | None = None,
    sensor: SensorModel | None = None,
    rng: np.random.Generator | int | None = None,
    *,
    params: ContactParams | None = None,
    n_elements: int = DEFAULT_ELEMENTS,
    quadrature: int = 2,
    model: ContactModel | None = None,
) -> SimLog:
    """Simulate a grasp of ``obj`` by ``tip`` and what the F/T sensor records.

    Parameters
    ----------
    tip : Fingertip
        Capsule, sphere or mesh, or one of them mounted at an angle or an offset
        (:class:`~softtip.core.mounting.Mounted`: its skin is the shape's, placed by the mount).
    obj : RigidObject
        The touched object; its ``pose`` is an offset in its contact frame (identity:
        placed exactly as the scenario says).
    scenario : GraspScenario, optional
        Default :func:`~softtip.sim.scenario.paper_scenario` at 0°.
    sensor : SensorModel, optional
        Default ATI Nano17 class at 50 Hz.
    rng : numpy Generator or int, optional
        Noise source, or a seed for ``numpy.random.default_rng`` (None: seed 0, so a run
        is reproducible unless a generator is passed).
    params : ContactParams, optional
        Skin material (default :class:`~softtip.sim.foundation.ContactParams`).
    n_elements : int
        Skin elements (≥ 10 000 by default).
    quadrature : int
        Quadrature points per element side.
    model : ContactModel, optional
        A prebuilt model (overrides ``params``, ``n_elements`` and ``quadrature``); reuse
        it across runs to skip the discretisation.

    Returns
    -------
    SimLog
    """
    scenario = paper_scenario() if scenario is None else scenario
    sensor = SensorModel() if sensor is None else sensor
    seed = None
    if rng is None or isinstance(rng, (int, np.integer)):
        seed = 0 if rng is None else int(rng)
        rng = np.random.default_rng(seed)
    if model is None:
        model = ContactModel(discretise_skin(tip, n_elements), ContactParams() if params is None else params, quadrature)
    elif model.skin.tip != tip:
        raise ValueError("model was built for a different fingertip")
    prm = model.params
    t = sensor.times(scenario.duration)
    n = len(t)
    r_c, n_c, u = scenario.nominal_contact(tip)
    base = scenario.placement(tip) @ obj.pose

    # ball cull: a rigid plane at the full skin depth touches within sqrt(2 R h) of r_c
    _, tip_r = tip.bounding_sphere
    reach = sum(
        np.linalg.norm(d.translation) + abs(d.angle) * (2.0 * tip_r) for d in scenario.disturbances
    )
    radius = math.sqrt(2.0 * tip_r * prm.depth_cap) + reach + 2e-3
    cull = _Cull(model, obj, model.candidates_near(r_c, radius), r_c, radius)
    rim = 2.0 * float(model.skin.spacing.max())

    wrench = np.zeros((n, 6))
    direction = np.zeros((n, 3))
    centre = np.full((n, 3), np.nan)
    area, depth, push, slipf = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
    friction_depth = np.full(n, np.nan)
    in_contact = np.zeros(n, dtype=bool)
    target = np.where(t >= scenario.t_contact, scenario.force_target(t), 0.0)

    e1, e2 = tangent_frame(-u)
    axes = np.stack((u, e1, e2))
    loads = any(any(d.load) for d in scenario.disturbances)
    n_free = 1 if scenario.tangential_force is None and not loads else 3
    load = np.zeros(3) if scenario.tangential_force is None else axes @ np.asarray(scenario.tangential_force)
    # before contact the object is free: no tangential load
    ramp = np.where(t >= scenario.t_contact, scenario.load_ramp(t), 0.0)

    state = FrictionState()
    history: list[NDArray[np.float64]] = []
    i = 0
    while i < n:
        ti = float(t[i])
        sample = _Sample(model, obj, scenario.disturbance_pose(ti, r_c) @ base, state, cull, axes)
        if target[i] <= 0.0:
            x = np.array([min(-scenario.approach_speed * (scenario.t_contact - ti), 0.0), 0.0, 0.0])
            res = sample(x)
        else:
            x0 = history[-1].copy() if history else np.zeros(3)
            if len(history) >= 2:
                x0 += history[-1] - history[-2]
            goal = np.array([target[i], ramp[i] * load[1], ramp[i] * load[2]])
            if loads:
                goal[1:] += (axes @ scenario.disturbance_load(ti))[1:]
            x, res = sample.solve(x0, goal, n_free)
        if res.in_contact:
            far = np.max(np.linalg.norm(res.centre - r_c, axis=1))
            if far > radius - rim:
                # the contact reached the cull's rim: widen it and redo this sample
                radius *= 1.5
                cull = _Cull(model, obj, model.candidates_near(r_c, radius), r_c, radius)
                continue
        if target[i] > 0.0:
            history.append(x)
        state = res.state
        pose = sample.pose(x)
        wrench[i] = res.wrench
        direction[i] = pose.rotate(obj.line_direction_local(pose.inverse_apply(r_c[None, :])))[0]
        centre[i] = res.pressure_centre
        area[i], depth[i], push[i], slipf[i] = res.contact_area, res.max_depth, x[0], res.slip_fraction
        in_contact[i] = res.in_contact
        friction_depth[i] = res.friction_depth
        i += 1

    truth = GroundTruth(
        direction=direction,
        angle=line_angle(direction, np.broadcast_to(n_c, direction.shape)),
        contact_point=np.broadcast_to(r_c, (n, 3)),
        contact_normal=np.broadcast_to(n_c, (n, 3)),
        pressure_centre=centre,
        contact_area=area,
        depth=depth,
        push=push,
        normal_force=wrench[:, :3] @ u,
        force_target=target,
        in_contact=in_contact,
        slip_fraction=slipf,
        friction_depth=friction_depth,
    )
    return SimLog(
        t=t,
        wrench=sensor.measure(wrench, rng),
        wrench_true=wrench,
        truth=truth,
        tip=tip,
        obj=obj,
        scenario=scenario,
        sensor=sensor,
        params=prm,
        n_elements=len(model.skin),
        quadrature=model.quadrature,
        seed=seed,
    )


def _atomic_write(path: str | os.PathLike, text: str) -> None:
    # one writer for every output (softtip.io.atomic): a failure never leaves a partial file
    from softtip.io.atomic import atomic_write_text

    atomic_write_text(path, text)


def log_csv_text(log: SimLog, units: str = "si") -> str:
    """The input log (manual §4) as text: header ``t,fx,fy,fz,mx,my,mz`` and one row per sample."""
    w = wrench_from_si(log.wrench, units)
    rows = ["t,fx,fy,fz,mx,my,mz"]
    rows += [",".join([f"{ti:.6f}"] + [f"{v:.10g}" for v in wi]) for ti, wi in zip(log.t, w, strict=True)]
    return "\n".join(rows) + "\n"


def write_log_csv(log: SimLog, path: str | os.PathLike, units: str = "si") -> None:
    """Write the input log (manual §4) (CSV, header ``t,fx,fy,fz,mx,my,mz``).

    Parameters
    ----------
    log : SimLog
    path : path
        Output file (replaced atomically).
    units : {"si", "kgf-mm"}
        ``si``: N and N·m (default); ``kgf-mm``: kgf and kgf·mm (the papers').
    """
    _atomic_write(path, log_csv_text(log, units))


def truth_dict(log: SimLog) -> dict:
    """The content of ``truth.json``: metadata plus per-sample columns (NaN → null)."""
    out = log.metadata()
    out["samples"] = {"t_s": log.t.tolist(), **log.truth.as_dict(), "wrench_true": log.wrench_true.tolist()}
    return out


def truth_json_text(log: SimLog) -> str:
    """The content of ``truth.json`` as text (see :func:`truth_dict`)."""
    return json.dumps(truth_dict(log), indent=1, allow_nan=False) + "\n"


def write_truth_json(log: SimLog, path: str | os.PathLike) -> None:
    """Write ``truth.json`` (see :func:`truth_dict`), replaced atomically."""
    _atomic_write(path, truth_json_text(log))


def scenario_options(
    *,
    force: float,
    t_contact: float,
    t_stable: float,
    duration: float | None,
    joint_rotation_deg: float,
    gravity_spin_deg: float,
    misalignment_deg: float,
    disturbance_timing: str,
    rock: bool,
    rock_amplitude_deg: float,
    rock_period: float,
    rock_load: float,
    **_other,
) -> dict:
    """Keyword arguments of :func:`~softtip.sim.scenario.paper_scenario` (rocked:
    :func:`~softtip.sim.scenario.rock_scenario`) from :func:`run_simulation`'s plain options
    (angles in degrees; ``duration`` None: 10 s, or to the rocking's end). Options of
    :func:`run_simulation` other than these are ignored (``**_other``), so that its whole
    option set can be passed (``softtip simulate --hand two-finger``)."""
    kw = dict(
        force=force, t_contact=t_contact, t_stable=t_stable, joint_rotation=math.radians(joint_rotation_deg),
        gravity_spin=math.radians(gravity_spin_deg), misalignment=math.radians(misalignment_deg),
        disturbance_timing=disturbance_timing,
    )  # fmt: skip
    if duration is not None:
        kw["duration"] = duration
    elif not rock:
        kw["duration"] = 10.0
    if rock:
        kw.update(rock_amplitude=math.radians(rock_amplitude_deg), rock_period=rock_period, rock_load=rock_load)
    return kw


#: m: the skin of a fingertip that gives none (the papers': 5 mm of silicone)
DEFAULT_SKIN_THICKNESS = 0.005


def skin_thickness_of(tip: Fingertip, thickness: float | None = None) -> float:
    """The simulated skin's thickness, m: ``thickness`` if given, else the fingertip's
    ``skin_thickness`` (a fingertip file's), else :data:`DEFAULT_SKIN_THICKNESS`."""
    if thickness is not None:
        return thickness
    return getattr(tip, "skin_thickness", None) or DEFAULT_SKIN_THICKNESS


#: Pa: the shear layer's modulus under a friction load (``scenario="friction"``) unless one is
#: given. With the default ``E / 3`` (0.2 MPa) a load of a quarter of the grasp force across a
#: 2 mm plate at 30° (far inside friction) finds no equilibrium, and the benchmarks' friction
#: loads are simulated with this one.
FRICTION_SHEAR_MODULUS = 2e6


def sensor_and_skin(
    *, rate: float, noise: bool, thickness: float, modulus: float, shear_modulus: float | None, friction: float,
    scenario: str = "paper", **_other,
) -> tuple[SensorModel, ContactParams]:
    """The sensor model and the skin's material from :func:`run_simulation`'s plain options
    (other options ignored, as in :func:`scenario_options`); under a friction load the shear
    modulus is :data:`FRICTION_SHEAR_MODULUS` unless given."""
    sensor = SensorModel(rate=rate) if noise else SensorModel.ideal(rate)
    if shear_modulus is None and scenario == "friction":
        shear_modulus = FRICTION_SHEAR_MODULUS
    return sensor, ContactParams(thickness=thickness, modulus=modulus, shear_modulus=shear_modulus, friction=friction)


def run_simulation(
    object_kind: str = "plate",
    size: float | None = None,
    angle_deg: float = 0.0,
    *,
    scenario: str = "paper",
    tip: str | Fingertip = "murakami2006",
    edge_radius: float = 0.0,
    apex_angle_deg: float = 90.0,
    tilt_deg: float = 45.0,
    force: float = 0.5 * 9.80665,
    duration: float | None = None,
    t_contact: float = 2.0,
    t_stable: float = 4.0,
    rate: float = 50.0,
    joint_rotation_deg: float = JOINT_ROTATION_DEG,
    gravity_spin_deg: float = 1.0,
    object_mass: float = OBJECT_MASS,
    misalignment_deg: float = 0.0,
    disturbance_timing: str = "after_grasp",
    rock: bool = False,
    rock_amplitude_deg: float = ROCK_AMPLITUDE_DEG,
    rock_period: float = 1.0,
    rock_load: float = ROCK_LOAD,
    n_elements: int = DEFAULT_ELEMENTS,
    modulus: float = 0.6e6,
    shear_modulus: float | None = None,
    friction: float = 1.0,
    thickness: float | None = None,
    noise: bool = True,
    seed: int = 0,
    output: str | os.PathLike | None = None,
    truth: str | os.PathLike | None = None,
    units: str = "si",
    load_ratio: float = 0.25,
    load_direction: str = "across",
    load_profile: str = "push",
) -> SimLog:
    """Simulate from plain parameters (the ``softtip simulate`` command) and write files.

    Lengths in m, forces in N, angles in degrees, rates in Hz, moduli in Pa. ``scenario``
    is ``"paper"`` (the papers' hand, with joint and gravity disturbances), ``"push"``
    (a plain push, no disturbance) or ``"friction"`` (:func:`~softtip.sim.scenario.friction_scenario`:
    ``load_ratio`` of the grasp force, ``load_direction`` ``across`` or ``along`` the line,
    ``load_profile`` ``push``, ``drag`` or ``slip``; ``object_mass`` is ignored); ``rock`` adds the
    rocking of :func:`~softtip.sim.scenario.rock_scenario` to the paper scenario (``duration``
    defaults to its end; otherwise 10 s). Writes the log CSV to ``output`` and the ground truth
    to ``truth`` when given; returns the log. ``thickness`` (m): the skin's; None, the
    fingertip's ``skin_thickness`` (:func:`skin_thickness_of`).
    """
    tipo = load_fingertip(tip)
    thickness = skin_thickness_of(tipo, thickness)
    obj = make_object(object_kind, size, edge_radius=edge_radius, apex_angle=math.radians(apex_angle_deg),
                      tilt=math.radians(tilt_deg))
    if rock and scenario != "paper":
        raise ValueError("--rock needs the paper scenario")
    kw = scenario_options(
        force=force, t_contact=t_contact, t_stable=t_stable, duration=duration, joint_rotation_deg=joint_rotation_deg,
        gravity_spin_deg=gravity_spin_deg, misalignment_deg=misalignment_deg, disturbance_timing=disturbance_timing,
        rock=rock, rock_amplitude_deg=rock_amplitude_deg, rock_period=rock_period, rock_load=rock_load,
    )  # fmt: skip
    angle = math.radians(angle_deg)
    if rock:
        scn = rock_scenario(angle, object_mass=object_mass, **kw)
    elif scenario == "paper":
        scn = paper_scenario(angle, object_mass=object_mass, **kw)
    elif scenario == "push":
        scn = push_scenario(angle, **{k: kw[k] for k in ("force", "t_contact", "t_stable", "duration")})
    elif scenario == "friction":
        if load_direction not in ("across", "along"):
            raise ValueError(f"load_direction must be across or along, got {load_direction!r}")
        scn = friction_scenario(tipo, angle, load_ratio, across=load_direction == "across", profile=load_profile, **kw)
    else:
        raise ValueError(f"unknown scenario {scenario!r}; expected paper, push or friction")
    sensor, params = sensor_and_skin(rate=rate, noise=noise, thickness=thickness, modulus=modulus,
                                     shear_modulus=shear_modulus, friction=friction, scenario=scenario)  # fmt: skip
    log = simulate_grasp(tipo, obj, scn, sensor, seed, params=params, n_elements=n_elements)
    if output is not None:
        write_log_csv(log, output, units)
    if truth is not None:
        write_truth_json(log, truth)
    return log
