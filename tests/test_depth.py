import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from softtip import EstimatorConfig, axial_difference, estimate
from softtip.core._xp import NP, PY
from softtip.core.depth import MURAKAMI2006_DEPTH, DepthLaw, depth_kernel, lever_depth
from softtip.sim.synthetic import smoothstep, synthetic_grasp


def grasp_with_friction_at_depth(law, ratio=0.4, angle=30.0):
    """A line contact whose tangential force (across the line, after the latch) acts at the
    law's depth below the skin: m gains (r − δn) × f_t instead of r × f_t."""
    g = synthetic_grasp(angle_deg=angle, noise=None, seed=None, tangential_ratio=0.0)
    n, d = g.normal, g.direction
    across = np.cross(n, d)
    f_normal = -g.wrench_true[:, :3] @ n
    ft = ratio * f_normal[:, None] * smoothstep((g.t - 5.0) / 1.0)[:, None] * across
    delta = depth_kernel(f_normal, law, NP)
    w = g.wrench.copy()
    w[:, :3] += ft
    w[:, 3:] += np.cross(g.point - delta[:, None] * n, ft)
    return g, w


def test_depth_law_values():
    law = MURAKAMI2006_DEPTH
    assert depth_kernel(0.2 * 9.80665, law, PY) == pytest.approx(0.99e-3, abs=0.01e-3)
    assert depth_kernel(1e9, law, PY) == law.max_depth
    assert depth_kernel(-1.0, law, PY) == 0.0
    with pytest.raises(ValueError):
        DepthLaw(-1.0)


@given(st.floats(0.0, 50.0))
def test_float_and_array_kernels_agree(f_normal):
    assert depth_kernel(f_normal, MURAKAMI2006_DEPTH, PY) == pytest.approx(float(depth_kernel(np.array([f_normal]), MURAKAMI2006_DEPTH, NP)[0]), rel=1e-12, abs=0)


def test_depth_compensation_removes_the_friction_lever():
    law = MURAKAMI2006_DEPTH
    g, w = grasp_with_friction_at_depth(law)
    late = g.t > 6.5
    plain = estimate(g.t, w, "murakami2006", EstimatorConfig(depth_compensation="off"))  # the papers' method
    # drift tracking off: it takes in the first samples of the touch, below the contact
    # threshold (~1e-4 N here), which this exactness check would see
    comp = estimate(g.t, w, "murakami2006", EstimatorConfig(skin_law=law, depth_compensation="law", drift_tracking=False))
    err_plain = np.degrees(np.abs(axial_difference(plain.angle[late], g.angle)))
    err_comp = np.degrees(np.abs(axial_difference(comp.angle[late], g.angle)))
    assert np.nanmedian(err_plain) > 5.0  # the lever rotates the direction
    assert np.nanmax(err_comp) < 1e-6  # the exact law removes it (noise-free)
    assert_allclose(comp.depth[late], depth_kernel(-comp.wrench[late, :3] @ g.normal, law, NP), rtol=1e-12)
    assert (plain.depth[plain.state > 0] == 0.0).all()


def test_lever_depth_recovers_the_depth():
    law = DepthLaw(3e6, 1.5, 0.005)
    g, w = grasp_with_friction_at_depth(law, angle=-20.0)
    late = g.t > 6.5
    lever = lever_depth(w[late] - g.bias, g.point, g.normal, g.direction)
    f_normal = -(w[late, :3] - g.bias[:3]) @ g.normal
    assert_allclose(lever, depth_kernel(f_normal, law, NP), rtol=1e-6)


def test_fit_recovers_the_law():
    law = DepthLaw(2.5e6, 1.8, 0.005)
    f_normal = np.linspace(1.0, 6.0, 40)
    fitted = DepthLaw.fit(f_normal, depth_kernel(f_normal, law, NP))
    assert fitted.stiffness == pytest.approx(law.stiffness, rel=1e-6)
    assert fitted.exponent == pytest.approx(law.exponent, rel=1e-6)
