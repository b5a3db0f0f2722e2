"""The online depth (issue 11): kernel, stage, defaults, simulator truth, CLI."""

import functools
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import simcache
from simcache import simulate_grasp
from softtip import Capsule, EstimatorConfig, Sphere, axial_difference, estimate, murakami2006
from softtip.core._xp import NP
from softtip.core.depth import (
    MURAKAMI2006_DEPTH,
    depth_frame_kernel,
    depth_kernel,
    depth_noise_kernel,
    depth_products,
    depth_solve_kernel,
    skin_depth_law,
)
from softtip.core.fingertip import load_fingertip
from softtip.core.noise import NANO17, SensorNoise
from softtip.core.spin import direction_angle
from softtip.errors import InputError
from softtip.estimator.depth import DEPTH_ITERATIONS, resolve_depth, tip_depth_law
from softtip.sim import ContactModel, ContactParams, Plate, Wedge, discretise_skin, friction_scenario

SOFTTIP = str(Path(sys.executable).with_name("softtip"))
TIP = murakami2006()
PAPERS = EstimatorConfig(depth_compensation="off", line_evidence=False)  # the papers: per sample, on the surface


@functools.cache
def _model():
    # the stiff shear layer of the accuracy benchmark (side walls hold a load across a thin
    # plate); a coarser skin than the benchmark's to keep the tests fast
    return ContactModel(discretise_skin(TIP, 6000), ContactParams(shear_modulus=2e6)).prepare()


@functools.cache
def friction_log(obj_name: str, angle_deg: float, ratio: float, across: bool, profile: str = "push", seed: int = 3):
    obj = {"plate2": Plate(0.002), "wedge90": Wedge(math.pi / 2)}[obj_name]
    scn = friction_scenario(TIP, math.radians(angle_deg), ratio, across=across, profile=profile)
    return simulate_grasp(TIP, obj, scn, rng=seed, model=_model())


def _dir_err(est, log, sel):
    line = sel & (est.state == 2)
    assert line.sum() > 0.8 * sel.sum()
    return np.degrees(np.abs(axial_difference(est.angle[line], log.truth.angle[line])))


# -- kernel -----------------------------------------------------------------------------


def _window(angle, delta, law_force, loads, tilts, noise=None, rng=None):
    """Wrenches of a line contact at the apex whose friction acts at ``delta`` below it."""
    r = np.array([0.0, 0.0, 0.036])
    n = np.array([0.0, 0.0, 1.0])
    d = np.array([math.cos(angle), math.sin(angle), 0.0])
    e = np.cross(n, d)
    k = len(loads)
    ft = loads[:, :1] * e + loads[:, 1:] * d
    f = -law_force * n + ft
    q = tilts[:, None] * e - delta * np.cross(n, ft) + 1e-4 * n  # about r: tilt, friction lever, spin
    m = np.cross(r, f) + q
    w = np.concatenate((f, m), axis=1)
    if noise is not None:
        w = w + rng.normal(size=(k, 6)) * np.r_[noise.force_std, noise.moment_std]
    return w, r, n


def _solve(w, r, n, noise):
    frame = depth_frame_kernel(*r, *n, NP)
    d0 = depth_kernel(-(w[:, :3] @ n), MURAKAMI2006_DEPTH, NP)
    sums = [float(np.sum(p)) for p in depth_products(*w.T, frame, d0)]
    cov = depth_noise_kernel(frame, noise.force_std, noise.moment_std)
    kappa, var = depth_solve_kernel(sums, float(len(w)), cov, 1.0, DEPTH_ITERATIONS, NP)
    return float(kappa), float(var), float(np.mean(d0))


@settings(max_examples=25, deadline=None)
@given(
    angle=st.floats(-1.5, 1.5),
    factor=st.floats(0.3, 2.0),
    amp=st.floats(0.3, 2.0),
    tilt=st.floats(1e-3, 5e-3),
)
def test_noise_free_window_gives_the_depth(angle, factor, amp, tilt):
    # a load across the line that varies while the tilt moment holds: κ identifiable
    fn = 4.9
    delta = factor * MURAKAMI2006_DEPTH.depth(fn)
    s = np.linspace(0.0, 1.0, 50)
    loads = np.stack((amp * s, 0.3 * amp * s * s), axis=1)
    quiet = SensorNoise((1e-9,) * 3, (1e-12,) * 3)
    w, r, n = _window(angle, delta, fn, loads, np.full(50, tilt))
    kappa, var, d0 = _solve(w, r, n, quiet)
    assert kappa * d0 == pytest.approx(delta, rel=1e-8)  # grid start, then Gauss–Newton
    assert var < 0.05  # the model floor (10 %) and little else


def test_a_load_along_the_line_or_none_leaves_the_prior():
    fn = 4.9
    s = np.linspace(0.0, 1.0, 50)
    for loads in (np.stack((0 * s, s), axis=1), np.zeros((50, 2)), np.stack((0.5 + 0 * s, 0 * s), axis=1)):
        w, r, n = _window(0.4, 1e-3, fn, loads, np.full(50, 3e-3))
        kappa, var, _ = _solve(w, r, n, NANO17)
        assert var == math.inf or var > 1.0, loads[-1]


def test_noise_alone_is_not_taken_for_excitation(rng):
    fn = 4.9
    hits = 0
    for _ in range(200):
        w, r, n = _window(0.3, 1e-3, fn, np.full((50, 2), 0.2), np.full(50, 3e-3), NANO17, rng)
        _, var, _ = _solve(w, r, n, NANO17)
        hits += var < 1.0
    assert hits <= 4  # the 3 σ margin of the joint fit: about 0.1 % per window


def test_noisy_windows_scatter_within_the_reported_std(rng):
    fn, delta = 4.9, 1.2e-3
    s = np.linspace(0.0, 1.0, 50)
    loads = np.stack((0.8 * s, 0 * s), axis=1)
    got, stds = [], []
    for _ in range(200):
        w, r, n = _window(-0.7, delta, fn, loads, np.full(50, 3e-3), NANO17, rng)
        kappa, var, d0 = _solve(w, r, n, NANO17)
        got.append(kappa * d0)
        stds.append(math.sqrt(var) * d0)
    err = np.abs(np.array(got) - delta)
    assert np.mean(err <= np.array(stds)) >= 0.68  # the std is not optimistic
    assert np.median(err) < 0.1 * delta


# -- defaults ---------------------------------------------------------------------------


def test_default_is_online_for_a_skin_and_off_without_one():
    assert resolve_depth(EstimatorConfig(), TIP).depth_compensation == "online"
    assert resolve_depth(EstimatorConfig(), TIP).skin_law == MURAKAMI2006_DEPTH
    assert resolve_depth(EstimatorConfig(), Capsule(0.016, 0.02)).depth_compensation == "off"
    assert resolve_depth(EstimatorConfig(contact_point="track"), TIP).depth_compensation == "off"
    assert resolve_depth(EstimatorConfig(contact_point="line-fit"), TIP).depth_compensation == "off"
    given = EstimatorConfig(contact_point="line-fit", skin_law=MURAKAMI2006_DEPTH)
    assert resolve_depth(given, TIP).depth_compensation == "law"  # a law given in line-fit mode: as before, fixed
    assert resolve_depth(EstimatorConfig(contact_point="line-fit", depth_compensation="online"), TIP).depth_compensation == "online"
    assert resolve_depth(EstimatorConfig(depth_compensation="off"), TIP).skin_law is None
    assert resolve_depth(EstimatorConfig(depth_compensation="law"), TIP).depth_compensation == "law"
    with pytest.raises(ValueError, match="skin law"):
        resolve_depth(EstimatorConfig(depth_compensation="online"), Sphere(0.02))
    with pytest.raises(ValueError, match="depth_compensation"):
        EstimatorConfig(depth_compensation="deep")
    with pytest.raises(ValueError, match="depth_prior_std"):
        EstimatorConfig(depth_prior_std=0.0)


def test_fingertip_file_with_a_skin_thickness(tmp_path):
    p = tmp_path / "tip.toml"
    p.write_text('[fingertip]\nshape = "sphere"\nradius = 0.02\nskin_thickness = 0.003\n')
    tip = load_fingertip(p)
    assert tip.skin_thickness == 0.003
    assert tip_depth_law(tip) == skin_depth_law(0.003)
    assert tip_depth_law(tip).max_depth == 0.003
    assert load_fingertip(tmp_path / "tip.toml") == Sphere(0.02)  # geometry equality ignores the skin
    assert "skin_thickness = 0.003" in tip.to_toml()
    assert tip_depth_law(TIP) == MURAKAMI2006_DEPTH
    p.write_text('[fingertip]\nshape = "sphere"\nradius = 0.02\nskin_thickness = -1\n')
    with pytest.raises(InputError, match="skin_thickness"):
        load_fingertip(p)


# -- simulator --------------------------------------------------------------------------


def test_simulator_records_where_friction_acts():
    log = friction_log("plate2", 30.0, 0.5, True)
    fd = log.truth.friction_depth
    assert np.all(np.isnan(fd[log.t < 1.9]))  # no contact yet
    held = log.t > 7.0
    # the 2 mm plate sinks ~1.5 mm at 0.5 kgf; friction acts a little above its deepest point
    assert np.all((fd[held] > 0.6e-3) & (fd[held] < log.truth.depth[held]))
    assert "friction_depth_m" in log.truth.as_dict()
    with pytest.raises(ValueError, match="profile"):
        friction_scenario(TIP, 0.0, 0.2, profile="shake")


# -- the estimator on friction grasps -----------------------------------------------------


def _oracle_err(est, log, sel):
    """Direction error with the simulator's true friction depth (not available to softtip)."""
    r, n, w = est.point, est.normal, est.wrench
    re = r - log.truth.friction_depth[:, None] * n
    q = w[:, 3:] - np.cross(re, w[:, :3])
    h = q - np.sum(q * n, -1, keepdims=True) * n
    d = np.cross(n, h)
    ang = np.degrees(np.abs(axial_difference(direction_angle(d, n)[sel], log.truth.angle[sel])))
    return ang


@pytest.mark.parametrize("angle", [30.0, -45.0])
def test_online_depth_on_a_push_across_the_plate(angle):
    log = friction_log("plate2", angle, 0.5, True)
    held = log.t > 7.0
    papers = estimate(log.t, log.wrench, TIP, PAPERS)
    online = estimate(log.t, log.wrench, TIP)
    assert np.median(_dir_err(papers, log, held)) > 20.0  # friction at depth turns the papers' direction
    err = np.median(_dir_err(online, log, held))
    # as good as knowing the true depth (at ±45° the simulated strip's own rolling
    # resistance biases every method by a few degrees, see the README)
    assert err < max(4.0, np.median(_oracle_err(papers, log, held)) + 1.5)
    assert online.depth_from_data[held].mean() > 0.9
    within = np.abs(online.depth[held] - log.truth.friction_depth[held]) <= online.depth_std[held]
    assert within.mean() > 0.8


def test_online_depth_on_a_wedge_loaded_along_its_edge_keeps_the_prior():
    log = friction_log("wedge90", 0.0, 0.5, False)
    held = log.t > 7.0
    online = estimate(log.t, log.wrench, TIP)
    assert online.depth_from_data[held].mean() < 0.5
    assert np.median(_dir_err(online, log, held)) < 4.0
    err = np.abs(online.depth[held] - log.truth.friction_depth[held])
    assert np.mean(err <= online.depth_std[held]) > 0.8


def test_without_tangential_load_the_default_equals_the_papers_method():
    scn = friction_scenario(TIP, math.radians(20.0), 0.0, across=True)
    log = simulate_grasp(TIP, Plate(0.001), scn, rng=5, model=_model())
    held = log.t > 6.0
    papers = estimate(log.t, log.wrench, TIP, PAPERS)
    online = estimate(log.t, log.wrench, TIP)
    assert (papers.state == online.state).mean() > 0.99
    both = held & (papers.state == 2) & (online.state == 2)
    diff = np.degrees(np.abs(axial_difference(papers.angle[both], online.angle[both])))
    assert np.median(diff) < 0.3
    assert np.max(np.linalg.norm(papers.point[both] - online.point[both], axis=1)) == 0.0


def test_the_priors_uncertainty_is_in_h_std(rng):
    """A point pushed by a rigid object with friction at the surface (hand-made data: no depth
    at all): while the depth is the skin law's, ± its standard deviation, the moment it adds
    (0.9 mm × 1 N) is within h's uncertainty and the contact reads `point`, as with the depth
    compensation off; h_std is the noise's and the depth's, ``sqrt(h_std₀² + δ_std² |n × f|²)``."""
    fs = 1000.0
    t = np.arange(int(3.0 * fs)) / fs
    th, ph = math.radians(30.0), math.radians(60.0)
    r = np.array([0.0, 0.0, 0.020]) + 0.016 * np.array([math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)])
    s = np.clip((t - 0.3) / 1.0, 0.0, 1.0)
    f = np.zeros((len(t), 3))
    f[:, 2] = -2.0 * s * s * (3 - 2 * s)  # straight down: 1 N along the skin at the point, 30° off its normal
    w = np.hstack((f, np.cross(r, f))) + rng.normal(scale=[*NANO17.force_std, *NANO17.moment_std], size=(len(t), 6))
    est = estimate(t, w, TIP, EstimatorConfig(noise_from_tare="off"))  # the model as given, for the identity below
    prior = (est.state != 0) & ~est.depth_from_data & (est.depth > 0.5e-3)
    assert prior.sum() > 300  # the law's depth (up to 0.9 mm) with its std, for the rest of the ramp and after
    assert not np.any(est.state == 2), np.unique(est.state, return_counts=True)
    off = estimate(t, w, TIP, EstimatorConfig(depth_compensation="off"))
    assert not np.any(off.state == 2)
    # the depth's part of h_std, to rounding: the noise's h_std at the same point (depth_std 0)
    from softtip.estimator.measure import measure

    i = np.flatnonzero(prior)
    e = est.point[i] - est.depth[i, None] * est.normal[i]
    x = est.wrench[i]
    base = measure(*x.T, *e.T, *est.normal[i].T, NANO17, 3.0, 5e-4, None, NP).h_std
    ft2 = np.sum(np.cross(est.normal[i], x[:, :3]) ** 2, axis=1)
    np.testing.assert_allclose(est.h_std[i] ** 2, base**2 + est.depth_std[i] ** 2 * ft2, rtol=1e-9)
    assert np.median(est.h_std[i] / base) > 1.5


# -- CLI --------------------------------------------------------------------------------


def _cli(*args):
    return subprocess.run([SOFTTIP, "estimate", "--example", *args], capture_output=True, text=True)


def _last_row(out: str) -> dict:
    lines = out.strip().splitlines()
    return dict(zip(lines[0].split(","), lines[-1].split(",")))


def test_cli_depth_options():
    default, papers, fixed = _cli(), _cli("--depth-compensation", "off"), _cli("--depth-compensation", "law")
    for r in (default, papers, fixed):
        assert r.returncode == 0, r.stderr
    d, p, f = _last_row(default.stdout), _last_row(papers.stdout), _last_row(fixed.stdout)
    assert float(p["depth"]) == 0.0 and float(p["depth_std"]) == 0.0
    assert float(f["depth"]) > 0.0 and float(f["depth_std"]) == 0.0
    assert float(d["depth_std"]) > 0.0 and d["depth_from_data"] in ("0", "1")
    bad = _cli("--depth-compensation", "fixed")
    assert bad.returncode == 2 and "'fixed'" in bad.stderr and "online" in bad.stderr and not bad.stdout


def test_cli_simulates_a_friction_grasp_with_its_truth(tmp_path):
    import json

    out = tmp_path / "fr.csv"
    r = subprocess.run(
        [SOFTTIP, "simulate", "--scenario", "friction", "--object", "plate", "--size",
         "2mm", "--angle", "30", "--load", "0.4", "--elements", "2500", "--shear-modulus", "2e6", "-o", str(out)],
        capture_output=True, text=True, env=simcache.subprocess_env(),
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    truth = json.loads((tmp_path / "fr.truth.json").read_text())
    assert truth["scenario"]["name"] == "friction-push"
    fd = [v for v in truth["samples"]["friction_depth_m"] if v is not None]
    assert 0.5e-3 < fd[-1] < 2.5e-3
    est = subprocess.run([SOFTTIP, "estimate", str(out)], capture_output=True, text=True)
    assert est.returncode == 0, est.stderr
    last = _last_row(est.stdout)
    assert last["state"] == "line" and last["depth_from_data"] == "1"
    assert abs(float(last["depth"]) - fd[-1]) < 3 * float(last["depth_std"])
    # a load the soft layer of the other scenarios (E / 3) cannot hold across a wedge: a clear
    # error, no files
    bad = subprocess.run(
        [SOFTTIP, "simulate", "--scenario", "friction", "--object", "wedge", "--load", "0.5", "--elements", "2500",
         "--shear-modulus", "2e5", "-o", str(tmp_path / "bad.csv")],
        capture_output=True, text=True, env=simcache.subprocess_env(),
    )  # fmt: skip
    assert bad.returncode == 2 and "cannot be held" in bad.stderr
    assert not (tmp_path / "bad.csv").exists() and not (tmp_path / "bad.truth.json").exists()
    # the manual's example with the scenario's own defaults (its shear layer 2 MPa) holds
    ok = subprocess.run([SOFTTIP, "simulate", "--scenario", "friction", "--elements", "2500", "-o", str(tmp_path / "ok.csv")],
                        capture_output=True, text=True, env=simcache.subprocess_env())  # fmt: skip
    assert ok.returncode == 0, ok.stderr
    assert json.loads((tmp_path / "ok.truth.json").read_text())["skin"]["shear_modulus_pa"] == 2e6

