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
autodoc_default_options = {"members": True, "member-order": "bysource", "show-inheritance": False}
autodoc_typehints = "none"  # the numpydoc sections carry the types
autodoc_mock_imports = ["rclpy", "rerun"]
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
numpydoc_validation_checks: set[str] = set()

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
