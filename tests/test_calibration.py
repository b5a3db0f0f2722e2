"""Fingertip calibration from simulated plane presses (softtip.calibration, `softtip calibrate`)."""

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from softtip.calibration import calibrate_fingertip, find_presses, simulate_probing
from softtip.errors import InputError
from softtip.fingertip import Capsule, Sphere, load_fingertip
from softtip.io import write_table

SOFTTIP = str(Path(sys.executable).with_name("softtip"))
MM = 1e-3
# nominal geometries the true ones differ from by a few mm
NOMINAL_SPHERE = Sphere(0.016, (0.0, 0.0, 0.020))
TRUE_SPHERE = Sphere(0.0175, (0.0015, -0.0010, 0.0225))
TRUE_CAPSULE = Capsule(0.0150, 0.0225)
CAPSULE_OFFSET = (0.0008, -0.0005)


@pytest.fixture(scope="module")
def sphere_log():
    return simulate_probing(TRUE_SPHERE, 30.0, rng=3)


@pytest.fixture(scope="module")
def capsule_log():
    return simulate_probing(TRUE_CAPSULE, 22.5, axis_offset=CAPSULE_OFFSET, rng=11)


def write_log(path, t, w):
    write_table({"t": t, **{c: w[:, i] for i, c in enumerate(("fx", "fy", "fz", "mx", "my", "mz"))}}, path, float_format="%.17g")


def run(*args):
    return subprocess.run([SOFTTIP, *map(str, args)], capture_output=True, text=True, timeout=120)


def test_sphere_recovered_within_0p2_mm(sphere_log):
    cal = calibrate_fingertip(*sphere_log, "sphere")
    # the nominal is several mm off: the fit does not just return its start
    assert np.linalg.norm(np.subtract(NOMINAL_SPHERE.center, TRUE_SPHERE.center)) > 2 * MM
    assert np.linalg.norm(cal.center - TRUE_SPHERE.center) <= 0.2 * MM
    assert abs(cal.radius - TRUE_SPHERE.radius) <= 0.2 * MM
    assert cal.radius_std < 0.2 * MM and np.all(cal.center_std < 0.2 * MM)
    assert isinstance(cal.tip, Sphere) and cal.n_presses == 20  # 30 s of 1.5 s presses


def test_rigid_model_biases_the_radius(sphere_log):
    # without the indentation term the radius comes out short by about the indentation
    rigid = calibrate_fingertip(*sphere_log, "sphere", compliance=False)
    assert TRUE_SPHERE.radius - rigid.radius > 0.25 * MM


def test_capsule_recovered_with_axis_offset(capsule_log):
    cal = calibrate_fingertip(*capsule_log, "capsule")
    true_centre = np.array([*CAPSULE_OFFSET, TRUE_CAPSULE.length])
    assert np.linalg.norm(cal.center - true_centre) <= 0.2 * MM
    assert abs(cal.radius - TRUE_CAPSULE.radius) <= 0.2 * MM
    assert isinstance(cal.tip, Capsule) and abs(cal.tip.length - TRUE_CAPSULE.length) <= 0.2 * MM
    assert cal.axis_offset_significant()


def test_refuses_pure_normal_presses():
    t, w = simulate_probing(TRUE_SPHERE, 9.0, slide=False, rng=4)
    with pytest.raises(InputError, match="do not excite enough directions.*force direction turns"):
        calibrate_fingertip(t, w, "sphere", source="normal.csv")


def test_refuses_presses_at_one_spot():
    t, w = simulate_probing(TRUE_SPHERE, 9.0, max_tilt=math.radians(4.0), rng=5)
    with pytest.raises(InputError, match="do not excite enough directions.*one spot"):
        calibrate_fingertip(t, w, "sphere")


def test_refuses_too_few_presses(sphere_log):
    t, w = sphere_log
    keep = t < 4.4  # three presses
    with pytest.raises(InputError, match="expected at least 4"):
        calibrate_fingertip(t[keep], w[keep], "sphere")


@settings(max_examples=60)
@given(st.lists(st.booleans(), min_size=1, max_size=60), st.integers(1, 4))
def test_find_presses_are_the_runs_above_threshold(mask, min_samples):
    f = np.where(mask, 1.0, 0.0)
    presses = find_presses(f, 0.5, min_samples)
    covered = np.zeros(len(f), dtype=bool)
    for p in presses:
        assert len(p) >= min_samples and np.all(f[p] >= 0.5) and np.all(np.diff(p) == 1)
        assert p[0] == 0 or f[p[0] - 1] < 0.5
        assert p[-1] == len(f) - 1 or f[p[-1] + 1] < 0.5
        covered[p] = True
    # every run long enough is found
    runs = np.split(np.arange(len(f)), np.flatnonzero(np.diff(f)) + 1)
    assert sum(len(r) >= min_samples and f[r[0]] > 0 for r in runs) == len(presses)


def test_cli_calibrate_writes_loadable_tip(tmp_path, sphere_log):
    log = tmp_path / "probe.csv"
    write_log(log, *sphere_log)
    out = tmp_path / "tip.toml"
    res = run("calibrate", log, "--shape", "sphere", "-o", out)
    assert res.returncode == 0, res.stderr
    assert "radius" in res.stdout and "±" in res.stdout and "residual" in res.stdout
    tip = load_fingertip(out)
    assert isinstance(tip, Sphere)
    assert np.linalg.norm(np.subtract(tip.center, TRUE_SPHERE.center)) <= 0.2 * MM
    assert abs(tip.radius - TRUE_SPHERE.radius) <= 0.2 * MM


def test_cli_calibrate_refuses_with_exit_2_and_no_file(tmp_path):
    t, w = simulate_probing(TRUE_SPHERE, 6.0, slide=False, rng=6)
    log = tmp_path / "flat.csv"
    write_log(log, t, w)
    out = tmp_path / "tip.toml"
    res = run("calibrate", log, "--shape", "sphere", "-o", out)
    assert res.returncode == 2
    assert "do not excite enough directions" in res.stderr and str(log) in res.stderr
    assert not out.exists() and list(tmp_path.iterdir()) == [log]
