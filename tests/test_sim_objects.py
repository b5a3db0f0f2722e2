"""Signed-distance objects and poses of the simulator."""

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from softtip.sim import Cylinder, CylinderRim, HalfSpace, Plate, Pose, Wedge, make_object, rotation_matrix
from softtip.sim.objects import RigidObject

OBJECTS = [
    HalfSpace(),
    Plate(0.001),
    Plate(0.003, edge_radius=0.001),
    Plate(0.002, edge_radius=0.001),
    Wedge(),
    Wedge(math.radians(60.0), tip_radius=0.0005),
    Cylinder(0.006),
    CylinderRim(0.040),
]
IDS = ["plane", "plate1", "plate3r", "plate2round", "wedge90", "wedge60r", "cyl6", "fringe"]

coord = st.floats(-0.006, 0.006, allow_nan=False)
unit = st.floats(-1.0, 1.0, allow_nan=False)


def _vec(data, elements):
    return np.array([data.draw(elements) for _ in range(3)])


@st.composite
def poses(draw):
    axis = np.array([draw(unit), draw(unit), draw(unit)])
    assume(np.linalg.norm(axis) > 1e-3)
    return Pose(rotation_matrix(axis, draw(st.floats(-math.pi, math.pi))), np.array([draw(coord) for _ in range(3)]))


@pytest.mark.parametrize("obj", OBJECTS, ids=IDS)
@settings(max_examples=60)
@given(data=st.data())
def test_ray_exit_lands_on_the_surface(obj, data):
    obj = obj.with_pose(data.draw(poses()))
    p = _vec(data, coord)
    sd = obj.sdf(p)
    if sd > -1e-5:  # pull the point inside, past the nearest surface
        p = p - (sd + data.draw(st.floats(1e-5, 3e-4))) * obj.normal(p)
    assume(obj.sdf(p) < -1e-6)
    u = _vec(data, unit)
    assume(np.linalg.norm(u) > 1e-2)
    u = u / np.linalg.norm(u)
    s, n = obj.ray_exit(p, u)
    if not np.isfinite(s):
        # only unbounded directions never leave: the sdf stays negative far along the ray
        assert obj.sdf(p + 1.0 * u) < 0.0
        return
    assert abs(obj.sdf(p + s * u)) < 1e-9
    along = p + np.linspace(0.0, 0.999, 25)[:, None] * s * u
    assert np.all(obj.sdf(along) <= 1e-12)
    assert abs(np.linalg.norm(n) - 1.0) < 1e-9
    assert n @ u >= -1e-9  # leaving: the outward normal faces along the ray


@pytest.mark.parametrize("obj", OBJECTS, ids=IDS)
@settings(max_examples=60)
@given(data=st.data())
def test_normal_is_the_sdf_gradient(obj, data):
    obj = obj.with_pose(data.draw(poses()))
    p = _vec(data, coord)
    h = 1e-7
    grad = np.array([(obj.sdf(p + h * e) - obj.sdf(p - h * e)) / (2 * h) for e in np.eye(3)])
    fwd = np.array([(obj.sdf(p + h * e) - obj.sdf(p)) / h for e in np.eye(3)])
    assume(np.allclose(grad, fwd, atol=1e-4))  # not on a ridge of the distance field
    assert_allclose(obj.normal(p), grad, atol=1e-4)


def test_line_directions():
    rot = rotation_matrix([1.0, 2.0, 3.0], 0.7)
    pose = Pose(rot, [0.01, 0.0, 0.02])
    for obj in (Plate(0.001), Wedge(), Cylinder(0.004)):
        assert_allclose(obj.with_pose(pose).line_direction(np.zeros((4, 3))), np.tile(rot[:, 2], (4, 1)), atol=1e-12)
    assert np.all(np.isnan(HalfSpace().line_direction(np.zeros(3))))
    rim = CylinderRim(0.040)
    d = rim.line_direction(np.zeros(3))
    assert abs(abs(d[2]) - 1.0) < 1e-12  # the rim tangent at the touched point is z'


def test_shapes_match_their_definitions():
    plate = Plate(0.002)
    assert_allclose(plate.sdf([[-0.001, 0.0, 0.0], [-0.001, 0.0015, 0.0], [0.001, 0.0, 0.5]]), [-0.001, 0.0005, 0.001])
    wedge = Wedge()  # 90°: the solid is x' <= -|y'|
    assert_allclose(wedge.sdf([[0.0, 0.0, 0.0], [-0.001, 0.0, 0.0], [0.001, 0.0, 0.0]]), [0.0, -0.001 / math.sqrt(2), 0.001])
    assert_allclose(Cylinder(0.004).sdf([[0.0, 0.0, 0.0], [-0.002, 0.0, 0.0], [0.001, 0.0, 0.0]]), [0.0, -0.002, 0.001])
    rounded = Plate(0.002, edge_radius=0.001)
    assert_allclose(rounded.sdf([[0.0, 0.0, 0.0], [0.0, 0.001, 0.0]]), [0.0, math.sqrt(2) * 0.001 - 0.001], atol=1e-15)
    rim = CylinderRim(0.040)
    assert abs(rim.sdf(np.zeros(3))) < 1e-15
    assert rim.sdf([-0.001, 0.0, 0.0]) < 0.0 < rim.sdf([0.001, 0.0, 0.0])
    with pytest.raises(ValueError):
        Plate(0.001, edge_radius=0.001)
    with pytest.raises(ValueError):
        make_object("sphere")


@settings(max_examples=50)
@given(a=poses(), b=poses(), data=st.data())
def test_pose_algebra(a, b, data):
    p = _vec(data, coord)
    assert_allclose((a @ b).apply(p), a.apply(b.apply(p)), atol=1e-15)
    assert_allclose(a.inverse_apply(a.apply(p)), p, atol=1e-15)
    assert_allclose(a.inverse().apply(p), a.inverse_apply(p), atol=1e-15)
    piv = _vec(data, coord)
    rot = Pose.from_axis_angle([0.0, 0.0, 1.0], 0.3, piv)
    assert_allclose(rot.apply(piv), piv, atol=1e-15)


@pytest.mark.parametrize("obj", OBJECTS, ids=IDS)
@settings(max_examples=40)
@given(data=st.data())
def test_segment_min_is_the_deepest_point_of_the_segment(obj, data):
    # closed forms (extruded objects) and the numerical search (fringe) against sampling
    rng = np.random.default_rng(data.draw(st.integers(0, 2**32 - 1)))
    q = rng.normal(scale=2e-3, size=(64, 3))
    u = rng.normal(size=(64, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    length = 5e-3
    s, f = obj.segment_min_local(q, u, length)
    assert np.all((s >= 0.0) & (s <= length))
    assert_allclose(obj.sdf_local(q + s[:, None] * u), f, atol=1e-12)
    along = np.min([obj.sdf_local(q + t * u) for t in np.linspace(0.0, length, 801)], axis=0)
    assert np.all(f <= along + 2e-9)  # (the fringe: a search to 1e-9 m)
    assert np.all(f >= along - 0.5 * length / 800)  # 1-Lipschitz: within half a sampling step
    _, f2 = RigidObject.segment_min_local(obj, q, u, length, obj.sdf_local(q))  # the generic search
    assert_allclose(f, f2, atol=2e-9)
