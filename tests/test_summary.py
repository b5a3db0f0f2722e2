"""Per-contact summaries."""

import dataclasses
import math

import numpy as np
import pytest

import softtip
from softtip.estimator.summary import format_summary, summarise_contacts
from softtip.sim.synthetic import synthetic_grasp


def test_two_grasps_are_two_contacts_with_their_own_directions():
    g1 = synthetic_grasp(angle_deg=-45.0, duration=7.0, seed=3)
    g2 = synthetic_grasp(angle_deg=45.0, duration=7.0, seed=4)
    t = np.concatenate((g1.t, g2.t + 7.0))
    w = np.concatenate((g1.wrench, g2.wrench))
    est = softtip.estimate(t, w)
    contacts = summarise_contacts(est)
    assert len(contacts) == 2
    assert math.degrees(contacts[0].direction) == pytest.approx(-45.0, abs=3.0)
    assert math.degrees(contacts[1].direction) == pytest.approx(45.0, abs=3.0)
    for c in contacts:
        assert 1.9 < c.start - (0.0 if c.index == 1 else 7.0) < 2.5
        assert c.peak_force > 5.0 and c.latched
        assert abs(sum(c.shares.values()) - 1.0) < 1e-12
        assert np.linalg.norm(np.array(c.point) - g1.point) < 1e-3
    lines = format_summary(contacts)
    assert lines[0].startswith("contact 1: ") and "direction -4" in lines[0]
    assert lines[1].startswith("contact 2: ") and "direction +4" in lines[1]


def test_a_contact_without_a_located_sample_lists_no_shares():
    # a pull (no pushing contact point): every sample `none`, no share, no point
    g = synthetic_grasp(angle_deg=45.0, seed=1)
    c = summarise_contacts(softtip.estimate(g.t, g.wrench))[0]
    pulled = dataclasses.replace(c, shares=dict.fromkeys(c.shares, 0.0), point=(math.nan,) * 3)
    line = format_summary([pulled])[0]
    assert line.startswith("contact 1: ") and " N; no point; " in line and ", ;" not in line


def test_no_contact():
    t = np.arange(100) / 50.0
    est = softtip.estimate(t, np.zeros((100, 6)))
    assert summarise_contacts(est) == []
    assert format_summary([]) == ["no contact"]


def test_the_command_prints_a_summary_per_contact_on_standard_error_unless_quiet(tmp_path):
    import subprocess
    import sys
    from pathlib import Path

    softtip_cmd = str(Path(sys.executable).with_name("softtip"))
    g1 = synthetic_grasp(angle_deg=-45.0, duration=7.0, seed=3)
    g2 = synthetic_grasp(angle_deg=45.0, duration=7.0, seed=4)
    t = np.concatenate((g1.t, g2.t + 7.0))
    w = np.concatenate((g1.wrench, g2.wrench))
    np.savetxt(tmp_path / "log.csv", np.c_[t, w], delimiter=",", header="t,fx,fy,fz,mx,my,mz", comments="", fmt="%.12g")
    r = subprocess.run([softtip_cmd, "estimate", tmp_path / "log.csv"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and r.stdout.startswith("t,")  # estimates on stdout, the summary on stderr
    assert "contact 1:" in r.stderr and "direction -4" in r.stderr
    assert "contact 2:" in r.stderr and "direction +4" in r.stderr
    assert "-> standard output" in r.stderr
    q = subprocess.run([softtip_cmd, "estimate", tmp_path / "log.csv", "-q"], capture_output=True, text=True, timeout=120)
    assert q.returncode == 0 and "contact 1:" not in q.stderr and q.stdout == r.stdout
    assert "bias from the first" in r.stderr and q.stderr == ""  # quiet: not the tare's line either
