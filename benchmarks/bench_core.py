"""Throughput of the contact solvers and latency of the streaming pipeline.

    python benchmarks/bench_core.py [--samples 1000000]

Prints batch samples/s for each fingertip shape (one core: numpy runs these kernels on one
thread) and the median and 99th-percentile time of one sample through the streaming
estimator, over all samples and over the samples in contact (the estimate's state not
``none``). Targets (manual §6, issue 31): streaming median <= 15 us, p99 <= 50 us in contact.

The live soak (--only soak, --soak-seconds 60, --soak-rate 7000): the fake Net F/T in a
process of its own streams grasps in contact about 90 % of the time over loopback UDP,
through softtip's receive thread, the streaming estimator and the CSV recorder, once with the
terminal and Rerun views on and once with them off (benchmarks/bench_live.py --soak says how):
samples lost and dropped (target 0), every counter, the latency from arrival to estimate
(median, p99, p99.9, max) in contact and over all, Estimator.update's own time in contact.

Then `softtip estimate` end to end on a --samples-row log (the 1 kHz example grasp
repeated), CSV and Parquet side by side: read (softtip.io.tables.read_log), the pipeline
(softtip.estimate), write (softtip.io.tables.write_table), their total, and the `softtip estimate`
command itself (a new process: Python start-up and imports included), in rows/s, with its
peak memory, by default (pieces of 131072 rows for a log this large) and in one piece; also the
hand-written Python CSV reader and writer that softtip used before, on the same files.
Rates are rows per second of CPU time (the process's own, or the command's): on a shared
machine that is the steady figure; the wall-clock time is printed beside it. Targets (manual §6) end to end, per core: CSV >= 0.4 M rows/s, Parquet >= 1 M rows/s.
Only this part: --only end-to-end; only the streaming rows: --only stream (with a sensor's first
touch: the estimator built in a fresh process, numba's cache warm and empty, with and without
its warm-up, and the slowest update of the grasp after it).

Bounds (--only bounds): pyarrow reading the log and softtip's own writers (write_table, with
the project's settings: the compiled CSV formatter, lean Parquet, uncompressed Arrow IPC)
writing the least output the command line contract allows (24 columns), and numpy filling that
many columns: what any `softtip estimate` must stay below, whatever its pipeline. Then the CSV
number formatters side by side (compiled, its fallback, pyarrow's own, printf) in ns per
number, the Parquet / Arrow IPC compressions measured on all the estimates' columns (and
softtip's Parquet settings with every column nullable, as before its numbers were declared
required), the log's CSV parsed by pyarrow as softtip's reader runs it and by pandas' C
engine, and the log's Parquet read in fresh processes memory-mapped and not.

Compiled (--only compiled): the pipeline at 2e4 rows with the stages' step functions compiled
by numba and run as Python (the same source; the path without numba), and the start-up cost of
the compiled steps (importing numba; the first call, compiling them or loading them from the cache).

Scaling (--only scaling, --sizes 1e5,1e6,1e7): at each log length, in a process of its own,
the contact kernel, the whole pipeline and end to end (read + estimate + write, Parquet and
CSV) side by side in rows per CPU second, the kernel/pipeline ratio, and the peak memory of
the pipeline per row (peak resident memory beyond its inputs). Then, in the same processes, the
pipeline (softtip.estimate) against its compiled reference for the default configuration, a
20 Hz low-pass, re-latching (2 mm) and line-fit: the reference is the same computation with
nothing around it, the pipeline's compiled loops (contact tracking, the contact point, the line
fit, then normal, depth, measurement and evidence with every output column;
softtip.estimator.pipeline, where each stage's step is called once per sample) and the low-pass
filter, run back to back with no validation, tare or Python between them, their outputs
allocated per call (as the pipeline's) and on buffers allocated once and reused (no page
faults: memory the process already has); the ratio is the reference's time over the pipeline's.
Target (manual §6, issue 31): pipeline >= 0.8x the reference, >= 3 M rows/s per core where the
computation allows it, <= 400 B/row.

Both cores (--only jobs): `softtip estimate --jobs 1`, `--jobs 2` and without --jobs (the
default) on the same --samples-row log, CSV -> CSV and Parquet -> Parquet, three runs each,
alternating: wall time, CPU time of the whole command (every thread), peak memory, the load
average before each run, and whether the outputs are the same bytes; then where the CPU time
goes on one thread: the command's start-up (interpreter, imports, compiled kernels loaded) and
each stage of the pieces (read, cut: the sequential stages, which find the cut; the per-contact stages; columns; write), from which the
critical path on two cores follows. Target (issue 31): >= 1.7x in wall time on 2 cores. On a
machine shared with other work the wall-time ratio is bounded by the share of the cores the run
gets: the CPU times say what the threads cost.

Mesh rows: the shipped mesh fingertip (the papers' capsule with a nail, 21.6k triangles),
contact location per sample (streaming kernel, median and p99 of CPU time; target median <=
50 us) on the example grasp's samples in contact (a contact moving continuously, noise
included) and on independent pushes within friction all over the skin (see plausible_wrenches,
the worst case), in batch, and the whole pipeline with the mesh tip.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from softtip import (
    Capsule,
    Ellipsoid,
    Estimator,
    EstimatorConfig,
    ImplicitSurface,
    Sphere,
    contact_from_wrench,
    estimate,
)
from softtip.sim.synthetic import synthetic_grasp

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _markdown import markdown_option, run_with_markdown  # noqa: E402


def pushing_wrenches(tip, n, rng):
    centre, radius = tip.bounding_sphere
    u = rng.normal(size=(n, 3))
    u[:, 2] = np.abs(u[:, 2])
    r = tip.project(centre + 3 * radius * u / np.linalg.norm(u, axis=1, keepdims=True))
    nrm = tip.normal(r)
    f = -rng.uniform(0.1, 10.0, (n, 1)) * nrm + rng.normal(scale=0.3, size=(n, 3))
    f = np.where(np.sum(f * nrm, axis=1, keepdims=True) < 0, f, -nrm)
    m = np.cross(r, f) + rng.uniform(-3e-3, 3e-3, (n, 1)) * nrm
    return np.ascontiguousarray(np.concatenate((f, m), axis=1))


def benchmark_grasp():
    """The benchmarks' grasp: 10 s of the murakami2006 tip on a line at 45°, 1 kHz."""
    return synthetic_grasp("murakami2006", angle_deg=45.0, duration=10.0, rate=1000.0, seed=1)


def grasp_log(n: int, *, whole: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """The benchmarks' log: the 10 s, 1 kHz synthetic grasp at 45° repeated, stamps at 1 ms.
    ``whole``: as many whole grasps as fit in ``n`` rows (at least one); else exactly ``n`` rows."""
    g = benchmark_grasp()
    if whole:
        reps = max(1, n // len(g.t))
        return np.arange(reps * len(g.t)) * 1e-3, np.tile(g.wrench, (reps, 1))
    return np.arange(n) * 1e-3, np.tile(g.wrench, (-(-n // len(g.t)), 1))[:n]


def best_of(fn, repeats):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def _bytecode_kept() -> None:
    """The commands this benchmark times keep their bytecode (:func:`softtip.testing._bytecode.keep_bytecode`)
    where ``PYTHONDONTWRITEBYTECODE`` is set: else each ``softtip`` subprocess compiles its sources
    again, which an installed softtip never does (start-up measured 1.66 s of CPU instead of
    1.09 s). The directory is filled before anything is timed and removed at the end."""
    import atexit
    import shutil

    from softtip.testing._bytecode import keep_bytecode

    prefix = keep_bytecode()
    if prefix is None:
        return
    atexit.register(shutil.rmtree, prefix, ignore_errors=True)
    subprocess.run([str(Path(sys.executable).with_name("softtip")), "--version"], capture_output=True)
    subprocess.run([sys.executable, "-c", "import numba, pyarrow.parquet, scipy.linalg, softtip.cli.estimate"],
                   capture_output=True)  # fmt: skip


def main(argv: list[str] | None = None) -> None:
    _bytecode_kept()
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    markdown_option(ap)
    ap.add_argument("--samples", type=int, default=1_000_000)
    ap.add_argument("--stream-samples", type=int, default=20_000)
    ap.add_argument("--only", choices=["end-to-end", "stream", "soak", "scaling", "compiled", "bounds", "jobs"], help="Run only this part.")
    ap.add_argument("--soak-seconds", type=float, default=60.0, help="s of each live soak session (default 60)")
    ap.add_argument("--soak-rate", type=float, default=7000.0, help="Hz of the live soak (default 7000)")
    ap.add_argument("--sizes", default="1e5,1e6,1e7", help="log lengths of the scaling table (comma-separated)")
    ap.add_argument("--scaling-worker", type=float, help=argparse.SUPPRESS)
    ap.add_argument("--first-contact-worker", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--mesh-only", action="store_true", help="only the mesh fingertip rows")
    args = ap.parse_args(argv)
    rng = np.random.default_rng(6)
    if args.mesh_only:
        print(f"softtip core benchmark | python {platform.python_version()} | numpy {np.__version__} | {platform.machine()}")
        mesh_rows(args, rng)
        return
    if args.scaling_worker:
        scaling_worker(int(args.scaling_worker))
        return
    if args.first_contact_worker is not None:
        first_contact_worker(args.first_contact_worker)
        return
    n = args.samples
    print(f"softtip core benchmark | python {platform.python_version()} | numpy {np.__version__} | {platform.machine()}")
    if args.only == "end-to-end":
        end_to_end(n)
        return
    if args.only == "stream":
        stream_rows(args, benchmark_grasp())
        first_contact_rows()
        return
    if args.only == "soak":
        soak_rows(args)
        return
    if args.only == "scaling":
        scaling([int(float(x)) for x in args.sizes.split(",")])
        return
    if args.only == "compiled":
        compiled_rows()
        return
    if args.only == "bounds":
        bounds(n)
        return
    if args.only == "jobs":
        both_cores(n)
        return
    print(f"batch contact location, {n:,} samples (best of 3; general solver: 1 run)")

    capsule = Capsule(0.016, 0.020)
    ellipsoid = Ellipsoid((0.014, 0.016, 0.022), center=(0.0, 0.0, 0.01))
    c = np.array(ellipsoid.center)
    a = np.array(ellipsoid.semi_axes)
    implicit = ImplicitSurface(
        function=lambda p: np.sum(((p - c) / a) ** 2, -1) - 1.0,
        gradient=lambda p: 2 * (p - c) / a**2,
        hessian=lambda p: np.broadcast_to(np.diag(2 / a**2), p.shape + (3,)),
        center=c,
        radius=float(a.max()),
    )
    shapes = [
        ("sphere", Sphere(0.016, center=(0.0, 0.0, 0.02)), 3),
        ("capsule", capsule, 3),
        ("ellipsoid", ellipsoid, 3),
        ("general (implicit ellipsoid)", implicit, 1),
    ]
    for name, tip, repeats in shapes:
        w = pushing_wrenches(ellipsoid if tip is implicit else tip, n, rng)
        dt = best_of(lambda: contact_from_wrench(w, tip), repeats)
        print(f"  {name:30s} {n / dt / 1e6:8.2f} M samples/s   ({dt:.3f} s)")

    t_rep, w_rep = grasp_log(args.samples)
    dt = best_of(lambda: estimate(t_rep, w_rep, "murakami2006"), 3)
    print(f"  {'whole batch pipeline (capsule)':30s} {len(t_rep) / dt / 1e6:8.2f} M samples/s   ({dt:.3f} s)")

    stream_rows(args, benchmark_grasp())
    first_contact_rows()
    soak_rows(args)
    end_to_end(n)
    bounds(n)
    compiled_rows()
    both_cores(n)
    scaling([int(float(x)) for x in args.sizes.split(",")])
    mesh_rows(args, rng)


def soak_rows(args) -> None:
    """The live soak of ``bench_live.py`` (views on, then off)."""
    from bench_live import soak_rows as soak

    soak(args.soak_rate, args.soak_seconds)


def stream_rows(args, g) -> None:
    """Median and p99 time of one sample of the 1 kHz grasp ``g`` through :class:`Estimator`,
    over all samples and over those in contact (the estimate's state not ``none``); each
    configuration three times, the pass with the lowest median in contact. The last row idles
    100 µs before each sample, as a thread fed by a 7 kHz sensor does (a sleep, then the
    update): its caches and the core's clock are those of a live session, not of a tight loop."""
    print(f"streaming pipeline, one sample at a time ({min(args.stream_samples, len(g.t)):,} samples of a 1 kHz grasp, best of 3)")
    for label, cfg, idle in (
        ("latch, no filter (online depth)", EstimatorConfig(), 0.0),
        ("latch, the papers' method", EstimatorConfig(depth_compensation="off"), 0.0),
        ("latch, --no-line-evidence", EstimatorConfig(line_evidence=False), 0.0),
        ("latch, 4th-order low-pass", EstimatorConfig(lowpass_hz=30.0, sample_rate=1000.0, lowpass_order=4), 0.0),
        ("track", EstimatorConfig(contact_point="track"), 0.0),
        ("latch, 100 us idle between", EstimatorConfig(), 100e-6),
    ):
        ts = g.t[: args.stream_samples]
        ws = g.wrench[: args.stream_samples].tolist()
        best = None
        for _ in range(3):  # the pass with the lowest median in contact (a shared machine)
            est = Estimator("murakami2006", cfg)
            per = np.empty(len(ts))
            contact = np.empty(len(ts), dtype=bool)
            clock, sleep = time.perf_counter, time.sleep
            for i, (t, w) in enumerate(zip(ts.tolist(), ws)):
                if idle:
                    sleep(idle)
                t0 = clock()
                e = est.update(t, w)
                per[i] = clock() - t0
                contact[i] = e.state != "none"
            if best is None or np.median(per[contact]) < np.median(best[0][contact]):
                best = per, contact
        per, contact = best
        if not contact.any():  # the targets are about the samples in contact
            raise SystemExit(f"bench_core.py: --stream-samples {args.stream_samples}: no sample in contact (the grasp "
                             "touches about 2 s in, sample 2,000 at 1 kHz); give more samples")  # fmt: skip
        print(
            f"  {label:30s} median {np.median(per) * 1e6:6.1f} us   p99 {np.percentile(per, 99) * 1e6:6.1f} us"
            f"   (in contact, {contact.mean():.0%}: median {np.median(per[contact]) * 1e6:6.1f} us"
            f"   p99 {np.percentile(per[contact], 99) * 1e6:6.1f} us)"
        )


#: In a fresh process (``--first-contact-worker``): build an Estimator for a sensor (length unknown,
#: with its warm-up) or for a replay of known length (no warm-up; SOFTTIP_NUMBA=1 keeps it compiled),
#: then stream the benchmarks' grasp; prints the build's time and the slowest update.
def first_contact_worker(expected: int) -> None:
    g = benchmark_grasp()
    t0 = time.perf_counter()
    est = Estimator("murakami2006", expected_samples=expected or None)
    build = time.perf_counter() - t0
    slowest, at, state, clock = 0.0, 0, "", time.perf_counter
    for i, (t, w) in enumerate(zip(g.t.tolist(), g.wrench.tolist())):
        t0 = clock()
        e = est.update(t, w)
        dt = clock() - t0
        if dt > slowest:
            slowest, at, state = dt, i, e.state
    print(json.dumps({"build": build, "slowest": slowest, "at": at, "state": state}))


def first_contact_rows() -> None:
    """A sensor's first contact: each way of building the estimator in a fresh process, with
    numba's disk cache as it is (warm) and empty (``NUMBA_CACHE_DIR`` a new folder: the first run
    after installing)."""
    print("a sensor's first touch: Estimator built, then the 1 kHz grasp streamed, in a fresh process; "
          "the build's wall time and the slowest update (the sample, its state)")  # fmt: skip
    for cache in ("warm", "empty"):
        for label, expected in (("for a sensor (with its warm-up)", 0), ("without the warm-up (length given)", 100_000)):
            with tempfile.TemporaryDirectory() as tmp:
                env = {**os.environ, "SOFTTIP_NUMBA": "1", **({"NUMBA_CACHE_DIR": tmp} if cache == "empty" else {})}
                out = subprocess.run([sys.executable, __file__, "--first-contact-worker", str(expected)], env=env,
                                     capture_output=True, text=True, check=True).stdout  # fmt: skip
            r = json.loads(out.strip().splitlines()[-1])
            print(f"  cache {cache:5s} {label:36s} build {r['build'] * 1e3:8.1f} ms   slowest update "
                  f"{r['slowest'] * 1e3:8.1f} ms (sample {r['at']:,}, {r['state']})")


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def _peak_rss() -> int:
    """Peak resident memory of this process, bytes. Linux: ``VmHWM`` of ``/proc/self/status``,
    the high-water mark of this process's own memory (``ru_maxrss`` starts a process made by
    fork and exec at its parent's peak, so a worker of a large parent measured nothing);
    elsewhere ``ru_maxrss``."""
    try:
        with open("/proc/self/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def scaling_worker(n: int) -> None:
    """One row of :func:`scaling` in a process of its own: prints ``key=value`` pairs."""
    import json
    import warnings

    import softtip.io.tables as sio
    from softtip import load_fingertip
    from softtip.core._jit import use_numba
    from softtip.core.location import contact_arrays

    warnings.simplefilter("ignore")
    t, w = grasp_log(n, whole=False)
    tip = load_fingertip("murakami2006")
    # at least 2: the first call of a size pays the fresh mappings of its outputs, whose page-fault cost
    # varies by seconds at 1e7 rows (huge-page compaction); one call made the first-measured look slower
    repeats = 2 if n >= 5_000_000 else 3
    # warm up: imports, the compiled steps' cache (not what a row of the table measures)
    estimate(t[:5000], w[:5000], tip)
    res: dict[str, float | bool] = {"n": n, "compiled": use_numba()}
    # the pipeline's peak first: the high-water mark must not already hold another run's
    base = _peak_rss()
    cpu = []
    for _ in range(repeats):
        cpu.append(_timed_cpu(lambda: estimate(t, w, tip)))
        if len(cpu) == 1:
            res["peak_bytes"] = _peak_rss() - base
    res["pipeline"] = min(cpu)
    cols = [np.ascontiguousarray(w[:, i]) for i in range(6)]
    res["kernel"] = min(_timed_cpu(lambda: contact_arrays(tip, *cols)) for _ in range(repeats))
    cols = None
    sets = {}
    for name, config in OPTION_SETS.items():
        estimate(t[:5000], w[:5000], tip, config)  # warm up (the compiled loops of this setting)
        ref, fresh = pipeline_reference(t, w, tip, config), pipeline_reference(t, w, tip, config, reuse=False)
        ref()
        sets[name] = (min(_timed_cpu(lambda: estimate(t, w, tip, config)) for _ in range(repeats)),
                      min(_timed_cpu(fresh) for _ in range(repeats)), min(_timed_cpu(ref) for _ in range(repeats)))  # fmt: skip
        ref = fresh = None
    res["sets"] = sets
    with tempfile.TemporaryDirectory() as tmp:
        for fmt in ("parquet", "csv"):
            src, dest = Path(tmp, f"in.{fmt}"), Path(tmp, f"out.{fmt}")
            sio.write_table({"t": t, **{k: w[:, i] for i, k in enumerate(("fx", "fy", "fz", "mx", "my", "mz"))}}, src)

            def run():
                log = sio.read_log(src)
                sio.write_table(estimate(log.t, log.wrench, tip).columns(), dest)

            res[fmt] = min(_timed_cpu(run) for _ in range(1 if fmt == "csv" else repeats))
            src.unlink()
            dest.unlink()
    print(json.dumps(res))


#: The settings of the pipeline's table (--only scaling); the benchmark log is at 1 kHz.
OPTION_SETS = {
    "default": EstimatorConfig(),
    "low-pass 20 Hz": EstimatorConfig(lowpass_hz=20.0, sample_rate=1000.0),
    "re-latch 2 mm": EstimatorConfig(relatch_distance=2e-3),
    "line-fit": EstimatorConfig(contact_point="line-fit"),
}


def pipeline_reference(t, w, tip, config, reuse=True):
    """The pipeline's computation with nothing around it: a function running the low-pass filter
    (when configured) and the compiled loops of softtip.estimate (contact tracking, then
    softtip.estimator.pipeline's) on buffers allocated here once and reused (module docs), or
    allocated per call (``reuse`` False: what any run that returns new arrays pays)."""
    from softtip.core.filtering import sosfilt_state
    from softtip.estimator.batch import _sequential_stages
    from softtip.estimator.contact import contact_params, contact_run, new_contact_state
    from softtip.estimator.depth import resolve_depth
    from softtip.estimator.measure import noise_correlation
    from softtip.estimator.pipeline import fused_columns

    config = resolve_depth(config, tip)
    bias, taring, _, sos, noise, *_ = _sequential_stages(t, w, config, None)
    n, start = len(t), int(np.count_nonzero(taring))
    params, corr = contact_params(config, noise), noise_correlation(sos)
    cid, busy, contact = np.empty(n, dtype=np.int64), np.empty(n, dtype=bool), np.empty(n, dtype=bool)
    drift, y, out = np.empty((n, 6)), np.empty((n, 6)), {}
    run_contacts = contact_run.compiled()

    def run():
        nonlocal cid, busy, contact, drift, y
        if not reuse:
            cid, busy, contact = np.empty(n, dtype=np.int64), np.empty(n, dtype=bool), np.empty(n, dtype=bool)
            drift, y = np.empty((n, 6)), np.empty((n, 6))
        x, sub = (w, bias) if sos is None else (sosfilt_state(sos, w - bias, None)[0], np.zeros(6))
        run_contacts(t, x, start, new_contact_state(), params, sub, cid, busy, drift, y, n)
        np.greater(cid, 0, out=contact)
        cols = fused_columns(t, y, drift, contact, taring, tip, config, noise, corr, False, out=out if reuse else None)
        if cols is None:
            raise SystemExit("the reference needs the compiled pipeline (a closed-form fingertip, numba)")

    return run


def _timed_cpu(fn) -> float:
    c0 = _cpu()
    fn()
    return _cpu() - c0


_COMPILE_PROBE = """
import resource, time
def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF); return r.ru_utime + r.ru_stime
c0 = cpu()
import numba
c1 = cpu()
import warnings
warnings.simplefilter("ignore")
from softtip import EstimatorConfig, estimate
from softtip.core._jit import set_jit
from softtip.sim.synthetic import synthetic_grasp
g = synthetic_grasp("murakami2006", duration=10.0, rate=1000.0, seed=1)
set_jit(True)
c2 = cpu(); estimate(g.t, g.wrench, "murakami2006", EstimatorConfig(relatch_distance=3e-3)); c3 = cpu()
print(c1 - c0, c3 - c2)
"""


def compiled_rows() -> None:
    """The numbers behind numba: the pipeline with its stages' steps compiled and the same
    steps run as Python (the path without numba), and what compiling costs at start-up."""
    import warnings

    from softtip.core._jit import set_jit

    print("the stages' step functions compiled by numba vs the same source run as Python; CPU s, best of 2")
    warnings.simplefilter("ignore")
    for n in (20_000,):  # as Python, about 30 µs a row: longer logs take minutes
        t, w = grasp_log(n, whole=False)
        cpu = {}
        for flag in (False, True):
            set_jit(flag)
            estimate(t[:2000], w[:2000], "murakami2006")
            cpu[flag] = min(_timed_cpu(lambda: estimate(t, w, "murakami2006")) for _ in range(2))
        set_jit(None)
        print(
            f"  {n:9,d} rows: as Python {cpu[False]:6.2f} s ({n / cpu[False] / 1e6:5.3f} M/s), compiled"
            f" {cpu[True]:6.2f} s ({n / cpu[True] / 1e6:5.2f} M/s): {cpu[False] / cpu[True]:4.0f}×"
        )
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        for label in ("cold cache (first run after install)", "warm cache"):
            out = subprocess.run([sys.executable, "-c", _COMPILE_PROBE], capture_output=True, text=True, env=env)
            if out.returncode != 0:
                raise SystemExit(out.stderr)
            imp, first = (float(x) for x in out.stdout.split())
            print(f"  start-up, {label}: import numba {imp:.2f} s CPU, first compiled call (10k rows) {first:.2f} s CPU")


def scaling(sizes: list[int]) -> None:
    """Kernel, pipeline and end to end side by side at each log length, one process per
    length (its peak memory measured alone); rows per CPU second (user + system)."""
    import json

    print(
        "scaling: contact kernel (capsule closed form), the whole pipeline (softtip.estimate) and end to end"
        " (read + estimate + write, Parquet and CSV), rows per CPU second; best of 3 (2 at 5e6 rows and"
        " more; CSV: 1); peak memory of softtip.estimate beyond its inputs (peak RSS)"
    )
    head = f"  {'rows':>11s} {'kernel':>10s} {'pipeline':>10s} {'ratio':>6s} {'Parquet e2e':>12s} {'CSV e2e':>10s} {'peak B/row':>11s}"
    print(head)
    rows = []
    for n in sizes:
        done = subprocess.run(
            [sys.executable, __file__, "--scaling-worker", str(n)], capture_output=True, text=True
        )
        if done.returncode != 0:
            raise SystemExit(done.stderr)
        r = json.loads(done.stdout.strip().splitlines()[-1])
        rate = {k: n / r[k] / 1e6 for k in ("kernel", "pipeline", "parquet", "csv")}
        print(
            f"  {n:11,d} {rate['kernel']:6.2f} M/s {rate['pipeline']:6.2f} M/s {rate['kernel'] / rate['pipeline']:5.0f}×"
            f" {rate['parquet']:8.2f} M/s {rate['csv']:6.2f} M/s {r['peak_bytes'] / n:11.0f}"
            f"{'' if r['compiled'] else '   (steps run as Python: numba not installed or SOFTTIP_NUMBA=0)'}"
        )
        rows.append((n, r["sets"]))
    print(
        "pipeline (softtip.estimate) against its compiled reference (the same loops with nothing around them; their"
        " outputs allocated per call, and reused), rows per CPU second, same process; ratio = reference time /"
        " pipeline time (target >= 0.8)"
    )
    print(f"  {'rows':>11s} {'settings':16s} {'pipeline':>10s} {'ref. new':>10s} {'ratio':>6s} {'ref. reused':>11s} {'ratio':>6s}")
    for n, sets in rows:
        for name, (pipe, fresh, ref) in sets.items():
            print(
                f"  {n:11,d} {name:16s} {n / pipe / 1e6:6.2f} M/s {n / fresh / 1e6:6.2f} M/s {fresh / pipe:6.2f}"
                f" {n / ref / 1e6:7.2f} M/s {ref / pipe:6.2f}"
            )


def timed(fn, repeats=2):
    """Best wall-clock and best CPU time of ``repeats`` calls, and the last result."""
    wall, cpu, out = [], [], None
    for _ in range(repeats):
        w0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        wall.append(time.perf_counter() - w0)
        cpu.append(time.process_time() - c0)
    return min(wall), min(cpu), out


_MEASURE = """import os, resource, subprocess, sys
one = sys.argv[1] == "--one-core"
if one:  # the command and its threads on this process's first CPU alone
    os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
done = subprocess.run(sys.argv[1 + one:], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
u = resource.getrusage(resource.RUSAGE_CHILDREN)
print(done.returncode, u.ru_utime + u.ru_stime, u.ru_maxrss * 1024)
sys.stderr.write(done.stderr.decode())
"""


def command(cmd: list[str], *, one_core: bool = False) -> tuple[float, float, float]:
    """Wall time, CPU time (user + system) and peak resident memory (bytes) of a command
    (``one_core``: with every thread of it on one CPU, Linux's CPU affinity).

    Run through a small Python process: a child's peak memory on Linux starts from the size
    of the process that forked it, so the benchmark (GBs by now) must not be that one.
    """
    w0 = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", _MEASURE, *(["--one-core"] if one_core else []), *cmd], capture_output=True, text=True)
    wall = time.perf_counter() - w0
    code, cpu, peak = done.stdout.split()
    if done.returncode != 0 or code != "0":
        raise SystemExit(done.stderr)
    return wall, float(cpu), float(peak)


def end_to_end(n: int) -> None:
    import pyarrow

    import softtip.io.tables as sio
    from softtip.io.tables import read_log, write_table

    t, w = grasp_log(n)
    n = len(t)
    log_columns = {"t": t, **{name: w[:, i] for i, name in enumerate(("fx", "fy", "fz", "mx", "my", "mz"))}}
    print(f"softtip estimate end to end, {n:,}-row log (1 kHz grasp repeated), pyarrow {pyarrow.__version__}; best of 2 "
          "after an untimed pass of both formats")  # fmt: skip
    print(f"  {'stage':34s} {'CSV: rows per CPU second':>36s} {'Parquet':>36s}")

    def cell(wall, cpu):
        return f"{n / cpu / 1e6:6.2f} M/s (CPU {cpu:5.2f} s; wall {wall:5.2f} s)"

    with tempfile.TemporaryDirectory() as tmp:
        # The first calls in a process load numba's kernels and touch their memory for the first
        # time (the pipeline took 1.25 and 0.96 s on its first two 1e6-row calls, 0.31-0.34 s from
        # the third on): one untimed pass, so that neither format's figures carry it.
        for fmt in ("csv", "parquet"):
            src, dest = Path(tmp, f"in.{fmt}"), Path(tmp, f"out.{fmt}")
            write_table(log_columns, src)
            log = read_log(src)
            write_table(estimate(log.t, log.wrench, "murakami2006").columns(), dest)
        rows: dict[str, list[str]] = {}
        totals = {}
        for fmt in ("csv", "parquet"):
            src, dest = Path(tmp, f"in.{fmt}"), Path(tmp, f"out.{fmt}")
            write_table(log_columns, src)
            wr, cr, log = timed(lambda: read_log(src))
            we, ce, est = timed(lambda: estimate(log.t, log.wrench, "murakami2006"))
            cols = est.columns()
            ww, cw, _ = timed(lambda: write_table(cols, dest))
            size = os.path.getsize(dest) / 1e6
            totals[fmt] = (wr + we + ww, cr + ce + cw)
            rows.setdefault("read (read_log)", []).append(cell(wr, cr))
            rows.setdefault("pipeline (softtip.estimate)", []).append(cell(we, ce))
            rows.setdefault(f"write (write_table, {len(cols)} columns)", []).append(cell(ww, cw))
            rows.setdefault("total of the three", []).append(cell(*totals[fmt]))
            rows.setdefault("I/O alone (read + write)", []).append(cell(wr + ww, cr + cw))
            cmd = [str(Path(sys.executable).with_name("softtip")), "estimate", str(src), "-o", str(dest)]
            for label, extra in ((" (pieces of 131072)", []), (" in one piece", ["--chunk-rows", str(10 * n)])):
                runs = [command(cmd + extra) for _ in range(2)]  # best of 2, as the rows above; the larger peak
                wall, cpu, peak = min(r[0] for r in runs), min(r[1] for r in runs), max(r[2] for r in runs)
                rows.setdefault(f"`softtip estimate`{label}", []).append(cell(wall, cpu))
                rows.setdefault(f"  peak memory{label}", []).append(f"{peak / 1e9:8.2f} GB".ljust(36))
            rows.setdefault("output file size", []).append(f"{size:8.1f} MB".ljust(36))
        for label, cells in rows.items():
            print(f"  {label:34s} {cells[0]:>36s} {cells[1]:>36s}")

        # the hand-written Python reader and writer softtip used before pyarrow, same files
        src = Path(tmp, "in.csv")
        wr, cr, _ = timed(lambda: sio._parse(sio._decode(src.read_bytes(), str(src)), str(src)))

        def old_write():
            plan = sio._plan_table(cols, "%.10g")
            with open(Path(tmp, "old.csv"), "w", newline="") as fh:
                fh.write(plan.header)
                sio._write_rows_printf(fh, plan)

        ww, cw, _ = timed(old_write, repeats=1)
        print(f"  {'before: Python CSV reader':34s} {cell(wr, cr):>36s}")
        print(f"  {'before: Python CSV writer':34s} {cell(ww, cw):>36s}")


def _load() -> float:
    return os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")


def both_cores(n: int, repeats: int = 3) -> None:
    """`softtip estimate` on one core (every thread on one CPU) against `--jobs 1` and `--jobs 2`
    on both, on an n-row log (the 1 kHz grasp repeated), CSV -> CSV and Parquet -> Parquet, end
    to end (new processes), alternating; then where the CPU time goes on one thread (start-up,
    then the pieces' stages), for the critical path. ``--jobs 1`` estimates and writes on one
    thread, but pyarrow's reader may use others: "one core" holds every thread to one CPU."""
    import hashlib

    from softtip.io.tables import write_table

    def digest(path: Path) -> str:
        h = hashlib.sha256()
        with open(path, "rb") as fh:
            while chunk := fh.read(1 << 24):
                h.update(chunk)
        return h.hexdigest()

    t, w = grasp_log(n)
    n = len(t)
    softtip_cmd = str(Path(sys.executable).with_name("softtip"))
    print(f"both cores: `softtip estimate` on a {n:,}-row log, {os.cpu_count()} CPUs, load average {_load():.1f} at the start;")
    print(f"  {repeats} runs of each, alternating (1 2 1 2 ...): wall s, CPU s (user + system, every thread), peak GB, load average")
    print("  before the run; a ratio is of the medians; \"one core\": --jobs 1 with every thread on one CPU")
    with tempfile.TemporaryDirectory() as tmp:
        log_columns = {"t": t, **{name: w[:, i] for i, name in enumerate(("fx", "fy", "fz", "mx", "my", "mz"))}}
        for fmt in ("csv", "parquet"):
            src, dest = Path(tmp, f"in.{fmt}"), Path(tmp, f"out.{fmt}")
            write_table(log_columns, src)
            runs: dict[str, list[tuple[float, float, float, float]]] = {}
            outputs = {}
            for _ in range(repeats):
                for jobs in ("one core", "1", "2", "default"):
                    load = _load()
                    extra = ["--jobs", "1"] if jobs == "one core" else [] if jobs == "default" else ["--jobs", jobs]
                    cmd = [softtip_cmd, "estimate", str(src), "-o", str(dest), "-q", *extra]
                    wall, cpu, peak = command(cmd, one_core=jobs == "one core")
                    runs.setdefault(jobs, []).append((wall, cpu, peak, load))
                    outputs[jobs] = digest(dest)
            same = len(set(outputs.values())) == 1
            for jobs, rs in runs.items():
                cells = "  ".join(f"{wl:5.2f} {c:5.2f} {p / 1e9:4.2f} ({ld:.1f})" for wl, c, p, ld in rs)
                label = jobs if jobs == "one core" else f"--jobs {jobs}"
                print(f"  {fmt:7s} {label:14s}: {cells}")
            med = {j: (float(np.median([r[0] for r in rs])), float(np.median([r[1] for r in rs]))) for j, rs in runs.items()}
            print(f"  {fmt:7s} the cores this process got: {cores_granted():.2f}x (two threads of a compiled loop against one;"
                  " 2.0 on an idle 2-core machine, ~1 when other work takes the cores)")
            print(f"  {fmt:7s} wall ratio one core / --jobs 2 {med['one core'][0] / med['2'][0]:.2f}x, --jobs 1 / --jobs 2"
                  f" {med['1'][0] / med['2'][0]:.2f}x; CPU --jobs 2 / one core {med['2'][1] / med['one core'][1]:.2f};"
                  f" output bytes identical: {same}")
        stage_cpu(Path(tmp), n, softtip_cmd)
    print(f"  load average at the end {_load():.1f} (other work on the machine shares the cores)")


def cores_granted(seconds: float = 0.5) -> float:
    """How much faster two threads of a compiled loop (numba, no GIL) run than one, now: the
    wall-time ratio any two-thread design can reach on this machine at this load (Linux shares
    the cores between sessions, not threads: under load a second thread gets little more)."""
    import threading

    import numba

    @numba.njit(nogil=True)
    def spin(n):
        s = 0.0
        for i in range(n):
            s += (i % 7) * 1e-9
        return s

    spin(10)
    n = int(seconds * 3e8)
    walls: dict[int, list[float]] = {1: [], 2: []}
    for _ in range(3):  # alternating, the median of each: the load changes
        for threads in (1, 2):
            workers = [threading.Thread(target=spin, args=(n,)) for _ in range(threads)]
            w0 = time.perf_counter()
            for th in workers:
                th.start()
            for th in workers:
                th.join()
            walls[threads].append((time.perf_counter() - w0) / threads)
    return float(np.median(walls[1]) / np.median(walls[2]))


def stage_cpu(tmp: Path, n: int, softtip_cmd: str) -> None:
    """CPU time of each stage of `softtip estimate` in pieces, on one thread (best of 2), and of its start-up."""
    from softtip.apps import chunked
    from softtip.apps.pool import warm_kernels
    from softtip.cli.estimate import _output_columns
    from softtip.core.fingertip import load_fingertip
    from softtip.estimator.batch import Carry, _estimate
    from softtip.estimator.config import EstimatorConfig
    from softtip.estimator.depth import resolve_depth
    from softtip.io.tables import TableWriter, iter_log, write_table

    small = tmp / "small.parquet"
    t, w = grasp_log(20_000, whole=False)
    write_table({"t": t, **{name: w[:, i] for i, name in enumerate(("fx", "fy", "fz", "mx", "my", "mz"))}}, small)
    env = {**os.environ, "SOFTTIP_NUMBA": "1"}  # the compiled kernels loaded, as a long log's run loads them
    startup = min(
        subprocess_cpu([softtip_cmd, "estimate", str(small), "-o", str(tmp / "small.out.parquet"), "-q"], env) for _ in range(2)
    )
    warm_kernels()
    tip = load_fingertip("murakami2006")
    config = resolve_depth(EstimatorConfig(), tip)
    print(f"  where the CPU time goes (s, one thread, best of 2; {n:,} rows, pieces of {chunked.DEFAULT_PIECE_ROWS}):")
    print(f"    start-up (`softtip estimate` of 20,000 rows, kernels loaded): {startup:.2f}")
    # any program that runs one function from numba's cache pays this; it leaves numba's objects out of
    # the collections at its exit (gc.freeze), as the command does (softtip.cli.app._leave_objects_to_the_exit)
    floor = tmp / "numba_floor.py"
    floor.write_text("import gc\n\nimport numba\n\n\n@numba.njit(cache=True)\ndef f(x):\n    return x + 1.0\n\n\nf(1.0)\n"
                     "gc.freeze()\n")  # fmt: skip
    bare = {**env, "OPENBLAS_NUM_THREADS": "1"}  # BLAS on one thread, as the command runs it
    subprocess_cpu([sys.executable, str(floor)], bare)  # its cache written
    least = min(subprocess_cpu([sys.executable, str(floor)], bare) for _ in range(3))
    print(f"    a Python program that imports numba and calls one function from numba's cache (exit collections skipped, as the command's): {least:.2f}")
    for fmt in ("csv", "parquet"):
        best: dict[str, float] = {}
        for _ in range(2):
            spent: dict[str, float] = {}

            def timed_call(key, fn, *args, **kwargs):
                c0 = time.thread_time()
                out = fn(*args, **kwargs)
                spent[key] = spent.get(key, 0.0) + time.thread_time() - c0
                return out

            c0 = time.thread_time()
            blocks = list(iter_log(str(tmp / f"in.{fmt}"), None, rows=1 << 16))
            spent["read"] = time.thread_time() - c0
            carry = Carry()

            def take(t, w, extra, cfg, stages):
                return timed_call("per-contact stages", _estimate, t, w, tip, cfg, carry, stages)

            sequential = chunked._sequential_stages
            chunked._sequential_stages = lambda *args, **kw: timed_call("cut (sequential stages)", sequential, *args, **kw)
            try:
                with open(os.devnull, "wb") as sink:
                    writer = TableWriter(sink, format=fmt, threads=1)  # formatting in this thread
                    for est, extra in chunked._split(iter(blocks), config, chunked.DEFAULT_PIECE_ROWS, carry, take):
                        columns = timed_call("columns", lambda: _output_columns(est.columns(units="si"), extra))
                        timed_call("write", writer.write, columns)
                    timed_call("write", writer.close)
            finally:
                chunked._sequential_stages = sequential
            for key, value in spent.items():
                best[key] = min(best.get(key, np.inf), value)
        print(f"    {fmt:7s} " + ", ".join(f"{k} {v:.2f}" for k, v in best.items()) + f"; sum {sum(best.values()):.2f}")


def subprocess_cpu(cmd: list[str], env: dict[str, str]) -> float:
    """CPU time (user + system) of a command run to its end."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(cmd, env=env, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime


#: The output columns manual §6's end-to-end targets are bound to (the least the command line
#: contract allows): time, state, wrench, point, normal, spin, h, |h|, direction, angle, evidence.
SPEC_COLUMNS = (
    "t", "state", "fx", "fy", "fz", "mx", "my", "mz", "rx", "ry", "rz", "nx", "ny", "nz", "sigma",
    "hx", "hy", "hz", "h_norm", "dx", "dy", "dz", "angle_deg", "line_evidence",
)  # fmt: skip


def bounds(n: int) -> None:
    """What the end-to-end targets leave for softtip: reading the n-row input log with pyarrow and
    writing the least output the command line contract allows (:data:`SPEC_COLUMNS` of softtip's
    own estimates) with softtip's own writers and settings (``write_table``: CSV by the compiled
    formatter, Parquet with :data:`~softtip.io.tables.PARQUET_COMPRESSION`, no dictionary on
    floats, no statistics; Arrow IPC uncompressed), per CPU second on one thread and with
    pyarrow's threads; numpy filling that many float64 columns; the CSV number formatters side
    by side in ns per number; the Parquet and Arrow IPC compressions on all the estimates'
    columns. Any `softtip estimate` is slower than read + write here, whatever its pipeline."""
    import pyarrow
    import pyarrow.csv as pcsv
    import pyarrow.parquet as pq

    import softtip.io.tables as sio
    from softtip.core._jit import set_jit

    t, w = grasp_log(n)
    n = len(t)
    every = estimate(t, w, "murakami2006").columns()
    cols = {k: every[k] for k in SPEC_COLUMNS}
    log = pyarrow.table({"t": t, **{k: w[:, i] for i, k in enumerate(("fx", "fy", "fz", "mx", "my", "mz"))}})
    print(f"bounds of end to end, {n:,}-row log, the {len(SPEC_COLUMNS)} columns the contract requires: read by "
          f"pyarrow {pyarrow.__version__}, written by softtip's write_table (its own settings); rows per second, "
          "best of 2 (end-to-end targets, manual §6, per core: CSV >= 0.4 M, Parquet >= 1 M)")  # fmt: skip
    old_threads = sio._WRITE_THREADS
    with tempfile.TemporaryDirectory() as tmp:
        src = {"csv": Path(tmp, "in.csv"), "parquet": Path(tmp, "in.parquet"), "arrow": Path(tmp, "in.arrow")}
        for path in src.values():
            sio.write_table({name: log.column(name).to_numpy() for name in log.column_names}, path)
        steps = {
            "CSV": (lambda: pcsv.read_csv(src["csv"]), Path(tmp, "out.csv")),
            "Parquet": (lambda: pq.ParquetFile(src["parquet"]).read(), Path(tmp, "out.parquet")),
            "Arrow IPC": (lambda: pyarrow.ipc.open_file(pyarrow.memory_map(str(src["arrow"]))).read_all(), Path(tmp, "out.arrow")),
        }
        cores = pyarrow.cpu_count()
        set_jit(True)  # the compiled CSV formatter where numba is installed
        for threads in (1, cores):
            label = "one thread" if threads == 1 else f"{threads} threads (pyarrow's default)"
            pyarrow.set_cpu_count(threads)
            sio._WRITE_THREADS = threads
            for fmt, (read, dest) in steps.items():
                wr, cr, _ = timed(read)
                ww, cw, _ = timed(lambda: sio.write_table(cols, dest))
                size = dest.stat().st_size / n
                print(f"  {fmt:9s} {label:34s} read {n / cr / 1e6:6.2f} M/s, write {n / cw / 1e6:6.2f} M/s "
                      f"({size:.0f} B/row), read + write {n / (cr + cw) / 1e6:6.2f} M/s per CPU second, "
                      f"{n / (wr + ww) / 1e6:6.2f} M/s wall")  # fmt: skip
        sio._WRITE_THREADS = old_threads
        pyarrow.set_cpu_count(cores)
        set_jit(None)
        csv_formatters(every)
        columnar_settings(every, Path(tmp, "settings"))
        csv_readers(src["csv"])
        parquet_input(src["parquet"], n)
    k = sum(1 for c in SPEC_COLUMNS if c not in ("state", "line_evidence"))
    m = 10 * n
    # memory the process has not touched yet costs the system a page fault per page, and on a
    # virtual machine that hands freed memory back to its host (free page reporting) far more:
    # then the first touch, and the first touch after the machine idled, is what varies
    gib = k * m * 8 / 2**30
    for label, idle in (("first allocation", 0.0), ("again", 0.0), ("again after 5 s idle", 5.0)):
        time.sleep(idle)
        r0 = resource.getrusage(resource.RUSAGE_SELF)
        arrays = [np.empty(m) for _ in range(k)]
        for a in arrays:
            a.fill(1.0)
        r1 = resource.getrusage(resource.RUSAGE_SELF)
        user, system = r1.ru_utime - r0.ru_utime, r1.ru_stime - r0.ru_stime
        del arrays
        print(f"  numpy: allocate and fill {k} float64 columns of {m:,} rows ({gib:.2f} GiB), {label}: "
              f"{(user + system) / m * 1e9:.0f} ns/row, system time {system / gib:.2f} s/GiB "
              "(3 M rows/s, about the pipeline target, is 330 ns/row for everything)")  # fmt: skip


def parquet_input(path: Path, n: int, repeats: int = 3) -> None:
    """The input Parquet log read in a fresh process, memory-mapped (softtip's reader) against
    read into pyarrow's buffers: CPU time of the process beyond its imports, alternating. In one
    process the second read reuses the first one's memory and hides the difference."""
    code = ("import resource, sys, pyarrow.parquet as pq; r = resource.getrusage(resource.RUSAGE_SELF); "
            "f = pq.ParquetFile(sys.argv[1], memory_map=sys.argv[2] == '1'); "
            "[c.to_numpy() for b in f.iter_batches(batch_size=65536) for c in b.columns]; "
            "q = resource.getrusage(resource.RUSAGE_SELF); "
            "print(q.ru_utime + q.ru_stime - r.ru_utime - r.ru_stime)")  # fmt: skip
    got: dict[str, list[float]] = {"1": [], "0": []}
    for _ in range(repeats):
        for mapped in got:
            out = subprocess.run([sys.executable, "-c", code, str(path), mapped], check=True, capture_output=True, text=True)
            got[mapped].append(float(out.stdout))
    print(f"  Parquet input in a fresh process ({n:,} rows, CPU s beyond the imports, {repeats} runs each, alternating): "
          f"memory-mapped (softtip's reader) {' '.join(f'{c:.2f}' for c in got['1'])}, "
          f"read into buffers {' '.join(f'{c:.2f}' for c in got['0'])}")  # fmt: skip


def csv_formatters(columns: dict) -> None:
    """CSV text of the estimates' float columns, ns per number of CPU time on one thread (best of
    3): the compiled formatter (:mod:`softtip.io._csvtext`, rounding included), the fallback
    (softtip's rounding then pyarrow's writer, the same bytes), pyarrow's shortest-repr writer
    on the unrounded values, and Python's printf; every 65536-row block as ``write_table`` makes it."""
    import io

    import pyarrow
    import pyarrow.csv as pcsv

    import softtip.io.tables as sio

    floats = {k: v for k, v in columns.items() if v.dtype.kind == "f"}
    n = len(next(iter(floats.values())))
    numbers = n * len(floats)
    plan = sio._plan_table(floats, "%.10g")
    starts = range(0, n, sio._CHUNK_ROWS)
    options = pcsv.WriteOptions(include_header=False)

    def per_number(fn, repeats=3) -> float:
        return timed(fn, repeats)[1] / numbers * 1e9

    def fallback():
        for s in starts:
            pcsv.write_csv(sio._arrow_block(plan, s, min(s + sio._CHUNK_ROWS, n), rounded=True), io.BytesIO(), options)

    table = pyarrow.table(floats)
    rows = {"fallback: softtip's rounding + pyarrow's writer": per_number(fallback),
            "pyarrow's shortest-repr writer alone (not rounded)": per_number(lambda: pcsv.write_csv(table, io.BytesIO(), options))}  # fmt: skip
    try:
        import numba  # noqa: F401
    except ImportError:
        compiled = None
    else:
        buffers = sio._TextBuffers()  # reused block after block, as write_table does

        def text(s):
            out, used = sio._compiled_block(plan, s, min(s + sio._CHUNK_ROWS, n), buffers)
            text = bytes(out[:used])
            buffers.put(out)
            return text

        text(0)  # compiled (or loaded from numba's cache) before the clock
        compiled = per_number(lambda: [buffers.put(sio._compiled_block(plan, s, min(s + sio._CHUNK_ROWS, n), buffers)[0]) for s in starts])
        same = all(text(s) == _fallback_bytes(plan, s, n) for s in starts[:4])
    few = min(n, 1 << 16)
    printf = timed(lambda: sio._write_rows_printf(io.StringIO(), sio._plan_table({k: v[:few] for k, v in floats.items()}, "%.10e")), 1)[1]
    rows["Python's printf (%.10e, cell by cell in C)"] = printf / (few * len(floats)) * 1e9
    print(f"  CSV number formatting, {len(floats)} float columns x {n:,} rows, ns per number of CPU time, one thread:")
    if compiled is not None:
        print(f"    {'compiled formatter (numba; rounding included)':52s} {compiled:6.0f} ns   "
              f"(same bytes as the fallback on the first blocks: {same})")  # fmt: skip
    else:
        print(f"    {'compiled formatter':52s}      -      (numba not installed)")
    for label, value in rows.items():
        print(f"    {label:52s} {value:6.0f} ns")


def csv_readers(path: Path) -> None:
    """The 7-column log's CSV body parsed as softtip's reader parses it (pyarrow, one thread, the
    column types given) and by pandas' C engine (where pandas is installed), CPU time (best of 3),
    and whether the values agree to the bit."""
    import io

    import pyarrow as pa
    import pyarrow.csv as pcsv

    data = path.read_bytes()
    start = data.index(b"\n") + 1
    body = memoryview(data)[start:]
    names = data[: start - 1].decode().split(",")

    def arrow():
        reader = pcsv.open_csv(
            pa.BufferReader(pa.py_buffer(body)), read_options=pcsv.ReadOptions(column_names=names, use_threads=False),
            parse_options=pcsv.ParseOptions(newlines_in_values=True, ignore_empty_lines=False),
            convert_options=pcsv.ConvertOptions(column_types=dict.fromkeys(names, pa.float64()), check_utf8=True,
                                                strings_can_be_null=False, quoted_strings_can_be_null=False),
        )  # fmt: skip
        table = pa.Table.from_batches(list(reader), schema=reader.schema)
        reader.close()
        return np.column_stack([table.column(n).to_numpy() for n in names])

    wa, ca, a = timed(arrow, 3)
    print(f"  CSV readers on the log's {len(data) / 1e6:.0f} MB ({len(a):,} rows, {len(names)} columns), CPU time, best of 3:")
    print(f"    {'pyarrow, as read_log runs it (one thread)':52s} {ca:6.3f} s")
    try:
        import pandas as pd
    except ImportError:
        print(f"    {'pandas C engine':52s}      -  (pandas not installed)")
        return
    wp, cp, p = timed(lambda: pd.read_csv(io.BytesIO(body), engine="c", header=None, names=names, dtype=np.float64).to_numpy(), 3)
    print(f"    {'pandas C engine (read_csv, engine=c)':52s} {cp:6.3f} s   (the same values: {np.array_equal(a, p)})")


def _fallback_bytes(plan, start: int, n: int) -> bytes:
    import io

    import pyarrow.csv as pcsv

    import softtip.io.tables as sio

    sink = io.BytesIO()
    block = sio._arrow_block(plan, start, min(start + sio._CHUNK_ROWS, n), rounded=True)
    pcsv.write_csv(block, sink, pcsv.WriteOptions(include_header=False))
    return sink.getvalue()


def columnar_settings(columns: dict, dest: Path) -> None:
    """Parquet and Arrow IPC writer settings on all the estimates' columns: compression none,
    snappy, lz4, zstd (Parquet with softtip's dictionary and statistics settings, and with
    pyarrow's defaults), write CPU time per row (best of 3) and file size; how
    :data:`softtip.io.tables.PARQUET_COMPRESSION` and ``ARROW_COMPRESSION`` were chosen."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    import softtip.io.tables as sio

    plan = sio._plan_table(columns, "%.10g")
    plan.parquet = True
    n = plan.n
    tables = [sio._arrow_block(plan, s, min(s + sio._PARQUET_ROWS, n), rounded=False) for s in range(0, n, sio._PARQUET_ROWS)]
    schema = tables[0].schema
    coded = [f.name for f in schema if not pa.types.is_floating(f.type)]
    configs = {f"Parquet {c:6s} (softtip's: no dictionary on floats, no statistics)": dict(compression=c, use_dictionary=coded, write_statistics=False)
               for c in ("none", "snappy", "lz4", "zstd")}  # fmt: skip
    configs["Parquet snappy with statistics"] = dict(compression="snappy", use_dictionary=coded)
    configs["Parquet pyarrow's defaults (snappy, dictionary everywhere, statistics)"] = {}
    # every column nullable, as before softtip declared its numbers required: definition levels
    nullable = pa.schema([f.with_nullable(True) for f in schema])
    configs["Parquet snappy, softtip's settings, every column nullable"] = dict(
        compression="snappy", use_dictionary=coded, write_statistics=False, schema=nullable
    )

    def parquet(kw):
        kw = dict(kw)
        use = kw.pop("schema", schema)
        with pq.ParquetWriter(dest, use, **kw) as writer:
            for table in tables:
                writer.write_table(table.cast(use) if use is not schema else table)

    def arrow(compression):
        with pa.OSFile(str(dest), "wb") as sink, pa.ipc.new_file(sink, schema, options=pa.ipc.IpcWriteOptions(compression=compression)) as writer:
            for table in tables:
                writer.write_table(table)

    print(f"  file writers on all {len(columns)} columns of the estimates, {n:,} rows, CPU time of the write (best of 3), "
          f"file size; chosen: Parquet {sio.PARQUET_COMPRESSION}, Arrow IPC {sio.ARROW_COMPRESSION or 'uncompressed'}")  # fmt: skip
    for label, kw in configs.items():
        c = timed(lambda: parquet(kw), 3)[1]
        print(f"    {label:72s} {c / n * 1e9:5.0f} ns/row {dest.stat().st_size / 1e6:7.1f} MB")
    for compression in (None, "lz4", "zstd"):
        c = timed(lambda: arrow(compression), 3)[1]
        print(f"    {'Arrow IPC ' + (compression or 'uncompressed'):72s} {c / n * 1e9:5.0f} ns/row {dest.stat().st_size / 1e6:7.1f} MB")


def plausible_wrenches(tip, n, rng):
    """Pushes within friction: tangential force up to half the normal force (0.2-10 N), spin
    torque up to 1 N·mm per N of normal force (ten times the papers' grasp)."""
    centre, radius = tip.bounding_sphere
    u = rng.normal(size=(n, 3))
    u[:, 2] = np.abs(u[:, 2])
    r = tip.project(centre + 3 * radius * u / np.linalg.norm(u, axis=1, keepdims=True))
    nrm = tip.normal(r)
    fn = rng.uniform(0.2, 10.0, (n, 1))
    t = rng.normal(size=(n, 3))
    t -= np.sum(t * nrm, axis=1, keepdims=True) * nrm
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    f = -fn * nrm + rng.uniform(0.0, 0.5, (n, 1)) * fn * t
    m = np.cross(r, f) + rng.uniform(-1e-3, 1e-3, (n, 1)) * fn * nrm
    return np.ascontiguousarray(np.concatenate((f, m), axis=1))


def mesh_rows(args, rng) -> None:
    from softtip.core._xp import PY
    from softtip.core.fingertip import load_fingertip
    from softtip.core.location import contact_kernel
    from softtip.io.examples import EXAMPLE_PATH

    t0 = time.perf_counter()
    tip = load_fingertip(EXAMPLE_PATH.with_name("murakami2006_nail.toml"))
    load = time.perf_counter() - t0
    print(f"mesh fingertip: murakami2006_nail.toml, {len(tip.faces):,} triangles (loaded and checked in {load:.2f} s)")
    n = min(args.samples, 200_000)
    w = plausible_wrenches(tip, n, rng)
    out = []
    dt = best_of(lambda: out.append(contact_from_wrench(w, tip)), 1)
    valid = float(np.mean(out[-1].valid))
    print(f"  {'batch contact location':30s} {n / dt / 1e6:8.3f} M samples/s   ({dt:.3f} s, {n:,} samples, {valid:.1%} solved)")
    clock = time.process_time  # CPU time: steadier than the wall clock on a shared machine
    g = synthetic_grasp(tip, angle_deg=45.0, duration=10.0, rate=1000.0, seed=1)
    held = g.wrench[np.linalg.norm(g.wrench[:, :3], axis=1) > 0.5]
    # a live contact moves continuously (the kernel starts from the previous sample's face);
    # independent pushes all over the skin are its worst case
    for label, ws in (
        ("stream contact location", held[: args.stream_samples].tolist()),
        ("  independent random pushes", w[: args.stream_samples].tolist()),
    ):
        per = np.empty(len(ws))
        for i, wi in enumerate(ws):
            t0 = clock()
            contact_kernel(tip, *wi, xp=PY)
            per[i] = clock() - t0
        print(f"  {label:30s} median {np.median(per) * 1e6:6.1f} us   p99 {np.percentile(per, 99) * 1e6:6.1f} us")
    dt = best_of(lambda: estimate(g.t, g.wrench, tip), 1)
    print(f"  {'whole batch pipeline (mesh)':30s} {len(g.t) / dt / 1e6:8.3f} M samples/s   ({dt:.3f} s)")
    for label, cfg in (("stream latch, no filter", EstimatorConfig()), ("stream track", EstimatorConfig(contact_point="track"))):
        est = Estimator(tip, cfg)
        ts = g.t[: args.stream_samples]
        wl = g.wrench[: args.stream_samples].tolist()
        per = np.empty(len(ts))
        for i, (t, wi) in enumerate(zip(ts.tolist(), wl)):
            t0 = clock()
            est.update(t, wi)
            per[i] = clock() - t0
        contact = g.t[: len(per)] > 2.2
        print(
            f"  {label:30s} median {np.median(per) * 1e6:6.1f} us   p99 {np.percentile(per, 99) * 1e6:6.1f} us"
            + (f"   (in contact: median {np.median(per[contact]) * 1e6:6.1f} us)" if contact.any() else
               f"   (no sample in contact in the first {len(per):,}: give more --stream-samples)")
        )  # fmt: skip


if __name__ == "__main__":
    sys.exit(run_with_markdown(main, "bench_core.py", code_block=True))
