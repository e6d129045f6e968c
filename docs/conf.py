"""Sphinx configuration of skatetrace's documentation.

Build: ``python -m sphinx -W --keep-going -b html docs docs/_build/html`` (warnings are errors).
The tutorials in ``gallery/`` run at every build (sphinx-gallery) and their output goes to
``tutorials/``; the API reference's stubs go to ``generated/``; the architecture picture is drawn
from the code by ``_ext/architecture.py`` into ``_generated/``. All three are git-ignored.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))
sys.path.insert(0, str(HERE.parent / "src"))  # document this checkout, installed or not
os.environ.setdefault("MPLBACKEND", "Agg")

import skatetrace  # noqa: E402

project = "skatetrace"
author = "the skatetrace authors"
copyright = "the skatetrace authors, MIT licence"
release = version = skatetrace.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
    "myst_parser",
    "sphinxarg.ext",
    "sphinx_gallery.gen_gallery",
    "architecture",
    "public_api",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "_generated", "gallery/GALLERY_HEADER.rst", "Thumbs.db", ".DS_Store",
                    "tutorials/*.ipynb", "tutorials/*.py", "tutorials/*.zip"]
templates_path = ["_templates"]

# Markdown pages: $...$ and $$...$$ maths (MathJax), ::: fences, and anchors on headings.
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

# API reference: one page per module (autosummary, recursive), docstrings in numpy style.
autosummary_generate = True
autosummary_imported_members = False
autosummary_ignore_module_all = False
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_typehints = "none"  # numpydoc's Parameters sections say the types
autodoc_member_order = "bysource"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
numpydoc_validation_checks: set[str] = set()

# Tutorials, executed at every build; a tutorial that raises fails the build.
sphinx_gallery_conf = {
    "examples_dirs": ["gallery"],
    "gallery_dirs": ["tutorials"],
    "filename_pattern": r"\.py$",  # run every script
    "within_subsection_order": "FileNameSortKey",
    "abort_on_example_error": True,
    "download_all_examples": False,
    "remove_config_comments": True,
    "min_reported_time": 0,
    "show_memory": False,
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "reset_modules": ("matplotlib",),
    "capture_repr": ("_repr_html_", "__repr__"),
    "show_signature": False,
}

html_theme = "pydata_sphinx_theme"
html_title = f"skatetrace {release}"
html_static_path: list[str] = []
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": [],
}
html_sidebars = {"**": ["sidebar-nav-bs"]}
html_show_sourcelink = False

# Only the warnings the build treats as errors are worth hearing; keep the log readable.
suppress_warnings: list[str] = []
