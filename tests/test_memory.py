"""Memory stays bounded by the log's size and the piece size, whatever its text cells hold (issue 32)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from softtip.io.tables import iter_log

SOFTTIP = str(Path(sys.executable).with_name("softtip"))

# Runs a command and prints its peak resident memory (kB on Linux).
_PEAK = (
    "import resource, subprocess, sys; done = subprocess.run(sys.argv[1:], capture_output=True); "
    "print(done.returncode, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)"
)


def _peak_mb(*args: object) -> tuple[int, float]:
    done = subprocess.run([sys.executable, "-c", _PEAK, SOFTTIP, *map(str, args)], capture_output=True, text=True,
                          timeout=120, check=True)  # fmt: skip
    code, kb = done.stdout.split()
    return int(code), int(kb) / 1024


def _log_with_note(path: Path, rows: int, note: str, bad_last: bool = False) -> None:
    rng = np.random.default_rng(0)
    w = rng.normal(0.0, 1.0, (rows, 6)) * np.array([3e-3] * 3 + [1.5e-5] * 3)
    lines = ["t,fx,fy,fz,mx,my,mz,note\n"]
    lines += [f"{i / 1000:.3f},{','.join(f'{v:.8f}' for v in w[i])},ok\n" for i in range(rows)]
    lines[101] = lines[101][: -len("ok\n")] + note + "\n"
    if bad_last:
        lines[-1] = lines[-1].replace(",", ",abc", 1)
    path.write_text("".join(lines))


def test_block_reader_text_columns_are_not_as_wide_as_the_longest_cell(tmp_path: Path) -> None:
    src = tmp_path / "in.csv"
    _log_with_note(src, 20000, "x" * 2000)
    blocks = list(iter_log(src))
    assert sum(len(t) for t, _, _ in blocks) == 20000
    for t, _, extra in blocks:
        assert extra["note"].nbytes <= 8 * len(t)  # pointers, not 2000 characters a cell
    assert blocks[0][2]["note"][100] == "x" * 2000


@pytest.mark.parametrize("pieces", [[], ["--chunk-rows", 20000]], ids=["one-shot", "pieces"])
def test_one_long_text_cell_does_not_multiply_memory(tmp_path: Path, pieces: list) -> None:
    """One 2000-character note in 60000 rows took 480 MB more (a unicode column 8000 bytes a cell)."""
    short, long = tmp_path / "short.csv", tmp_path / "long.csv"
    _log_with_note(short, 60000, "ok")
    _log_with_note(long, 60000, "x" * 2000)
    code_short, base = _peak_mb("estimate", short, "-o", tmp_path / "a.csv", *pieces)
    code_long, peak = _peak_mb("estimate", long, "-o", tmp_path / "b.csv", *pieces)
    assert code_short == code_long == 0
    assert peak < base + 120, (base, peak)
    assert ("x" * 2000) in (tmp_path / "b.csv").read_text()
