"""Sphinx configuration of g2tom's documentation (``make docs``)."""

from __future__ import annotations

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))

import g2tom  # noqa: E402

project = "g2tom"
author = "the g2tom developers"
copyright = "the g2tom developers"
release = g2tom.__version__
version = ".".join(release.split(".")[:2])

extensions = [
    "myst_parser",
    "numpydoc",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "g2tom_docs",  # docs/_ext: the parameter, variable and CLI references, generated at build time
    "g2tom_examples",  # docs/_ext: docs/examples/*.py run at build time, their pages in _generated/examples
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "_generated/*.md", "_ext", "Thumbs.db", ".DS_Store"]
templates_path: list[str] = []

# MyST: $...$ and $$...$$ maths, ::: fences, anchors on headings for cross-page links.
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

# API reference: stubs under api/generated (not committed), written at each build.
autosummary_generate = True
autosummary_imported_members = False
autodoc_default_options = {"members": True, "show-inheritance": False}
autodoc_typehints = "none"
autodoc_member_order = "bysource"
autoclass_content = "class"

# numpydoc: the docstrings are numpydoc; members are listed by autosummary, not repeated per class.
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_validation_checks: set[str] = set()
numpydoc_xref_param_type = False

nitpicky = False
suppress_warnings = [
    "myst.header",          # generated help text starts at level 2 headings inside a page
    "autosummary.import_cycle",
    "docutils",             # docstring prose written for the terminal (e.g. a * for rho*) parsed as rST
    "ref.python",           # one name defined in two modules (a re-export) is ambiguous to Sphinx
    "autodoc",              # numba-compiled functions and dataclass fields without source
]

html_theme = "pydata_sphinx_theme"
html_title = f"g2tom {release}"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "navbar_align": "left",
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
    "secondary_sidebar_items": ["page-toc"],
}
html_show_sourcelink = False
html_static_path: list[str] = []
