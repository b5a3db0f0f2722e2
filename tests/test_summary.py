"""Per-contact summaries."""

import math

import numpy as np
import pytest

import softtip
from softtip.summary import format_summary, summarise_contacts
from softtip.synthetic import synthetic_grasp


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


def test_no_contact():
    t = np.arange(100) / 50.0
    est = softtip.estimate(t, np.zeros((100, 6)))
    assert summarise_contacts(est) == []
    assert format_summary([]) == ["no contact"]
