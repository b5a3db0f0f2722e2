"""Where the test suite's time goes: each test's CPU (its own and its subprocesses') and wall time.

A pytest plugin and the table it feeds. Run the suite with it, then print the table::

    SOFTTIP_SUITE_CPU=/tmp/suite-cpu PYTHONPATH=benchmarks \\
        python -m pytest -q -n auto --dist loadfile -p no:cacheprovider -p suite_cpu
    python benchmarks/suite_cpu.py /tmp/suite-cpu --top 20

Each pytest process (the controller, each pytest-xdist worker) writes ``<worker>.json`` into
``$SOFTTIP_SUITE_CPU`` at the end of its session. A subprocess's CPU counts once it is reaped
(``RUSAGE_CHILDREN``): processes that no process waits for (the pool workers of ``softtip
reproduce``) are not seen, so the table's total is below the run's ``user + sys``.
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import resource
import time
from pathlib import Path

_ENV = "SOFTTIP_SUITE_CPU"
_rows: list[tuple[str, float, float, float]] = []
#: When this pytest process loaded the plugin, its first test started and its last ended (epoch s)
_loaded = time.time()
_span: list[float] = []


def _cpu() -> tuple[float, float]:
    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime, children.ru_utime + children.ru_stime


try:
    import pytest
except ImportError:  # the table alone needs no pytest
    pytest = None

if pytest is not None:

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_protocol(item, nextitem):
        """One row per test: its own CPU, its reaped subprocesses' CPU, its wall time (s)."""
        before, start = _cpu(), time.perf_counter()
        if not _span:
            _span.append(time.time())
        yield
        after = _cpu()
        _span[1:] = [time.time()]
        _rows.append((item.nodeid, after[0] - before[0], after[1] - before[1], time.perf_counter() - start))

    def pytest_sessionfinish(session):
        folder = os.environ.get(_ENV)
        if not folder or not _rows:
            return
        Path(folder).mkdir(parents=True, exist_ok=True)
        own, children = _cpu()
        worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
        record = {"rows": _rows, "process_cpu": own, "children_cpu": children, "loaded": _loaded}
        record.update(first_test=_span[0], last_test_end=_span[-1], finished=time.time())
        (Path(folder) / f"{worker}.json").write_text(json.dumps(record), encoding="utf-8")


def table(folder: Path, top: int) -> str:
    """Per test file, largest first: CPU (own + subprocesses) and wall time; then the ``top`` tests."""
    files, sub, wall, tests = collections.Counter(), collections.Counter(), collections.Counter(), []
    workers = sorted(folder.glob("*.json"))
    if not workers:
        raise SystemExit(f"{folder}: no <worker>.json (run the suite with -p suite_cpu and {_ENV}={folder})")
    busy, spans = [], []
    for path in workers:
        record = json.loads(path.read_text(encoding="utf-8"))
        rows = record["rows"]
        busy.append(f"{path.stem} {sum(r[3] for r in rows):.0f} s")
        spans.append((path.stem, record))
        for nodeid, own, children, seconds in rows:
            name = nodeid.split("::")[0]
            files[name] += own + children
            sub[name] += children
            wall[name] += seconds
            tests.append((own + children, children, nodeid))
    total = sum(files.values())
    lines = [f"test CPU {total:.0f} s (own + reaped subprocesses); each worker's time in tests: {', '.join(busy)}", "",
             "| file | CPU s | of it subprocesses | wall s |", "| --- | ---: | ---: | ---: |"]  # fmt: skip
    timed = all("loaded" in r for _, r in spans)  # not in records written before it was kept
    start = min(r["loaded"] for _, r in spans) if timed else 0.0
    lines[1:1] = [] if not timed else [
        "", "| worker (s from the first worker's start) | started | first test | last test ended | session ended |",
        "| --- | ---: | ---: | ---: | ---: |",
        *(f"| {name} | {r['loaded'] - start:.1f} | {r['first_test'] - start:.1f} | {r['last_test_end'] - start:.1f} "
          f"| {r['finished'] - start:.1f} |" for name, r in spans),
    ]  # fmt: skip
    lines += [f"| {f} | {c:.1f} | {sub[f]:.1f} | {wall[f]:.1f} |" for f, c in files.most_common()]
    lines += ["", f"| the {top} costliest tests | CPU s | of it subprocesses |", "| --- | ---: | ---: |"]
    lines += [f"| {n} | {c:.1f} | {s:.1f} |" for c, s, n in sorted(tests, reverse=True)[:top]]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folder", type=Path, help=f"the folder ${_ENV} named during the run")
    parser.add_argument("--top", type=int, default=20, help="how many single tests to list (default 20)")
    args = parser.parse_args()
    print(table(args.folder, args.top))


if __name__ == "__main__":
    main()
