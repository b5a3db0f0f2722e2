"""``--markdown PATH`` for the benchmark scripts: what a run prints, also written to a file that
the documentation's benchmark pages include (their figures are the scripts', not typed by hand).

    sys.exit(run_with_markdown(main, "bench_core.py", code_block=True))
"""

from __future__ import annotations

import argparse
import os
import resource
import shlex
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path


class _Tee:
    """Standard output, also kept."""

    def __init__(self, out):
        self.out, self.kept = out, []

    def write(self, text: str) -> int:
        self.kept.append(text)
        return self.out.write(text)

    def flush(self) -> None:
        self.out.flush()


def markdown_option(parser: argparse.ArgumentParser) -> None:
    """List ``--markdown PATH`` in ``parser``'s help (:func:`run_with_markdown` takes it out of the
    arguments before the parser sees them)."""
    parser.add_argument("--markdown", metavar="PATH",
                        help="also write what the run prints to PATH, headed by the command and its time (the "
                             "generated pages of docs/benchmarks/)")  # fmt: skip


def run_with_markdown(main: Callable[[list[str]], int | None], script: str, argv: Sequence[str] | None = None, *,
                      code_block: bool = False) -> int:  # fmt: skip
    """Run ``main(argv)``; with ``--markdown PATH`` in ``argv`` its standard output is also
    written to PATH (only when it returns 0 or None), headed by the command that made it and
    how long it took (wall and CPU time, and the machine's load average, which says how
    shared the machine was).

    Parameters
    ----------
    main : callable
        The script's ``main``, taking the argument list without ``--markdown PATH``.
    script : str
        The script's file name under ``benchmarks/``, for the header.
    argv : sequence of str, optional
        Default ``sys.argv[1:]``.
    code_block : bool
        The output is plain text (in a fenced block); otherwise Markdown (its ``###`` headings
        become ``####``, to sit under the including page's sections).
    """
    argv = list(sys.argv[1:] if argv is None else argv)
    if "--markdown" not in argv:
        return main(argv) or 0
    k = argv.index("--markdown")
    if k + 1 >= len(argv):
        print(f"{script}: --markdown needs a PATH", file=sys.stderr)
        return 2
    path = Path(argv[k + 1])
    del argv[k : k + 2]
    tee = _Tee(sys.stdout)
    sys.stdout = tee
    wall, load = time.perf_counter(), os.getloadavg()[0]
    try:
        code = main(argv) or 0
    finally:
        sys.stdout = tee.out
    if code == 0:
        wall = time.perf_counter() - wall
        cpu = sum(u.ru_utime + u.ru_stime for u in map(resource.getrusage, (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN)))
        took = (f"{wall / 60:.1f} min ({cpu / 60:.1f} min CPU) on {os.cpu_count()} cores, load average "
                f"{load:.1f} at the start and {os.getloadavg()[0]:.1f} at the end")  # fmt: skip
        command = shlex.join(["python", f"benchmarks/{script}", *argv])  # quoted: the line runs as printed
        text = "".join(tee.kept)
        body = f"```text\n{text}```\n" if code_block else ("\n" + text).replace("\n### ", "\n#### ")[1:]
        path.write_text(f"<!-- written by {command} --markdown {shlex.quote(path.name)}; do not edit -->\n\n"
                        f"Run: `{command}`, {took}\n\n" + body, encoding="utf-8")  # fmt: skip
    return code
