"""The fingertip shape protocol (softtip.core.shape) and its registry; the ellipsoid simulated and calibrated."""

import math
import sys

import numpy as np
import pytest
from click.testing import CliRunner
from numpy.testing import assert_allclose
from scipy.spatial.transform import Rotation

from simcache import simulate_grasp, simulate_probing
from softtip import Capsule, Ellipsoid, ImplicitSurface, MeshFingertip, Mounted, Sphere, contact_from_wrench, estimate
from softtip.calibration.probing import SHAPES as CALIBRATION_SHAPES
from softtip.calibration.probing import calibrate_fingertip
from softtip.cli.calibrate import CALIBRATED_SHAPES, calibrate
from softtip.cli.simulate import simulate
from softtip.core._xp import PY
from softtip.core.fingertip import SHAPES, fingertip_from_mapping, load_fingertip
from softtip.core.location import contact_kernel
from softtip.core.mesh import capsule_mesh
from softtip.core.shape import Fingertip
from softtip.io.tables import read_log, write_table
from softtip.sim import ContactModel, HalfSpace, SensorModel, discretise_skin, push_scenario

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

MM = 1e-3
# an ellipsoidal fingertip: its axes along the sensor's, its centre a little off the z axis
ELLIPSOID = Ellipsoid((0.014, 0.016, 0.020), (0.0003, -0.0002, 0.012))


def _ball(radius, centre):
    c = np.asarray(centre, dtype=float)
    return ImplicitSurface(
        lambda p: np.linalg.norm(p - c, axis=-1) - radius,
        lambda p: (p - c) / np.linalg.norm(p - c, axis=-1, keepdims=True),
        c,
        radius,
    )


TIPS = {
    "sphere": Sphere(0.012, (0.001, 0.0, 0.02)),
    "capsule": Capsule(0.016, 0.02, axis_offset=(0.001, -0.0005)),
    "ellipsoid": ELLIPSOID,
    "implicit": _ball(0.014, (0.0, 0.0, 0.02)),
    "mesh": MeshFingertip(*capsule_mesh(0.016, 0.02, segments=48)),
    "mounted": Mounted(Ellipsoid((0.012, 0.015, 0.02), (0.0, 0.0, 0.01)), Rotation.from_euler("y", 20, degrees=True), (0.0, 0.002, 0.001)),
}


def test_the_registry_names_each_file_shape_by_its_kind():
    assert list(SHAPES) == ["sphere", "capsule", "ellipsoid", "mesh"]
    for name, cls in SHAPES.items():
        assert issubclass(cls, Fingertip) and cls.kind == name
    # calibrate --shape offers the shapes that calibrate, from the registry
    assert CALIBRATION_SHAPES == ("sphere", "capsule", "ellipsoid")
    assert CALIBRATED_SHAPES == ["sphere", "capsule", "ellipsoid", "mesh"]


@pytest.mark.parametrize("name", ["sphere", "capsule", "ellipsoid"])
def test_a_shape_reads_back_its_own_file(name):
    tip = TIPS[name]
    assert fingertip_from_mapping(tomllib.loads(tip.to_toml())) == tip
    mounted = Mounted(tip, Rotation.from_euler("x", 15, degrees=True), (0.0, 0.001, 0.0))
    again = fingertip_from_mapping(tomllib.loads(mounted.to_toml()))
    assert again.tip == tip
    assert_allclose(again.rotation, mounted.rotation, atol=1e-15)


@pytest.mark.parametrize("name", sorted(TIPS))
def test_every_shape_solves_a_press_at_its_apex(name):
    tip = TIPS[name]
    apex = tip.project(tip.apex_hint())
    n = tip.normal(apex)
    f = -2.0 * n
    w = np.concatenate((f, np.cross(apex, f) + 1e-4 * n))
    c = contact_from_wrench(w, tip)
    assert c.valid
    assert_allclose(c.point, apex, atol=1e-6)
    assert_allclose(c.normal, n, atol=1e-6)
    assert c.sigma == pytest.approx(1e-4, abs=1e-8)
    # one sample through the float kernel: the same solution
    s = contact_kernel(tip, *map(float, w), xp=PY)
    assert_allclose(s[:3], c.point, atol=1e-9)


@pytest.mark.parametrize("name", sorted(TIPS))
def test_every_shape_gives_a_view_on_its_skin(name):
    tip = TIPS[name]
    v, tri, n = tip.surface_mesh(24, 16)
    assert v.shape[1] == 3 and tri.dtype == np.int32 and tri.max() < len(v)
    assert np.abs(tip.surface(v)).max() < 1e-9
    assert_allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-9)


@pytest.mark.parametrize("name", ["sphere", "capsule", "ellipsoid", "mesh", "mounted"])
def test_every_file_shape_has_a_simulator_skin(name):
    tip = TIPS[name]
    skin = discretise_skin(tip, 2000)
    assert len(skin) >= 1900
    scale = 1e-9 if name in ("ellipsoid", "mounted") else 1e-12  # the ellipsoid's S is in units of its size
    assert np.abs(tip.surface(skin.centres)).max() < scale
    if name != "mesh":  # the mesh's elements carry its interpolated normals (test_mesh_sim)
        assert_allclose(skin.normals, tip.normal(skin.centres), atol=1e-12)


def test_an_implicit_surface_has_no_simulator_skin():
    with pytest.raises(TypeError, match="no skin"):
        discretise_skin(TIPS["implicit"], 2000)


def test_the_ellipsoid_skin_areas_sum_to_its_area():
    # a prolate spheroid, whole (z_min at its bottom): S = 2πa² (1 + c/(a e) asin e), e² = 1 − a²/c²
    a, c = 0.012, 0.02
    tip = Ellipsoid((a, a, c), (0.0, 0.0, 0.01))
    skin = discretise_skin(tip, 20_000, z_min=0.01 - c)
    e = math.sqrt(1.0 - a * a / (c * c))
    area = 2.0 * math.pi * a * a * (1.0 + c / (a * e) * math.asin(e))
    assert skin.total_area == pytest.approx(area, rel=2e-4)
    # the default covers down to 120° from the top, as the sphere's
    top = discretise_skin(tip, 2000)
    assert top.centres[:, 2].min() >= 0.01 - 0.5 * c - 1e-12


@pytest.mark.parametrize("name", ["sphere", "capsule", "ellipsoid", "mounted"])
def test_the_support_point_has_the_normal_asked_for(name):
    tip = TIPS[name]
    rng = np.random.default_rng(8380)
    n = rng.normal(size=(50, 3))
    n[:, 2] = np.abs(n[:, 2])  # the capsule's cap
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    if name == "mounted":
        n = n @ np.array(tip.rotation).T
    p = tip.support_point(n)
    assert np.abs(tip.surface(p)).max() < 1e-12
    assert_allclose(tip.normal(p), n, atol=1e-12)


@pytest.fixture(scope="module")
def ellipsoid_model():
    return ContactModel(discretise_skin(ELLIPSOID, 6000))


@pytest.mark.parametrize("where", ["apex", "side"])
def test_a_simulated_ellipsoid_grasp_is_located_within_half_a_millimetre(ellipsoid_model, where):
    point = None
    if where == "side":
        n = np.array([0.5, 0.3, 0.81])
        point = tuple(ELLIPSOID.support_point(n / np.linalg.norm(n)))
    scn = push_scenario(0.0, contact_point=point, force=3.0, duration=2.0, t_contact=0.3, t_stable=1.0)
    log = simulate_grasp(ELLIPSOID, HalfSpace(), scn, SensorModel(), model=ellipsoid_model, rng=1)
    est = estimate(log.t, log.wrench, ELLIPSOID)
    held = (est.state >= 1) & (log.t > 1.2)
    assert held.sum() > 30
    assert np.all(np.isfinite(est.point[held]))
    # the undeformed skin's contact point, and the pressure centre (moved in by the indentation)
    assert np.max(np.linalg.norm(est.point[held] - log.truth.contact_point[held], axis=1)) < 0.5 * MM
    assert np.max(np.linalg.norm(est.point[held] - log.truth.pressure_centre[held], axis=1)) < 0.5 * MM


def test_softtip_simulate_takes_an_ellipsoid_file(tmp_path):
    path = tmp_path / "ellipsoid.toml"
    path.write_text(ELLIPSOID.to_toml())
    out = tmp_path / "log.csv"
    res = CliRunner().invoke(simulate, ["--tip", str(path), "--object", "plate", "--size", "2mm", "--duration", "4",
                                        "--elements", "3000", "-o", str(out)])  # fmt: skip
    assert res.exit_code == 0, res.output
    log = read_log(str(out))
    est = estimate(log.t, log.wrench, load_fingertip(path))
    touched = est.state >= 1
    assert touched.sum() > 20
    top = np.array(ELLIPSOID.center) + np.array([0.0, 0.0, ELLIPSOID.semi_axes[2]])  # the paper scenario's apex
    assert np.median(np.linalg.norm(est.point[touched] - top, axis=1)) < 0.5 * MM


@pytest.fixture(scope="module")
def ellipsoid_probing():
    """30 simulated plane presses with slides over ±85° of the ellipsoid (Nano17 noise, 50 Hz)."""
    return simulate_probing(ELLIPSOID, 45.0, max_tilt=math.radians(85.0), rng=7, n_elements=4000)


@pytest.fixture(scope="module")
def ellipsoid_calibration(ellipsoid_probing):
    return calibrate_fingertip(*ellipsoid_probing, "ellipsoid")


def test_the_ellipsoid_calibrates_from_plane_presses(ellipsoid_calibration):
    # the stated tolerance: semi-axes and centre within 0.3 mm, each within 3 of its standard deviations
    cal = ellipsoid_calibration
    assert isinstance(cal.tip, Ellipsoid) and cal.shape == "ellipsoid" and cal.n_presses == 30
    err = np.concatenate((np.subtract(cal.tip.center, ELLIPSOID.center), np.subtract(cal.tip.semi_axes, ELLIPSOID.semi_axes)))
    assert np.all(np.abs(err) < 0.3 * MM), err / MM
    assert np.all(np.abs(err) < 3.0 * cal.parameters_std), err / cal.parameters_std
    assert_allclose(cal.parameters, [*cal.tip.center, *cal.tip.semi_axes], rtol=0, atol=0)
    assert math.isnan(cal.radius)
    text = cal.summary()
    assert "shape ellipsoid: 30 presses" in text and "\n  semi-axes  a = " in text
    # the presses near the centre's height pin it (within ±60° the centre's height and c are entangled)
    assert cal.condition < 1e4


def test_softtip_calibrate_shape_ellipsoid_writes_the_fitted_file(tmp_path, ellipsoid_probing, ellipsoid_calibration):
    t, w = ellipsoid_probing
    log = tmp_path / "probe.csv"
    write_table({"t": t, **{c: w[:, i] for i, c in enumerate(("fx", "fy", "fz", "mx", "my", "mz"))}}, log, float_format="%.17g")
    out = tmp_path / "tip.toml"
    res = CliRunner().invoke(calibrate, [str(log), "--shape", "ellipsoid", "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert "semi-axes" in res.output
    tip = load_fingertip(out)
    # the CLI's moment noise goes through N·mm: the same fit to rounding
    assert isinstance(tip, Ellipsoid)
    assert_allclose(tip.semi_axes, ellipsoid_calibration.tip.semi_axes, rtol=1e-9)
    assert_allclose(tip.center, ellipsoid_calibration.tip.center, rtol=1e-9)
    assert out.read_text().splitlines()[1].startswith("# semi-axes std ")
