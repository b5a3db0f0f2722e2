from pathlib import Path

import numpy as np
import pytest

import softtip
from softtip import Estimator, EstimatorConfig, contact_from_wrench, estimate
from softtip.core._jit import set_jit
from softtip.core.fingertip import load_fingertip
from softtip.core.location import contact_arrays
from softtip.estimator.batch import Carry
from softtip.estimator.latch import latch_points
from softtip.sim.synthetic import synthetic_grasp


def sliding_grasp(slide=0.004):
    """After the grasp the force drops into the light-force window and the contact slides
    ``slide`` m along x on the tip (the moment follows the moved point)."""
    g = synthetic_grasp(angle_deg=30.0, noise=None, seed=None, h_peak=0.0)
    w = g.wrench.copy()
    late = g.t > 6.0
    f = w[:, :3] - g.bias[:3]
    f[late] *= 0.4 / 0.55
    shift = np.clip((g.t - 6.0) / 1.0, 0.0, 1.0)[:, None] * np.array([slide, 0.0, 0.0])
    w[:, :3] = f + g.bias[:3]
    w[:, 3:] = np.cross(g.point + shift, f) + g.bias[3:]
    return g, w, shift


def test_a_stale_latch_is_replaced_when_the_contact_moves():
    g, w, shift = sliding_grasp()
    held = estimate(g.t, w, "murakami2006")
    moving = estimate(g.t, w, "murakami2006", EstimatorConfig(relatch_distance=2e-3))
    end = g.t > 8.0
    # where the contact is now: the soft-finger solution of the (spin-free) final wrench
    now = contact_from_wrench(w[end] - g.bias, "murakami2006").point
    stale = np.linalg.norm(held.point[end] - now, axis=1)
    fresh = np.linalg.norm(moving.point[end] - now, axis=1)
    assert np.min(stale) > 3.5e-3  # the papers' latch keeps the first point
    assert not held.relatched.any()
    assert moving.relatched.sum() >= 1
    # re-latched whenever the drift passed 2 mm: never staler than that
    assert np.max(fresh) < 2e-3


def test_no_relatch_while_the_contact_stays():
    g = synthetic_grasp(angle_deg=45.0, seed=3)
    est = estimate(g.t, g.wrench, "murakami2006", EstimatorConfig(relatch_distance=3e-3))
    assert not est.relatched.any()


def test_contact_regained_is_flagged():
    g1 = synthetic_grasp(angle_deg=30.0, duration=6.0, seed=3)
    g2 = synthetic_grasp(angle_deg=-60.0, duration=6.0, seed=4)
    t = np.concatenate((g1.t, g2.t + 6.0))
    w = np.concatenate((g1.wrench, g2.wrench))
    est = estimate(t, w, "murakami2006")
    starts = np.flatnonzero(np.diff((est.state > 0).astype(int)) == 1) + 1
    assert len(starts) == 2
    assert not est.relatched[starts[0]] and est.relatched[starts[1]]


# -- one step function, batch and stream (estimator/latch.py) -----------------------------------------

NAIL = Path(softtip.__file__).parent / "data" / "murakami2006_nail.toml"
LATCH_COLUMNS = ("point", "latched", "latch_fallback", "relatched", "state")


def taps_log():
    """A long untouched lead, then short touches at 1 kHz, one pressed hard (its rise ends at
    once): latches on the window and on the fallback, and contacts regained after a latch."""
    g = synthetic_grasp(angle_deg=30.0, duration=0.5, rate=1000.0, contact_time=0.1, settle_time=0.15,
                        h_start=0.2, h_rise=0.1, seed=1)  # fmt: skip
    lead = synthetic_grasp(duration=2.0, rate=1000.0, contact_time=5.0, seed=1)
    w = np.concatenate([lead.wrench] + [g.wrench] * 4)
    w[2600:2700] *= np.linspace(1.0, 3.0, 100)[:, None]
    return np.arange(len(w)) / 1000.0, w


def _sliding():
    g, w, _ = sliding_grasp()
    return g.t, w


def _grasp():
    g = synthetic_grasp(angle_deg=45.0, seed=1)
    return g.t, g.wrench


LATCH_CASES = {
    "tight-relatch": (_sliding, EstimatorConfig(relatch_distance=0.3e-3), "murakami2006"),
    "tight-relatch-nail": (_sliding, EstimatorConfig(relatch_distance=0.3e-3), NAIL),
    "taps": (taps_log, EstimatorConfig(relatch_distance=3e-3), "murakami2006"),
    # the rise stalls before the light-force window: a fallback latch, re-latched at light force
    # (a stall time under the 50 Hz period: one sample without a new peak stalls; at exactly one
    # period a sample sits on the stall's edge, which does not count)
    "stall-fallback-relatch": (_grasp, EstimatorConfig(stall_time=0.015, relatch_distance=1e-3), "murakami2006"),
    # a window no sample falls in: every latch is a fallback one
    "fallback-nail": (_sliding, EstimatorConfig(latch_window=(0.01, 0.02), fallback_samples=3), NAIL),
}


def _stream_columns(t, w, tip, config):
    out = Estimator(tip, config).process(t, w)
    return {name: np.array([getattr(s, name) for s in out]) for name in LATCH_COLUMNS}


@pytest.mark.parametrize("case", sorted(LATCH_CASES))
def test_latch_batch_equals_stream_to_the_bit(case, recwarn):
    # the batch runs the stream's step: the same decisions, the same sums, the same projections
    log, config, tip = LATCH_CASES[case]
    t, w = log()
    batch = estimate(t, w, tip, config)
    stream = _stream_columns(t, w, tip, config)
    for name in LATCH_COLUMNS[:-1]:
        assert np.array_equal(stream[name], getattr(batch, name), equal_nan=True), name
    assert list(stream["state"]) == list(batch.state_names)
    assert batch.latched.any()


def test_the_cases_reach_every_branch(recwarn):
    # what the cases above are for: re-latches after re-latches, fallback latches, both tips
    t, w = _sliding()
    est = estimate(t, w, "murakami2006", LATCH_CASES["tight-relatch"][1])
    assert est.relatched.sum() >= 3 and (est.latched & ~est.latch_fallback).any()
    t, w = _grasp()
    est = estimate(t, w, "murakami2006", LATCH_CASES["stall-fallback-relatch"][1])
    first = np.flatnonzero(est.relatched)[0]
    assert est.latch_fallback[:first].any() and not est.latch_fallback[first:].any()
    t, w = taps_log()
    est = estimate(t, w, "murakami2006", LATCH_CASES["taps"][1])
    assert est.latch_fallback.any() and est.relatched.any()


@pytest.mark.parametrize("case", ["tight-relatch", "taps", "fallback-nail"])
def test_latch_step_compiled_equals_python(case, recwarn):
    # latch_step compiled (numba) and as Python (SOFTTIP_NUMBA=0): the same bits
    pytest.importorskip("numba")
    log, config, tip = LATCH_CASES[case]
    t, w = log()
    tip = load_fingertip(tip)
    bias = np.median(w[:50], axis=0)
    x = w - bias
    f_norm = np.linalg.norm(x[:, :3], axis=1)
    contact = f_norm > 0.2
    with np.errstate(invalid="ignore", divide="ignore"):
        sc = contact_arrays(tip, *x.T)
    old = set_jit(True)
    try:
        out = []
        for flag in (True, False):
            set_jit(flag)
            out.append((latch_points(t, f_norm, contact, sc, tip, config), _stream_columns(t, w, tip, config)))
    finally:
        set_jit(old)
    (fast, fast_stream), (slow, slow_stream) = out
    for a, b in zip(fast, slow):
        assert np.array_equal(a, b, equal_nan=True)
    for name in LATCH_COLUMNS:
        assert np.array_equal(fast_stream[name], slow_stream[name], equal_nan=name != "state"), name
    assert fast.latched.any()


def test_a_log_in_pieces_carries_the_latch(recwarn):
    # Carry.had_latch: the contact after a cut starts re-latched as in the one-shot run
    t, w = taps_log()
    config = EstimatorConfig(relatch_distance=3e-3)
    whole = estimate(t, w, "murakami2006", config)
    free = np.flatnonzero((whole.contact_id == 0) & (t > 2.5))
    cut = int(free[len(free) // 2])
    carry = Carry()
    pieces = [estimate(t[:cut], w[:cut], "murakami2006", config, carry=carry)]
    assert carry.had_latch
    pieces.append(estimate(t[cut:], w[cut:], "murakami2006", config, carry=carry))
    for name in LATCH_COLUMNS[:-1]:
        got = np.concatenate([getattr(p, name) for p in pieces])
        assert np.array_equal(got, getattr(whole, name), equal_nan=True), name
    assert whole.relatched[cut:].any()


@pytest.mark.parametrize("seed", range(4))
def test_a_press_lighter_than_the_window_is_latched_where_it_pushes(seed, recwarn):
    # a pure push to 1.5 N, below the 1.96 N window, at 200 Hz: the fallback averages the rise
    # weighted by |f|²; it took the contact's first five solutions, at the contact threshold,
    # and latched about 1 mm off, so that the lever error read as a line (h = Δr × f)
    g = synthetic_grasp(angle_deg=0.0, rate=200.0, force=1.5, h_peak=0.0, spin=0.0, seed=seed)
    est = estimate(g.t, g.wrench, "murakami2006")
    held = est.latch_fallback
    assert held.sum() > 0.5 * np.count_nonzero(est.contact_id)
    assert np.linalg.norm(est.point[held] - g.point, axis=1).max() < 0.1e-3
    assert "line" not in set(np.asarray(est.state_names)[est.contact_id > 0])
