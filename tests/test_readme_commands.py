"""Every ``softtip ...`` line of the README's shell blocks runs as written, so they cannot rot.

The README is short; the shell blocks it held before moved to the user guide pages in
``DOCUMENTS``, and they are walked the same way. The README's Python example runs too.

Each block runs in its own temporary directory, its lines in order (a line may use what an
earlier one wrote), through the installed ``softtip`` command. Files a line reads that the
README assumes the reader has (their own grasp log, probing log, still log, a bag) and no
earlier line of the block wrote are put there first, made from softtip's shipped examples.
Skipped, and said so: lines that need a sensor (``stream --netft``), a display (``--rerun``)
or ROS 2 (``python -m softtip.ros``), and lines that are not softtip's (``make``, ``pip``).
The fast test leaves out the slow lines (``reproduce``, a rocked two-finger simulation) and
the lines that read what they write; the ``slow`` test runs those too.
"""

from __future__ import annotations

import re
import shlex
import shutil
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import simcache

SOFTTIP = Path(sys.executable).with_name("softtip")
ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
#: The README and the documentation pages whose shell blocks came from it
DOCUMENTS = (
    README,
    ROOT / "docs" / "guide" / "using-softtip.md",
    ROOT / "docs" / "guide" / "real-data.md",
    ROOT / "docs" / "guide" / "grasped-object.md",
)

#: Lines not run, and why (the first pattern found in a line decides)
SKIP = {
    "--netft": "needs a Net F/T sensor on the network",
    "--rerun ": "needs a display for the Rerun viewer",
    "python -m softtip.ros": "needs a sourced ROS 2 installation",
}
#: Lines run only by the slow test: their outputs, and every later line that reads them, too
SLOW = ("softtip reproduce", "--hand two-finger")


def readme_blocks(documents=DOCUMENTS) -> list[list[str]]:
    """The softtip command lines of each shell code block of the documents, comments removed."""
    blocks = []
    for doc in documents:
        blocks += re.findall(r"```(?:sh|bash|shell|console)\n(.*?)```", doc.read_text(encoding="utf-8"), re.DOTALL)
    out = []
    for block in blocks:
        text = block.replace("\\\n", " ")
        lines = []
        for raw in text.splitlines():
            line = raw.strip().removeprefix("$ ")
            line = " ".join(shlex.split(line, comments=True))
            if line.startswith("softtip ") or line.startswith("python -m softtip"):
                lines.append(line)
        if lines:
            out.append(lines)
    return out


def _write_csv(path: Path, t, wrench, names=("t", "fx", "fy", "fz", "mx", "my", "mz")) -> None:
    np.savetxt(path, np.column_stack([t, wrench]), delimiter=",", header=",".join(names), comments="", fmt="%.9g")


def _seed(name: str, line: str, block: list[str], work: Path) -> None:
    """Put the input the README assumes the reader has under ``name`` (made from shipped examples)."""
    from softtip.io.examples import EXAMPLE_PATH, EXAMPLE_PROBING_PATH, EXAMPLE_STILL_PATH

    dest = work / name.rstrip("/")
    if name == "grasp.csv":
        if "--units kgf-mm" in line:  # the reader's own log in the papers' units
            from softtip.core.units import wrench_from_si
            from softtip.io.tables import read_log

            log = read_log(EXAMPLE_PATH, units="si")
            _write_csv(dest, log.t, wrench_from_si(log.wrench, "kgf-mm"))
        else:
            shutil.copy(EXAMPLE_PATH, dest)
    elif name in ("probing.csv", "probe.csv"):
        shutil.copy(EXAMPLE_PROBING_PATH, dest)
    elif name == "still.csv":
        shutil.copy(EXAMPLE_STILL_PATH, dest)
    elif name == "my_tip.toml":
        run = subprocess.run([SOFTTIP, "calibrate", "--example", "--shape", "sphere", "-o", dest], capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
    elif name == "run1/":
        if any("--topics" in other for other in block):  # two fingertips' wrenches and their /tf
            run = subprocess.run(
                [SOFTTIP, "simulate", "--hand", "two-finger", "--duration", "3", "--elements", "2000", "-o", work / "_hand",
                 "--to-bag", dest],
                capture_output=True, text=True,
            )  # fmt: skip
            assert run.returncode == 0, run.stderr
            shutil.rmtree(work / "_hand")
        else:  # one sensor's wrench on the topic the README names
            from softtip.core.fingertip import load_fingertip
            from softtip.estimator import estimate
            from softtip.estimator.results import EstimatorWarning
            from softtip.io.bag import write_estimates_bag
            from softtip.io.tables import read_log

            log = read_log(EXAMPLE_PATH, units="si")
            with warnings.catch_warnings():  # what the tare says is the README line's business
                warnings.simplefilter("ignore", EstimatorWarning)
                est = estimate(log.t, log.wrench, load_fingertip("murakami2006"))
            write_estimates_bag(dest, est, log.wrench, frame_id="ft_sensor", raw_topic="/ft_sensor/wrench")
    else:
        raise AssertionError(f"the README's line {line!r} reads {name}, which this test does not know how to provide")


#: What a README line may read that the reader is assumed to have
INPUTS = ("grasp.csv", "probing.csv", "probe.csv", "still.csv", "my_tip.toml", "run1/")


def _reads(line: str) -> list[str]:
    """The assumed inputs a line names (not counting what it writes with -o / --to-bag)."""
    words = line.split()
    outputs = {words[i + 1] for i, w in enumerate(words[:-1]) if w in ("-o", "--output", "--out", "--to-bag", "--record")}
    return [w for w in words if w in INPUTS and w not in outputs]


def _written(line: str) -> set[str]:
    words = line.split()
    return {words[i + 1] for i, w in enumerate(words[:-1]) if w in ("-o", "--output", "--out", "--to-bag", "--record")}


def _run_block(block: list[str], work: Path, slow: bool) -> list[str]:
    """Run a README block's lines in ``work``; returns what was skipped and why."""
    skipped, made, slow_outputs = [], set(), set()
    for line in block:
        reason = next((why for pattern, why in SKIP.items() if pattern in line + " "), None)
        if reason is None and not slow:
            if any(p in line for p in SLOW):
                reason, slow_outputs = "slow (run by the slow test)", slow_outputs | _written(line)
            elif any(out in line for out in slow_outputs):
                reason = "reads the output of a slow line (run by the slow test)"
        if reason is not None:
            skipped.append(f"{line}: {reason}")
            continue
        for name in _reads(line):
            if name not in made:
                _seed(name, line, block, work)
                if name != "grasp.csv":  # grasp.csv: in the units of each line that reads it
                    made.add(name)
        argv = shlex.split(line)
        argv[0] = str(SOFTTIP)
        # the grasps that `reproduce` and `simulate` simulate come from the tests' cache (simcache.py)
        env = simcache.subprocess_env() if argv[1] in ("reproduce", "simulate") else None
        run = subprocess.run(argv, cwd=work, capture_output=True, text=True, timeout=900, env=env)
        assert run.returncode == 0, f"README line failed (exit {run.returncode}): {line}\n{run.stderr[-3000:]}"
        assert "Traceback" not in run.stderr, f"{line}\n{run.stderr[-3000:]}"
        made |= _written(line) | {n.rstrip("/") + "/" for n in _written(line)}
    return skipped


BLOCKS = readme_blocks()


def test_the_readme_has_softtip_commands() -> None:
    assert len(BLOCKS) >= 3 and sum(len(b) for b in BLOCKS) >= 15, BLOCKS
    assert readme_blocks([README]), "the README's command-line example is gone"


def test_the_readme_is_short() -> None:
    assert len(README.read_text(encoding="utf-8").splitlines()) <= 200


def _references(text: str) -> list[str]:
    """The bullets of a "How to cite" section, whitespace collapsed."""
    section = text.split("## How to cite", 1)[1].split("\n## ", 1)[0]
    return [" ".join(b.split()) for b in re.findall(r"^- (.*?)(?=^- |^\s*$)", section, re.DOTALL | re.MULTILINE)]


def test_the_papers_references_agree() -> None:
    """The README, the site's front page and CITATION.cff cite the two papers and softtip alike
    (softtip without an address: it has no public home yet, scripts/set_home.py)."""
    readme = _references(README.read_text(encoding="utf-8"))
    assert len(readme) == 3, readme
    assert _references((ROOT / "docs" / "index.md").read_text(encoding="utf-8")) == readme
    cff = (ROOT / "CITATION.cff").read_text(encoding="utf-8")
    for ref in readme[:2]:
        title = re.search(r'"(.+?)"', ref).group(1)
        assert f'title: "{title}"' in cff, title
    assert re.search(r"pp\. (\d+) ff\.", readme[0]).group(1) == re.search(r"^    start: (\d+)", cff, re.M).group(1)
    pages = re.search(r"pp\. (\d+)–(\d+)", readme[1]).groups()
    assert f"start: {pages[0]}" in cff and f"end: {pages[1]}" in cff
    software = re.search(r"\*(.+?)\*", readme[2]).group(1)
    assert f'title: "{software}"' in cff and "BSD-3-Clause" in readme[2]


def test_the_readme_python_example_runs() -> None:
    """The README's Python blocks run as written (the shipped example needs no file)."""
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(encoding="utf-8"), re.DOTALL)
    assert blocks
    for code in blocks:
        run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
        assert run.returncode == 0, run.stderr[-3000:]


def _has_slow_line(block: list[str]) -> bool:
    return any(any(p in line for p in SLOW) for line in block)


@pytest.mark.parametrize("k", range(len(BLOCKS)), ids=[b[0][:40] for b in BLOCKS])
def test_readme_block_runs_as_written(k: int, tmp_path: Path, request: pytest.FixtureRequest) -> None:
    slow_test = test_readme_block_runs_as_written_with_the_slow_lines.__name__
    if _has_slow_line(BLOCKS[k]) and any(
        item.name == f"{slow_test}[{request.node.callspec.id}]" and item.path == request.node.path
        for item in request.session.items
    ):  # fmt: skip
        pytest.skip("the slow test of this block runs every line of it in this session")
    skipped = _run_block(BLOCKS[k], tmp_path, slow=False)
    for why in skipped:  # in the report with -rA; every skip reason is one of SKIP's or SLOW's
        print("skipped:", why)
    assert len(skipped) < len(BLOCKS[k]) or all("--netft" in line or "softtip.ros" in line for line in BLOCKS[k])


@pytest.mark.slow
@pytest.mark.parametrize("k", range(len(BLOCKS)), ids=[b[0][:40] for b in BLOCKS])
def test_readme_block_runs_as_written_with_the_slow_lines(k: int, tmp_path: Path) -> None:
    if not _has_slow_line(BLOCKS[k]):
        pytest.skip("no slow line in this block (the fast test ran it)")
    _run_block(BLOCKS[k], tmp_path, slow=True)


@pytest.mark.skipif(shutil.which("make") is None, reason="needs make")
def test_the_readmes_make_demo_runs(tmp_path: Path) -> None:
    """The README's quick start ``make demo`` runs its recipe as written (the Makefile's, not a
    copy), with the interpreter running the tests standing in for the ``.venv`` it would
    create (no network: nothing is installed) and its output in a temporary directory.
    (``make test`` runs the whole suite, and ``pip install`` / ``git clone`` need the network:
    those README lines are not run.)"""
    assert "make demo" in README.read_text(encoding="utf-8")
    venv = tmp_path / "venv"
    (venv / "bin").mkdir(parents=True)
    for name in ("python", "softtip"):
        (venv / "bin" / name).symlink_to(Path(sys.executable).with_name(name))
    (venv / ".demo-installed").touch()  # newer than pyproject.toml: make installs nothing
    out = tmp_path / "demo-output"
    run = subprocess.run(["make", "--no-print-directory", "-C", str(ROOT), "demo", f"VENV={venv}", f"OUT={out}"],
                         capture_output=True, text=True, timeout=300)  # fmt: skip
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    assert "pip" not in run.stdout, run.stdout  # it used the stand-in, installed nothing
    assert (out / "estimates.csv").stat().st_size > 0 and (out / "estimates.png").stat().st_size > 0


def test_the_walk_fails_on_a_broken_line(tmp_path: Path) -> None:
    """The walk is not vacuous: a line that exits non-zero fails it, and an unknown input is named."""
    with pytest.raises(AssertionError, match="README line failed"):
        _run_block(["softtip estimate grasp.csv --relatch-distance 3parsecs"], tmp_path, slow=False)
    with pytest.raises(AssertionError, match="does not know how to provide"):
        _seed("other.csv", "softtip estimate other.csv", [], tmp_path)
