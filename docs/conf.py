"""Sphinx configuration of the motioncue documentation.

Built by ``tests/test_docs.py`` with warnings as errors (``sphinx-build -W``), so the test
command (``make test``) fails on a broken page, a bad cross-reference in the text or a
docstring Sphinx cannot read. Pages are Markdown (MyST); the API reference comes from the
numpydoc docstrings (autodoc + numpydoc).
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

project = "motioncue"
author = "the motioncue authors"
copyright = "2026, the motioncue authors"

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "numpydoc",
]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
master_doc = "index"
exclude_patterns = ["_build"]
myst_heading_anchors = 3

# API reference: what each subpackage's __all__ lists, in source order, no private members
autodoc_default_options = {"members": True, "member-order": "bysource"}
autodoc_typehints = "none"  # the numpydoc sections carry types, shapes and units
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_validation_checks: set[str] = set()

html_theme = "alabaster"
html_title = "motioncue"
html_static_path = ["_static"]
html_css_files = ["motioncue.css"]  # field names unbroken, long lines scroll
