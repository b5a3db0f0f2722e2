"""One grammar across the commands: -o/--output (old names kept), lengths with units, defaults
as typed, simulate's report and file modes, --rerun without a display, the --plot |h| panel."""

from __future__ import annotations

import csv
import math
import os
import re
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from softtip.cli.types import Force, Length, as_written
from softtip.core.units import KGF, KGF_MM

SOFTTIP = Path(sys.executable).with_name("softtip")
COMMANDS = ("estimate", "stream", "simulate", "reproduce", "calibrate", "calibrate-payload", "fuse")


def run(*args, env=None, umask=None, cwd=None):
    pre = (lambda: os.umask(umask)) if umask is not None else None
    return subprocess.run(
        [SOFTTIP, *map(str, args)], capture_output=True, text=True, env=env, preexec_fn=pre, cwd=cwd, timeout=300
    )


def _example_estimates():
    from softtip.core.fingertip import load_fingertip
    from softtip.estimator import estimate
    from softtip.estimator.results import EstimatorWarning
    from softtip.io.examples import load_example

    log = load_example()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", EstimatorWarning)
        return estimate(log.t, log.wrench, load_fingertip("murakami2006"))


# -- option types ------------------------------------------------------------------------------


@given(st.floats(1e-3, 1e3))
def test_a_length_is_the_same_in_every_unit(mm: float) -> None:
    length = Length("mm", 0.0, min_open=True)
    bare = length.convert(repr(mm), None, None)
    assert bare == pytest.approx(mm * 1e-3, rel=1e-12)
    for text in (f"{mm!r}mm", f"{mm!r} mm", f"{mm / 10!r}cm", f"{mm * 1e-3!r}m", f"{mm * 1e3!r}um"):
        assert length.convert(text, None, None) == pytest.approx(bare, rel=1e-12), text


@given(st.floats(1e-3, 1e3))
def test_a_force_in_kgf_or_newtons(n: float) -> None:
    force = Force(0.0)
    assert force.convert(repr(n), None, None) == pytest.approx(n, rel=1e-12)
    assert force.convert(f"{n / KGF!r}kgf", None, None) == pytest.approx(n, rel=1e-12)
    assert force.convert(f"{n!r}N", None, None) == pytest.approx(n, rel=1e-12)


def test_defaults_print_as_typed() -> None:
    assert as_written(0.030000000000000002) == "0.03"
    assert as_written((2.0, "0.2mm")) == "2 0.2mm"
    assert as_written(600000.0) == "600000"


# -- --help of every command -------------------------------------------------------------------


def test_help_shows_defaults_as_people_write_them() -> None:
    env = {**os.environ, "COLUMNS": "250"}
    helps = {}
    for command in COMMANDS:
        out = run(command, "--help", env=env)
        assert out.returncode == 0, out.stderr
        helps[command] = out.stdout
        assert not re.search(r"\d\.\d{7,}|\d{6,}\.\d", out.stdout), (command, re.findall(r"\S*\d\.\d{7,}\S*", out.stdout))
        assert "-o, --output" in out.stdout, command
    assert "INPUT" not in helps["stream"]  # stream reads --netft or --replay, no INPUT argument
    assert "-o, --output, --record FILE.csv" in helps["stream"]
    assert "-o, --output, --out DIR" in helps["reproduce"]
    assert "[default: 0.2kgf 0.5kgf]" in helps["estimate"]


# -- lengths with units through the command ----------------------------------------------------


def test_length_options_take_units(tmp_path: Path) -> None:
    outs = {}
    for value in ("3", "3mm", "0.3cm"):
        out = tmp_path / f"{value}.csv"
        r = run("estimate", "--example", "--relatch-distance", value, "--evidence-reset-distance", "1mm",
                "--line-fit-max-angle-std", "2", "--line-fit-max-offset-std", "0.2mm", "-o", out, "-q")  # fmt: skip
        assert r.returncode == 0, r.stderr
        outs[value] = out.read_bytes()
    assert outs["3"] == outs["3mm"] == outs["0.3cm"]
    bad = run("estimate", "--example", "--relatch-distance", "3parsecs", "-o", tmp_path / "bad.csv")
    assert bad.returncode == 2 and "'--relatch-distance'" in bad.stderr and "length" in bad.stderr
    assert not (tmp_path / "bad.csv").exists()


def test_output_aliases_of_stream(tmp_path: Path) -> None:
    from softtip.io.examples import EXAMPLE_PATH

    tables = []
    for flag in ("-o", "--output", "--record"):
        out = tmp_path / f"rec{flag.strip('-')}.csv"
        r = run("stream", "--replay", EXAMPLE_PATH, "--speed", "0", flag, out, "--no-view")
        assert r.returncode == 0, r.stderr
        with open(out, newline="") as fh:
            rows = list(csv.DictReader(line for line in fh if not line.startswith("#")))
        tables.append([{k: v for k, v in row.items() if k != "host_time"} for row in rows])
    assert len(tables[0]) > 100 and tables[0] == tables[1] == tables[2]


# -- simulate: what it wrote, and with which mode ----------------------------------------------


def test_simulate_says_what_it_wrote_and_honours_the_umask(tmp_path: Path) -> None:
    args = ("simulate", "--duration", "3", "--elements", "2000", "-o", "log.csv")
    r = run(*args, umask=0o027, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "-> log.csv, log.truth.json" in r.stderr
    for name in ("log.csv", "log.truth.json"):
        assert (tmp_path / name).stat().st_mode & 0o777 == 0o640, name
    os.chmod(tmp_path / "log.csv", 0o604)  # a replaced file keeps its mode
    r = run(*args, umask=0o077, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "log.csv").stat().st_mode & 0o777 == 0o604


def test_output_directories_follow_the_umask(tmp_path: Path) -> None:
    from softtip.io.atomic import partial_dir

    old = os.umask(0o022)
    try:
        d = partial_dir(tmp_path / "bag")
    finally:
        os.umask(old)
    assert d.parent == tmp_path and d.name.startswith(".bag.") and d.stat().st_mode & 0o777 == 0o755


# -- --rerun on a machine without a display ----------------------------------------------------


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the display check is Linux's")
def test_rerun_without_a_display_stops_at_once(tmp_path: Path) -> None:
    pytest.importorskip("rerun")
    from softtip.io.examples import EXAMPLE_PATH

    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    for args in (("estimate", "--example", "-o", tmp_path / "e.csv"), ("stream", "--replay", EXAMPLE_PATH, "-o", tmp_path / "s.csv")):
        r = run(*args, "--rerun", env=env)
        assert r.returncode == 2, r.stderr
        assert "no display" in r.stderr and "--rerun-save FILE.rrd" in r.stderr and "Traceback" not in r.stderr
    assert list(tmp_path.iterdir()) == []


# -- library: what the CLI used to compute itself ----------------------------------------------


def test_columns_in_the_papers_units_and_the_line_threshold() -> None:
    from softtip.estimator import EstimatorConfig
    from softtip.estimator.columns import COLUMNS

    est = _example_estimates()
    si, kgf = est.columns(), est.columns(units="kgf-mm")
    assert list(si) == list(kgf)
    units = {c.name: c.unit for c in COLUMNS}
    assert {n for n in si if units[n] == "N"} == {"fx", "fy", "fz", "drift_fx", "drift_fy", "drift_fz"}
    for name in si:
        unit = KGF if units[name] == "N" else KGF_MM if units[name] == "N·m" else None
        if unit is None:
            assert np.array_equal(np.asarray(si[name]), np.asarray(kgf[name]), equal_nan=si[name].dtype.kind == "f"), name
        else:  # exactly the division the CLI did before
            np.testing.assert_array_equal(kgf[name], si[name] / unit, err_msg=name)
    config = EstimatorConfig(h_sigmas=2.0, h_min=1e-3)
    np.testing.assert_array_equal(config.line_threshold([1e-4, 1e-3]), [1e-3, 2e-3])
    assert est.state[est.h_norm > EstimatorConfig().line_threshold(est.h_std)].min() >= 2  # above it: line or area


def test_plot_shows_h_as_missing_while_latching(tmp_path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.collections import PolyCollection

    from softtip.viz.plot import latching, plot_estimates

    est = _example_estimates()
    shade = latching(est)
    assert shade.sum() >= 5 and np.all(est.state[shade] > 0)
    fig = plot_estimates(est, tmp_path / "p.png", h_threshold=1e-3)
    ax_h = next(ax for ax in fig.axes if ax.get_ylabel().startswith("|h|"))
    y = ax_h.lines[0].get_ydata()
    assert np.all(np.isnan(y[shade])) and np.all(np.isfinite(y[(est.state > 0) & ~shade]))
    assert any(isinstance(c, PolyCollection) and c.get_label().startswith("latching") for c in ax_h.collections)
    assert any(ax.get_ylabel() == "state" for ax in fig.axes)  # the state band
    assert (tmp_path / "p.png").stat().st_size > 10_000


@pytest.mark.parametrize(("truth", "drawn"), [(45.0, [45.0]), (90.0, [-90.0, 90.0]), (-88.0, [-88.0, 92.0]), (135.0, [-45.0])])
def test_a_true_direction_is_drawn_where_its_measurements_fall(truth: float, drawn: list[float]) -> None:
    """A direction is axial: a truth near ±90° is dashed on both edges of the direction chart."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from softtip.viz.plot import draw_truth

    fig, ax = plt.subplots()
    draw_truth(ax, truth, color="k")
    assert sorted(line.get_ydata()[0] for line in ax.lines) == drawn
    plt.close(fig)


def test_the_line_or_area_figure_dashes_where_h_of_the_true_line_lies() -> None:
    """X1's left panel: with a true direction d, the dashed line is n × d (d turned by 90°), and
    the example grasp's h (a 45° line) lies along it; without one, nothing is dashed."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from softtip.viz.plot import plot_line_or_area

    est = _example_estimates()
    fig = plot_line_or_area([("with", est, 45.0), ("without", est, None)], t_from=6.0)
    with_ax, without_ax = (ax for ax in fig.axes if ax.get_xlabel().startswith("h·e1"))
    (dashed,) = [ln for ln in with_ax.lines if ln.get_linestyle() == "--"]
    x, y = dashed.get_data()
    assert math.degrees(math.atan2(y[1] - y[0], x[1] - x[0])) % 180 == pytest.approx(135.0)
    h1, h2 = with_ax.lines[0].get_data()  # the trace: along n × d, up to the noise
    assert math.degrees(math.atan2(np.median(h2), np.median(h1))) % 180 == pytest.approx(135.0, abs=3.0)
    assert not [ln for ln in without_ax.lines if ln.get_linestyle() == "--"]
    plt.close(fig)


def test_calibration_noise_warning_comes_from_the_library(tmp_path: Path) -> None:
    # a noise model far larger than the example log's (a still larger one, 0.2 N and 2 N·mm, ends the fit
    # far from its start sphere and adds the delete-one-press jackknife: 20 s instead of 1 s;
    # the jackknife has its own tests in test_calibration.py)
    r = run("calibrate", "--example", "--shape", "sphere", "--force-noise", "0.05", "--moment-noise", "0.5", "-o", tmp_path / "t.toml")
    assert r.returncode == 0, r.stderr
    assert "softtip: warning: the residual is" in r.stderr and "(--force-noise 0.05 N, --moment-noise 0.5 N·mm)" in r.stderr
    ratio = float(re.search(r"the residual is ([0-9.]+) times", r.stderr).group(1))
    assert ratio < 0.5  # the residual is a small fraction of the noise model
