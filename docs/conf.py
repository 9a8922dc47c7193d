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


def setup(app: object) -> None:
    """Compile numpydoc's docstring template once per builder instead of once per docstring.

    numpydoc 1.x's ``get_doc_object`` makes a new Jinja environment and compiles
    ``numpydoc_docstring.rst`` on every call: about 600 compilations for this reference, a
    fifth of the build's CPU time. The same template is kept here and handed to numpydoc's
    own docstring classes; the pages are byte for byte the same. Where numpydoc has moved
    the names used, numpydoc is left as it is (a slower build, not a different one).
    """
    import os

    from numpydoc import docscrape_sphinx as ds
    from numpydoc import numpydoc as ext

    needed = ("get_doc_object_orig", "SphinxClassDoc", "SphinxFunctionDoc", "SphinxObjDoc",
              "BuiltinTemplateLoader", "FileSystemLoader", "SandboxedEnvironment")  # fmt: skip
    if not all(hasattr(ds, name) for name in needed) or not hasattr(ext, "get_doc_object"):
        return
    template_dirs = [os.path.join(os.path.dirname(ds.__file__), "templates")]
    templates: dict[int, object] = {}

    def get_doc_object(  # the signature of numpydoc.docscrape_sphinx.get_doc_object
        obj: object,
        what: str | None = None,
        doc: str | None = None,
        config: dict | None = None,
        builder: object = None,
    ) -> object:
        config = {} if config is None else config
        key = id(builder)
        if key not in templates:
            if builder is not None:
                loader = ds.BuiltinTemplateLoader()
                loader.init(builder, dirs=template_dirs)
            else:
                loader = ds.FileSystemLoader(template_dirs)
            env = ds.SandboxedEnvironment(loader=loader)
            templates[key] = env.get_template("numpydoc_docstring.rst")
        config["template"] = templates[key]
        return ds.get_doc_object_orig(
            obj,
            what=what,
            doc=doc,
            config=config,
            class_doc=ds.SphinxClassDoc,
            func_doc=ds.SphinxFunctionDoc,
            obj_doc=ds.SphinxObjDoc,
        )

    ext.get_doc_object = get_doc_object
