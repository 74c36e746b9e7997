"""Sphinx configuration: API reference from the numpydoc docstrings of the public namespace."""

import os
import sys

sys.path.insert(0, os.path.abspath(".."))

from machsurf_cad import __version__

project = "machsurf_cad"
author = "machsurf_cad contributors"
copyright = "2026, machsurf_cad contributors"
release = version = __version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
    "myst_parser",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
myst_heading_anchors = 3
autosummary_generate = True
autodoc_default_options = {"members": False}
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
templates_path = []
exclude_patterns = ["_build", "generated/*.rst.bak"]
html_theme = "alabaster"
html_static_path = []
suppress_warnings = ["autosummary.import_cycle"]
