"""Reproduction outcomes on the simulator (SPEC §5): the conditions the papers report on.

Each test simulates its grasps (about a second each) and measures them with the default
pipeline. Tolerances: "measured" means the direction is reported on at least half of the held
samples with the median axial error stated per test; "not measured" means large error
(> 10°) or unobservable (reported on fewer than half).
"""

import pytest

import simcache
import softtip.sim
from softtip.apps.reproduce import (
    LARGE_ERROR_DEG,
    POSITION_BOUND,
    Condition,
    conditions,
    run_condition,
    run_reproduction,
)


@pytest.fixture(scope="module", autouse=True)
def _shared_grasps():
    # the conditions simulate through softtip.sim.simulate_grasp: from the session's cache
    # (tests/simcache.py), as other files simulate some of the same grasps
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(softtip.sim, "simulate_grasp", simcache.simulate_grasp)
        yield


def cond(exp, kind, size, angle, **kw):
    return Condition(exp, kind, size, angle, None, "", **kw)


def test_ninety_degree_plate_is_unobservable():
    r = run_condition(cond("E2", "plate", 1e-3, 90.0))
    assert r.outcome == "unobservable"
    assert r.share_reported < 0.1


@pytest.mark.parametrize("kind,size", [("plate", 1e-3), ("plate", 2e-3), ("cylinder", 4e-3), ("wedge", None)])
def test_thin_objects_at_zero_degrees_within_the_spec_target(kind, size):
    r = run_condition(cond("E3", kind, size, 0.0))
    assert r.share_reported > 0.9
    assert r.median_error_deg <= 3.0


@pytest.mark.parametrize("size", [1e-3, 2e-3])
@pytest.mark.parametrize("angle", [-45.0, 45.0])
def test_thin_plates_at_45_degrees_near_the_spec_target(size, angle):
    # 0.9–3.0° here (target 3°); the simulator's discretisation alone moves the 1 mm
    # plate at +45° between 2.5° and 4.1° from 10 000 to 48 000 skin elements, so the test
    # allows 4°
    r = run_condition(cond("E3", "plate", size, angle))
    assert r.share_reported > 0.9
    assert r.median_error_deg <= 4.0


@pytest.mark.parametrize("kind,size", [("wedge", None), ("cylinder", 4e-3)])
def test_edges_and_thin_cylinders_at_45_degrees_within_10_degrees(kind, size):
    # a 90° edge and a Ø 4 mm stick resist rolling about their own axis in the simulated
    # skin, which biases ±45° by 5–8° (README, reproduction): not the 3° target
    r = run_condition(cond("E3", kind, size, 45.0))
    assert r.share_reported > 0.9
    assert r.median_error_deg <= LARGE_ERROR_DEG


@pytest.mark.parametrize("kind,size", [("plate", 10e-3), ("plate", 15e-3), ("cylinder", 14e-3)])
def test_thick_objects_at_45_degrees_show_large_error(kind, size):
    r = run_condition(cond("E3", kind, size, 45.0))
    assert r.outcome in ("large error", "unobservable")


def test_sharpness_does_not_matter():
    errs = [run_condition(cond("E1", "wedge", None, 45.0, edge_radius=rad)).median_error_deg for rad in (0.0, 1e-3)]
    assert abs(errs[0] - errs[1]) < 1.5


def test_contact_position_within_half_a_millimetre_above_02_kgf():
    for c in conditions(["E6"])[:2]:
        r = run_condition(c)
        assert r.agrees and r.contact_error < POSITION_BOUND


def test_latched_point_of_a_line_contact_is_within_half_a_millimetre():
    r = run_condition(cond("E2", "plate", 1e-3, 45.0))
    assert r.contact_error < POSITION_BOUND


def test_report_files(tmp_path):
    results = run_reproduction(tmp_path, experiments=["E6"])
    assert len(results) == 4
    assert sorted(p.name for p in tmp_path.iterdir()) == ["e6_contact_position.png", "summary.csv", "summary.md"]
    text = (tmp_path / "summary.md").read_text()
    assert "E6" in text and "Agreement with the published outcomes: 4 of 4" in text


def test_experiment_selection():
    assert {c.experiment for c in conditions(["e2"])} == {"E2"}
    with pytest.raises(ValueError, match="E7"):
        conditions(["E7"])
    assert len(conditions()) == len({(c.experiment, c.variant, c.angle_deg) for c in conditions()})


def test_papers_lines_stay_lines_now_unconfirmed():
    # one axis of excitation (the papers' grasp): published outcome kept, evidence unconfirmed
    r = run_condition(cond("E2", "plate", 1e-3, 45.0))
    assert r.outcome == "measured"
    assert r.confirmed_share == 0.0 and r.area_share == 0.0


def test_extension_x1_is_judged_line_or_area():
    xs = conditions(["X1"])
    assert {c.kind for c in xs if c.expect_measured} == {"plate", "cylinder"}
    assert {c.kind for c in xs if c.expect_measured is False} == {"plate", "plane"}
    assert all(c.size is None or c.size >= 10e-3 for c in xs if c.expect_measured is False)
    from softtip.apps.reproduce import _measured

    assert _measured(True, "line") and not _measured(True, "area") and not _measured(True, "line, biased")
    assert _measured(False, "area") and not _measured(False, "line") and not _measured(False, "neither")
