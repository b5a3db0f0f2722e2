"""Skin discretisation and the sensor model of the simulator."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from softtip.core.fingertip import ImplicitSurface, Sphere, murakami2006
from softtip.sim import SensorModel, discretise_skin


@pytest.mark.parametrize("n", [1_000, 12_000])
def test_capsule_mesh_covers_the_touchable_skin(n):
    tip = murakami2006()
    skin = discretise_skin(tip, n)
    area = 2 * math.pi * tip.radius**2 + 2 * math.pi * tip.radius * tip.length
    assert skin.total_area == pytest.approx(area, rel=1e-12)
    assert abs(len(skin) - n) <= 0.01 * n + 30
    assert np.abs(tip.surface(skin.centres)).max() < 1e-12
    assert_allclose(skin.normals, tip.normal(skin.centres), atol=1e-12)
    assert skin.centres[:, 2].min() >= 0.0
    # quasi-uniform: element sizes within 5 % of each other
    assert skin.spacing.max() / skin.spacing.min() < 1.05


def test_sphere_mesh():
    tip = Sphere(0.015, center=(0.0, 0.0, 0.01))
    skin = discretise_skin(tip, 5_000)
    assert len(skin) == 5_000
    assert skin.total_area == pytest.approx(2 * math.pi * 0.015**2 * 1.5, rel=1e-12)  # down to 120° from the top
    assert np.abs(tip.surface(skin.centres)).max() < 1e-12
    # a surface given as code has no simulator skin (the ellipsoid has one: tests/test_shapes.py)
    ball = ImplicitSurface(lambda p: np.linalg.norm(p, axis=-1) - 0.01, lambda p: p / np.linalg.norm(p, axis=-1, keepdims=True), (0, 0, 0), 0.01)
    with pytest.raises(TypeError, match="no skin"):
        discretise_skin(ball)


def test_sensor_noise_bias_and_quantisation():
    sensor = SensorModel(bias=(0.1, 0, 0, 0, 0, 1e-4))
    w = np.zeros((20_000, 6))
    a = sensor.measure(w, np.random.default_rng(3))
    b = sensor.measure(w, np.random.default_rng(3))
    assert np.array_equal(a, b)  # seeded
    res = np.array(sensor.resolution)
    assert_allclose(a / res, np.round(a / res), atol=1e-9)  # on the quantisation grid
    tol = 2e-4 * np.array([1, 1, 1, 1e-3, 1e-3, 1e-3]) + res / 4
    assert np.all(np.abs(a.mean(axis=0) - np.array(sensor.bias)) <= tol)
    # quantisation adds res²/12 to the variance
    expected = np.sqrt(np.array(sensor.noise_std) ** 2 + res**2 / 12)
    assert_allclose(a.std(axis=0), expected, rtol=0.05)
    told = sensor.noise_model()  # what the estimator is told of this sensor
    assert_allclose(told.force_std + told.moment_std, expected, rtol=1e-12)
    ideal = SensorModel.ideal().measure(w + 0.123, np.random.default_rng(0))
    assert np.all(ideal == 0.123)
    assert len(SensorModel(rate=50.0).times(10.0)) == 500
    with pytest.raises(ValueError):
        SensorModel(noise_std=(-1.0,) * 6)
