"""The documentation site builds with no warning, its gallery runs, and its API reference
covers every public name (``softtip.__all__`` and each public subpackage's ``__all__``).

Slow (a Sphinx build: tens of seconds, the gallery's examples a few seconds each, re-run
only when they change). Needs the ``docs`` extra: ``pip install -e '.[docs]'`` (``make
test`` installs it); skipped, saying so, without it.
"""

from __future__ import annotations

import importlib
import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
NEEDED = ("sphinx", "numpydoc", "sphinx_gallery", "myst_parser", "furo")
MISSING = [m for m in NEEDED if importlib.util.find_spec(m) is None]
pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(bool(MISSING), reason=f"the docs extra is not installed ({', '.join(MISSING)} missing): pip install -e '.[docs]'"),
]

#: The public modules, each with its page in docs/api/ (a package without ``__all__`` is
#: documented by the module that holds its public names)
MODULES = {
    "softtip": "softtip",
    "softtip.estimator": "estimator",
    "softtip.io.tables": "io",
    "softtip.calibration.probing": "calibration",
    "softtip.sim": "sim",
    "softtip.fusion": "fusion",
    "softtip.viz.rerun": "viz",
    "softtip.ros": "ros",
    "softtip.apps.chunked": "apps",
    "softtip.cli": "cli",
}


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("docs")
    run = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-b", "html", "-d", str(out / "doctrees"), str(DOCS), str(out / "html")],
        capture_output=True, text=True, timeout=900, cwd=ROOT,
    )  # fmt: skip
    assert run.returncode == 0, f"the docs build failed or warned:\n{run.stderr[-6000:]}"
    assert "WARNING" not in run.stderr and "ERROR" not in run.stderr, run.stderr[-6000:]
    return out / "html"


def test_every_public_module_has_an_api_page() -> None:
    pages = {p.stem for p in (DOCS / "api").glob("*.rst")} - {"index"}
    assert pages == set(MODULES.values())
    for package in (ROOT / "src" / "softtip").iterdir():  # a new public subpackage needs a page
        if (package / "__init__.py").is_file() and "__all__" in (package / "__init__.py").read_text(encoding="utf-8"):
            assert f"softtip.{package.name}" in MODULES, package.name


def test_the_api_reference_covers_every_public_name(site: Path) -> None:
    top = importlib.import_module("softtip")
    ids = set()
    for page in MODULES.values():
        ids |= set(re.findall(r'id="([^"]+)"', (site / "api" / f"{page}.html").read_text(encoding="utf-8")))
    missing = []
    for module in MODULES:
        for name in importlib.import_module(module).__all__:
            here = f"{module}.{name}" in ids
            at_top = name in top.__all__ and getattr(importlib.import_module(module), name) is getattr(top, name)
            if not (here or (at_top and f"softtip.{name}" in ids)):
                missing.append(f"{module}.{name}")
    assert not missing, missing


def _split(dotted: str) -> tuple[str, str]:
    """``softtip.io.bag.read_bag`` -> (``softtip.io.bag``, ``read_bag``): the longest importable module and the rest."""
    parts = dotted.split(".")
    for k in range(len(parts) - 1, 0, -1):
        try:
            importlib.import_module(".".join(parts[:k]))
        except ImportError:
            continue
        return ".".join(parts[:k]), ".".join(parts[k:])
    raise AssertionError(dotted)


def _taught_names() -> set[tuple[str, str]]:
    """(module, name) of every softtip name the README, the guide and the gallery show a reader
    importing (``from softtip.x import a, b``) or calling (``softtip.x.a(``)."""
    texts = [ROOT / "README.md", *DOCS.glob("*.md"), *DOCS.glob("guide/*.md"), *DOCS.glob("examples/*.py")]
    taught = set()
    for path in texts:
        text = path.read_text(encoding="utf-8")
        imports = re.findall(r"^\s*from (softtip(?:\.\w+)*) import (?:\(([^)]*)\)|([\w, ]+))", text, re.M)
        for module, wrapped, line in imports:
            taught |= {(module, n.strip()) for n in (wrapped or line).split(",") if n.strip()}
        for dotted in re.findall(r"\b(softtip(?:\.[A-Za-z_]\w*)+)\(", text):
            taught.add(_split(dotted))
    return taught


def test_the_api_reference_covers_every_name_the_docs_teach(site: Path) -> None:
    """A name the README, the guide or a gallery example imports or calls has its entry in the
    API reference (under its module, or under ``softtip`` when that re-exports it)."""
    ids = set()
    for page in (site / "api").glob("*.html"):
        ids |= set(re.findall(r'id="([^"]+)"', page.read_text(encoding="utf-8")))
    top = importlib.import_module("softtip")
    taught = _taught_names()
    assert ("softtip.io.bag", "read_bag") in taught and ("softtip", "run") in taught, sorted(taught)
    missing = []
    for module, name in sorted(taught):
        head = name.split(".")[0]
        if not isinstance(getattr(importlib.import_module(module), head), type):
            name = head  # a method of a constant (``STATES.index``): the constant's entry
        if f"{module}.{name}" not in ids and not (getattr(top, head, None) is getattr(importlib.import_module(module), head)
                                                 and f"softtip.{name}" in ids):  # fmt: skip
            missing.append(f"{module}.{name}")
    assert not missing, missing


def test_the_gallery_ran(site: Path) -> None:
    examples = sorted(p.stem for p in (DOCS / "examples").glob("plot_*.py"))
    assert len(examples) >= 5
    for name in examples:
        page = (site / "auto_examples" / f"{name}.html").read_text(encoding="utf-8")
        assert re.search(r'<img [^>]*src="../_images/sphx_glr_' + name, page), f"{name}: no figure"


def test_the_site_has_its_pages(site: Path) -> None:
    for page in ("index", "getting-started", "guide/index", "guide/03-the-measurement", "guide/ros2-package",
                 "reproduction", "benchmarks/performance", "benchmarks/accuracy", "changelog", "contributing"):  # fmt: skip
        assert (site / f"{page}.html").is_file(), page
    assert "sphx_glr_plot" not in (site / "reproduction.html").read_text(encoding="utf-8")
    for figure in (DOCS / "reproduction").glob("*.png"):  # the reproduction page shows every figure
        assert (site / "_images" / figure.name).is_file(), figure.name
