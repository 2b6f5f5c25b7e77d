"""Settings of the rotation-equivariant pixel policy (`configs/equivariant.yaml`)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from agents.camera.crops import CropConfig
from agents.errors import AgentError
from configs import load_config
from configs.checks import check_fields, checked

EQUIVARIANT_CONFIG = "equivariant"
"""Bundled config name (``configs/equivariant.yaml``)."""


class EquivariantConfigError(AgentError):
    """A setting of the equivariant policy outside its allowed range."""


@dataclass(frozen=True)
class EquivariantConfig:
    """Crops, network and behaviour-cloning settings of the equivariant policy.

    Attributes:
        grid: Crop cells per side (a crop spans ``grid * pitch``).
        pitch: Crop cell size [m].
        foreground: Colour distance from the belt's median colour marking a tile pixel
            [0-255 per channel].
        min_blob_px: Smallest blob counted as a tile [px].
        supersample: Slot-template anti-aliasing factor.
        turns: Fine in-plane turns scored per (tile, slot): ``turns`` steps of ``360 / turns``
            deg (a multiple of 4, so the quarter turns are among them).
        width: Channels of the encoders' hidden convolutions.
        features: Channels of the dense feature maps that are correlated.
        template: Stack the slot's figure drawn from the task description (its mask and its
            design colour inside it) with the output camera's crop of the slot.
        temperature: Initial scale of the cosine correlation (learned).
        colour_weight: Initial weight of the colour distance (learned) [per unit RGB^2].
        steps: Gradient steps of behaviour cloning.
        batch_size: Demonstrated steps per gradient step.
        learning_rate: Adam step size.
        weight_decay: Adam L2 penalty.
        augment: Turn every crop of a batch by one random quarter turn (labels turned with it).
        turn_tolerance_deg: A fine turn counts as right within this of a right turn [deg].
    """

    grid: int = checked(24, integer=True, ge=8)
    pitch: float = checked(0.0025, gt=0)
    foreground: float = checked(40.0, gt=0, le=255)
    min_blob_px: int = checked(6, integer=True, ge=1)
    supersample: int = checked(4, integer=True, ge=1)
    turns: int = checked(36, integer=True, ge=4)
    width: int = checked(8, integer=True, ge=1)
    features: int = checked(8, integer=True, ge=1)
    template: bool = True
    temperature: float = checked(10.0, gt=0)
    colour_weight: float = checked(20.0, gt=0)
    steps: int = checked(300, integer=True, ge=1)
    batch_size: int = checked(8, integer=True, ge=1)
    learning_rate: float = checked(3e-3, gt=0)
    weight_decay: float = checked(1e-5, ge=0)
    augment: bool = True
    turn_tolerance_deg: float = checked(6.0, gt=0, le=45)

    def __post_init__(self) -> None:
        check_fields(self, EquivariantConfigError)
        if self.turns % 4:
            raise EquivariantConfigError(
                f"turns must be a multiple of 4 (the quarter turns among them), got {self.turns}"
            )

    def crop(self) -> CropConfig:
        """The crop settings."""
        return CropConfig(
            self.grid, self.pitch, self.foreground, self.min_blob_px, self.supersample
        )

    @property
    def slot_channels(self) -> int:
        """Channels of a slot's input: the output crop (mask, RGB), then the template's."""
        return 8 if self.template else 4


def load_equivariant_config(
    name_or_path: str | Path = EQUIVARIANT_CONFIG, **overrides: Any
) -> EquivariantConfig:
    """Load an `EquivariantConfig` strictly from ``configs/`` (by name) or a path."""
    return load_config(EquivariantConfig, name_or_path, **overrides)


__all__ = [
    "EQUIVARIANT_CONFIG",
    "EquivariantConfig",
    "EquivariantConfigError",
    "load_equivariant_config",
]
