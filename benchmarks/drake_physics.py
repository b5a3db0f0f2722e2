"""A second, independent contact model for the benchmarks: Drake's hydroelastic contact.

    from drake_physics import simulate_drake          # benchmarks/ on the path
    log = simulate_drake(murakami2006(), Plate(0.001), rock_scenario(0.4))   # a softtip.sim.SimLog

softtip's own simulator (:mod:`softtip.sim`) is a Winkler skin with a Coulomb-limited
elastic shear layer; the estimator's thresholds were tuned on it. This module produces the
same :class:`~softtip.sim.SimLog` (``t``, noisy ``wrench``, ``wrench_true``,
:class:`~softtip.sim.GroundTruth`) with the contact force computed by Drake
(https://drake.mit.edu, ``pip install drake``; checked with drake 1.51.1 on Python 3.11), so
that every benchmark runs unchanged on both physics (issue 27 item 1).

What is softtip's and what is Drake's
-------------------------------------
* softtip's: the *kinematics* of a grasp (:class:`~softtip.sim.GraspScenario`: placement,
  force profile, tilts, rocking, tangential-load targets over time), the object's line
  direction (the truth), the nominal contact point and normal, and the sensor model
  (:class:`~softtip.sim.SensorModel`: noise, quantisation, rate).
* Drake's: the *contact force*. The fingertip is a compliant-hydroelastic
  :class:`pydrake.geometry.Capsule` (radius ``R`` and cylinder ``length`` of the softtip
  :class:`~softtip.Capsule`, placed so that its upper hemisphere is centred at
  ``(0, 0, length)``; the lower hemisphere lies below the sensor plate and is never touched),
  welded to the world, whose frame is the sensor frame. Its pressure field is Drake's for a
  compliant capsule, ``p = E · d / R`` at depth ``d`` below the undeformed surface (measured,
  not assumed: :func:`pressure_check`, printed by the bench's ``--check``): with ``E = 2 MPa`` and ``R = 16 mm`` its
  surface stiffness, 1.25e8 Pa/m, is that of a 5 mm layer of 0.6 MPa (softtip's default
  Winkler skin, 1.2e8 Pa/m); penetrations stay below 2.5 mm, inside the 5 mm skin, so the
  shell under it is not modelled. ``mesh_resolution`` is Drake's resolution hint of the
  tip's tetrahedral mesh. The objects are rigid-hydroelastic: a plate edge is a
  :class:`~pydrake.geometry.Box` (sharp corners), a cylinder a
  :class:`~pydrake.geometry.Cylinder` (tessellated by its own resolution hint), a wedge a
  convex prism (written as an OBJ file, sharp apex), a plane a large box. Rounded plate
  corners and wedge tips (``edge_radius``, ``tip_radius``) and the cylinder-bottom fringe
  are not built (a ValueError says so).

Which scenario uses which solver, and why
-----------------------------------------
* ``solver="quasistatic"`` (default; the papers' grasp :func:`~softtip.sim.paper_scenario`,
  pushes and the rocking :func:`~softtip.sim.rock_scenario`): **frictionless**, per sample
  independently. The object is set to the scenario's orientation and translated along the
  push axis ``u`` (and, when the scenario prescribes a tangential load, across the line:
  along ``u × d``) until the force targets are met (Newton/Broyden steps on the offsets,
  bracketing for first touch); the wrench is the integral of Drake's pressure over its
  contact surface, ``f = ∫ p n dA``, ``m = ∫ r × p n dA`` about the sensor origin
  (:meth:`QueryObject.ComputeContactSurfaces`, polygon surfaces, each polygon fanned into
  triangles on which the linear pressure and ``r`` are integrated exactly). These grasps
  carry only small tangential loads (the object's weight, 0.05 N; the rocking push, 0.03 N),
  which a frictionless contact holds by the geometry (a sideways shift of a fraction of a
  millimetre). It is exactly the physics the issue describes: every pressure element acts
  along the rigid surface's normal, so on the cap the tangential load is locked to ``h``.
  A frictionless edge, cylinder or plane cannot carry a load *along* its line (or, for a
  plane, any tangential load): that component of the target is dropped (the object would
  slide; the extrusions are infinite, so sliding along the line changes nothing) and
  recorded in ``log.drake["dropped_load_max_N"]``.
* ``solver="sap"`` (the friction loads :func:`~softtip.sim.friction_scenario`, tangential
  load 0.2–0.5 of the normal force across or along the line): those loads are only held
  by friction, so a frictionless solve cannot produce them. A discrete
  :class:`~pydrake.multibody.plant.MultibodyPlant` with the SAP solver
  (``DiscreteContactApproximation.kSap``), hydroelastic contact with Hunt–Crossley
  dissipation and Coulomb friction ``friction``: the object hangs on three prismatic joints
  (along ``u`` and the two tangent axes) and three revolute joints; the orientation follows
  the scenario through stiff implicit PD actuators, the translations are *force-driven* (the
  force targets applied as actuation, heavily damped), and the whole grasp is simulated
  continuously at ``sap_dt`` (the friction state carries over from sample to sample, as
  stick and slip need), sampled at the sensor rate. The tip's tetrahedra are refined to half
  a plate's thickness (:func:`sap_tip_resolution`: SAP's friction acts once per contact
  polygon, and tetrahedra wider than the plate cut its two side faces unalike). The harness
  checks every sample that the object is still in the scenario: its orientation within
  0.5° of the scenario's (the PD holds it within 0.03°), its contact kept and its slide
  across the skin below 1 mm once the grasp is stable; otherwise the grasp raises
  RuntimeError ("the object left the scenario", "friction cannot hold the load"),
  remembered in the cache. The object's pose over time is kept in
  :attr:`DrakeSimLog.diagnostics` (``bench_physics.py --sap-trace`` plots it). The wrench is the contact wrench on the
  fingertip from the contact results (:class:`HydroelasticContactInfo`), moved to the
  sensor origin; its normal part is recomputed from the pressure on the contact surface and
  the rest is the friction, whose lever below the surface point gives
  :attr:`GroundTruth.friction_depth` (the hydroelastic tractions act *on the contact
  surface*, which is the rigid object's surface inside the undeformed skin, so at the depth
  of the pressed-in surface).

What the frictionless physics implies (measured with ``bench_physics.py --check``)
-------------------------------------------------------------------------------
Drake's compliant capsule field depends only on the distance from the cap centre ``c``,
so on every flat face of a rigid object the pressure is symmetric about the foot of the
perpendicular from ``c``, and the face's resultant passes through ``c``: ``m ≈ c × f``.
Relative to the latched point and normal, ``h = k n₀ × f_t`` with ``k = −15.9 mm ≈ −R``
(residual 3–8 %, from the truncated faces). The wrench is then a function of the force
alone: a 1 mm plate, a 120° wedge, a Ø 4 mm cylinder and a 10 mm plate rocked alike give
wrenches within 0.04 N·mm and 0.2 mN of each other (below the sensor noise); the object
shows only through which loads it can carry (a line cannot carry one along itself, so
the tilt of its face along the line turns the force; a plane and a 15 mm plate at this
depth carry none, so the load stays at the target).

With friction (``sap``) the lever of the friction force about ``r_c`` is not the depth of
the contact surface: side faces of a thin plate carry friction couples (a 1 mm plate pressed
3.1 mm deep carries 12.6 N of pressure on its side faces and 4.9 N on its edge), and
tractions left by the disturbances before the load add couples (SAP's friction has no
tangential compliance, so the rotations slide the embedded faces at the Coulomb limit: the
1° gravity spin leaves −16.5 N·mm about the normal on a 1 mm plate, −12.7 on a 2 mm plate,
which reach ``h`` through the line's 3° tilt out of the tangent plane; tetrahedra fine
enough, see :func:`sap_tip_resolution`). :attr:`GroundTruth.friction_depth` therefore records
the pressure-weighted depth of the contact surface below ``r_c`` (the depth where the
tractions act if they follow the pressure, as on the Winkler skin). With the tip's 2 mm
tetrahedra a 1 mm plate loaded across at 0.5 slid off at μ = 1; refined to 0.5 mm it holds.

Truth that differs from softtip's simulator: ``pressure_centre`` is on the contact surface
(the rigid object's surface, deformed skin), not on the undeformed skin; ``slip_fraction``
is NaN (not available); ``depth`` is the largest pressure over ``E / R``.

Logs are cached on disk (``benchmarks/.cache/drake/<hash>.npz``, the noise-free wrench and
the truth; the noise is drawn on loading) because a log takes 5–450 s. The key holds this
file's own source (:data:`HARNESS`): a log is simulated again whenever the harness changed,
so no figure comes from a log an older harness made (a version number bumped by hand was
once left behind: the two-physics page quoted an old log of the 15 mm plate for a while).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from softtip import Capsule, Sphere
from softtip.core.fingertip import Fingertip
from softtip.sim import (
    ContactParams,
    Cylinder,
    GraspScenario,
    GroundTruth,
    HalfSpace,
    Plate,
    RigidObject,
    SensorModel,
    SimLog,
    Wedge,
    line_angle,
    tangent_frame,
)
from softtip.sim.pose import Pose

__all__ = ["DRAKE_MISSING", "DrakeSimLog", "drake_available", "drake_version", "pressure_check", "sap_tip_resolution",
           "simulate_drake", "CACHE_DIR"]

#: The message printed when Drake is not installed.
DRAKE_MISSING = (
    "Drake is not installed: the hydroelastic physics needs it. Install it with "
    "`pip install drake` (or `pip install softtip[bench]`); --physics winkler runs without it."
)
#: Where simulated logs are cached.
CACHE_DIR = Path(__file__).resolve().parent / ".cache" / "drake"
#: This file's source, hashed: part of every cache key, so that editing the harness
#: invalidates the logs it made (a comment too: simulating again is cheaper than a stale figure).
HARNESS = hashlib.sha256(Path(__file__).read_bytes()).hexdigest()[:16]
_FTOL = 5e-5  # N: force tolerance of the quasi-static solve (the sensor resolves 6 mN)
_FTOL_JUMP = 5e-3  # N: residual accepted where the piecewise-linear force jumps (a mesh face enters)
_STEP_MAX = 5e-4  # m: largest Newton step of an offset


def drake_available() -> bool:
    try:
        import pydrake  # noqa: F401
    except ImportError:
        return False
    return True


def drake_version() -> str:
    try:
        from importlib.metadata import version

        return version("drake")
    except Exception:  # noqa: BLE001
        return "unknown"


@dataclass(frozen=True, eq=False)
class DrakeSimLog(SimLog):
    """A :class:`~softtip.sim.SimLog` from Drake; ``drake``: the physics' settings and notes;
    ``diagnostics``: per-sample arrays of the harness (``sap``: ``object_turn``, (n, 3) rad, the
    rotation vector from the scenario's orientation to the object's, world frame, NaN before
    contact; ``object_offset``, (n, 3) m, the object's origin relative to the nominal contact
    point)."""

    drake: dict = field(default_factory=dict)
    diagnostics: dict = field(default_factory=dict)

    def metadata(self) -> dict:
        out = super().metadata()
        out["skin"] = {"physics": "drake-hydroelastic", **self.drake}
        return out


# -- geometry ---------------------------------------------------------------------------
def _tip_shape(tip: Fingertip) -> tuple[float, float]:
    """(radius, cylinder length) of a capsule or a sphere centred on the z axis."""
    if isinstance(tip, Capsule):
        if any(tip.axis_offset):
            raise ValueError("drake physics: a capsule with an axis offset is not built")
        return tip.radius, tip.length
    if isinstance(tip, Sphere):
        if tip.center[0] or tip.center[1]:
            raise ValueError("drake physics: a sphere off the z axis is not built")
        return tip.radius, -1.0  # marker: a sphere at center
    raise ValueError(f"drake physics builds capsule and sphere fingertips, got {type(tip).__name__}")


def _wedge_obj(apex_angle: float, depth: float = 0.015, half_len: float = 0.03) -> str:
    """OBJ text of a wedge prism in the contact frame: apex line on z', bisector along −x'."""
    w = depth * math.tan(0.5 * apex_angle)
    pts2 = [(0.0, 0.0), (-depth, w), (-depth, -w)]
    v = [(x, y, z) for z in (-half_len, half_len) for x, y in pts2]
    faces = [(1, 3, 2), (4, 5, 6), (1, 2, 5), (1, 5, 4), (1, 4, 6), (1, 6, 3), (2, 3, 6), (2, 6, 5)]
    lines = [f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in v] + [f"f {a} {b} {c}" for a, b, c in faces]
    return "\n".join(lines) + "\n"


def _object_geometry(obj: RigidObject, resolution: float):
    """(list of (shape, X_BG)) of ``obj`` in its contact frame (the body frame)."""
    from pydrake.geometry import Box, Convex
    from pydrake.geometry import Cylinder as DCylinder
    from pydrake.math import RigidTransform

    if isinstance(obj, Plate):
        if obj.edge_radius > 0.0:
            raise ValueError("drake physics: rounded plate corners are not built (edge_radius must be 0)")
        return [(Box(0.02, obj.thickness, 0.06), RigidTransform([-0.01, 0.0, 0.0]))]
    if isinstance(obj, Cylinder):
        return [(DCylinder(0.5 * obj.diameter, 0.06), RigidTransform([-0.5 * obj.diameter, 0.0, 0.0]))]
    if isinstance(obj, Wedge):
        if obj.tip_radius > 0.0:
            raise ValueError("drake physics: a rounded wedge tip is not built (tip_radius must be 0)")
        path = Path(tempfile.gettempdir()) / f"softtip_wedge_{math.degrees(obj.apex_angle):.4f}.obj"
        if not path.exists():
            tmp = path.with_suffix(f".{os.getpid()}.tmp")
            tmp.write_text(_wedge_obj(obj.apex_angle))
            os.replace(tmp, path)
        return [(Convex(str(path)), RigidTransform())]
    if isinstance(obj, HalfSpace):
        return [(Box(0.02, 0.1, 0.1), RigidTransform([-0.01, 0.0, 0.0]))]
    raise ValueError(f"drake physics builds plates, cylinders, wedges and planes, got {type(obj).__name__}")


def sap_tip_resolution(obj: RigidObject, mesh_resolution: float) -> float:
    """The fingertip's resolution hint of a ``sap`` grasp of ``obj``, m: ``mesh_resolution``,
    refined to half the thickness of a plate thinner than twice it.

    SAP applies friction once per contact polygon, and the polygons are the object's faces cut
    by the tip's tetrahedra: with tetrahedra wider than the plate, the two side faces of a
    1 mm plate embedded 3.1 mm deep (12.6 N of pressure on them, 4.9 N on the edge) are cut
    unalike, and the joint rotation leaves a friction couple of 4.4 N·mm about the plate's own
    line at a 2 mm hint (0.02 N·mm at 0.5 mm; the 2 mm plate −0.01 at 2 and 1 mm): ``h`` in the
    tangent plane 40° off ``n × d`` before the load. ``h`` along the line at 6 s, by hint:
    4.1 N·mm at 2 mm, 1.8 at 1.5, −0.2 at 1, −0.5 at 0.75, −0.85 at 0.5, −0.92 at 0.35 (what
    remains is the gravity spin's friction couple seen through the line's 3° tilt).
    Frictionless solves integrate the pressure exactly on the polygons and keep the hint.
    """
    if isinstance(obj, Plate):
        return min(mesh_resolution, 0.5 * obj.thickness)
    return mesh_resolution


def _object_resolution(obj: RigidObject, mesh_resolution: float) -> float:
    if isinstance(obj, Cylinder):
        return min(mesh_resolution, 0.1 * obj.diameter)  # ≥ 31 facets around the circumference
    return mesh_resolution


@dataclass
class _World:
    """A built diagram: plant, scene graph, contexts, the object's body, the tip's geometry id."""

    diagram: object
    plant: object
    scene_graph: object
    context: object
    plant_context: object
    sg_context: object
    body: object
    tip_id: object
    modulus: float
    radius: float
    centre: NDArray[np.float64]  # cap centre
    length: float


def _build(tip: Fingertip, obj: RigidObject, *, modulus: float, mesh_resolution: float, friction: float,
           dissipation: float = 0.0, time_step: float = 0.0, joints: bool = False):
    from pydrake.geometry import (
        AddCompliantHydroelasticProperties,
        AddContactMaterial,
        AddRigidHydroelasticProperties,
        ProximityProperties,
    )
    from pydrake.geometry import Capsule as DCapsule
    from pydrake.geometry import Sphere as DSphere
    from pydrake.math import RigidTransform
    from pydrake.multibody.plant import (
        AddMultibodyPlant,
        ContactModel,
        CoulombFriction,
        DiscreteContactApproximation,
        MultibodyPlantConfig,
    )
    from pydrake.multibody.tree import SpatialInertia
    from pydrake.systems.framework import DiagramBuilder

    radius, length = _tip_shape(tip)
    builder = DiagramBuilder()
    cfg = MultibodyPlantConfig(time_step=time_step, contact_model="hydroelastic", use_sampled_output_ports=False)
    if time_step > 0.0:
        cfg.discrete_contact_approximation = "sap"
    plant, sg = AddMultibodyPlant(cfg, builder)
    tprops = ProximityProperties()
    AddCompliantHydroelasticProperties(mesh_resolution, modulus, tprops)
    AddContactMaterial(dissipation=dissipation if dissipation > 0.0 else None,
                       friction=CoulombFriction(friction, friction), properties=tprops)  # fmt: skip
    if length >= 0.0:
        shape, centre = DCapsule(radius, length), np.array([0.0, 0.0, 0.5 * length])
        cap = np.array([0.0, 0.0, length])
    else:
        shape, centre = DSphere(radius), np.asarray(tip.center, dtype=float)
        cap = centre
    tip_id = plant.RegisterCollisionGeometry(plant.world_body(), RigidTransform(centre), shape, "fingertip", tprops)
    body = plant.AddRigidBody("object", SpatialInertia.SolidSphereWithMass(0.01, 0.01))
    oprops = ProximityProperties()
    AddRigidHydroelasticProperties(_object_resolution(obj, mesh_resolution), oprops)
    AddContactMaterial(friction=CoulombFriction(friction, friction), properties=oprops)
    for k, (g, x) in enumerate(_object_geometry(obj, mesh_resolution)):
        plant.RegisterCollisionGeometry(body, x, g, f"object{k}", oprops)
    plant.set_contact_model(ContactModel.kHydroelastic)
    extra = joints(plant, body) if callable(joints) else None
    if time_step > 0.0:
        plant.set_discrete_contact_approximation(DiscreteContactApproximation.kSap)
    plant.Finalize()
    diagram = builder.Build()
    ctx = diagram.CreateDefaultContext()
    w = _World(diagram, plant, sg, ctx, plant.GetMyMutableContextFromRoot(ctx), sg.GetMyContextFromRoot(ctx), body,
               tip_id, modulus, radius, cap, length)  # fmt: skip
    return w, extra


def _integrate_surfaces(surfaces, tip_id, centroid_rule: bool = False) -> tuple[NDArray[np.float64], dict]:
    """Wrench on the fingertip about the origin (6,), and contact-surface statistics.

    Each polygon is fanned into triangles; on a triangle (a, b, c) with linear pressure
    ``p``: ``∫ p dA = A (pa + pb + pc) / 3`` and ``∫ p r dA = A/12 Σ (p_i + Σp) r_i``, exact.
    ``centroid_rule``: each polygon's pressure force applied at its area centroid instead
    (SAP's one-point quadrature per face, so that the friction's share of SAP's contact
    wrench comes out right).
    """
    f = np.zeros(3)
    m = np.zeros(3)
    pr_tot = np.zeros(3)
    p_tot = 0.0
    area = 0.0
    pmax = 0.0
    faces = []
    for s in surfaces:
        sign = 1.0 if s.id_M() == tip_id else -1.0  # face normals point out of N, into M
        mesh, field_ = s.poly_mesh_W(), s.poly_e_MN()
        nv = mesh.num_vertices()
        V = np.array([mesh.vertex(i) for i in range(nv)]).reshape(nv, 3)
        P = np.array([field_.EvaluateAtVertex(i) for i in range(nv)])
        fd = np.asarray(mesh.face_data(), dtype=np.intp)
        ia, ib, ic, fid = [], [], [], []
        k = 0
        j = 0
        while k < len(fd):
            cnt = fd[k]
            idx = fd[k + 1:k + 1 + cnt]
            for q in range(1, cnt - 1):
                ia.append(idx[0])
                ib.append(idx[q])
                ic.append(idx[q + 1])
                fid.append(j)
            k += cnt + 1
            j += 1
        ia, ib, ic, fid = map(np.asarray, (ia, ib, ic, fid))
        normals = np.array([mesh.face_normal(i) for i in range(j)]).reshape(j, 3)
        a, b, c = V[ia], V[ib], V[ic]
        pa, pb, pc = P[ia], P[ib], P[ic]
        A = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
        ps = pa + pb + pc
        ip = A * ps / 3.0  # ∫ p dA per triangle
        ipr = (A / 12.0)[:, None] * ((pa + ps)[:, None] * a + (pb + ps)[:, None] * b + (pc + ps)[:, None] * c)
        n = normals[fid]
        f += sign * (ip[:, None] * n).sum(axis=0)
        if centroid_rule:
            ac = np.zeros((j, 3))
            np.add.at(ac, fid, A[:, None] * (a + b + c) / 3.0)
            af = np.bincount(fid, A, minlength=j)
            pf = np.bincount(fid, ip, minlength=j)
            cf = ac / np.where(af > 0.0, af, 1.0)[:, None]
            m += sign * np.cross(cf * pf[:, None], normals).sum(axis=0)
        else:
            m += sign * np.cross(ipr, n).sum(axis=0)
        pr_tot += ipr.sum(axis=0)
        p_tot += float(ip.sum())
        area += float(A.sum())
        pmax = max(pmax, float(P.max(initial=0.0)))
        faces.append((ipr, ip, n, sign))
    stats = {"area": area, "pmax": pmax, "centre": pr_tot / p_tot if p_tot > 0.0 else np.full(3, np.nan),
             "faces": faces}  # fmt: skip
    return np.r_[f, m], stats


def _set_pose(w: _World, pose: Pose) -> None:
    from pydrake.math import RigidTransform, RotationMatrix

    w.plant.SetFreeBodyPose(w.plant_context, w.body, RigidTransform(RotationMatrix(pose.rotation), pose.translation))


def _contact(w: _World, pose: Pose):
    from pydrake.geometry import HydroelasticContactRepresentation

    _set_pose(w, pose)
    q = w.scene_graph.get_query_output_port().Eval(w.sg_context)
    return _integrate_surfaces(q.ComputeContactSurfaces(HydroelasticContactRepresentation.kPolygon), w.tip_id)


def pressure_check(tip: Fingertip, *, modulus: float = 2e6, mesh_resolution: float = 0.002,
                   depth: float = 1e-3) -> dict:
    """Press a plane ``depth`` (m) into the tip's apex: the pressure per depth below the
    undeformed surface against ``E / R`` (Drake's compliant capsule field), the force, and
    that of a Winkler layer of the same surface stiffness (``E_w / h = E / R``)."""
    w, _ = _build(tip, HalfSpace(), modulus=modulus, mesh_resolution=mesh_resolution, friction=0.0)
    top = w.centre + np.array([0.0, 0.0, w.radius])
    pose = Pose.from_frame([0.0, 0.0, -1.0], [1.0, 0.0, 0.0], top - np.array([0.0, 0.0, depth]))
    wr, st = _contact(w, pose)
    # a plane at depth δ in the field p = E (R − r) / R (r: distance from the cap centre), a = R − δ:
    # F = 2π E / R ∫_a^R (R − r) r dr = 2π E / R [R (R² − a²) / 2 − (R³ − a³) / 3]
    r, a = w.radius, w.radius - depth
    exact = 2.0 * math.pi * modulus / r * (r * (r * r - a * a) / 2.0 - (r**3 - a**3) / 3.0)
    return {"p_max_over_E_depth_per_R": st["pmax"] / (modulus * depth / w.radius), "force_N": float(-wr[2]),
            "force_field_N": exact, "area_mm2": st["area"] * 1e6}  # fmt: skip


# -- cache --------------------------------------------------------------------------------
def _tip_key(tip: Fingertip) -> dict:
    r, length = _tip_shape(tip)
    return {"kind": type(tip).__name__, "radius": r, "length": length,
            "center": list(getattr(tip, "center", (0, 0, 0)))}  # fmt: skip


def _cache_key(tip, obj, scenario, rate, settings) -> str:
    payload = {"harness": HARNESS, "tip": _tip_key(tip), "obj": obj.describe(), "scenario": scenario.as_dict(),
               "rate": rate, **settings}  # fmt: skip
    text = json.dumps(payload, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:24]


_TRUTH_FIELDS = [f.name for f in dataclasses.fields(GroundTruth)]


def _save(path: Path, t, wrench, truth: GroundTruth, info: dict) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(f".{os.getpid()}.tmp.npz")
    diag = info.get("diagnostics", {})
    info = {k: v for k, v in info.items() if k != "diagnostics"}
    np.savez_compressed(tmp, t=t, wrench_true=wrench, info=json.dumps(info),
                        **{f"truth_{k}": getattr(truth, k) for k in _TRUTH_FIELDS},
                        **{f"diag_{k}": v for k, v in diag.items()})  # fmt: skip
    os.replace(tmp, path)


def _load(path: Path):
    with np.load(path) as z:
        truth = GroundTruth(**{k: z[f"truth_{k}"] for k in _TRUTH_FIELDS})
        diag = {k[5:]: z[k] for k in z.files if k.startswith("diag_")}
        return z["t"], z["wrench_true"], truth, {**json.loads(str(z["info"])), "diagnostics": diag}


# -- the simulation -----------------------------------------------------------------------
def simulate_drake(
    tip: Fingertip,
    obj: RigidObject,
    scenario: GraspScenario,
    sensor: SensorModel | None = None,
    rng: np.random.Generator | int | None = None,
    *,
    modulus: float = 2e6,
    mesh_resolution: float = 0.002,
    friction: float = 1.0,
    solver: str = "quasistatic",
    dissipation: float = 5.0,
    sap_dt: float = 1e-3,
    tip_resolution: float | None = None,
    cache: bool | str | os.PathLike = True,
    progress: bool = True,
) -> DrakeSimLog:
    """Simulate a grasp of ``obj`` by ``tip`` with Drake's hydroelastic contact.

    Parameters
    ----------
    tip, obj, scenario, sensor, rng
        As :func:`softtip.sim.simulate_grasp` (``rng`` None: seed 0). ``tip``: a
        :class:`~softtip.Capsule` (no axis offset) or a :class:`~softtip.Sphere` on the z axis.
    modulus : float
        Drake's hydroelastic modulus of the tip, Pa (pressure ``E · d / R`` at depth ``d``).
    mesh_resolution : float
        Drake's resolution hint of the tip's tetrahedral mesh (and of rigid curved objects), m.
    friction : float
        Coulomb friction coefficient (used by ``sap`` only).
    solver : {"quasistatic", "sap"}
        See the module docs: frictionless per-sample force solve, or SAP with friction.
    dissipation : float
        Hunt–Crossley dissipation, s/m (``sap``).
    sap_dt : float
        Time step of the ``sap`` simulation, s.
    tip_resolution : float, optional
        The tip's resolution hint of a ``sap`` grasp, m (None: :func:`sap_tip_resolution`).
    cache : bool or path
        Cache the noise-free result (True: :data:`CACHE_DIR`; a path: that folder; False: no).
    progress : bool
        Show a progress bar while simulating.

    Returns
    -------
    DrakeSimLog
    """
    if solver not in ("quasistatic", "sap"):
        raise ValueError(f"solver must be quasistatic or sap, got {solver!r}")
    sensor = SensorModel() if sensor is None else sensor
    seed = None
    if rng is None or isinstance(rng, (int, np.integer)):
        seed = 0 if rng is None else int(rng)
        rng = np.random.default_rng(seed)
    settings = {"modulus": modulus, "mesh_resolution": mesh_resolution, "solver": solver,
                "friction": friction if solver == "sap" else 0.0}  # fmt: skip
    if solver == "sap":
        settings.update(dissipation=dissipation, sap_dt=sap_dt, sap_harness=_SAP_HARNESS,
                        tip_resolution=sap_tip_resolution(obj, mesh_resolution) if tip_resolution is None
                        else float(tip_resolution))  # fmt: skip
    path = None
    if cache:
        folder = CACHE_DIR if cache is True else Path(cache)
        path = folder / f"{_cache_key(tip, obj, scenario, sensor.rate, settings)}.npz"
    failed = None if path is None else path.with_suffix(".failed.txt")
    if failed is not None and failed.exists():
        raise RuntimeError(failed.read_text().strip() + " (cached)")
    if path is not None and path.exists():
        t, wrench, truth, info = _load(path)
    else:
        if not drake_available():
            raise ImportError(DRAKE_MISSING)
        t0 = time.perf_counter()
        run = _run_quasistatic if solver == "quasistatic" else _run_sap
        try:
            t, wrench, truth, info = run(tip, obj, scenario, sensor, settings, progress)
        except RuntimeError as exc:  # remembered: a grasp this physics cannot hold stays so
            if failed is not None:
                failed.parent.mkdir(parents=True, exist_ok=True)
                failed.write_text(f"{exc}\n")
            raise
        info = {**info, "cpu_s": round(time.perf_counter() - t0, 2), "drake": drake_version()}
        if path is not None:
            _save(path, t, wrench, truth, info)
    return DrakeSimLog(
        t=t, wrench=sensor.measure(wrench, rng), wrench_true=wrench, truth=truth, tip=tip, obj=obj,
        scenario=scenario, sensor=sensor, params=ContactParams(modulus=modulus, friction=max(friction, 0.0)),
        n_elements=0, quadrature=0, seed=seed, drake={**settings, **{k: v for k, v in info.items() if k != "diagnostics"}},
        diagnostics=info.get("diagnostics", {}),
    )  # fmt: skip


def _bar(n: int, label: str, on: bool):
    if not on:
        return None
    from tqdm import tqdm

    return tqdm(total=n, desc=label, unit="sample", leave=False, file=sys.stderr, mininterval=1.0)


def _line_dir(obj: RigidObject, pose: Pose, r_c) -> NDArray[np.float64]:
    return pose.rotate(obj.line_direction_local(pose.inverse_apply(np.asarray(r_c)[None, :])))[0]


def _run_quasistatic(tip, obj, scenario, sensor, settings, progress):
    w, _ = _build(tip, obj, modulus=settings["modulus"], mesh_resolution=settings["mesh_resolution"], friction=0.0)
    t = sensor.times(scenario.duration)
    n = len(t)
    r_c, n_c, u = scenario.nominal_contact(tip)
    base = scenario.placement(tip) @ obj.pose
    target = np.where(t >= scenario.t_contact, scenario.force_target(t), 0.0)
    load = np.zeros(3) if scenario.tangential_force is None else np.asarray(scenario.tangential_force)
    ramp = np.where(t >= scenario.t_contact, scenario.load_ramp(t), 0.0)
    has_line = not isinstance(obj, HalfSpace)

    wrench = np.zeros((n, 6))
    direction = np.full((n, 3), np.nan)
    centre = np.full((n, 3), np.nan)
    area, depth, push = np.zeros(n), np.zeros(n), np.zeros(n)
    in_contact = np.zeros(n, dtype=bool)
    dropped = 0.0
    fallback = 0
    hist: list[NDArray[np.float64]] = []
    jac = None
    bar = _bar(n, f"drake {obj.kind}", progress)
    for i in range(n):
        ti = float(t[i])
        pre = scenario.disturbance_pose(ti, r_c) @ base
        d = _line_dir(obj, pre, r_c) if has_line else np.full(3, np.nan)
        direction[i] = d
        if has_line:
            across = np.cross(u, d)
            across /= np.linalg.norm(across)
            axes = np.stack((u, across))
        else:
            axes = u[None, :]
        goal_t = ramp[i] * load + scenario.disturbance_load(ti)
        goal = np.r_[target[i], (axes[1:] @ goal_t)]
        tang = goal_t - (goal_t @ u) * u
        dropped = max(dropped, float(np.linalg.norm(tang - axes[1:].T @ goal[1:])))

        def evaluate(x):
            pose = Pose._trusted(pre.rotation, pre.translation + x @ axes)
            wr, st = _contact(w, pose)
            return wr, st, axes @ wr[:3] - goal

        if target[i] <= 0.0:
            x = np.zeros(len(axes))
            x[0] = min(-scenario.approach_speed * (scenario.t_contact - ti), 0.0)
            wr, st, _ = evaluate(x)
        else:
            x = hist[-1].copy() if hist else np.zeros(len(axes))
            if len(hist) >= 2 and len(hist[-1]) == len(hist[-2]):
                x += hist[-1] - hist[-2]
            if len(x) != len(axes):
                x = np.r_[x[0], np.zeros(len(axes) - 1)]
            try:
                x, wr, st, jac = _solve(evaluate, x, jac)
            except RuntimeError:
                if len(axes) == 1:
                    raise
                # a load across that the frictionless contact cannot hold here (a wide face:
                # shifting it across changes nothing): push only, the load dropped
                dropped = max(dropped, float(np.linalg.norm(tang)))
                fallback += 1
                axes = u[None, :]
                goal = goal[:1]
                x, wr, st, jac1 = _solve(evaluate, x[:1].copy(), None)
            hist.append(x)
        wrench[i] = wr
        centre[i] = st["centre"]
        area[i] = st["area"]
        depth[i] = st["pmax"] * w.radius / settings["modulus"]
        push[i] = x[0]
        in_contact[i] = st["area"] > 0.0
        if bar is not None:
            bar.update()
    if bar is not None:
        bar.close()
    truth = _truth(direction, r_c, n_c, u, wrench, centre, area, depth, push, target, in_contact, np.full(n, np.nan))
    return t, wrench, truth, {"dropped_load_max_N": dropped, "push_only_samples": fallback}


def _solve(evaluate, x, jac):
    """Offsets ``x`` whose force residual is zero: bracket first touch, then Newton steps with a
    Broyden-updated Jacobian (a difference Jacobian when a step does not reduce the residual)."""
    k = len(x)
    wr, st, r = evaluate(x)
    # first touch: push in until the force along u exceeds the target's sign change
    step = 2e-5
    guard = 0
    while st["area"] <= 0.0:
        x[0] += step
        step *= 2.0
        wr, st, r = evaluate(x)
        guard += 1
        if guard > 40:
            raise RuntimeError("drake physics: no contact found along the push axis")
    if jac is None or jac.shape != (k, k):
        jac = _fd_jac(evaluate, x, r)
    for _ in range(40):
        if np.all(np.abs(r) <= _FTOL):
            return x, wr, st, jac
        dx = np.linalg.lstsq(jac, -r, rcond=None)[0]
        big = float(np.abs(dx).max())
        if big > _STEP_MAX:
            dx *= _STEP_MAX / big
        y = x + dx
        wy, sy, ry = evaluate(y)
        if sy["area"] <= 0.0:  # stepped out of contact: halve back toward x
            dx *= 0.5
            y = x + dx
            wy, sy, ry = evaluate(y)
        if np.abs(ry).max() < np.abs(r).max():
            jac = jac + np.outer(ry - r - jac @ dx, dx) / float(dx @ dx)  # Broyden
            x, wr, st, r = y, wy, sy, ry
        else:
            jac = _fd_jac(evaluate, x, r)
            dx = np.linalg.lstsq(jac, -r, rcond=None)[0]
            big = float(np.abs(dx).max())
            if big > _STEP_MAX:
                dx *= _STEP_MAX / big
            for _ in range(12):
                y = x + dx
                wy, sy, ry = evaluate(y)
                if np.abs(ry).max() < np.abs(r).max():
                    break
                dx *= 0.5
            else:
                if np.abs(r).max() < _FTOL_JUMP:  # a jump of the piecewise-linear force: as close as it gets
                    return x, wr, st, jac
                raise RuntimeError(f"drake physics: force solve stalled at residual {r.tolist()} N")
            x, wr, st, r = y, wy, sy, ry
    if np.abs(r).max() < _FTOL_JUMP:
        return x, wr, st, jac
    raise RuntimeError(f"drake physics: force solve did not converge (residual {r.tolist()} N)")


def _fd_jac(evaluate, x, r, h: float = 2e-6):
    k = len(x)
    jac = np.empty((k, k))
    for j in range(k):
        y = x.copy()
        y[j] += h
        jac[:, j] = (evaluate(y)[2] - r) / h
    return jac


_SAP_DAMPING = 30.0  # N·s/m: damping of the force-driven translations (overdamped at ≈ 4000 N/m, 0.05 kg)
_SAP_PD = (50.0, 0.05)  # N·m/rad, N·m·s/rad: the implicit PD that holds the prescribed orientation
_SAP_INPUT_DT = 5e-3  # s: the force targets and the orientation are updated this often
_SAP_SLID = 1e-3  # m: a slide across the skin beyond this means friction did not hold the load
#: rad: the object's orientation may differ from the scenario's by this much (measured: ≤ 0.03°)
_SAP_TURN_MAX = math.radians(0.5)
#: Bumped whenever the sap harness changes (its logs only): 2 = tip hint by the plate's
#: thickness, the object's pose recorded and checked.
_SAP_HARNESS = 2


def _frame_axes(u: NDArray[np.float64]) -> NDArray[np.float64]:
    """Columns ``(u, t1, t2)``, right-handed: the push axis and two tangent axes."""
    t1 = tangent_frame(-u)[0]
    return np.column_stack((u, t1, np.cross(u, t1)))


def _run_sap(tip, obj, scenario, sensor, settings, progress):
    """SAP with friction: the object on three force-driven prismatic joints (along ``u`` and
    two tangent axes) and three PD-held revolute joints (the scenario's orientation), the
    grasp simulated continuously and sampled at the sensor rate."""
    from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix
    from pydrake.multibody.tree import (
        FixedOffsetFrame,
        PdControllerGains,
        PrismaticJoint,
        RevoluteJoint,
        SpatialInertia,
    )
    from pydrake.systems.analysis import Simulator

    r_c, n_c, u = scenario.nominal_contact(tip)
    for d in scenario.disturbances:
        if any(d.translation) or d.pivot is not None:
            raise ValueError("sap solver: disturbances must be rotations about the nominal contact point")
    base = scenario.placement(tip) @ obj.pose
    if np.linalg.norm(base.translation - r_c) > 1e-12:
        raise ValueError("sap solver: an object pose offset is not supported")
    RF = _frame_axes(u)
    joints = {}

    def chain(plant, body):
        F = plant.AddFrame(FixedOffsetFrame("F", plant.world_frame(), RigidTransform(RotationMatrix(RF), r_c)))
        parent = F
        links = []
        for k in range(5):
            links.append(plant.AddRigidBody(f"link{k}", SpatialInertia.SolidSphereWithMass(0.005, 0.005)))
        for k, ax in enumerate(np.eye(3)):
            j = plant.AddJoint(PrismaticJoint(f"slide{k}", parent, links[k].body_frame(), ax, damping=_SAP_DAMPING))
            joints[f"slide{k}"] = j
            parent = links[k].body_frame()
        # revolutes z, y, x (in F's axes): R = Rz(yaw) Ry(pitch) Rx(roll), RollPitchYaw's order
        child_on_obj = plant.AddFrame(FixedOffsetFrame(
            "C", body.body_frame(), RigidTransform(RotationMatrix(RF.T @ base.rotation)).inverse()))
        for k, (nm, ax) in enumerate((("yaw", [0, 0, 1]), ("pitch", [0, 1, 0]), ("roll", [1, 0, 0]))):
            child = links[3 + k].body_frame() if k < 2 else child_on_obj
            j = plant.AddJoint(RevoluteJoint(nm, parent, child, np.asarray(ax, float), damping=0.0))
            act = plant.AddJointActuator(f"a_{nm}", j)
            act.set_controller_gains(PdControllerGains(p=_SAP_PD[0], d=_SAP_PD[1]))
            joints[nm] = j
            parent = child
        return joints

    w, _ = _build(tip, obj, modulus=settings["modulus"], mesh_resolution=settings["tip_resolution"],
                  friction=settings["friction"], dissipation=settings["dissipation"], time_step=settings["sap_dt"],
                  joints=chain)  # fmt: skip
    plant = w.plant
    plant.mutable_gravity_field().set_gravity_vector(np.zeros(3))
    pc = w.plant_context
    nv = plant.num_velocities()
    vidx = {k: j.velocity_start() for k, j in joints.items()}
    instance = joints["yaw"].model_instance()
    plant.get_actuation_input_port().FixValue(pc, np.zeros(plant.num_actuated_dofs()))
    applied = plant.get_applied_generalized_force_input_port()
    desired = plant.get_desired_state_input_port(instance)
    order = [plant.get_joint_actuator(i).joint().name() for i in plant.GetJointActuatorIndices(instance)]

    def angles(ti: float) -> dict:
        rd = scenario.disturbance_pose(ti, r_c).rotation
        rpy = RollPitchYaw(RotationMatrix(RF.T @ rd @ RF))
        return {"roll": rpy.roll_angle(), "pitch": rpy.pitch_angle(), "yaw": rpy.yaw_angle()}

    load = np.zeros(3) if scenario.tangential_force is None else np.asarray(scenario.tangential_force)

    def set_inputs(ti: float) -> None:
        a = angles(ti)
        desired.FixValue(pc, np.r_[[a[nm] for nm in order], np.zeros(len(order))])
        tgt = float(scenario.force_target(ti)) if ti >= scenario.t_contact else 0.0
        ramp = float(scenario.load_ramp(ti)) if ti >= scenario.t_contact else 0.0
        goal = ramp * load + scenario.disturbance_load(ti)
        gen = np.zeros(nv)
        gen[vidx["slide0"]] = tgt  # pushes the object into the tip: the tip feels +tgt along u
        gen[vidx["slide1"]] = goal @ RF[:, 1]
        gen[vidx["slide2"]] = goal @ RF[:, 2]
        applied.FixValue(pc, gen)

    t = sensor.times(scenario.duration)
    n = len(t)
    t_start = float(scenario.t_contact)
    a0 = angles(t_start)
    for nm, j in joints.items():
        if nm.startswith("slide"):
            j.set_translation(pc, 0.0)
        else:
            j.set_angle(pc, a0[nm])
    sim = Simulator(w.diagram, w.context)
    w.context.SetTime(t_start)
    sim.Initialize()

    wrench = np.zeros((n, 6))
    direction = np.full((n, 3), np.nan)
    centre = np.full((n, 3), np.nan)
    area, depth, push, fdepth = np.zeros(n), np.zeros(n), np.zeros(n), np.full(n, np.nan)
    in_contact = np.zeros(n, dtype=bool)
    turn = np.full((n, 3), np.nan)  # rotation vector from the scenario's orientation to the object's, world
    offset = np.full((n, 3), np.nan)  # the object's origin relative to the nominal contact point, world
    target = np.where(t >= scenario.t_contact, scenario.force_target(t), 0.0)
    has_line = not isinstance(obj, HalfSpace)
    # a friction load (a force target across) must be held; a rocked object may roll and creep further
    slid_limit = _SAP_SLID if scenario.load_start is not None else 4.0 * _SAP_SLID
    bar = _bar(n, f"drake sap {obj.kind}", progress)
    now = t_start
    for i in range(n):
        ti = float(t[i])
        while now < ti - 1e-12:
            set_inputs(now)
            now = min(now + _SAP_INPUT_DT, ti)
            sim.AdvanceTo(now)
        pose_rot = scenario.disturbance_pose(ti, r_c) @ base
        if has_line:
            direction[i] = _line_dir(obj, pose_rot, r_c)
        if ti >= t_start:
            wr, st, fd = _sap_wrench(w, r_c, n_c)
            wrench[i] = wr
            centre[i] = st["centre"]
            area[i] = st["area"]
            depth[i] = st["pmax"] * w.radius / settings["modulus"]
            fdepth[i] = fd
            push[i] = joints["slide0"].get_translation(pc)
            if os.environ.get("SOFTTIP_DRAKE_DEBUG") and i % 8 == 0:
                v = plant.GetVelocities(pc)
                print(f"t {ti:.2f} slides {[round(joints[f'slide{k}'].get_translation(pc) * 1e3, 4) for k in range(3)]} mm "
                      f"v {np.round(v[[vidx['slide0'], vidx['slide1'], vidx['slide2']]] * 1e3, 4)} mm/s f {np.round(wr[:3], 3)}",
                      file=sys.stderr)
            in_contact[i] = st["area"] > 0.0
            X = plant.EvalBodyPoseInWorld(pc, w.body)
            turn[i] = _rotation_vector(X.rotation().matrix() @ pose_rot.rotation.T)
            offset[i] = X.translation() - r_c
            across = np.hypot(joints["slide1"].get_translation(pc), joints["slide2"].get_translation(pc))
            # the scenario holds only while the object keeps its orientation and its contact
            off = float(np.linalg.norm(turn[i]))
            if off > _SAP_TURN_MAX:
                raise RuntimeError(f"the object left the scenario: turned {math.degrees(off):.2f}° from its commanded "
                                   f"orientation at t = {ti:.2f} s (bound {math.degrees(_SAP_TURN_MAX):g}°)")  # fmt: skip
            if ti > scenario.t_stable and not in_contact[i]:
                raise RuntimeError(f"the object left the scenario: contact lost at t = {ti:.2f} s")
            if ti > scenario.t_stable and across > slid_limit:
                raise RuntimeError(f"friction cannot hold the load (μ = {settings['friction']:g}): the object slid "
                                   f"{across * 1e3:.1f} mm across the skin by t = {ti:.2f} s")  # fmt: skip
        if bar is not None:
            bar.update()
    if bar is not None:
        bar.close()
    truth = _truth(direction, r_c, n_c, u, wrench, centre, area, depth, push, target, in_contact, fdepth)
    held = np.isfinite(turn[:, 0])
    info = {"sap_damping": _SAP_DAMPING, "sap_pd": list(_SAP_PD),
            "max_turn_deg": float(np.degrees(np.linalg.norm(turn[held], axis=1).max(initial=0.0))),
            "max_offset_tangential_mm": float(1e3 * np.linalg.norm(offset[held] - np.outer(offset[held] @ u, u),
                                                                   axis=1).max(initial=0.0)),
            "diagnostics": {"object_turn": turn, "object_offset": offset}}  # fmt: skip
    return t, wrench, truth, info


def _rotation_vector(R: NDArray[np.float64]) -> NDArray[np.float64]:
    """Rotation vector (axis × angle, rad) of a rotation matrix (angles below π)."""
    c = float(np.clip(0.5 * (np.trace(R) - 1.0), -1.0, 1.0))
    angle = math.acos(c)
    v = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    s = math.sin(angle)
    return v * (0.5 * angle / s) if s > 1e-12 else 0.5 * v


def _truth(direction, r_c, n_c, u, wrench, centre, area, depth, push, target, in_contact, friction_depth) -> GroundTruth:
    """The per-sample truth of a Drake grasp (``slip_fraction`` is not available: NaN)."""
    n = len(wrench)
    return GroundTruth(
        direction=direction,
        angle=line_angle(direction, np.broadcast_to(n_c, direction.shape)),
        contact_point=np.broadcast_to(r_c, (n, 3)).copy(),
        contact_normal=np.broadcast_to(n_c, (n, 3)).copy(),
        pressure_centre=centre,
        contact_area=area,
        depth=depth,
        push=push,
        normal_force=wrench[:, :3] @ u,
        force_target=target,
        in_contact=in_contact,
        slip_fraction=np.full(n, np.nan),
        friction_depth=friction_depth,
    )


def _sap_wrench(w: _World, r_c, n_c):
    """Contact wrench on the fingertip about the sensor origin from the contact results, the
    surface statistics, and the depth of the contact surface below ``r_c`` along ``n_c`` where
    the tractions act (NaN when the tangential force is below 1 % of the normal force)."""
    res = w.plant.get_contact_results_output_port().Eval(w.plant_context)
    total = np.zeros(6)
    surfaces = []
    for k in range(res.num_hydroelastic_contacts()):
        info = res.hydroelastic_contact_info(k)
        s = info.contact_surface()
        F = info.F_Ac_W()
        sign = 1.0 if s.id_M() == w.tip_id else -1.0  # F_Ac_W acts on the body of M
        f = sign * np.asarray(F.translational())
        c = np.asarray(s.centroid())
        total += np.r_[f, sign * np.asarray(F.rotational()) + np.cross(c, f)]
        surfaces.append(s)
    _, st = _integrate_surfaces(surfaces, w.tip_id)
    fd = math.nan
    f_t = total[:3] - (total[:3] @ n_c) * n_c
    if st["area"] > 0.0 and np.linalg.norm(f_t) >= 0.01 * abs(total[:3] @ n_c):
        # the tractions act on the contact surface: its pressure-weighted depth below r_c
        # (what GroundTruth.friction_depth means on the Winkler skin, with tractions ∝ p)
        fd = float((np.asarray(r_c) - st["centre"]) @ n_c)
    return total, st, fd
