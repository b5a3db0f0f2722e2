"""Simulated probing logs: plane presses on a fingertip, for calibration's tests, benchmarks and examples.

:func:`simulate_probing` runs the skin simulator (:func:`softtip.sim.simulate_grasp` with a
:class:`~softtip.sim.HalfSpace`) on a sphere, capsule or ellipsoid; :func:`mesh_probing_log` writes a
soft-finger-model log for a mesh fingertip. :func:`probing_presses` plans the presses of both.
The fits are in :mod:`softtip.calibration`.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from softtip.core._vec import cross as _cross
from softtip.core._vec import tangent_basis as _tangent_basis
from softtip.core.fingertip import Fingertip
from softtip.core.mesh import MeshFingertip
from softtip.sim.foundation import ContactModel, ContactParams
from softtip.sim.objects import HalfSpace
from softtip.sim.scenario import Disturbance, push_scenario
from softtip.sim.sensor import SensorModel
from softtip.sim.simulate import simulate_grasp
from softtip.sim.skin import discretise_skin

__all__ = ["probing_presses", "simulate_probing", "mesh_probing_log"]


def probing_presses(
    n_presses: int,
    rng: np.random.Generator,
    max_tilt: float = math.radians(60.0),
    force_range: tuple[float, float] = (1.5, 4.0),
) -> list[dict]:
    """Random press plans: contact normal, force and two tangential slides per press.

    Parameters
    ----------
    n_presses : int
    rng : numpy Generator
    max_tilt : float
        Largest angle of the contact normal from the fingertip axis (+z), rad.
    force_range : (float, float)
        Each press's held force is drawn uniformly from this range, N.

    Returns
    -------
    list of dict
        ``normal`` (3,), ``force`` (N), ``slides`` ((2, 3), m, tangential).
    """
    plans = []
    golden = math.pi * (3.0 - math.sqrt(5.0))
    for i in range(n_presses):
        # an equal-area spiral over the cap, jittered: presses spread over the skin
        cz = 1.0 - (i + rng.uniform(0.2, 0.8)) / n_presses * (1.0 - math.cos(max_tilt))
        sz = math.sqrt(max(1.0 - cz * cz, 0.0))
        phi = golden * i + rng.uniform(-0.3, 0.3)
        n = np.array([sz * math.cos(phi), sz * math.sin(phi), cz])
        t1, t2 = _tangent_basis(n)
        a = rng.uniform(0.0, 2.0 * math.pi)
        d1 = math.cos(a) * t1 + math.sin(a) * t2
        d2 = _cross(n, d1)
        slides = np.stack((rng.uniform(0.3e-3, 0.7e-3) * d1, rng.choice([-1.0, 1.0]) * rng.uniform(0.3e-3, 0.7e-3) * d2))
        plans.append({"normal": n, "force": float(rng.uniform(*force_range)), "slides": slides})
    return plans


def simulate_probing(
    tip: Fingertip,
    duration: float = 30.0,
    *,
    press_duration: float = 1.5,
    slide: bool = True,
    max_tilt: float = math.radians(60.0),
    force_range: tuple[float, float] = (1.5, 4.0),
    sensor=None,
    rng: np.random.Generator | int | None = 0,
    n_elements: int = 12_000,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A simulated probing log: plane presses at many points, with friction and sensor noise.

    Each press (``press_duration`` s): 0.3 s untouched, the surface pushes along the skin
    normal to a force in ``force_range`` (default 1.5–4 N) over 0.3 s, then (``slide``) slides 0.3–0.7 mm along one tangent
    direction and then along the other, which turns the friction force. Uses
    :func:`softtip.sim.simulate_grasp` with a :class:`~softtip.sim.HalfSpace`.

    Parameters
    ----------
    tip : Fingertip
        The true fingertip: a shape with a simulator skin and a skin point for each normal
        (:meth:`~softtip.core.shape.Fingertip.support_point`: sphere, capsule — presses on
        the cap only, its ``axis_offset`` simulated — ellipsoid, or one of them mounted).
    duration : float
        s; ``duration / press_duration`` presses.
    slide : bool
        False: pure normal presses (a degenerate log: the radius is unobservable).
    max_tilt : float
        Presses cover contact normals up to this angle from +z, rad (a few degrees: all at
        one spot, another degenerate log).
    force_range : (float, float)
        Each press holds a force drawn uniformly from this range, N.
    sensor : softtip.sim.SensorModel, optional
        Default Nano17 class at 50 Hz.
    rng : Generator or int

    Returns
    -------
    t : ndarray, shape (N,)
        s.
    wrench : ndarray, shape (N, 6)
        Measured wrench, N and N·m.
    """
    rng = np.random.default_rng(rng)
    sensor = SensorModel() if sensor is None else sensor
    model = ContactModel(discretise_skin(tip, n_elements), ContactParams(), 2).prepare()
    n_presses = max(1, int(round(duration / press_duration)))
    ts, ws = [], []
    for k, plan in enumerate(probing_presses(n_presses, rng, max_tilt, force_range)):
        p = tip.support_point(plan["normal"])
        dist = ()
        if slide:
            s1, s2 = plan["slides"]
            dist = (
                Disturbance(translation=tuple(s1), start=0.7, end=1.0, label="slide 1"),
                Disturbance(translation=tuple(s2), start=1.0, end=1.35, label="slide 2"),
            )
        sc = push_scenario(
            0.0, contact_point=tuple(p), force=plan["force"], duration=press_duration,
            t_contact=0.3, t_stable=0.6, disturbances=dist, name=f"press {k}",
        )  # fmt: skip
        log = simulate_grasp(tip, HalfSpace(), sc, SensorModel.ideal(sensor.rate), model=model)
        ts.append(log.t + k * press_duration)
        ws.append(sensor.measure(log.wrench_true, rng))
    return np.concatenate(ts), np.concatenate(ws)


def mesh_probing_log(
    tip: MeshFingertip,
    n_presses: int,
    rng: np.random.Generator,
    *,
    compliance: float = 2e-4,
    noise=None,
    rate: float = 200.0,
    friction: float = 0.25,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A synthetic probing log of plane presses on ``tip`` (soft-finger model), for tests.

    Press ``k`` touches the skin where its normal points along a planned direction (the mesh
    vertex farthest that way), with the skin's interpolated normal there as the table's
    normal; the normal force rises and falls, the friction force (``friction`` × normal)
    turns through 90°, the skin indents by ``compliance √F``, and a small random spin is
    added. 0.3 s untouched first (the tare). ``noise``: a :class:`~softtip.core.noise.SensorNoise`.

    Returns
    -------
    t : array (N,)
    wrench : array (N, 6)
    """
    rows = [np.zeros((int(0.3 * rate), 6))]
    for plan in probing_presses(n_presses, rng):
        r0 = tip.vertices[np.argmax(tip.vertices @ plan["normal"])]
        r0 = tip.project(r0)
        n = tip.normal(r0)
        t1, t2 = _tangent_basis(n)
        k = 40
        force = plan["force"] * (0.5 + 0.5 * np.sin(np.linspace(0.2, math.pi - 0.2, k)))
        turn = np.linspace(0.0, math.radians(90.0), k) + rng.uniform(0.0, 2.0 * math.pi)
        f = -force[:, None] * n + friction * force[:, None] * (np.cos(turn)[:, None] * t1 + np.sin(turn)[:, None] * t2)
        r = r0 - compliance * np.sqrt(force)[:, None] * n
        m = np.cross(r, f) + rng.normal(scale=1e-4, size=k)[:, None] * n
        rows += [np.concatenate((f, m), axis=1), np.zeros((5, 6))]
    w = np.concatenate(rows)
    if noise is not None:
        w = w + rng.normal(size=w.shape) * np.concatenate((noise.force_std, noise.moment_std))
    return np.arange(len(w)) / rate, w
