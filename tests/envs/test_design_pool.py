"""The design pool (`envs.pool`): designs and cells prepared in a worker process give the
same episodes as drawn in place, are keyed by the configuration (a changed design or cell
configuration never takes a stale model), stay within their memory bound, and the worker stops
with the env (and at interpreter exit)."""

from __future__ import annotations

import errno
import os
import subprocess
import sys
import textwrap
import time
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path
from typing import Any

import gymnasium as gym
import pytest

from envs.pool import (
    DesignPool,
    DesignPoolConfig,
    DesignPoolError,
    load_pool_config,
)
from envs.pool.worker import Prepared, hand_over
from tests.envs.rollouts import digest

HELD_OUT = "MosaicHeldOutDesigns-v1"
PROCEDURAL: dict[str, Any] = {
    "design_source": "procedural",
    "exclude_designs": ["hexagon", "trencadis"],
}
ROOT = Path(__file__).resolve().parents[2]


def _gone(pid: int, wait_s: float = 5.0) -> bool:
    """Whether process ``pid`` has ended (no longer running or a zombie) within ``wait_s``."""
    deadline = time.monotonic() + wait_s
    while time.monotonic() < deadline:
        try:
            status = Path(f"/proc/{pid}/status").read_text()
        except FileNotFoundError:
            return True
        if "State:\tZ" in status:
            return True
        time.sleep(0.05)
    return False


def _episodes(env: gym.Env, seeds: list[int | None], steps: int) -> list[Any]:
    """Observation digests and rewards of the expert's first ``steps`` steps after each reset."""
    u: Any = env.unwrapped
    out: list[Any] = []
    for seed in seeds:
        obs, _ = env.reset(seed=seed)
        out.append(digest(obs))
        for k in range(steps):
            obs, reward, *_ = env.step(u.expert_action(k, k))
            out.append((digest(obs), reward))
    return out


@pytest.fixture(scope="module")
def pooled() -> Iterator[gym.Env]:
    """The held-out rung's procedural entry with both images, with the bundled design pool."""
    env = gym.make(HELD_OUT, design_pool="design_pool", obs_mode="rgb+state", **PROCEDURAL)
    yield env
    env.close()


def test_pooled_resets_give_the_episodes_drawn_in_place(pooled: gym.Env) -> None:
    """Seeds in order and unseeded resets (the worker's two plans), images and state rows, bit
    for bit; the resets really took prepared designs and cells."""
    seeds: list[int | None] = [0, 1, None, None]
    plain = gym.make(HELD_OUT, obs_mode="rgb+state", **PROCEDURAL)
    want = _episodes(plain, seeds, 1)
    plain.close()
    pool: DesignPool = pooled.unwrapped.pool  # type: ignore[attr-defined]
    hits = pool.hits
    assert _episodes(pooled, seeds, 1) == want
    assert pool.hits - hits >= 2  # seed 1 and the second unseeded reset
    assert pooled.unwrapped.cell.model is not None  # type: ignore[attr-defined]


def test_a_changed_cell_or_design_configuration_never_takes_a_stale_model(
    pooled: gym.Env,
) -> None:
    u: Any = pooled.unwrapped
    pool: DesignPool = u.pool
    pooled.reset(seed=10)
    pooled.reset(seed=11)  # the pool now works on seeds 12, 13, ...
    old = u.config
    changed = replace(old.cell, tiles=replace(old.cell.tiles, color_jitter=0.05))
    u.config = replace(old, cell=changed)
    hits, misses = pool.hits, pool.misses
    try:
        pooled.reset(seed=12)  # prepared with the old cell configuration: not taken
        assert (pool.hits, pool.misses) == (hits, misses + 1)
        assert u.cell.cfg == changed and u.cell.cfg != old.cell
        pooled.reset(seed=13)  # planned anew with the changed configuration: taken
        assert pool.hits == hits + 1 and u.cell.cfg == changed
        generator = u.designs.generator
        tries = generator.config.max_tries + 1
        u.designs.generator = type(generator)(
            replace(generator.config, max_tries=tries), generator.rules
        )
        pooled.reset(seed=14)  # prepared with the old generator parameters: not taken
        assert pool.hits == hits + 1 and pool.misses == misses + 2
        u.designs.generator = generator
    finally:
        u.config = old


def test_the_pool_stays_within_its_memory_bound() -> None:
    cfg = load_pool_config("design_pool")
    assert cfg == DesignPoolConfig()  # the bundled file states the defaults
    assert cfg.max_mb == cfg.ahead * cfg.max_entry_mb
    path = ROOT / "configs" / "design_pool.yaml"  # by path, as a user's own file
    env = gym.make(HELD_OUT, design_pool=str(path), **PROCEDURAL)
    u: Any = env.unwrapped
    u.pool.config = replace(u.pool.config, ahead=2, max_entry_mb=0.01)  # 10 kB: a cell is ~1 MB
    try:
        for seed in range(2):
            env.reset(seed=seed)
            assert len(u.pool) == 0 and u.pool.held_mb == 0.0
        assert u.pool.hits == 0 and u.pool.dropped >= 1
        u.pool.config = replace(u.pool.config, max_entry_mb=16.0)
        for seed in range(2, 4):
            env.reset(seed=seed)
            assert len(u.pool) <= 2 and u.pool.held_mb <= 2 * 16.0
            # the entries' files: those held, and at most the one being written
            assert len(os.listdir(u.pool.folder)) <= len(u.pool) + 1
        assert u.pool.hits >= 1
    finally:
        env.close()


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"ahead": 0}, "ahead must be an int >= 1"),
        ({"max_entry_mb": -1.0}, "max_entry_mb must be > 0"),
        ({"start_method": "fork"}, "'fork' is not allowed; allowed: \\['spawn', 'forkserver'\\]"),
        ({"ahead_by": 3}, "ahead_by"),
    ],
)
def test_bad_pool_settings_are_refused_naming_the_key(
    overrides: dict[str, Any], message: str
) -> None:
    with pytest.raises(DesignPoolError, match=message):
        load_pool_config("design_pool", **overrides)


def test_an_unknown_pool_file_is_refused() -> None:
    with pytest.raises(DesignPoolError, match="design_pool 'nope'"):
        gym.make(HELD_OUT, design_pool="nope", **PROCEDURAL)


def test_close_stops_the_worker_and_a_fixed_design_starts_none() -> None:
    env = gym.make(HELD_OUT, design_pool="design_pool", **PROCEDURAL)
    pool: DesignPool = env.unwrapped.pool  # type: ignore[attr-defined]
    pid = pool.pid
    assert pool.alive and os.path.isdir(pool.folder)
    env.reset(seed=0)
    env.close()
    env.close()  # twice is fine
    assert _gone(pid) and not pool.alive
    assert not os.path.exists(pool.folder)  # the handed-over entries' folder is removed
    fixed = gym.make(HELD_OUT, design_pool="design_pool")
    assert fixed.unwrapped.pool is None  # type: ignore[attr-defined]
    fixed.close()


@pytest.mark.slow
def test_an_unclosed_pool_ends_with_the_interpreter() -> None:
    """A script that never closes its env exits at once, its worker with it."""
    script = textwrap.dedent(
        f"""
        import gymnasium as gym
        import envs

        if __name__ == "__main__":
            env = gym.make({HELD_OUT!r}, design_pool="design_pool", **{PROCEDURAL!r})
            env.reset(seed=0)
            print(env.unwrapped.pool.folder, env.unwrapped.pool.pid, flush=True)
        """
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    done = subprocess.run(
        [sys.executable, "-c", script],
        check=False,
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
    )
    assert done.returncode == 0, done.stderr
    folder, pid = done.stdout.split()[-2:]
    assert _gone(int(pid)) and not os.path.exists(folder)


@pytest.mark.slow
def test_a_pool_of_designs_alone_gives_the_same_episodes(tmp_path: Path) -> None:
    """``build_cells: false``: the worker draws, the env builds the cell."""
    path = tmp_path / "designs_only.yaml"
    path.write_text("build_cells: false\nahead: 1\n", encoding="utf-8")
    pooled = gym.make(HELD_OUT, design_pool=str(path), **PROCEDURAL)
    plain = gym.make(HELD_OUT, **PROCEDURAL)
    try:
        for seed in (0, 1):
            assert digest(pooled.reset(seed=seed)[0]) == digest(plain.reset(seed=seed)[0])
        assert pooled.unwrapped.pool.hits == 1  # type: ignore[attr-defined]
    finally:
        pooled.close()
        plain.close()


def test_a_failed_hand_over_is_drawn_in_place_and_the_worker_lives_on() -> None:
    """A hand-over file that cannot be written (its folder gone here; a full ``/dev/shm``
    alike) costs a miss, not the pool: the same episode, and later entries are taken again."""
    env = gym.make(HELD_OUT, design_pool="design_pool", **PROCEDURAL)
    plain = gym.make(HELD_OUT, **PROCEDURAL)
    pool: DesignPool = env.unwrapped.pool  # type: ignore[attr-defined]
    try:
        env.reset(seed=30)
        os.rename(pool.folder, pool.folder + ".away")  # the worker's next writes fail
        time.sleep(1.0)  # let it try (and fail) its planned entries
        misses = pool.misses
        assert _episodes(env, [31], 1) == _episodes(plain, [31], 1)
        assert pool.misses == misses + 1 and pool.alive
        os.rename(pool.folder + ".away", pool.folder)
        env.reset(seed=40)  # a new plan, written again
        hits = pool.hits
        assert _episodes(env, [41], 1) == _episodes(plain, [41], 1)
        assert pool.hits == hits + 1
    finally:
        if os.path.isdir(pool.folder + ".away"):
            os.rename(pool.folder + ".away", pool.folder)
        env.close()
        plain.close()


def test_a_hand_over_that_fails_midway_leaves_no_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A write that fails (a full ``/dev/shm``) raises and leaves no partly written entry."""
    real_open = open

    class Full:
        def __init__(self, path: str, mode: str) -> None:
            self._f = real_open(path, mode)  # the file exists from here on

        def __enter__(self) -> Full:
            return self

        def __exit__(self, *exc: object) -> None:
            self._f.close()

        def write(self, data: bytes) -> int:
            raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr("builtins.open", Full)
    with pytest.raises(OSError, match="No space left"):
        hand_over(Prepared(b"entry" * 100), str(tmp_path / "1.entry"))
    monkeypatch.undo()
    assert list(tmp_path.iterdir()) == []
