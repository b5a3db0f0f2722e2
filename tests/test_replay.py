"""softtip.sources and `softtip stream --replay`: the live path without hardware."""

import csv
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from softtip import EXAMPLE_PATH, Estimator, load_example
from softtip.io import write_table
from softtip.live import RECORD_COLUMNS, LiveStats, Recorder, run_live
from softtip.sources import LogSource, Reading, run

SOFTTIP = str(Path(sys.executable).with_name("softtip"))


def read_rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def _cell(text):
    """A CSV cell as a number when it is one (NaN as a string, so that it compares equal)."""
    try:
        value = float(text)
    except ValueError:
        return text
    return "nan" if value != value else value


def test_run_accepts_any_iterable_of_t_wrench():
    log = load_example()
    expected = Estimator("murakami2006").process(log.t, log.wrench)

    def my_driver():  # a user's own source: a plain generator of (t, wrench)
        for t, w in zip(log.t.tolist(), log.wrench.tolist()):
            yield t, w

    assert list(run(my_driver(), "murakami2006")) == expected
    assert list(run(LogSource(log.t, log.wrench, speed=0))) == expected


def test_replay_record_matches_estimate(tmp_path):
    rec = tmp_path / "rec.csv"
    out = subprocess.run(
        [SOFTTIP, "stream", "--replay", EXAMPLE_PATH, "--speed", "0", "--record", rec],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 0, out.stderr
    assert "500 samples" in out.stderr and "end of log" in out.stderr
    est = subprocess.run(
        [SOFTTIP, "estimate", EXAMPLE_PATH], capture_output=True, text=True, timeout=60
    )
    expected = list(csv.DictReader(est.stdout.splitlines()))
    rows = read_rows(rec)
    assert list(rows[0]) == list(RECORD_COLUMNS)
    assert len(rows) == len(expected) == 500
    # the same numbers as the batch command (both to 10 significant digits; the recorder
    # writes them with printf's %.10g, `softtip estimate` with pyarrow: 1e-05 vs 0.00001)
    for r, e in zip(rows, expected):
        assert {k: _cell(r[k]) for k in e} == {k: _cell(v) for k, v in e.items()}
    log = load_example()
    assert [float(r["raw_fz"]) for r in rows] == pytest.approx(
        log.wrench[:, 2].tolist(), rel=1e-9
    )


def test_replay_runs_at_the_recorded_rate(tmp_path):
    log = load_example()
    short = tmp_path / "short.csv"
    n = 31  # 0.6 s at 50 Hz
    write_table(
        {
            "t": log.t[:n],
            **{
                c: log.wrench[:n, i]
                for i, c in enumerate(["fx", "fy", "fz", "mx", "my", "mz"])
            },
        },
        short,
    )
    t0 = time.monotonic()
    out = subprocess.run(
        [SOFTTIP, "stream", "--replay", short, "--speed", "2"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 0, out.stderr
    assert f"{n} samples in 0.3" in out.stderr  # 0.6 s of log at twice the speed
    assert time.monotonic() - t0 >= 0.3


def test_duration_stops_a_replay(tmp_path):
    out = subprocess.run(
        [
            SOFTTIP,
            "stream",
            "--replay",
            EXAMPLE_PATH,
            "--duration",
            "0.3",
            "--record",
            tmp_path / "r.csv",
        ],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 0, out.stderr
    assert "duration reached" in out.stderr
    assert 10 <= len(read_rows(tmp_path / "r.csv")) <= 25  # 50 Hz for 0.3 s


def test_replay_bad_input(tmp_path):
    out = subprocess.run(
        [
            SOFTTIP,
            "stream",
            "--replay",
            tmp_path / "missing.csv",
            "--record",
            tmp_path / "r.csv",
        ],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 2 and "missing.csv: file not found" in out.stderr
    assert not (tmp_path / "r.csv").exists()
    out = subprocess.run(
        [SOFTTIP, "stream"], capture_output=True, text=True, timeout=60
    )
    assert out.returncode == 2 and "--netft HOST or --replay" in out.stderr


def test_live_loop_with_recorder_and_stop(tmp_path):
    log = load_example()
    rec = Recorder(tmp_path / "r.csv", flush_interval=0.01)
    stats = LiveStats()

    def source():
        for k, (t, w) in enumerate(zip(log.t, log.wrench)):
            yield Reading(float(t), tuple(w), seq=10 + 2 * k, lost=1 if k else 0)

    summary = run_live(source(), Estimator(), recorder=rec, stats=stats)
    assert (summary.samples, summary.lost, summary.reason) == (500, 499, "end")
    rows = read_rows(tmp_path / "r.csv")
    assert [int(r["seq"]) for r in rows] == list(range(10, 1010, 2))
    assert np.isclose(float(rows[-1]["angle_deg"]), np.degrees(summary.last.angle))
