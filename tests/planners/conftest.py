"""Shared fixtures of the planners' tests: the bundled configuration, the IK and the planner.

Each is built once per test module (the IK loads the arm model; building it per test would
dominate the module's time).
"""

from __future__ import annotations

import pytest

from planners.config import PlannerConfig, load_planner_config
from planners.ik import IKSolver
from planners.pick_place import PickPlacePlanner


@pytest.fixture(scope="module")
def planner_config() -> PlannerConfig:
    """The bundled planner configuration (``configs/planners.yaml``)."""
    return load_planner_config()


@pytest.fixture(scope="module")
def ik(planner_config: PlannerConfig) -> IKSolver:
    """The tool-down IK on the arm model, with the bundled limits."""
    return IKSolver(config=planner_config.ik, limits=planner_config.limits)


@pytest.fixture(scope="module")
def planner(ik: IKSolver, planner_config: PlannerConfig) -> PickPlacePlanner:
    """The pick-and-place planner on the module's IK."""
    return PickPlacePlanner(ik, planner_config)
