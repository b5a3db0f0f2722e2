"""Fuzzing ``softtip estimate`` with damaged CSV logs: bytes flipped, cells replaced, lines cut or
duplicated, columns renamed.

Whatever the damage, the command either succeeds with a complete output (one row per sample
of the log as read) or exits 2 with a message that names the file, leaving no output file
and no temporary file; never a traceback. Runs in-process (click's test runner) to stay fast.
"""

import warnings
from pathlib import Path

from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from softtip import EXAMPLE_PATH
from softtip.cli import main
from softtip.errors import InputError
from softtip.io.tables import read_log

# the example grasp, shortened: untouched, then the start of the contact (fast to estimate)
BASE = EXAMPLE_PATH.read_bytes().splitlines(keepends=True)[:180]
NAMES = ["t", "fx", "fy", "fz", "mx", "my", "mz"]
CELLS = ["", " ", "nan", "NaN", "inf", "-inf", "1e400", "-1e400", "abc", "0x10", "1,5", '"', '"1"', "-0", "1e-320", "٣", "\x00", "1 2", "+", "."]


@st.composite
def damaged_logs(draw) -> bytes:
    lines = list(BASE)
    for _ in range(draw(st.integers(1, 3))):
        kind = draw(st.sampled_from(["flip", "cell", "cut", "truncate", "duplicate", "swap", "rename"]))
        k = draw(st.integers(0, len(lines) - 1))
        if kind == "flip" and lines[k]:
            line = bytearray(lines[k])
            i = draw(st.integers(0, len(line) - 1))
            line[i] = draw(st.integers(0, 255))
            lines[k] = bytes(line)
        elif kind == "cell" and lines[k]:
            cells = lines[k].rstrip(b"\r\n").split(b",")
            i = draw(st.integers(0, len(cells) - 1))
            cells[i] = draw(st.sampled_from(CELLS)).encode()
            lines[k] = b",".join(cells) + b"\n"
        elif kind == "cut":
            del lines[k]
        elif kind == "truncate":  # the file ends inside line k
            lines[k] = lines[k][: draw(st.integers(0, len(lines[k])))]
            del lines[k + 1 :]
        elif kind == "duplicate":
            lines.insert(k, lines[k])
        elif kind == "swap" and k + 1 < len(lines):
            lines[k], lines[k + 1] = lines[k + 1], lines[k]
        elif kind == "rename":
            name = draw(st.sampled_from(NAMES))
            new = draw(st.sampled_from([name.upper(), f" {name}", f"{name}_", "", name[:-1] or "x", "t" if name != "t" else "fx"]))
            header = lines[0].rstrip(b"\r\n").split(b",")
            header = [new.encode() if c.strip() == name.encode() else c for c in header]
            lines[0] = b",".join(header) + b"\n"
        if not lines:
            break
    return b"".join(lines)


def _samples(path: Path) -> int | None:
    try:
        return len(read_log(path).t)
    except InputError:
        return None


@settings(max_examples=150)
@given(data=damaged_logs())
def test_damaged_csv_gives_a_complete_output_or_a_located_error(tmp_path_factory, data):
    d = tmp_path_factory.mktemp("fuzz")
    log, out = d / "damaged.csv", d / "est.csv"
    log.write_bytes(data)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the command line shows warnings; they are not failures
        result = CliRunner().invoke(main, ["estimate", str(log), "-o", str(out)])
    if isinstance(result.exception, SystemExit) or result.exception is None:
        pass
    else:  # a traceback
        raise result.exception
    assert result.exit_code in (0, 2), result.output
    if result.exit_code == 0:
        n = _samples(log)
        assert n is not None
        with open(out, newline="") as fh:
            rows = fh.read().splitlines()
        assert len(rows) == n + 1 and rows[0].startswith("t,state,")
        assert sorted(p.name for p in d.iterdir()) == ["damaged.csv", "est.csv"]
    else:
        assert "damaged.csv" in result.output, result.output
        assert sorted(p.name for p in d.iterdir()) == ["damaged.csv"]
