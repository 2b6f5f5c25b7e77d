"""Errors of the agents package: one base class, `AgentError`."""

from __future__ import annotations


class AgentError(Exception):
    """Base of every error raised by ``agents`` (the message says what, and what is allowed)."""


class PerceptionError(AgentError):
    """An image or camera model the perception cannot use (wrong shape, plane behind camera)."""


class CalibrationError(AgentError):
    """The calibration target was not found in enough views, or the solve failed."""


__all__ = ["AgentError", "CalibrationError", "PerceptionError"]
