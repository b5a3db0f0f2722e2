"""Simulated grasps (SPEC §5 scenarios), the log/truth writers and the simulate command."""

import csv
import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

from softtip.cli.simulate import simulate
from softtip.core.fingertip import murakami2006
from softtip.core.units import parse_force, parse_length
from softtip.sim import (
    ContactModel,
    HandFrame,
    Plate,
    SensorModel,
    Wedge,
    discretise_skin,
    paper_scenario,
    push_scenario,
    simulate_grasp,
    write_log_csv,
    write_truth_json,
)

TIP = murakami2006()


@pytest.fixture(scope="module")
def model():
    return ContactModel(discretise_skin(TIP))


def tangential_spin(log, i):
    """h and the measured direction from the true wrench with the nominal contact point."""
    w = log.wrench_true[i]
    r, n = log.truth.contact_point[i], log.truth.contact_normal[i]
    q = w[3:] - np.cross(r, w[:3])
    h = q - (q @ n) * n
    d = np.cross(n, h)
    return h, d / np.linalg.norm(d), n


def axial_error_deg(a, b):
    return abs((a - b + 90.0) % 180.0 - 90.0)


@pytest.fixture(scope="module")
def plate_logs(model):
    return {a: simulate_grasp(TIP, Plate(0.001), paper_scenario(math.radians(a)), rng=7, model=model) for a in (0, 45, 90)}


def test_grasp_follows_the_papers_time_line(plate_logs):
    log = plate_logs[45]
    tr = log.truth
    assert log.t.shape == (500,) and log.wrench.shape == (500, 6)
    assert np.all(np.diff(log.t) == pytest.approx(0.02))
    first = np.argmax(tr.in_contact)
    assert 1.98 <= log.t[first] <= 2.1
    assert np.all(log.wrench_true[: first - 1] == 0.0)
    assert np.abs(tr.normal_force - tr.force_target).max() < 1e-4
    assert tr.normal_force[-1] == pytest.approx(0.5 * 9.80665, abs=1e-4)  # solver tolerance 2e-5 N
    assert np.all(tr.force_target[log.t >= 4.0] == pytest.approx(0.5 * 9.80665))
    assert np.all(log.wrench_true[tr.in_contact, :3] @ tr.contact_normal[0] < 0.0)  # pushes in
    assert 1e-3 < tr.depth[-1] < 4e-3
    # the pressure centre stays near the nominal contact point; the contact is a strip
    assert np.linalg.norm(tr.pressure_centre[-1] - tr.contact_point[-1]) < 1e-3
    assert 5e-6 < tr.contact_area[-1] < 5e-5
    # the object tangential load (half of 10 g) is carried
    hand = HandFrame.paper()
    assert log.wrench_true[-1, :3] @ hand.gravity == pytest.approx(0.5 * 0.01 * 9.80665, abs=1e-4)


@pytest.mark.parametrize("angle", [0, 45])
def test_thin_plate_direction_is_measurable(plate_logs, angle):
    # measured as the papers do: about the contact point latched at light force (the
    # object's weight already shifts the strip there; the nominal point ignores that)
    from softtip import axial_difference, estimate

    log = plate_logs[angle]
    h, _, _ = tangential_spin(log, -1)
    assert np.linalg.norm(h) > 1e-3  # > 1 N·mm
    est = estimate(log.t, log.wrench, TIP)
    held = (log.t >= 6.0) & (est.state == 2)
    assert held.sum() > 150
    err = np.degrees(np.abs(axial_difference(est.angle[held], log.truth.angle[held])))
    # about ±1° of this is the skin's discretisation (README, reproduction)
    assert np.median(err) < 4.0
    assert abs(log.truth.angle_deg[-1] - angle) < 2.0  # the gravity spin turns the plate ~1°


def test_plate_along_the_joint_axes_has_no_tangential_spin_torque(plate_logs):
    # the paper's 90° case: nothing rotates the object about an axis in the hand x–z plane
    log = plate_logs[90]
    h, _, _ = tangential_spin(log, -1)
    h0, _, _ = tangential_spin(plate_logs[0], -1)
    assert np.linalg.norm(h) < 0.5e-3  # below h_min = 0.5 N·mm
    assert np.linalg.norm(h) < 0.15 * np.linalg.norm(h0)
    hand = HandFrame.paper()
    for dist in log.scenario.disturbances:
        if dist.axis is not None:
            assert abs(np.dot(dist.axis, hand.up)) < 1e-12


def test_misalignment_makes_the_90_degree_plate_observable(model):
    log = simulate_grasp(TIP, Plate(0.001), paper_scenario(math.radians(90), misalignment=math.radians(15)),
                         SensorModel.ideal(), model=model)
    h, _, _ = tangential_spin(log, -1)
    assert np.linalg.norm(h) > 0.5e-3


def test_sensor_output_is_the_truth_plus_noise(plate_logs):
    log = plate_logs[0]
    diff = log.wrench - log.wrench_true
    assert np.all(np.abs(diff[:, :3]) < 0.03) and np.all(np.abs(diff[:, 3:]) < 2e-4)
    again = simulate_grasp(TIP, Plate(0.001), paper_scenario(0.0), rng=7, model=ContactModel(discretise_skin(TIP)))
    assert np.array_equal(again.wrench, log.wrench)


def test_push_scenario_without_disturbance_has_no_tangential_spin(model):
    scn = push_scenario(math.radians(30), duration=5.0)
    log = simulate_grasp(TIP, Wedge(), scn, SensorModel.ideal(), model=model)
    h, _, _ = tangential_spin(log, -1)
    assert np.linalg.norm(h) < 1e-4
    assert log.truth.angle_deg[-1] == pytest.approx(30.0)


def test_writers(plate_logs, tmp_path):
    log = plate_logs[45]
    write_log_csv(log, tmp_path / "log.csv")
    with (tmp_path / "log.csv").open() as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["t", "fx", "fy", "fz", "mx", "my", "mz"]
    data = np.array(rows[1:], dtype=float)
    assert data.shape == (500, 7)
    np.testing.assert_allclose(data[:, 1:], log.wrench, rtol=1e-9, atol=1e-12)
    write_truth_json(log, tmp_path / "truth.json")
    truth = json.loads((tmp_path / "truth.json").read_text())
    assert truth["object"]["kind"] == "plate" and truth["object"]["thickness_m"] == 0.001
    s = truth["samples"]
    assert len(s["t_s"]) == 500 and s["angle_deg"][-1] == pytest.approx(log.truth.angle_deg[-1])
    assert s["pressure_centre_m"][0] == [None, None, None]  # NaN before contact
    assert truth["scenario"]["hand"]["gravity"] == pytest.approx([-1.0, 0.0, 0.0])


def test_parse_units():
    assert parse_length("2mm") == pytest.approx(0.002)
    assert parse_length("0.5 cm") == pytest.approx(0.005)
    assert parse_length("0.003") == 0.003
    assert parse_force("0.5kgf") == pytest.approx(4.903325)
    with pytest.raises(ValueError):
        parse_length("2 inches")


def test_simulate_command(tmp_path):
    out = tmp_path / "log.csv"
    runner = CliRunner()
    res = runner.invoke(simulate, ["--object", "plate", "--size", "2mm", "--angle", "45", "--duration", "3",
                                   "--elements", "3000", "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert out.exists() and (tmp_path / "log.truth.json").exists()
    assert out.read_text().splitlines()[0] == "t,fx,fy,fz,mx,my,mz"
    bad = runner.invoke(simulate, ["--size", "2 parsecs", "-o", str(tmp_path / "x.csv")])
    assert bad.exit_code == 2
    assert not (tmp_path / "x.csv").exists()
    missing = runner.invoke(simulate, ["--tip", "nosuchtip", "--duration", "3", "-o", str(tmp_path / "y.csv")])
    assert missing.exit_code == 2
    assert not (tmp_path / "y.csv").exists()


def test_paper_scenario_disturbances_wait_for_the_grasp():
    # the papers' procedure: the object is kept still while the fingers close and the
    # grasp force builds; the joint and gravity moments come in afterwards
    scn = paper_scenario(math.radians(45))
    r_c = np.array([0.0, 0.0, 0.036])
    for t in (0.0, 2.0, 3.0, 4.0):
        pose = scn.disturbance_pose(t, r_c)
        assert np.allclose(pose.rotation, np.eye(3)) and np.allclose(pose.translation, 0.0)
    full = scn.disturbance_pose(scn.duration, r_c)
    assert not np.allclose(full.rotation, np.eye(3))
    for d in scn.disturbances:
        assert d.start == scn.t_stable and d.end > d.start and d.end <= scn.duration - 2.0
    old = paper_scenario(0.0, disturbance_timing="during_rise")
    assert all(d.start == old.t_contact and d.end == old.t_stable for d in old.disturbances)
    own = paper_scenario(0.0, disturbance_start=5.0, disturbance_end=6.0, t_stable=3.0)
    assert all(d.start == 5.0 and d.end == 6.0 for d in own.disturbances)
    with pytest.raises(ValueError):
        paper_scenario(0.0, disturbance_timing="sometime")
    with pytest.raises(ValueError):
        paper_scenario(0.0, disturbance_start=6.0, disturbance_end=5.0)


def test_light_force_contact_is_measured_before_the_disturbances(plate_logs):
    # up to t_stable only the push acts: the pressure centre stays on the nominal point,
    # so the latch (0.2-0.5 kgf during the first rise) sees the undisturbed contact
    log = plate_logs[45]
    rise = np.flatnonzero(log.truth.in_contact & (log.t <= 4.0))
    for i in rise:
        h, _, _ = tangential_spin(log, i)
        assert np.linalg.norm(h) < 0.4e-3
    h, _, _ = tangential_spin(log, -1)
    assert np.linalg.norm(h) > 2.5e-3


def test_default_spin_torque_is_of_the_papers_order(plate_logs):
    # Figs. 8-10: |h| of 0.3-1 kgf·mm at 0.5 kgf for the thin plate at 0° and ±45°
    for angle in (0, 45):
        h, _, _ = tangential_spin(plate_logs[angle], -1)
        assert 2.5e-3 < np.linalg.norm(h) < 10e-3


def test_a_bare_size_above_10_cm_needs_a_unit():
    out = CliRunner().invoke(simulate, ["--object", "plate", "--size", "2", "-o", "x.csv"])
    assert out.exit_code == 2 and "give a unit" in out.output
