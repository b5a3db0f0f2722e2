"""The simulator's per-sample force solve: a force with a jump or cross-coupled stiffness
converges, a load the contact cannot hold still raises, and the rocked grasp that used to
fail on a jump of the force simulates."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

from softtip.core.fingertip import murakami2006
from softtip.sim import ContactModel, ContactParams, Plate, discretise_skin, rock_scenario, simulate_grasp
from softtip.sim.pose import Pose
from softtip.sim.simulate import _FTOL, _FTOL_JUMP, _Sample

AREA = 4.3e-5  # m²: contact area the synthetic contacts report (a rocked 3 mm plate's)


class _Synthetic:
    """Stands in for ContactModel: force along (u, t1, t2) = ``law(x)``, x the offset."""

    params = ContactParams()

    def __init__(self, law):
        self.law = law

    def evaluate(self, obj, pose, state, candidates):
        return SimpleNamespace(force=self.law(pose.translation), contact_area=AREA, area=np.array([AREA]),
                               slip=np.array([False]))


def _sample(law):
    return _Sample(_Synthetic(law), None, Pose.identity(), None, lambda pose: None, np.eye(3))


# the diagonal stiffness the solve assumes: E/h × area along the push, G/h × area across
KN = ContactParams().normal_stiffness * AREA
KT = ContactParams().tangential_stiffness * AREA
XS = np.array([1.4e-3, -3e-5, 2e-5])  # m


def test_a_root_inside_a_jump_of_the_force_is_accepted_within_the_jump():
    # the rocked 3 mm plate at 60°: a quadrature point's coverage switches, the force jumps
    # by ≈ 8e-5 N right where the target lies, and no offset meets the 2e-5 N tolerance
    # (the diagonal steps cycled across the jump until the solve gave up)
    jump = np.array([6.9e-5, 3.1e-5, -3.7e-5])
    k = np.diag([KN, 1.2 * KT, 1.2 * KT])
    law = lambda x: k @ (x - XS) + jump * (x[0] > XS[0])  # noqa: E731
    target = 0.5 * jump
    x, res = _sample(law).solve(XS + [2e-5, 1e-6, -1e-6], target, 3)
    r = res.force - target
    assert np.abs(r).max() > _FTOL  # really inside the jump
    assert np.abs(r).max() <= np.abs(jump).max()  # and not farther than the jump
    assert abs(x[0] - XS[0]) < 1e-9


def test_a_jump_larger_than_the_accepted_residual_still_fails():
    jump = np.array([20.0 * _FTOL_JUMP, 0.0, 0.0])
    law = lambda x: np.diag([KN, KT, KT]) @ (x - XS) + jump * (x[0] > XS[0])  # noqa: E731
    with pytest.raises(RuntimeError, match="did not converge"):
        _sample(law).solve(XS + [2e-5, 0.0, 0.0], 0.5 * jump, 3)


def test_coupled_stiffness_far_from_the_diagonal_estimate_converges():
    # across the push the true stiffness is 2.5× G/h × area and pushing deeper pushes
    # sideways: the diagonal steps alone overshoot and diverge
    k = np.array([[KN, 0.3 * KN, 0.0], [0.4 * KN, 2.5 * KT, 0.0], [0.0, 0.0, 2.5 * KT]])
    target = np.array([4.9, -0.02, 0.01])
    x, res = _sample(lambda x: k @ x).solve(np.zeros(3), target, 3)
    assert np.all(np.abs(res.force - target) <= _FTOL)
    np.testing.assert_allclose(x, np.linalg.solve(k, target), rtol=0, atol=1e-8)


def test_a_tangential_load_the_contact_cannot_hold_still_fails():
    # the tangential force saturates at 0.5 N (a sliding contact): a 0.8 N load has no equilibrium
    law = lambda x: np.array([KN * x[0], 0.5 * math.tanh(KT * x[1] / 0.5), KT * x[2]])  # noqa: E731
    with pytest.raises(RuntimeError, match="cannot be held"):
        _sample(law).solve(np.zeros(3), np.array([4.9, 0.8, 0.0]), 3)


@pytest.mark.slow
def test_the_rocked_3mm_plate_at_60_degrees_simulates():
    # `softtip simulate --object plate --size 3mm --angle 60 --rock` failed at 8.28 s (the
    # second rocking axis) on a jump of the contact force; the run up to 8.4 s reaches it
    tip = murakami2006()
    model = ContactModel(discretise_skin(tip))
    log = simulate_grasp(tip, Plate(0.003), rock_scenario(math.radians(60), duration=8.4), model=model)
    tr = log.truth
    assert log.t[-1] > 8.28
    assert np.abs(tr.normal_force - tr.force_target).max() < _FTOL_JUMP
    assert np.all(tr.in_contact[log.t >= 2.1])
