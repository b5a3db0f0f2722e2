"""Writing a large output file: plainly against softtip's writer, which hands the file's pages to
the kernel's writeback and drops them behind it (``softtip.io.atomic``).

    python benchmarks/bench_write_behind.py --gb 4.9 --repeats 2

Each run writes ``--gb`` GB of text in 64 MiB blocks to a new file beside ``--dir`` and syncs it,
once through a plain ``open`` and once through :class:`softtip.io.atomic.AtomicFile` (alternating,
a pause between runs), and prints the wall time and the process's system time of each.
"""

from __future__ import annotations

import argparse
import os
import resource
import tempfile
import time
from pathlib import Path

from softtip.io.atomic import AtomicFile


def _system_time() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_stime


def _write(fh, block: bytes, total: int) -> None:
    for _ in range(max(1, total // len(block))):
        fh.write(block)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--gb", type=float, default=4.9, help="GB per file (default 4.9, a 1e7-row CSV output)")
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--pause", type=float, default=6.0, help="s between runs (default 6)")
    ap.add_argument("--dir", default=None, help="where to write (default: the system's temporary folder)")
    args = ap.parse_args()
    block = (b"0.1234567891," * 5_000_000)[: 64 << 20]
    total = int(args.gb * 1e9)
    with tempfile.TemporaryDirectory(dir=args.dir) as tmp:
        path = Path(tmp, "out.csv")
        print(f"{total / 1e9:.1f} GB in 64 MiB blocks, synced; wall s, system s")
        for _ in range(args.repeats):
            for how in ("plain open", "softtip's writer"):
                w0, s0 = time.perf_counter(), _system_time()
                if how == "plain open":
                    with open(path, "wb") as fh:
                        _write(fh, block, total)
                        fh.flush()
                        os.fsync(fh.fileno())
                else:
                    with AtomicFile(path) as f:
                        with f.open("wb") as fh:
                            _write(fh, block, total)
                        f.commit()
                print(f"  {how:17s} {time.perf_counter() - w0:6.2f} {_system_time() - s0:6.2f}", flush=True)
                path.unlink()
                time.sleep(args.pause)


if __name__ == "__main__":
    main()
