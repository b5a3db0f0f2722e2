"""Soft-fingertip contact simulator: synthetic F/T logs with ground truth.

A quasi-static elastic-foundation (Winkler) model of the 5 mm silicone skin over the rigid
shell, with a Coulomb-limited elastic tangential layer, touched by rigid objects given as
signed distance functions (plane, thin plate, wedge, cylinder/stick, cylinder-bottom
fringe). Scenarios reproduce the papers' grasps (manual §5); the sensor model adds bias,
noise and quantisation.

Modules: :mod:`~softtip.sim.skin` (surface elements), :mod:`~softtip.sim.objects` (SDF
objects), :mod:`~softtip.sim.foundation` (Winkler + friction), :mod:`~softtip.sim.scenario`
(grasp time series, the papers' hand), :mod:`~softtip.sim.sensor` (noise),
:mod:`~softtip.sim.truth` (ground truth), :mod:`~softtip.sim.simulate` (the loop and the
writers), :mod:`~softtip.sim.probing` (probing logs for calibration), :mod:`~softtip.sim.digest` (a key for
caches of simulated logs); the ``simulate`` command is :mod:`softtip.cli.simulate`.

Example
-------
>>> from softtip import murakami2006
>>> from softtip.sim import Plate, paper_scenario, simulate_grasp
>>> import math
>>> log = simulate_grasp(murakami2006(), Plate(0.001), paper_scenario(math.radians(45)), rng=1)
>>> log.wrench.shape
(500, 6)
"""

from softtip.sim.digest import simulator_digest
from softtip.sim.foundation import ContactModel, ContactParams, ContactResult, FrictionState
from softtip.sim.objects import (
    OBJECT_KINDS,
    Cylinder,
    CylinderRim,
    HalfSpace,
    Plate,
    RigidObject,
    Wedge,
    make_object,
    stick,
)
from softtip.sim.pose import Pose, rotation_matrix
from softtip.sim.probing import mesh_probing_log, probing_presses, simulate_probing
from softtip.sim.scenario import (
    DISTURBANCE_RAMP,
    DISTURBANCE_TIMINGS,
    FRICTION_PROFILES,
    JOINT_ROTATION_DEG,
    OBJECT_MASS,
    Disturbance,
    GraspScenario,
    HandFrame,
    friction_scenario,
    paper_scenario,
    push_scenario,
    rock_scenario,
    smoothstep,
)
from softtip.sim.sensor import NANO17_SENSOR, SensorModel
from softtip.sim.simulate import SimLog, run_simulation, simulate_grasp, truth_dict, write_log_csv, write_truth_json
from softtip.sim.skin import DEFAULT_ELEMENTS, SkinMesh, discretise_skin
from softtip.sim.truth import GroundTruth, line_angle, tangent_frame

__all__ = [
    "simulator_digest",
    "ContactModel",
    "simulate_probing",
    "probing_presses",
    "mesh_probing_log",
    "ContactParams",
    "ContactResult",
    "FrictionState",
    "OBJECT_KINDS",
    "Cylinder",
    "CylinderRim",
    "HalfSpace",
    "Plate",
    "RigidObject",
    "Wedge",
    "make_object",
    "stick",
    "Pose",
    "rotation_matrix",
    "DISTURBANCE_RAMP",
    "DISTURBANCE_TIMINGS",
    "JOINT_ROTATION_DEG",
    "OBJECT_MASS",
    "FRICTION_PROFILES",
    "Disturbance",
    "GraspScenario",
    "friction_scenario",
    "HandFrame",
    "paper_scenario",
    "push_scenario",
    "rock_scenario",
    "smoothstep",
    "NANO17_SENSOR",
    "SensorModel",
    "SimLog",
    "run_simulation",
    "simulate_grasp",
    "truth_dict",
    "write_log_csv",
    "write_truth_json",
    "DEFAULT_ELEMENTS",
    "SkinMesh",
    "discretise_skin",
    "GroundTruth",
    "line_angle",
    "tangent_frame",
]
