"""The benchmarks' helpers that reach into softtip's private writer run against today's code.

The benchmarks are not run by the suite (they time things), but ``bench_core.py``'s CSV
formatter comparison calls the writer's block formatter and its buffer pool directly: a
change of those signatures broke ``--only bounds`` unnoticed once. This runs that comparison
on a short log (its timings are not looked at) and checks the bytes it reports.
"""

import contextlib
import importlib
import io
import sys
from pathlib import Path

import pytest

from softtip import estimate
from softtip.sim.synthetic import synthetic_grasp

BENCHMARKS = Path(__file__).resolve().parent.parent / "benchmarks"


@pytest.fixture(scope="module")
def bench_core():
    pytest.importorskip("numba", reason="the comparison times the compiled formatter")
    sys.path.insert(0, str(BENCHMARKS))
    try:
        yield importlib.import_module("bench_core")
    finally:
        sys.path.remove(str(BENCHMARKS))


def test_the_csv_formatter_comparison_runs_and_finds_the_same_bytes(bench_core) -> None:
    log = synthetic_grasp(rate=1000.0)
    columns = estimate(log.t, log.wrench, "murakami2006").columns()
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        bench_core.csv_formatters(columns)
    text = printed.getvalue()
    assert "compiled formatter" in text
    assert "same bytes as the fallback on the first blocks: True" in text, text
