"""Sphinx configuration of exactff's documentation site.

Build: ``pip install -e ".[docs]"`` then ``python -m sphinx -W -b html docs docs/_build/html``.
The Markdown pages are read by MyST; the notebooks (``docs/notebooks`` is a link to the
repository's ``notebooks/``) are executed by myst-nb at build time; the reference is
generated from the numpydoc docstrings.
"""

import exactff

project = "exactff"
author = "exactff developers"
copyright = "2026, exactff developers"
release = version = exactff.__version__

extensions = [
    "myst_nb",                      # Markdown pages and notebooks (includes myst_parser)
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
]

exclude_patterns = ["_build", "**/.ipynb_checkpoints", "results/*/reference.npz"]
source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}

# the reference: one page per public name, from its docstring
autosummary_generate = True
autodoc_default_options = {"members": False}
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

# MyST: $...$ maths, GitHub-style heading anchors for the pages' internal links
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence"]
myst_heading_anchors = 3

# notebooks run at build time; any error in a cell fails the build; two minutes per cell
nb_execution_mode = "auto"
nb_execution_timeout = 120
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_merge_streams = True

html_theme = "pydata_sphinx_theme"
html_title = f"exactff {release}"
html_theme_options = {
    "show_toc_level": 2,
    "navigation_with_keys": False,
    "secondary_sidebar_items": ["page-toc"],
}
html_static_path = []
