"""``softtip simulate``: a grasp on the simulator, written as an F/T log and its ground truth.

Lengths accept a unit suffix (``2mm``, ``0.5 mm``, ``40e-3``, ``1cm``; a bare number is in
metres); forces accept ``N`` or ``kgf`` (``0.5kgf``; bare: newtons); angles are degrees.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import click

from softtip.cli.types import Force, Length, Number, dash_is_stdout, option
from softtip.core.units import UNIT_SYSTEMS
from softtip.errors import InputError
from softtip.io.atomic import (
    AtomicFile,
    cannot_write,
    check_distinct,
    commit_all,
    write_stdout,
)
from softtip.sim.objects import OBJECT_KINDS
from softtip.sim.scenario import (
    DISTURBANCE_TIMINGS,
    FRICTION_PROFILES,
    JOINT_ROTATION_DEG,
    OBJECT_MASS,
    ROCK_AMPLITUDE_DEG,
    ROCK_LOAD,
)
from softtip.sim.simulate import (
    FRICTION_SHEAR_MODULUS,
    log_csv_text,
    run_simulation,
    skin_thickness_of,
    truth_json_text,
)
from softtip.sim.skin import DEFAULT_ELEMENTS

__all__ = ["simulate"]

#: Ranges of the simulation's size options (a larger run would not fit in memory)
MAX_RATE = 100_000.0  # Hz
MAX_SAMPLES = 10_000_000
MAX_ELEMENTS = 200_000
MAX_FRICTION = 10.0

#: simulate's lengths: a bare number is in metres, and one of 0.1 m or more needs a unit
LENGTH, FORCE = Length("m", bare_max=0.1), Force()


def _check_sizes(options: dict) -> None:
    """Sample count and skin thickness: a run that cannot fit in memory, or a skin thicker than the fingertip."""
    duration = 10.0 if options["duration"] is None else options["duration"]
    n = options["rate"] * duration
    if n > MAX_SAMPLES:
        raise click.BadParameter(
            f"{options['rate']:g} Hz for {duration:g} s is {n:.3g} samples; expected at most {MAX_SAMPLES:g} "
            "(lower --rate or --duration)",
            param_hint="'--rate'",
        )
    if options["size"] is not None and not options["size"] > 0:
        raise click.BadParameter(f"{options['size'] * 1e3:g} mm; expected a positive length", param_hint="'--size'")
    if not options["force"] > 0:
        raise click.BadParameter(f"{options['force']:g} N; expected a positive force (N or kgf)", param_hint="'--force'")
    try:
        from softtip.core.fingertip import load_fingertip

        tip = load_fingertip(options["tip"])
    except (InputError, ValueError, OSError):
        return  # run_simulation names the problem with --tip
    options["thickness"] = skin_thickness_of(tip, options["thickness"])  # the file's skin, else 5 mm
    thickness, (_, reach) = options["thickness"], tip.bounding_sphere
    if not 0.0 < thickness < reach:
        raise click.BadParameter(
            f"{thickness * 1e3:g} mm; expected a skin thickness in (0, {reach * 1e3:g}) mm, less than the fingertip's size",
            param_hint="'--thickness'",
        )


@click.command("simulate")
@option("--object", "object_kind", type=click.Choice(OBJECT_KINDS), default="plate", show_default=True,
              help="What the fingertip touches.")
@option("--size", type=LENGTH, default=None,
              help="Plate thickness, or cylinder/stick/fringe diameter (e.g. 2mm). Defaults: plate 1mm, "
                   "cylinder 6mm, stick 4mm, fringe 40mm. Every length option here takes a unit; a bare number "
                   "is in m, and one of 0.1 or more is refused as ambiguous.")
@option("--angle", "angle_deg", type=Number("deg"), default=0.0, show_default=True,
              help="Direction of the edge/axis/fringe at the contact, degrees from the sensor x axis "
                   "(manual §3.4 tangent frame; 90 = along the hand's joint axes).")
@option("--scenario", type=click.Choice(["paper", "push", "friction"]), default="paper", show_default=True,
              help="paper: the papers' two-fingered grasp with joint and gravity disturbances; "
                   "push: a plain push; friction: the papers' grasp (weightless object) with a friction load "
                   "during the hold (--load, --load-direction, --load-profile).")
@option("--load", "load_ratio", type=Number("(fraction of the grasp force)", 0.0), default=0.25, show_default=True,
              help="friction scenario: tangential load, a fraction of the grasp force.")
@option("--load-direction", type=click.Choice(["across", "along"]), default="across", show_default=True,
              help="friction scenario: load across the line or along it.")
@option("--load-profile", type=click.Choice(FRICTION_PROFILES), default="push", show_default=True,
              help="friction scenario: push (ramped in at 6-6.5 s, held), drag (slowly, 5.5-9.5 s) or slip "
                   "(the object slides 1.5 mm at 6-7 s, friction at the Coulomb limit).")
@option("--tip", default="murakami2006", show_default=True, help="Fingertip preset or TOML file.")
@option("--edge-radius", type=LENGTH, default="0mm", show_default=True,
              help="Plate corner radius or wedge tip radius (length).")
@option("--apex-angle", "apex_angle_deg", type=Number("deg", 0.0, 180.0, min_open=True, max_open=True), default=90.0, show_default=True,
              help="Wedge apex angle, degrees.")
@option("--tilt", "tilt_deg", type=Number("deg", 0.0, 90.0), default=45.0, show_default=True,
              help="Fringe: contact normal's angle from the cylinder side toward its bottom face, degrees.")
@option("--force", type=FORCE, default="0.5kgf", show_default=True, help="Held grasp force (N or kgf).")
@option("--duration", type=Number("s", 0.0, min_open=True), default=None, help="Recorded time, s [default: 10, or the end of --rock].")
@option("--t-contact", type=Number("s", 0.0), default=2.0, show_default=True, help="Time of first touch, s.")
@option("--t-stable", type=Number("s", 0.0, min_open=True), default=4.0, show_default=True, help="End of the force ramp, s.")
@option("--rate", type=Number("Hz", 0.0, MAX_RATE, min_open=True), default=50.0, show_default=True, help="Sample rate, Hz.")
@option("--joint-rotation", "joint_rotation_deg", type=Number("deg", -90.0, 90.0), default=JOINT_ROTATION_DEG, show_default=True,
              help="paper: object rotation about the joint axis once the grasp holds it, degrees.")
@option("--gravity-spin", "gravity_spin_deg", type=Number("deg", -90.0, 90.0), default=1.0, show_default=True,
              help="paper: object rotation about the grasp axis from its weight, degrees.")
@option("--mass", "object_mass", type=Number("kg", 0.0), default=OBJECT_MASS, show_default=True,
              help="paper: object mass, kg (half its weight loads each finger tangentially).")
@option("--disturbance-timing", type=click.Choice(DISTURBANCE_TIMINGS), default="after_grasp",
              show_default=True,
              help="paper: after_grasp (the papers' procedure: disturbances ramp in after the grasp force "
                   "is established) or during_rise (together with the force rise; harder for the latch).")
@option("--misalignment", "misalignment_deg", type=Number("deg", -90.0, 90.0), default=0.0, show_default=True,
              help="paper: fixed alignment error about the hand z axis, degrees.")
@option("--rock", is_flag=True,
              help="paper: after the grasp, rock the object about two tangent axes and then in a figure-eight "
                   "(each segment averaging to zero tilt), the excitation that tells a line from an area; "
                   "--duration defaults to the end of the rocking.")
@option("--rock-amplitude", "rock_amplitude_deg", type=Number("deg", 0.0, 90.0, min_open=True), default=ROCK_AMPLITUDE_DEG, show_default=True,
              help="--rock: tilt amplitude, degrees.")
@option("--rock-period", type=Number("s", 0.0, min_open=True), default=1.0, show_default=True, help="--rock: period of the rocking, s.")
@option("--rock-load", type=FORCE, default=str(ROCK_LOAD), show_default=True,
              help="--rock: tangential load that comes with the tilt (N or kgf), turning with the tilt axis.")
@option("--elements", "n_elements", type=click.IntRange(50, MAX_ELEMENTS), default=DEFAULT_ELEMENTS, show_default=True,
              help="Skin surface elements.")
@option("--modulus", type=Number("Pa", 0.0, min_open=True), default=0.6e6, show_default=True, help="Skin Winkler modulus, Pa.")
@option("--shear-modulus", type=Number("Pa", 0.0, min_open=True), default=None, help=f"Skin shear modulus, Pa [default: modulus/3; {FRICTION_SHEAR_MODULUS / 1e6:g} MPa with --scenario friction].")
@option("--friction", type=Number("", 0.0, MAX_FRICTION, min_open=True), default=1.0, show_default=True, help="Coulomb friction coefficient.")
@option("--thickness", type=LENGTH, default=None, help="Skin thickness (length).  [default: the --tip file's skin_thickness, else 5mm]")
@option("--noise/--no-noise", default=True, show_default=True,
              help="Apply the sensor model (ATI Nano17 class noise and quantisation) or write the true wrench.")
@option("--seed", type=click.IntRange(min=0), default=0, show_default=True, help="Seed of the noise generator.")
@option("--units", type=click.Choice(UNIT_SYSTEMS), default="si", show_default=True,
              help="Units of the written log: si (N, N·m) or kgf-mm.")
@option("--hand", type=click.Choice(["one-finger", "two-finger"]), default="one-finger", show_default=True,
              help="two-finger: both fingertips of the papers' hand on one object (the paper scenario, --rock "
                   "optional): -o is then a new directory for right.csv, left.csv, hand.toml (their poses in the "
                   "hand frame) and truth.json (the object's line and plate normal in the hand frame), for "
                   "`softtip fuse`. The paper or friction scenario's, rocking's, skin's and sensor's options apply to "
                   "both fingertips (a friction load: one vector in the hand, --load-direction as seen at the right "
                   "fingertip).")
@option("--left-object", type=click.Choice(OBJECT_KINDS), default=None,
              help="--hand two-finger: what the left fingertip touches [default: --object, its other side].")
@option("--width", type=LENGTH, default="30mm", show_default=True,
              help="--hand two-finger: the object's width between the two contacts.")
@option("--to-bag", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="--hand two-finger: also a rosbag2 (MCAP) with /right/wrench, /left/wrench and the fingertips' "
                   "poses on /tf_static and /tf (DIR must not exist).")
@option("-o", "--output", type=click.Path(path_type=Path, allow_dash=True), default=None, callback=dash_is_stdout,
              help="Log CSV (t,fx,fy,fz,mx,my,mz) [default, or '-': stdout]; --hand two-finger: a new directory.")
@option("--truth", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Ground truth JSON [default: OUTPUT with suffix .truth.json; none when writing to stdout].")
def simulate(
    output: Path | None, truth: Path | None, units: str, hand: str, left_object: str | None, width: float,
    to_bag: Path | None, **options,
) -> None:
    """Simulate a grasp of an object by the soft fingertip and write the F/T log.

    The log is the input log (manual §4) of `softtip estimate`; the truth file holds the object's
    line direction and angle, the nominal and pressure-centre contact points, contact area,
    depth, the depth at which friction acts and normal force per sample, and every parameter
    of the run.
    """
    if hand == "two-finger":
        _simulate_hand(output, truth, units, left_object, width, to_bag, options)
        return
    if left_object is not None or to_bag is not None:
        raise click.UsageError("--left-object and --to-bag go with --hand two-finger")
    from softtip.cli.options import check_output_names, check_table_names

    check_output_names([("-o", output), ("--truth", truth)])
    check_table_names([("-o", output)], formats=("csv",))
    if truth is None and output is not None and (output.is_file() or not output.exists()):
        # beside a file, not beside a device or a pipe (-o /dev/stdout, /dev/null: none, as on standard output)
        truth = output.with_name(output.stem + ".truth.json")
    tip = options["tip"]
    check_distinct(
        [("--tip", tip if os.path.isfile(tip) else None)], [("-o", output), ("--truth", truth)]
    )
    for path in (output, truth):
        if path is not None and not path.parent.exists():
            raise click.BadParameter(f"directory {path.parent} does not exist", param_hint=str(path))
    _check_sizes(options)
    try:
        log = run_simulation(**options)
    except InputError as exc:
        raise click.BadParameter(str(exc), param_hint="--tip") from None
    except ValueError as exc:
        raise click.UsageError(str(exc)) from None
    except RuntimeError as exc:  # the contact solve found no equilibrium for these options
        raise _no_equilibrium(exc, options) from None
    # both files appear together or neither does (and no temporary file stays behind)
    files = {name: AtomicFile(path) for name, path in (("log", output), ("truth", truth)) if path is not None}
    try:
        texts = {"log": lambda: log_csv_text(log, units), "truth": lambda: truth_json_text(log)}
        if output is None:
            write_stdout(texts["log"]())
        for name, f in files.items():
            try:
                with f.open() as fh:
                    fh.write(texts[name]())
            except OSError as exc:
                raise cannot_write(f.path, exc) from None
        commit_all(files.values())
    finally:
        for f in files.values():
            f.discard()
    written = [str(p) for p in (output, truth) if p is not None] or ["standard output"]
    click.echo(f"softtip: simulated {len(log.t)} samples ({options['scenario']}, {options['object_kind']}) -> {', '.join(written)}", err=True)


def _no_equilibrium(exc: RuntimeError, options) -> click.UsageError:
    """The error for a contact solve that found no equilibrium, with what may help."""
    if options["scenario"] == "friction":
        hint = "a stiffer shear layer (a larger --shear-modulus) or a smaller --load may find one"
    else:
        hint = "a larger --friction or --force, a smaller --mass, or a thinner --thickness helps"
    return click.UsageError(f"the simulated grasp has no equilibrium with these options ({exc}); {hint}")


def _simulate_hand(output, truth, units, left_object, width, to_bag, options) -> None:
    """``softtip simulate --hand two-finger``: both fingertips, files for ``softtip fuse``."""
    from softtip.core.fingertip import load_fingertip
    from softtip.sim.hand import (
        FrictionLoad,
        simulate_two_finger,
        write_two_finger,
        write_two_finger_bag,
    )
    from softtip.sim.objects import make_object
    from softtip.sim.simulate import scenario_options, sensor_and_skin

    if output is None:
        raise click.UsageError("--hand two-finger writes several files: give -o DIR (a new directory)")
    if truth is not None or units != "si" or options["scenario"] == "push":
        raise click.UsageError(
            "--hand two-finger writes SI logs of the paper or friction scenario (no --truth, --units, --scenario push)"
        )
    if options["scenario"] == "friction" and options["rock"]:
        raise click.UsageError("--rock needs the paper scenario")
    if output.exists():
        raise click.BadParameter(f"{output} exists; expected a new directory", param_hint="-o")
    if to_bag is not None and to_bag.exists():
        raise click.BadParameter(f"{to_bag} exists; expected a new directory for the bag", param_hint="--to-bag")
    if not (0.0 < width <= 0.3):
        raise click.BadParameter(f"{width * 1e3:g} mm; expected a width between 0 and 300 mm", param_hint="--width")
    _check_sizes(options)
    kind = options["object_kind"]
    shape = dict(edge_radius=options["edge_radius"], apex_angle=math.radians(options["apex_angle_deg"]),
                 tilt=math.radians(options["tilt_deg"]))  # fmt: skip
    objs = {"right": make_object(kind, options["size"], **shape),
            "left": make_object(left_object or kind, options["size"] if left_object in (None, kind) else None, **shape)}  # fmt: skip
    # every option of the one-finger paper scenario reaches both fingers, as in run_simulation
    scenario = scenario_options(**options)
    sensor, params = sensor_and_skin(**options)
    load = None
    if options["scenario"] == "friction":
        load = FrictionLoad(options["load_ratio"], options["load_direction"] == "across", options["load_profile"])
    try:
        tip = load_fingertip(options["tip"])
        grasp = simulate_two_finger(
            tip, objs, math.radians(options["angle_deg"]), width=width, rng=options["seed"],
            object_mass=options["object_mass"], n_elements=options["n_elements"], rock=options["rock"],
            sensor=sensor, params=params, load=load, **scenario,
        )  # fmt: skip
    except InputError as exc:
        raise click.BadParameter(str(exc), param_hint="--tip") from None
    except ValueError as exc:
        raise click.UsageError(str(exc)) from None
    except RuntimeError as exc:  # a contact solve found no equilibrium for these options
        raise _no_equilibrium(exc, options) from None
    paths = write_two_finger(grasp, output)
    if to_bag is not None:
        write_two_finger_bag(grasp, to_bag)
        paths.append(to_bag)
    click.echo(f"softtip: two-finger grasp ({len(grasp.t)} samples per finger) -> {', '.join(map(str, paths))}", err=True)
