import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from softtip import Capsule, Ellipsoid, InputError, Sphere, load_fingertip, murakami2006
from softtip.core.fingertip import fingertip_from_mapping

from strategies import TIPS, surface_points


@pytest.mark.parametrize("tip", TIPS, ids=lambda t: t.kind)
@given(data=st.data())
def test_surface_points_are_on_the_skin_and_normals_are_gradients(tip, data):
    r, n = data.draw(surface_points(tip))
    assert abs(tip.surface(r)) < 1e-12
    assert_allclose(np.linalg.norm(n), 1.0, atol=1e-12)
    # outward: a step along n goes outside, against it inside
    assert tip.surface(r + 1e-5 * n) > 0 > tip.surface(r - 1e-5 * n)
    # n is the normalised gradient (central differences of S)
    h = 1e-7
    grad = np.array([(tip.surface(r + h * e) - tip.surface(r - h * e)) / (2 * h) for e in np.eye(3)])
    assert_allclose(grad / np.linalg.norm(grad), n, atol=1e-5)


@pytest.mark.parametrize("tip", TIPS, ids=lambda t: t.kind)
@given(data=st.data(), offset=st.floats(-1e-3, 1e-3))
def test_projection_lands_on_the_skin(tip, data, offset):
    r, n = data.draw(surface_points(tip))
    p = tip.project(r + offset * n)
    assert abs(tip.surface(p)) < 1e-12
    if not isinstance(tip, Ellipsoid):  # exact closest point for sphere and capsule
        assert_allclose(p, r, atol=1e-12)


def test_capsule_geometry():
    tip = murakami2006()
    assert tip == Capsule(0.016, 0.020)
    assert_allclose(tip.normal([0.0, 0.016, 0.01]), [0, 1, 0])
    assert_allclose(tip.normal([0.0, 0.0, 0.036]), [0, 0, 1])
    assert tip.surface([0.0, 0.0, 0.0]) == pytest.approx(-0.016)


@pytest.mark.parametrize(
    "tip",
    [Sphere(0.01, center=(0.0, 0.0, 0.02)), Capsule(0.016, 0.02), Ellipsoid((0.01, 0.012, 0.02), (0.0, 0.0, 0.01))],
)
def test_toml_round_trip(tmp_path, tip):
    path = tmp_path / "tip.toml"
    path.write_text(tip.to_toml())
    assert load_fingertip(path) == tip


def test_presets_and_errors(tmp_path):
    assert load_fingertip("murakami2006") == murakami2006()
    with pytest.raises(InputError, match="unknown fingertip preset 'nano'"):
        load_fingertip("nano")
    with pytest.raises(InputError, match="semi_axes"):
        fingertip_from_mapping({"fingertip": {"shape": "ellipsoid", "semi_axes": [1, 2]}}, "x.toml")
    with pytest.raises(InputError, match=r"x.toml: expected a \[fingertip\] table"):
        fingertip_from_mapping({}, "x.toml")


def test_invalid_dimensions():
    with pytest.raises(ValueError, match="radius"):
        Sphere(0.0)
    with pytest.raises(ValueError, match="length"):
        Capsule(0.01, -1.0)
    with pytest.raises(ValueError, match="center"):
        Sphere(0.01, center=(0, 0))
