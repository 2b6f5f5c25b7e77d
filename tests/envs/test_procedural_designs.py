"""Procedural training designs: a new design at every reset, reproducible by seed, fixed spaces,
held-out classes never drawn, solvable by the privileged expert; typed errors for bad options."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
import yaml

import envs
from apps.train import TrainConfig, make_env_fn
from envs.design_source import DesignSourceError
from envs.env_config import EnvConfigError
from envs.tasks import BenchmarkTask, TaskError, get_task
from qshape.design import Design

HELD_OUT = "MosaicHeldOutDesigns-v0"
PROCEDURAL: dict[str, Any] = {
    "design_source": "procedural",
    "exclude_designs": ["hexagon", "trencadis"],
}


@pytest.fixture(scope="module")
def env() -> Iterator[gym.Env]:
    """The held-out rung (6 slots, discrete actions, kinematic, state) on procedural designs."""
    e = gym.make(HELD_OUT, **PROCEDURAL)
    try:
        yield e
    finally:
        e.close()


def _design(e: gym.Env) -> list[tuple[Any, ...]]:
    """The episode's slots: class name and pose."""
    spec = e.get_wrapper_attr("task_spec")
    assert spec.design == "procedural"
    return [(s.class_name, *np.round([*s.xy, s.yaw], 6).tolist()) for s in spec.slots]


def test_the_same_seed_draws_the_same_design_and_episode(env: gym.Env) -> None:
    other = gym.make(HELD_OUT, **PROCEDURAL)
    try:
        a, _ = env.reset(seed=7)
        first = _design(env)
        b, _ = other.reset(seed=7)
        assert _design(other) == first
        for key in a:
            np.testing.assert_array_equal(a[key], b[key])
        env.reset(seed=8)
        env.reset(seed=7)
        assert _design(env) == first
    finally:
        other.close()


def test_every_reset_draws_another_design_with_the_same_spaces(env: gym.Env) -> None:
    obs_space, act_space = env.observation_space, env.action_space
    designs = []
    for k in range(4):
        obs, _ = env.reset(seed=100 + k) if k < 2 else env.reset()
        designs.append(_design(env))
        assert env.observation_space == obs_space and env.action_space == act_space
        assert env.unwrapped.observer.space == obs_space
        assert env.unwrapped.actions.space == act_space
        assert obs_space.contains(obs)
        assert len(designs[-1]) == 6 and obs["tiles"].shape == (6 * 7,)
    assert len({tuple(d) for d in designs}) == len(designs)


def test_the_privileged_expert_fills_procedural_designs(env: gym.Env) -> None:
    u = env.unwrapped
    for seed in (11, 12):
        env.reset(seed=seed)
        for slot in range(6):  # tile i is built from slot i (design order)
            *_, terminated, _, info = env.step(u.expert_action(slot, slot))
        assert info["evaluation"]["correct"] == 6, seed
        assert terminated and info["is_success"]


def test_held_out_classes_are_never_drawn(tmp_path: Path) -> None:
    """Regular polygons of the hexagon design's size and green: hexagons are drawn again."""
    cfg = yaml.safe_load(Path("configs/design_generator_train.yaml").read_text())
    cfg.update(
        classes=[1, 1],
        size_mm=[36.0, 36.0],
        families={"regular": 1.0},
        hole_probability=0.0,
        recolor_probability=0.0,
        turns_deg=0.0,
        palette=["#3f9e4d"],
    )
    path = tmp_path / "hexagonal.yaml"
    path.write_text(yaml.safe_dump(cfg))
    e = gym.make(HELD_OUT, design_source="procedural", design_generator=str(path))
    kept = gym.make(HELD_OUT, **{**PROCEDURAL, "design_generator": str(path)})
    try:
        sides = set()
        hexagons = 0
        for seed in range(8):
            e.reset(seed=seed)
            hexagons += sum(s.shape.get("sides") == 6 for s in e.unwrapped.designs.last.slots)
            kept.reset(seed=seed)
            design = kept.unwrapped.designs.last
            sides |= {s.shape["sides"] for s in design.slots}
            assert kept.unwrapped.designs.exclusion.clashes(design) == []
        assert hexagons > 0  # without the exclusion the hexagon class is drawn
        assert 6 not in sides and len(sides) >= 3
    finally:
        e.close()
        kept.close()
    regulars = tmp_path / "regulars.yaml"  # one regular polygon of every side count, green
    Design.from_dict(
        {
            "name": "regulars",
            "mesh": {"width": 250.0, "height": 230.0},
            "joint": 2.0,
            "slots": [
                {
                    "name": f"p{n}",
                    "shape": {"kind": "regular_polygon", "sides": n, "radius": 18.0},
                    "color": "#3f9e4d",
                    "pose": {"x": 25.0 + 40.0 * (n - 3), "y": 115.0},
                }
                for n in range(3, 9)
            ],
        }
    ).save(regulars)
    tight = {"design_generator": str(path), "design_tries": 3}
    with pytest.raises(DesignSourceError, match="every one of 3 drawn designs.*'regulars'"):
        gym.make(HELD_OUT, design_source="procedural", exclude_designs=[str(regulars)], **tight)


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        (
            {"design_source": "random"},
            r"'random' is not allowed; allowed: \['fixed', 'procedur",
        ),
        ({"design_source": "procedural", "max_slots": 0}, "needs max_slots >= 1"),
        ({**PROCEDURAL, "design_generator": "nope"}, "design_generator 'nope'"),
        ({**PROCEDURAL, "exclude_designs": ["nope"]}, "exclude_designs: .*allowed: bundled"),
        ({**PROCEDURAL, "max_slots": 7}, "draws 6-6 slots; the env draws exactly max_slots=7"),
        ({**PROCEDURAL, "design_tries": 0}, "design_tries must be an int >= 1"),
        ({"exclude_designs": ["hexagon"]}, "exclude_designs needs design_source 'procedural'"),
    ],
)
def test_bad_options_are_refused_with_what_is_allowed(
    overrides: dict[str, Any], message: str
) -> None:
    with pytest.raises(EnvConfigError, match=message):
        gym.make(HELD_OUT, **overrides)


def test_a_task_asks_for_procedural_designs_by_name() -> None:
    task = get_task(HELD_OUT)
    assert task.designs("train") == ("paper_mixed", "square_grid", "procedural")
    assert task.design_kwargs("train", 0) == {"design": "paper_mixed"}
    assert task.design_kwargs("train", 2) == PROCEDURAL
    assert task.env_kwargs("train", 5)["design_source"] == "procedural"
    assert "design_source" not in task.env_kwargs("eval", 0)
    assert gym.spec(HELD_OUT).kwargs["design"] == "paper_mixed"
    assert "design_source" not in gym.spec(HELD_OUT).kwargs
    assert envs  # the ids are registered on import
    with pytest.raises(TaskError, match="'procedural' is allowed in train_designs only"):
        BenchmarkTask("T-v0", "t", 2, 1.0, (0, 1), eval_designs=("procedural",))


def test_a_training_vector_makes_its_procedural_entry_procedural() -> None:
    cfg = TrainConfig(task=HELD_OUT, n_envs=3)
    made = [make_env_fn(cfg, i)() for i in (1, 2)]
    try:
        square, drawn = (e.unwrapped for e in made)
        assert square.designs is None and square.config.design == "square_grid"
        assert drawn.designs is not None
        assert drawn.designs.exclusion.designs == ("hexagon", "trencadis")
    finally:
        for e in made:
            e.close()
