"""A constant shift of every time stamp changes no estimate: a sample exactly on a time window's
edge (evenly spaced stamps put samples there) is on the edge whatever the rounding of ``t − W``
(:data:`softtip.core._blocks.TIME_EDGE`)."""

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from softtip import EstimatorConfig, estimate, load_example
from softtip.estimator.results import EstimatorWarning

CONFIGS = {  # by the stamps' shift (a stated rocking is in the log's own time)
    "default": lambda shift: EstimatorConfig(),
    "line-fit": lambda shift: EstimatorConfig(contact_point="line-fit"),
    "low-pass, re-latch, stated rocking": lambda shift: EstimatorConfig(
        lowpass_hz=10.0, relatch_distance=0.5e-3, rocked=((6.0 + shift, 9.0 + shift),)),
}


def _estimate(t, cfg):
    log = load_example()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", EstimatorWarning)
        return estimate(t, log.wrench, "murakami2006", cfg)


def _assert_same(a, b):
    assert np.array_equal(a.state, b.state)
    ca, cb = a.columns(), b.columns()
    for name, tol in (("angle_deg", 1e-6), ("angle_std_deg", 1e-6), ("depth", 1e-12), ("h_norm", 1e-12), ("rx", 1e-12)):
        np.testing.assert_allclose(np.asarray(cb[name], float), np.asarray(ca[name], float), rtol=0, atol=tol,
                                   equal_nan=True, err_msg=name)  # fmt: skip


@pytest.mark.parametrize("name", list(CONFIGS))
@settings(max_examples=8, deadline=None)
@given(shift=st.sampled_from([3.3, 1000.0, -2.0, 0.7, 123.456]) | st.floats(-1e4, 1e4, allow_nan=False))
def test_a_constant_shift_of_the_stamps_changes_no_estimate(name, shift):
    # before: +3.3 s moved the example's angles by up to 1.6° and their std by 2.3°
    t = load_example().t
    _assert_same(_estimate(t, CONFIGS[name](0.0)), _estimate(t + shift, CONFIGS[name](shift)))


def test_stamps_a_rounding_apart_give_the_same_estimates():
    # before: scaling by 1 + 1e-15 turned one sample from line to point and an angle by 10°
    t = load_example().t
    _assert_same(_estimate(t, EstimatorConfig()), _estimate(t * (1 + 1e-15), EstimatorConfig()))
