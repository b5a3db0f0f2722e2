"""Every option value is range-checked: exit 2, a message naming the option and its unit, no traceback.

Most cases run the command in-process (click's test runner: they fail while parsing, before
any work); a few run the installed ``softtip`` as a user would.
"""

import subprocess
import sys
from pathlib import Path

import click
import pytest
from click.testing import CliRunner

from softtip import EXAMPLE_PATH
from softtip.cli import main
from softtip.cli.types import Number, check_lowpass

SOFTTIP = str(Path(sys.executable).with_name("softtip"))
LOG = str(EXAMPLE_PATH)

# (arguments, the option named in the message, the unit or range the message states)
BAD = [
    # estimate (the estimator options are shared with stream)
    (["estimate", LOG, "--lowpass-hz", "1e-10"], "--lowpass-hz", "Hz"),
    (["estimate", LOG, "--lowpass-hz", "30"], "--lowpass-hz", "Nyquist"),
    (["estimate", LOG, "--lowpass-hz", "nan"], "--lowpass-hz", "Hz"),
    (["estimate", LOG, "--latch-window", "1", "inf"], "--latch-window", "N"),
    (["estimate", LOG, "--latch-window", "3", "2"], "--latch-window", "LOW < HIGH"),
    (["estimate", LOG, "--latch-window", "-1", "2"], "--latch-window", "N"),
    (["estimate", LOG, "--skin-law", "-1", "2", "3", "--depth-compensation", "online"], "--skin-law", "N/m^P"),
    (["estimate", LOG, "--skin-law", "1", "2", "nan", "--depth-compensation", "online"], "--skin-law", "mm"),
    (["estimate", LOG, "--tare-duration", "-1"], "--tare-duration", " s"),
    (["estimate", LOG, "--tare-duration", "nan"], "--tare-duration", " s"),
    (["estimate", LOG, "--contact-threshold", "inf"], "--contact-threshold", " N"),
    (["estimate", LOG, "--h-min", "-0.1"], "--h-min", "N·mm"),
    (["estimate", LOG, "--force-noise", "nan"], "--force-noise", " N"),
    (["estimate", LOG, "--moment-noise", "-1"], "--moment-noise", "N·mm"),
    (["estimate", LOG, "--relatch-distance", "0"], "--relatch-distance", "mm"),
    (["estimate", LOG, "--line-fit-window", "0"], "--line-fit-window", " s"),
    (["estimate", LOG, "--line-fit-max-angle-std", "-1"], "--line-fit-max-angle-std", "deg"),
    (["estimate", LOG, "--line-fit-max-offset-std", "-1"], "--line-fit-max-offset-std", "mm"),
    (["estimate", LOG, "--line-fit-drift", "2000"], "--line-fit-drift", "mm/√s"),
    (["estimate", LOG, "--h-sigmas", "nan"], "--h-sigmas", "noise standard deviations"),
    (["estimate", LOG, "--fallback-samples", "0"], "--fallback-samples", "x>=1"),
    (["estimate", LOG, "--line-fit-max-residual", "inf"], "--line-fit-max-residual", "noise standard deviations"),
    # stream
    (["stream", "--replay", LOG, "--speed", "inf"], "--speed", "real time"),
    (["stream", "--replay", LOG, "--speed", "1e-300"], "--speed", "real time"),
    (["stream", "--replay", LOG, "--speed", "-1"], "--speed", "real time"),
    (["stream", "--netft", "127.0.0.1", "--timeout", "0"], "--timeout", " s"),
    (["stream", "--netft", "127.0.0.1", "--timeout", "-1"], "--timeout", " s"),
    (["stream", "--netft", "127.0.0.1", "--timeout", "nan"], "--timeout", " s"),
    (["stream", "--netft", "127.0.0.1", "--timeout", "1e300"], "--timeout", " s"),
    (["stream", "--netft", "127.0.0.1", "--rdt-port", "70000"], "--rdt-port", "65535"),
    (["stream", "--netft", "127.0.0.1", "--http-port", "0"], "--http-port", "65535"),
    (["stream", "--replay", LOG, "--duration", "inf"], "--duration", " s"),
    (["stream", "--replay", LOG, "--duration", "0"], "--duration", " s"),
    # simulate
    (["simulate", "--friction", "0"], "--friction", "(0, 10]"),
    (["simulate", "--thickness", "100mm"], "--thickness", "mm"),
    (["simulate", "--thickness", "0mm"], "--thickness", "mm"),
    (["simulate", "--rate", "1e12"], "--rate", "Hz"),
    (["simulate", "--rate", "100000", "--duration", "1000"], "--rate", "samples"),
    (["simulate", "--elements", "100000000000"], "--elements", "200000"),
    (["simulate", "--duration", "nan"], "--duration", " s"),
    (["simulate", "--t-contact", "-1"], "--t-contact", " s"),
    (["simulate", "--modulus", "0"], "--modulus", "Pa"),
    (["simulate", "--shear-modulus", "nan"], "--shear-modulus", "Pa"),
    (["simulate", "--mass", "-1"], "--mass", "kg"),
    (["simulate", "--angle", "inf"], "--angle", "deg"),
    (["simulate", "--apex-angle", "180"], "--apex-angle", "deg"),
    (["simulate", "--tilt", "nan"], "--tilt", "deg"),
    (["simulate", "--joint-rotation", "nan"], "--joint-rotation", "deg"),
    (["simulate", "--gravity-spin", "inf"], "--gravity-spin", "deg"),
    (["simulate", "--misalignment", "nan"], "--misalignment", "deg"),
    (["simulate", "--size", "0mm"], "--size", "length"),
    (["simulate", "--force", "0"], "--force", "N"),
    (["simulate", "--seed", "-1"], "--seed", "x>=0"),
    # reproduce
    (["reproduce", "--seed", "-1"], "--seed", "x>=0"),
    (["reproduce", "--jobs", "1000"], "--jobs", "64"),
    # calibrate
    (["calibrate", "--shape", "sphere", LOG, "--tare-duration", "nan"], "--tare-duration", " s"),
    (["calibrate", "--shape", "sphere", LOG, "--tare-duration", "-1"], "--tare-duration", " s"),
    (["calibrate", "--shape", "sphere", LOG, "--contact-threshold", "0"], "--contact-threshold", " N"),
    (["calibrate", "--shape", "sphere", LOG, "--min-force", "inf"], "--min-force", " N"),
]


@pytest.mark.parametrize("args, option, unit", BAD, ids=[" ".join(a[:1] + a[-2:]) for a, _, _ in BAD])
def test_bad_option_value_exits_2_naming_option_and_unit(tmp_path, args, option, unit):
    result = CliRunner().invoke(main, args, catch_exceptions=False)
    assert result.exit_code == 2, result.output
    assert f"'{option}'" in result.output and unit in result.output, result.output
    assert "Traceback" not in result.output
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "args, option",
    [
        (["stream", "--replay", LOG, "--speed", "inf", "--no-view"], "--speed"),
        (["simulate", "--friction", "0"], "--friction"),
        (["calibrate", "--shape", "sphere", LOG, "--tare-duration", "nan"], "--tare-duration"),
    ],
)
def test_bad_option_value_through_the_command(args, option):
    out = subprocess.run([SOFTTIP, *args], capture_output=True, text=True, timeout=120)
    assert out.returncode == 2 and f"'{option}'" in out.stderr and "Traceback" not in out.stderr, out.stderr
    assert out.stdout == ""


def test_simulation_without_equilibrium_is_a_usage_error():
    # a skin almost as thick as the fingertip: the grasp force cannot be reached
    result = CliRunner().invoke(main, ["simulate", "--thickness", "20mm", "--rate", "20", "--duration", "5"], catch_exceptions=False)
    assert result.exit_code == 2 and "no equilibrium" in result.output and "--friction" in result.output



def test_simulate_takes_the_skin_of_the_fingertip_file(tmp_path):
    # the file's skin_thickness is the simulated skin (it used to be the 5 mm default whatever
    # the file said); --thickness still overrides it
    import json

    tip = tmp_path / "tip.toml"
    tip.write_text('[fingertip]\nshape = "sphere"\nradius = 0.012\ncenter = [0.0, 0.0, 0.018]\nskin_thickness = 0.002\n')
    for extra, skin in (([], 0.002), (["--thickness", "3mm"], 0.003)):
        out = tmp_path / f"s{skin}.csv"
        args = ["simulate", "--tip", str(tip), "--scenario", "push", "--duration", "3", "--rate", "20", *extra, "-o", str(out)]
        result = CliRunner().invoke(main, args, catch_exceptions=False)
        assert result.exit_code == 0, result.output
        truth = json.loads(out.with_name(out.stem + ".truth.json").read_text())
        assert truth["skin"]["thickness_m"] == skin

def test_number_type_bounds():
    t = Number("s", 0.0, 10.0, min_open=True)
    assert t.convert("10", None, None) == 10.0 and t.convert(0.5, None, None) == 0.5
    for bad in ("0", "10.5", "nan", "-inf", "x"):
        with pytest.raises(click.BadParameter, match=r"expected a number in \(0, 10\] s"):
            t.convert(bad, None, None)
    assert Number("deg").expected() == "a finite number deg"


def test_lowpass_bounds_follow_the_sample_rate():
    check_lowpass(0.36, 7000.0)
    check_lowpass(None, 7000.0)
    check_lowpass(1.0, [0.0, 0.02, 0.04])
    with pytest.raises(click.BadParameter, match=r"\[0.35, 3500\) Hz"):
        check_lowpass(0.3, 7000.0)
    with pytest.raises(click.BadParameter, match="25"):
        check_lowpass(25.0, [0.0, 0.02, 0.04])
