"""The moment-to-force ratio catches a log read in the wrong units (issue 13, item 12)."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from softtip import load_example, murakami2006
from softtip.core.fingertip import Capsule, Ellipsoid, Sphere
from softtip.core.lever import LEVER_MARGIN, check_force_lever, force_lever
from softtip.core.units import KGF, KGF_MM
from softtip.errors import InputError
from softtip.io.tables import write_table

SOFTTIP = str(Path(sys.executable).with_name("softtip"))
AXES = ("fx", "fy", "fz", "mx", "my", "mz")


def in_kgf_mm(wrench):
    w = np.asarray(wrench)
    return np.concatenate([w[:, :3] / KGF, w[:, 3:] / KGF_MM], axis=1)


@pytest.mark.parametrize("tip", [murakami2006(), Sphere(0.008, (0.0, 0.0, 0.01)), Ellipsoid((0.01, 0.012, 0.02), (0.0, 0.0, 0.015)), Capsule(0.01, 0.03)])
def test_any_contact_on_the_skin_is_plausible(tip, rng):
    # random skin points, forces pushing in within a friction cone of 1, spin torques up to 2 N·mm
    n = 2000
    r = tip.project(rng.normal(size=(n, 3)) * 0.05 + tip.bounding_sphere[0])
    normal = tip.normal(r)
    tangent = rng.normal(size=(n, 3))
    tangent -= np.einsum("ij,ij->i", tangent, normal)[:, None] * normal
    f = -normal * rng.uniform(0.2, 10.0, (n, 1)) + tangent * rng.uniform(0.0, 1.0, (n, 1)) * 0.2
    m = np.cross(r, f) + normal * rng.uniform(-2e-3, 2e-3, (n, 1))
    for k in range(0, n, 100):  # every batch of 100 contacts, as a log's contact samples
        lever = force_lever(np.hstack([f, m])[k : k + 100], tip)
        assert lever.plausible and lever.median <= lever.reach
        assert not force_lever(in_kgf_mm(np.hstack([f, m])[k : k + 100]), tip).plausible or lever.median < LEVER_MARGIN * lever.reach / 100


def test_example_in_kgf_mm_read_as_si_is_refused():
    ex = load_example()
    tared = ex.wrench - ex.wrench[:10].mean(axis=0)
    assert check_force_lever(tared, murakami2006(), units="si").median < 0.005
    with pytest.raises(InputError, match=r"grasp.csv: the forces act 2\d{3} mm .* --units kgf-mm"):
        check_force_lever(in_kgf_mm(tared), murakami2006(), units="si", source="grasp.csv")


def test_too_few_samples_decide_nothing():
    w = np.zeros((4, 6))
    w[:, 2], w[:, 3] = -1.0, 5.0  # 5 m lever, but only four samples
    assert force_lever(w, murakami2006()).plausible


def test_cli_stops_a_kgf_mm_log_read_as_si(tmp_path):
    ex = load_example()
    w = in_kgf_mm(ex.wrench)
    log = tmp_path / "kgf.csv"
    write_table({"t": ex.t, **{c: w[:, i] for i, c in enumerate(AXES)}}, log, float_format="%.17g")
    out = subprocess.run([SOFTTIP, "estimate", log, "-o", tmp_path / "e.csv"], capture_output=True, text=True, timeout=120)
    assert out.returncode == 2, out.stderr
    assert "--units kgf-mm" in out.stderr and "kgf.csv" in out.stderr and "Traceback" not in out.stderr
    assert not (tmp_path / "e.csv").exists()
    out = subprocess.run([SOFTTIP, "estimate", log, "--units", "kgf-mm", "-o", tmp_path / "e.csv"], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr


@given(
    sigma=st.floats(2e-3, 2e-2),
    quantum_over_sigma=st.floats(0.3, 2.0),
    seed=st.integers(0, 2**31 - 1),
)
@settings(max_examples=60, deadline=None)
def test_the_noise_of_a_sensor_as_coarse_as_its_noise_is_measured(sigma, quantum_over_sigma, seed):
    """Quantised noise repeats its values (the median difference of successive samples is 0 from
    a quantum of 2σ on, and lands on a quantum's multiple from about 0.8σ on): the ratio is
    still measured, not skipped, within 25 % of the noise (the quantum 0.3σ to 2σ)."""
    from softtip.core.lever import noise_ratio
    from softtip.core.noise import SensorNoise

    rng = np.random.default_rng(seed)
    q = quantum_over_sigma * sigma
    w = np.round(rng.normal(0.0, sigma, (200, 6)) / q) * q
    w[:, 3:] *= 0.01  # moments: the same noise at a hundredth of the scale
    ratio = noise_ratio(w, SensorNoise(force_std=(sigma,) * 3, moment_std=(0.01 * sigma,) * 3))
    assert ratio is not None
    assert ratio[0] == pytest.approx(1.0, rel=0.25) and ratio[1] == pytest.approx(1.0, rel=0.25)
    assert noise_ratio(np.zeros((50, 6)), SensorNoise(force_std=(sigma,) * 3, moment_std=(sigma,) * 3)) is None


def test_cli_stops_a_simulated_si_log_read_as_kgf_mm(tmp_path):
    """softtip's own simulated sensor quantises its samples about as coarsely as its noise: an SI
    log read as kgf and kgf·mm stops on the noise. With a 1 s tare (50 samples) SI fits it; with
    the default 0.2 s tare (10 samples) the moment noise comes out 3.4 times low, no pair fits
    within 3 times, and the pair 100 times nearer than kgf-mm is named (it ran on, exit 0)."""
    sim = subprocess.run([SOFTTIP, "simulate", "-o", tmp_path / "log.csv"], capture_output=True, text=True, timeout=120)
    assert sim.returncode == 0, sim.stderr
    for tare, named in ((["--tare-duration", "1"], "the data fit forces in N with moments in N·m (the default"),
                        ([], "no unit pair puts it within 3 times the sensor's; 102 times nearer: forces in N with "
                             "moments in N·m (the default")):  # fmt: skip
        out = subprocess.run([SOFTTIP, "estimate", tmp_path / "log.csv", "--units", "kgf-mm", *tare, "-o", tmp_path / "e.csv"],
                             capture_output=True, text=True, timeout=120)  # fmt: skip
        assert out.returncode == 2, out.stderr
        assert "the noise while taring" in out.stderr and named in out.stderr, out.stderr
        assert not (tmp_path / "e.csv").exists()
        out = subprocess.run([SOFTTIP, "estimate", tmp_path / "log.csv", *tare, "-o", tmp_path / "e.csv"],
                             capture_output=True, text=True, timeout=120)  # fmt: skip
        assert out.returncode == 0, out.stderr
        (tmp_path / "e.csv").unlink()


def test_a_lever_off_by_a_thousand_names_the_pairs_it_fits_when_the_noise_fits_none():
    # moments in N·mm read as N·m (a lever 1000 times the fingertip's) with a tare whose noise is
    # 2.5 times quieter than the sensor's in force and 5 times in N·mm (a simulated log's quantised
    # noise, a short tare): the noise puts no pair within 3 times (kgf-mm: 4 and 2 times too
    # noisy), so it picks none; every pair the lever fits is named, --moment-units N*mm among them
    from softtip.core.lever import check_wrench_units
    from softtip.core.noise import NANO17

    ex = load_example()
    tared = ex.wrench - ex.wrench[:10].mean(axis=0)
    in_nmm = np.concatenate([tared[:, :3], tared[:, 3:] * 1e3], axis=1)
    rng = np.random.default_rng(5)
    f0, m0 = NANO17.force_std[0], NANO17.moment_std[0] * 1e3  # the sensor's, the moment's as read (N·mm as N·m)
    quiet = np.concatenate([rng.normal(0, 0.4 * f0, (40, 3)), rng.normal(0, 0.2 * m0, (40, 3))], axis=1)
    with pytest.raises(InputError) as info:
        check_wrench_units(in_nmm, murakami2006(), quiet=quiet, noise=NANO17)
    msg = str(info.value)
    assert "the noise while taring fits no unit pair within 3 times the sensor's" in msg
    assert "forces in N with moments in N·mm (--moment-units N*mm)" in msg
    # a tare far quieter than the sensor in force and moment alike (noise-free simulated data): the
    # same, the lever names the pairs
    silent = rng.normal(0, 1e-9, (40, 6))
    with pytest.raises(InputError) as info:
        check_wrench_units(in_nmm, murakami2006(), quiet=silent, noise=NANO17)
    assert "the noise while taring fits no unit pair within 3 times the sensor's" in str(info.value)
    assert "forces in N with moments in N·mm (--moment-units N*mm)" in str(info.value)
