"""Sphinx configuration of galvoscan's documentation: Markdown pages read by MyST.

The test suite builds these docs with warnings as errors and nitpicky references
(tests/test_docs.py), so a broken internal link or anchor fails the suite.
"""

project = "galvoscan"
author = "the galvoscan contributors"
copyright = "the galvoscan contributors, BSD-2-Clause"

extensions = ["myst_parser"]
source_suffix = {".md": "markdown"}
root_doc = "index"
# What is not a page: the build's output, and the figures' data files beside the pages.
exclude_patterns = ["_build"]

# Markdown headings get anchors (h1 to h3), so that `page.md#a-heading` links resolve and a
# link to an anchor that does not exist is a warning.
myst_heading_anchors = 3
# Pages link to one another with plain Markdown links; with nitpicky, a link that Sphinx
# cannot resolve is a warning, and -W makes it an error.
nitpicky = True
myst_enable_extensions = ["colon_fence"]

# The default theme: nothing to install beyond Sphinx.
html_theme = "alabaster"
html_static_path = []
# The link check (`-b linkcheck`) is not run by the suite: it needs the network. External
# links are checked for form by tests/test_docs.py instead.
