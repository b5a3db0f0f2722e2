"""Settings as data: every field of EstimatorConfig carries its metadata, and the estimator options of
``estimate``, ``stream`` and ``fuse`` and the ROS node's parameters are those fields (one name each)."""

from __future__ import annotations

import dataclasses
import math

import click
import pytest

from softtip.cli import main
from softtip.cli.options import config_options, make_config
from softtip.estimator import EstimatorConfig
from softtip.estimator.settings import KINDS, Setting, check_value, settings_of
from softtip.ros.node import NODE_PARAMETERS, PARAMETERS, UNSET_PARAMETERS, config_from_parameters

SETTINGS = list(settings_of(EstimatorConfig))
COMMANDS = ("estimate", "stream", "fuse")


def test_every_field_has_its_setting():
    assert [s.name for s in SETTINGS] == [f.name for f in dataclasses.fields(EstimatorConfig)]
    for s in SETTINGS:
        assert isinstance(s, Setting) and s.kind in KINDS, s.name
        assert s.help and s.help[0] != " " and s.help.rstrip().endswith((".", "...", ")")), s.name
        default = getattr(EstimatorConfig, s.name)
        if s.kind == "float":
            assert s.unit or s.low is not None, f"{s.name}: a number with neither unit nor range"
            assert (default is None) == s.optional, s.name
            if default is not None:
                assert s.inside(default), f"{s.name}: default {default!r} outside its range"
            if s.optional:  # the ROS value 0 stands for None: 0 must not be a value
                assert s.low == 0.0 and s.low_open, s.name
        if s.kind == "choice":
            assert default in s.choices, s.name
        if s.kind in ("tuple", "tuples"):
            assert s.parts and all(p.metavar for p in s.parts), s.name
            assert s.metavar == " ".join(p.metavar for p in s.parts), s.name
        if s.kind == "composite":
            assert s.options and all(o.startswith("--") for o in s.options), s.name
        if s.cli_unit is not None:
            assert s.cli_unit in ("deg", "mm", "N·mm", "mm/√s", "force"), s.name
        assert check_value(s, default) == default or s.kind in ("tuple", "tuples", "composite"), s.name


def test_a_setting_out_of_its_range_is_refused_naming_it():
    for s in SETTINGS:
        if s.kind == "float" and s.low is not None:
            with pytest.raises(ValueError, match=rf"^{s.name} must be a number"):
                EstimatorConfig(**{s.name: s.low - 1.0})
        if s.kind == "choice":
            with pytest.raises(ValueError, match=rf"^{s.name} must be one of"):
                EstimatorConfig(**{s.name: "nonsense"})
        if s.kind == "int":
            with pytest.raises(ValueError, match=rf"^{s.name} must be an integer"):
                EstimatorConfig(**{s.name: 0})


def _estimator_params(command: str) -> dict[str, click.Option]:
    """A command's options, by their first long name."""
    cmd = main.commands[command]
    return {max(p.opts, key=len): p for p in cmd.params if isinstance(p, click.Option)}


@pytest.mark.parametrize("command", COMMANDS)
def test_each_command_has_the_settings_as_options(command):
    params = _estimator_params(command)
    names = {o for p in params.values() for o in p.opts + p.secondary_opts}
    expected = config_options()
    assert [o for o in expected if o not in names] == []
    for s in SETTINGS:
        if s.kind == "composite" or not s.cli:
            continue
        p = params[s.option]
        assert p.name == s.name, (command, s.option)  # the keyword argument is the field's name
        if s.kind == "bool":
            assert p.secondary_opts == [f"--no-{s.option[2:]}"], s.name
        default = getattr(EstimatorConfig, s.name)
        if s.make is None and s.kind != "tuples":
            assert p.default == default, (command, s.name)
    # no option names a setting that is not a field (e.g. a left-over --joint-window)
    fields = {s.option for s in SETTINGS}
    settingish = {o for o in names if o.removeprefix("--no-").removeprefix("--") in {f[2:] for f in fields}}
    assert settingish <= fields | {f"--no-{s.option[2:]}" for s in SETTINGS if s.kind == "bool"}
    assert not {o for o in names if o.startswith("--joint")}


@pytest.mark.parametrize("command", COMMANDS)
def test_the_options_defaults_make_the_configs_defaults(command):
    cmd = main.commands[command]
    args = {"estimate": ["--example"], "stream": ["--replay", "x.csv"], "fuse": ["a.csv", "b.csv"]}[command]
    ctx = cmd.make_context(command, args)
    with ctx:
        assert make_config(dict(ctx.params)) == EstimatorConfig()


def test_options_are_typed_in_the_units_people_use():
    """Degrees, mm (any length unit), N·mm, kgf: the config gets SI, the same bits as the library's arithmetic."""
    cmd = main.commands["estimate"]
    ctx = cmd.make_context("estimate", [
        "--example", "--line-fit-max-angle-std", "3", "--line-fit-max-offset-std", "0.03cm", "--h-min", "0.7",
        "--latch-window", "0.1kgf", "4", "--evidence-max-angle-std", "12", "--line-fit-drift", "0.05",
        "--skin-law", "1e6", "1.5", "4", "--depth-compensation", "law", "--no-drift-tracking", "--rocked", "1", "2",
        "--rocked", "5", "6",
    ])  # fmt: skip
    with ctx:
        cfg = make_config(dict(ctx.params))
    assert cfg.line_fit_max_angle_std == math.radians(3.0) and cfg.evidence_max_angle_std == math.radians(12.0)
    assert cfg.line_fit_max_offset_std == pytest.approx(3e-4, rel=1e-15) and cfg.h_min == 0.7 * 1e-3
    assert cfg.latch_window == pytest.approx((0.1 * 9.80665, 4.0)) and cfg.line_fit_drift == 0.05 * 1e-3
    assert (cfg.skin_law.stiffness, cfg.skin_law.exponent, cfg.skin_law.max_depth) == pytest.approx((1e6, 1.5, 4e-3))
    assert cfg.depth_compensation == "law" and not cfg.drift_tracking and cfg.rocked == ((1.0, 2.0), (5.0, 6.0))


def test_the_ros_parameters_are_the_same_settings():
    """One parameter per option (its name without dashes), plus sample_rate, which the commands take from the data."""
    ros = (set(PARAMETERS) | set(UNSET_PARAMETERS)) - set(NODE_PARAMETERS)
    cli = {o.removeprefix("--").replace("-", "_") for o in config_options()}
    assert ros == cli | {s.name for s in SETTINGS if not s.cli}
    assert {s.name for s in SETTINGS if not s.ros} == set()
    assert config_from_parameters({}) == EstimatorConfig()
    for s in SETTINGS:  # SI, the field's own default (0.0: none)
        if s.kind == "float":
            default = getattr(EstimatorConfig, s.name)
            assert PARAMETERS[s.name] == (0.0 if default is None else default), s.name
