"""Sphinx configuration of the API reference (``make docs``).

Only ``index.rst`` is a Sphinx source; the Markdown pages beside it are read
on GitHub and linked from the reference.  Importing the package loads no
compiled kernel, so the build needs no compiler cache.
"""

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import proximity  # noqa: E402

project = "proximity"
release = version = proximity.__version__
copyright = "the proximity authors"

extensions = ["sphinx.ext.autodoc", "numpydoc"]
source_suffix = {".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build"]

autodoc_member_order = "bysource"
autodoc_typehints = "none"
# Dataclass fields and protocol attributes are documented in the
# "Attributes" sections of their classes; listing them again as members
# would describe each twice.
numpydoc_show_class_members = False
numpydoc_xref_param_type = False

html_theme = "alabaster"
html_title = f"proximity {release}: API reference"
