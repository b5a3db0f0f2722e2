"""Sphinx configuration of softtip's documentation (``make docs`` builds it with ``-W``)."""

from __future__ import annotations

import os
import sys
from importlib.metadata import PackageNotFoundError
from importlib.metadata import version as _version
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))  # the sources beside this file, not an older install
os.environ.setdefault("MPLBACKEND", "Agg")

import softtip  # noqa: E402

project = "softtip"
author = "softtip developers"
copyright = "softtip developers"  # noqa: A001
try:
    release = _version("softtip")
except PackageNotFoundError:  # pragma: no cover - docs built from a tree that was never installed
    release = softtip.__version__
version = release

extensions = [
    "myst_parser",  # the guide, the README's old sections and the changelog are Markdown
    "sphinx.ext.autodoc",
    "sphinx.ext.intersphinx",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",  # the docstrings are numpydoc
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = [
    "_build",
    "manual.md",  # a pointer to guide/ kept for old links
    "benchmarks/physics-*.md",  # written by benchmarks/bench_physics.py and bench_fusion.py --markdown, included by two-physics.md
    "benchmarks/performance-*.md",  # written by benchmarks/bench_core.py --markdown, included by performance.md
    "benchmarks/accuracy-*run.md",  # written by benchmarks/bench_accuracy.py --markdown, included by accuracy.md
    "benchmarks/calibration-*run.md",  # written by benchmarks/bench_calibration.py --markdown, included by accuracy.md
    "guide/columns.md",  # written by scripts/make_column_table.py, included by 04-data-and-command-line.md
    "guide/fused-columns.md",  # written by scripts/make_column_table.py, included by 08-two-fingertips-….md
    "examples/README.txt",
    "auto_examples/*.ipynb",
    "auto_examples/*.py",
    "auto_examples/*.zip",
    "auto_examples/*.md5",
    "auto_examples/*.pickle",
    "auto_examples/*.json",
]

myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 3

# the API reference: each public module's __all__, in source order
autodoc_default_options = {"members": True, "undoc-members": True, "member-order": "bysource", "show-inheritance": False}
autodoc_typehints = "none"  # the numpydoc sections carry the types
autodoc_mock_imports = ["rclpy", "rerun"]
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
numpydoc_validation_checks: set[str] = set()


def _write_data_pages() -> None:
    """``docs/api/generated/<page>.rst``: an ``autodata`` for each constant of a module's
    ``__all__`` that autodoc's ``automodule`` leaves out (constants imported from the submodule
    that defines them), with the ``#:`` comment of the module that defines it."""
    import importlib
    import inspect
    import pkgutil

    from sphinx.pycode import ModuleAnalyzer

    def attr_docs(name: str) -> dict:
        try:
            return {k[1]: v for k, v in ModuleAnalyzer.for_module(name).find_attr_docs().items() if k[0] == ""}
        except Exception:  # noqa: BLE001 - a module without source
            return {}

    every = [m.name for m in pkgutil.walk_packages(softtip.__path__, "softtip.") if ".ros.node" not in m.name]
    defined = {}
    for name in every:
        try:
            mod = importlib.import_module(name)
        except ImportError:  # an optional dependency's module
            continue
        for attr, doc in attr_docs(name).items():
            defined.setdefault(id(getattr(mod, attr, None)), doc)
    out = Path(__file__).parent / "api" / "generated"
    out.mkdir(exist_ok=True)
    for page, module in API_PAGES.items():
        mod = importlib.import_module(module)
        own = attr_docs(module)
        lines = []
        for attr in mod.__all__:
            obj = getattr(mod, attr)
            if inspect.isclass(obj) or inspect.isroutine(obj) or inspect.ismodule(obj) or attr in own:
                continue
            lines.append(f".. autodata:: {module}.{attr}")
            lines.append("   :no-value:" if isinstance(obj, str) and len(obj) > 80 else "")
            doc = defined.get(id(obj))
            if doc:
                lines += ["", *("   " + line for line in doc)]
            lines.append("")
        head = ["Constants and other objects", "---------------------------", ""] if lines else []
        (out / f"{page}.rst").write_text("\n".join(head + lines) + "\n", encoding="utf-8")


#: API page -> public module (docs/api/<page>.rst)
API_PAGES = {
    "softtip": "softtip",
    "estimator": "softtip.estimator",
    "io": "softtip.io.tables",
    "calibration": "softtip.calibration.probing",
    "sim": "softtip.sim",
    "fusion": "softtip.fusion",
    "viz": "softtip.viz.rerun",
    "ros": "softtip.ros",
    "apps": "softtip.apps.chunked",
    "cli": "softtip.cli",
}
_write_data_pages()
exclude_patterns.append("api/generated/*")

intersphinx_mapping = {}  # offline build: no inventories fetched
nitpicky = False

sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "matplotlib_animations": False,
    "show_memory": False,
    "min_reported_time": 1,
    "write_computation_times": False,
}

html_theme = "furo"
html_title = f"softtip {release}"
html_static_path: list[str] = []
html_last_updated_fmt = None
html_show_sourcelink = False
suppress_warnings = ["myst.header"]


def _collapsed_navigation(app, pagename, templatename, context, doctree) -> None:
    """Furo draws the whole site's navigation into every page (``collapse=False``): Sphinx
    copies every document's table of contents for each page, which took 12 of the build's 27 s
    of CPU. Collapsed, each page's sidebar holds the top-level pages and the branch it is on
    (the table of contents on the right is unchanged); the build takes 15 s."""
    toctree = context.get("toctree")
    if toctree is None:
        return

    def collapsed(**kwargs):
        return toctree(**{**kwargs, "collapse": True})

    context["toctree"] = collapsed


def setup(app):
    # before furo's handler (priority 500), which calls context["toctree"]
    app.connect("html-page-context", _collapsed_navigation, priority=100)
