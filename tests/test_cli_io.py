"""``softtip estimate`` with Parquet, the reader's warnings, and the progress bar."""

from __future__ import annotations

import io
import os
import select
import subprocess
import sys
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq

from softtip import estimate, load_example
from softtip.core.units import KGF
from softtip.io.tables import PARQUET_FINGERTIP_KEY, PARQUET_UNITS_KEY, write_table

SOFTTIP = str(Path(sys.executable).with_name("softtip"))
WRENCH = ("fx", "fy", "fz", "mx", "my", "mz")


def run(*args: object) -> subprocess.CompletedProcess:
    return subprocess.run([SOFTTIP, *map(str, args)], capture_output=True, text=True, timeout=120)


def _example_columns(t_scale: float = 1.0) -> dict[str, np.ndarray]:
    log = load_example()
    return {"t": log.t * t_scale, **{name: log.wrench[:, i] for i, name in enumerate(WRENCH)}}


def test_parquet_in_and_out(tmp_path: Path) -> None:
    log = load_example()
    src = tmp_path / "in.parquet"
    write_table({**_example_columns(), "trial": np.full(len(log.t), "a b")}, src)
    dest = tmp_path / "out.parquet"
    out = run("estimate", src, "-o", dest, "--output-units", "kgf-mm")
    assert out.returncode == 0, out.stderr
    table = pq.read_table(dest)
    meta = {k.decode(): v.decode() for k, v in table.schema.metadata.items()}
    assert meta[PARQUET_UNITS_KEY] == "kgf-mm"
    assert meta[PARQUET_FINGERTIP_KEY].startswith('[fingertip]\nshape = "capsule"\nradius = 0.016')
    assert meta["softtip.input"] == str(src) and meta["softtip.tip"] == "murakami2006"
    est = estimate(log.t, log.wrench, "murakami2006")
    # binary, so exactly the library's numbers (forces converted to kgf)
    np.testing.assert_array_equal(table.column("rz").to_numpy(), est.point[:, 2])
    np.testing.assert_array_equal(table.column("fz").to_numpy(), est.wrench[:, 2] / KGF)
    assert table.column("state").to_pylist() == list(est.state_names)
    assert table.column("latched").type == "bool"
    assert set(table.column("trial").to_pylist()) == {"a b"}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.parquet", "out.parquet"]


def test_parquet_bad_input_exits_2_without_output(tmp_path: Path) -> None:
    cols = {k: v.tolist() for k, v in _example_columns().items()}
    cols["fy"][99] = None
    src = tmp_path / "bad.parquet"
    import pyarrow as pa

    pq.write_table(pa.table(cols), src)
    out = run("estimate", src, "-o", tmp_path / "out.parquet")
    assert out.returncode == 2
    assert f"softtip: error: {src}: column 'fy', row 100: empty (null); expected a number" in out.stderr
    assert [p.name for p in tmp_path.iterdir()] == ["bad.parquet"]


def test_time_in_milliseconds_stops_naming_the_option(tmp_path: Path) -> None:
    """Read as seconds, t in ms gives a one-sample tare: the run stops naming --time-units (issue 28)."""
    src = tmp_path / "ms.csv"
    write_table(_example_columns(t_scale=1e3), src)
    out = run("estimate", src, "-o", tmp_path / "out.csv")
    assert out.returncode == 2, out.stderr
    assert f"softtip: error: {src}: column 't': median step 20 s" in out.stderr
    assert "if t is in milliseconds 50 Hz (--time-units ms)" in out.stderr and "Stopped: give --time-units" in out.stderr
    assert not (tmp_path / "out.csv").exists()
    out = run("estimate", src, "--time-units", "ms", "-o", tmp_path / "out.csv")
    assert out.returncode == 0, out.stderr
    assert "warning" not in out.stderr


def _repeated_stamp_log(tmp_path: Path) -> Path:
    cols = _example_columns()
    cols["t"][200] = cols["t"][199]
    src = tmp_path / "rep.csv"
    write_table(cols, src, float_format="%.17g")
    return src


def test_repeated_stamps_are_estimated_and_warned_about(tmp_path: Path) -> None:
    src = _repeated_stamp_log(tmp_path)
    out = run("estimate", src, "-o", tmp_path / "out.csv")
    assert out.returncode == 0, out.stderr
    assert (
        f"softtip: warning: {src}: 1 repeated time stamp (the first on line 202: t = 3.98 s as on the line before); "
        "kept in file order"
    ) in out.stderr


def test_progress_bar_only_on_a_terminal() -> None:
    from softtip.cli.options import progress_bar

    plain = io.StringIO()
    with progress_bar(100, "writing", file=plain, delay=0.0) as bar:
        bar.update(100)
    assert plain.getvalue() == ""

    master, slave = os.openpty()
    shown = ""
    try:
        with open(slave, "w", closefd=False) as tty, progress_bar(100, "writing", file=tty, delay=0.0) as bar:
            bar.update(40)
            bar.refresh()
            tty.flush()
            while "40.0/100" not in shown and select.select([master], [], [], 5.0)[0]:
                shown += os.read(master, 4096).decode()
    finally:
        os.close(master)
        os.close(slave)
    assert "softtip: writing" in shown and "40.0/100" in shown


def test_simulate_refuses_a_table_name_it_would_fill_with_csv(tmp_path: Path) -> None:
    """simulate writes CSV: -o x.parquet / x.arrow / x.bag exits 2, and nothing is written."""
    for name in ("x.parquet", "x.feather", "x.bag"):
        done = subprocess.run([SOFTTIP, "simulate", "-o", str(tmp_path / name)], capture_output=True, text=True, timeout=120)
        assert done.returncode == 2 and "Invalid value for '-o'" in done.stderr, done.stderr
    assert not list(tmp_path.iterdir())


def test_a_log_cut_inside_its_last_row(tmp_path: Path) -> None:
    # refused, naming the line and the option; read without that line with --missing drop
    log = load_example()
    src = tmp_path / "cut.csv"
    write_table(_example_columns(), src)
    text = src.read_text()
    src.write_text(text[: text.rstrip("\n").rfind(",") - 2])  # the last row cut inside a cell
    last = text.count("\n")
    out = run("estimate", src, "-q", "-o", tmp_path / "out.csv")
    assert out.returncode == 2 and not (tmp_path / "out.csv").exists()
    assert f"cut.csv:{last}: expected 7 cells" in out.stderr and "or give --missing drop" in out.stderr
    out = run("estimate", src, "--missing", "drop", "-o", tmp_path / "out.csv")
    assert out.returncode == 0, out.stderr
    assert f"cut.csv:{last}: the file ends inside this line" in out.stderr
    assert (tmp_path / "out.csv").read_text().count("\n") == len(log.t)  # the header and every row but the cut one

