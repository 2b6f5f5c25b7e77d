"""Env keywords the tests share."""

from __future__ import annotations

from typing import Any

FAST_DISCRETE: dict[str, Any] = {
    "design": "paper_mixed",
    "action_mode": "pick_place_discrete",
    "obs_mode": "state",
    "execution": "kinematic",
}
"""A quick ``pick_place_discrete`` env: the paper's mixed design, state observations, kinematic
execution (add ``max_slots`` for a shorter episode)."""
