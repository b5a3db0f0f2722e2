"""A log's pieces estimated by worker processes (``estimate_pieces(..., jobs=2)``, ``softtip estimate
--jobs 2``) give the bits of the pieces estimated one after the other (``jobs=1``)."""

from __future__ import annotations

import dataclasses
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from softtip import EstimatorConfig
from softtip.apps import chunked
from softtip.apps.chunked import estimate_pieces
from softtip.io.tables import write_table
from softtip.sim.synthetic import sliding_presses

SOFTTIP = str(Path(sys.executable).with_name("softtip"))
WRENCH = ("fx", "fy", "fz", "mx", "my", "mz")

CONFIGS = {
    "default": EstimatorConfig(),
    "lowpass": EstimatorConfig(lowpass_hz=20.0),
    "relatch": EstimatorConfig(relatch_distance=0.5e-3),
    "line-fit": EstimatorConfig(contact_point="line-fit", relatch_distance=0.5e-3, lowpass_hz=25.0),
    "track": EstimatorConfig(contact_point="track"),
    "never-latches": EstimatorConfig(latch_window=(40.0, 50.0)),  # every guess of "an earlier latch" is wrong
}


def _log(seed: int, presses: int) -> tuple[np.ndarray, np.ndarray]:
    """Presses with untouched gaps (100 Hz), sensor noise, a bias that drifts."""
    rng = np.random.default_rng(seed)
    t, w = sliding_presses(rng, n_presses=presses, center=(0.0, 0.0, 20e-3), radius=10e-3)
    w = w + rng.normal(0.0, 1.0, w.shape) * np.array([3e-3] * 3 + [1.5e-5] * 3)
    ramp = (t - t[0]) / (t[-1] - t[0])
    w = w + np.array([0.05, 0.3, -0.2, 1e-4, -2e-4, 5e-5]) + ramp[:, None] * np.array([0.02, -0.01, 0.015, 2e-5, 0, -1e-5])
    return t, w


def _blocks(t, w, size):
    return [(t[i : i + size], w[i : i + size], {"row": np.arange(i, min(i + size, len(t)))}) for i in range(0, len(t), size)]


def _same(a, b, where: str) -> None:
    """``a`` and ``b`` equal to the bit: arrays (dtype, shape, NaN where NaN), dataclasses field by field."""
    if isinstance(a, np.ndarray):
        assert isinstance(b, np.ndarray) and a.dtype == b.dtype and a.shape == b.shape, where
        assert a.tobytes() == b.tobytes(), where
    elif dataclasses.is_dataclass(a):
        assert type(a) is type(b), where
        for f in dataclasses.fields(a):
            _same(getattr(a, f.name), getattr(b, f.name), f"{where}.{f.name}")
    elif isinstance(a, (tuple, list)):
        assert type(a) is type(b) and len(a) == len(b), where
        for k, (x, y) in enumerate(zip(a, b)):
            _same(x, y, f"{where}[{k}]")
    elif isinstance(a, float):
        assert isinstance(b, float) and (a == b or (a != a and b != b)), where
    else:
        assert a == b, where


def _pieces(t, w, config, rows, jobs):
    return list(estimate_pieces(_blocks(t, w, 41), "murakami2006", config, rows, jobs=jobs))


@pytest.mark.parametrize("name", sorted(CONFIGS))
def test_pieces_in_workers_give_the_bits_of_jobs_1(name: str) -> None:
    t, w = _log(seed=4, presses=14)
    config = CONFIGS[name]
    one = _pieces(t, w, config, 90, 1)
    two = _pieces(t, w, config, 90, 2)
    assert len(one) == len(two) > 8
    assert sum(e.n_contacts > 0 for e, _ in one) > 0 and max(e.n_contacts for e, _ in one) >= 10
    if name in ("relatch", "line-fit"):  # re-latches within contacts too, not only at the onsets
        assert any(np.any(e.relatched[1:] & (e.contact_id[1:] == e.contact_id[:-1])) for e, _ in one)
    for k, ((ea, xa), (eb, xb)) in enumerate(zip(one, two)):
        _same(ea, eb, f"piece {k}")
        _same(xa["row"], xb["row"], f"piece {k} extra")


@pytest.mark.parametrize("guess", [True, False])
def test_a_wrong_latch_guess_is_estimated_again(monkeypatch, guess: bool) -> None:
    """The flag "an earlier contact latched" guessed always true, always false: the same bits."""
    t, w = _log(seed=9, presses=8)
    config = EstimatorConfig(relatch_distance=1e-3)
    one = _pieces(t, w, config, 70, 1)
    assert any(e.relatched.any() for e, _ in one[1:])  # the flag changes a later piece's onset
    again = []
    real = chunked._estimate_again
    monkeypatch.setattr(chunked._LatchGuess, "next", lambda self: guess)
    monkeypatch.setattr(chunked, "_estimate_again", lambda *a: again.append(1) or real(*a))
    two = _pieces(t, w, config, 70, 2)
    assert again  # some guess was wrong, and that piece was estimated again
    for k, ((ea, _), (eb, _)) in enumerate(zip(one, two)):
        _same(ea, eb, f"piece {k}")


def test_a_consumer_that_stops_ends_the_workers(monkeypatch) -> None:
    pools = []
    start = chunked._start_pool
    monkeypatch.setattr(chunked, "_start_pool", lambda *a: pools.append(start(*a)) or pools[-1])
    t, w = _log(seed=2, presses=10)
    it = estimate_pieces(_blocks(t, w, 41), "murakami2006", EstimatorConfig(), 60, jobs=3)
    next(it)
    workers = list(pools[0]._processes.values())
    assert len(workers) == 2  # and this process
    it.close()
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and any(p.is_alive() for p in workers):
        time.sleep(0.05)
    assert not any(p.is_alive() for p in workers)


def test_jobs_must_be_positive() -> None:
    t, w = _log(seed=1, presses=1)
    with pytest.raises(ValueError, match="jobs = 0"):
        next(estimate_pieces(_blocks(t, w, 50), "murakami2006", None, 60, jobs=0))


def run(*args: object, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([SOFTTIP, *map(str, args)], capture_output=True, text=True, timeout=300, check=False, **kw)


@pytest.mark.parametrize("fmt", ["csv", "parquet"])
@pytest.mark.parametrize("options", [[], ["--lowpass-hz", 20, "--contact-point", "line-fit", "--relatch-distance", "1mm"]], ids=["default", "line-fit"])
def test_cli_jobs_2_writes_the_bytes_of_jobs_1(tmp_path: Path, fmt: str, options: list) -> None:
    t, w = _log(seed=11, presses=12)
    src = tmp_path / f"in.{fmt}"
    write_table({"t": t, **{k: w[:, i] for i, k in enumerate(WRENCH)}, "trial": np.full(len(t), "a")}, src)
    outs = {}
    for jobs in (1, 2):
        dest = tmp_path / f"out{jobs}.{fmt}"
        done = run("estimate", src, "-o", dest, "--chunk-rows", 60, "--jobs", jobs, "--save-bias", tmp_path / f"b{jobs}.toml", *options)
        assert done.returncode == 0, done.stderr
        outs[jobs] = (dest.read_bytes(), done.stderr.replace(str(dest), "OUT").replace(f"b{jobs}.toml", "B"))
    assert outs[1] == outs[2]
    assert "contact 10:" in outs[1][1]
    assert (tmp_path / "b1.toml").read_bytes() == (tmp_path / "b2.toml").read_bytes()


def test_cli_jobs_is_checked(tmp_path: Path) -> None:
    done = run("estimate", "--example", "-o", tmp_path / "o.csv", "--jobs", 0)
    assert done.returncode == 2 and "--jobs" in done.stderr
    assert os.listdir(tmp_path) == []


def _descendants(pid: int) -> list[int]:
    """Process ids below ``pid`` (Linux /proc): the forkserver's workers are grandchildren."""
    parents = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                parents[int(entry.name)] = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
            except OSError:
                continue
    found, todo = [], [pid]
    while todo:
        p = todo.pop()
        kids = [c for c, pp in parents.items() if pp == p]
        found += kids
        todo += kids
    return found


def _alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux /proc")
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_cli_jobs_signal_ends_workers_and_leaves_no_output(tmp_path: Path, sig: int) -> None:
    t, w = _log(seed=12, presses=40)
    reps = 60  # a log the workers take seconds over
    t = np.concatenate([t + k * (t[-1] + 0.01) for k in range(reps)])
    w = np.tile(w, (reps, 1))
    src = tmp_path / "in.parquet"
    write_table({"t": t, **{k: w[:, i] for i, k in enumerate(WRENCH)}}, src)
    proc = subprocess.Popen(
        [SOFTTIP, "estimate", str(src), "-o", "out.csv", "--chunk-rows", "2000", "--jobs", "2", "--save-bias", "b.toml"],
        cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )  # fmt: skip
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and len(_descendants(proc.pid)) < 2 and proc.poll() is None:
        time.sleep(0.05)  # the forkserver and its worker
    below = _descendants(proc.pid)
    assert proc.poll() is None and len(below) >= 2, proc.stderr.read().decode() if proc.poll() is not None else below
    time.sleep(0.5)
    proc.send_signal(sig)
    try:
        _, err = proc.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        proc.kill()
        raise
    err = err.decode()
    assert proc.returncode == 128 + sig, err
    assert "Traceback" not in err
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and any(_alive(p) for p in below):
        time.sleep(0.05)
    assert not any(_alive(p) for p in below)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.parquet"]


def test_a_piece_crosses_through_shared_memory_or_in_the_pickle(tmp_path: Path) -> None:
    """A worker's estimates come back through a file, removed when mapped; without a file
    (shared memory full, no such folder) in the pickle, no file left."""
    t, w = _log(seed=3, presses=2)
    est = _pieces(t, w, EstimatorConfig(), 10**6, 1)[0][0]
    path = tmp_path / "piece"
    shared = chunked._to_shared(est, str(path))
    assert shared[1] is not None and path.exists()
    _same(est, chunked._from_shared(shared, str(path)), "mapped")
    assert not path.exists()
    nowhere = tmp_path / "missing" / "piece"
    shared = chunked._to_shared(est, str(nowhere))
    assert shared[1] is None
    _same(est, chunked._from_shared(shared, str(nowhere)), "pickled")
    assert sorted(os.listdir(tmp_path)) == []


def test_cli_jobs_2_wrong_units_fall_back_to_the_one_shot_message(tmp_path: Path) -> None:
    """A log in kgf and kgf·mm read as SI: with --jobs 2 the one-shot run's message, exit 2, nothing written."""
    t, w = _log(seed=8, presses=3)
    src = tmp_path / "kgf.csv"
    write_table({"t": t, **{k: (w[:, i] / 9.80665) * (1e3 if i >= 3 else 1.0) for i, k in enumerate(WRENCH)}}, src)
    dest = tmp_path / "out.csv"
    one, two = run("estimate", src, "-o", dest), run("estimate", src, "-o", dest, "--chunk-rows", 50, "--jobs", 2)
    assert one.returncode == two.returncode == 2
    assert "--units kgf-mm" in two.stderr and two.stderr == one.stderr
    assert sorted(os.listdir(tmp_path)) == ["kgf.csv"]


@pytest.mark.skipif(not hasattr(__import__("socket"), "AF_UNIX"), reason="the pool's server socket is a Unix socket")
def test_cli_jobs_with_a_temporary_folder_too_long_for_a_socket(tmp_path: Path) -> None:
    """A TMPDIR whose path leaves no room for the pool's server socket (a Unix socket address
    holds about 107 bytes): the pool's private folder goes elsewhere, the run gives the bytes
    of --jobs 1 and leaves nothing in TMPDIR (it stopped with 'AF_UNIX path too long')."""
    t, w = _log(seed=5, presses=3)
    src = tmp_path / "in.csv"
    write_table({"t": t, **{k: w[:, i] for i, k in enumerate(WRENCH)}}, src)
    long_tmp = tmp_path / ("t" * (110 - len(str(tmp_path))))
    long_tmp.mkdir()
    assert len(str(long_tmp)) >= 110
    env = {**os.environ, "TMPDIR": str(long_tmp)}
    one = run("estimate", src, "-o", tmp_path / "one.csv", "--chunk-rows", 50, "-q")
    two = run("estimate", src, "-o", tmp_path / "two.csv", "--chunk-rows", 50, "--jobs", 2, "-q", env=env)
    assert one.returncode == 0 and two.returncode == 0, two.stderr
    assert (tmp_path / "one.csv").read_bytes() == (tmp_path / "two.csv").read_bytes()
    assert os.listdir(long_tmp) == []
