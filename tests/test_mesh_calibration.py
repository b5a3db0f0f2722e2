"""Calibration of a mesh fingertip's placement from plane presses (softtip.calibration.mesh)."""

import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from softtip import InputError, load_fingertip
from softtip.calibration.mesh import calibrate_mesh
from softtip.core.mesh import MeshFingertip, capsule_mesh
from softtip.core.noise import NANO17
from softtip.io.tables import write_table
from softtip.sim.probing import mesh_probing_log

SOFTTIP = str(Path(sys.executable).with_name("softtip"))
V, F = capsule_mesh(0.016, 0.020, segments=64)


@pytest.fixture(scope="module")
def nominal():
    return MeshFingertip(V, F)


def shifted(shift):
    return MeshFingertip(V + shift, F)


def test_noise_free_presses_give_the_shift_and_the_compliance(nominal):
    shift = np.array([0.4e-3, -0.3e-3, 0.5e-3])
    t, w = mesh_probing_log(shifted(shift), 16, np.random.default_rng(1), compliance=2e-4)
    cal = calibrate_mesh(t, w, nominal)
    assert_allclose(cal.translation, shift, atol=1e-7)
    assert cal.compliance == pytest.approx(2e-4, abs=1e-7)
    assert cal.n_presses == 16 and cal.n_skipped == 0
    # the moved fingertip is the shifted one
    assert_allclose(cal.tip.vertices, V + cal.translation, atol=1e-12)


@pytest.mark.parametrize("seed", [2, 3])
def test_noisy_presses_are_within_their_standard_deviations(nominal, seed):
    rng = np.random.default_rng(seed)
    shift = rng.normal(scale=0.5e-3, size=3)
    t, w = mesh_probing_log(shifted(shift), 20, rng, noise=NANO17)
    cal = calibrate_mesh(t, w, nominal)
    assert np.all(cal.translation_std > 0) and np.all(cal.translation_std < 0.5e-3)
    assert np.all(np.abs(cal.translation - shift) < 4.0 * cal.translation_std)


@pytest.mark.parametrize("seed", [6, 7])
def test_a_turned_tip_fitted_by_its_shift_alone_is_warned(seed):
    # an oval tip (a capsule scaled 0.8 × 1.2 across) turned 15° about its axis: no shift fits it,
    # and the residual says so; the same presses of the tip as the file places it fit within
    # their scatter (a round tip's turn about its cap's centre is a shift: nothing to warn of)
    oval = V * np.array([0.8, 1.2, 1.0])
    c, s = np.cos(np.radians(15.0)), np.sin(np.radians(15.0))
    turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    nominal = MeshFingertip(oval, F)
    t, w = mesh_probing_log(MeshFingertip(oval @ turn.T, F), 20, np.random.default_rng(seed), noise=NANO17)
    cal = calibrate_mesh(t, w, nominal)
    assert cal.noise_ratio > 2.0 and "--rotation fits it" in cal.fit_warning
    t, w = mesh_probing_log(nominal, 20, np.random.default_rng(seed), noise=NANO17)
    good = calibrate_mesh(t, w, nominal)
    assert good.noise_ratio < 2.0 and good.fit_warning == ""


def test_a_round_tips_roll_is_refused(nominal):
    t, w = mesh_probing_log(shifted(np.zeros(3)), 16, np.random.default_rng(4))
    with pytest.raises(InputError, match="undetermined"):
        calibrate_mesh(t, w, nominal, rotation=True)


def test_too_few_presses_are_refused(nominal):
    t, w = mesh_probing_log(shifted(np.zeros(3)), 4, np.random.default_rng(5))
    with pytest.raises(InputError, match="4 usable presses"):
        calibrate_mesh(t, w, nominal)


def test_calibrate_command_writes_a_mesh_fingertip(tmp_path):
    import trimesh

    trimesh.Trimesh(V * 1e3, F, process=False).export(tmp_path / "tip.stl")
    shift = np.array([0.3e-3, 0.2e-3, -0.4e-3])
    t, w = mesh_probing_log(shifted(shift), 16, np.random.default_rng(6))
    w[3, 2] += 30.0  # a spike while taring: left out, and said
    cols = dict(zip(("fx", "fy", "fz", "mx", "my", "mz"), w.T))
    write_table({"t": t, **cols}, tmp_path / "probe.csv")
    out = subprocess.run(
        [SOFTTIP, "calibrate", tmp_path / "probe.csv", "--shape", "mesh", "--mesh", tmp_path / "tip.stl",
         "--mesh-units", "mm", "-o", tmp_path / "tip.toml"],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    assert "mesh shift" in out.stdout and "1 spike(s) among the 40 tare samples" in out.stderr
    tip = load_fingertip(tmp_path / "tip.toml")
    assert_allclose(np.sort(tip.vertices, axis=0), np.sort(V + shift, axis=0), atol=1e-6)
    # the mesh named relative to the file, as a fingertip file's paths are read: the folder can move
    assert 'mesh = "tip.stl"' in (tmp_path / "tip.toml").read_text()
    bad = subprocess.run(
        [SOFTTIP, "calibrate", tmp_path / "probe.csv", "--shape", "mesh", "--mesh", tmp_path / "tip.stl",
         "-o", tmp_path / "bad.toml"],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert bad.returncode == 2 and "--mesh-units" in bad.stderr and not (tmp_path / "bad.toml").exists()
    # a mesh drawn in mm declared in cm: 10× a fingertip, refused by its size (it made the fit diverge)
    cm = subprocess.run(
        [SOFTTIP, "calibrate", tmp_path / "probe.csv", "--shape", "mesh", "--mesh", tmp_path / "tip.stl",
         "--mesh-units", "cm", "-o", tmp_path / "cm.toml"],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert cm.returncode == 2 and "read as cm 10×" in cm.stderr and "Traceback" not in cm.stderr, cm.stderr
    assert not (tmp_path / "cm.toml").exists()
    # --skin-thickness goes into the file written from a bare mesh (depth compensation needs it)
    thick = subprocess.run(
        [SOFTTIP, "calibrate", tmp_path / "probe.csv", "--shape", "mesh", "--mesh", tmp_path / "tip.stl",
         "--mesh-units", "mm", "--skin-thickness", "5mm", "-o", tmp_path / "thick.toml"],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert thick.returncode == 0, thick.stderr
    assert load_fingertip(tmp_path / "thick.toml").skin_thickness == pytest.approx(0.005)
    assert load_fingertip(tmp_path / "tip.toml").skin_thickness is None and "has no skin_thickness" in out.stderr


def test_a_shift_known_to_more_than_a_tenth_of_a_millimetre_says_how_many_presses(nominal):
    t, w = mesh_probing_log(shifted(np.zeros(3)), 16, np.random.default_rng(3), noise=NANO17)
    cal = calibrate_mesh(t, w, nominal)
    assert replace(cal, translation_std=np.full(3, 0.05e-3)).precision_warning() == ""
    loose = replace(cal, translation_std=np.array([0.05e-3, 0.05e-3, 0.2e-3]))
    assert loose.precision_warning().startswith(
        f"the shift along z is known to ±0.20 mm (1 std) only: about {4 * cal.n_presses} presses like these would "
        "bring it to 0.1 mm"
    )


def test_fitted_shift_is_composed_with_the_files_transform(tmp_path):
    # a mesh drawn in a rotated, shifted CAD frame, placed by its file's transform; the fitted
    # shift goes into the transform that the written file holds
    import trimesh
    from scipy.spatial.transform import Rotation

    from softtip.calibration.mesh import calibrate_mesh_file

    rot = Rotation.from_euler("xyz", [10.0, -5.0, 30.0], degrees=True)
    offset = np.array([0.001, -0.002, 0.003])
    trimesh.Trimesh(rot.inv().apply(V - offset) * 1e3, F, process=False).export(tmp_path / "cad.stl")
    (tmp_path / "tip.toml").write_text(
        '[fingertip]\nmesh = "cad.stl"\nmesh_units = "mm"\n[fingertip.mount]\n'
        "translation = [0.001, -0.002, 0.003]\nrpy_deg = [10.0, -5.0, 30.0]\n"
    )
    shift = np.array([0.2e-3, -0.3e-3, 0.25e-3])
    t, w = mesh_probing_log(shifted(shift), 16, np.random.default_rng(7))
    cal = calibrate_mesh_file(t, w, str(tmp_path / "tip.toml"))
    assert_allclose(cal.translation, shift, atol=1e-6)
    (tmp_path / "fitted.toml").write_text(cal.tip.to_toml())
    again = load_fingertip(tmp_path / "fitted.toml")
    assert_allclose(again.vertices, cal.tip.vertices, atol=1e-9)
    assert_allclose(np.sort(again.vertices, axis=0), np.sort(V + shift, axis=0), atol=2e-6)


def test_a_spike_while_taring_is_left_out(nominal):
    """The estimator's tare (the mean without spikes), as the sphere's calibration: 30 N in z on
    one of the 40 untouched samples would move every press by 0.75 N with the plain mean."""
    shift = np.array([0.4e-3, -0.3e-3, 0.5e-3])
    t, w = mesh_probing_log(shifted(shift), 20, np.random.default_rng(2), noise=NANO17)
    spiked = w.copy()
    spiked[3, 2] += 30.0
    clean, got = calibrate_mesh(t, w, nominal), calibrate_mesh(t, spiked, nominal)
    assert got.n_presses == clean.n_presses == 20 and got.tare.spikes == 1 and clean.tare.spikes == 0
    assert_allclose(got.translation, clean.translation, atol=0.2 * np.max(clean.translation_std))


def test_an_18_mm_tip_drawn_in_mm_and_read_in_cm_is_a_located_error(tmp_path):
    # 180 mm across: within a fingertip's size range, but the presses lie nowhere near its skin;
    # the fit diverged (numpy's SVD did not converge, a traceback) and now says what to check
    import trimesh

    from softtip.calibration.mesh import calibrate_mesh_file

    v, f = capsule_mesh(0.008, 0.010, segments=48)
    trimesh.Trimesh(v * 1e3, f, process=False).export(tmp_path / "small.stl")
    t, w = mesh_probing_log(MeshFingertip(v, f), 16, np.random.default_rng(8), noise=NANO17)
    with pytest.raises(InputError, match=r"the presses do not fit this mesh .* wrong mesh units"):
        calibrate_mesh_file(t, w, str(tmp_path / "small.stl"), "cm")
    cal = calibrate_mesh_file(t, w, str(tmp_path / "small.stl"), "mm")  # the same presses, the mesh's own units
    assert np.all(np.abs(cal.translation) < 5 * cal.translation_std + 1e-5)
