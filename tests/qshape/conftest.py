"""Shared fixtures of qshape's tests: the design the synthetic pictures are drawn from.

The bundled picture and extraction parameters are fixtures of ``tests/conftest.py``. Loaded once
per test module (frozen values: a test changes a copy, ``dataclasses.replace``).
"""

from __future__ import annotations

import pytest

from qshape.design import Design


@pytest.fixture(scope="module")
def design() -> Design:
    """The paper's mixed design (``paper_mixed``): squares, triangles, arcs and holes."""
    return Design.load("paper_mixed")
