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


@pytest.mark.parametrize(("table", "said"), [
    ({"shape": "capsule", "radius": 16, "length": 20}, "mm across (1.61e+03× a fingertip's size); expected 2 to 200 mm"),
    ({"shape": "sphere", "radius": 0.0005}, "the fingertip is 1 mm across (30× smaller than a fingertip)"),
    ({"shape": "sphere", "radius": 0.016, "skin_thickness": 5e-6}, "skin_thickness = 5e-06 m (0.005 mm) on a fingertip 32"),
    ({"shape": "sphere", "radius": 0.016, "skin_thickness": 0.1}, "expected 0.1 mm to less than its radius (16 mm)"),
])  # fmt: skip
def test_a_fingertip_file_of_no_fingertips_size_is_refused(table: dict, said: str) -> None:
    # a file in mm (16 for 0.016) gave a 48 m fingertip and confident estimates, exit 0
    with pytest.raises(InputError, match=r"^tip\.toml: .*" + said.replace("(", r"\(").replace(")", r"\)").replace("+", r"\+")):
        fingertip_from_mapping({"fingertip": table}, "tip.toml")
    fingertip_from_mapping({"fingertip": {"shape": "sphere", "radius": 0.016, "skin_thickness": 0.005}}, "tip.toml")


@pytest.mark.parametrize("extra", [{"mount": {"translation": [0.0, 0.0, 0.01]}}, {"tip": {"radius": 0.01}}, {"radius": 0.01}])
def test_a_table_outside_fingertip_is_refused(extra):
    # [mount] for [fingertip.mount] used to leave the tip unmounted without a word
    table = {"fingertip": {"shape": "sphere", "radius": 0.016}, **extra}
    with pytest.raises(InputError, match=f"tip.toml: unknown .*'{next(iter(extra))}' outside"):
        fingertip_from_mapping(table, "tip.toml")


def test_a_mesh_file_given_as_the_fingertip_file_names_the_toml_it_needs(tmp_path):
    # read as TOML it was "malformed TOML"; a missing shape read "shape = None"
    mesh = tmp_path / "tip.stl"
    mesh.write_text("solid x\nendsolid x\n")
    with pytest.raises(InputError, match=r'tip\.stl: a mesh file, not a fingertip file; .*\[fingertip\] mesh = "tip\.stl"'):
        load_fingertip(mesh)
    with pytest.raises(InputError, match=r"x\.toml: \[fingertip\] has no shape key; expected shape = one of sphere"):
        fingertip_from_mapping({"fingertip": {"radius": 0.01}}, "x.toml")
