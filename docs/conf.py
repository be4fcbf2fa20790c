"""Sphinx configuration of sphcore's documentation.

Build it with ``python -m sphinx -W -b html docs docs/_build/html`` (the ``docs`` extra
installs Sphinx and MyST). The reference pages are written from the code at every build
by ``docs/_ext/reference.py``: the case keys from the same declarations as ``sph options``,
the command line from the same parser as ``sph --help``, the hooks from their specification.
"""

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))

project = "sphcore"
author = "the sphcore developers"
copyright = "the sphcore developers, MIT licence"

extensions = ["myst_parser", "sphinx.ext.autodoc", "sphinx.ext.mathjax", "reference"]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3
exclude_patterns = ["_build", "validation/tables", "**/README.md"]
html_theme = "alabaster"
html_static_path = ["_static"]
html_theme_options = {"description": "SPH with physical reflective walls", "fixed_sidebar": True}
autodoc_member_order = "bysource"
autodoc_typehints = "none"
nitpicky = False
