"""Fixtures shared by the test folders: the bundled picture and extraction parameters.

Loaded once per test module (frozen values: a test changes a copy, ``dataclasses.replace``).
"""

from __future__ import annotations

import pytest

from qshape.synthetic.synth import SynthParams
from qshape.vision.params import ExtractParams


@pytest.fixture(scope="module")
def synth_params() -> SynthParams:
    """The bundled synthetic-picture parameters (``configs/vision.yaml``, ``synth``)."""
    return SynthParams.load()


@pytest.fixture(scope="module")
def extract_params() -> ExtractParams:
    """The bundled extraction parameters (``configs/vision.yaml``, ``extract``)."""
    return ExtractParams.load()
