"""A log's pieces estimated on threads (``estimate_pieces(..., jobs=2)``, ``softtip estimate
--jobs 2``) give the bits of the pieces estimated one after the other (``jobs=1``); the
compiled loops they run release the interpreter, the stream's per-sample steps keep it."""

from __future__ import annotations

import dataclasses
import os
import signal
import subprocess
import sys
import time
import types
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
def test_pieces_on_threads_give_the_bits_of_jobs_1(name: str) -> None:
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


@pytest.mark.parametrize("jobs", [1, 2])
@pytest.mark.parametrize("guess", [None, True, False])
def test_after_runs_on_each_piece_as_handed_out(monkeypatch, jobs: int, guess: bool | None) -> None:
    """``after`` of each piece is its result on the estimates handed out, on a wrongly guessed
    piece too (done again with them), on the pool's threads when there are some."""
    t, w = _log(seed=9, presses=8)
    config = EstimatorConfig(relatch_distance=1e-3)
    if guess is not None:
        monkeypatch.setattr(chunked._LatchGuess, "next", lambda self: guess)
    where = set()

    def after(est, extra):
        import threading

        where.add(threading.current_thread().name.split("_")[0])
        return float(np.nansum(est.angle)), int(est.relatched.sum()), len(est)

    pieces = list(estimate_pieces(_blocks(t, w, 41), "murakami2006", config, 70, jobs=jobs, after=after))
    plain = _pieces(t, w, config, 70, 1)
    assert len(pieces) == len(plain) > 3
    for k, ((est, _extra, done), (ref, _)) in enumerate(zip(pieces, plain)):
        _same(est, ref, f"piece {k}")
        _same(done, (float(np.nansum(ref.angle)), int(ref.relatched.sum()), len(ref)), f"piece {k} after")
    assert ("softtip-piece" in where) == (jobs > 1)


def _threads(prefix: str) -> list:
    import threading

    return [th for th in threading.enumerate() if th.name.startswith(prefix)]


def test_a_consumer_that_stops_ends_the_threads(monkeypatch) -> None:
    """Closing the pieces stops the reading thread at once and starts no further piece; the
    pool's threads end when the pieces they hold are done."""
    started = []
    real = chunked._estimate_piece
    monkeypatch.setattr(chunked, "_estimate_piece", lambda *a: started.append(1) or real(*a))
    t, w = _log(seed=2, presses=30)
    it = estimate_pieces(_blocks(t, w, 41), "murakami2006", EstimatorConfig(), 60, jobs=3)
    next(it)
    assert _threads("softtip-read") and _threads("softtip-piece")
    it.close()
    assert not _threads("softtip-read")
    count = len(started)
    assert count < len(_pieces(t, w, EstimatorConfig(), 60, 1))  # not all were started
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and _threads("softtip-piece"):
        time.sleep(0.05)
    assert not _threads("softtip-piece") and len(started) == count


def test_an_error_while_reading_comes_after_the_pieces_before_it() -> None:
    """A bad block (time going back) stops the run in the caller's thread once the pieces read
    before it are handed out, as with jobs=1; the reading thread has ended."""
    t, w = _log(seed=6, presses=6)
    blocks = _blocks(t, w, 41)
    bad = len(blocks) * 2 // 3
    tb, wb, xb = blocks[bad]
    blocks[bad] = (tb - 1.0, wb, xb)
    got = {}
    for jobs in (1, 2):
        got[jobs] = []
        with pytest.raises(ValueError, match="time must not go back"):
            for est, _ in estimate_pieces(iter(blocks), "murakami2006", None, 60, jobs=jobs):
                got[jobs].append(est)
    assert len(got[1]) == len(got[2]) > 3
    assert sum(len(e) for e in got[1]) <= bad * 41
    for k, (a, b) in enumerate(zip(got[1], got[2])):
        _same(a, b, f"piece {k}")
    assert not _threads("softtip-read")


def test_jobs_must_be_positive() -> None:
    t, w = _log(seed=1, presses=1)
    with pytest.raises(ValueError, match="jobs = 0"):
        next(estimate_pieces(_blocks(t, w, 50), "murakami2006", None, 60, jobs=0))


def run(*args: object, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([SOFTTIP, *map(str, args)], capture_output=True, text=True, timeout=300, check=False, **kw)


@pytest.mark.parametrize("fmt", ["csv", "parquet", "arrow"])
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


@pytest.mark.parametrize("fmt", ["csv", "parquet"])
def test_cli_jobs_2_and_the_default_on_standard_output(tmp_path: Path, fmt: str) -> None:
    """Onto standard output (each piece written as it is done), --jobs 2 and no --jobs (both
    cores where there are two) give the bytes of --jobs 1."""
    t, w = _log(seed=13, presses=10)
    src = tmp_path / f"in.{fmt}"
    write_table({"t": t, **{k: w[:, i] for i, k in enumerate(WRENCH)}}, src)
    outs = []
    for jobs in (["--jobs", 1], ["--jobs", 2], []):
        done = subprocess.run([SOFTTIP, "estimate", str(src), "--chunk-rows", "70", *map(str, jobs)], capture_output=True,
                              timeout=300, check=False)  # fmt: skip
        assert done.returncode == 0, done.stderr
        outs.append((done.stdout, done.stderr))
    assert outs[0] == outs[1] == outs[2]
    assert outs[0][0].count(b"\n") == len(t) + 1


def test_cli_jobs_is_checked(tmp_path: Path) -> None:
    done = run("estimate", "--example", "-o", tmp_path / "o.csv", "--jobs", 0)
    assert done.returncode == 2 and "--jobs" in done.stderr
    assert os.listdir(tmp_path) == []


def _threads_of(pid: int) -> int:
    """Threads of a process (Linux /proc)."""
    try:
        return len(os.listdir(f"/proc/{pid}/task"))
    except OSError:
        return 0


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux /proc")
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_cli_jobs_signal_while_the_threads_run_leaves_no_output(tmp_path: Path, sig: int) -> None:
    t, w = _log(seed=12, presses=40)
    reps = 60  # a log the threads take seconds over
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
    while time.monotonic() < deadline and _threads_of(proc.pid) < 4 and proc.poll() is None:
        time.sleep(0.05)  # the reading thread and two estimating
    assert proc.poll() is None, proc.stderr.read().decode()
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
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.parquet"]


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


_POOL_IN_LONG_TMP = """
from softtip.apps.pool import _end_with_parent, end_pool, start_pool
pool = start_pool(2, _end_with_parent)
print(sorted(pool.map(abs, [-1, -2, -3])))
end_pool(pool)
"""


@pytest.mark.skipif(not hasattr(__import__("socket"), "AF_UNIX"), reason="the pool's server socket is a Unix socket")
def test_the_process_pool_with_a_temporary_folder_too_long_for_a_socket(tmp_path: Path) -> None:
    """A TMPDIR whose path leaves no room for the process pool's server socket (``softtip
    reproduce --jobs``; a Unix socket address holds about 107 bytes): the pool's private folder
    goes elsewhere, the pool runs and leaves nothing in TMPDIR (it stopped with 'AF_UNIX path
    too long')."""
    long_tmp = tmp_path / ("t" * (110 - len(str(tmp_path))))
    long_tmp.mkdir()
    assert len(str(long_tmp)) >= 110
    env = {**os.environ, "TMPDIR": str(long_tmp)}
    done = subprocess.run([sys.executable, "-c", _POOL_IN_LONG_TMP], capture_output=True, text=True, timeout=300, env=env)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[0] == "[1, 2, 3]"
    assert os.listdir(long_tmp) == []


def _dispatchers(obj, found: dict, path: str, seen: set) -> dict:
    """The numba dispatchers an object of softtip holds, by attribute path."""
    from numba.core.dispatcher import Dispatcher

    if id(obj) in seen:
        return found
    seen.add(id(obj))
    if isinstance(obj, Dispatcher):
        found[path] = obj
    elif isinstance(obj, types.FunctionType) and obj.__module__.startswith("softtip"):  # a closure's
        for k, cell in enumerate(obj.__closure__ or ()):
            _dispatchers(cell.cell_contents, found, f"{path}.<closure {k}>", seen)
    elif type(obj).__module__.startswith("softtip"):
        names = list(getattr(obj, "__dict__", {}))
        names += [k for cls in type(obj).__mro__ for k in getattr(cls, "__slots__", ())]
        for k in names:
            if hasattr(obj, k):
                _dispatchers(getattr(obj, k), found, f"{path}.{k}", seen)
    return found


def test_stream_steps_keep_the_interpreter_and_every_other_compiled_function_releases_it() -> None:
    """Pieces of a log run in parallel only if the batch's compiled functions release the
    interpreter; a step the stream calls per sample from Python keeps it (a release mid-update
    hands it to a live run's other threads: the performance page's live soak). Checked on the
    flags the functions are built with: the functions the stream holds, over four
    configurations, are exactly those built ``nogil=False``."""
    pytest.importorskip("numba")
    import softtip.io.tables  # noqa: F401 - its compiled CSV formatter too
    from softtip import Estimator
    from softtip.core._jit import _Lazy, set_jit

    old = set_jit(True)
    try:
        held = {}
        for name in ("default", "lowpass", "line-fit", "track"):
            config = dataclasses.replace(CONFIGS[name], sample_rate=100.0)  # a stream's filter needs the rate
            _dispatchers(Estimator("murakami2006", config), held, name, set())
    finally:
        set_jit(old)
    assert "default._contacts._step" in held and "lowpass._filter._step" in held
    assert not any(d.targetoptions["nogil"] for d in held.values())
    lazy = {id(v.py_func): v for m in list(sys.modules.values()) if m and m.__name__.startswith("softtip.")
            for v in vars(m).values() if isinstance(v, _Lazy)}  # fmt: skip
    assert len(lazy) > 30
    kept = {v.__name__ for v in lazy.values() if not v.nogil}
    assert kept == {lazy[id(d.py_func)].__name__ for d in held.values()}
