"""Sphinx configuration of the documentation: the API reference (autodoc + numpydoc, from the
docstrings of ``masonry_dem.__all__``) and the guides of docs/*.md (myst-parser).

Build (what CI runs, .ci/run): ``sphinx-build -W --keep-going -b html -c docs/api docs
build/docs`` from the repository root, with the ``docs`` extra installed. The source folder is
docs/ (the guides stay where the README links them); this folder holds the configuration and
the API page.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pygments.lexers.special import TextLexer
from sphinx.addnodes import pending_xref
from sphinx.transforms.post_transforms import SphinxPostTransform

import masonry_dem

project = "masonry_dem"
author = "masonry_dem contributors"
release = version = masonry_dem.__version__

extensions = ["sphinx.ext.autodoc", "numpydoc", "myst_parser"]

root_doc = "api/index"
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["images/**"]
# the guides are written for GitHub, where some headings skip a level
suppress_warnings = ["myst.header"]

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


def setup(app: Any) -> None:
    # a mermaid diagram of a guide (GitHub draws it; Pygments has no lexer): shown as text
    app.add_lexer("mermaid", TextLexer)
    app.add_post_transform(RepositoryLinks)


class RepositoryLinks(SphinxPostTransform):
    """A guide's link to a Markdown file of the repository outside docs/ (e.g.
    benchmarks/README.md) is right where the guides are read, on the repository's pages; the
    HTML build has no page for it and shows the link's text. A link to a file that does not
    exist is still a warning (myst's, after this transform)."""

    default_priority = 8  # before myst's resolver (9)

    def run(self, **kwargs: Any) -> None:
        docs = Path(self.env.srcdir).resolve()
        for node in list(self.document.findall(pending_xref)):
            if node.get("reftype") != "myst" or node.get("refdomain") != "doc":
                continue
            target = Path(str(node["reftarget"]))
            if not target.is_absolute() or target.resolve().is_relative_to(docs):
                continue
            if target.with_suffix(".md").is_file() and docs.parent in target.parents:
                node.replace_self(node[0].deepcopy())
