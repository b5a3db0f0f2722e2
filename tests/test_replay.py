"""softtip.io.sources and `softtip stream --replay`: the live path without hardware."""

import csv
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from softtip import EXAMPLE_PATH, Estimator, load_example
from softtip.apps.live import RECORD_COLUMNS, LiveStats, Recorder, run, run_live
from softtip.io.sources import LogSource, Reading
from softtip.io.tables import write_table

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
        yield from zip(log.t.tolist(), log.wrench.tolist())

    # repr: every float to the bit, NaN equal to NaN (== on tuples holds NaN equal only to itself)
    assert repr(list(run(my_driver(), "murakami2006"))) == repr(expected)
    assert repr(list(run(LogSource(log.t, log.wrench, speed=0)))) == repr(expected)


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
    # the same numbers as the batch command, its columns under the same names (fx..mz the
    # tared wrench in both), t and the raw wrench fx_raw..mz_raw exactly (shortest round-trip
    # repr); `softtip estimate` writes with pyarrow, the recorder with printf (0.00001 vs
    # 1e-05), so the cells compare as numbers
    wrench = ("fx", "fy", "fz", "mx", "my", "mz")
    for r, e in zip(rows, expected):
        same = [k for k in e if k != "t"]
        assert [_cell(r[k]) for k in same] == [_cell(e[k]) for k in same]
        assert float(r["t"]) == float(e["t"])
    log = load_example()
    assert [float(r["t"]) for r in rows] == log.t.tolist()
    assert [[float(r[k + "_raw"]) for k in wrench] for r in rows] == log.wrench.tolist()


def test_a_short_replay_runs_the_steps_as_python_with_the_compiled_bits(tmp_path):
    """A replay of fewer than STEP_MIN_SAMPLES samples does not load numba (about 0.7 s of CPU
    before the first sample): its recording is the one of the compiled steps to the byte."""
    import os

    runs = {}
    for name, numba in (("python", None), ("compiled", "1")):
        env = {k: v for k, v in os.environ.items() if k != "SOFTTIP_NUMBA"}
        if numba is not None:
            env["SOFTTIP_NUMBA"] = numba
        rec = tmp_path / f"{name}.csv"
        out = subprocess.run(
            [sys.executable, "-X", "importtime", "-m", "softtip.cli", "stream", "--replay", EXAMPLE_PATH,
             "--speed", "0", "--no-view", "--record", rec],
            capture_output=True, text=True, timeout=120, env=env,
        )  # fmt: skip
        assert out.returncode == 0, out.stderr[-3000:]
        imported = {line.rsplit("|", 1)[-1].strip() for line in out.stderr.splitlines() if line.startswith("import time:")}
        rows = rec.read_text().splitlines()
        host = rows[0].split(",").index("host_time")  # the arrival on this host: differs from run to run
        runs[name] = ([",".join(c for k, c in enumerate(r.split(",")) if k != host) for r in rows], "numba" in imported)
    assert runs["python"][1] is False and runs["compiled"][1] is True
    assert len(runs["python"][0]) == 501 and runs["python"][0] == runs["compiled"][0]


def test_a_recording_is_a_log_estimate_and_replay_read_as_it_is(tmp_path):
    rec, again = tmp_path / "rec.csv", tmp_path / "again.csv"
    out = subprocess.run(
        [SOFTTIP, "stream", "--replay", EXAMPLE_PATH, "--speed", "0", "--record", rec],
        capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    est = subprocess.run([SOFTTIP, "estimate", rec], capture_output=True, text=True, timeout=60)
    assert est.returncode == 0, est.stderr  # was: "rec.csv:2: column 'fx': ... got 'nan'"
    recorded = read_rows(rec)
    estimated = list(csv.DictReader(est.stdout.splitlines()))
    # the recording reproduces its own estimates: same raw input, same tare, same states
    assert [e["state"] for e in estimated] == [r["state"] for r in recorded]
    assert [_cell(e["angle_deg"]) for e in estimated] == [_cell(r["angle_deg"]) for r in recorded]
    out = subprocess.run(
        [SOFTTIP, "stream", "--replay", rec, "--speed", "0", "--record", again],
        capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    cols = [c for c in RECORD_COLUMNS if c not in ("host_time", "seq")]
    assert [[r[c] for c in cols] for r in read_rows(again)] == [[r[c] for c in cols] for r in recorded]


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
    assert summary.counters == {"received": 500, "lost": 499, "dropped": 0}
    rows = read_rows(tmp_path / "r.csv")
    assert [int(r["seq"]) for r in rows] == list(range(10, 1010, 2))
    assert np.isclose(float(rows[-1]["angle_deg"]), np.degrees(summary.last.angle))


def test_a_stopped_replay_ends_at_once_with_every_row(tmp_path):
    import threading

    log = load_example()
    stop = threading.Event()
    rec = Recorder(tmp_path / "r.csv")
    src = LogSource(log.t * 100, log.wrench, speed=1.0, stop=stop)  # 2 s between samples
    threading.Timer(0.3, stop.set).start()
    t0 = time.monotonic()
    summary = run_live(src, Estimator(), recorder=rec, stop=stop)
    assert time.monotonic() - t0 < 1.5 and summary.reason == "interrupt"
    assert summary.samples == 1 and len(read_rows(tmp_path / "r.csv")) == 1


def test_estimating_a_recording_says_its_renamed_columns_in_one_line(tmp_path):
    # a recording holds softtip's own output columns: estimating it again renames them all to
    # input_NAME, which took one warning line per column (46)
    rec = tmp_path / "rec.csv"
    r = subprocess.run([SOFTTIP, "stream", "--replay", str(EXAMPLE_PATH), "--speed", "0", "-o", str(rec)],
                       capture_output=True, text=True, timeout=120)  # fmt: skip
    assert r.returncode == 0, r.stderr
    r = subprocess.run([SOFTTIP, "estimate", str(rec), "-o", str(tmp_path / "again.csv")], capture_output=True, text=True,
                       timeout=120)  # fmt: skip
    assert r.returncode == 0, r.stderr
    lines = [line for line in r.stderr.splitlines() if "named like" in line]
    assert len(lines) == 1 and "input columns are named like output columns" in lines[0] and "'state' -> 'input_state'" in lines[0]


def test_a_replayed_ros_export_keeps_its_stamps_in_the_recording(tmp_path):
    """A ROS export's absolute stamps (ns since the epoch) go along: ``softtip estimate`` keeps
    them as column ``stamp_ns``, and so does a replay's recording, exactly; the recording,
    estimated again, keeps them too."""
    from softtip.io.tables import read_log

    src = Path(__file__).parent / "data" / "foreign" / "rostopic_echo_p.csv"
    stamps = [str(s) for s in read_log(src).stamps_ns]
    rec = tmp_path / "rec.csv"
    out = subprocess.run([SOFTTIP, "stream", "--replay", src, "--speed", "0", "--record", rec, "--no-view"],
                         capture_output=True, text=True, timeout=60)  # fmt: skip
    assert out.returncode == 0, out.stderr
    assert "the stamps go along as column stamp_ns" in out.stderr
    rows = read_rows(rec)
    assert list(rows[0])[-1] == "stamp_ns" and [r["stamp_ns"] for r in rows] == stamps
    est = subprocess.run([SOFTTIP, "estimate", rec], capture_output=True, text=True, timeout=60)
    assert est.returncode == 0, est.stderr
    assert [r["stamp_ns"] for r in csv.DictReader(est.stdout.splitlines())] == stamps
    # a log without absolute stamps records no such column
    plain = tmp_path / "plain.csv"
    out = subprocess.run([SOFTTIP, "stream", "--replay", EXAMPLE_PATH, "--speed", "0", "--record", plain, "--no-view"],
                         capture_output=True, text=True, timeout=60)  # fmt: skip
    assert out.returncode == 0, out.stderr
    assert tuple(read_rows(plain)[0]) == RECORD_COLUMNS


def test_the_recording_is_csv_and_a_parquet_or_arrow_name_is_refused(tmp_path):
    # the recorder writes CSV rows as they come: under a .parquet name they were CSV text (exit 0)
    for name in ("rec.parquet", "rec.arrow", "rec.feather"):
        r = subprocess.run([SOFTTIP, "stream", "--replay", EXAMPLE_PATH, "--speed", "0", "-o", str(tmp_path / name)],
                           capture_output=True, text=True, timeout=60)  # fmt: skip
        assert r.returncode == 2 and "but this command writes CSV; expected a name ending in .csv" in r.stderr, r.stderr
    assert list(tmp_path.iterdir()) == []


def test_quiet_stream_says_nothing_but_records_the_same(tmp_path):
    loud, quiet = tmp_path / "loud.csv", tmp_path / "quiet.csv"
    a = subprocess.run([SOFTTIP, "stream", "--replay", EXAMPLE_PATH, "--speed", "0", "-o", str(loud)],
                       capture_output=True, text=True, timeout=60)  # fmt: skip
    b = subprocess.run([SOFTTIP, "stream", "--replay", EXAMPLE_PATH, "--speed", "0", "-o", str(quiet), "-q"],
                       capture_output=True, text=True, timeout=60)  # fmt: skip
    assert a.returncode == b.returncode == 0, a.stderr + b.stderr
    assert "samples in" in a.stderr and b.stderr == ""
    for row_a, row_b in zip(read_rows(loud), read_rows(quiet), strict=True):
        row_a.pop("host_time"), row_b.pop("host_time")  # the host's clock at each sample
        assert row_a == row_b
    # a foreign file: how it was read is a note, said without -q only (as estimate -q)
    ati = tmp_path / "ati.csv"
    log = load_example()
    rows = [f"{t!r},{','.join(repr(v) for v in w)}" for t, w in zip(log.t.tolist(), log.wrench.tolist())]
    ati.write_text("Time,Fx,Fy,Fz,Tx,Ty,Tz\n" + "\n".join(rows) + "\n")
    c = subprocess.run([SOFTTIP, "stream", "--replay", str(ati), "--speed", "0", "-o", str(tmp_path / "c.csv"), "-q"],
                       capture_output=True, text=True, timeout=60)  # fmt: skip
    assert c.returncode == 0 and c.stderr == "", c.stderr
