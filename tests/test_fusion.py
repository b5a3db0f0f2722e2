"""Two fingertips in a common frame: poses, /tf, the fused grasp, and `softtip fuse`."""

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.spatial.transform import Rotation

import simcache
import softtip
import softtip.sim.hand
from softtip import EstimatorConfig, InputError
from softtip.core.noise import NANO17
from softtip.fusion import Finger, PoseSeries, fuse, fuse_logs, poses_from_columns, read_hand_file
from softtip.fusion.tf import TfTree
from softtip.sim.synthetic import synthetic_grasp

SOFTTIP = str(Path(sys.executable).with_name("softtip"))
HAND_X = np.array([1.0, 0.0, 0.0])


# -- poses ------------------------------------------------------------------------------------


def test_pose_series_interpolates_and_refuses_stale_times():
    r0, r1 = Rotation.identity(), Rotation.from_euler("z", 90, degrees=True)
    ps = PoseSeries(np.array([0.0, 1.0]), Rotation.concatenate([r0, r1]), np.array([[0, 0, 0], [1.0, 0, 0]]), max_gap=0.1)
    rot, tr = ps.at([0.5])
    assert_allclose(rot.as_euler("xyz", degrees=True)[0], [0, 0, 45], atol=1e-9)
    assert_allclose(tr, [[0.5, 0, 0]])
    assert_allclose(ps.apply([1.0], [[1.0, 0.0, 0.0]]), [[1.0, 1.0, 0.0]], atol=1e-12)
    ps.at([1.05])  # within max_gap: held at the last pose
    with pytest.raises(InputError, match="no pose of sensor at t = 1.200000 s.*missing or stale"):
        ps.at([1.2])


def test_pose_columns_and_their_errors():
    t = np.arange(3) * 0.1
    cols = {"px": [0, 0, 0], "py": [0, 0, 0], "pz": [0.1] * 3, "qw": [1, 1, 1], "qx": [0] * 3, "qy": [0] * 3, "qz": [0] * 3}
    ps = poses_from_columns(t, cols)
    assert_allclose(ps.apply(t, np.zeros((3, 3))), [[0, 0, 0.1]] * 3)
    with pytest.raises(InputError, match="missing pose column.*qz"):
        poses_from_columns(t, {k: v for k, v in cols.items() if k != "qz"}, source="log.csv")
    with pytest.raises(InputError, match="row 2: pose quaternion .* norm 2"):
        poses_from_columns(t, {**cols, "qw": [1, 2, 1]})


def test_hand_file(tmp_path):
    p = tmp_path / "hand.toml"
    p.write_text('[hand]\nframe = "palm"\n\n[finger.a]\ntranslation = [0.05, 0, 0]\nrpy_deg = [0, -90, 0]\n\n[finger.b]\nquaternion = [1, 0, 0, 0]\n')
    hand = read_hand_file(p)
    assert hand.frame == "palm" and list(hand.fingers) == ["a", "b"]
    # the sensor's z axis (toward the tip) points along −x of the hand
    assert_allclose(hand.fingers["a"].rotate([0.0], [[0, 0, 1.0]]), [[-1.0, 0, 0]], atol=1e-12)
    p.write_text('[finger.a]\nrpy_deg = [0, 0]\n')
    with pytest.raises(InputError, match=r"\[finger.a\] rpy_deg"):
        read_hand_file(p)


def test_tf_tree_composes_static_and_moving_edges():
    tree = TfTree("test.bag")
    q = Rotation.from_euler("z", 90, degrees=True).as_quat()
    tree.add("world", "hand", 0, (1.0, 0.0, 0.0), q, static=True)
    for k in range(11):  # the finger slides along hand x at 1 m/s, sampled at 10 Hz
        tree.add("hand", "finger", k * 100_000_000, (0.1 * k, 0.0, 0.0), (0, 0, 0, 1), static=False)
    rot, tr = tree.lookup("world", "finger", [250_000_000])
    # finger at hand x = 0.25, hand rotated 90° about z in world and offset by 1 m along x
    assert_allclose(tr, [[1.0, 0.25, 0.0]], atol=1e-12)
    assert_allclose(rot.as_matrix()[0], Rotation.from_quat(q).as_matrix(), atol=1e-12)
    # and the other way round
    rot2, tr2 = tree.lookup("finger", "world", [250_000_000])
    assert_allclose(rot2.apply([1.0, 0.25, 0.0]) + tr2, [[0.0, 0.0, 0.0]], atol=1e-12)
    with pytest.raises(InputError, match="'elbow' is not connected to 'world'.*frames present: finger, hand, world"):
        tree.lookup("world", "elbow", [0])
    with pytest.raises(InputError, match="'hand' → 'finger'.*missing or stale"):
        tree.lookup("world", "finger", [3_000_000_000])


# -- fusion of synthetic fingertips --------------------------------------------------------------

R_RIGHT = Rotation.from_matrix(np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]).T)
R_LEFT = Rotation.from_matrix(np.array([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]]).T)


def _finger(name, rot, angle_deg, width=0.03, seed=0, **kw):
    """A synthetic grasp on the papers' tip whose sensor sits at the hand's ±x, apex at ±width/2."""
    g = synthetic_grasp(angle_deg=angle_deg, seed=seed, tangential_ratio=0.0, **kw)
    apex = rot.apply(g.point)
    side = 1.0 if name == "right" else -1.0
    pose = PoseSeries.fixed(rot, side * 0.5 * width * HAND_X - apex, name)
    return g, pose


def _fuse(right_angle, left_angle, left_kw=None, **options):
    gr, pr = _finger("right", R_RIGHT, right_angle, seed=1)
    gl, pl = _finger("left", R_LEFT, left_angle, seed=2, **(left_kw or {}))
    fused, fingers = fuse_logs([("right", gr.t, gr.wrench, pr), ("left", gl.t, gl.wrench, pl)], "murakami2006", **options)
    return fused, gr, pr, gl, pl


def test_a_plate_pinched_across_gives_one_line_and_its_plane():
    # the same line seen by both fingers: +30° at the right apex is −30° at the left one
    fused, gr, pr, gl, pl = _fuse(30.0, -30.0)
    late = fused.t > 7.0
    assert (fused.grasp_names[late] == "parallel_lines").all()
    truth = pr.rotate([0.0], gr.direction[None])[0]
    err = np.degrees(np.arccos(np.abs(fused.direction[late] @ truth)))
    assert np.median(err) < 1.0
    # the plane through both lines contains the line and the grasp axis
    plane = np.cross(truth, HAND_X)
    nerr = np.degrees(np.arccos(np.abs(fused.plane_normal[late] @ plane)))
    assert np.median(nerr) < 1.5
    assert (fused.evidence[late] != "").all() and (fused.flag[late] == "").all()
    # the fused direction's standard deviation: that of two independent fingers
    sa = fused.direction_std[late]
    assert np.all(sa > 0) and np.all(np.isfinite(fused.plane_normal_std[late]))


def test_two_different_edges_cross():
    fused, gr, pr, gl, pl = _fuse(45.0, 45.0)  # in the hand: +45° and −45°, 90° apart
    late = fused.t > 7.0
    assert (fused.grasp_names[late] == "crossing_lines").all()
    assert np.median(np.degrees(fused.line_angle[late])) == pytest.approx(90.0, abs=2.0)
    # closest approach of the two lines: the distance between the contacts along the grasp axis
    assert np.median(fused.closest_approach[late]) == pytest.approx(0.03, abs=1e-3)


def test_a_line_and_a_face():
    fused, gr, pr, gl, pl = _fuse(0.0, 0.0, left_kw={"h_peak": 0.0})
    late = fused.t > 7.0
    assert (fused.grasp_names[late] == "line_and_face").all()
    # the face under the left finger: its outward normal on the object points at the left finger (−x)
    assert_allclose(np.median(fused.face_normal[late], axis=0), -HAND_X, atol=0.02)


def test_forces_that_do_not_balance_are_flagged():
    fused, *_ = _fuse(30.0, -30.0, left_kw={"force": 2.0 * 0.55 * 9.80665})
    late = fused.t > 7.0
    assert (fused.flag[late] == "unbalanced").all()
    # and a known weight that the fingers do not carry
    fused, *_ = _fuse(30.0, -30.0, object_mass=0.5)
    assert (fused.flag[fused.t > 7.0] == "unbalanced").all()
    fused, *_ = _fuse(30.0, -30.0, object_mass=0.0)
    assert (fused.flag[fused.t > 7.0] == "").all()


def test_fuse_needs_two_fingers():
    gr, pr = _finger("right", R_RIGHT, 0.0)
    est = softtip.estimate(gr.t, gr.wrench)
    with pytest.raises(ValueError, match="two fingers"):
        fuse([Finger("right", est, pr)])


# -- the command, on CSV logs with a hand file and on a bag with /tf --------------------------------


def _run(*args):
    env = simcache.subprocess_env() if args[:1] == ("simulate",) else None  # the grasps from the tests' cache
    return subprocess.run([SOFTTIP, *map(str, args)], capture_output=True, text=True, timeout=120, env=env)


@pytest.fixture(scope="module", autouse=True)
def _shared_grasps():
    # the hand simulates each fingertip through softtip.sim.hand.simulate_grasp: from the
    # session's cache (tests/simcache.py)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(softtip.sim.hand, "simulate_grasp", simcache.simulate_grasp)
        yield


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    from softtip.sim import Plate
    from softtip.sim.hand import simulate_two_finger, write_two_finger, write_two_finger_bag

    out = tmp_path_factory.mktemp("hand")
    g = simulate_two_finger(softtip.murakami2006(), Plate(0.001), math.radians(-45), n_elements=6000, duration=7.0)
    write_two_finger(g, out / "grasp")
    pytest.importorskip("rosbags")
    write_two_finger_bag(g, out / "bag")
    return g, out


def test_fuse_stops_on_impossible_units_as_estimate_does(simulated, tmp_path):
    """One finger's moments in N·mm read as N·m: exit 2 naming that file, nothing written (the options'
    units apply to both logs; a header's unit is per file)."""
    g, out = simulated
    lines = (out / "grasp/left.csv").read_text().splitlines()
    head = lines[0].split(",")
    moments = [head.index(c) for c in ("mx", "my", "mz")]
    rows = [ln.split(",") for ln in lines[1:]]
    for row in rows:
        for j in moments:
            row[j] = repr(float(row[j]) * 1e3)
    left = tmp_path / "left_nmm.csv"
    left.write_text("\n".join([lines[0], *(",".join(r) for r in rows)]) + "\n")
    done = _run("fuse", out / "grasp/right.csv", left, "--hand", out / "grasp/hand.toml", "-o", tmp_path / "f.csv")
    assert done.returncode == 2, done.stderr
    assert f"softtip: error: {left}: the forces act " in done.stderr and "fingertip reaches only" in done.stderr, done.stderr
    assert not (tmp_path / "f.csv").exists()


def test_fuse_command_on_csv_and_on_a_bag_agree(simulated):
    g, out = simulated
    a = _run(
        "fuse", out / "grasp/right.csv", out / "grasp/left.csv", "--hand", out / "grasp/hand.toml", "-o", out / "a.csv",
        "--plot", out / "a.png",
    )  # fmt: skip
    assert a.returncode == 0, a.stderr
    assert (out / "a.png").stat().st_size > 10_000
    assert "parallel lines: median direction" in a.stderr
    assert "softtip: right: bias from the first 0.2 s" in a.stderr and "softtip: left: bias from" in a.stderr
    b = _run("fuse", out / "bag", "--topics", "/right/wrench", "/left/wrench", "--frame", "hand", "-o", out / "b.csv")
    assert b.returncode == 0, b.stderr
    ta = np.genfromtxt(out / "a.csv", delimiter=",", names=True, dtype=None, encoding=None)
    tb = np.genfromtxt(out / "b.csv", delimiter=",", names=True, dtype=None, encoding=None)
    # the CSV holds 10 significant digits and µs times, the bag the doubles and ns stamps: the
    # windowed stages (depth, line evidence) then differ a little, never in substance
    assert np.mean(ta["grasp"] == tb["grasp"]) > 0.95
    # the bag's stamps go along, as `estimate` keeps them: the first topic's, one per fused row
    assert "stamp_ns" not in ta.dtype.names and tb.dtype.names[-1] == "stamp_ns"
    stamps = tb["stamp_ns"].astype(np.int64)
    assert (np.diff(stamps) > 0).all() and np.allclose((stamps - stamps[0]) * 1e-9, tb["t"] - tb["t"][0], atol=2e-6)
    both = (ta["grasp"] == "parallel_lines") & (tb["grasp"] == "parallel_lines")
    da = np.stack([ta["dx"], ta["dy"], ta["dz"]], axis=-1)[both]
    db = np.stack([tb["dx"], tb["dy"], tb["dz"]], axis=-1)[both]
    assert np.degrees(np.arccos(np.clip(np.abs(np.sum(da * db, axis=-1)), 0, 1))).max() < 0.5
    held = (ta["t"] > 6.0) & (ta["grasp"] == "parallel_lines")
    assert held.sum() > 0.5 * np.count_nonzero(ta["t"] > 6.0)
    d = np.stack([ta["dx"], ta["dy"], ta["dz"]], axis=-1)[held]
    truth = g.truth_line()[held]
    err = np.degrees(np.arccos(np.clip(np.abs(np.sum(d * truth, axis=-1)), 0, 1)))
    assert np.median(err) < 4.0


def test_fuse_command_errors(simulated, tmp_path):
    g, out = simulated
    r = _run("fuse", out / "bag", "--topics", "/right/wrench", "/left/wrench", "--frame", "elbow", "-o", tmp_path / "x.csv")
    assert r.returncode == 2 and "'right_sensor' is not connected to 'elbow'" in r.stderr
    assert not (tmp_path / "x.csv").exists()
    r = _run("fuse", out / "bag", "--topics", "/right/wrench", "/left/wrench")
    assert r.returncode == 2 and "--frame" in r.stderr
    r = _run("fuse", out / "grasp/right.csv", out / "grasp/left.csv")
    assert r.returncode == 2 and "missing pose column" in r.stderr and "--hand HAND.toml" in r.stderr
    r = _run("fuse", out / "grasp/right.csv", "--hand", out / "grasp/hand.toml")
    assert r.returncode == 2 and "expected two logs, one per finger" in r.stderr
    r = _run("fuse", out / "grasp/right.csv", out / "grasp/left.csv", "--hand", out / "grasp/hand.toml", "--object-mass", "-1")
    assert r.returncode == 2 and "--object-mass" in r.stderr


def _shifted(src, dest, dt, keep=None):
    """A copy of a grasp log with ``dt`` (s) added to t, rows ``keep`` (a slice) only."""
    lines = src.read_text().splitlines()
    rows = [ln.split(",") for ln in lines[1:]][keep or slice(None)]
    for row in rows:
        row[0] = f"{float(row[0]) + dt:.6f}"
    dest.write_text("\n".join([lines[0], *(",".join(r) for r in rows)]) + "\n")
    return dest


def test_fuse_puts_two_dated_logs_on_their_common_clock(simulated, tmp_path):
    """Logs with absolute stamps are fused on the clock they share (each log's own t counts from
    its first stamp); logs that never overlap, or one dated and one not, stop the run."""
    g, out = simulated
    hand = out / "grasp/hand.toml"
    epoch = 1_710_408_121.0
    right = _shifted(out / "grasp/right.csv", tmp_path / "r.csv", epoch)
    late = _shifted(out / "grasp/left.csv", tmp_path / "l.csv", epoch, slice(50, None))  # starts 1 s later
    rel = _shifted(out / "grasp/left.csv", tmp_path / "l_rel.csv", 0.0, slice(50, None))
    dated = _run("fuse", right, late, "--hand", hand, "-o", tmp_path / "dated.csv")
    plain = _run("fuse", out / "grasp/right.csv", rel, "--hand", hand, "-o", tmp_path / "plain.csv")
    assert dated.returncode == 0 and plain.returncode == 0, dated.stderr + plain.stderr
    a = np.genfromtxt(tmp_path / "dated.csv", delimiter=",", names=True, dtype=None, encoding=None)
    b = np.genfromtxt(tmp_path / "plain.csv", delimiter=",", names=True, dtype=None, encoding=None)
    assert (a["grasp"] == b["grasp"]).all() and np.allclose(a["t"], b["t"], atol=2e-6)
    assert "unbalanced" not in dated.stderr
    assert f"finger 1 (right) <- {right}, finger 2 (left) <- {late}" in dated.stderr
    far = _shifted(out / "grasp/left.csv", tmp_path / "far.csv", epoch + 100.0)
    r = _run("fuse", right, far, "--hand", hand, "-o", tmp_path / "x.csv")
    assert r.returncode == 2 and "the logs do not overlap in time" in r.stderr, r.stderr
    r = _run("fuse", right, out / "grasp/left.csv", "--hand", hand, "-o", tmp_path / "x.csv")
    assert r.returncode == 2 and "has absolute stamps (dates) and" in r.stderr, r.stderr
    assert not (tmp_path / "x.csv").exists()


# -- gravity from the robot's transforms -----------------------------------------------------------


def test_gravity_compensation_with_orientation_from_tf_and_from_a_callback():
    from softtip.calibration.payload import CompensatedSource, Payload, compensate_payload

    payload = Payload(mass=0.02, com=(0.0, 0.0, 0.02))
    tree = TfTree("robot")
    t = np.arange(50) * 0.02
    stamps = (t * 1e9).astype(np.int64)
    # the wrist turns 90° about world x in a second; the sensor is fixed on it
    for ns, a in zip(stamps, np.linspace(0.0, 90.0, len(t))):
        tree.add("world", "wrist", int(ns), (0.0, 0.0, 0.5), Rotation.from_euler("x", a, degrees=True).as_quat(), False)
    tree.add("wrist", "ft_sensor", 0, (0.0, 0.0, 0.05), (0.0, 0.0, 0.0, 1.0), True)
    q = tree.orientations("world", "ft_sensor", stamps)
    assert_allclose(q[-1], Rotation.from_euler("x", 90.0, degrees=True).as_quat(scalar_first=True), atol=1e-12)
    raw = np.zeros((len(t), 6))
    expected = compensate_payload(raw, q, payload)
    # the same, live: a callback gives the orientation at each sample's time
    src = CompensatedSource(list(zip(t, raw)), lambda ti: tuple(tree.orientations("world", "ft_sensor", [int(round(ti * 1e9))])[0]), payload)
    live = np.array([r.wrench for r in src])
    assert_allclose(live, expected, atol=1e-12)
    # at first the sensor is upright: the fingertip's weight pulls along its −z
    assert_allclose(-expected[0, :3], [0.0, 0.0, -0.02 * 9.80665], atol=1e-12)


def test_the_simulator_options_reach_both_fingertips(tmp_path):
    """``--hand two-finger`` simulates what the one-finger options say (rate, duration, noise,
    skin), not silently the defaults."""
    r = _run(
        "simulate", "--hand", "two-finger", "--object", "stick", "--size", "4mm", "--rate", "100", "--duration", "4",
        "--no-noise", "--friction", "0.8", "--modulus", "0.8e6", "--elements", "2000", "-o", tmp_path / "g",
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    for side in ("right", "left"):
        log = np.genfromtxt(tmp_path / f"g/{side}.csv", delimiter=",", names=True)
        assert_allclose(np.diff(log["t"]), 0.01, atol=1e-9)
        assert log["t"][-1] == pytest.approx(4.0 - 0.01, abs=0.011)
        # noise-free: untouched before contact at 2 s, exactly
        before = log["t"] < 1.5
        assert all(np.all(log[c][before] == 0.0) for c in ("fx", "fy", "fz", "mx", "my", "mz"))
    # the skin's options too: the default skin (0.6 MPa, friction 1) gives another wrench
    r = _run(
        "simulate", "--hand", "two-finger", "--object", "stick", "--size", "4mm", "--rate", "100", "--duration", "4",
        "--no-noise", "--elements", "2000", "-o", tmp_path / "h",
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    stiff, soft = (np.genfromtxt(tmp_path / f"{d}/right.csv", delimiter=",", names=True) for d in "gh")
    assert not np.array_equal(stiff["mx"], soft["mx"])


def test_another_contact_model_simulates_each_finger_from_the_same_scenarios():
    """``simulate_two_finger(simulate=...)``: each finger's scenario, sensor and seed reach the
    given contact model (the benchmarks pass Drake's); the default model through that hook gives
    the default grasp to the bit."""
    import functools

    from softtip.sim import Plate, simulate_grasp
    from softtip.sim.hand import simulate_two_finger

    tip, angle = softtip.murakami2006(), math.radians(30)
    calls = []

    def recording(tip_, obj, scenario, sensor, rng):
        calls.append((round(math.degrees(scenario.angle)), rng, sensor, scenario.hand.rotation))
        return simulate_grasp(tip_, obj, scenario, sensor, rng=rng, n_elements=1500)

    hooked = simulate_two_finger(tip, Plate(0.001), angle, rng=4, duration=4.0, simulate=recording)
    plain = simulate_two_finger(tip, Plate(0.001), angle, rng=4, duration=4.0, n_elements=1500)
    assert [c[:2] for c in calls] == [(30, 4), (-30, 5)] and calls[0][2] is calls[1][2]
    assert np.array_equal(calls[1][3], softtip.sim.HandFrame.paper(side="left").rotation)
    for side in ("right", "left"):
        assert np.array_equal(hooked.logs[side].wrench, plain.logs[side].wrench)
        assert np.array_equal(hooked.logs[side].truth.angle, plain.logs[side].truth.angle, equal_nan=True)
    with pytest.raises(ValueError, match="give them to your simulate"):
        simulate_two_finger(tip, Plate(0.001), angle, n_elements=1500, simulate=functools.partial(simulate_grasp))


def test_a_friction_load_on_the_grasped_object(tmp_path):
    """A friction load pushes the pinched plate (100 g) across its line (0.25 of the grasp
    force at each fingertip, one vector in the hand): both fingertips carry the same
    tangential load on top of half the weight, the fused line stays within the friction
    target for thin objects (4° median), and while the load is on the contact forces no longer balance the weight alone:
    flagged ``unbalanced``, not before."""
    from softtip.sim import ContactModel, ContactParams, Plate, discretise_skin
    from softtip.sim.hand import FrictionLoad, simulate_two_finger

    tip = softtip.murakami2006()
    model = ContactModel(discretise_skin(tip, n_elements=6000), ContactParams(shear_modulus=2e6), 2)
    g = simulate_two_finger(tip, Plate(0.001), math.radians(30), rng=3, model=model, object_mass=0.1, load=FrictionLoad(0.25))
    f_hand = {s: g.logs[s].wrench_true[:, :3] @ g.sensor_poses[s].rotation.T for s in ("right", "left")}
    t = g.logs["right"].t
    weight = np.array([0.0, 0.0, -0.1 * 9.80665])
    held, late = (t > 4.6) & (t < 5.9), t > 7.0
    assert_allclose((f_hand["right"] + f_hand["left"])[held], np.broadcast_to(weight, (held.sum(), 3)), atol=0.01)
    # across the grasp (hand x) the pinch is opposite; the load (hand y, z) is one vector
    assert_allclose(f_hand["right"][late, 1:], f_hand["left"][late, 1:], atol=0.05)
    assert np.all(np.linalg.norm(f_hand["right"][late, 1:], axis=1) > 0.2 * 4.9)
    fz = fuse(_fingers(g, tip), object_mass=g.object_mass)
    lines = (fz.t > 7.0) & (fz.grasp_names == "parallel_lines")
    assert lines.mean() > 0.9 * np.mean(fz.t > 7.0)
    err = np.degrees(np.arccos(np.clip(np.abs(np.sum(fz.direction[lines] * g.truth_line()[lines], axis=-1)), 0, 1)))
    assert np.median(err) < 4.0
    assert np.mean(fz.flag[fz.t > 6.6] == "unbalanced") > 0.9
    assert not np.any(fz.flag[(fz.t > 4.6) & (fz.t < 5.9)] == "unbalanced")
    # the same from the command line, its load options for both fingertips
    r = _run(
        "simulate", "--hand", "two-finger", "--scenario", "friction", "--load", "0.25", "--shear-modulus", "2e6",
        "--object", "plate", "--size", "1mm", "--angle", "30", "--elements", "3000", "-o", tmp_path / "g",
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    r = _run("fuse", tmp_path / "g/right.csv", tmp_path / "g/left.csv", "--hand", tmp_path / "g/hand.toml", "-o", tmp_path / "f.csv")
    assert r.returncode == 0 and "flagged unbalanced" in r.stderr, r.stderr
    r = _run("simulate", "--hand", "two-finger", "--scenario", "friction", "--rock", "-o", tmp_path / "x")
    assert r.returncode == 2 and "--rock needs the paper scenario" in r.stderr


def test_a_plane_against_an_edge_is_flagged_once_rocked_and_unconfirmed_before(tmp_path):
    """The edge of a 1 mm plate on the right fingertip, a flat face on the left: before the
    object is rocked no reading can tell this from two edges (every line unconfirmed); once
    rocked about two axes the left contact is an area and the grasp is flagged."""
    r = _run(
        "simulate", "--hand", "two-finger", "--object", "plate", "--size", "1mm", "--angle", "30", "--rock",
        "--left-object", "plane", "--elements", "6000", "-o", tmp_path / "g",
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in (tmp_path / "g").iterdir()) == ["hand.toml", "left.csv", "right.csv", "truth.json"]
    r = _run("fuse", tmp_path / "g/right.csv", tmp_path / "g/left.csv", "--hand", tmp_path / "g/hand.toml", "-o", tmp_path / "f.csv")
    assert r.returncode == 0, r.stderr
    f = np.genfromtxt(tmp_path / "f.csv", delimiter=",", names=True, dtype=None, encoding=None)
    before = (f["t"] > 4.6) & (f["t"] < 5.5)  # the papers' disturbances only: one axis
    assert not np.any(np.char.find(f["flag"][before].astype(str), "area") >= 0)
    assert set(f["evidence"][before]) <= {"unconfirmed", ""}
    after = f["t"] > 8.0  # rocked about both axes
    # area is a reading of the current window: it may lapse briefly where one rocking axis
    # hands over to the next
    assert np.mean(np.char.find(f["flag"][after].astype(str), "area") >= 0) > 0.85
    assert np.mean(f["grasp"][after] == "line_and_face") > 0.85
    assert "flagged area" in r.stderr


# -- the fused standard deviations and the 3-D view ----------------------------------------------


def _fingers(grasp, tip, config=None):
    """Both fingertips of a simulated two-finger grasp, estimated, at their poses in the hand."""
    config = config or softtip.EstimatorConfig()
    fingers = []
    for side in ("right", "left"):
        log, p = grasp.logs[side], grasp.sensor_poses[side]
        est = softtip.estimate(log.t, log.wrench, tip, config)
        fingers.append(Finger(side, est, PoseSeries.fixed(p.rotation, p.translation, side), config.noise))
    return fingers


def _fused_z(grasp, tip, start, config=None, **options):
    """rms(error / reported std) of the fused direction and plane normal over the held grasp."""
    fz = fuse(_fingers(grasp, tip, config), object_mass=grasp.object_mass, **options)
    held = (fz.t > start) & (fz.grasp_names == "parallel_lines")
    assert held.sum() > 0.8 * np.count_nonzero(fz.t > start)

    def axial(a, b):
        return np.arccos(np.clip(np.abs(np.sum(a * b, axis=-1)), 0.0, 1.0))

    e = axial(fz.direction[held], grasp.truth_line()[held])
    en = axial(fz.plane_normal[held], grasp.truth_plane_normal()[held])
    z = np.sqrt(np.mean((e / fz.direction_std[held]) ** 2))
    zn = np.sqrt(np.mean((en / fz.plane_normal_std[held]) ** 2))
    return z, zn, fz.evidence[held]


def test_fused_std_counts_the_error_both_fingers_share():
    """A stick at −45° without rocking: both fingers' lines are turned the same way by the
    rolling the single-axis load cannot show (about 7°, each finger reporting under 4°). The
    fused standard deviation must cover it (the shared error and the unconfirmed line's
    model error); treating the fingers as independent and the line as certain does not."""
    from softtip.sim import stick
    from softtip.sim.hand import simulate_two_finger

    tip = softtip.murakami2006()
    g = simulate_two_finger(tip, stick(0.004), math.radians(-45), rng=7, n_elements=6000, duration=8.0)
    z, zn, evidence = _fused_z(g, tip, 6.0)
    assert np.all(evidence == "unconfirmed")
    assert 0.5 < z < 1.5 and 0.5 < zn < 1.5
    # the fingers as independent and their unconfirmed lines as certain (noise only)
    noise_only = softtip.EstimatorConfig(unconfirmed_model_std=0.0, window_model_std=0.0)
    z_naive, _, _ = _fused_z(g, tip, 6.0, noise_only, finger_correlation=0.0)
    assert z_naive > 2.0
    # the model error given to fuse instead of to the estimator: the same reading (one model
    # error for every unconfirmed sample, as fuse adds it, for the held h and a window alike)
    five = math.radians(5.0)
    z_one, _, _ = _fused_z(g, tip, 6.0, softtip.EstimatorConfig(unconfirmed_model_std=five, window_model_std=five))
    z_fuse, _, _ = _fused_z(g, tip, 6.0, noise_only, unconfirmed_std=five)
    assert abs(z_fuse - z_one) < 0.1 * z_one


def test_fused_std_propagation():
    """The fused direction's variance from the fingers' angle stds: independent (ρ = 0), or
    with each finger's model error (its ``angle_std`` less the noise's share; here both lines
    are unconfirmed, so at least their 5° each) shared (ρ = 1: the noise averages out, the
    shared error does not), plus fuse's own term."""
    gr, pr = _finger("right", R_RIGHT, 30.0, seed=1)
    gl, pl = _finger("left", R_LEFT, -30.0, seed=2)
    logs = [("right", gr.t, gr.wrench, pr), ("left", gl.t, gl.wrench, pl)]
    # one model error for every unconfirmed direction (a held h's and a one-axis window's alike)
    one = softtip.EstimatorConfig(window_model_std=softtip.EstimatorConfig().unconfirmed_model_std)
    runs = {rho: fuse_logs(logs, "murakami2006", one, finger_correlation=rho, unconfirmed_std=0.0) for rho in (0.0, 1.0)}
    fused, fingers = runs[0.0]
    late = (fused.t > 7.0) & (fused.grasp_names == "parallel_lines")
    assert late.sum() > 50
    assert (fused.evidence[late] == "unconfirmed").all()
    ib = np.searchsorted(fingers[1].estimates.t, fused.t[late], side="right") - 1
    ea, eb = fingers[0].estimates, fingers[1].estimates
    sa, sb = ea.angle_std[late], eb.angle_std[ib]
    ma = np.sqrt(sa**2 - ea.angle_noise_std[late] ** 2)
    mb = np.sqrt(sb**2 - eb.angle_noise_std[ib] ** 2)
    m = one.unconfirmed_model_std
    assert np.all(ma >= m * (1 - 1e-9)) and np.all(mb >= m * (1 - 1e-9))
    wa, wb = sa**-2, sb**-2
    assert_allclose(fused.direction_std[late], 1.0 / np.sqrt(wa + wb), rtol=1e-12)
    shared = runs[1.0][0].direction_std[late]
    assert_allclose(shared**2, (wa + wb + 2 * wa * wb * ma * mb) / (wa + wb) ** 2, rtol=1e-12)
    # never below the smaller shared error, never above the whole errors fully correlated
    assert np.all(shared >= np.minimum(ma, mb) * (1 - 1e-12))
    assert np.all(shared <= (1 / sa + 1 / sb) / (wa + wb) * (1 + 1e-12))
    # the noise of the two sensors averages: never above the worse finger where both are
    # alike, and below the better one where they are alike within 5 % and the noise is a real
    # share of each (with a model error of 0.5°: at 5° the shared model error is nearly all)
    alike = np.abs(sa / sb - 1) < 0.2
    assert alike.sum() > 10 and np.all(shared[alike] < np.maximum(sa, sb)[alike])
    half = math.radians(0.5)
    small = softtip.EstimatorConfig(unconfirmed_model_std=half, window_model_std=half)
    fs, (fa, fb) = fuse_logs(logs, "murakami2006", small, finger_correlation=1.0)
    late = (fs.t > 7.0) & (fs.grasp_names == "parallel_lines")
    ib = np.searchsorted(fb.estimates.t, fs.t[late], side="right") - 1
    sa, sb = fa.estimates.angle_std[late], fb.estimates.angle_std[ib]
    noisy = (np.abs(sa / sb - 1) < 0.05) & (fa.estimates.angle_noise_std[late] > 0.3 * sa)
    noisy &= fb.estimates.angle_noise_std[ib] > 0.3 * sb
    assert noisy.sum() > 5 and np.all(fs.direction_std[late][noisy] < np.minimum(sa, sb)[noisy])
    # fuse's own term adds in quadrature
    su = math.radians(5.0)
    withu, _ = fuse_logs(logs, "murakami2006", one, finger_correlation=1.0, unconfirmed_std=su)
    assert_allclose(withu.direction_std[late] ** 2, runs[1.0][0].direction_std[late] ** 2 + su**2, rtol=1e-12)
    with pytest.raises(ValueError, match="finger_correlation"):
        fuse(fingers, finger_correlation=1.5)


@pytest.mark.slow
def test_fused_std_of_a_rocked_edge_is_calibrated():
    """A cube's edge rocked about two axes (confirmed lines): error / std near 1 over three
    noise seeds (one run's z spreads by about ±0.25 from seed to seed), neither
    overconfident nor several times too cautious."""
    from softtip.sim import ContactModel, ContactParams, Wedge, discretise_skin
    from softtip.sim.hand import simulate_two_finger

    tip = softtip.murakami2006()
    model = ContactModel(discretise_skin(tip, n_elements=6000), ContactParams(), 2)
    zs, zns = [], []
    for seed in (7, 8, 9):
        g = simulate_two_finger(tip, Wedge(0.5 * math.pi), math.radians(-40), rng=seed, model=model, rock=True)
        z, zn, evidence = _fused_z(g, tip, 8.0)
        assert np.mean(evidence == "confirmed") > 0.8
        zs.append(z)
        zns.append(zn)
    z, zn = np.sqrt(np.mean(np.square(zs))), np.sqrt(np.mean(np.square(zns)))
    assert 0.7 < z < 1.5 and 0.7 < zn < 1.5, (zs, zns)


def _strips(path, entity):
    """{t (s): first line strip (K, 3)} logged to ``entity`` in a saved recording."""
    from rerun.chunk import RrdReader

    out = {}
    for chunk in RrdReader(path).store().stream():
        if chunk.entity_path != entity:
            continue
        batch = chunk.to_record_batch()
        if "LineStrips3D:strips" not in batch.schema.names:
            continue  # a Clear
        ts = batch.column("t").to_pylist()
        strips = batch.column("LineStrips3D:strips").to_pylist()
        for t, s in zip(ts, strips):
            if s:  # a Clear logs no strips
                out[t.total_seconds()] = np.asarray(s[0], dtype=float)
    return out


def test_fuse_rerun_view_shows_both_fingers_the_fused_line_and_the_truth(simulated, tmp_path):
    pytest.importorskip("rerun")
    g, out = simulated
    grasp = out / "grasp"
    r = _run(
        "fuse", grasp / "right.csv", grasp / "left.csv", "--hand", grasp / "hand.toml", "-o", tmp_path / "f.csv",
        "--rerun-save", tmp_path / "v.rrd", "--truth", grasp / "truth.json",
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f.csv", "v.rrd"]
    from test_viz import entity_rows

    rows = entity_rows(tmp_path / "v.rrd")
    for side in ("right", "left"):
        assert rows[f"/hand/{side}/skin"] == 1
        for part in ("", "/contact", "/normal", "/edge"):
            assert rows[f"/hand/{side}{part}"] == len(g.t)
    for entity in ("/hand/fused/line", "/hand/fused/plane", "/hand/truth/line", "/series/fused/direction_std_deg"):
        assert rows[entity] == len(g.t)
    # the line drawn is the fused line, and it lies along the object's true line
    fused, truth = _strips(tmp_path / "v.rrd", "/hand/fused/line"), _strips(tmp_path / "v.rrd", "/hand/truth/line")
    late = [t for t in fused if t > 6.0 and t in truth]
    assert len(late) > 20

    def axis(strip):
        d = strip[-1] - strip[0]
        return d / np.linalg.norm(d)

    err = [np.degrees(np.arccos(min(1.0, abs(axis(fused[t]) @ axis(truth[t]))))) for t in late]
    assert np.median(err) < 4.0
    # drawn through the midpoint of the contacts written to the table
    table = np.genfromtxt(tmp_path / "f.csv", delimiter=",", names=True, dtype=None, encoding=None)
    k = int(np.argmin(np.abs(table["t"] - late[-1])))
    mid = 0.5 * np.array([table[f"r1_{a}"][k] + table[f"r2_{a}"][k] for a in "xyz"])
    assert_allclose(fused[late[-1]].mean(axis=0), mid, atol=1e-6)


def test_fuse_rerun_errors_leave_no_output(simulated, tmp_path):
    pytest.importorskip("rerun")
    _, out = simulated
    grasp = out / "grasp"
    args = ("fuse", grasp / "right.csv", grasp / "left.csv", "--hand", grasp / "hand.toml", "-o", tmp_path / "f.csv")
    r = _run(*args, "--truth", grasp / "truth.json")
    assert r.returncode == 2 and "--truth" in r.stderr and "--rerun" in r.stderr
    bad = tmp_path / "truth.json"
    bad.write_text('{"format": "something else"}\n')
    r = _run(*args, "--rerun-save", tmp_path / "v.rrd", "--truth", bad)
    assert r.returncode == 2 and "truth.json: not a softtip two-finger truth file" in r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["truth.json"]


@pytest.mark.parametrize(("left_angle", "left_kw", "grasp", "strips"), [(45.0, None, "crossing_lines", 2), (0.0, {"h_peak": 0.0}, "line_and_face", 1)])
def test_rerun_view_of_crossing_lines_and_of_a_line_and_a_face(tmp_path, left_angle, left_kw, grasp, strips):
    pytest.importorskip("rerun")
    from softtip.fusion.viz import log_fused

    right_angle = 45.0 if grasp == "crossing_lines" else 0.0
    gr, pr = _finger("right", R_RIGHT, right_angle, seed=1)
    gl, pl = _finger("left", R_LEFT, left_angle, seed=2, **(left_kw or {}))
    fused, fingers = fuse_logs([("right", gr.t, gr.wrench, pr), ("left", gl.t, gl.wrench, pl)], "murakami2006")
    k = int(np.flatnonzero(fused.grasp_names == grasp)[-1])
    log_fused(fused, fingers, softtip.murakami2006(), save=tmp_path / "v.rrd", max_frames=len(fused))
    lines = _strips(tmp_path / "v.rrd", "/hand/fused/line")
    from rerun.chunk import RrdReader

    drawn = None
    for chunk in RrdReader(tmp_path / "v.rrd").store().stream():
        if chunk.entity_path == "/hand/fused/line":
            batch = chunk.to_record_batch()
            if "LineStrips3D:strips" in batch.schema.names:
                for t, s in zip(batch.column("t").to_pylist(), batch.column("LineStrips3D:strips").to_pylist()):
                    if t.total_seconds() == pytest.approx(fused.t[k], abs=1e-9):
                        drawn = [np.asarray(x) for x in s]
    assert drawn is not None and len(drawn) == strips and fused.t[k] in lines
    # each line drawn passes through a contact and runs along a fused direction
    dirs = [fused.direction[k]] + ([fused.direction_b[k]] if strips == 2 else [])
    for strip, d, r in zip(drawn, dirs, (fused.point_a[k], fused.point_b[k])):
        assert_allclose(strip.mean(axis=0), r, atol=1e-6)
        u = (strip[-1] - strip[0]) / np.linalg.norm(strip[-1] - strip[0])
        assert abs(u @ d) == pytest.approx(1.0, abs=1e-6)


def test_fuse_logs_checks_the_force_balance_against_the_noise_each_tare_measured():
    gr, pr = _finger("right", R_RIGHT, 30.0, seed=1, noise=NANO17.scaled(0.5))
    gl, pl = _finger("left", R_LEFT, -30.0, seed=2, noise=NANO17.scaled(2.0))
    logs = [("right", gr.t, gr.wrench, pr), ("left", gl.t, gl.wrench, pl)]
    config = EstimatorConfig(noise_from_tare=True, tare_duration=1.5)
    _, fingers = fuse_logs(logs, "murakami2006", config)
    for finger, scale in zip(fingers, (0.5, 2.0)):
        assert finger.noise == finger.estimates.tare.noise
        assert_allclose(finger.noise.force_std, np.full(3, scale * NANO17.force_std[0]), rtol=0.5)


def test_fuse_refuses_a_sample_beyond_the_sensors_range_as_estimate_does(tmp_path):
    # fuse had no range check (one row at 100 N: "1 time step flagged unbalanced", exit 0), and its
    # help named a --full-scale it did not have
    r = _run("simulate", "--hand", "two-finger", "--rate", "50", "--duration", "6", "-o", tmp_path / "g")
    assert r.returncode == 0, r.stderr
    lines = (tmp_path / "g" / "left.csv").read_text().splitlines()
    cells = lines[200].split(",")
    cells[2] = "100"  # fy
    lines[200] = ",".join(cells)
    spiked = tmp_path / "spiked.csv"
    spiked.write_text("\n".join(lines) + "\n")
    args = ["fuse", tmp_path / "g" / "right.csv", spiked, "--hand", tmp_path / "g" / "hand.toml", "-o", tmp_path / "f.csv"]
    done = _run(*args)
    assert done.returncode == 2 and f"{spiked}: sample 200 (t = 3.98 s): fy = 100 N is beyond the sensor's" in done.stderr
    assert not (tmp_path / "f.csv").exists()
    allowed = _run(*args, "--full-scale", "off")
    assert allowed.returncode == 0, allowed.stderr


def test_fuse_refuses_one_log_twice_and_says_how_much_is_fused_alone(tmp_path):
    r = _run("simulate", "--hand", "two-finger", "--rate", "50", "--duration", "6", "-o", tmp_path / "g")
    assert r.returncode == 0, r.stderr
    right, left, hand = (tmp_path / "g" / n for n in ("right.csv", "left.csv", "hand.toml"))
    twice = _run("fuse", right, right, "--hand", hand)
    assert twice.returncode == 2 and "are the same file; expected one log per finger" in twice.stderr
    half = tmp_path / "half.csv"  # the left finger's first 3 s of 6: half the fused rows are one finger's
    half.write_text("\n".join(left.read_text().splitlines()[:151]) + "\n")
    done = _run("fuse", right, half, "--hand", hand, "-o", tmp_path / "f.csv")
    assert done.returncode == 0 and "the logs overlap for 2.98 s of the longer's 5.98 s" in done.stderr, done.stderr
