"""Sphinx configuration of symid's documentation: the user guide, the gallery and the API from the docstrings.

Build: ``.venv/bin/pip install ".[docs]" && .venv/bin/sphinx-build -W -b html docs docs/_build/html``
(CI runs it, warnings are errors). The options table is generated from the estimators at build time.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

project = "symid"
author = "symid developers"
copyright = "symid developers"
extensions = ["sphinx.ext.autodoc", "sphinx.ext.napoleon", "sphinx.ext.mathjax"]
napoleon_numpy_docstring = True
napoleon_google_docstring = False
napoleon_use_rtype = False
autodoc_member_order = "bysource"
autodoc_typehints = "none"
exclude_patterns = ["_build", "_generated/README.md"]
html_theme = "alabaster"
suppress_warnings = ["ref.python"]  # several numpydoc cross-references name a class by its short name


def _options_page(app) -> None:
    """docs/_generated/options.rst: every method's options, read from the estimators (symid.fit.catalog)."""
    from symid.fit.catalog import options_table

    rows = [line.strip("|").split(" | ") for line in options_table().splitlines()[2:]]
    out = [".. list-table::", "   :header-rows: 1", "   :widths: 14 14 14 12 46", "",
           "   * - data", "     - method", "     - option", "     - default", "     - meaning"]
    bars = re.compile(r"(?<![\\`|])\|([^|\s`][^|`]*?)\|(?![`|_])")  # |H| in plain text is not a substitution
    for row in rows:
        cells = [bars.sub(lambda m: "\\|" + m.group(1) + "\\|", c.strip().replace("\\|", "|")) for c in row]
        out.append(f"   * - {cells[0]}")
        out.extend(f"     - {c.replace('`', '``') if c.count('`') % 2 == 0 else c}" for c in cells[1:])
    target = Path(app.srcdir) / "_generated"
    target.mkdir(exist_ok=True)
    text = "\n".join(out) + "\n"
    path = target / "options.rst"
    if not path.exists() or path.read_text(encoding="utf-8") != text:
        path.write_text(text, encoding="utf-8")


_BARS = None


def _plain_bars(app, what, name, obj, options, lines) -> None:
    """Docstrings write magnitudes as |H| in plain text; reST would read |H| as a substitution."""
    global _BARS
    _BARS = _BARS or re.compile(r"(?<![\\`|])\|([^|\s`][^|`]*?)\|(?![`|_])")
    for k, line in enumerate(lines):
        lines[k] = _BARS.sub(lambda m: "\\|" + m.group(1) + "\\|", line)


def setup(app):
    app.connect("builder-inited", _options_page)
    app.connect("autodoc-process-docstring", _plain_bars)
