import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from softtip import (
    axial_difference,
    axial_median,
    direction_angle,
    edge_direction,
    spin_torque,
    tangent_frame,
    tangential_spin_torque,
)
from strategies import unit_vectors


def test_angle_at_the_tip_is_from_the_sensor_x_axis():
    n = np.array([0.0, 0.0, 1.0])
    for deg in (-45.0, 0.0, 30.0, 45.0, 89.0):
        a = np.radians(deg)
        d = np.array([np.cos(a), np.sin(a), 0.0])
        assert_allclose(direction_angle(d, n, unit="deg"), deg, atol=1e-12)
        # an axis: -d is the same direction
        assert_allclose(direction_angle(-d, n, unit="deg"), deg, atol=1e-12)


def test_angle_wraps_into_half_open_interval():
    n = np.array([0.0, 0.0, 1.0])
    assert direction_angle([0.0, 1.0, 0.0], n, unit="deg") == pytest.approx(90.0)
    assert direction_angle([0.0, -1.0, 0.0], n, unit="deg") == pytest.approx(90.0)


def test_tangent_frame_switches_to_y_near_the_x_axis():
    e1, e2 = tangent_frame(np.array([1.0, 0.0, 0.0]))
    assert_allclose(e1, [0.0, 1.0, 0.0])
    assert_allclose(e2, [0.0, 0.0, 1.0])


@given(n=unit_vectors(), v=unit_vectors())
def test_tangent_frame_is_orthonormal_and_right_handed(n, v):
    e1, e2 = tangent_frame(n)
    assert_allclose(np.linalg.norm(e1), 1.0, atol=1e-12)
    assert_allclose([e1 @ n, e2 @ n, e1 @ e2], 0.0, atol=1e-12)
    assert_allclose(np.cross(e1, e2), n, atol=1e-12)


@given(n=unit_vectors(), v=unit_vectors(), q_n=st.floats(-1e-2, 1e-2), scale=st.floats(1e-4, 1e-1))
def test_h_and_d_from_a_line_contact(n, v, q_n, scale):
    # a moment about an axis perpendicular to n and to the line d gives d back
    d = np.cross(n, v)
    if np.linalg.norm(d) < 1e-3:
        return
    d /= np.linalg.norm(d)
    h_true = scale * np.cross(d, n)
    q = q_n * n + h_true
    h = tangential_spin_torque(q, n)
    assert_allclose(h, h_true, atol=1e-12 * max(1, abs(q_n)) + 1e-15)
    got = edge_direction(h, n)
    assert abs(abs(got @ d) - 1.0) < 1e-9


def test_spin_torque_removes_the_moment_of_the_force(rng):
    r = rng.normal(size=(5, 4, 3))
    f = rng.normal(size=(5, 4, 3))
    q = rng.normal(size=(5, 4, 3))
    w = np.concatenate((f, q + np.cross(r, f)), axis=-1)
    assert_allclose(spin_torque(w, r), q, atol=1e-12)


def test_direction_is_nan_without_h():
    assert np.isnan(edge_direction([0.0, 0.0, 0.0], [0.0, 0.0, 1.0])).all()


def test_axial_statistics():
    a = np.radians([89.0, -89.0, 88.0, -87.0, 90.0])
    assert np.degrees(axial_median(a)) == pytest.approx(90.0, abs=1.01) or np.degrees(axial_median(a)) == pytest.approx(-90, abs=1.01)
    assert_allclose(np.degrees(axial_difference(np.radians(89.0), np.radians(-89.0))), -2.0, atol=1e-9)
    assert np.isnan(axial_median([np.nan]))
