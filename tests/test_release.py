"""A release builds: a tagged tree gives a wheel and an sdist of the tag's version that pass
``twine check``, and the sdist carries what the README links to. Slow (two builds, ~30 s).

Built without isolation (``python -m build --no-isolation``) so that no network is needed:
setuptools, setuptools-scm, build and twine are in the ``test`` extra.
"""

from __future__ import annotations

import importlib.util
import re
import shutil
import subprocess
import sys
import tarfile
import zipfile
from email.parser import HeaderParser
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
MISSING = [m for m in ("build", "twine", "setuptools_scm") if importlib.util.find_spec(m) is None]
pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(bool(MISSING), reason=f"needs {', '.join(MISSING)} (pip install -e '.[test]')"),
]

#: What the sdist must carry: the files the README and the docs link to or build from
IN_SDIST = (
    "README.md",
    "CHANGELOG.md",
    "CITATION.cff",
    "LICENSE",
    "docs/conf.py",
    "docs/index.md",
    "docs/guide/using-softtip.md",
    "docs/guide/03-the-measurement.md",
    "docs/reproduction.md",
    "docs/reproduction/summary.md",
    "docs/example.png",
    "docs/benchmarks/performance.md",
    "benchmarks/bench_core.py",
    "ros/package.xml",
    "ros/launch/softtip.launch.py",
)


#: A stand-in for softtip's public home, which does not exist yet (scripts/set_home.py)
HOME = "https://git.example.org/softtip/softtip"


def _git(cwd: Path, *args: str) -> None:
    subprocess.run(["git", "-c", "user.name=t", "-c", "user.email=t@t", "-c", "commit.gpgsign=false", *args],
                   cwd=cwd, check=True, capture_output=True)  # fmt: skip


def _copy_tree(dest: Path) -> Path:
    """The working tree as it is (tracked and untracked files git does not ignore)."""
    files = subprocess.run(["git", "ls-files", "-co", "--exclude-standard", "-z"], cwd=ROOT, check=True,
                           capture_output=True).stdout.decode().split("\0")  # fmt: skip
    for name in filter(None, files):
        src = ROOT / name
        if src.is_file():
            (dest / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dest / name)
    return dest


def _build(tree: Path, *what: str) -> list[Path]:
    out = tree / "dist"
    run = subprocess.run([sys.executable, "-m", "build", "--no-isolation", *what, "--outdir", str(out), str(tree)],
                         capture_output=True, text=True, timeout=600)  # fmt: skip
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    return sorted(out.iterdir())


@pytest.fixture(scope="module")
def tagged(tmp_path_factory) -> list[Path]:
    tree = _copy_tree(tmp_path_factory.mktemp("tagged"))
    # the release step that gives the files softtip's home (docs/contributing.md), with a stand-in
    subprocess.run([sys.executable, str(tree / "scripts" / "set_home.py"), HOME, "--blob", f"{HOME}/blob/v9.8.7/",
                    "--raw", f"{HOME}/raw/v9.8.7/", "--root", str(tree)], check=True, capture_output=True)  # fmt: skip
    _git(tree, "init", "-q")
    _git(tree, "add", "-A")
    _git(tree, "commit", "-q", "-m", "release")
    _git(tree, "tag", "v9.8.7")
    return _build(tree, "--sdist", "--wheel")


def test_a_tag_gives_the_version(tagged: list[Path]) -> None:
    names = [p.name for p in tagged]
    assert "softtip-9.8.7.tar.gz" in names and "softtip-9.8.7-py3-none-any.whl" in names, names


def test_twine_check_passes(tagged: list[Path]) -> None:
    run = subprocess.run([sys.executable, "-m", "twine", "check", "--strict", *map(str, tagged)], capture_output=True, text=True)
    assert run.returncode == 0, run.stdout + run.stderr
    assert run.stdout.count("PASSED") == 2, run.stdout


def test_the_sdist_carries_what_the_readme_links_to(tagged: list[Path]) -> None:
    sdist = next(p for p in tagged if p.suffix == ".gz")
    with tarfile.open(sdist) as tar:
        names = {n.split("/", 1)[1] for n in tar.getnames() if "/" in n}
    linked = [t.split("#")[0] for t in re.findall(r"\]\(([^)\s]+)\)", (ROOT / "README.md").read_text(encoding="utf-8"))
              if "://" not in t and not t.startswith("#")]  # fmt: skip
    assert linked, "the README links to no file of the tree (relative while softtip has no home)"
    missing = [n for n in (*IN_SDIST, *linked) if n not in names]
    assert not missing, missing
    assert not any(n.startswith(("docs/_build/", "docs/auto_examples/", "docs/api/generated/")) for n in names)


def test_the_wheel_metadata(tagged: list[Path]) -> None:
    """Project URLs, classifiers, keywords, and a README whose links and images are absolute
    (a package index shows it away from the repository)."""
    wheel = next(p for p in tagged if p.suffix == ".whl")
    with zipfile.ZipFile(wheel) as zf:
        meta_name = next(n for n in zf.namelist() if n.endswith(".dist-info/METADATA"))
        text = zf.read(meta_name).decode()
        assert "softtip/_version.py" in zf.namelist()
    meta = HeaderParser().parsestr(text)
    assert meta["Version"] == "9.8.7"
    urls = meta.get_all("Project-URL") or []
    assert len(urls) >= 4 and all(u.split(", ", 1)[1].startswith(HOME) for u in urls), urls
    assert len(meta.get_all("Classifier") or []) >= 8
    assert "tactile sensing" in (meta["Keywords"] or "")
    body = meta.get_payload()
    targets = re.findall(r"\]\(([^)\s]+)\)", body)
    assert targets and all(t.startswith(HOME + "/") for t in targets), [t for t in targets if not t.startswith(HOME)]


def test_a_tree_without_git_builds_with_the_fallback_version(tmp_path: Path) -> None:
    tree = _copy_tree(tmp_path)  # a tarball of the sources, no .git: setuptools-scm's fallback
    built = _build(tree, "--wheel")
    assert [p.name for p in built] == ["softtip-0.2.0.dev0-py3-none-any.whl"]
