"""The simulator's skin from a triangle-mesh fingertip."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from softtip import Capsule, contact_from_wrench
from softtip.core.mesh import MeshFingertip, capsule_mesh
from softtip.sim import ContactModel, Plate, SensorModel, discretise_skin, push_scenario, simulate_grasp

TIP = Capsule(0.016, 0.020)


@pytest.fixture(scope="module")
def mesh_tip():
    return MeshFingertip(*capsule_mesh(0.016, 0.020, segments=64))


def test_skin_elements_cover_the_mesh_above_the_base(mesh_tip):
    skin = discretise_skin(mesh_tip, 8000)
    assert len(skin) >= 8000
    tri = mesh_tip.vertices[mesh_tip.faces]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    side_and_cap = area[tri[:, :, 2].mean(axis=1) > 1e-9].sum()
    assert_allclose(skin.total_area, side_and_cap, rtol=1e-12)
    # the tessellated capsule's touchable skin is the capsule's within the chords' deficit
    assert_allclose(skin.total_area, 2 * math.pi * 0.016 * 0.020 + 2 * math.pi * 0.016**2, rtol=5e-3)
    assert_allclose(mesh_tip.surface(skin.centres), 0.0, atol=1e-15)
    assert_allclose(skin.normals, mesh_tip.normal(skin.centres), atol=1e-12)
    assert np.all(skin.centres[:, 2] > 0.0)
    # elements of about equal size: the target area, split from larger triangles
    assert skin.areas.max() <= 1.01 * skin.total_area / 8000
    with pytest.raises(ValueError, match="no skin"):
        discretise_skin(mesh_tip, 100, z_min=0.05)


def test_simulated_push_on_a_mesh_matches_the_capsule(mesh_tip):
    # the same push on the analytic capsule and on its tessellation: the same wrench, and the
    # estimator finds the same contact on both
    scn = push_scenario(math.radians(30.0), duration=3.0, t_contact=0.5, t_stable=1.5)
    logs = []
    for tip in (TIP, mesh_tip):
        model = ContactModel(discretise_skin(tip, 4000), quadrature=1)
        logs.append(simulate_grasp(tip, Plate(0.002), scn, SensorModel.ideal(), model=model))
    w_cap, w_mesh = logs[0].wrench_true, logs[1].wrench_true
    held = np.linalg.norm(w_cap[:, :3], axis=1) > 1.0
    assert held.sum() > 20
    scale = np.linalg.norm(w_cap[held, :3], axis=1)
    assert np.max(np.linalg.norm(w_mesh[held, :3] - w_cap[held, :3], axis=1) / scale) < 0.05
    a = contact_from_wrench(w_cap[held], TIP)
    b = contact_from_wrench(w_mesh[held], mesh_tip)
    assert a.valid.all() and b.valid.all()
    assert np.max(np.linalg.norm(a.point - b.point, axis=1)) < 0.2e-3
