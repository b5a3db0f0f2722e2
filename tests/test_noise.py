import numpy as np
import pytest

from softtip import SensorNoise, direction_angle_std, tangential_spin_torque_std
from softtip.core.spin import direction_angle, edge_direction, spin_torque, tangential_spin_torque


@pytest.mark.parametrize("normal", [(0.0, 0.0, 1.0), (0.6, 0.0, 0.8), (0.0, -1.0, 0.0)])
def test_propagated_noise_matches_monte_carlo(rng, normal):
    n = np.array(normal)
    r = np.array([0.0, 0.0, 0.02]) + 0.016 * n
    noise = SensorNoise(force_std=(0.01, 0.02, 0.015), moment_std=(4e-5, 2e-5, 3e-5))
    # a line contact: h along a tangent direction
    t = np.cross(n, [0.3, 0.5, 0.2])
    t /= np.linalg.norm(t)
    f = -5.0 * n
    w0 = np.concatenate((f, np.cross(r, f) + 1e-3 * n + 1.5e-2 * t))
    k = 200_000
    w = w0 + rng.normal(size=(k, 6)) * np.concatenate((noise.force_std, noise.moment_std))
    h = tangential_spin_torque(spin_torque(w, np.broadcast_to(r, (k, 3))), np.broadcast_to(n, (k, 3)))
    dh = h - tangential_spin_torque(spin_torque(w0, r), n)
    h_std = tangential_spin_torque_std(r, n, noise)
    assert np.sqrt(np.mean(np.sum(dh * dh, axis=1))) == pytest.approx(h_std, rel=0.01)
    angles = direction_angle(edge_direction(h, np.broadcast_to(n, (k, 3))), np.broadcast_to(n, (k, 3)))
    h0 = tangential_spin_torque(spin_torque(w0, r), n)
    d0 = edge_direction(h0, n)
    predicted = direction_angle_std(d0, np.linalg.norm(h0), r, noise)
    # first order in noise/|h| (here ~0.03 rad): good to a percent or two
    assert np.std(angles) == pytest.approx(predicted, rel=0.02)


def test_noise_model_validation():
    with pytest.raises(ValueError, match="force_std"):
        SensorNoise(force_std=(-1, 0, 0), moment_std=(0, 0, 0))
    assert SensorNoise(0.01, 1e-5).force_std == (0.01, 0.01, 0.01)
