"""The cell's design loading warns about glazes it cannot tell from its belt."""

from __future__ import annotations

import warnings

import pytest

from envs.cell.glazes import GlazeWarning, unseparable_glazes
from envs.env_config import load_env_config
from envs.episode_setup import design_cell_parts
from qshape.design import Design


def test_dark_glazes_are_named_without_a_height_cue() -> None:
    with pytest.warns(GlazeWarning, match=r"\['black_square', 'belt_grey', 'arrow_black'\]"):
        design_cell_parts(load_env_config(design="catalogue"))


def test_nothing_is_said_with_a_height_cue_or_bright_glazes() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error", GlazeWarning)
        design_cell_parts(load_env_config(design="catalogue", depth=True))
        design_cell_parts(load_env_config(design="paper_mixed"))


def test_a_white_belt_cannot_tell_white_glazes() -> None:
    cell = load_env_config().cell
    white = cell.__class__(
        **{
            **cell.__dict__,
            "scenery": cell.scenery.__class__(
                **{**cell.scenery.__dict__, "belt_rgba": (0.95, 0.95, 0.93, 1.0)}
            ),
        }
    )
    assert unseparable_glazes(Design.load("catalogue"), white, 40.0) == ["white_square"]
