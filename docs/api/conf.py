"""Sphinx configuration of the documentation: the API reference (autodoc + numpydoc, from the
docstrings of ``masonry_dem.__all__``) and the guides of docs/*.md (myst-parser).

Build (what CI runs, .ci/run): ``sphinx-build -W --keep-going -b html -c docs/api docs
build/docs`` from the repository root, with the ``docs`` extra installed. The source folder is
docs/ (the guides stay where the README links them); this folder holds the configuration and
the API page.
"""

from __future__ import annotations

import masonry_dem

project = "masonry_dem"
author = "masonry_dem contributors"
release = version = masonry_dem.__version__

extensions = ["sphinx.ext.autodoc", "numpydoc", "myst_parser"]

root_doc = "api/index"
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["images/**"]
# the guides are written for GitHub: a mermaid diagram (no Pygments lexer: shown as text) and
# headings that skip a level
suppress_warnings = ["misc.highlighting_failure", "myst.header"]

# autodoc: members in source order; the signatures' annotations in the description, not in
# the one-line signature (the Parameters sections give the types a reader needs)
autodoc_member_order = "bysource"
autodoc_typehints = "none"
autodoc_default_options = {"members": True, "undoc-members": False}

# numpydoc: the sections render; class members are listed by autodoc, not by numpydoc's own
# autosummary tables (which would need pages of their own)
numpydoc_show_class_members = False
numpydoc_xref_param_type = False

# the guides are GitHub Markdown: headings get anchors so links to them resolve
myst_heading_anchors = 3
myst_enable_extensions = ["dollarmath"]

html_theme = "alabaster"
html_title = f"masonry_dem {release}"
