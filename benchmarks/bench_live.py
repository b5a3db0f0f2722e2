"""Latency, sustained rate and fault counters of the live path, against the fake Net F/T.

    python benchmarks/bench_live.py [--rates 1000 7000] [--seconds 5] [--no-faults]

For each rate a fake device (``python -m softtip.testing.netft_fake``, its own process so it does
not share softtip's interpreter) streams RDT records over loopback UDP; softtip receives
them in its receive thread, runs the streaming estimator on every sample, records every row
to a CSV file and redraws the terminal view (to /dev/null) five times a second: the full
``softtip stream --record`` path. Latency is from a packet's arrival on the socket (the
receive thread's time stamp, monotonic clock) to its estimate being available (the
``on_estimate`` hook, after the row was queued for the file).

With faults (the default) the device also duplicates every 97th record, sends every 89th
after the next one, puts a malformed datagram (zero-length or 7 bytes) before every 83rd,
does not send every 101st, sets the status word of every 500th to 0x80010000, and restarts
once after 40 % of the run (silent for 1 s, then both sequences start again). Reported:
median and 99th percentile latency, the rate sustained while streaming, and every counter:
lost (network), late, duplicates, malformed, dropped by softtip (its queue), restarts,
records with a nonzero status. Target: 7 kHz with nothing dropped, and the session alive.
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import tempfile
import time

import numpy as np

from softtip.apps.live import LiveStats, Recorder, TerminalView, run_live
from softtip.estimator import Estimator
from softtip.io.netft import NetFTSource

FAULT_ARGS = ["--duplicate-every", "97", "--reorder-every", "89", "--malformed-every", "83",
              "--drop-every", "101", "--status-every", "500"]  # fmt: skip


def bench(rate: float, seconds: float, record: bool = True, view: bool = True, faults: bool = True) -> dict:
    more = [*FAULT_ARGS, "--reboot-after", str(0.4 * seconds)] if faults else []
    dev = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "softtip.testing.netft_fake",
            "--rate",
            str(rate),
            "--duration",
            str(seconds + 10),
            *more,
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        line = dev.stdout.readline().split()
        rdt_port, http_port = (
            int(line[line.index("--rdt-port") + 1]),
            int(line[line.index("--http-port") + 1]),
        )
        latencies = np.empty(int(rate * (seconds + 5)), dtype=np.int64)
        n = 0

        prev, longest = 0, 0  # the longest silence (the restart), not counted as streaming time

        def on_estimate(e, r):
            nonlocal n, prev, longest
            latencies[n] = time.monotonic_ns() - r.arrival_ns
            n += 1
            if prev and r.arrival_ns - prev > longest:
                longest = r.arrival_ns - prev
            prev = r.arrival_ns

        with tempfile.TemporaryDirectory() as tmp, open(os.devnull, "w") as null:
            recorder = Recorder(os.path.join(tmp, "rec.csv")) if record else None
            with NetFTSource(
                "127.0.0.1", rdt_port=rdt_port, http_port=http_port, timeout=2.0
            ) as src:
                stats = LiveStats(source_name=src.name, dropped=lambda: src.dropped, counters=src.counters,
                                  warnings=lambda: src.warnings)  # fmt: skip
                term = (
                    TerminalView(stats, out=null, recorder=recorder) if view else None
                )
                summary = run_live(
                    src,
                    Estimator(),
                    recorder=recorder,
                    view=term,
                    stats=stats,
                    duration=seconds,
                    on_estimate=on_estimate,
                )
                rows = recorder.rows if recorder else 0
    finally:
        dev.kill()
        dev.wait()
    lat = latencies[:n] * 1e-6  # ms
    c = summary.counters
    silent = longest * 1e-9 if faults else 0.0
    return {
        "rate": rate,
        "samples": summary.samples,
        "sustained": summary.samples / (summary.seconds - silent),
        "counters": c,
        "median_ms": float(np.median(lat)),
        "p99_ms": float(np.percentile(lat, 99)),
        "max_ms": float(lat.max()),
        "lost": summary.lost,
        "dropped": summary.dropped,
        "rows": rows,
    }


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rates", type=float, nargs="+", default=[1000.0, 7000.0])
    p.add_argument("--seconds", type=float, default=5.0)
    p.add_argument("--no-record", action="store_true", help="without the CSV recorder")
    p.add_argument("--no-view", action="store_true", help="without the terminal view")
    p.add_argument("--no-faults", action="store_true", help="a clean stream")
    args = p.parse_args()
    print(
        f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}"
    )
    print(
        "| input rate | samples | sustained | latency median | p99 | max | lost (network) | late | duplicates "
        "| malformed | dropped by softtip | restarts | nonzero status | rows recorded |"
    )
    print("| --- " * 14 + "|")
    for rate in args.rates:
        r = bench(rate, args.seconds, record=not args.no_record, view=not args.no_view, faults=not args.no_faults)
        c = r["counters"]
        print(
            f"| {r['rate']:.0f} Hz | {r['samples']} | {r['sustained']:.0f} Hz | {r['median_ms']:.3f} ms | {r['p99_ms']:.3f} ms "
            f"| {r['max_ms']:.2f} ms | {c.get('lost', 0)} | {c.get('late', 0)} | {c.get('duplicates', 0)} "
            f"| {c.get('malformed', 0)} | {c.get('dropped', 0)} | {c.get('restarts', 0)} | {c.get('status_records', 0)} | {r['rows']} |"
        )


if __name__ == "__main__":
    main()
