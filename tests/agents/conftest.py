"""Shared fixtures of the agents' tests: the design the rendered cells are built from.

Loaded once per test module.
"""

from __future__ import annotations

import pytest

from qshape.design import Design


@pytest.fixture(scope="module")
def design() -> Design:
    """The paper's mixed design (``paper_mixed``): squares, triangles, arcs and holes."""
    return Design.load("paper_mixed")
