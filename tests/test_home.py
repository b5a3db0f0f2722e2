"""softtip's public home (its repository's address) is declared in one place, ``[project.urls]``
of ``pyproject.toml``, and every other file agrees with it.

softtip has no public home yet, so none is declared and no file may name one (no invented
address): the README's links are relative and resolve to files of the tree. Before the first
upload ``scripts/set_home.py`` writes the home into every file that names it (docs/contributing.md,
"Releases"); the last test runs it on a copy and holds the copy to the same rules.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: The files that may name the home (set_home.py writes those it names), and the pages whose links a reader follows
FILES = ("pyproject.toml", "README.md", "CITATION.cff", "ros/package.xml", "ros/setup.py", "docs/**/*.md")
#: Addresses on a code host: a repository's home or a file in one
CODE_HOST = re.compile(
    r"https?://(?:www\.)?(?:github\.com|gitlab\.com|raw\.githubusercontent\.com|codeberg\.org|bitbucket\.org)/[^\s)\"'<>`]*"
)
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")


def _home(root: Path) -> str | None:
    urls = tomllib.loads((root / "pyproject.toml").read_text(encoding="utf-8"))["project"].get("urls")
    return None if urls is None else urls["Repository"].rstrip("/")


def _raw(home: str) -> str:
    m = re.fullmatch(r"https://github\.com/([^/]+)/([^/]+)", home)
    return f"https://raw.githubusercontent.com/{m[1]}/{m[2]}/" if m else home + "/"


def _check(root: Path) -> None:
    home = _home(root)
    named = []
    for pattern in FILES:
        for path in sorted(root.glob(pattern)):
            if "_build" in path.parts or "auto_examples" in path.parts:
                continue
            for url in CODE_HOST.findall(path.read_text(encoding="utf-8")):
                if "/OWNER/REPO" not in url:  # the release checklist's placeholder
                    named.append((path.relative_to(root).as_posix(), url))
    if home is None:
        assert not named, f"no home is declared in pyproject.toml's [project.urls], yet these name one: {named}"
    else:
        stray = [(f, u) for f, u in named if not (u.rstrip("/") == home or u.startswith((home + "/", _raw(home))))]
        assert not stray, f"addresses outside the declared home {home}: {stray}"
        cff = (root / "CITATION.cff").read_text(encoding="utf-8")
        assert f'repository-code: "{home}"' in cff
        urls = {u.get("type"): u.text for u in ET.parse(root / "ros" / "package.xml").getroot().iter("url")}
        assert urls.get("repository") == home and urls.get("website") == home
    readme = (root / "README.md").read_text(encoding="utf-8")
    targets = [t for t in LINK.findall(readme) if not t.startswith("#")]
    assert targets
    for target in targets:
        if home is None:  # relative, to a file of the tree
            assert "://" not in target, f"README: {target}: an absolute link with no home declared"
            assert (root / target.split("#")[0]).exists(), f"README: {target}: no such file"
        elif target.startswith((home + "/", _raw(home))):  # absolute, to a file of the tree at some ref
            path = re.sub(r"^(?:.*?/(?:blob|raw)/[^/]+/|" + re.escape(_raw(home)) + r"[^/]+/)", "", target)
            assert (ROOT / path.split("#")[0]).exists(), f"README: {target}: no {path} in the tree"
        else:
            assert target.startswith("https://"), f"README: {target}: relative, but a package index shows the README"


def test_the_home_is_declared_once_and_every_file_agrees() -> None:
    _check(ROOT)


def test_the_check_fails_on_a_stray_address(tmp_path: Path) -> None:
    """Not vacuous: a code-host address in a file, with no home declared, fails it."""
    for name in ("pyproject.toml", "README.md", "CITATION.cff", "ros/package.xml", "ros/setup.py"):
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(ROOT / name, tmp_path / name)
    for target in set(LINK.findall((ROOT / "README.md").read_text(encoding="utf-8"))):
        if (ROOT / target).is_file():
            (tmp_path / target).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy(ROOT / target, tmp_path / target)
    if _home(ROOT) is None:
        _check(tmp_path)
        with (tmp_path / "CITATION.cff").open("a", encoding="utf-8") as f:
            f.write("# see https://github.com/someone/softtip\n")
        with pytest.raises(AssertionError, match="no home is declared"):
            _check(tmp_path)


def test_set_home_writes_the_home_everywhere(tmp_path: Path) -> None:
    """The release step (scripts/set_home.py) on a copy: every file then names the home, the
    README's links are absolute and point at files of the tree; a second run changes nothing."""
    for name in ("pyproject.toml", "README.md", "CITATION.cff", "ros/package.xml", "ros/setup.py"):
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(ROOT / name, tmp_path / name)
    home = "https://github.com/example-owner/softtip"
    argv = [
        sys.executable,
        str(ROOT / "scripts" / "set_home.py"),
        home,
        "--email",
        "someone@example.org",
        "--root",
        str(tmp_path),
    ]
    subprocess.run(argv, check=True, capture_output=True)
    _check(tmp_path)
    readme = (tmp_path / "README.md").read_text(encoding="utf-8")
    assert re.search(r"!\[[^\]]*\]\(https://raw\.githubusercontent\.com/example-owner/softtip/main/docs/", readme)
    assert 'email="someone@example.org"' in (tmp_path / "ros" / "package.xml").read_text(encoding="utf-8")
    urls = tomllib.loads((tmp_path / "pyproject.toml").read_text(encoding="utf-8"))["project"]["urls"]
    assert set(urls) == {"Homepage", "Documentation", "Repository", "Issues", "Changelog"}
    before = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    subprocess.run(argv, check=True, capture_output=True)
    assert {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()} == before


def test_citation_cff_follows_the_format() -> None:
    """CITATION.cff parses and has what the Citation File Format 1.2.0 requires (validated in full
    by ``cffconvert --validate`` where installed; it is not a dependency); the papers' references
    carry their pages and ISBNs as printed on them."""
    yaml = pytest.importorskip("yaml", reason="PyYAML not installed (the docs extra brings it)")
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))
    assert cff["cff-version"] == "1.2.0" and cff["type"] == "software"
    assert {"authors", "message", "title"} <= set(cff) and cff["authors"]
    for ref in cff["references"]:
        assert {"type", "title", "authors"} <= set(ref) and ref["type"] == "conference-paper"
        assert re.fullmatch(r"[0-9\- ]{10,17}X?", ref["isbn"]) and isinstance(ref["start"], int)
    cffconvert = shutil.which("cffconvert")
    if cffconvert is not None:
        run = subprocess.run(
            [cffconvert, "--validate", "-i", str(ROOT / "CITATION.cff")], capture_output=True, text=True
        )
        assert run.returncode == 0, run.stdout + run.stderr
