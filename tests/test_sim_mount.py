"""The simulator with a mounted fingertip: the same physics as the bare shape moved and rotated."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.spatial.transform import Rotation

from softtip import Capsule, contact_from_wrench
from softtip.core.mounting import Mounted
from softtip.core.spin import tangent_frame
from softtip.sim import ContactModel, Plate, SensorModel, discretise_skin, push_scenario, simulate_grasp

SHAPE = Capsule(0.016, 0.020)


@pytest.mark.parametrize(
    ("rpy_deg", "shift"),
    [((0.0, 25.0, 0.0), (0.0, 0.0, 0.004)), ((10.0, -15.0, 40.0), (0.003, -0.002, 0.001))],
)
def test_mounted_tip_simulates_the_bare_tip_moved_and_rotated(rpy_deg, shift):
    rot = Rotation.from_euler("xyz", rpy_deg, degrees=True).as_matrix()
    t = np.array(shift)
    mounted = Mounted(SHAPE, rot, t)
    # the skin: the bare tip's elements, placed by the mount
    bare_skin, skin = discretise_skin(SHAPE, 3000), discretise_skin(mounted, 3000)
    assert_allclose(skin.centres, bare_skin.centres @ rot.T + t, atol=1e-15)
    assert_allclose(skin.normals, bare_skin.normals @ rot.T, atol=1e-15)
    assert_allclose(mounted.surface(skin.centres), 0.0, atol=1e-12)
    # the same push, off the apex with a tangential load, described in each frame
    r0 = SHAPE.project(np.array([0.006, -0.004, 0.040]))
    n0 = SHAPE.normal(r0)
    angle0 = math.radians(30.0)
    e1, e2 = tangent_frame(n0)
    d = rot @ (math.cos(angle0) * e1 + math.sin(angle0) * e2)
    r1, n1 = rot @ r0 + t, rot @ n0
    f1, f2 = tangent_frame(n1)
    angle1 = math.atan2(d @ f2, d @ f1)
    load0 = np.array([0.3, -0.2, 0.0])
    common = dict(duration=2.0, t_contact=0.4, t_stable=1.2, force=3.0)
    scn0 = push_scenario(angle0, contact_point=tuple(r0), tangential_force=tuple(load0), **common)
    scn1 = push_scenario(angle1, contact_point=tuple(r1), tangential_force=tuple(rot @ load0), **common)
    log0 = simulate_grasp(SHAPE, Plate(0.002), scn0, SensorModel.ideal(), model=ContactModel(bare_skin, quadrature=1))
    log1 = simulate_grasp(mounted, Plate(0.002), scn1, SensorModel.ideal(), model=ContactModel(skin, quadrature=1))
    f_a, m_a = log0.wrench_true[:, :3], log0.wrench_true[:, 3:]
    expect = np.concatenate((f_a @ rot.T, m_a @ rot.T + np.cross(t, f_a @ rot.T)), axis=1)
    held = np.linalg.norm(f_a, axis=1) > 1.0
    assert held.sum() > 20
    scale = np.linalg.norm(f_a[held], axis=1)[:, None]
    # equal to the force solve's tolerance (a wrong mount is off by the whole wrench)
    assert np.max(np.abs(log1.wrench_true[held, :3] - expect[held, :3]) / scale) < 1e-4
    assert np.max(np.abs(log1.wrench_true[held, 3:] - expect[held, 3:]) / scale) < 1e-4 * 0.04
    # and the estimator reads the contact where the mount puts it
    a = contact_from_wrench(log0.wrench_true[held], SHAPE)
    b = contact_from_wrench(log1.wrench_true[held], mounted)
    assert a.valid.all() and b.valid.all()
    assert_allclose(b.point, a.point @ rot.T + t, atol=1e-6)


def test_default_contact_of_a_mounted_tip_is_its_own_apex():
    rot = Rotation.from_euler("y", 90, degrees=True).as_matrix()
    mounted = Mounted(SHAPE, rot, (0.0, 0.0, 0.01))
    r_c, n_c, _ = push_scenario().nominal_contact(mounted)
    assert_allclose(r_c, rot @ np.array([0.0, 0.0, 0.036]) + [0.0, 0.0, 0.01], atol=1e-12)
    assert_allclose(n_c, rot @ np.array([0.0, 0.0, 1.0]), atol=1e-12)
