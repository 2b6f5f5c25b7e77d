"""Shared fixtures of qshape's tests: the bundled designs the synthetic pictures are drawn from.

Loaded once per test module.
"""

from __future__ import annotations

import pytest

from qshape.design import Design


@pytest.fixture(scope="module")
def design() -> Design:
    """The paper's mixed design (``paper_mixed``): squares, triangles, arcs and holes."""
    return Design.load("paper_mixed")
