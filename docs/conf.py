"""Sphinx configuration of rockbench's documentation.

Build (warnings are errors, as in CI)::

    .venv/bin/pip install -e '.[all,docs]'
    .venv/bin/python -m sphinx -W --keep-going -b html docs docs/_build/html
    python3 -m http.server -d docs/_build/html 8000     # then open http://localhost:8000

Markdown pages are read by MyST, docstrings by numpydoc, the examples in
``docs/examples`` are run by sphinx-gallery, and ``docs/_ext/rockbench_docs.py``
generates the tables that come from the code (engine knobs and presets, command
help, the validation table from a results store made during the build).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE / "_ext"))
sys.path.insert(0, str(ROOT))

import rockbench  # noqa: E402

project = "rockbench"
author = "rockbench developers"
copyright = "rockbench developers"  # noqa: A001
release = rockbench.__version__
version = release

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
    "rockbench_docs",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "examples",
                    "**/sg_execution_times.rst"]
templates_path = ["_templates"]

# --- MyST (Markdown pages) ---
myst_enable_extensions = ["colon_fence", "deflist", "dollarmath", "fieldlist"]
myst_heading_anchors = 3

# --- autodoc / autosummary / numpydoc (the API reference) ---
autosummary_generate = True
autosummary_imported_members = False
autodoc_default_options = {"members": True, "ignore-module-all": True}
autodoc_member_order = "bysource"
autodoc_typehints = "none"
autodoc_class_signature = "separated"
autodoc_inherit_docstrings = False
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
numpydoc_validation_checks: set[str] = set()
#: Modules left out of the API reference: the command line (documented on the
#: commands page).
autosummary_context = {"skip": ["rockbench.cli"]}

# --- sphinx-gallery (executed examples) ---
sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "show_memory": False,
    "abort_on_example_error": True,
    "write_computation_times": False,
    "reset_modules": ("matplotlib",),
}
os.environ.setdefault("MPLBACKEND", "Agg")

# --- HTML ---
html_theme = "furo"
html_title = f"rockbench {release}"
html_static_path = ["_static"]
html_css_files = ["rockbench.css"]
html_theme_options = {
    "source_repository": "",
    "navigation_with_keys": True,
}
html_show_sourcelink = False
