"""Capsules mounted off the sensor axis (``axis_offset = [x, y]``): geometry, file, contact, simulator, view."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from softtip import Capsule, InputError, contact_from_wrench, load_fingertip
from softtip.core._xp import PY
from softtip.core.fingertip import fingertip_from_mapping
from softtip.core.location import contact_kernel
from softtip.sim import discretise_skin
from softtip.viz.rerun import surface_mesh

offsets = st.tuples(st.floats(-3e-3, 3e-3), st.floats(-3e-3, 3e-3))


@st.composite
def offset_capsules(draw):
    return Capsule(draw(st.floats(0.005, 0.03)), draw(st.floats(0.0, 0.04)), draw(offsets))


@st.composite
def contacts_on(draw, tip):
    """(r, n, f, sigma): a push into the skin of ``tip`` at r, on the cap or the side."""
    ox, oy = tip.axis_offset
    if draw(st.booleans()):
        u = np.array([draw(st.floats(-1, 1)), draw(st.floats(-1, 1)), draw(st.floats(0.05, 1))])
        u /= np.linalg.norm(u)
        r = np.array([ox, oy, tip.length]) + tip.radius * u
    else:
        phi = draw(st.floats(-np.pi, np.pi))
        r = np.array([ox + tip.radius * np.cos(phi), oy + tip.radius * np.sin(phi), draw(st.floats(0.0, tip.length))])
    n = tip.normal(r)
    t = np.cross(n, [draw(st.floats(-1, 1)), draw(st.floats(-1, 1)), draw(st.floats(-1, 1))])
    t = t / np.linalg.norm(t) if np.linalg.norm(t) > 1e-6 else np.zeros(3)
    push = draw(st.floats(0.05, 20.0))
    f = -push * n + draw(st.floats(0.0, 1.0)) * push * t
    return r, n, f, draw(st.floats(-5e-3, 5e-3))


def wrench_of(r, n, f, sigma):
    return np.concatenate((f, np.cross(r, f) + sigma * n))


@given(data=st.data(), tip=offset_capsules())
def test_closed_form_round_trip_with_axis_offset(data, tip):
    r, n, f, sigma = data.draw(contacts_on(tip))
    w = wrench_of(r, n, f, sigma)
    c = contact_from_wrench(w, tip)
    assert c.valid
    assert np.linalg.norm(c.point - r) <= 1e-9
    assert_allclose(c.normal, n, atol=1e-8)
    assert abs(c.sigma - sigma) <= 1e-9 * max(1.0, np.linalg.norm(f))
    # the streaming path (scalar kernel) gives the batch result
    s = contact_kernel(tip, *map(float, w), PY)
    assert_allclose(s[:3], c.point, rtol=1e-12, atol=1e-15)
    assert_allclose(s[6], c.sigma, rtol=1e-12, atol=1e-18)


@given(tip=offset_capsules(), p=st.tuples(*[st.floats(-0.05, 0.05)] * 3))
def test_surface_normal_and_projection_follow_the_offset_axis(tip, p):
    ox, oy = tip.axis_offset
    centred = Capsule(tip.radius, tip.length)
    shifted = np.subtract(p, [ox, oy, 0.0])
    assert tip.surface(p) == pytest.approx(float(centred.surface(shifted)), abs=1e-12)
    assert_allclose(tip.normal(p), centred.normal(shifted), atol=1e-12)
    assert_allclose(tip.project(p), centred.project(shifted) + [ox, oy, 0.0], atol=1e-12)


def test_toml_round_trip_and_default(tmp_path):
    tip = Capsule(0.016, 0.02, (4e-4, -2.5e-4))
    path = tmp_path / "tip.toml"
    path.write_text(tip.to_toml())
    assert "axis_offset = [0.0004, -0.00025]" in path.read_text()
    assert load_fingertip(path) == tip
    # no key: on the sensor axis, and such a file does not mention it
    assert "axis_offset" not in Capsule(0.016, 0.02).to_toml()
    assert load_fingertip("murakami2006").axis_offset == (0.0, 0.0)


@pytest.mark.parametrize("value", [[0.001, 0.0, 0.0], 0.001, ["a", 0.0], [True, 0.0]])
def test_malformed_axis_offset_names_file_and_key(value):
    with pytest.raises(InputError, match=r"tip\.toml: \[fingertip\] axis_offset = .* list of 2 numbers \[x, y\] in metres"):
        fingertip_from_mapping({"fingertip": {"shape": "capsule", "radius": 0.016, "length": 0.02, "axis_offset": value}}, "tip.toml")
    with pytest.raises(ValueError, match="axis_offset"):
        Capsule(0.016, 0.02, (float("nan"), 0.0))


def test_simulator_skin_and_view_mesh_lie_on_the_offset_skin():
    tip = Capsule(0.015, 0.0225, (8e-4, -5e-4))
    skin = discretise_skin(tip, 2000)
    assert np.max(np.abs(tip.surface(skin.centres))) < 1e-12
    assert_allclose(tip.normal(skin.centres), skin.normals, atol=1e-12)
    assert_allclose(skin.centres[:, :2].mean(axis=0), tip.axis_offset, atol=2e-4)
    vertices, _, normals = surface_mesh(tip)
    assert np.max(np.abs(tip.surface(vertices))) < 1e-12
    assert_allclose(vertices[:, :2].mean(axis=0), tip.axis_offset, atol=1e-4)
