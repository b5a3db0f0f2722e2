"""The line evidence through the installed ``softtip`` command: simulate --rock, estimate
with and without it, and its options' errors."""

import csv
import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

import simcache

SOFTTIP = str(Path(sys.executable).with_name("softtip"))


def run(*args):
    env = simcache.subprocess_env() if args[:1] == ("simulate",) else None  # the grasps from the tests' cache
    return subprocess.run([SOFTTIP, *map(str, args)], capture_output=True, text=True, timeout=120, env=env)


def read_csv(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


@pytest.fixture(scope="module")
def rocked_plane(tmp_path_factory):
    d = tmp_path_factory.mktemp("rock")
    log = d / "plane.csv"
    out = run("simulate", "--object", "plane", "--rock", "--rock-period", "0.5", "--angle", "15", "--elements", "1200",
              "--seed", "5", "-o", log)  # fmt: skip
    assert out.returncode == 0, out.stderr
    return log


def test_rocked_plane_is_an_area_and_off_gives_the_papers_lines(rocked_plane, tmp_path):
    out = run("estimate", rocked_plane, "-o", tmp_path / "on.csv")
    assert out.returncode == 0, out.stderr
    rows = read_csv(tmp_path / "on.csv")
    # after both axes were rocked (one period into the second rocking axis) the plane is an area
    a2 = next(d for d in json.loads(rocked_plane.with_suffix(".truth.json").read_text())["scenario"]["disturbances"]
              if d["label"] == "rock-a2")  # fmt: skip
    late = [r["state"] for r in rows if float(r["t"]) >= a2["start_s"] + a2["period_s"]]
    assert late.count("area") >= 0.9 * len(late) and "line" not in late
    assert all(r["line_evidence"] in ("confirmed", "unconfirmed") for r in rows if r["state"] == "line")
    assert all(r["line_evidence"] == "" and r["angle_deg"] == "nan" for r in rows if r["state"] != "line")
    assert " area" in out.stderr
    assert re.search(r"\d+ line \((none confirmed: the load never turned|\d+ confirmed by a load turned)", out.stderr)
    off = run("estimate", rocked_plane, "-o", tmp_path / "off.csv", "--no-line-evidence")
    assert off.returncode == 0, off.stderr
    rows = read_csv(tmp_path / "off.csv")
    assert not any(r["state"] == "area" for r in rows)
    assert {r["line_evidence"] for r in rows if r["state"] == "line"} == {"unconfirmed"}


@pytest.mark.parametrize(
    "args, word",
    [
        (["--area-ratio", "0.1", "0.3"], "area_ratio"),
        (["--line-evidence=off"], "--line-evidence"),
        (["--evidence-window", "0"], "--evidence-window"),
        (["--excitation-ratio", "0"], "--excitation-ratio"),
        (["--excitation-min", "-1"], "--excitation-min"),
        (["--evidence-reset-distance", "-1"], "--evidence-reset-distance"),
        (["--evidence-model-std", "-0.5"], "--evidence-model-std"),
        (["--unconfirmed-model-std", "nan"], "--unconfirmed-model-std"),
    ],
)
def test_bad_evidence_options_exit_2_naming_them(args, word, tmp_path):
    out = run("estimate", "--example", "-o", tmp_path / "x.csv", *args)
    assert out.returncode == 2
    assert word in out.stderr
    assert not (tmp_path / "x.csv").exists()


def test_the_window_direction_std_carries_the_model_error_option(tmp_path):
    log = tmp_path / "plate.csv"
    out = run("simulate", "--object", "plate", "--rock", "--rock-period", "0.5", "--angle", "30", "--elements", "1200",
              "--seed", "5", "-o", log)  # fmt: skip
    assert out.returncode == 0, out.stderr
    stds = {}
    for model in ("0", "2"):
        out = run("estimate", log, "-o", tmp_path / f"m{model}.csv", "--evidence-model-std", model,
                  "--unconfirmed-model-std", "0")  # fmt: skip
        assert out.returncode == 0, out.stderr
        stds[model] = [float(r["angle_std_deg"]) for r in read_csv(tmp_path / f"m{model}.csv")
                       if r["line_evidence"] == "confirmed"]  # fmt: skip
    assert len(stds["0"]) > 50 and len(stds["0"]) == len(stds["2"])
    # added in quadrature to a direction from a window excited about two axes (the window's own
    # term unchanged); a one-axis window's carries --unconfirmed-model-std (0 here) instead
    two_axis = 0
    for a, b in zip(stds["0"], stds["2"]):
        if b != a:
            assert b >= 2.0 - 1e-9 and abs(b * b - a * a - 4.0) < 1e-6 * max(1.0, b * b)
            two_axis += 1
    assert two_axis > 20


def test_rock_needs_the_paper_scenario(tmp_path):
    out = run("simulate", "--rock", "--scenario", "push", "-o", tmp_path / "x.csv")
    assert out.returncode == 2 and "--rock" in out.stderr
    assert not (tmp_path / "x.csv").exists()
