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


def test_markdown_pages_are_what_the_run_printed(tmp_path: Path, capsys) -> None:
    """``--markdown PATH`` (benchmarks/_markdown.py): listed in the script's help, taken out of the
    arguments before its parser sees them, and PATH holds what the run printed under the command
    that made it (quoted, so that it runs as printed); a failed run writes no page."""
    sys.path.insert(0, str(BENCHMARKS))
    try:
        from _markdown import markdown_option, run_with_markdown
    finally:
        sys.path.remove(str(BENCHMARKS))
    import argparse

    def main(argv):
        ap = argparse.ArgumentParser(prog="bench_x.py")
        ap.add_argument("--rows", type=int)
        ap.add_argument("--label", nargs="*")
        markdown_option(ap)
        args = ap.parse_args(argv)
        assert args.markdown is None  # taken out before the parser
        print(f"### {args.rows} rows\n\n| a |\n| --- |")
        return 1 if args.rows < 0 else 0

    page = tmp_path / "page.md"
    assert run_with_markdown(main, "bench_x.py", ["--rows", "3", "--markdown", str(page)]) == 0
    text = page.read_text(encoding="utf-8")
    assert text.startswith("<!-- written by python benchmarks/bench_x.py --rows 3 --markdown page.md; do not edit -->")
    assert "Run: `python benchmarks/bench_x.py --rows 3`" in text and text.endswith("#### 3 rows\n\n| a |\n| --- |\n")
    page.unlink()
    # an argument with spaces is quoted: the printed command runs as it reads
    assert run_with_markdown(main, "bench_x.py", ["--rows", "2", "--label", "plate 1 mm", "--markdown", str(page)]) == 0
    assert "Run: `python benchmarks/bench_x.py --rows 2 --label 'plate 1 mm'`" in page.read_text(encoding="utf-8")
    page.unlink()
    assert run_with_markdown(main, "bench_x.py", ["--rows", "-1", "--markdown", str(page)]) == 1 and not page.exists()
    with pytest.raises(SystemExit):
        main(["--help"])
    assert "--markdown PATH" in capsys.readouterr().out
