"""The live path's views and its pauses: the Rerun view drawn in a process of its own, the garbage
collector frozen for a live run, and the 7 kHz soak's measurement (benchmarks/bench_live.py)."""

import gc
import os
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from softtip import Estimator, load_fingertip
from softtip.apps.live import run_live
from softtip.errors import InputError
from softtip.sim.synthetic import synthetic_grasp

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


@pytest.fixture(scope="module")
def estimates():
    tip = load_fingertip("murakami2006")
    g = synthetic_grasp(tip, duration=10.0, rate=1000.0, seed=1)  # 500 drawn: more than a pipe holds
    est = Estimator(tip)
    return tip, [est.update(t, w) for t, w in zip(g.t, g.wrench)]


def _series(path: Path, entity: str) -> dict[float, float]:
    """{t (s): value} of a scalar series in a saved recording."""
    from rerun.chunk import RrdReader

    out = {}
    for chunk in RrdReader(str(path)).store().stream():
        if chunk.entity_path == entity:
            batch = chunk.to_record_batch()
            for t, v in zip(batch.column("t").to_pylist(), batch.column("Scalars:scalars").to_pylist()):
                out[t.total_seconds()] = v[0]
    return out


@pytest.mark.parametrize("wait", [True, False], ids=["started", "starting"])
def test_the_live_rerun_view_draws_what_the_logger_draws_from_another_process(estimates, tmp_path, wait):
    pytest.importorskip("rerun")
    from softtip.viz.rerun import LiveRerun, RerunLogger

    tip, es = estimates
    live = LiveRerun(tip, save=tmp_path / "live.rrd", wait=wait)
    assert live._proc.pid != os.getpid() and not hasattr(live, "rec")  # nothing of Rerun's in this process
    for k, e in enumerate(es):
        live.log_sample(e)
        if k == len(es) // 2:  # more than the pipe holds is on its way (to a process still starting)
            time.sleep(0.2)
    live.close()
    assert live._proc.returncode == 0
    live.close()  # idempotent
    ref = RerunLogger(tip, save=tmp_path / "ref.rrd")
    for e in es:
        ref.log_sample(e)
    ref.close()
    for entity in ("/series/state", "/series/h_norm", "/series/force/fz"):
        got, want = _series(tmp_path / "live.rrd", entity), _series(tmp_path / "ref.rrd", entity)
        assert len(want) > 400 and got.keys() == want.keys(), entity  # 50 samples per s of t, the same ones
        assert np.array_equal(list(got.values()), list(want.values()), equal_nan=True), entity
    assert set(_series(tmp_path / "live.rrd", "/series/state").values()) >= {0.0, 1.0, 2.0}  # none, point, line


@pytest.mark.parametrize("n", [1, 13, 20])
def test_the_rerun_series_keep_every_drawn_sample(estimates, tmp_path, n):
    # the series go out as columns every SERIES_BATCH_S of t: the samples of an unfinished batch
    # are sent at close, each at its own t with its own values
    pytest.importorskip("rerun")
    from softtip.viz.rerun import SERIES, SERIES_BATCH_S, RerunLogger

    tip, es = estimates
    drawn = [e for e in es if e.state != "none"][: n * 25 : 25]  # 40 Hz of t: every one drawn (50 at most)
    assert len(drawn) == n and (n == 1 or drawn[-1].t - drawn[0].t > SERIES_BATCH_S)
    view = RerunLogger(tip, save=tmp_path / "v.rrd")
    for e in drawn:
        view.log_sample(e)
    view.close()
    for k, entity in enumerate(SERIES):
        got = _series(tmp_path / "v.rrd", "/" + entity)
        want = [(*e.wrench, e.h_norm, np.degrees(e.angle), ("none", "point", "line", "area").index(e.state))[k] for e in drawn]
        assert sorted(got) == pytest.approx([e.t for e in drawn]), entity
        assert np.array_equal([got[t] for t in sorted(got)], want, equal_nan=True), entity


def test_the_live_rerun_view_draws_behind_the_estimator(estimates, tmp_path):
    # the drawing process and every thread Rerun started in it run only on a core the
    # estimator's threads leave idle (Linux's idle class), elsewhere at the lowest priority
    pytest.importorskip("rerun")
    from softtip.viz.rerun import LiveRerun

    tip, es = estimates
    live = LiveRerun(tip, save=tmp_path / "live.rrd")  # started: Rerun's threads are running
    try:
        for e in es[:100]:
            live.log_sample(e)
        pid = live._proc.pid
        if sys.platform.startswith("linux"):
            threads = [int(tid) for tid in os.listdir(f"/proc/{pid}/task")]
            assert len(threads) > 1
            assert {os.sched_getscheduler(tid) for tid in threads} == {os.SCHED_IDLE}
            assert os.sched_getscheduler(0) != os.SCHED_IDLE  # the estimator's process keeps its class
        else:
            assert os.getpriority(os.PRIO_PROCESS, pid) == 19
    finally:
        live.close()
    assert live._proc.returncode == 0


def test_the_live_rerun_view_says_why_it_cannot_start(estimates, tmp_path):
    pytest.importorskip("rerun")
    from softtip.viz.rerun import LiveRerun

    tip, es = estimates
    with pytest.raises(InputError, match="no-such-folder"):
        LiveRerun(tip, save=tmp_path / "no-such-folder" / "view.rrd")
    live = LiveRerun(tip, save=tmp_path / "no-such-folder" / "view.rrd", wait=False)  # starts meanwhile
    with pytest.raises(InputError, match="no-such-folder"):
        for e in es:  # the loop learns of it within a few samples of the failure
            live.log_sample(e)
            time.sleep(0.002)
    assert live._proc.returncode is not None
    live.close()  # closed already


def test_a_live_run_freezes_the_start_up_heap_and_unfreezes_it_at_the_end():
    g = synthetic_grasp("murakami2006", duration=1.0, rate=1000.0, seed=2)
    frozen = []

    def count(e, r):  # every 100th sample (the count walks the frozen objects)
        if len(g.t) - r.t * 1000 < 1.5 or round(r.t * 1000) % 100 == 0:
            frozen.append(gc.get_freeze_count())

    before = gc.get_freeze_count()
    run_live(zip(g.t, g.wrench), Estimator(), on_estimate=count)
    assert len(frozen) == 11 and min(frozen) > before + 1000  # softtip, numpy, ... frozen while it runs
    assert gc.get_freeze_count() == before and gc.isenabled()
    frozen.clear()
    run_live(zip(g.t, g.wrench), Estimator(), on_estimate=count, freeze_gc=False)
    assert frozen == [before] * 11


def test_the_soak_measures_a_clean_stream_in_contact_with_nothing_lost():
    sys.path.insert(0, str(BENCHMARKS))
    try:
        import bench_live
    finally:
        sys.path.remove(str(BENCHMARKS))
    w = bench_live.soak_wrench(1000.0, 25.0)
    touched = np.linalg.norm(w[:, :3] - np.median(w[:900, :3], axis=0), axis=1) > 0.05  # N beyond the bias
    assert w.shape == (25_000, 6) and not touched[:900].any() and 0.85 < touched.mean() < 0.95
    r = bench_live.soak(rate=1000.0, seconds=2.5, views=False)
    c = r["counters"]
    assert c["lost"] == 0 and c["dropped"] == 0 and r["rows"] == r["samples"] > 2000
    assert 0.3 < r["in_contact"] < 0.8  # the tare (1 s), then the press
    assert 0 < r["own_contact"]["median"] <= r["own_contact"]["p99"] <= r["latency_contact"]["max"]
    own, cpu = r["own_contact"], r["own_cpu_contact"]  # a call's CPU time is within its wall time
    assert 0 < cpu["median"] <= own["median"] and cpu["p99"] <= own["p99"]


def test_stream_saves_the_rerun_view_drawn_by_its_own_process(tmp_path):
    pytest.importorskip("rerun")
    import subprocess

    from softtip.io.examples import EXAMPLE_PATH, load_example

    view = tmp_path / "view.rrd"
    r = subprocess.run([sys.executable, "-m", "softtip.cli", "stream", "--replay", str(EXAMPLE_PATH), "--speed", "0",
                        "--rerun-save", str(view), "--no-view"], capture_output=True, text=True, timeout=120)  # fmt: skip
    assert r.returncode == 0, r.stderr
    log = load_example()
    states = _series(view, "/series/state")
    drawn = np.array(sorted(states))
    assert np.abs(drawn[:, None] - log.t).min(axis=1).max() < 1e-6  # at the samples' t (rerun keeps ns)
    assert drawn[0] == log.t[0] and log.t[-1] - drawn[-1] <= 0.04
    assert np.diff(drawn).max() <= 0.04 + 1e-9  # at most 50 per s of the log's 50 Hz, none of them left out for long
    assert set(states.values()) >= {0.0, 2.0}


def test_the_receiver_says_how_far_behind_its_consumer_is():
    from softtip.io.netft import NetFTSource
    from softtip.testing.netft_fake import FakeNetFT

    with FakeNetFT(rate_hz=2000) as dev:
        with NetFTSource("127.0.0.1", rdt_port=dev.rdt_port, http_port=dev.http_port, timeout=2.0) as src:
            it = iter(src)
            next(it)
            time.sleep(0.3)  # the consumer stalls: about 600 datagrams wait
            behind = src.queued
            for _ in range(behind):
                next(it)
            after = src.queued
    assert 300 <= behind <= 2000 and after < behind


def test_a_retare_is_in_the_summary_and_the_tare_line_says_where():
    # the t key's tare was not said anywhere: the summary's tare line read "from the first 0.2 s"
    import threading

    g = synthetic_grasp("murakami2006", duration=3.0, rate=100.0, seed=2)
    request = threading.Event()
    est = Estimator()

    def press(e, r):
        if abs(r.t - 1.0) < 1e-9:
            request.set()  # taken at the next sample

    summary = run_live(zip(g.t, g.wrench), est, on_estimate=press, tare_request=request)
    assert summary.retares == [pytest.approx(1.01)]
    assert est.tare_report.summary(summary.retares[-1]).startswith("bias from the first 0.2 s of the re-tare at t = 1.01 s (")
