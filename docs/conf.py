"""Sphinx configuration of the documentation site (``make docs``).

The pages are the Markdown files of ``docs/`` (read through MyST, and on
GitHub as they are) and the API reference under ``docs/api/``, from the
docstrings.  Importing the package loads no compiled kernel, so the build
needs no compiler cache.
"""

import importlib
import os
import re
import sys
from pathlib import Path

from docutils import nodes
from sphinx.util.docutils import SphinxDirective

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import proximity  # noqa: E402

project = "proximity"
release = version = proximity.__version__
copyright = "the proximity authors"

extensions = ["sphinx.ext.autodoc", "numpydoc", "myst_parser"]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build"]

# Anchors for the Markdown pages' section links (``accuracy.md#the-unit-eps-s``).
myst_heading_anchors = 3

autodoc_member_order = "bysource"
autodoc_typehints = "none"
# Dataclass fields and protocol attributes are documented in the
# "Attributes" sections of their classes; listing them again as members
# would describe each twice.
numpydoc_show_class_members = False
numpydoc_xref_param_type = False

html_theme = "alabaster"
html_title = f"proximity {release}"
html_theme_options = {
    "description": "Exact, robust and fast closest-point queries in 3D",
    "fixed_sidebar": True,
    "sidebar_collapse": True,
}
html_sidebars = {"**": ["about.html", "navigation.html", "searchbox.html"]}


def _keyword_only(app, what, name, obj, options, signature, return_annotation):
    """Signatures without the ``*args`` that the queries take only to say that
    ``method`` is keyword-only: ``(points, *, method='robust')``; and none for
    a protocol class, which is not called."""
    if signature == "(*args, **kwargs)":
        return "", return_annotation
    if signature and "*args" in signature:
        signature = re.sub(r"\*args, (?!\*\*)", "*, ", signature).replace(", *args)", ")")
    return signature, return_annotation


class CommandHelp(SphinxDirective):
    """``.. command-help:: proximity.cloud``: the ``--help`` text of a
    command, from the ``parser()`` of its module."""

    required_arguments = 1

    def run(self):
        module = importlib.import_module(self.arguments[0])
        text = module.parser().format_help()
        block = nodes.literal_block(text, text)
        block["language"] = "text"
        return [block]


def setup(app):
    # argparse wraps the help text to the terminal's width: one width for every build.
    os.environ["COLUMNS"] = "100"
    app.connect("autodoc-process-signature", _keyword_only)
    app.add_directive("command-help", CommandHelp)
