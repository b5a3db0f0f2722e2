"""The batch pipeline's compiled loops (softtip.estimator.pipeline): the staged path's bits on
every closed-form shape and mode, and the same source run as Python."""

import numpy as np
import pytest

from softtip import Capsule, Ellipsoid, EstimatorConfig, Sphere, estimate
from softtip.core._jit import set_jit
from softtip.core.depth import MURAKAMI2006_DEPTH, DepthLaw
from softtip.estimator import pipeline
from softtip.sim.synthetic import synthetic_grasp
from test_sequential import assert_same_estimates

pytest.importorskip("numba")

TIPS = {
    "sphere": Sphere(0.02, center=(0.0, 0.0, 0.01)),
    "capsule-offset": Capsule(0.016, 0.02, axis_offset=(0.001, -0.002)),
    "ellipsoid": Ellipsoid((0.014, 0.016, 0.022), center=(0.0, 0.0, 0.01)),
}
CONFIGS = {
    "latch": EstimatorConfig(),
    "track": EstimatorConfig(contact_point="track"),
    "relatch-law": EstimatorConfig(relatch_distance=2e-3, depth_compensation="law", skin_law=MURAKAMI2006_DEPTH),
    "line-fit-lowpass": EstimatorConfig(contact_point="line-fit", lowpass_hz=8.0, sample_rate=50.0),
    "line-fit-law": EstimatorConfig(contact_point="line-fit", skin_law=MURAKAMI2006_DEPTH),
}


def _grasp(tip):
    g = synthetic_grasp(tip, angle_deg=30.0, seed=3)
    return g.t, g.wrench


def _both(t, w, tip, config):
    old = set_jit(True)
    try:
        fused = estimate(t, w, tip, config)
        set_jit(False)  # the staged path, its steps as Python
        staged = estimate(t, w, tip, config)
    finally:
        set_jit(old)
    return fused, staged


@pytest.mark.parametrize("config", sorted(CONFIGS))
@pytest.mark.parametrize("tip", sorted(TIPS))
def test_fused_equals_staged(tip, config, recwarn):
    t, w = _grasp(TIPS[tip])
    fused, staged = _both(t, w, TIPS[tip], CONFIGS[config])
    assert_same_estimates(fused, staged)
    assert np.any(fused.state > 0)  # the grasp was located


def test_only_closed_forms_and_square_laws_are_fused():
    assert pipeline.shape_record(Capsule(0.016, 0.02)).kind == pipeline.CAPSULE
    assert pipeline.shape_record(Sphere(0.02)).kind == pipeline.SPHERE
    assert pipeline.shape_record(Ellipsoid((0.01, 0.02, 0.03))).kind == pipeline.ELLIPSOID

    class Bigger(Sphere):  # a subclass may change the kernels: the staged path
        pass

    assert pipeline.shape_record(Bigger(0.02)) is None
    t, w = _grasp("murakami2006")
    z = np.zeros((len(t), 6))
    args = (t, w.copy(), z, np.zeros(len(t), dtype=bool), np.zeros(len(t), dtype=bool))
    old = set_jit(True)
    try:
        config = EstimatorConfig(depth_compensation="law", skin_law=DepthLaw(2e6, 1.5, 0.005))
        assert pipeline.fused_columns(*args, Capsule(0.016, 0.02), config, None, 1.0, False) is None
        assert pipeline.fused_columns(*args, Bigger(0.02), EstimatorConfig(), None, 1.0, False) is None
    finally:
        set_jit(old)


@pytest.mark.parametrize("config", ["latch", "track", "line-fit-lowpass"])
def test_the_loops_as_python_give_the_compiled_bits(config, monkeypatch, recwarn):
    # the loops' one source, run as Python (the steps' and kernels' Python forms): the compiled bits
    g = synthetic_grasp("murakami2006", angle_deg=30.0, seed=3, duration=6.0)
    t, w = g.t, g.wrench
    old = set_jit(True)
    try:
        compiled = estimate(t, w, "murakami2006", CONFIGS[config])
        for loop in (pipeline.points_run, pipeline.line_fit_run, pipeline.tail_run, pipeline.ring_rows):
            monkeypatch.setattr(loop, "compiled", lambda loop=loop: loop.python)
        python = estimate(t, w, "murakami2006", CONFIGS[config])
    finally:
        set_jit(old)
    assert_same_estimates(compiled, python)


def test_reused_buffers_give_the_same_columns():
    from softtip.estimator.batch import _sequential_stages
    from softtip.estimator.depth import resolve_depth
    from softtip.estimator.measure import noise_correlation

    g = synthetic_grasp("murakami2006", angle_deg=30.0, seed=3)
    tip = Capsule(0.016, 0.02, skin_thickness=0.005)
    config = resolve_depth(EstimatorConfig(contact_point="line-fit"), tip)
    old = set_jit(True)
    try:
        runs = []
        out = {}
        for _ in range(2):
            _, taring, _, sos, noise, ct, *_ = _sequential_stages(g.t, g.wrench, config, None)
            cols = pipeline.fused_columns(g.t, ct.wrench, ct.drift, ct.contact, taring, tip, config, noise,
                                          noise_correlation(sos), False, out=out)  # fmt: skip
            runs.append({k: np.array(v) for k, v in cols.items()})
    finally:
        set_jit(old)
    assert out and all(np.array_equal(runs[0][k], runs[1][k], equal_nan=runs[0][k].dtype.kind == "f") for k in runs[0])
