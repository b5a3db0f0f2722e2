"""Issue 32, "nothing lost": a failed run leaves every file as it was, no option value gives a
traceback, signals end every command within seconds, live faults end the session.

Every case runs the installed ``softtip`` command with a bounded time-out.
"""

from __future__ import annotations

import os
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from softtip import EXAMPLE_PATH

SOFTTIP = str(Path(sys.executable).with_name("softtip"))
posix_only = pytest.mark.skipif(os.name != "posix", reason="FIFOs and signals are POSIX")
has_dev_full = pytest.mark.skipif(not Path("/dev/full").is_char_device(), reason="needs /dev/full")


def run(*args, cwd=None, timeout=120, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([SOFTTIP, *map(str, args)], capture_output=True, text=True, timeout=timeout, cwd=cwd, **kw)


def no_traceback(r: subprocess.CompletedProcess) -> None:
    assert "Traceback" not in r.stderr, r.stderr
    assert "RuntimeWarning" not in r.stderr, r.stderr


def snapshot(folder: Path) -> dict[str, bytes | None]:
    """Every entry of ``folder`` (recursively) with its bytes (None for a directory or special file)."""
    out = {}
    for p in sorted(folder.rglob("*")):
        out[str(p.relative_to(folder))] = p.read_bytes() if p.is_file() and not p.is_fifo() else None
    return out


@pytest.fixture
def log(tmp_path) -> Path:
    path = tmp_path / "grasp.csv"
    shutil.copy(EXAMPLE_PATH, path)
    return path


# ---------------------------------------------------------------------------------------
# 1. the outputs of a run are one transaction


FAILING_SECOND_OUTPUT = {
    "save-bias-missing-folder": ["--save-bias", "nodir/b.toml"],
    "plot-missing-folder": ["--plot", "nodir/p.png"],
    "rerun-save-full": ["--rerun-save", "/dev/full"],
    "chunked-save-bias-missing-folder": ["--chunk-rows", "100", "--save-bias", "nodir/b.toml"],
    "save-bias-whole-log-in-tare": ["--tare-duration", "100", "--save-bias", "b.toml"],
    "to-bag-exists": ["--to-bag", "bag_exists"],
    "plot-and-bag-then-bias-fails": ["--plot", "p.png", "--to-bag", "newbag", "--save-bias", "nodir/b.toml"],
    "chunked-whole-log-in-tare": ["--chunk-rows", "100", "--tare-duration", "100", "--save-bias", "b.toml"],
}


@pytest.mark.parametrize("existing", [True, False], ids=["replaces", "creates"])
@pytest.mark.parametrize("extra", list(FAILING_SECOND_OUTPUT.values()), ids=list(FAILING_SECOND_OUTPUT))
def test_a_failing_output_leaves_every_file_as_it_was(tmp_path, log, extra, existing):
    if "/dev/full" in extra and not Path("/dev/full").is_char_device():
        pytest.skip("needs /dev/full")
    if "--to-bag" in extra:
        pytest.importorskip("rosbags")
    (tmp_path / "bag_exists").mkdir()
    (tmp_path / "bag_exists" / "metadata.yaml").write_text("not mine\n")
    if existing:
        (tmp_path / "out.csv").write_text("an earlier result\n")
    before = snapshot(tmp_path)
    r = run("estimate", log.name, "-o", "out.csv", *extra, cwd=tmp_path)
    no_traceback(r)
    assert r.returncode == 2, r.stderr
    assert "softtip: error:" in r.stderr
    assert snapshot(tmp_path) == before


def test_all_outputs_appear_together(tmp_path, log):
    pytest.importorskip("rosbags")
    (tmp_path / "out.parquet").write_bytes(b"old")
    r = run("estimate", log.name, "-o", "out.parquet", "--plot", "p.png", "--to-bag", "bag", "--save-bias", "b.toml", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["b.toml", "bag", "grasp.csv", "out.parquet", "p.png"]
    assert (tmp_path / "out.parquet").read_bytes()[:4] == b"PAR1"


def test_chunked_outputs_commit_together(tmp_path, log):
    r = run("estimate", log.name, "-o", "out.csv", "--chunk-rows", "100", "--save-bias", "b.toml", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b.toml", "grasp.csv", "out.csv"]
    one = run("estimate", log.name, "-o", "one.csv", cwd=tmp_path)
    assert one.returncode == 0
    assert (tmp_path / "one.csv").read_bytes() == (tmp_path / "out.csv").read_bytes()


def test_outputs_object_restores_replaced_files_when_a_rename_fails(tmp_path, monkeypatch):
    from softtip.errors import InputError
    from softtip.io.atomic import Outputs

    (tmp_path / "a.txt").write_text("A")
    (tmp_path / "b.txt").write_text("B")
    real_replace = os.replace
    calls = []

    def failing_replace(src, dst):
        calls.append(dst)
        if len(calls) == 2:
            raise OSError(28, "No space left on device")
        return real_replace(src, dst)

    monkeypatch.setattr(os, "replace", failing_replace)
    with pytest.raises(InputError, match="b.txt"), Outputs() as out:
        for name in ("a.txt", "b.txt"):
            with out.file(tmp_path / name).open() as fh:
                fh.write("new")
    monkeypatch.setattr(os, "replace", real_replace)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt", "b.txt"]
    assert (tmp_path / "a.txt").read_text() == "A" and (tmp_path / "b.txt").read_text() == "B"


@posix_only
@pytest.mark.parametrize("command", [["estimate", "{log}"], ["simulate", "--rate", "50"]])
def test_output_to_dev_stdout_through_a_pipe(log, command):
    args = [a.replace("{log}", str(log)) for a in command]
    r = subprocess.run(f"{SOFTTIP} {' '.join(args)} -o /dev/stdout | cat", shell=True, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    no_traceback(r)
    assert r.stdout.startswith("t,")
    assert len(r.stdout.splitlines()) > 50


@posix_only
def test_output_to_dev_null(tmp_path, log):
    r = run("estimate", log, "-o", "/dev/null", "--save-bias", tmp_path / "b.toml")
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "b.toml").exists()


@posix_only
def test_output_to_a_fifo_whose_reader_quits(tmp_path, log):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    (tmp_path / "b.toml").write_text("old")
    reader = subprocess.Popen(["head", "-c", "10", str(fifo)], stdout=subprocess.DEVNULL)
    try:
        r = run("estimate", log, "-o", fifo, "--save-bias", tmp_path / "b.toml", timeout=60)
    finally:
        reader.wait(timeout=30)
    no_traceback(r)
    assert r.returncode == 2
    assert str(fifo) in r.stderr and "Broken pipe" in r.stderr
    assert (tmp_path / "b.toml").read_text() == "old"
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b.toml", "grasp.csv", "pipe"]
