"""Issue 28, item 6: the rest of a user's path from a recording to estimates.

``calibrate`` says whether its fingertip file carries the skin thickness (the depth
compensation needs it) and ``estimate`` says when a fingertip file turns it off; ``--sensor``
picks the noise preset; a configured ``sample_rate`` that the stamps contradict is a warning.
"""

from __future__ import annotations

import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from softtip import Estimator, EstimatorConfig, EstimatorWarning, estimate, load_example
from softtip.core.noise import NANO25

SOFTTIP = str(Path(sys.executable).with_name("softtip"))


def run(*args: object) -> subprocess.CompletedProcess:
    return subprocess.run([SOFTTIP, *map(str, args)], capture_output=True, text=True, timeout=180)


def test_calibrate_writes_or_says_the_skin_thickness(tmp_path: Path) -> None:
    bare, skin = tmp_path / "bare.toml", tmp_path / "skin.toml"
    done = run("calibrate", "--example", "--shape", "sphere", "-o", bare)
    assert done.returncode == 0, done.stderr
    assert "has no skin_thickness, so estimate's depth compensation" in done.stderr and "--skin-thickness" in done.stderr
    assert "# no skin_thickness: softtip estimate's depth compensation is off" in bare.read_text()
    done = run("calibrate", "--example", "--shape", "sphere", "--skin-thickness", "5mm", "-o", skin)
    assert done.returncode == 0, done.stderr
    assert "skin_thickness = 0.005" in skin.read_text() and "no skin_thickness" not in done.stderr
    done = run("estimate", "--example", "--tip", bare, "-o", tmp_path / "a.csv")
    assert done.returncode == 0 and f"{bare}: no skin_thickness, so the depth compensation is off" in done.stderr
    done = run("estimate", "--example", "--tip", skin, "-o", tmp_path / "b.csv")
    assert done.returncode == 0 and "no skin_thickness" not in done.stderr


def test_sensor_preset_sets_the_noise_model(tmp_path: Path) -> None:
    out = tmp_path / "e.csv"
    done = run("estimate", "--example", "--sensor", "nano25", "-o", out)
    assert done.returncode == 0, done.stderr
    assert "0.21 times the noise model" in done.stderr  # the example's Nano17 noise against a Nano25's
    done = run("estimate", "--example", "--sensor", "nano25", "--force-noise", "0.006", "--moment-noise", "0.03", "-o", out)
    assert done.returncode == 0 and "1.2 times the noise model" in done.stderr  # given values win
    done = run("calibrate", "--example", "--shape", "sphere", "--sensor", "mini40")
    assert done.returncode == 0, done.stderr
    assert run("estimate", "--example", "--sensor", "nano99").returncode == 2
    assert NANO25.force_std[2] == pytest.approx(1 / 16)


def test_configured_sample_rate_contradicting_the_stamps_is_a_warning() -> None:
    log = load_example()  # 50 Hz
    with pytest.warns(EstimatorWarning, match=r"config.sample_rate is 1000 Hz but the stamps step at 50 Hz"):
        estimate(log.t, log.wrench, "murakami2006", EstimatorConfig(sample_rate=1000))
    est = Estimator("murakami2006", EstimatorConfig(sample_rate=1000))
    with pytest.warns(EstimatorWarning, match=r"stamps step at 50 Hz"):
        for t, w in zip(log.t[:30], log.wrench[:30]):
            est.update(t, w)
    with warnings.catch_warnings():
        warnings.simplefilter("error", EstimatorWarning)
        estimate(log.t, log.wrench, "murakami2006", EstimatorConfig(sample_rate=50))
        right = Estimator("murakami2006", EstimatorConfig(sample_rate=50))
        for t, w in zip(log.t[:30], log.wrench[:30]):
            right.update(t, w)



def test_the_sample_rate_check_reads_the_same_stamps_in_batch_and_stream() -> None:
    # 100 Hz for 0.3 s, then 125 Hz: the stream checks its first stamps (100 Hz, as configured)
    # and the batch checked all of them (their median: 125 Hz) and warned where the stream did not
    t = np.concatenate([np.arange(30) / 100.0, 0.3 + np.arange(1, 400) / 125.0])
    w = np.zeros((len(t), 6))
    cfg = EstimatorConfig(sample_rate=100.0, tare_duration=0.1)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", EstimatorWarning)
        batch = estimate(t, w, "murakami2006", cfg).warnings
        est = Estimator("murakami2006", cfg)
        est.process(t, w)
    assert not any("sample_rate" in m for m in batch) and list(batch) == est.warnings, (batch, est.warnings, caught)

def test_the_package_is_typed() -> None:
    import softtip

    assert (Path(softtip.__file__).parent / "py.typed").exists()


def test_estimates_as_arrow_and_pandas() -> None:
    log = load_example()
    est = estimate(log.t, log.wrench)
    table = est.to_arrow()
    assert table.column_names == list(est.columns())
    assert table.column("state").to_pylist() == list(est.state_names)
    assert table.num_rows == len(log.t)
    try:
        import pandas  # noqa: F401
    except ImportError:
        with pytest.raises(ImportError, match="pip install pandas"):
            est.to_pandas()
    else:
        assert list(est.to_pandas()["state"]) == list(est.state_names)
