"""Throughput of the contact solvers and latency of the streaming pipeline.

    python benchmarks/bench_core.py [--samples 1000000]

Prints batch samples/s for each fingertip shape (one core: numpy runs these kernels on one
thread) and the median and 99th-percentile time of one sample through the streaming
estimator. Targets (manual §6): capsule batch >= 5 M samples/s; streaming median <= 20 us.

Then `softtip estimate` end to end on a --samples-row log (the 1 kHz example grasp
repeated), CSV and Parquet side by side: read (softtip.io.read_log), the pipeline
(softtip.estimate), write (softtip.io.write_table), their total, and the `softtip estimate`
command itself (a new process: Python start-up and imports included), in rows/s, with its
peak memory, by default (pieces of 131072 rows for a log this large) and in one piece; also the
hand-written Python CSV reader and writer that softtip used before, on the same files.
Rates are rows per second of CPU time (the process's own, or the command's): on a shared
machine that is the steady figure; the wall-clock time is printed beside it. Targets (manual §6) end to end: CSV >= 2 M rows/s, Parquet >= 10 M rows/s.
Only this part: --only end-to-end.

Mesh rows: the shipped mesh fingertip (the papers' capsule with a nail, 21.6k triangles),
contact location per sample (streaming kernel, median and p99; target median <= 50 us) and in
batch, on pushes within friction (see plausible_wrenches), and the whole pipeline with the
mesh tip.
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from softtip import Capsule, Ellipsoid, EstimatorConfig, Estimator, ImplicitSurface, Sphere, contact_from_wrench, estimate
from softtip.synthetic import synthetic_grasp


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


def best_of(fn, repeats):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--samples", type=int, default=1_000_000)
    ap.add_argument("--stream-samples", type=int, default=20_000)
    ap.add_argument("--only", choices=["end-to-end"], help="Run only this part.")
    ap.add_argument("--mesh-only", action="store_true", help="only the mesh fingertip rows")
    args = ap.parse_args()
    rng = np.random.default_rng(6)
    if args.mesh_only:
        print(f"softtip core benchmark | python {platform.python_version()} | numpy {np.__version__} | {platform.machine()}")
        mesh_rows(args, rng)
        return
    n = args.samples
    print(f"softtip core benchmark | python {platform.python_version()} | numpy {np.__version__} | {platform.machine()}")
    if args.only == "end-to-end":
        end_to_end(n)
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

    g = synthetic_grasp("murakami2006", angle_deg=45.0, duration=10.0, rate=1000.0, seed=1)
    reps = max(1, args.samples // len(g.t))
    t_rep = np.arange(reps * len(g.t)) * 1e-3
    w_rep = np.tile(g.wrench, (reps, 1))
    dt = best_of(lambda: estimate(t_rep, w_rep, "murakami2006"), 3)
    print(f"  {'whole batch pipeline (capsule)':30s} {len(t_rep) / dt / 1e6:8.2f} M samples/s   ({dt:.3f} s)")

    print(f"streaming pipeline, one sample at a time ({args.stream_samples:,} samples of a 1 kHz grasp)")
    for label, cfg in (
        ("latch, no filter (online depth)", EstimatorConfig()),
        ("latch, the papers' method", EstimatorConfig(depth_mode="off")),
        ("latch, --line-evidence off", EstimatorConfig(line_evidence=False)),
        ("latch, 4th-order low-pass", EstimatorConfig(lowpass_hz=30.0, sample_rate=1000.0, lowpass_order=4)),
        ("track", EstimatorConfig(contact_point="track")),
    ):
        est = Estimator("murakami2006", cfg)
        ts = g.t[: args.stream_samples]
        ws = g.wrench[: args.stream_samples].tolist()
        per = np.empty(len(ts))
        clock = time.perf_counter
        for i, (t, w) in enumerate(zip(ts.tolist(), ws)):
            t0 = clock()
            est.update(t, w)
            per[i] = clock() - t0
        contact = g.t[: len(per)] > 2.2
        print(
            f"  {label:30s} median {np.median(per) * 1e6:6.1f} us   p99 {np.percentile(per, 99) * 1e6:6.1f} us"
            f"   (in contact: median {np.median(per[contact]) * 1e6:6.1f} us)"
        )
    end_to_end(n)
    mesh_rows(args, rng)


def timed(fn, repeats=2):
    """Best wall-clock and best CPU time of ``repeats`` calls, and the last result."""
    wall, cpu, out = [], [], None
    for _ in range(repeats):
        w0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        wall.append(time.perf_counter() - w0)
        cpu.append(time.process_time() - c0)
    return min(wall), min(cpu), out


_MEASURE = """import resource, subprocess, sys
done = subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
u = resource.getrusage(resource.RUSAGE_CHILDREN)
print(done.returncode, u.ru_utime + u.ru_stime, u.ru_maxrss * 1024)
sys.stderr.write(done.stderr.decode())
"""


def command(cmd: list[str]) -> tuple[float, float, float]:
    """Wall time, CPU time (user + system) and peak resident memory (bytes) of a command.

    Run through a small Python process: a child's peak memory on Linux starts from the size
    of the process that forked it, so the benchmark (GBs by now) must not be that one.
    """
    w0 = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", _MEASURE, *cmd], capture_output=True, text=True)
    wall = time.perf_counter() - w0
    code, cpu, peak = done.stdout.split()
    if done.returncode != 0 or code != "0":
        raise SystemExit(done.stderr)
    return wall, float(cpu), float(peak)


def end_to_end(n: int) -> None:
    import pyarrow

    import softtip.io as sio
    from softtip.io import read_log, write_table

    g = synthetic_grasp("murakami2006", angle_deg=45.0, duration=10.0, rate=1000.0, seed=1)
    reps = max(1, n // len(g.t))
    t = np.arange(reps * len(g.t)) * 1e-3
    w = np.tile(g.wrench, (reps, 1))
    n = len(t)
    log_columns = {"t": t, **{name: w[:, i] for i, name in enumerate(("fx", "fy", "fz", "mx", "my", "mz"))}}
    print(f"softtip estimate end to end, {n:,}-row log (1 kHz grasp repeated), pyarrow {pyarrow.__version__}; best of 2")
    print(f"  {'stage':34s} {'CSV: rows per CPU second':>36s} {'Parquet':>36s}")

    def cell(wall, cpu):
        return f"{n / cpu / 1e6:6.2f} M/s (CPU {cpu:5.2f} s; wall {wall:5.2f} s)"

    with tempfile.TemporaryDirectory() as tmp:
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
                wall, cpu, peak = command(cmd + extra)
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
    from softtip.contact import contact_kernel
    from softtip._xp import PY
    from softtip.examples import EXAMPLE_PATH
    from softtip.fingertip import load_fingertip

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
    ws = w[: args.stream_samples].tolist()
    per = np.empty(len(ws))
    clock = time.perf_counter
    for i, wi in enumerate(ws):
        t0 = clock()
        contact_kernel(tip, *wi, xp=PY)
        per[i] = clock() - t0
    print(f"  {'stream contact location':30s} median {np.median(per) * 1e6:6.1f} us   p99 {np.percentile(per, 99) * 1e6:6.1f} us")
    g = synthetic_grasp(tip, angle_deg=45.0, duration=10.0, rate=1000.0, seed=1)
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
            f"   (in contact: median {np.median(per[contact]) * 1e6:6.1f} us)"
        )


if __name__ == "__main__":
    main()
