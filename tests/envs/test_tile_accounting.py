"""Tile accounting: every real tile fed is in exactly one state, at every step of any episode.

Property tests (Hypothesis) drive the env with random and adversarial action sequences (corners
of the action box, places on the mesh's edges, the vacuum toggled mid-move) and check after every
step that the states sum to the tiles fed, that fed and waiting tiles make up the design, and
that the episode ends exactly when every slot is filled or nothing placeable is left.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import envs  # noqa: F401 - registers the env
from envs.cell.accounting import (
    CORRECT,
    DROPPED,
    HELD,
    LOST,
    MISPLACED,
    NOT_COUNTED,
    ON_INPUT,
    REJECTED,
    STRANDED,
    TILE_STATES,
    WAITING,
    TileFlags,
    state_counts,
    tile_states,
)

ENV_ID = "envs:MosaicAssembly-v0"
_ENVS: dict[str, Any] = {}


def _env(mode: str) -> Any:
    """One env per action mode for the whole module (Hypothesis reruns the test body)."""
    if mode not in _ENVS:
        kw: dict[str, Any] = {"action_mode": mode, "obs_mode": "state", "max_slots": 4}
        if mode.startswith("pick_place"):
            kw["execution"] = "kinematic"
        _ENVS[mode] = gym.make(ENV_ID, **kw)
    return _ENVS[mode]


def check_accounting(info: dict[str, Any], n_real: int, terminated: bool) -> None:
    """The invariants of the tile accounting on one step's ``info``."""
    ev = info["evaluation"]
    assert sum(ev[s] for s in TILE_STATES) == ev["fed"], ev
    assert ev["fed"] + ev["waiting"] == n_real, ev
    assert min(ev[s] for s in TILE_STATES) >= 0
    assert ev["held"] <= 1
    assert ev["correct"] == sum(ev["slot_filled"])
    assert terminated == (ev["success"] or ev["placeable"] == 0), ev


_UNIT = st.one_of(
    st.sampled_from([-1.0, -0.999, 0.0, 0.999, 1.0]),
    st.floats(-1.0, 1.0, allow_nan=False, width=32),
)

SIMULATED = settings(deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
"""Hypothesis settings of the simulated sequences: reproducible, no per-example deadline."""


@pytest.mark.slow
@settings(SIMULATED, max_examples=25)
@given(
    seed=st.integers(0, 2**16),
    actions=st.lists(st.lists(_UNIT, min_size=6, max_size=6), min_size=1, max_size=30),
)
def test_pick_place_sequences_keep_every_tile_accounted(seed, actions):
    env = _env("pick_place")
    _, info = env.reset(seed=seed)
    n_real = info["evaluation"]["fed"] + info["evaluation"]["waiting"]
    check_accounting(info, n_real, False)
    for a in actions:
        _, _, terminated, truncated, info = env.step(np.array(a, np.float32))
        check_accounting(info, n_real, terminated)
        if terminated or truncated:
            break


@pytest.mark.slow
@settings(SIMULATED, max_examples=15)
@given(
    seed=st.integers(0, 2**16),
    actions=st.lists(st.lists(_UNIT, min_size=5, max_size=5), min_size=1, max_size=25),
    hold=st.integers(1, 20),
)
def test_cartesian_sequences_with_the_vacuum_keep_every_tile_accounted(seed, actions, hold):
    env = _env("cartesian")
    _, info = env.reset(seed=seed)
    n_real = info["evaluation"]["fed"] + info["evaluation"]["waiting"]
    for a in actions:
        for _ in range(hold):  # each action held for a while: the arm travels, tiles drop
            _, _, terminated, truncated, info = env.step(np.array(a, np.float32))
            check_accounting(info, n_real, terminated)
            if terminated or truncated:
                return


def _flags(n: int, **set_true: list[int]) -> TileFlags:
    fields = {
        k: np.zeros(n, bool)
        for k in (
            "real",
            "fed",
            "held",
            "rejected",
            "lost",
            "was_dropped",
            "on_mesh",
            "correct",
            "on_input",
        )
    }
    fields["real"][:] = True
    fields["fed"][:] = True
    for k, idx in set_true.items():
        fields[k][idx] = True
    return TileFlags(**fields)


def test_states_follow_the_priority_order():
    f = _flags(
        8,
        held=[0],
        rejected=[0, 1],
        lost=[0, 1, 2, 3],
        was_dropped=[0, 1, 2, 6],
        on_mesh=[4, 5],
        correct=[4],
        on_input=[0, 5, 6],
    )
    real = f.real.copy()
    s = tile_states(f)
    assert [TILE_STATES[k] for k in s[:7]] == [
        "held",
        "rejected",
        "dropped_tiles",
        "lost_tiles",
        "correct",
        "misplaced",
        "on_input",
    ]
    assert s[7] == STRANDED
    assert real.all()
    counts = state_counts(s)
    assert sum(counts.values()) == 8
    assert counts["stranded"] == 1


def test_dropped_beside_the_belts_distractors_and_waiting_tiles():
    f = _flags(4, was_dropped=[0])
    f.real[3] = False
    f.fed[2] = False
    s = tile_states(f)
    assert s.tolist() == [DROPPED, STRANDED, WAITING, NOT_COUNTED]
    assert sum(state_counts(s).values()) == 2
    g = _flags(2, rejected=[0], on_input=[1])
    assert tile_states(g).tolist() == [REJECTED, ON_INPUT]


@settings(max_examples=6, deadline=None, derandomize=True)
@given(
    seed=st.integers(0, 2**16),
    actions=st.lists(st.lists(_UNIT, min_size=6, max_size=6), min_size=1, max_size=8),
)
def test_short_pick_place_sequences_keep_every_tile_accounted(seed, actions):
    # The default run's share of the slow property test above.
    test_pick_place_sequences_keep_every_tile_accounted.hypothesis.inner_test(seed, actions)


@settings(max_examples=10, deadline=None, derandomize=True)
@given(
    seed=st.integers(0, 2**16),
    actions=st.lists(
        st.tuples(st.integers(0, 3), st.integers(0, 3), st.integers(0, 3)), max_size=12
    ),
)
def test_discrete_sequences_that_always_grasp_keep_every_tile_accounted(seed, actions):
    # Every discrete action grasps a tile: stacks, misplaced tiles and refills happen.
    env = _env("pick_place_discrete")
    _, info = env.reset(seed=seed)
    n_real = info["evaluation"]["fed"] + info["evaluation"]["waiting"]
    for a in actions:
        _, _, terminated, truncated, info = env.step(np.array(a))
        check_accounting(info, n_real, terminated)
        if terminated or truncated:
            break


def test_states_equal_a_per_tile_reading_of_the_priority_order():
    """Random flag combinations (seeded): each tile's state is the first true test of the
    module docstring's order, read tile by tile."""
    rng = np.random.default_rng(0)
    names = ("real", "fed", "held", "rejected", "lost", "was_dropped", "on_mesh", "correct")
    for _ in range(50):
        flags = {k: rng.random(24) < 0.5 for k in (*names, "on_input")}
        states = tile_states(TileFlags(**flags))
        for i in range(24):
            f = {k: bool(v[i]) for k, v in flags.items()}
            expected = (
                NOT_COUNTED
                if not f["real"]
                else WAITING
                if not f["fed"]
                else HELD
                if f["held"]
                else REJECTED
                if f["rejected"]
                else DROPPED
                if f["lost"] and f["was_dropped"]
                else LOST
                if f["lost"]
                else CORRECT
                if f["on_mesh"] and f["correct"]
                else MISPLACED
                if f["on_mesh"]
                else ON_INPUT
                if f["on_input"]
                else DROPPED
                if f["was_dropped"]
                else STRANDED
            )
            assert states[i] == expected
    assert states.dtype == np.int8
