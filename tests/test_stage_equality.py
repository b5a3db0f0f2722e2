"""Each estimator stage's batch form against its stream form, on the same inputs.

The whole pipeline's batch == stream test (test_pipeline) says that something differs; these
say which stage. Each stage gets identical inputs (made by the batch stages before it) and its
outputs must agree to 1e-12 relative, sample by sample.
"""

import dataclasses
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from rocking import rocking_log
from softtip import EstimatorConfig, load_fingertip
from softtip.core._jit import set_jit
from softtip.core._xp import NP, PY
from softtip.core.depth import DepthLaw
from softtip.core.location import contact_arrays
from softtip.core.noise import noise_variances
from softtip.estimator.contact import ContactTracker, track_contacts
from softtip.estimator.depth import DepthTracker, depth_points, resolve_depth
from softtip.estimator.evidence import EvidenceTracker, evidence_states
from softtip.estimator.floats import PointGeometry
from softtip.estimator.latch import latch_points
from softtip.estimator.measure import effective_noise, measure, noise_correlation
from softtip.estimator.tare import StreamTare, tare_log
from softtip.sim.synthetic import synthetic_grasp

CLOSE = dict(rtol=1e-12, atol=1e-300, equal_nan=True)


def _two_grasps(seed: int, drift: float = 0.0):
    """Two 1 kHz grasps (−45° then +30°) back to back, with an optional force drift, N/s."""
    a = synthetic_grasp("murakami2006", angle_deg=-45.0, duration=6.0, rate=1000.0, seed=seed)
    b = synthetic_grasp("murakami2006", angle_deg=30.0, duration=6.0, rate=1000.0, seed=seed + 1)
    t = np.concatenate((a.t, b.t + a.t[-1] + 1e-3))
    w = np.concatenate((a.wrench, b.wrench))
    w[:, 2] += drift * t
    return t, w


def _rocked(kind: str, seed: int):
    t, w, _ = rocking_log(kind, 20.0, rate=200.0, seed=seed)
    return t, w


LOGS = {
    "two grasps": lambda: _two_grasps(3),
    "two grasps, drifting": lambda: _two_grasps(4, drift=-2e-3),
    "rocked line": lambda: _rocked("line", 5),
    "rocked area": lambda: _rocked("area", 6),
}


def _stages(t, w, config):
    """The batch stages up to the evidence stage's inputs (as softtip.estimate runs them)."""
    tip = load_fingertip("murakami2006")
    config = resolve_depth(config, tip)
    noise = effective_noise(config.noise, None)
    corr = noise_correlation(None)
    bias, taring, _ = tare_log(t, w, config)
    x = w - bias
    ct = track_contacts(t, x, int(np.count_nonzero(taring)), config, noise)
    c = [np.ascontiguousarray(ct.wrench[:, i]) for i in range(6)]
    fn = np.sqrt(c[0] ** 2 + c[1] ** 2 + c[2] ** 2)
    with np.errstate(invalid="ignore", divide="ignore"):
        sc = contact_arrays(tip, *c)
        point, _, _, relatched = latch_points(t, fn, ct.contact, sc, tip, config)
        normal = tip.normal(point)
        delta, delta_std, from_data = depth_points(t, c, ct.contact, point, normal, config, noise, corr)
        eff = point - delta[:, None] * normal
        ms = measure(*c, *eff.T, *normal.T, noise, config.h_sigmas, config.h_min, None, NP, delta_std)
    has = np.all(np.isfinite(point), axis=-1)
    located = ct.contact & has & ms.pushing
    begin = ct.contact & ~np.concatenate(([False], ct.contact[:-1])) | (relatched & ct.contact)
    return dict(
        tip=tip, config=config, noise=noise, corr=corr, bias=bias, taring=taring, x=x, ct=ct, c=c,
        point=point, normal=normal, relatched=relatched, depth=(delta, delta_std, from_data), ms=ms,
        located=located, begin=begin,
    )  # fmt: skip


@pytest.fixture(scope="module", params=sorted(LOGS))
def staged(request):
    t, w = LOGS[request.param]()
    return t, w, _stages(t, w, EstimatorConfig())


def test_tare_stage(staged):
    t, w, s = staged
    tare = StreamTare(s["config"])
    taring = [tare.update(ti, wi) is None for ti, wi in zip(t.tolist(), w.tolist())]
    assert_array_equal(taring, s["taring"])
    assert_allclose(tare.bias, s["bias"], **CLOSE)


def test_contact_stage(staged):
    t, _, s = staged
    tracker = ContactTracker(s["config"], s["noise"])
    ct = s["ct"]
    start = int(np.count_nonzero(s["taring"]))
    prev = float(t[start - 1]) if start else None  # the stream's dt spans the last tare sample
    ys, ids, drift = [], [], []
    for ti, xi in zip(t[start:].tolist(), s["x"][start:].tolist()):
        y, _ = tracker.step(ti, 0.0 if prev is None else ti - prev, xi)
        prev = ti
        ys.append(y)
        ids.append(tracker.contact_id)
        drift.append(tracker.drift_before)
    assert_array_equal(ids, ct.contact_id[start:])
    assert_allclose(np.array(ys), ct.wrench[start:], **CLOSE)
    assert_allclose(np.array(drift), ct.drift[start:], **CLOSE)
    assert ct.contact_id.max() >= 1  # the logs do have contacts


def test_contact_step_compiled_equals_python(staged):
    """contact_step is one source: compiled and as Python (the batch loop and the stream), the same bits."""
    from softtip.core._jit import set_jit

    t, _, s = staged
    start = int(np.count_nonzero(s["taring"]))
    runs = []
    for jit in (True, False):
        old = set_jit(jit)
        try:
            ct = track_contacts(t, s["x"], start, s["config"], s["noise"])
            tracker = ContactTracker(s["config"], s["noise"])
            prev, rows = None, []
            for ti, xi in zip(t[start:].tolist(), s["x"][start:].tolist()):
                y, code = tracker.step(ti, 0.0 if prev is None else ti - prev, xi)
                prev = ti
                rows.append((*y, code, tracker.contact_id, *tracker.drift_before))
        finally:
            set_jit(old)
        runs.append((ct, np.array(rows), tracker.state.copy()))
    (a, rows_a, state_a), (b, rows_b, state_b) = runs
    for name in ("wrench", "drift", "contact_id", "busy"):
        assert_array_equal(getattr(a, name), getattr(b, name))
    assert np.array_equal(a.state.state, b.state.state, equal_nan=True)
    assert_array_equal(rows_a, rows_b)
    assert np.array_equal(state_a, state_b, equal_nan=True)


def _stream_depth(tracker, t, c, contact, point, normal):
    """(N, 3): depth, depth_std, from_data of ``tracker`` fed the batch's inputs sample by sample."""
    onset = contact & ~np.concatenate(([False], contact[:-1]))
    got = np.zeros((len(t), 3))
    for i in np.flatnonzero(contact):
        if onset[i]:
            tracker.start_contact()
        if not np.all(np.isfinite(point[i])):
            tracker.gap()
            continue
        x = [float(c[k][i]) for k in range(6)]
        d, d_std, data = tracker.step(float(t[i]), x, tuple(point[i].tolist()), tuple(normal[i].tolist()))
        got[i] = d, d_std, float(data)
    return got


def test_depth_stage(staged):
    """The online depth, fed the batch's contact points and normals sample by sample."""
    t, _, s = staged
    got = _stream_depth(DepthTracker(s["config"], s["noise"], s["corr"]), t, s["c"], s["ct"].contact, s["point"],
                        s["normal"])  # fmt: skip
    delta, delta_std, from_data = s["depth"]
    assert_allclose(got[:, 0], delta, **CLOSE)
    assert_allclose(got[:, 1], delta_std, **CLOSE)
    assert_array_equal(got[:, 2].astype(bool), from_data)


DEPTH_MODES = {
    "latch": dict(),
    # a new segment at every sample (the point moves): no window is ever solved
    "track": dict(contact_point="track", depth_compensation="online"),
    "law p=1.5": dict(skin_law=DepthLaw(3.0e5, 1.5, 0.004)),
    "short window": dict(depth_window=0.05, depth_drift=0.2),
    "law only": dict(depth_compensation="law"),
}


@pytest.mark.parametrize("mode", sorted(DEPTH_MODES))
def test_depth_step_compiled_equals_python(staged, mode, request):
    """One source: the depth step compiled (numba) and as Python (``SOFTTIP_NUMBA=0``) give the
    same bits, in the batch's loop and in the stream, which give the same bits too."""
    pytest.importorskip("numba")
    t, _, s = staged
    config = resolve_depth(dataclasses.replace(s["config"], **DEPTH_MODES[mode]), s["tip"])
    contact, point, normal = s["ct"].contact, s["point"], s["normal"]
    if config.contact_point == "track":
        with np.errstate(invalid="ignore", divide="ignore"):
            sc = contact_arrays(s["tip"], *s["c"])
        point, normal = np.stack(sc.point, axis=-1), np.stack(sc.normal, axis=-1)
    out = {}
    old = set_jit(None)
    try:
        for compiled in (True, False):
            set_jit(compiled)
            batch = depth_points(t, s["c"], contact, point, normal, config, s["noise"], s["corr"])
            tracker = DepthTracker(config, s["noise"], s["corr"])
            out[compiled] = batch, _stream_depth(tracker, t, s["c"], contact, point, normal)
    finally:
        set_jit(old)
    (batch, stream), (batch_py, stream_py) = out[True], out[False]
    for a, b in zip(batch, batch_py):
        assert_array_equal(a, b)
    assert_array_equal(stream, stream_py)
    assert_array_equal(stream, np.stack((batch[0], batch[1], batch[2].astype(float)), axis=-1))
    assert np.count_nonzero(out[True][0].depth) > 100  # the log reaches the stage
    if mode in ("latch", "law p=1.5") and request.node.callspec.params["staged"].startswith("two grasps"):
        assert out[True][0].from_data.any()  # windows were solved and informed the depth


def test_evidence_stage(staged):
    """The line/area verdicts and directions, fed the batch's measurements sample by sample."""
    t, _, s = staged
    cfg, ms = s["config"], s["ms"]
    h = np.stack((ms.hx, ms.hy, ms.hz), axis=-1)
    force = np.stack(s["c"][:3], axis=-1)
    state, evidence, d, angle, angle_std, noise_std, h_ratio, f_ratio = evidence_states(
        t, s["located"], s["begin"], s["point"], s["normal"], h, force, ms, s["noise"], s["corr"], cfg, s["depth"][0]
    )
    tracker = EvidenceTracker(cfg, s["noise"], s["corr"])
    variances = noise_variances(s["noise"])
    names = {1: "point", 2: "line", 3: "area"}
    eff = s["point"] - s["depth"][0][:, None] * s["normal"]  # h is taken about the point under the depth
    geo = None
    for i in np.flatnonzero(s["located"]):
        if s["begin"][i]:
            tracker.start_segment()
        point, normal = tuple(s["point"][i].tolist()), tuple(s["normal"][i].tolist())
        if geo is None or geo.point != point or geo.normal != normal:  # one geometry per held point
            geo = PointGeometry(point, normal, variances)
        st, ev, di, an, an_std, an_noise, hr, fr = tracker.step(
            float(t[i]), geo, *eff[i].tolist(), *h[i].tolist(), *force[i].tolist(), float(ms.h_norm[i]),
            float(ms.h_std[i]),
        )  # fmt: skip
        assert st == names[int(state[i])], i
        assert ev == {0: "", 1: "unconfirmed", 2: "confirmed"}[int(evidence[i])], i
        if st == "line":
            assert_allclose(di, d[i], **CLOSE)
            assert_allclose([an, an_std, an_noise], [angle[i], angle_std[i], noise_std[i]], **CLOSE)
        assert_allclose([hr, fr], [h_ratio[i], f_ratio[i]], **CLOSE)
    seen = set(np.unique(state[s["located"]]).tolist())
    assert len(seen) >= 2, seen  # the log exercises the stage: more than one state


def test_measure_stage_is_one_kernel():
    """measure() in both back ends, on random pushes: identical to rounding."""
    rng = np.random.default_rng(7)
    tip = load_fingertip("murakami2006")
    cfg = EstimatorConfig()
    noise = effective_noise(cfg.noise, None)
    r = tip.project(rng.normal(size=(50, 3)) * 0.02 + [0.0, 0.0, 0.02])
    n = tip.normal(r)
    f = -rng.uniform(0.5, 5.0, (50, 1)) * n + rng.normal(scale=0.3, size=(50, 3))
    m = np.cross(r, f) + rng.normal(scale=2e-3, size=(50, 3))
    batch = measure(*f.T, *m.T, *r.T, *n.T, noise, cfg.h_sigmas, cfg.h_min, None, NP)
    for i in range(50):
        one = measure(*f[i].tolist(), *m[i].tolist(), *r[i].tolist(), *n[i].tolist(), noise, cfg.h_sigmas,
                      cfg.h_min, None, PY)  # fmt: skip
        for name in batch._fields:
            b = np.asarray(getattr(batch, name))[i]
            got = getattr(one, name)
            if isinstance(got, bool) or np.asarray(b).dtype == bool:
                assert bool(got) == bool(b), name
            elif not (isinstance(got, float) and math.isnan(got)):
                assert_allclose(got, b, **CLOSE, err_msg=name)
