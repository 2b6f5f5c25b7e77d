"""Shared fixtures of the programs' tests: a YAML file written from text in the test's folder.

The programs load their settings strictly; several tests hand them a hand-written (often bad)
file to check the error names the key.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest


@pytest.fixture
def yaml_file(tmp_path: Path) -> Callable[[str], Path]:
    """Write YAML text to ``bad.yaml`` in the test's temporary folder; gives its path."""

    def write(text: str) -> Path:
        path = tmp_path / "bad.yaml"
        path.write_text(text)
        return path

    return write
