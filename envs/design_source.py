"""Where an env's design comes from: one fixed design, or a new procedural one at every reset.

``design_source: fixed`` (the default) builds ``design`` once, at construction.
``design_source: procedural`` draws a design from `qshape.design.generator.DesignGenerator`
(parameters: the ``design_generator`` file, e.g. ``configs/design_generator_train.yaml``) at
every reset, from the env's ``np_random``: ``reset(seed=s)`` gives the same design for the same
``s``, and different seeds give different designs. A drawn design has exactly ``max_slots``
slots (the generator's slot range is set to it), so the observation and action spaces, built
for ``max_slots`` tiles and slots, never change. A draw holding a tile class of one of
``exclude_designs`` (equal by the qualitative theory's matching, `qshape.design.exclusion`) is
drawn again, up to ``design_tries`` times; then `DesignSourceError`. Each reset builds the cell
anew (its MuJoCo model, the task's slots, the observer, the index maps, the executor, the
``task_spec``) with one tile variant (`source_config`); the IK solver and the spaces are kept,
and renderers are made only when something renders.

`BenchmarkTask` (`envs.tasks`) asks for it with the training design name `PROCEDURAL`: that
entry of a training vector gets ``design_source: procedural`` with the task's evaluation designs
excluded.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from configs import ConfigError
from envs.env_config import EnvConfig, EnvConfigError
from envs.errors import EnvError
from envs.tasks import PROCEDURAL

if TYPE_CHECKING:
    from qshape.design import Design
    from qshape.design.exclusion import ClassExclusion
    from qshape.design.generator import DesignGenerator

FIRST_DRAW_SEED = 0
"""Seed of the design the env is built with before its first reset (every reset draws anew)."""


class DesignSourceError(EnvError, RuntimeError):
    """No design free of the excluded tile classes was drawn at a reset (names the clash)."""


class ProceduralDesigns:
    """Draws the designs of a ``design_source: procedural`` env.

    Args:
        config: The env's configuration (``max_slots``, ``design_generator``,
            ``exclude_designs``, ``design_tries``).

    Raises:
        EnvConfigError: A bad generator file (unknown key, value out of range, a slot range
            without ``max_slots``) or an unknown excluded design; the message names the key.
    """

    def __init__(self, config: EnvConfig) -> None:
        from qshape.design import Design  # noqa: PLC0415 - keep `import envs` light
        from qshape.design.exclusion import ClassExclusion  # noqa: PLC0415
        from qshape.design.generator import DesignGenerator  # noqa: PLC0415
        from qshape.design.generator_config import GeneratorConfig  # noqa: PLC0415
        from qshape.errors import DesignError  # noqa: PLC0415

        k, name = config.max_slots, config.design_generator
        try:
            file = GeneratorConfig.load(name)
            lo, hi = file.tiles
            if not lo <= k <= hi:
                raise EnvConfigError(
                    f"design_generator {name!r} draws {lo}-{hi} slots; the env draws exactly "
                    f"max_slots={k}: allowed are generator files whose tiles range holds it"
                )
            gen_cfg = GeneratorConfig.load(name, tiles=(k, k), classes=_classes(file.classes, k))
        except (ConfigError, DesignError) as exc:
            if isinstance(exc, EnvConfigError):
                raise
            raise EnvConfigError(f"design_generator {name!r}: {exc}") from exc
        try:
            excluded = [Design.load(d) for d in config.exclude_designs]
        except DesignError as exc:
            raise EnvConfigError(
                f"exclude_designs: {exc}; allowed: bundled design names or design files"
            ) from exc
        self.generator: DesignGenerator = DesignGenerator(gen_cfg)
        self.exclusion: ClassExclusion = ClassExclusion(excluded)
        self.tries = config.design_tries
        self.last: Design | None = None
        """The design drawn last (the current episode's after a reset)."""

    def draw(self, rng: np.random.Generator) -> Design:
        """A design of ``max_slots`` slots holding no excluded class, drawn from ``rng``.

        Raises:
            DesignSourceError: ``design_tries`` draws all held an excluded class, or the
                generator failed (its message says which parameter to change).
        """
        from qshape.design.exclusion import draw_excluding  # noqa: PLC0415
        from qshape.errors import GeneratorError  # noqa: PLC0415

        try:
            self.last = draw_excluding(self.generator, rng, self.exclusion, self.tries, PROCEDURAL)
        except GeneratorError as exc:
            raise DesignSourceError(f"procedural design source: {exc}") from exc
        return self.last


def _classes(classes: tuple[int, int], k: int) -> tuple[int, int]:
    """The generator file's class range clipped to ``k`` slots (a design has k classes at most)."""
    return (min(classes[0], k), min(classes[1], k))


def source_config(config: EnvConfig) -> EnvConfig:
    """The configuration an env of ``config`` runs with: ``procedural`` builds one tile variant.

    A procedural env builds its cell anew at every reset, with a build seed drawn from the
    env's ``np_random``, so its tiles' outline and glaze noise is fresh at every reset with one
    variant per tile; more variants would only cost build time (``tile_variants`` is set to 1).
    """
    if config.design_source != PROCEDURAL or config.cell.tiles.variants == 1:
        return config
    tiles = replace(config.cell.tiles, variants=1)
    return replace(config, cell=replace(config.cell, tiles=tiles))


def design_source(config: EnvConfig) -> ProceduralDesigns | None:
    """The procedural source of ``config``, or None for ``design_source: fixed``."""
    return ProceduralDesigns(config) if config.design_source == PROCEDURAL else None


__all__ = [
    "FIRST_DRAW_SEED",
    "PROCEDURAL",
    "DesignSourceError",
    "ProceduralDesigns",
    "design_source",
    "source_config",
]
