"""Nothing the user gave is destroyed; every failure to write is a clear exit 2 with nothing left behind.

Output onto an input (also through a symlink or a hard link), onto another output, onto a
FIFO; disk full and file too large (RLIMIT_FSIZE); standard output on a full device or a
closed pipe; SIGTERM and SIGHUP in the middle of writing. All through the installed
``softtip`` command.
"""

import os
import resource
import shutil
import signal
import stat
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from softtip import EXAMPLE_PATH
from softtip.cli import main
from softtip.errors import InputError
from softtip.io.atomic import AtomicFile, atomic_write_text, check_distinct
from softtip.io.tables import write_table

SOFTTIP = str(Path(sys.executable).with_name("softtip"))
posix_only = pytest.mark.skipif(os.name != "posix", reason="FIFOs, rlimits and signals are POSIX")


def run(*args, cwd=None, **kw):
    return subprocess.run([SOFTTIP, *map(str, args)], capture_output=True, text=True, timeout=120, cwd=cwd, **kw)


def run_here(*args):
    """The command in-process (click's runner): (exit code, everything it printed)."""
    result = CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)
    return result.exit_code, result.output


def listing(folder):
    return sorted(p.name for p in Path(folder).iterdir())


@pytest.fixture
def log(tmp_path):
    path = tmp_path / "grasp.csv"
    shutil.copy(EXAMPLE_PATH, path)
    return path


def payload_log(path, n=200):
    """A contact-free log with varied orientations: input of ``calibrate-payload``."""
    from scipy.spatial.transform import Rotation

    from softtip.calibration.payload import Payload, payload_wrench

    rng = np.random.default_rng(5)
    q = Rotation.from_rotvec(rng.normal(size=(n, 3)) * 0.8).as_quat(scalar_first=True)
    w = payload_wrench(q, Payload(0.02, (0.001, -0.0005, 0.02))) + rng.normal(scale=1e-3, size=(n, 6)) * [1, 1, 1, 1e-3, 1e-3, 1e-3]
    cols = {"t": np.arange(n) * 0.02, **{c: w[:, i] for i, c in enumerate(("fx", "fy", "fz", "mx", "my", "mz"))}}
    cols.update({c: q[:, i] for i, c in enumerate(("qw", "qx", "qy", "qz"))})
    write_table(cols, path, float_format="%.17g")
    return path


# ---------------------------------------------------------------------------------------
# 1. never an output onto an input or onto another output


@pytest.mark.parametrize("how", ["same", "relative", "symlink", "hardlink"])
def test_estimate_refuses_to_overwrite_its_input(tmp_path, log, how, monkeypatch):
    before = log.read_bytes()
    target = {"same": log, "relative": Path("sub/../grasp.csv"), "symlink": tmp_path / "link.csv", "hardlink": tmp_path / "hard.csv"}[how]
    (tmp_path / "sub").mkdir()
    if how == "symlink":
        target.symlink_to(log)
    elif how == "hardlink":
        os.link(log, target)
    if how == "same":  # once through the installed command
        out = run("estimate", "grasp.csv", "-o", target, cwd=tmp_path)
        code, message = out.returncode, out.stderr
    else:
        monkeypatch.chdir(tmp_path)
        code, message = run_here("estimate", "grasp.csv", "-o", target)
    assert code == 2, message
    assert "grasp.csv" in message and str(target) in message and "Traceback" not in message
    assert log.read_bytes() == before


def test_plot_onto_output_and_outputs_onto_each_other(tmp_path, log):
    code, message = run_here("estimate", log, "-o", tmp_path / "e.png", "--plot", tmp_path / "e.png")
    assert code == 2 and "--plot" in message and "-o" in message
    assert listing(tmp_path) == ["grasp.csv"]
    code, message = run_here("estimate", log, "--plot", log.with_suffix(".png"), "--rerun-save", log.with_suffix(".png"))
    assert code == 2 and "--rerun-save" in message
    assert listing(tmp_path) == ["grasp.csv"]


def test_every_command_refuses_its_input_as_output(tmp_path, log):
    free = payload_log(tmp_path / "free.csv")
    cases = [
        (("stream", "--replay", log, "--record", log, "--speed", "0", "--no-view"), log),
        (("calibrate", "--shape", "sphere", log, "-o", log), log),
        (("calibrate-payload", free, "-o", free), free),
        (("estimate", log, "--payload", free, "-o", free), free),
    ]
    for args, victim in cases:
        before = victim.read_bytes()
        code, message = run_here(*args)
        assert code == 2, (args, message)
        assert str(victim) in message and "refusing" in message, message
        assert victim.read_bytes() == before
    assert listing(tmp_path) == ["free.csv", "grasp.csv"]


def test_simulate_truth_onto_its_log_or_its_tip(tmp_path):
    code, message = run_here("simulate", "--rate", "20", "--duration", "5", "-o", tmp_path / "s.csv", "--truth", tmp_path / "s.csv")
    assert code == 2 and "--truth" in message and "-o" in message
    tip = tmp_path / "tip.toml"
    tip.write_text('[fingertip]\nshape = "sphere"\nradius = 0.016\ncenter = [0, 0, 0.02]\n')
    code, message = run_here("simulate", "--rate", "20", "--duration", "5", "--tip", tip, "-o", tmp_path / "s.csv", "--truth", tip)
    assert code == 2 and "--tip" in message
    assert listing(tmp_path) == ["tip.toml"]


def test_bag_input_protects_its_files(tmp_path):
    bag = tmp_path / "bag"
    bag.mkdir()
    (bag / "metadata.yaml").write_text("x\n")
    with pytest.raises(InputError, match="inside the input INPUT"):
        check_distinct([("INPUT", bag)], [("-o", bag / "metadata.yaml")])
    check_distinct([("INPUT", bag)], [("-o", tmp_path / "bag.csv"), ("--plot", None), ("-o", "-")])


# ---------------------------------------------------------------------------------------
# 2. devices and FIFOs are written into, never renamed over


@posix_only
def test_output_onto_a_fifo_stays_a_fifo(tmp_path, log):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    got = []
    reader = threading.Thread(target=lambda: got.append(fifo.read_bytes()), daemon=True)
    reader.start()
    out = run("estimate", log, "-o", fifo)
    if fifo.is_fifo() and reader.is_alive():  # nobody wrote into the pipe: release the reader
        os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
    reader.join(timeout=60)
    assert out.returncode == 0, out.stderr
    assert fifo.is_fifo()
    assert got[0].decode() == run("estimate", log).stdout
    assert listing(tmp_path) == ["grasp.csv", "pipe"]


def test_atomic_file_follows_a_symlink_and_keeps_the_mode(tmp_path):
    real = tmp_path / "real.txt"
    real.write_text("old\n")
    real.chmod(0o640)
    link = tmp_path / "link.txt"
    link.symlink_to(real)
    atomic_write_text(link, "new\n")
    assert link.is_symlink() and real.read_text() == "new\n"
    assert real.stat().st_mode & 0o777 == 0o640
    assert listing(tmp_path) == ["link.txt", "real.txt"]


def test_atomic_file_refuses_a_directory_and_discards_on_error(tmp_path):
    with pytest.raises(InputError, match="is a directory"):
        AtomicFile(tmp_path)
    with pytest.raises(RuntimeError):
        with AtomicFile(tmp_path / "x.csv") as f:
            f.tmp.write_text("partial")
            raise RuntimeError("boom")
    assert listing(tmp_path) == []



@pytest.mark.skipif(not hasattr(os, "posix_fadvise"), reason="needs posix_fadvise")
@pytest.mark.parametrize("mode", ["w", "wb"])
def test_atomic_file_hands_its_pages_to_writeback_behind_the_writer(tmp_path, monkeypatch, mode):
    import softtip.io.atomic as atomic

    calls = []
    monkeypatch.setattr(atomic, "WRITE_BEHIND_BYTES", 1000)
    monkeypatch.setattr(os, "posix_fadvise", lambda fd, start, length, advice: calls.append((start, length, advice)))
    rng = np.random.default_rng(3)
    pieces = ["".join(rng.choice(list("0123456789,.\n"), size=int(rng.integers(1, 900)))) for _ in range(400)]
    with AtomicFile(tmp_path / "t.csv") as f:
        with f.open(mode) as fh:
            for p in pieces:
                fh.write(p if mode == "w" else p.encode())
        f.commit()
    assert (tmp_path / "t.csv").read_text() == "".join(pieces)
    # each range is handed to writeback once, contiguous from the start, and dropped at the next hand-over
    ranges = [(start, length) for start, length, advice in calls if advice == os.POSIX_FADV_DONTNEED]
    handed = list(dict.fromkeys(ranges))
    assert len(ranges) == len(calls) and len(handed) >= 10 and handed[0][0] == 0
    assert all(a + n == b for (a, n), (b, _) in zip(handed, handed[1:])) and all(n >= 1000 for _, n in handed)
    assert handed[-1][0] + handed[-1][1] <= len("".join(pieces))
    assert ranges == [handed[0]] + [r for pair in zip(handed, handed[1:]) for r in pair]


def test_atomic_file_writes_on_where_the_kernel_takes_no_advice(tmp_path, monkeypatch):
    import softtip.io.atomic as atomic

    calls = []

    def refuse(fd, start, length, advice):
        calls.append(start)
        raise OSError(29, "Illegal seek")

    monkeypatch.setattr(atomic, "WRITE_BEHIND_BYTES", 10)
    monkeypatch.setattr(os, "posix_fadvise", refuse, raising=False)
    with AtomicFile(tmp_path / "t.bin") as f:
        with f.open("wb") as fh:
            for k in range(100):
                fh.write(bytes([k]) * 7)
                fh.flush()
        f.commit()
    assert (tmp_path / "t.bin").read_bytes() == b"".join(bytes([k]) * 7 for k in range(100))
    assert len(calls) == 1  # asked once, then written as any file

# ---------------------------------------------------------------------------------------
# 3. disk full, file too large, standard output on a full device or a closed pipe


def _limit_file_size(limit):
    def preexec():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # write() then fails with EFBIG
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    return preexec


@posix_only
@pytest.mark.parametrize(
    "args, names",
    [
        (("estimate", "{log}", "-o", "{d}/e.csv"), ["e.csv"]),
        (("estimate", "{log}", "-o", "{d}/e.csv", "--plot", "{d}/p.png"), ["e.csv", "p.png"]),
        (("estimate", "{log}", "--to-bag", "{d}/out_bag"), ["out_bag"]),
        (("simulate", "--rate", "50", "--duration", "6", "-o", "{d}/s.csv"), ["s.csv", "s.truth.json"]),
    ],
    ids=["estimate-o", "estimate-plot", "estimate-to-bag", "simulate"],
)
def test_file_too_large_exits_2_and_leaves_nothing(tmp_path, log, args, names):
    if "--to-bag" in args:
        pytest.importorskip("rosbags")
    d = tmp_path / "out"
    d.mkdir()
    argv = [a.format(log=log, d=d) for a in args]
    # no bytecode written under the limit: Python would keep a cut .pyc where the run's later
    # processes read it (tests/conftest.py keeps their bytecode in one folder)
    out = run(*argv, preexec_fn=_limit_file_size(30_000), env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"})
    assert out.returncode == 2, out.stderr
    assert "File too large" in out.stderr and "Traceback" not in out.stderr
    assert any(str(d / n) in out.stderr for n in names), out.stderr
    assert listing(d) == []


@posix_only
@pytest.mark.skipif(not Path("/dev/full").is_char_device(), reason="needs /dev/full")
@pytest.mark.parametrize("args", [("estimate", "--example"), ("simulate", "--rate", "20", "--duration", "5")])
def test_standard_output_on_a_full_device_exits_2(args):
    with open("/dev/full", "w") as full:
        out = subprocess.run([SOFTTIP, *args], stdout=full, stderr=subprocess.PIPE, text=True, timeout=120)
    assert out.returncode == 2, out.stderr
    assert "standard output" in out.stderr and "No space left on device" in out.stderr and "Traceback" not in out.stderr


@posix_only
@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() != 0, reason="creating device nodes needs root")
def test_output_onto_a_device_node_is_written_into(tmp_path):
    # our own nodes of the null and full devices (never the system's: a rename would replace them)
    null, full = tmp_path / "null", tmp_path / "full"
    os.mknod(null, 0o666 | stat.S_IFCHR, os.makedev(1, 3))
    os.mknod(full, 0o666 | stat.S_IFCHR, os.makedev(1, 7))
    out = run("estimate", "--example", "-o", null)
    assert out.returncode == 0, out.stderr
    out = run("estimate", "--example", "-o", full)
    assert out.returncode == 2 and f"{full}: cannot write (No space left on device)" in out.stderr, out.stderr
    assert null.is_char_device() and full.is_char_device()
    assert listing(tmp_path) == ["full", "null"]


@posix_only
def test_closed_pipe_exits_2():
    with subprocess.Popen([SOFTTIP, "estimate", "--example"], stdout=subprocess.PIPE, stderr=subprocess.PIPE) as proc:
        proc.stdout.readline()
        proc.stdout.close()  # the reader went away, as `| head -1` does
        err = proc.stderr.read().decode()
        assert proc.wait(timeout=120) == 2, err
    assert "standard output" in err and "Broken pipe" in err and "Traceback" not in err


# ---------------------------------------------------------------------------------------
# 4. SIGTERM and SIGHUP unwind like Ctrl-C: no temporary file stays, exit 128 + signal


def _interrupt_while_blocked(tmp_path, argv, sig, expect_tmp):
    """Run ``argv`` writing into a FIFO nobody reads: it blocks at the end, with its temporary
    files in place; then send ``sig``."""
    tmpdir = tmp_path / "tmpdir"
    tmpdir.mkdir()
    env = {**os.environ, "TMPDIR": str(tmpdir)}
    # Ctrl-C as in a terminal: a job started in the background (as a CI runner may start the
    # tests) inherits SIGINT ignored, and Python then leaves it ignored
    proc = subprocess.Popen(
        [SOFTTIP, *map(str, argv)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )  # fmt: skip
    deadline = time.monotonic() + 90
    while time.monotonic() < deadline and proc.poll() is None:
        hidden = [p.name for d in (tmp_path, tmpdir) for p in d.iterdir() if p.name.startswith(".")]
        if len(hidden) >= expect_tmp:
            break
        time.sleep(0.05)
    assert proc.poll() is None, proc.stderr.read().decode()
    time.sleep(0.3)
    proc.send_signal(sig)
    try:
        _, err = proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate()
        raise
    return proc.returncode, err.decode(), tmpdir


@posix_only
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP, signal.SIGINT], ids=["SIGTERM", "SIGHUP", "SIGINT"])
def test_estimate_interrupted_leaves_no_temporary_file(tmp_path, log, sig):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    code, err, tmpdir = _interrupt_while_blocked(tmp_path, ["estimate", log, "-o", fifo, "--plot", tmp_path / "p.png"], sig, 2)
    assert code == 128 + sig, err
    assert f"interrupted ({signal.Signals(sig).name})" in err and "Traceback" not in err
    assert listing(tmp_path) == ["grasp.csv", "pipe", "tmpdir"] and listing(tmpdir) == []


@posix_only
def test_simulate_and_calibrate_interrupted_leave_no_temporary_file(tmp_path):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    argv = ["simulate", "--rate", "20", "--duration", "5", "-o", fifo, "--truth", tmp_path / "t.json"]
    code, err, tmpdir = _interrupt_while_blocked(tmp_path, argv, signal.SIGTERM, 2)
    assert code == 143, err
    assert listing(tmp_path) == ["pipe", "tmpdir"] and listing(tmpdir) == []
    shutil.rmtree(tmpdir)
    free = payload_log(tmp_path / "free.csv")
    code, err, tmpdir = _interrupt_while_blocked(tmp_path, ["calibrate-payload", free, "-o", fifo], signal.SIGTERM, 1)
    assert code == 143, err
    assert listing(tmp_path) == ["free.csv", "pipe", "tmpdir"] and listing(tmpdir) == []


@pytest.mark.parametrize("name", ["out.csv.gz", "out.csv.ZST", "out.bz2"])
def test_o_refuses_a_compressed_name_it_would_fill_with_plain_text(tmp_path, name):
    # the readers take compressed logs; the writers write plain text, which a .gz name hid (exit 0,
    # a file gzip and pandas then refused)
    for args in (("estimate", "--example"), ("stream", "--replay", EXAMPLE_PATH, "--speed", "0"), ("simulate",)):
        out = run(*args, "-o", tmp_path / name)
        assert out.returncode == 2 and "compressed file, but -o writes uncompressed text" in out.stderr, out.stderr
        plain = str(tmp_path / name)[: -len(Path(name).suffix)]
        assert f"(-o {plain}, then compress it:" in out.stderr
        assert ("-o OUT.parquet" in out.stderr) == (args[0] == "estimate")
    assert list(tmp_path.iterdir()) == []


def test_o_dash_is_standard_output_for_every_command(tmp_path):
    # simulate, calibrate and calibrate-payload wrote a file named '-' (and simulate '-.truth.json')
    for args, first in ((("simulate",), "t,fx"), (("calibrate", "--example", "--shape", "sphere"), "[fingertip]"),
                        (("calibrate-payload", "--example"), "# softtip calibrate-payload")):  # fmt: skip
        out = run(*args, "-o", "-", cwd=tmp_path)
        assert out.returncode == 0 and out.stdout.startswith(first), out.stderr
    assert listing(tmp_path) == []


@posix_only
def test_simulate_writes_no_truth_file_beside_a_device(tmp_path):
    # -o /dev/null (or /dev/stdout) made /dev/null.truth.json: the truth goes beside a file only
    before = set(os.listdir("/dev"))
    out = run("simulate", "-o", "/dev/null", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert not any(n.endswith(".truth.json") for n in set(os.listdir("/dev")) - before)
    assert "-> /dev/null" in out.stderr and "truth" not in out.stderr


def test_o_dot_is_a_directory(tmp_path):
    # simulate -o . said "'' is an empty file name"
    for args in (("simulate",), ("estimate", "--example"), ("calibrate", "--example", "--shape", "sphere")):
        out = run(*args, "-o", ".", cwd=tmp_path)
        assert out.returncode == 2 and ("'.' is a directory" in out.stderr or ". is a directory" in out.stderr), out.stderr
    assert listing(tmp_path) == []


def test_a_replay_of_a_bag_says_it_is_one_and_where_bags_are_read(tmp_path):
    # it said "not valid UTF-8 ... re-save it as UTF-8"
    bag = tmp_path / "run.bag"
    bag.write_bytes(b"#ROSBAG V2.0\n" + bytes(range(256)))
    out = run("stream", "--replay", bag, "--speed", "0", cwd=tmp_path)
    assert out.returncode == 2 and f"{bag}: a ROS bag; --replay reads a CSV, Parquet or Arrow log" in out.stderr, out.stderr


def test_a_csv_only_output_named_like_parquet_names_no_conversion_that_loses_columns(tmp_path):
    # the remedy named `softtip estimate LOG.csv -o OUT.parquet`, which writes estimates, not the log
    # or the recording (their raw columns lost)
    for args in (("simulate",), ("stream", "--replay", EXAMPLE_PATH, "--speed", "0")):
        out = run(*args, "-o", tmp_path / "x.parquet", cwd=tmp_path)
        assert out.returncode == 2 and "this command writes CSV; expected a name ending in .csv" in out.stderr
        assert "converts" not in out.stderr
    assert listing(tmp_path) == []
