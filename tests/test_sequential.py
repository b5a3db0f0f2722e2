"""The stages' step functions: compiled and as Python, the same bits; when each runs."""

import dataclasses
import os
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import softtip.core._blocks
from softtip import estimate
from softtip.core._jit import JIT_MIN_SAMPLES, jit_enabled, set_jit, use_numba
from softtip.sim.synthetic import synthetic_grasp
from test_pipeline import CASES, drifting_grasp, grasp_with_two_contacts, impact_grasp, sliding_grasp

pytest.importorskip("numba")


@pytest.fixture
def both_paths():
    """Run a function with the compiled kernels and with the numpy paths."""
    old = set_jit(None)

    def run(fn, *args):
        out = []
        for flag in (True, False):
            set_jit(flag)
            out.append(fn(*args))
        return out

    yield run
    set_jit(old)


def assert_same_estimates(a, b):
    for f in dataclasses.fields(a):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, np.ndarray):
            # the same operations in the same order: equal to the last bit
            assert np.array_equal(x, y, equal_nan=x.dtype.kind == "f"), f.name
        else:
            assert repr(x) == repr(y), f.name


def _log(name):
    if name == "single":
        g = synthetic_grasp(angle_deg=45.0, seed=1)
        return g.t, g.wrench
    if name == "drifting":
        return drifting_grasp()
    if name == "taps":  # many short touches, some too quick for the latch window
        g = synthetic_grasp(angle_deg=30.0, duration=0.5, rate=1000.0, contact_time=0.1, settle_time=0.15,
                            h_start=0.2, h_rise=0.1, seed=1)  # fmt: skip
        lead = synthetic_grasp(duration=2.0, rate=1000.0, contact_time=5.0, seed=1)
        w = np.concatenate([lead.wrench] + [g.wrench] * 12)
        w[2600:2700] *= np.linspace(1.0, 3.0, 100)[:, None]  # a hard press: the rise ends early
        return np.arange(len(w)) / 1000.0, w
    return {"two-contacts": grasp_with_two_contacts, "impact": impact_grasp, "sliding": sliding_grasp}[name]()


@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("log", ["single", "two-contacts", "impact", "sliding", "drifting", "taps"])
def test_compiled_pipeline_equals_numpy(case, log, both_paths, recwarn):
    t, w = _log(log)
    a, b = both_paths(estimate, t, w, "murakami2006", CASES[case])
    assert_same_estimates(a, b)


@pytest.mark.parametrize("case", ["latch", "evidence-joint-depth-relatch", "online-short-window-lowpass-relatch"])
@pytest.mark.parametrize("log", ["two-contacts", "taps"])
def test_small_blocks_equal_one_block(case, log, both_paths, monkeypatch, recwarn):
    # blocks of 37 samples: the running sums carried across many block boundaries
    t, w = _log(log)
    a, b = both_paths(estimate, t, w, "murakami2006", CASES[case])
    monkeypatch.setattr(softtip.core._blocks, "BLOCK", 37)
    c, d = both_paths(estimate, t, w, "murakami2006", CASES[case])
    for x in (b, c, d):
        assert_same_estimates(a, x)


def test_short_logs_take_the_numpy_path(monkeypatch):
    monkeypatch.delenv("SOFTTIP_NUMBA", raising=False)
    old = set_jit(None)
    try:
        assert not jit_enabled(JIT_MIN_SAMPLES - 1)
        assert jit_enabled(JIT_MIN_SAMPLES)
        monkeypatch.setenv("SOFTTIP_NUMBA", "0")
        assert not jit_enabled(10 * JIT_MIN_SAMPLES)
        monkeypatch.setenv("SOFTTIP_NUMBA", "1")
        assert jit_enabled(1)
    finally:
        set_jit(old)


def test_step_functions_run_compiled_whenever_numba_is_used(monkeypatch):
    # a step function has no numpy path: compiled for a stream and for long logs (short ones too
    # once numba is loaded), as Python when SOFTTIP_NUMBA=0
    from softtip.core._jit import STEP_MIN_SAMPLES
    from softtip.estimator.depth import depth_step

    monkeypatch.delenv("SOFTTIP_NUMBA", raising=False)
    old = set_jit(None)
    try:
        assert use_numba() and depth_step.function() is depth_step.compiled()
        assert use_numba(STEP_MIN_SAMPLES) and depth_step.function(STEP_MIN_SAMPLES) is depth_step.compiled()
        assert use_numba(10)  # numba is loaded in this process by now: no start-up left to save
        monkeypatch.setenv("SOFTTIP_NUMBA", "0")
        assert not use_numba() and depth_step.function() is depth_step.python
        set_jit(True)  # the setting outranks the environment
        assert use_numba() and depth_step.function() is depth_step.compiled()
    finally:
        set_jit(old)


def test_a_short_log_in_a_fresh_process_does_not_load_numba():
    # importing numba and loading the steps (about 0.7 s of CPU) costs more than a short log as Python
    code = (
        "import sys, warnings; warnings.simplefilter('ignore'); import softtip; log = softtip.load_example(); "
        "e = softtip.estimate(log.t, log.wrench); print('numba' in sys.modules, int((e.state == 2).sum()))"
    )
    env = {k: v for k, v in os.environ.items() if k != "SOFTTIP_NUMBA"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120)
    assert out.returncode == 0, out.stderr
    loaded, lines = out.stdout.split()
    assert loaded == "False" and int(lines) > 0


@settings(max_examples=60, deadline=None)
@given(
    n=st.integers(1, 600),
    p_touch=st.floats(0.0, 0.2),
    cut=st.floats(0.0, 1.0),
    start=st.integers(0, 20),
    tau=st.sampled_from([0.01, 0.5, 5.0]),
    seed=st.integers(0, 2**32 - 1),
    cut_from=st.integers(0, 620),
)
def test_track_contacts_compiled_equals_python(n, p_touch, cut, start, tau, seed, cut_from):
    # one source (contact_step in contact_run), compiled and as Python, the same bits: touches
    # of random lengths and forces (near the thresholds too) on a drifting bias, tracked at
    # once and in two pieces cut at an untouched sample (the state carried); and tracked up to
    # the first untouched sample from cut_from on (the piece a log is cut into), in one pass
    from softtip.core.noise import SensorNoise
    from softtip.estimator import EstimatorConfig
    from softtip.estimator.contact import track_contacts

    rng = np.random.default_rng(seed)
    steps = rng.choice([0.0, 1e-3, 2.5e-3, 0.05], size=n, p=[0.1, 0.6, 0.2, 0.1])
    t = 10.0 + np.cumsum(steps)
    x = rng.normal(scale=0.02, size=(n, 6)) + np.linspace(0.0, 0.3, n)[:, None]
    touch = np.repeat(rng.random(n // 4 + 1) < p_touch, 4)[:n]
    x[touch, :3] += rng.choice([0.1, 0.2, 1.0], size=(np.count_nonzero(touch), 1))
    config = EstimatorConfig(drift_time_constant=tau, contact_threshold=0.2)
    noise = SensorNoise(force_std=(0.02,) * 3, moment_std=(2e-4,) * 3)
    start = min(start, n)
    out = []
    for flag in (True, False):
        set_jit(flag)
        try:
            whole = track_contacts(t, x, start, config, noise)
            free = np.flatnonzero(~whole.busy[start:]) + start
            k = int(free[int(cut * (len(free) - 1))]) if len(free) else n
            first = track_contacts(t[:k], x[:k], start, config, noise)
            second = track_contacts(t[k:], x[k:], 0, config, noise, first.state)
            upto = track_contacts(t, x, start, config, noise, cut_from=cut_from)
            free = np.flatnonzero(~whole.busy[max(start, cut_from):]) + max(start, cut_from)
            if not len(free):
                assert upto is None
            else:
                c = int(free[0])
                alone = track_contacts(t[:c], x[:c], start, config, noise)
                for name in ("wrench", "drift", "contact", "contact_id", "busy"):
                    assert np.array_equal(getattr(upto, name), getattr(alone, name)), name
                assert upto.drift_alarm == alone.drift_alarm
                assert np.array_equal(upto.state.state, alone.state.state, equal_nan=True)
        finally:
            set_jit(None)
        out.append((whole, first, second))
    for a, b in zip(out[0], out[1]):
        for name in ("wrench", "drift", "contact", "contact_id", "busy"):
            assert np.array_equal(getattr(a, name), getattr(b, name)), name
        assert a.drift_alarm == b.drift_alarm
        assert np.array_equal(a.state.state, b.state.state, equal_nan=True)
    (whole, first, second), _ = out
    assert np.array_equal(whole.drift, np.concatenate((first.drift, second.drift)))
    assert np.array_equal(whole.contact_id, np.concatenate((first.contact_id, second.contact_id)))


@pytest.mark.parametrize("block", [1, 7, 1000])
def test_blockwise_writes_into_given_outputs(block):
    # outputs given as columns of an (N, 2) array are written there, the others allocated;
    # every block's values land where the whole-array expression puts them
    from softtip.core._blocks import blockwise

    rng = np.random.default_rng(3)
    a, b = rng.normal(size=50), rng.normal(size=50)
    pair = np.full((50, 2), np.nan)
    s, d, q = blockwise(lambda x, y: (x + y, x - y, x * y), (a, b), block=block, out=(*pair.T, None))
    assert s.base is pair and d.base is pair
    assert np.array_equal(pair, np.stack((a + b, a - b), axis=-1))
    assert np.array_equal(q, a * b)
