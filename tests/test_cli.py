"""The installed ``softtip`` command, run as a user would."""

import csv
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from softtip import EXAMPLE_PATH, EstimatorConfig, estimate, load_example
from softtip.core.units import KGF, KGF_MM
from softtip.io.tables import read_log, write_table

SOFTTIP = str(Path(sys.executable).with_name("softtip"))
SPEC_COLUMNS = (
    "t state fx fy fz mx my mz rx ry rz nx ny nz sigma hx hy hz h_norm dx dy dz angle_deg".split()
)


def run(*args, stdin=None, cwd=None):
    return subprocess.run(
        [SOFTTIP, *map(str, args)], capture_output=True, text=True, input=stdin, cwd=cwd, timeout=120
    )


def read_csv(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_help_explains_units_and_frames():
    for args in ([], ["estimate"]):
        out = run(*args, "--help")
        assert out.returncode == 0
        assert "sensor frame" in out.stdout and "N·m" in out.stdout


def test_example_writes_csv_and_plot(tmp_path):
    out = run("estimate", "--example", "-o", tmp_path / "est.csv", "--plot", tmp_path / "est.png")
    assert out.returncode == 0, out.stderr
    rows = read_csv(tmp_path / "est.csv")
    assert list(rows[0])[: len(SPEC_COLUMNS)] == SPEC_COLUMNS
    assert {r["state"] for r in rows} == {"none", "point", "line"}
    angles = [float(r["angle_deg"]) for r in rows if r["state"] == "line"]
    assert abs(np.median(angles) - 45.0) < 3.0
    # nothing measured where there is no contact or no line
    none = [r for r in rows if r["state"] == "none"]
    assert all(r["rx"] == "nan" and r["angle_deg"] == "nan" for r in none)
    assert all(r["angle_deg"] == "nan" for r in rows if r["state"] == "point")
    assert (tmp_path / "est.png").stat().st_size > 10_000
    assert sorted(p.name for p in tmp_path.iterdir()) == ["est.csv", "est.png"]


def test_stdout_matches_library(tmp_path):
    out = run("estimate", EXAMPLE_PATH)
    assert out.returncode == 0, out.stderr
    rows = list(csv.DictReader(out.stdout.splitlines()))
    log = load_example()
    est = estimate(log.t, log.wrench, "murakami2006")
    assert [r["state"] for r in rows] == list(est.state_names)
    np.testing.assert_allclose([float(r["rz"]) for r in rows], est.point[:, 2], rtol=1e-9, equal_nan=True)


def test_kgf_mm_input_gives_the_si_result(tmp_path):
    log = load_example()
    cols = {"t": log.t}
    for i, name in enumerate(("fx", "fy", "fz", "mx", "my", "mz")):
        cols[name] = log.wrench[:, i] / (KGF if i < 3 else KGF_MM)
    write_table(cols, tmp_path / "kgf.csv", float_format="%.17g")
    si = run("estimate", EXAMPLE_PATH, "-o", tmp_path / "si.csv")
    kg = run("estimate", tmp_path / "kgf.csv", "--units", "kgf-mm", "-o", tmp_path / "kg.csv")
    assert si.returncode == 0 and kg.returncode == 0, kg.stderr
    a, b = read_csv(tmp_path / "si.csv"), read_csv(tmp_path / "kg.csv")
    assert [r["state"] for r in a] == [r["state"] for r in b]
    for key in ("rx", "ry", "rz", "h_norm", "angle_deg"):
        np.testing.assert_allclose(
            [float(r[key]) for r in a], [float(r[key]) for r in b], rtol=1e-8, atol=1e-12, equal_nan=True
        )


@pytest.fixture(scope="module")
def example_run(tmp_path_factory):
    """``softtip estimate --example -o si.csv`` (the defaults): the run and its output, which two
    tests read (each ran this command)."""
    out = tmp_path_factory.mktemp("example") / "si.csv"
    return run("estimate", "--example", "-o", out), out


def test_output_units_kgf_mm(tmp_path, example_run):
    si, si_csv = example_run
    kg = run("estimate", "--example", "--output-units", "kgf-mm", "-o", tmp_path / "kg.csv")
    assert si.returncode == kg.returncode == 0
    a, b = read_csv(si_csv)[-1], read_csv(tmp_path / "kg.csv")[-1]
    assert float(b["fz"]) == pytest.approx(float(a["fz"]) / KGF, rel=1e-8)
    assert float(b["h_norm"]) == pytest.approx(float(a["h_norm"]) / KGF_MM, rel=1e-8)
    assert float(b["rz"]) == pytest.approx(float(a["rz"]))


def test_extra_columns_are_kept(tmp_path):
    src = tmp_path / "in.csv"
    lines = EXAMPLE_PATH.read_text().splitlines()
    src.write_text("\n".join([lines[0] + ",trial"] + [ln + ",a b" for ln in lines[1:]]) + "\n")
    out = run("estimate", src, "-o", tmp_path / "out.csv")
    assert out.returncode == 0, out.stderr
    assert {r["trial"] for r in read_csv(tmp_path / "out.csv")} == {"a b"}


def test_tip_from_toml_and_track_mode(tmp_path):
    toml = tmp_path / "tip.toml"
    toml.write_text('[fingertip]\nshape = "capsule"\nradius = 0.016\nlength = 0.020\n')
    out = run("estimate", "--example", "--tip", toml, "--contact-point", "track", "-o", tmp_path / "o.csv")
    assert out.returncode == 0, out.stderr
    assert {r["state"] for r in read_csv(tmp_path / "o.csv")} == {"none", "point"}


def test_lowpass_option(tmp_path):
    out = run("estimate", "--example", "--lowpass-hz", "5", "-o", tmp_path / "o.csv")
    assert out.returncode == 0, out.stderr
    bad = run("estimate", "--example", "--lowpass-hz", "40", "-o", tmp_path / "p.csv")
    assert bad.returncode == 2 and "Nyquist" in bad.stderr
    assert not (tmp_path / "p.csv").exists()


def good_lines():
    return EXAMPLE_PATH.read_text().splitlines()


def bad_inputs():
    lines = good_lines()
    header, rows = lines[0], lines[1:]
    yield "missing-column", "t,fx,fy,fz,mx,my\n" + "\n".join(",".join(r.split(",")[:6]) for r in rows), ["mz"]
    # (upper case "Fy" is read as fy since issue 28: a real misspelling)
    yield "misspelled-column", header.replace("fy", "fyy") + "\n" + "\n".join(rows), ["fy", "fyy"]
    yield "non-numeric", "\n".join([header] + rows[:5] + ["0.1,abc,0,0,0,0,0"] + rows[6:]), [":7:", "fx", "abc"]
    yield "nan", "\n".join([header] + rows[:3] + [rows[3].replace(rows[3].split(",")[3], "nan", 1)] + rows[4:]), [":5:", "fz"]
    yield "inf", "\n".join([header] + rows[:3] + ["0.07,inf,0,0,0,0,0"] + rows[4:]), [":5:", "fx"]
    yield "time-not-increasing", "\n".join([header] + rows[:10] + [rows[8]] + rows[11:]), [":12:", "t"]
    yield "empty", "", ["empty"]
    yield "header-only", header + "\n", ["no data"]


@pytest.mark.parametrize("name,text,needles", list(bad_inputs()), ids=[b[0] for b in bad_inputs()])
def test_bad_input_exits_2_with_a_clear_message_and_no_output(tmp_path, name, text, needles):
    src = tmp_path / "bad.csv"
    src.write_text(text)
    dest = tmp_path / "out.csv"
    out = run("estimate", src, "-o", dest, "--plot", tmp_path / "out.png")
    assert out.returncode == 2
    assert "bad.csv" in out.stderr
    for needle in needles:
        assert needle.lower() in out.stderr.lower(), out.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.csv"]


def test_failure_leaves_an_existing_output_untouched(tmp_path):
    src = tmp_path / "bad.csv"
    src.write_text("t,fx\n0,1\n")
    dest = tmp_path / "out.csv"
    dest.write_text("precious\n")
    assert run("estimate", src, "-o", dest).returncode == 2
    assert dest.read_text() == "precious\n"


@pytest.mark.parametrize(
    "args,needles",
    [
        (["--units", "furlongs"], ["furlongs", "si", "kgf-mm"]),
        (["--tip", "nonexistent_preset"], ["nonexistent_preset", "murakami2006"]),
        (["--tip", "missing.toml"], ["missing.toml", "not found"]),
        (["--contact-point", "windowed"], ["windowed", "latch", "track", "line-fit"]),
        (["--contact-point", "line-fit", "--line-fit-max-angle-std", "0", "--line-fit-max-offset-std", "0.2"], ["--line-fit-max-angle-std", "0"]),
        (["--contact-point", "line-fit", "--line-fit-window", "-1"], ["--line-fit-window", "-1"]),
    ],
)
def test_bad_options_exit_2(tmp_path, args, needles):
    out = run("estimate", "--example", "-o", tmp_path / "o.csv", *args)
    assert out.returncode == 2
    for needle in needles:
        assert needle in out.stderr
    assert not (tmp_path / "o.csv").exists()


@pytest.mark.parametrize(
    "text,needles",
    [
        ("[fingertip\nshape=", ["malformed TOML"]),
        ('[fingertip]\nshape = "cube"\nradius = 0.01\n', ["cube", "sphere", "capsule"]),
        ('[fingertip]\nshape = "capsule"\nradius = 0.016\n', ["missing", "length"]),
        ('[fingertip]\nshape = "sphere"\nradius = -1\n', ["radius", "positive"]),
        ('[fingertip]\nshape = "sphere"\nradius = 0.01\nradios = 2\n', ["radios"]),
        ('[fingertip]\nshape = "sphere"\nradius = "big"\n', ["radius", "number"]),
    ],
)
def test_malformed_fingertip_file(tmp_path, text, needles):
    toml = tmp_path / "tip.toml"
    toml.write_text(text)
    out = run("estimate", "--example", "--tip", toml, "-o", tmp_path / "o.csv")
    assert out.returncode == 2
    assert "tip.toml" in out.stderr
    for needle in needles:
        assert needle in out.stderr, out.stderr
    assert not (tmp_path / "o.csv").exists()


def test_input_and_example_are_exclusive(tmp_path):
    assert run("estimate").returncode == 2
    assert run("estimate", EXAMPLE_PATH, "--example").returncode == 2


def test_pulling_samples_are_none_with_a_warning(tmp_path):
    log = read_log(EXAMPLE_PATH)
    w = log.wrench.copy()
    w[300:320, 2] = -w[300:320, 2] + 2 * w[0, 2]  # pull on the tip instead of pushing
    cols = {"t": log.t, **{n: w[:, i] for i, n in enumerate(("fx", "fy", "fz", "mx", "my", "mz"))}}
    write_table(cols, tmp_path / "pull.csv", float_format="%.17g")
    out = run("estimate", tmp_path / "pull.csv", "-o", tmp_path / "o.csv")
    assert out.returncode == 0, out.stderr
    assert "warning" in out.stderr and "20 sample" in out.stderr
    states = [r["state"] for r in read_csv(tmp_path / "o.csv")]
    assert set(states[300:320]) == {"none"}


def test_stdin_input():
    out = run("estimate", "-", stdin=EXAMPLE_PATH.read_text())
    assert out.returncode == 0, out.stderr
    assert out.stdout.count("\n") == 501


@pytest.mark.parametrize(
    "args,needles",
    [
        (["--plot", "figure"], ["figure", ".png"]),
        (["--plot", "x.xyz"], ["x.xyz", ".pdf"]),
        (["--plot", "no_such_folder/x.png"], ["no_such_folder", "does not exist"]),
        (["--units", "kgf-mm"], ["--units", "example"]),
        (["--relatch-distance", "-1"], ["--relatch-distance"]),
        (["--h-min", "nan"], ["--h-min", "finite"]),
    ],
)
def test_bad_plot_paths_and_values_exit_2(tmp_path, args, needles):
    out = run("estimate", "--example", "-o", "o.csv", *args, cwd=tmp_path)
    assert out.returncode == 2
    for needle in needles:
        assert needle in out.stderr, out.stderr
    assert list(tmp_path.iterdir()) == []


def test_tare_that_cannot_be_right_is_reported(tmp_path, example_run):
    log = read_log(EXAMPLE_PATH)
    for name, keep in (("short.csv", log.t < 0.1), ("in_contact.csv", log.t > 3.0)):
        cols = {"t": log.t[keep], **{n: log.wrench[keep, i] for i, n in enumerate(("fx", "fy", "fz", "mx", "my", "mz"))}}
        write_table(cols, tmp_path / name)
    short = run("estimate", tmp_path / "short.csv", "-o", tmp_path / "a.csv")  # nothing to estimate: a located error
    assert short.returncode == 2 and "the whole log (5 samples, t from 0 to 0.08 s as read) lies within" in short.stderr
    assert not (tmp_path / "a.csv").exists()
    touched = run("estimate", tmp_path / "in_contact.csv", "-o", tmp_path / "b.csv")
    assert touched.returncode == 0 and "while taring" in touched.stderr
    untouched, _ = example_run  # estimate --example -o si.csv
    assert "bias from the first 0.2 s" in untouched.stderr and "while taring" not in untouched.stderr


def test_line_fit_mode_columns(tmp_path):
    out = run("estimate", "--example", "--contact-point", "line-fit", "--line-fit-window", "0.8", "--line-fit-max-angle-std", "3", "--line-fit-max-offset-std", "0.3",
              "-o", tmp_path / "j.csv")  # fmt: skip
    assert out.returncode == 0, out.stderr
    rows = read_csv(tmp_path / "j.csv")
    log = load_example()
    cfg = EstimatorConfig(contact_point="line-fit", line_fit_window=0.8, line_fit_max_angle_std=np.radians(3.0),
                          line_fit_max_offset_std=0.3e-3)  # fmt: skip
    est = estimate(log.t, log.wrench, "murakami2006", cfg)
    assert [r["line_fit_fallback"] for r in rows] == [str(int(v)) for v in est.line_fit_fallback]
    for key, ref in (("line_fit_angle_std_deg", np.degrees(est.line_fit_angle_std)), ("line_fit_residual", est.line_fit_residual),
                     ("rx", est.point[:, 0])):  # fmt: skip
        np.testing.assert_allclose([float(r[key]) for r in rows], ref, rtol=1e-9, equal_nan=True)
    assert np.isfinite(est.line_fit_conditioning).any()
    assert "exceeds the noise model" not in out.stderr
    # a noise model well below the sensor's: line-fit mode would take the rest for excitation
    low = run("estimate", "--example", "--contact-point", "line-fit", "--force-noise", "0.003", "--noise-from-tare", "off",
              "-o", tmp_path / "k.csv")  # fmt: skip
    assert low.returncode == 0 and "exceeds the noise model (0.003 N)" in low.stderr
    # by default the tare raises that model to the noise it shows, and line-fit mode uses it
    raised = run("estimate", "--example", "--contact-point", "line-fit", "--force-noise", "0.003", "-o", tmp_path / "m.csv")
    assert raised.returncode == 0 and "exceeds the noise model" not in raised.stderr
    assert "noise model raised to theirs where larger: force (" in raised.stderr
    latch = run("estimate", "--example", "--force-noise", "0.003", "-o", tmp_path / "l.csv")
    assert "exceeds the noise model" not in latch.stderr


def test_joint_is_no_longer_a_mode(tmp_path):
    """``joint``, the former name of ``line-fit``, is gone (0.x: no alias), on the command line and in the library."""
    b = run("estimate", "--example", "--contact-point", "joint", "-o", tmp_path / "b.csv", "-q")
    assert b.returncode == 2 and "'joint'" in b.stderr and "line-fit" in b.stderr
    with pytest.raises(ValueError, match="contact_point"):
        EstimatorConfig(contact_point="joint")
    helptext = " ".join(run("estimate", "--help").stdout.split())
    assert "line-fit: latch, then" in helptext and "joint" not in helptext.split("--contact-point")[1].split("--")[0]


def test_the_command_runs_without_importing_pandas(tmp_path):
    # pandas comes with the test extras, not with softtip: the console command never imports it
    # (pyarrow would, converting a column: a third of a short run's CPU) and writes the same
    # bytes as a process where pyarrow has pandas
    pytest.importorskip("pandas")
    outs = []
    for first in ("", "import pandas; "):
        outs.append(tmp_path / f"est{len(outs)}.csv")
        code = (
            f"import atexit, sys; {first}from softtip.cli import run; "
            "atexit.register(lambda: print('pandas loaded:', 'pandas' in sys.modules, file=sys.stderr)); "
            f"sys.argv = ['softtip', 'estimate', '--example', '-o', {str(outs[-1])!r}]; run()"
        )
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
        assert out.returncode == 0, out.stderr
        assert f"pandas loaded: {bool(first)}" in out.stderr
    assert outs[0].read_bytes() == outs[1].read_bytes()


def test_the_command_runs_blas_on_one_thread_unless_told(tmp_path):
    # a BLAS thread pool costs every command its start (0.1-0.3 s of CPU) and helps none of its
    # small-matrix maths: the command sets OpenBLAS to one thread before numpy loads, unless the
    # user's environment says how many; the output is the same bytes either way
    import os

    from softtip.cli.app import _one_blas_thread

    for given, expected in (({}, "1"), ({"OPENBLAS_NUM_THREADS": "4"}, "4"), ({"OMP_NUM_THREADS": "2"}, None)):
        environ = dict(given)
        _one_blas_thread(environ)
        assert environ.get("OPENBLAS_NUM_THREADS") == expected and {k: environ[k] for k in given} == given
    env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
    outs = []
    for extra in ({}, {"OPENBLAS_NUM_THREADS": "2"}):
        outs.append(tmp_path / f"est{len(outs)}.csv")
        code = (
            "import atexit, os, sys; from softtip.cli import run; "
            "assert 'numpy' not in sys.modules, 'numpy loaded before the command set its threads'; "
            "atexit.register(lambda: print('blas threads:', os.environ.get('OPENBLAS_NUM_THREADS'), file=sys.stderr)); "
            f"sys.argv = ['softtip', 'estimate', '--example', '-o', {str(outs[-1])!r}]; run()"
        )
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, env={**env, **extra})
        assert out.returncode == 0, out.stderr
        assert f"blas threads: {extra.get('OPENBLAS_NUM_THREADS', '1')}" in out.stderr
    assert outs[0].read_bytes() == outs[1].read_bytes()


def test_the_command_list_is_the_commands_own_help() -> None:
    """``softtip --help`` lists the commands from the registry without importing them: the
    same lines, at every width, as the commands themselves would give."""
    import click
    from click.testing import CliRunner

    from softtip.cli.app import COMMANDS, main

    real = click.Group("softtip", commands=[main.commands[name] for name in COMMANDS])
    assert sorted(real.commands) == sorted(COMMANDS)
    for name, (_, _, summary) in COMMANDS.items():
        assert real.commands[name].name == name
        assert summary.split() == real.commands[name].help.split("\n\n")[0].split()
    for width in (40, 60, 80):
        lazy, full = click.Context(main, terminal_width=width), click.Context(real, terminal_width=width)
        for group, ctx in ((main, lazy), (real, full)):
            ctx.formatter = ctx.make_formatter()
            group.format_commands(ctx, ctx.formatter)
        assert lazy.formatter.getvalue() == full.formatter.getvalue() and "Commands:" in lazy.formatter.getvalue()
    assert CliRunner().invoke(main, ["estimat"]).output.endswith("(Did you mean one of: 'estimate', 'simulate'?)\n")


def test_a_command_imports_only_its_own_module() -> None:
    """``import softtip`` imports none of its public names' modules, the ``softtip`` group (its
    --help, --version) not the estimator, and a command's module is imported only when the
    command runs (most of a short run's start-up)."""
    code = (
        "import atexit, json, sys; import softtip; before = sorted(sys.modules); from softtip.cli import run; "
        "group = sorted(sys.modules); sys.argv = ['softtip', 'estimate', '--help']; "
        "atexit.register(lambda: print(json.dumps([before, group, sorted(sys.modules)]))); run()"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    at_import, group, loaded = json.loads(out.stdout.splitlines()[-1])
    assert [m for m in at_import if m.startswith("softtip.") and m != "softtip._version"] == []
    assert not {"softtip.cli.options", "softtip.estimator", "softtip.core.fingertip"} & set(group)  # softtip --help
    assert "softtip.cli.estimate" in loaded
    others = {"softtip.cli.calibrate", "softtip.cli.calibrate_payload", "softtip.cli.fuse", "softtip.cli.reproduce",
              "softtip.cli.simulate", "softtip.cli.stream", "softtip.apps.live"}  # fmt: skip
    assert not others & set(loaded), others & set(loaded)


@pytest.mark.parametrize("pieces", [[], ["--chunk-rows", "100"], ["--chunk-rows", "100", "--jobs", "2"]],
                         ids=["one-shot", "pieces", "pieces-jobs"])  # fmt: skip
def test_a_log_entirely_inside_the_tare_stops_the_run(tmp_path, pieces):
    # 'Time (ms)' over seconds: 10 s read as 10 ms, every sample inside the 0.2 s tare; nothing
    # would be estimated, with exit 0 and a warning before (in pieces, until this was checked there
    # too: a log the pieces' reader takes, t in s under a plain header)
    ex = load_example()
    rows = [f"{t:.6f},{','.join(f'{v:.6g}' for v in w)}" for t, w in zip(ex.t * (1e-3 if pieces else 1.0), ex.wrench)]
    log = tmp_path / "ms.csv"
    log.write_text(("t" if pieces else "Time (ms)") + ",fx,fy,fz,mx,my,mz\n" + "\n".join(rows) + "\n")
    said = f"softtip: error: {log}: the whole log (500 samples, t from 0 to 0.00998 s as read) lies within the first "
    out = subprocess.run([SOFTTIP, "estimate", log, "-o", tmp_path / "out.csv", *pieces], capture_output=True, text=True,
                         timeout=120)  # fmt: skip
    assert out.returncode == 2, out.stderr
    assert said in out.stderr
    assert not (tmp_path / "out.csv").exists()
    if pieces:  # onto standard output: the rows gone out are said to be wrong
        out = subprocess.run([SOFTTIP, "estimate", log, *pieces], capture_output=True, text=True, timeout=120)
        assert out.returncode == 2 and said in out.stderr and "cannot be taken back" in out.stderr, out.stderr
    tared = subprocess.run([SOFTTIP, "estimate", log, "-o", tmp_path / "out.csv", "--tare-duration", "0"],
                           capture_output=True, text=True, timeout=120)  # fmt: skip
    assert "the whole log" not in tared.stderr


def test_a_one_sample_log_stops_the_run_as_a_longer_one_inside_the_tare(tmp_path):
    # one row exited 0 with a warning where two rows stopped; --tare-duration 0 estimates it
    ex = load_example()
    log = tmp_path / "one.csv"
    log.write_text("t,fx,fy,fz,mx,my,mz\n" + ",".join(repr(float(v)) for v in (ex.t[0], *ex.wrench[0])) + "\n")
    for args in (("estimate", log, "-o", tmp_path / "o.csv"), ("stream", "--replay", log, "--speed", "0", "-o", tmp_path / "r.csv")):
        out = subprocess.run([SOFTTIP, *map(str, args)], capture_output=True, text=True, timeout=120)
        assert out.returncode == 2 and f"{log}: one sample (t = 0 s): nothing to estimate" in out.stderr, out.stderr
    assert not (tmp_path / "o.csv").exists() and not (tmp_path / "r.csv").exists()
    tared = subprocess.run([SOFTTIP, "estimate", log, "--tare-duration", "0", "-o", tmp_path / "o.csv"], capture_output=True,
                           text=True, timeout=120)  # fmt: skip
    assert tared.returncode == 0, tared.stderr
    assert len((tmp_path / "o.csv").read_text().splitlines()) == 2


def test_a_csv_output_whose_t_cannot_resolve_the_samples_says_so(tmp_path):
    # t from a clock started 30 days ago at 7 kHz: 10 significant digits resolve 1 ms, seven steps
    ex = load_example()
    n = 2000
    rows = [",".join(repr(float(v)) for v in (2.6e6 + k / 7000, *ex.wrench[k % len(ex.t)])) for k in range(n)]
    log = tmp_path / "mono.csv"
    log.write_text("t,fx,fy,fz,mx,my,mz\n" + "\n".join(rows) + "\n")
    said = "t reaches 2.6e+06 s, where the CSV's 10 significant digits resolve 0.001 s, more than a tenth of the log's"
    for out, warned in (("o.csv", True), ("o.parquet", False)):
        done = subprocess.run([SOFTTIP, "estimate", log, "-o", tmp_path / out], capture_output=True, text=True, timeout=120)
        assert done.returncode == 0 and (said in done.stderr) == warned, done.stderr
    example = subprocess.run([SOFTTIP, "estimate", "--example", "-o", tmp_path / "ex.csv"], capture_output=True, text=True,
                             timeout=120)  # fmt: skip
    assert example.returncode == 0 and "t reaches" not in example.stderr
