"""Sphinx configuration of the documentation site (MyST Markdown, furo theme).

Build (offline, warnings are errors): ``bash scripts/docs.sh`` or
``python -m sphinx -W --keep-going -b html docs docs/_build/html``.
"""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path

from pygments.lexers.special import TextLexer
from sphinx.application import Sphinx
from sphinx.highlighting import lexers

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))
from envs.cell.rendering import use_headless_rendering  # noqa: E402 - the root on sys.path first

use_headless_rendering()
os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from bench_page import (  # noqa: E402 - docs/ on sys.path
    write_bench_table,
    write_glance_table,
    write_ratio_table,
)

project = "Mosaic assembly cell"
author = "The mosaic-cell authors"
copyright = "the mosaic-cell authors, Apache-2.0"  # noqa: A001 - Sphinx's name

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
exclude_patterns = ["_build", "_templates", "_generated", "Thumbs.db", ".DS_Store"]
templates_path = ["_templates"]

myst_enable_extensions = ["colon_fence", "deflist"]
myst_heading_anchors = 3

autosummary_generate = True
autosummary_imported_members = False
autodoc_default_options = {"members": True, "show-inheritance": True, "ignore-module-all": True}
autodoc_typehints = "description"
autodoc_member_order = "bysource"
autodoc_mock_imports: list[str] = []
napoleon_google_docstring = True
napoleon_numpy_docstring = False
napoleon_attr_annotations = True
napoleon_use_ivar = True  # "Attributes:" as fields: no second description of a property

html_theme = "furo"
html_title = "Mosaic assembly cell"
html_static_path: list[str] = []

# The architecture page's diagram is Mermaid source: shown as plain text (no highlighter).
lexers["mermaid"] = TextLexer()

# Docstrings name exceptions and types by their short names ("Raises: LimitError"); where two
# packages define the same short name (qshape and planners both have a LimitError) Sphinx links
# the first and warns: these are ambiguities of the short names, not broken references.
suppress_warnings = ["ref.python"]


_LITERAL = re.compile(r"(``.+?``)")


def escape_bars(
    _app: Sphinx, _what: str, _name: str, _obj: object, _options: object, lines: list[str]
) -> None:
    """Escape ``|x|`` (absolute values in the docstrings) outside literals: not substitutions."""
    for i, line in enumerate(lines):
        parts = _LITERAL.split(line)
        lines[i] = "".join(p if p.startswith("``") else p.replace("|", "\\|") for p in parts)


_MARKDOWN_HEADING = re.compile(r"^(\s*)#{2,6} (\S.*)$")


def markdown_headings(
    _app: Sphinx, _what: str, _name: str, _obj: object, _options: object, lines: list[str]
) -> None:
    """Render a docstring's Markdown section heads (``## Rewards``) as rubrics.

    Gymnasium's convention writes the env docstring's sections as ``## Name``; reStructuredText
    would show them as text inside the paragraph that follows.
    """
    out: list[str] = []
    for line in lines:
        match = _MARKDOWN_HEADING.match(line)
        if match:
            indent, title = match.groups()
            if out and out[-1].strip():
                out.append("")
            out += [f"{indent}.. rubric:: {title}", ""]
        else:
            out.append(line)
    lines[:] = out


def setup(app: Sphinx) -> None:
    """Escape docstrings' bars and render their Markdown heads; generate the benchmark table."""
    app.connect("autodoc-process-docstring", markdown_headings)
    app.connect("autodoc-process-docstring", escape_bars)
    if (Path(__file__).parent / "bench.json").is_file():
        app.connect("builder-inited", lambda _app: write_bench_table())
    if (Path(__file__).parent / "bench_env_ratios.json").is_file():
        app.connect("builder-inited", lambda _app: write_ratio_table())
    if all((Path(__file__).parent / f).is_file() for f in ("bench.json", "bench_env_ratios.json")):
        app.connect("builder-inited", lambda _app: write_glance_table())
