"""Units: designs and qshape figures are in millimetres, the simulated world in metres."""

from __future__ import annotations

MM_PER_M = 1000.0
"""Millimetres per metre (design units per world metre)."""
M_PER_MM = 1.0 / MM_PER_M
"""Metres per millimetre (the same double as ``1e-3``)."""

__all__ = ["MM_PER_M", "M_PER_MM"]
